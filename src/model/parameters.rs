//! The calibration parameters: names, units, order (SPEC section 5).

use std::fmt;

/// The unit a parameter is reported in. Angles are radians inside the code and files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// An angle: radians internally, degrees in reports.
    Deg,
    /// A length in millimetres.
    Mm,
}

impl Unit {
    /// The unit's report name.
    pub fn name(self) -> &'static str {
        match self {
            Unit::Deg => "deg",
            Unit::Mm => "mm",
        }
    }

    /// Converts an internal value (rad or mm) into report units (deg or mm).
    pub fn to_report(self, value: f64) -> f64 {
        match self {
            Unit::Deg => value.to_degrees(),
            Unit::Mm => value,
        }
    }

    /// Converts a value in report units (deg or mm) into internal units (rad or mm).
    pub fn from_report(self, value: f64) -> f64 {
        match self {
            Unit::Deg => value.to_radians(),
            Unit::Mm => value,
        }
    }
}

macro_rules! parameters {
    ($($name:ident: $unit:ident, $fixed:expr;)*) => {
        /// One calibration parameter. The first 21 are the paper's, in the order of its
        /// Table 2; further ones are held fixed by default (SPEC section 5).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(usize)]
        pub enum Param { $(#[doc = concat!("Offset `", stringify!($name), "`.")] $name,)* }

        impl Param {
            /// Every parameter, in order.
            pub const ALL: [Param; [$(Param::$name),*].len()] = [$(Param::$name),*];

            /// The parameter's name as in SPEC and the result JSON.
            pub fn name(self) -> &'static str {
                match self { $(Param::$name => stringify!($name),)* }
            }

            /// The unit the parameter is reported in.
            pub fn unit(self) -> Unit {
                match self { $(Param::$name => Unit::$unit,)* }
            }

            /// Whether the parameter is held fixed unless asked otherwise.
            pub fn fixed_by_default(self) -> bool {
                match self { $(Param::$name => $fixed,)* }
            }
        }
    };
}

parameters! {
    CamYaw: Deg, false;
    CamPitch: Deg, false;
    CamRoll: Deg, false;
    LHipYawPitch: Deg, false;
    LHipRoll: Deg, false;
    LHipPitch: Deg, false;
    LKneePitch: Deg, false;
    LAnklePitch: Deg, false;
    LAnkleRoll: Deg, false;
    RHipYawPitch: Deg, false;
    RHipRoll: Deg, false;
    RHipPitch: Deg, false;
    RKneePitch: Deg, false;
    RAnklePitch: Deg, false;
    RAnkleRoll: Deg, false;
    LBoardRotZ: Deg, false;
    LBoardTransX: Mm, false;
    LBoardTransY: Mm, false;
    RBoardRotZ: Deg, false;
    RBoardTransX: Mm, false;
    RBoardTransY: Mm, false;
    HeadYaw: Deg, true;
    HeadPitch: Deg, true;
}

/// Number of parameters the paper estimates (the first ones of [`Param::ALL`]).
pub const PAPER_PARAMETERS: usize = 21;

/// Total number of parameters, including those held fixed by default.
pub const PARAMETER_COUNT: usize = Param::ALL.len();

impl Param {
    /// Index of the parameter in [`Param::ALL`] and in every parameter vector.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Looks a parameter up by its name (exact, case-sensitive).
    pub fn from_name(name: &str) -> Option<Param> {
        Param::ALL.iter().copied().find(|p| p.name() == name)
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which parameters are held fixed in a solve.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FixedSet([bool; PARAMETER_COUNT]);

impl Default for FixedSet {
    fn default() -> Self {
        FixedSet(Param::ALL.map(Param::fixed_by_default))
    }
}

impl FixedSet {
    /// The default set, with `extra` also held fixed.
    pub fn with(extra: &[Param]) -> Self {
        let mut set = FixedSet::default();
        for p in extra {
            set.0[p.index()] = true;
        }
        set
    }

    /// Holds `param` fixed (or frees it).
    pub fn set(&mut self, param: Param, fixed: bool) {
        self.0[param.index()] = fixed;
    }

    /// Whether `param` is held fixed.
    pub fn is_fixed(&self, param: Param) -> bool {
        self.0[param.index()]
    }

    /// The free parameters, in order.
    pub fn free(&self) -> Vec<Param> {
        Param::ALL
            .iter()
            .copied()
            .filter(|p| !self.is_fixed(*p))
            .collect()
    }

    /// A mask indexed by [`Param::index`].
    pub fn mask(&self) -> &[bool; PARAMETER_COUNT] {
        &self.0
    }
}

/// Parses a comma-separated list of parameter names (`CamYaw,LBoardRotZ`).
pub fn parse_param_list(list: &str) -> Result<Vec<Param>, String> {
    list.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            Param::from_name(s).ok_or_else(|| {
                let names: Vec<_> = Param::ALL.iter().map(|p| p.name()).collect();
                format!("unknown parameter '{s}' (known: {})", names.join(", "))
            })
        })
        .collect()
}

/// A group of parameters that move together in the model: one parameter block for the
/// solvers (Ceres parameter blocks, tiny-solver variables).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ParamGroup {
    /// CamYaw, CamPitch, CamRoll.
    Camera,
    /// The six left leg joint offsets.
    LeftLeg,
    /// The six right leg joint offsets.
    RightLeg,
    /// The left sandal's mounting offsets.
    LeftBoard,
    /// The right sandal's mounting offsets.
    RightBoard,
    /// HeadYaw, HeadPitch.
    Head,
}

impl ParamGroup {
    /// Short name (used as a variable name).
    pub fn name(self) -> &'static str {
        match self {
            ParamGroup::Camera => "camera",
            ParamGroup::LeftLeg => "left_leg",
            ParamGroup::RightLeg => "right_leg",
            ParamGroup::LeftBoard => "left_board",
            ParamGroup::RightBoard => "right_board",
            ParamGroup::Head => "head",
        }
    }
}

impl Param {
    /// The block this parameter belongs to.
    pub fn group(self) -> ParamGroup {
        use Param::*;
        match self {
            CamYaw | CamPitch | CamRoll => ParamGroup::Camera,
            LHipYawPitch | LHipRoll | LHipPitch | LKneePitch | LAnklePitch | LAnkleRoll => {
                ParamGroup::LeftLeg
            }
            RHipYawPitch | RHipRoll | RHipPitch | RKneePitch | RAnklePitch | RAnkleRoll => {
                ParamGroup::RightLeg
            }
            LBoardRotZ | LBoardTransX | LBoardTransY => ParamGroup::LeftBoard,
            RBoardRotZ | RBoardTransX | RBoardTransY => ParamGroup::RightBoard,
            HeadYaw | HeadPitch => ParamGroup::Head,
        }
    }
}

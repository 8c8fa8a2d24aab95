//! The calibration parameters as data: one registry names every parameter with its family,
//! unit and solver block (docs/MODEL.md lists them). Adding a parameter is one line here
//! plus its place in the model.

use super::joint::{JOINT_COUNT, Joint};
use std::fmt;

/// The unit a parameter is reported in. Inside the code and files, angles are radians.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// An angle: radians internally, degrees in reports.
    Deg,
    /// A length in millimetres.
    Mm,
    /// Pixels.
    Px,
    /// A dimensionless coefficient.
    One,
    /// Compliance: rad/(N·m) internally, deg/(N·m) in reports.
    DegPerNm,
}

impl Unit {
    /// The unit's report name.
    pub fn name(self) -> &'static str {
        match self {
            Unit::Deg => "deg",
            Unit::Mm => "mm",
            Unit::Px => "px",
            Unit::One => "1",
            Unit::DegPerNm => "deg/(N·m)",
        }
    }

    /// Whether report and internal units differ (degrees vs radians).
    pub fn is_scaled(self) -> bool {
        matches!(self, Unit::Deg | Unit::DegPerNm)
    }

    /// Converts an internal value into report units.
    pub fn to_report(self, value: f64) -> f64 {
        if self.is_scaled() {
            value.to_degrees()
        } else {
            value
        }
    }

    /// Converts a value in report units into internal units.
    pub fn from_report(self, value: f64) -> f64 {
        if self.is_scaled() {
            value.to_radians()
        } else {
            value
        }
    }
}

/// A family of parameters, freed or held together (`--free compliance`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Family {
    /// The paper's 21: camera rotation, leg joint offsets, sandal mounting.
    Paper,
    /// The upper camera's rotation offsets (free when a dataset has upper-camera captures).
    UpperCamera,
    /// Head joint offsets.
    Head,
    /// Corrections of the focal lengths and the principal point.
    Intrinsics,
    /// Corrections of the radial distortion k1, k2.
    Distortion,
    /// Corrections of link lengths and the camera position.
    Links,
    /// Joint elasticity under the gravity torque.
    Compliance,
    /// Joint play (backlash) held at one end by gravity.
    Play,
}

/// One row of the family registry: what a family is and where the tools use it. Adding a
/// family is one [`Family`] variant, one row of [`FAMILIES`], its parameters in the
/// parameter registry below and its place in the model; the CLI's help and lists, `--model
/// auto`, `simulate --effects realistic` and the tests read these rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FamilyInfo {
    /// The family.
    pub family: Family,
    /// Its name in `--free`, `--effects`, the result JSON (`compliance`, …).
    pub name: &'static str,
    /// One line on what it models (help texts, docs/MODEL.md §5).
    pub about: &'static str,
    /// Whether `--model auto` may free it. Distortion is not: it belongs to the a-priori
    /// intrinsic calibration (`[camera] distortion`), and its K1/K2 take up what the held
    /// principal point leaves (freeing it raised rms(err/σ) of the paper's parameters from
    /// 1.0 to 4.8 on realistic robots); free it with `--free distortion`.
    pub auto: bool,
    /// Whether `simulate --effects realistic` draws it.
    pub realistic: bool,
}

/// The family registry, in [`Family`] order.
pub const FAMILIES: [FamilyInfo; 8] = [
    FamilyInfo {
        family: Family::Paper,
        name: "paper",
        about: "the paper's 21: camera rotation, leg joint offsets, sandal mounting",
        auto: false,
        realistic: false,
    },
    FamilyInfo {
        family: Family::UpperCamera,
        name: "upper_camera",
        about: "the upper camera's rotation offsets (free when the dataset has upper-camera \
                captures)",
        auto: false,
        realistic: false,
    },
    FamilyInfo {
        family: Family::Head,
        name: "head",
        about: "head joint offsets",
        auto: true,
        realistic: true,
    },
    FamilyInfo {
        family: Family::Intrinsics,
        name: "intrinsics",
        about: "corrections of the focal lengths and the principal point",
        auto: true,
        realistic: true,
    },
    FamilyInfo {
        family: Family::Distortion,
        name: "distortion",
        about: "corrections of the radial distortion k1, k2",
        auto: false,
        realistic: false,
    },
    FamilyInfo {
        family: Family::Links,
        name: "links",
        about: "corrections of link lengths and the camera position",
        auto: true,
        realistic: true,
    },
    FamilyInfo {
        family: Family::Compliance,
        name: "compliance",
        about: "joint elasticity under the gravity torque",
        auto: true,
        realistic: true,
    },
    FamilyInfo {
        family: Family::Play,
        name: "play",
        about: "joint play (backlash) held at one end by gravity",
        auto: true,
        realistic: true,
    },
];

impl Family {
    /// Every family, in registry order.
    pub const ALL: [Family; FAMILIES.len()] = {
        let mut out = [Family::Paper; FAMILIES.len()];
        let mut i = 0;
        while i < FAMILIES.len() {
            out[i] = FAMILIES[i].family;
            i += 1;
        }
        out
    };

    /// The family's row of [`FAMILIES`].
    pub fn info(self) -> &'static FamilyInfo {
        &FAMILIES[self as usize]
    }

    /// The family's name (`paper`, `compliance`, …).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Looks a family up by name.
    pub fn from_name(name: &str) -> Option<Family> {
        Family::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The family's parameters, in registry order.
    pub fn params(self) -> impl Iterator<Item = Param> {
        Param::ALL.into_iter().filter(move |p| p.family() == self)
    }

    /// The families `--model auto` may free, in registry order.
    pub fn auto() -> Vec<Family> {
        Family::ALL.into_iter().filter(|f| f.info().auto).collect()
    }

    /// The families `simulate --effects realistic` draws, in registry order.
    pub fn realistic() -> Vec<Family> {
        Family::ALL
            .into_iter()
            .filter(|f| f.info().realistic)
            .collect()
    }

    /// The names of `families`, comma-separated (for help texts and messages).
    pub fn names(families: impl IntoIterator<Item = Family>) -> String {
        families
            .into_iter()
            .map(Family::name)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
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
    /// Intrinsics and distortion corrections.
    Projection,
    /// Head-side link corrections (neck, camera position, hip spacing).
    BodyLinks,
    /// The left leg's link corrections.
    LeftLinks,
    /// The right leg's link corrections.
    RightLinks,
    /// The left leg's compliance and play.
    LeftElastic,
    /// The right leg's compliance and play.
    RightElastic,
    /// UpperCamYaw, UpperCamPitch, UpperCamRoll.
    UpperCamera,
    /// The upper camera's intrinsics and distortion corrections.
    UpperProjection,
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
            ParamGroup::Projection => "projection",
            ParamGroup::BodyLinks => "body_links",
            ParamGroup::LeftLinks => "left_links",
            ParamGroup::RightLinks => "right_links",
            ParamGroup::LeftElastic => "left_elastic",
            ParamGroup::RightElastic => "right_elastic",
            ParamGroup::UpperCamera => "upper_camera",
            ParamGroup::UpperProjection => "upper_projection",
        }
    }

    /// A small number per group (the Ceres block id).
    pub fn id(self) -> u32 {
        self as u32
    }
}

macro_rules! parameters {
    ($($name:ident: $unit:ident, $family:ident, $group:ident $(, $joint:ident)?;)*) => {
        /// One calibration parameter. The first 21 are the paper's, in the order of its
        /// Table 2; the upper camera's three follow, then the extended model's, held fixed
        /// unless freed, the upper camera's intrinsics and distortion last.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(usize)]
        pub enum Param { $(#[doc = concat!("Parameter `", stringify!($name), "`.")] $name,)* }

        impl Param {
            /// Every parameter, in order.
            pub const ALL: [Param; [$(Param::$name),*].len()] = [$(Param::$name),*];

            /// The parameter's name as in the result JSON and truth.toml.
            pub const fn name(self) -> &'static str {
                match self { $(Param::$name => stringify!($name),)* }
            }

            /// The unit the parameter is reported in.
            pub fn unit(self) -> Unit {
                match self { $(Param::$name => Unit::$unit,)* }
            }

            /// The family the parameter belongs to.
            pub fn family(self) -> Family {
                match self { $(Param::$name => Family::$family,)* }
            }

            /// The solver block this parameter belongs to.
            pub fn group(self) -> ParamGroup {
                match self { $(Param::$name => ParamGroup::$group,)* }
            }

            /// The measured joint a per-joint parameter of the extended model (a
            /// compliance, a play) belongs to; `None` for the others.
            pub fn joint(self) -> Option<Joint> {
                match self { $(Param::$name => None $(.or(Some(Joint::$joint)))?,)* }
            }
        }
    };
}

parameters! {
    CamYaw: Deg, Paper, Camera;
    CamPitch: Deg, Paper, Camera;
    CamRoll: Deg, Paper, Camera;
    LHipYawPitch: Deg, Paper, LeftLeg;
    LHipRoll: Deg, Paper, LeftLeg;
    LHipPitch: Deg, Paper, LeftLeg;
    LKneePitch: Deg, Paper, LeftLeg;
    LAnklePitch: Deg, Paper, LeftLeg;
    LAnkleRoll: Deg, Paper, LeftLeg;
    RHipYawPitch: Deg, Paper, RightLeg;
    RHipRoll: Deg, Paper, RightLeg;
    RHipPitch: Deg, Paper, RightLeg;
    RKneePitch: Deg, Paper, RightLeg;
    RAnklePitch: Deg, Paper, RightLeg;
    RAnkleRoll: Deg, Paper, RightLeg;
    LBoardRotZ: Deg, Paper, LeftBoard;
    LBoardTransX: Mm, Paper, LeftBoard;
    LBoardTransY: Mm, Paper, LeftBoard;
    RBoardRotZ: Deg, Paper, RightBoard;
    RBoardTransX: Mm, Paper, RightBoard;
    RBoardTransY: Mm, Paper, RightBoard;
    UpperCamYaw: Deg, UpperCamera, UpperCamera;
    UpperCamPitch: Deg, UpperCamera, UpperCamera;
    UpperCamRoll: Deg, UpperCamera, UpperCamera;
    HeadYaw: Deg, Head, Head;
    HeadPitch: Deg, Head, Head;
    Fx: Px, Intrinsics, Projection;
    Fy: Px, Intrinsics, Projection;
    Cx: Px, Intrinsics, Projection;
    Cy: Px, Intrinsics, Projection;
    K1: One, Distortion, Projection;
    K2: One, Distortion, Projection;
    LThigh: Mm, Links, LeftLinks;
    LTibia: Mm, Links, LeftLinks;
    LFoot: Mm, Links, LeftLinks;
    RThigh: Mm, Links, RightLinks;
    RTibia: Mm, Links, RightLinks;
    RFoot: Mm, Links, RightLinks;
    HipOffsetY: Mm, Links, BodyLinks;
    NeckZ: Mm, Links, BodyLinks;
    CamX: Mm, Links, BodyLinks;
    CamY: Mm, Links, BodyLinks;
    CamZ: Mm, Links, BodyLinks;
    LHipYawPitchCompliance: DegPerNm, Compliance, LeftElastic, LHipYawPitch;
    LHipRollCompliance: DegPerNm, Compliance, LeftElastic, LHipRoll;
    LHipPitchCompliance: DegPerNm, Compliance, LeftElastic, LHipPitch;
    LKneePitchCompliance: DegPerNm, Compliance, LeftElastic, LKneePitch;
    LAnklePitchCompliance: DegPerNm, Compliance, LeftElastic, LAnklePitch;
    LAnkleRollCompliance: DegPerNm, Compliance, LeftElastic, LAnkleRoll;
    RHipYawPitchCompliance: DegPerNm, Compliance, RightElastic, RHipYawPitch;
    RHipRollCompliance: DegPerNm, Compliance, RightElastic, RHipRoll;
    RHipPitchCompliance: DegPerNm, Compliance, RightElastic, RHipPitch;
    RKneePitchCompliance: DegPerNm, Compliance, RightElastic, RKneePitch;
    RAnklePitchCompliance: DegPerNm, Compliance, RightElastic, RAnklePitch;
    RAnkleRollCompliance: DegPerNm, Compliance, RightElastic, RAnkleRoll;
    LHipYawPitchPlay: Deg, Play, LeftElastic, LHipYawPitch;
    LHipRollPlay: Deg, Play, LeftElastic, LHipRoll;
    LHipPitchPlay: Deg, Play, LeftElastic, LHipPitch;
    LKneePitchPlay: Deg, Play, LeftElastic, LKneePitch;
    LAnklePitchPlay: Deg, Play, LeftElastic, LAnklePitch;
    LAnkleRollPlay: Deg, Play, LeftElastic, LAnkleRoll;
    RHipYawPitchPlay: Deg, Play, RightElastic, RHipYawPitch;
    RHipRollPlay: Deg, Play, RightElastic, RHipRoll;
    RHipPitchPlay: Deg, Play, RightElastic, RHipPitch;
    RKneePitchPlay: Deg, Play, RightElastic, RKneePitch;
    RAnklePitchPlay: Deg, Play, RightElastic, RAnklePitch;
    RAnkleRollPlay: Deg, Play, RightElastic, RAnkleRoll;
    UpperFx: Px, Intrinsics, UpperProjection;
    UpperFy: Px, Intrinsics, UpperProjection;
    UpperCx: Px, Intrinsics, UpperProjection;
    UpperCy: Px, Intrinsics, UpperProjection;
    UpperK1: One, Distortion, UpperProjection;
    UpperK2: One, Distortion, UpperProjection;
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

    /// The parameter of `family` that belongs to `joint` (its compliance, its play), from
    /// the registry's joint column; `None` when the family has none for that joint.
    pub fn of_joint(family: Family, joint: Joint) -> Option<Param> {
        Param::ALL
            .into_iter()
            .find(|p| p.family() == family && p.joint() == Some(joint))
    }

    /// Looks a parameter up by its name (exact, case-sensitive).
    pub fn from_name(name: &str) -> Option<Param> {
        Param::ALL.iter().copied().find(|p| p.name() == name)
    }

    /// Whether the parameter is held fixed unless asked otherwise (all but the paper's).
    pub fn fixed_by_default(self) -> bool {
        self.family() != Family::Paper
    }

    /// Whether the parameter corrects the upper camera's intrinsics or distortion
    /// (`UpperFx` … `UpperK2`): part of a problem only when it has upper-camera captures.
    pub fn is_upper_projection(self) -> bool {
        self.group() == ParamGroup::UpperProjection
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which parameters are held fixed in a solve.
///
/// Besides the mask it remembers which parameters were held on purpose ([`FixedSet::set`],
/// [`FixedSet::with`], `--fix`) and which were asked to be free: the upper camera's
/// parameters are part of a problem only when it has upper-camera captures
/// ([`FixedSet::for_upper_camera`]). Its rotation offsets, held by default, are then freed
/// unless held on purpose; its intrinsics and distortion (`UpperFx` … `UpperK2`) are free
/// when asked (`--free intrinsics` frees both cameras'), and held whenever there are no
/// upper-camera captures, whatever was asked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FixedSet {
    held: [bool; PARAMETER_COUNT],
    pinned: [bool; PARAMETER_COUNT],
    wanted: [bool; PARAMETER_COUNT],
    upper: bool,
}

impl Default for FixedSet {
    fn default() -> Self {
        let held = Param::ALL.map(Param::fixed_by_default);
        FixedSet {
            held,
            pinned: [false; PARAMETER_COUNT],
            wanted: held,
            upper: false,
        }
    }
}

impl FixedSet {
    /// The default set, with `extra` also held fixed.
    pub fn with(extra: &[Param]) -> Self {
        let mut set = FixedSet::default();
        for p in extra {
            set.set(*p, true);
        }
        set
    }

    /// The default set with `free` freed, then `fix` held (lists of family and parameter
    /// names, as `--free` and `--fix` take them).
    pub fn from_lists(free: &str, fix: &str) -> Result<Self, String> {
        let mut set = FixedSet::default();
        for p in parse_param_list(free).map_err(|e| format!("--free: {e}"))? {
            set.set(p, false);
        }
        for p in parse_param_list(fix).map_err(|e| format!("--fix: {e}"))? {
            set.set(p, true);
        }
        Ok(set)
    }

    /// Holds `param` fixed (on purpose), or frees it (the upper camera's intrinsics only
    /// once the set is for a problem with upper-camera captures).
    pub fn set(&mut self, param: Param, fixed: bool) {
        let i = param.index();
        self.wanted[i] = fixed;
        self.pinned[i] = fixed;
        self.held[i] = fixed || (param.is_upper_projection() && !self.upper);
    }

    /// Whether `param` is held fixed.
    pub fn is_fixed(&self, param: Param) -> bool {
        self.held[param.index()]
    }

    /// The set for a problem with (`upper`) or without upper-camera captures: the upper
    /// camera's rotation offsets are freed when it has some, unless held on purpose; its
    /// intrinsics are free as asked when it has some; all are held when it has none (no
    /// capture depends on them).
    pub fn for_upper_camera(mut self, upper: bool) -> Self {
        self.upper = upper;
        for p in Family::UpperCamera.params() {
            self.held[p.index()] = !upper || self.pinned[p.index()];
        }
        for p in Param::ALL.into_iter().filter(|p| p.is_upper_projection()) {
            self.held[p.index()] = !upper || self.wanted[p.index()];
        }
        self
    }

    /// Whether `param` is part of the fitted model: false for the upper camera's rotation
    /// offsets of a problem without upper-camera captures (held, and not on purpose), and
    /// for its intrinsics unless free (or held on purpose in a problem with upper-camera
    /// captures); results and reports leave those out.
    pub fn in_model(&self, param: Param) -> bool {
        let i = param.index();
        if param.is_upper_projection() {
            !self.held[i] || (self.pinned[i] && self.upper)
        } else {
            param.family() != Family::UpperCamera || !self.held[i] || self.pinned[i]
        }
    }

    /// Whether `param` may be freed in this problem (`--model auto`'s candidates, the
    /// misfit tests): every parameter of the model, and the upper camera's intrinsics when
    /// the problem has upper-camera captures.
    pub fn can_free(&self, param: Param) -> bool {
        self.in_model(param) || (param.is_upper_projection() && self.upper)
    }

    /// Whether reports list `param` in their tables: the paper's parameters, the upper
    /// camera's when part of the model, and every free one.
    pub fn is_shown(&self, param: Param) -> bool {
        param.family() == Family::Paper
            || (param.family() == Family::UpperCamera && self.in_model(param))
            || !self.is_fixed(param)
    }

    /// The free parameters, in order.
    pub fn free(&self) -> Vec<Param> {
        Param::ALL
            .iter()
            .copied()
            .filter(|p| !self.is_fixed(*p))
            .collect()
    }

    /// The families with at least one free parameter, in registry order.
    pub fn families(&self) -> Vec<Family> {
        Family::ALL
            .into_iter()
            .filter(|f| f.params().any(|p| !self.is_fixed(p)))
            .collect()
    }

    /// A mask indexed by [`Param::index`].
    pub fn mask(&self) -> &[bool; PARAMETER_COUNT] {
        &self.held
    }
}

/// Parses a comma-separated list of family and parameter names (`compliance,play,Fx`)
/// into the parameters they name, in order, without repeats.
pub fn parse_param_list(list: &str) -> Result<Vec<Param>, String> {
    let mut out: Vec<Param> = Vec::new();
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let named: Vec<Param> = if let Some(family) = Family::from_name(name) {
            family.params().collect()
        } else if let Some(p) = Param::from_name(name) {
            vec![p]
        } else {
            let families: Vec<_> = Family::ALL.iter().map(|f| f.name()).collect();
            let names: Vec<_> = Param::ALL.iter().map(|p| p.name()).collect();
            return Err(format!(
                "unknown parameter or family '{name}' (families: {}; parameters: {})",
                families.join(", "),
                names.join(", ")
            ));
        };
        for p in named {
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    Ok(out)
}

impl Joint {
    /// The calibration parameter that offsets this joint (`q = θ + α`): the registry's
    /// parameter of the joint's name.
    pub fn offset(self) -> Param {
        JOINT_OFFSETS[self.index()]
    }

    /// The joint's compliance parameter (leg joints only), from the parameter registry.
    pub fn compliance(self) -> Option<Param> {
        Param::of_joint(Family::Compliance, self)
    }

    /// The joint's play parameter (leg joints only), from the parameter registry.
    pub fn play(self) -> Option<Param> {
        Param::of_joint(Family::Play, self)
    }
}

/// Each joint's offset parameter, in [`Joint::ALL`] order: the registry's parameter named
/// as the joint, found when compiling (a joint without one does not compile).
const JOINT_OFFSETS: [Param; JOINT_COUNT] = {
    const fn same(a: &str, b: &str) -> bool {
        let (a, b) = (a.as_bytes(), b.as_bytes());
        if a.len() != b.len() {
            return false;
        }
        let mut i = 0;
        while i < a.len() {
            if a[i] != b[i] {
                return false;
            }
            i += 1;
        }
        true
    }
    let mut offsets = [Param::CamYaw; JOINT_COUNT];
    let mut j = 0;
    while j < JOINT_COUNT {
        let name = Joint::ALL[j].name();
        let mut k = 0;
        while !same(Param::ALL[k].name(), name) {
            k += 1; // past the registry's end: no offset for this joint, a compile error
        }
        offsets[j] = Param::ALL[k];
        j += 1;
    }
    offsets
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_has_the_extended_model() {
        assert_eq!(PARAMETER_COUNT, 73);
        let count = |f: Family| f.params().count();
        assert_eq!(count(Family::Paper), PAPER_PARAMETERS);
        assert_eq!(count(Family::UpperCamera), 3);
        assert_eq!(count(Family::Head), 2);
        assert_eq!(count(Family::Intrinsics), 8);
        assert_eq!(count(Family::Distortion), 4);
        assert_eq!(count(Family::Links), 11);
        assert_eq!(count(Family::Compliance), 12);
        assert_eq!(count(Family::Play), 12);
        assert!(
            Param::ALL[..PAPER_PARAMETERS]
                .iter()
                .all(|p| p.family() == Family::Paper)
        );
        let list = parse_param_list("compliance, Fx,LHipPitchCompliance").unwrap();
        assert_eq!(list.len(), 13);
        assert_eq!(list[12], Param::Fx);
        assert!(
            parse_param_list("elasticity")
                .unwrap_err()
                .contains("elasticity")
        );
    }

    #[test]
    fn the_upper_camera_is_free_only_with_upper_captures_unless_held_on_purpose() {
        let upper: Vec<Param> = Family::UpperCamera.params().collect();
        assert_eq!(
            upper,
            [
                Param::UpperCamYaw,
                Param::UpperCamPitch,
                Param::UpperCamRoll
            ]
        );
        let default = FixedSet::default();
        assert!(upper.iter().all(|&p| default.is_fixed(p)));
        let with = default.clone().for_upper_camera(true);
        assert!(upper.iter().all(|&p| !with.is_fixed(p) && with.in_model(p)));
        let without = FixedSet::from_lists("upper_camera", "")
            .unwrap()
            .for_upper_camera(false);
        assert!(
            upper
                .iter()
                .all(|&p| without.is_fixed(p) && !without.in_model(p))
        );
        assert!(upper.iter().all(|&p| !without.is_shown(p)));
        let pinned = FixedSet::from_lists("", "UpperCamYaw")
            .unwrap()
            .for_upper_camera(true);
        assert!(pinned.is_fixed(Param::UpperCamYaw) && pinned.in_model(Param::UpperCamYaw));
        assert!(pinned.is_shown(Param::UpperCamYaw) && !pinned.is_fixed(Param::UpperCamRoll));
        // Nothing else changes.
        for p in Param::ALL
            .into_iter()
            .filter(|p| !upper.contains(p) && !p.is_upper_projection())
        {
            assert_eq!(with.is_fixed(p), default.is_fixed(p));
            assert!(with.in_model(p) && without.in_model(p));
        }
    }

    #[test]
    fn the_upper_cameras_intrinsics_are_free_with_the_lower_ones_only_with_upper_captures() {
        let intrinsics: Vec<Param> = Param::ALL
            .into_iter()
            .filter(|p| p.is_upper_projection())
            .collect();
        assert_eq!(
            intrinsics.iter().map(|p| p.name()).collect::<Vec<_>>(),
            [
                "UpperFx", "UpperFy", "UpperCx", "UpperCy", "UpperK1", "UpperK2"
            ]
        );
        let free = FixedSet::from_lists("intrinsics", "").unwrap();
        // Both cameras' focal lengths and centres are freed, the distortion stays held.
        let with = free.clone().for_upper_camera(true);
        for p in Family::Intrinsics.params() {
            assert!(
                !with.is_fixed(p) && with.in_model(p) && with.is_shown(p),
                "{p}"
            );
        }
        assert!(with.is_fixed(Param::UpperK1) && !with.in_model(Param::UpperK1));
        assert!(with.can_free(Param::UpperK1));
        // Without upper captures they are held and left out, whatever was asked.
        let without = free.clone().for_upper_camera(false);
        for &p in &intrinsics {
            assert!(without.is_fixed(p) && !without.in_model(p) && !without.is_shown(p));
            assert!(!without.can_free(p));
        }
        assert_eq!(
            without.free(),
            FixedSet::from_lists("Fx,Fy,Cx,Cy", "").unwrap().free()
        );
        // Freed later (as --model auto does) they follow the same rule.
        let mut auto = FixedSet::default().for_upper_camera(false);
        auto.set(Param::UpperFx, false);
        assert!(auto.is_fixed(Param::UpperFx) && !auto.in_model(Param::UpperFx));
        let mut auto = FixedSet::default().for_upper_camera(true);
        assert!(!auto.in_model(Param::UpperFx) && auto.can_free(Param::UpperFx));
        auto.set(Param::UpperFx, false);
        assert!(!auto.is_fixed(Param::UpperFx) && auto.in_model(Param::UpperFx));
        // Held on purpose in a problem with upper captures: part of the model, held.
        let pinned = FixedSet::from_lists("intrinsics", "UpperCx")
            .unwrap()
            .for_upper_camera(true);
        assert!(pinned.is_fixed(Param::UpperCx) && pinned.in_model(Param::UpperCx));
        assert!(!pinned.is_fixed(Param::UpperCy));
        // The default set is what it was: none of them free or in the model.
        let default = FixedSet::default().for_upper_camera(true);
        assert!(
            intrinsics
                .iter()
                .all(|&p| default.is_fixed(p) && !default.in_model(p))
        );
    }

    #[test]
    fn the_family_registry_is_in_family_order_with_unique_names() {
        for (i, row) in FAMILIES.iter().enumerate() {
            assert_eq!(row.family as usize, i, "{}", row.name);
            assert_eq!(Family::from_name(row.name), Some(row.family));
            assert!(
                row.family.params().count() > 0,
                "{} has no parameters",
                row.name
            );
        }
        assert!(!Family::Paper.info().auto && !Family::Paper.info().realistic);
    }
}

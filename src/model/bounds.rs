//! Physical bounds of every calibration parameter: the values a real NAO can have. A fit
//! outside them is no calibration, however small its residuals (a focal length fitted to
//! zero explains corners that are all one pixel "to rounding"); such a result never
//! becomes a robot file, and `--model auto` does not free a family whose fit leaves them.
//!
//! The bounds follow from each parameter's family and unit in the registry
//! ([`super::parameters`]), in report units (deg, mm, px, 1, deg/(N·m)):
//!
//! | family | parameters | bound | why |
//! |---|---|---|---|
//! | paper | camera rotations, joint offsets, sandal rotations (deg) | ±30° | an offset is a correction of a mounting or an encoder; 30° is far beyond any (the paper's are below 2°, a lower camera's tilt correction below 8°) |
//! | paper | sandal translations (mm) | ±50 mm | the sandal is strapped to the foot, whose sole is about 100 mm × 160 mm |
//! | head | HeadYaw, HeadPitch (deg) | ±30° | as the joint offsets |
//! | intrinsics | Fx, Fy corrections (px) | ±280 px | half the smallest nominal focal length of a NAO camera (V4: 562.5 px at 640 × 480): the focal length stays positive |
//! | intrinsics | Cx, Cy corrections (px) | ±160 px | a quarter of a 640 px image: the principal point stays inside the image |
//! | distortion | K1, K2 corrections | ±1 | the NAO's lenses have \|k\| below 0.2 |
//! | links | link-length and camera-position corrections (mm) | ±20 mm | the shortest nominal link (the foot height, 45.19 mm) stays positive; manufacturing tolerances are below 1 mm |
//! | compliance | per joint (deg/(N·m)) | 0 … 2 | a joint bends with its load, never against it; 2 deg/(N·m) would let a standing leg's knee give 10° |
//! | play | per joint (deg) | 0 … 5 | backlash is a width, never negative; a NAO's is below 1° |

use super::parameters::{Family, Param, Unit};

/// The physical range of one parameter, in report units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// Smallest physical value.
    pub min: f64,
    /// Largest physical value.
    pub max: f64,
    /// Why: what a value beyond the bound would mean.
    pub why: &'static str,
}

impl Bound {
    /// Whether `value` (report units) is a finite number within the bound.
    pub fn contains(&self, value: f64) -> bool {
        value.is_finite() && (self.min..=self.max).contains(&value)
    }

    /// Whether an estimate `value` with one-sigma `sigma` (report units) is consistent
    /// with the bound: within it, where a limit of zero (compliance and play are never
    /// negative) is widened by [`SIGMAS`] σ, capped at [`MAX_SLACK`] of the bound's width
    /// — a joint without play has its play estimated slightly negative half the time, but
    /// a σ as wide as the bound excuses nothing. Limits away from zero (±30° for an
    /// offset) are far from any real estimate and are not widened.
    pub fn admits(&self, value: f64, sigma: f64) -> bool {
        let cap = MAX_SLACK * (self.max - self.min);
        let slack = if sigma.is_finite() && sigma > 0.0 {
            (SIGMAS * sigma).min(cap)
        } else {
            0.0
        };
        let at_zero = |limit: f64| if limit == 0.0 { slack } else { 0.0 };
        value.is_finite()
            && (self.min - at_zero(self.min)..=self.max + at_zero(self.max)).contains(&value)
    }
}

impl Bound {
    /// Whether an intermediate estimate (a screening fit of `--model auto`, before the
    /// families that would explain the rest are free) is consistent with the bound: within
    /// it widened by [`SIGMAS`] σ at both limits, without a cap. A parameter the fit
    /// cannot determine yet (an ankle roll's compliance lying down, before play is free)
    /// may wander far; one the data pin down beyond the bound (a focal length fitted to
    /// zero) may not. The final calibration is held to [`Bound::admits`].
    pub fn admits_at_screening(&self, value: f64, sigma: f64) -> bool {
        let slack = if sigma.is_finite() && sigma > 0.0 {
            SIGMAS * sigma
        } else {
            0.0
        };
        value.is_finite() && (self.min - slack..=self.max + slack).contains(&value)
    }
}

/// The parameters of `params` whose screening estimate in `values` with one-sigma `std`
/// (internal units) is not consistent with its bound ([`Bound::admits_at_screening`]).
pub fn violations_at_screening(
    values: &[f64; super::PARAMETER_COUNT],
    std: &[f64; super::PARAMETER_COUNT],
    params: impl IntoIterator<Item = Param>,
) -> Vec<Violation> {
    params
        .into_iter()
        .filter_map(|param| {
            let unit = param.unit();
            let value = unit.to_report(values[param.index()]);
            let sigma = unit.to_report(std[param.index()]);
            let bound = bound(param);
            (!bound.admits_at_screening(value, sigma)).then_some(Violation {
                param,
                value,
                bound,
            })
        })
        .collect()
}

/// How many standard deviations an estimate may lie beyond its bound ([`Bound::admits`]).
pub const SIGMAS: f64 = 3.0;

/// The most an estimate may lie beyond its bound, as a fraction of the bound's width
/// ([`Bound::admits`]).
pub const MAX_SLACK: f64 = 0.5;

/// The physical bound of `param` (report units), from its family and unit (see the
/// module's table).
pub fn bound(param: Param) -> Bound {
    let sym = |limit: f64, why| Bound {
        min: -limit,
        max: limit,
        why,
    };
    match (param.family(), param.unit()) {
        (Family::Paper | Family::UpperCamera | Family::Head, Unit::Deg) => sym(
            30.0,
            "an angle offset beyond ±30° is no mounting or encoder error",
        ),
        (Family::Paper, _) => sym(50.0, "the sandal is strapped to the foot"),
        (Family::Intrinsics, _)
            if matches!(
                param,
                Param::Fx | Param::Fy | Param::UpperFx | Param::UpperFy
            ) =>
        {
            sym(
                280.0,
                "the focal length must stay positive (half of the smallest NAO focal length)",
            )
        }
        (Family::Intrinsics, _) => sym(160.0, "the principal point must stay in the image"),
        (Family::Distortion, _) => sym(1.0, "the NAO's lenses have |k| below 0.2"),
        (Family::Links, _) => sym(
            20.0,
            "link lengths must stay positive (the foot height is 45.19 mm)",
        ),
        (Family::Compliance, _) => Bound {
            min: 0.0,
            max: 2.0,
            why: "a joint gives with its load, never against it",
        },
        (Family::Play, _) => Bound {
            min: 0.0,
            max: 5.0,
            why: "play is a width, never negative",
        },
        (Family::Head | Family::UpperCamera, _) => {
            sym(30.0, "an angle offset beyond ±30° is no encoder error")
        }
    }
}

/// A parameter value outside its physical bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Violation {
    /// The parameter.
    pub param: Param,
    /// Its value, report units.
    pub value: f64,
    /// The bound it leaves.
    pub bound: Bound,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = self.param.unit().name();
        write!(
            f,
            "{} = {} {unit} is outside {} … {} {unit} ({})",
            self.param.name(),
            self.value,
            self.bound.min,
            self.bound.max,
            self.bound.why
        )
    }
}

/// The values of `values` (pairs of parameter and value in report units) outside their
/// physical bounds.
pub fn violations(values: impl IntoIterator<Item = (Param, f64)>) -> Vec<Violation> {
    violations_of_estimates(values.into_iter().map(|(p, v)| (p, v, 0.0)))
}

/// The estimates of `estimates` (parameter, value, one-sigma; report units) that are not
/// consistent with their physical bounds ([`Bound::admits`]).
pub fn violations_of_estimates(
    estimates: impl IntoIterator<Item = (Param, f64, f64)>,
) -> Vec<Violation> {
    estimates
        .into_iter()
        .filter_map(|(param, value, sigma)| {
            let bound = bound(param);
            (!bound.admits(value, sigma)).then_some(Violation {
                param,
                value,
                bound,
            })
        })
        .collect()
}

/// The parameters of `params` whose estimate in `values` with one-sigma `std` (every
/// parameter, internal units: rad, mm, px; `std` `None` for the widest slack, as for a
/// fit whose σ is not known yet) is not consistent with its physical bound.
pub fn violations_internal(
    values: &[f64; super::PARAMETER_COUNT],
    std: Option<&[f64; super::PARAMETER_COUNT]>,
    params: impl IntoIterator<Item = Param>,
) -> Vec<Violation> {
    violations_of_estimates(params.into_iter().map(|p| {
        let unit = p.unit();
        let sigma = std.map_or(f64::INFINITY, |s| unit.to_report(s[p.index()]));
        let sigma = if sigma.is_infinite() { f64::MAX } else { sigma };
        (p, unit.to_report(values[p.index()]), sigma)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_parameter_has_a_bound_that_holds_zero_and_realistic_values() {
        for p in Param::ALL {
            let b = bound(p);
            assert!(b.min < b.max, "{p}");
            assert!(b.contains(0.0), "{p}: zero is the nominal robot");
            assert!(!b.contains(f64::NAN) && !b.contains(f64::INFINITY), "{p}");
        }
        // Sizes of real robots (the simulator's realistic effects) are inside.
        for (p, v) in [
            (Param::CamPitch, -8.0),
            (Param::LKneePitch, 2.0),
            (Param::Fx, 10.0),
            (Param::LThigh, 0.5),
            (Param::LKneePitchCompliance, 0.3),
            (Param::RHipPitchPlay, 0.5),
        ] {
            assert!(bound(p).contains(v), "{p} = {v}");
        }
    }

    #[test]
    fn the_issues_garbage_is_outside() {
        let bad = violations([
            (Param::CamPitch, 1e300),
            (Param::LKneePitch, 720.0),
            (Param::Fx, -600.0),
            (Param::LThigh, -150.0),
            (Param::LKneePitchPlay, -0.1),
            (Param::LHipRollCompliance, -0.01),
            (Param::CamYaw, 39.6),
        ]);
        assert_eq!(bad.len(), 7, "{bad:?}");
        assert!(bad[0].to_string().starts_with("CamPitch = "), "{}", bad[0]);
        assert!(violations([(Param::CamYaw, 1.0)]).is_empty());
        let mut values = [0.0; crate::model::PARAMETER_COUNT];
        values[Param::CamRoll.index()] = 31f64.to_radians();
        let std = [0.0; crate::model::PARAMETER_COUNT];
        assert_eq!(
            violations_internal(&values, Some(&std), Param::ALL)
                .iter()
                .map(|v| v.param)
                .collect::<Vec<_>>(),
            [Param::CamRoll]
        );
        // Within σ of a bound is consistent with it; far beyond is not, whatever the σ.
        let play = bound(Param::LKneePitchPlay);
        assert!(play.admits(-0.02, 0.01) && !play.admits(-0.02, 0.005));
        assert!(!play.admits(-2.6, 10.0), "the slack is capped");
        assert_eq!(
            violations_internal(&values, None, Param::ALL).len(),
            1,
            "no slack at 30°"
        );
    }
}

//! Property: any result JSON that `export` accepts for robot files produces
//! robot files whose values, read back with the team readers, are inside the physical
//! bounds of `naocalib::model::bounds`. The generated results mix plausible values with
//! garbage (huge, negative, non-physical), missing keys and odd fit summaries.

use std::path::Path;

use naocalib::export::{BHUMAN_JOINTS, Calibration, Format, bhuman};
use naocalib::model::CameraId;
use naocalib::model::Param;
use naocalib::model::bounds::bound;
use proptest::prelude::*;

/// A value for a parameter: mostly plausible, sometimes far out (any sign, any size).
fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -3.0..3.0f64,
        1 => -1e4..1e4f64,
        1 => prop_oneof![Just(1e300), Just(-1e300), Just(720.0), Just(-600.0), Just(45.0)],
    ]
}

/// A result JSON as `naocalib solve --json` writes it, with generated values.
fn result() -> impl Strategy<Value = serde_json::Value> {
    (
        proptest::collection::vec((value(), 0.0..0.5f64, any::<bool>()), Param::ALL.len()),
        proptest::option::of(any::<bool>()),
        (-1.0..5.0f64, -1.0..5.0f64),
    )
        .prop_map(|(values, converged, rms)| {
            let mut parameters = serde_json::Map::new();
            for (p, (v, s, fixed)) in Param::ALL.iter().zip(values) {
                parameters.insert(
                    p.name().to_string(),
                    serde_json::json!({"value": v, "std": s, "fixed": fixed && p.index() > 20}),
                );
            }
            let mut json = serde_json::json!({
                "solver": "lm",
                "rms_px": [rms.0, rms.1],
                "parameters": parameters,
            });
            if let Some(c) = converged {
                json["converged"] = c.into();
            }
            json
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn accepted_results_give_robot_files_within_the_bounds(json in result()) {
        let text = serde_json::to_string(&json).unwrap();
        let Ok(cal) = Calibration::from_json(&text, Path::new("r.json")) else {
            return Ok(());
        };
        if !cal.problems().is_empty() {
            // Refused for robot files (what `export` does without --allow-unconverged).
            return Ok(());
        }
        let camera = bhuman::Camera.write(&cal);
        let [x, y, z] = bhuman::Camera::stored(&camera, Path::new("c.cfg"), CameraId::Lower)
            .unwrap()
            .unwrap();
        for (p, v) in [(Param::CamRoll, x), (Param::CamPitch, y), (Param::CamYaw, z)] {
            prop_assert!(bound(p).contains(v), "{p} = {v} in {camera}");
        }
        let joints = bhuman::Joints.write(&cal);
        for (name, v) in bhuman::Joints::stored(&joints, Path::new("j.cfg")).unwrap() {
            let param = BHUMAN_JOINTS
                .iter()
                .find(|(n, _)| *n == name)
                .and_then(|(_, p)| *p);
            if let Some(p) = param {
                // Team files store −α; the bound of an offset is symmetric.
                prop_assert!(bound(p).contains(-v) && bound(p).contains(v), "{name} = {v}");
            } else {
                prop_assert!(v == 0.0, "{name} = {v} is not calibrated");
            }
        }
    }
}

#[test]
fn the_property_sees_both_accepted_and_refused_results() {
    // The generator is not vacuous: plausible results pass, garbage is refused.
    let mut good = serde_json::json!({"solver": "lm", "converged": true, "rms_px": [0.3, 0.3]});
    let mut parameters = serde_json::Map::new();
    for p in Param::ALL {
        parameters.insert(
            p.name().into(),
            serde_json::json!({"value": 0.5, "std": 0.1}),
        );
    }
    good["parameters"] = parameters.into();
    let cal = Calibration::from_json(&good.to_string(), Path::new("g.json")).unwrap();
    assert!(cal.problems().is_empty(), "{:?}", cal.problems());
    let mut bad = good.clone();
    bad["parameters"]["LKneePitch"]["value"] = 720.0.into();
    let cal = Calibration::from_json(&bad.to_string(), Path::new("b.json")).unwrap();
    assert!(
        cal.problems().iter().any(|p| p.contains("LKneePitch")),
        "{:?}",
        cal.problems()
    );
}

//! A held parameter correlated with a reported one: the reported σ assumes the held one at
//! its nominal value, and says so in the table and the JSON.

use crate::util::{naocalib, stderr};

/// A lower-camera robot whose principal point is off by 3 px (`simulate --effects
/// intrinsics --seed 4`, 6 stances of 2 head postures), solved with its intrinsics free: Cy
/// is undetermined and held at nominal, and Fy (7.6σ off the truth) has its σ marked as
/// assuming Cy, with how far an error of Cy moves it, in the table and the JSON.
#[test]
fn a_sigma_that_assumes_a_held_parameter_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("robot");
    let out = naocalib()
        .args(["simulate", "--effects", "intrinsics", "--seed", "4"])
        .args(["--stances", "6", "--heads", "2"])
        .arg(&data)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .args(["--free", "intrinsics", "--json"])
        .output()
        .unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", stderr(&out)));
    let undetermined: Vec<&str> = json["undetermined"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|u| u["parameter"].as_str())
        .collect();
    assert!(undetermined.contains(&"Cy"), "{}", json["undetermined"]);
    let fy = &json["parameters"]["Fy"];
    let ratio = fy["std_assumes_held"]["Cy"]
        .as_f64()
        .unwrap_or_else(|| panic!("Fy: {fy}"));
    let sigma = fy["std"].as_f64().unwrap();
    assert!(ratio.abs() > sigma, "{ratio} vs σ {sigma}");
    // Fy is off the truth by more than 5σ: the σ alone would have hidden it.
    let (value, truth) = (fy["value"].as_f64().unwrap(), fy["truth"].as_f64().unwrap());
    assert!((value - truth).abs() > 5.0 * sigma, "{fy}");
    // A parameter no held one moves says nothing.
    let params = json["parameters"].as_object().unwrap();
    assert!(
        params.values().any(|p| p.get("std_assumes_held").is_none()),
        "every σ marked"
    );
    let out = naocalib()
        .arg("solve")
        .arg(&data)
        .args(["--free", "intrinsics"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let row = text
        .lines()
        .find(|l| l.split_whitespace().next() == Some("Fy"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(row.contains('†'), "{row}");
    assert!(
        text.contains("† Fy: its σ") && text.contains("is not honest: it assumes Cy at nominal"),
        "{text}"
    );
}

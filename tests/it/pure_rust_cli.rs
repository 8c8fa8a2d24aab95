//! `naocalib compare` from the command line: every solver of the build in the table and
//! the JSON, and the reference named.

use crate::util::{naocalib, simulate_small};

use naocalib::solve::backend_names;

#[test]
fn compare_prints_every_solver() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("ds");
    simulate_small(&dir, 3);
    let out = naocalib().arg("compare").arg(&dir).output().expect("ran");
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in backend_names() {
        assert!(
            stdout
                .lines()
                .any(|l| l.starts_with(&format!("{name} ")) && l.contains("yes")),
            "{name} missing or not converged"
        );
    }
    assert!(stdout.contains("CamYaw") && stdout.contains("RBoardTransY"));
    if cfg!(feature = "ceres") {
        assert!(stdout.contains("reference: ceres"));
    } else {
        assert!(stdout.contains("reference: lm (no Ceres"));
    }
}

#[test]
fn compare_json_has_every_solver_and_parameter() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("ds");
    simulate_small(&dir, 3);
    let out = naocalib()
        .args(["compare", "--json", "--fix", "CamYaw"])
        .arg(&dir)
        .output()
        .expect("ran");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let solvers = v["solvers"].as_array().expect("solvers");
    let names: Vec<&str> = solvers
        .iter()
        .map(|s| s["solver"].as_str().unwrap())
        .collect();
    assert_eq!(names, backend_names());
    for s in solvers {
        assert_eq!(s["converged"], true, "{s}");
        let d = s["max_sigma_difference"].as_f64().expect("difference");
        assert!(d < 0.01, "{s}");
    }
    let params = v["parameters"].as_object().expect("parameters");
    assert_eq!(params.len(), 20, "CamYaw is held");
    assert!(!params.contains_key("CamYaw"));
    assert_eq!(v["reference_is_ceres"], cfg!(feature = "ceres"));
}

#[test]
fn compare_with_loss_and_unknown_solver() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("ds");
    simulate_small(&dir, 3);
    let out = naocalib()
        .args(["compare", "--json", "--loss", "cauchy:0.5"])
        .arg(&dir)
        .output()
        .expect("ran");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for s in v["solvers"].as_array().expect("solvers") {
        assert!(
            s["max_sigma_difference"].as_f64().expect("difference") < 0.01,
            "{s}"
        );
    }
    let out = naocalib()
        .args(["compare", "--solvers", "lm,bogus"])
        .arg(&dir)
        .output()
        .expect("ran");
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown solver 'bogus'"));
}

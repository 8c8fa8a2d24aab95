//! The extended model (docs/MODEL.md): each family's effect is recovered exactly from
//! noise-free data when that family is freed, several at once too; the backends agree on
//! extended problems; families that trade against each other are held and named, never
//! printed as numbers; bad family names are refused.

use naocalib::model::{Family, FixedSet, Model, PARAMETER_COUNT, Param};
use naocalib::sim::{SimOptions, simulate};
use naocalib::solve::{Problem, Solution, UncertaintyOptions, backend, backend_names, calibrate};

use crate::util::{assert_clean_failure, determined_truth, naocalib, stderr};

/// A noise-free dataset of `stances` stances × 2 head postures per leg whose robot has the
/// effects of `effects`, and its truth.
fn noise_free(
    effects: &[Family],
    seed: u64,
    stances: usize,
) -> (naocalib::dataset::Dataset, [f64; PARAMETER_COUNT]) {
    let options = SimOptions {
        seed,
        stances,
        heads: 2,
        px_noise: 0.0,
        effects: effects.to_vec(),
        ..SimOptions::default()
    };
    let dataset = simulate(&Model::default(), &options).expect("simulated");
    let truth = dataset.truth.as_ref().expect("truth").values;
    (dataset, truth)
}

fn free(families: &[Family]) -> FixedSet {
    let mut fixed = FixedSet::default();
    for f in families {
        for p in f.params() {
            fixed.set(p, false);
        }
    }
    fixed
}

/// Largest |estimate − truth| in report units over the free parameters.
fn worst_error(solution: &Solution, truth: &[f64; PARAMETER_COUNT]) -> (f64, Param) {
    solution
        .fixed
        .free()
        .into_iter()
        .map(|p| {
            let e = p
                .unit()
                .to_report(solution.values[p.index()] - truth[p.index()])
                .abs();
            (e, p)
        })
        .fold((0.0, Param::CamYaw), |a, b| if b.0 > a.0 { b } else { a })
}

fn solve_free(families: &[Family], seed: u64) -> (Solution, [f64; PARAMETER_COUNT]) {
    let (dataset, truth) = noise_free(families, seed, 12);
    let problem = Problem::from_dataset(&dataset, free(families)).expect("problem");
    let solver = backend(backend_names()[0], false).expect("backend");
    let solution =
        calibrate(&problem, solver.as_ref(), &UncertaintyOptions::default()).expect("solved");
    (solution, truth)
}

#[test]
fn each_family_is_recovered_from_noise_free_data() {
    for family in [
        Family::Head,
        Family::Intrinsics,
        Family::Distortion,
        Family::Links,
        Family::Compliance,
        Family::Play,
    ] {
        let (solution, truth) = solve_free(&[family], 11);
        assert!(
            solution.summary.converged,
            "{family}: {:?}",
            solution.summary
        );
        assert!(solution.values.iter().all(|v| v.is_finite()));
        let truth = determined_truth(&solution, &truth);
        let (err, p) = worst_error(&solution, &truth);
        assert!(err < 1e-6, "{family}: {p} off by {err:e}");
        assert!(
            !solution.misfit.detected,
            "{family}: {}",
            solution.misfit.message
        );
        // Every parameter of the family is fitted or named as undetermined; the upper
        // camera's intrinsics only with upper captures (this dataset has none).
        for p in family.params() {
            assert_eq!(
                solution.fixed.is_fixed(p),
                p.is_upper_projection(),
                "{family}: {p} free or held wrongly"
            );
        }
    }
}

#[test]
fn several_families_at_once_are_recovered() {
    let families = [
        Family::Intrinsics,
        Family::Links,
        Family::Compliance,
        Family::Play,
    ];
    let (solution, truth) = solve_free(&families, 12);
    assert!(solution.summary.converged);
    let truth = determined_truth(&solution, &truth);
    let (err, p) = worst_error(&solution, &truth);
    assert!(err < 1e-6, "{p} off by {err:e}");
    assert_eq!(solution.families[0], Family::Paper);
    for f in families {
        assert!(solution.families.contains(&f), "{f} not reported free");
    }
}

/// The misfit test does not see the play of a joint whose gravity torque keeps one sign:
/// the play is then held and named with the offset it trades against, and that offset
/// carries half the play (what a lying robot's offset is).
#[test]
fn play_of_a_one_signed_joint_is_named_not_printed() {
    let (solution, truth) = solve_free(&[Family::Play], 11);
    for u in &solution.undetermined {
        assert_eq!(u.param.family(), Family::Play);
        assert!(
            u.direction.terms.len() >= 2,
            "{} is named with what it trades against: {:?}",
            u.param,
            u.direction
        );
        assert_eq!(solution.values[u.param.index()], 0.0, "held at nominal");
        assert_eq!(solution.std[u.param.index()], 0.0);
        assert!(!solution.is_determined(u.param));
    }
    let determined = determined_truth(&solution, &truth);
    let (err, p) = worst_error(&solution, &determined);
    assert!(err < 1e-6, "{p} off by {err:e}");
}

/// Freeing families that trade against each other (the head and the camera position, with
/// the paper's camera rotation) exits 0, marks the right parameters undetermined in the
/// JSON with no number for their σ, recovers the others and prints no NaN.
#[test]
fn non_identifiable_families_exit_cleanly_with_named_directions() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("ds");
    let out = naocalib()
        .args([
            "simulate",
            "--stances",
            "8",
            "--heads",
            "2",
            "--seed",
            "4",
            "--px-noise",
            "0.05",
        ])
        .arg("--board")
        .arg(crate::util::paper_board())
        .arg(&dir)
        .output()
        .expect("ran");
    assert!(out.status.success(), "{}", stderr(&out));
    let out = naocalib()
        .args(["solve", "--json", "--free", &crate::util::every_family()])
        .arg(&dir)
        .output()
        .expect("ran");
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("NaN") && !text.contains("nan"), "{text}");
    let json: serde_json::Value = serde_json::from_str(&text).expect("json");
    let params = json["parameters"].as_object().expect("parameters");
    let undetermined: Vec<&String> = params
        .iter()
        .filter(|(_, v)| v["undetermined"] == serde_json::Value::Bool(true))
        .map(|(k, _)| k)
        .collect();
    assert!(!undetermined.is_empty(), "something must be undetermined");
    for name in &undetermined {
        let p = &params[name.as_str()];
        assert!(p["std"].is_null(), "{name}: {p}");
        assert_eq!(p["value"].as_f64(), Some(0.0), "{name} held at nominal");
    }
    let named = json["undetermined"].as_array().expect("named combinations");
    assert_eq!(named.len(), undetermined.len());
    // The paper's parameters are all determined and close to the truth (noise 0.05 px).
    for p in &Param::ALL[..naocalib::model::PAPER_PARAMETERS] {
        let e = &params[p.name()];
        assert!(
            e["std"].as_f64().is_some_and(|s| s.is_finite() && s > 0.0),
            "{p}: {e}"
        );
    }
    let table = naocalib()
        .args(["solve", "--free", "head,links"])
        .arg(&dir)
        .output()
        .expect("ran");
    assert!(table.status.success(), "{}", stderr(&table));
    let text = String::from_utf8_lossy(&table.stdout);
    assert!(text.contains("undetermined, held at nominal"), "{text}");
    assert!(!text.contains("NaN"), "{text}");
}

#[test]
fn backends_agree_on_an_extended_problem() {
    let families = [Family::Intrinsics, Family::Links, Family::Compliance];
    let options = SimOptions {
        seed: 21,
        stances: 8,
        heads: 2,
        px_noise: 0.1,
        effects: families.to_vec(),
        ..SimOptions::default()
    };
    let dataset = simulate(&Model::default(), &options).expect("simulated");
    let problem = Problem::from_dataset(&dataset, free(&families)).expect("problem");
    let comparison = naocalib::solve::compare::compare(&problem, &[]).expect("compared");
    assert_eq!(comparison.runs.len(), backend_names().len());
    for run in &comparison.runs {
        assert!(
            run.converged(),
            "{}: {:?}",
            run.solver,
            run.outcome.as_ref().err()
        );
        let (diff, p) = run.max_sigma.expect("compared with the reference");
        assert!(diff < 0.01, "{} differs by {diff} σ in {p}", run.solver);
    }
}

#[test]
fn unknown_family_is_refused_by_name() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("ds");
    crate::util::simulate_small(&dir, 2);
    let out = naocalib()
        .args(["solve", "--free", "elasticity"])
        .arg(&dir)
        .output()
        .expect("ran");
    assert_clean_failure(&out, &["elasticity", "families"]);
    let out = naocalib()
        .args(["simulate", "--effects", "paper"])
        .arg(tmp.path().join("x"))
        .output()
        .expect("ran");
    assert_clean_failure(&out, &["paper"]);
}

/// docs/MODEL.md §5's tables are the registries': every family row (name, what it models,
/// auto, realistic) and every parameter's name, family and unit, in order.
#[test]
fn model_md_tables_match_the_registries() {
    use naocalib::model::{FAMILIES, Param};
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/MODEL.md"),
    )
    .unwrap();
    let cells = |line: &str| -> Vec<String> {
        line.trim()
            .trim_matches('|')
            .split('|')
            .map(|c| c.trim().to_string())
            .collect()
    };
    let yes = |b: bool| if b { "yes" } else { "no" };
    let families: Vec<Vec<String>> = text
        .lines()
        .skip_while(|l| !l.starts_with("| family | models | auto | realistic |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(cells)
        .collect();
    let expected: Vec<Vec<String>> = FAMILIES
        .iter()
        .map(|f| {
            vec![
                f.name.to_string(),
                f.about.to_string(),
                yes(f.auto).to_string(),
                yes(f.realistic).to_string(),
            ]
        })
        .collect();
    assert_eq!(families, expected, "MODEL.md §5's family table");
    let params: Vec<Vec<String>> = text
        .lines()
        .skip_while(|l| !l.starts_with("| # | name | family | unit |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(cells)
        .collect();
    assert_eq!(params.len(), Param::ALL.len(), "one row per parameter");
    for (row, p) in params.iter().zip(Param::ALL) {
        assert_eq!(
            (
                row[0].as_str(),
                row[1].as_str(),
                row[2].as_str(),
                row[3].as_str()
            ),
            (
                p.index().to_string().as_str(),
                p.name(),
                p.family().name(),
                p.unit().name()
            ),
            "MODEL.md §5 row of {p}"
        );
    }
}

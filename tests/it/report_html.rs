//! The HTML report of the sample dataset: well-formed, self-contained (no external
//! resource), and holding every parameter, the diagnosis, the residual plot and overlays.

use naocalib::dataset::Dataset;
use naocalib::model::FixedSet;
use naocalib::report::{self, html, shown_parameters};
use naocalib::run::Run;
use naocalib::solve::{Problem, UncertaintyOptions, backend, calibrate};

use crate::util::{naocalib, sample, stderr};

/// Every `src`/`href` value of the document, and whether it has other ways to load
/// something (`<link>`, `<script>`, `@import`, `url(`).
fn check_self_contained(doc: &roxmltree::Document<'_>, text: &str) {
    for node in doc.descendants().filter(|n| n.is_element()) {
        let name = node.tag_name().name();
        assert!(
            !matches!(name, "script" | "link" | "iframe" | "object" | "embed"),
            "<{name}> loads or runs something"
        );
        for attr in node.attributes() {
            if matches!(attr.name(), "src" | "href") {
                assert!(
                    attr.value().starts_with("data:") || attr.value().starts_with('#'),
                    "<{name} {}=\"{}…\"> is an external resource",
                    attr.name(),
                    &attr.value()[..attr.value().len().min(40)]
                );
            }
        }
    }
    assert!(!text.contains("@import") && !text.contains("url("));
}

#[test]
fn sample_report_is_well_formed_and_complete() {
    let dataset = Dataset::load(&sample()).unwrap();
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    let lm = backend("lm", false).unwrap();
    let solution = calibrate(&problem, lm.as_ref(), &UncertaintyOptions::default()).unwrap();
    let run = Run::new(&dataset, solution.clone(), None);
    let page = html::solve_page(&run, &dataset).unwrap();
    let doc = roxmltree::Document::parse_with_options(
        &page,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("the report is well-formed (X)HTML");
    assert_eq!(doc.root_element().tag_name().name(), "html");
    check_self_contained(&doc, &page);

    // Every parameter of the table is in a row of its own.
    let rows: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("tr"))
        .map(|n| n.descendants().filter_map(|t| t.text()).collect::<String>())
        .collect();
    for p in shown_parameters(&solution) {
        assert!(
            rows.iter().any(|r| r.starts_with(p.name())),
            "no row for {}",
            p.name()
        );
    }
    // The diagnosis, line by line.
    for line in report::diagnosis(&solution) {
        assert!(
            page.contains(&html::escape(&line)),
            "diagnosis lacks {line}"
        );
    }
    assert!(page.contains("converged after"));
    // The residual plot and the per-capture RMS, inline SVG.
    for id in ["residuals", "captures"] {
        let figure = doc
            .descendants()
            .find(|n| n.attribute("id") == Some(id))
            .unwrap_or_else(|| panic!("no figure {id}"));
        let svg = figure
            .descendants()
            .find(|n| n.tag_name().name() == "svg")
            .expect("an inline svg");
        assert!(
            svg.descendants()
                .filter(|n| n.has_tag_name("circle"))
                .count()
                > 20
        );
    }
    // Overlays of the worst captures: PNG images in data URLs.
    let images: Vec<&str> = doc
        .descendants()
        .filter(|n| n.has_tag_name("img"))
        .filter_map(|n| n.attribute("src"))
        .collect();
    assert_eq!(images.len(), html::OVERLAYS);
    for src in images {
        // "iVBORw0KGgo" is base64 of the PNG signature.
        assert!(src.starts_with("data:image/png;base64,iVBORw0KGgo"));
        assert!(src.len() > 10_000, "an image of the capture, not a stub");
    }
    let worst = html::worst_captures(&solution, 1)[0].0;
    assert!(page.contains(&format!("Capture {worst}, RMS")));
}

#[test]
fn base64_matches_the_standard() {
    assert_eq!(html::base64(b""), "");
    assert_eq!(html::base64(b"f"), "Zg==");
    assert_eq!(html::base64(b"fo"), "Zm8=");
    assert_eq!(html::base64(b"foo"), "Zm9v");
    assert_eq!(html::base64(b"foobar"), "Zm9vYmFy");
    assert_eq!(html::base64(&[0xff, 0xfe, 0x00]), "//4A");
}

#[test]
fn solve_report_flag_writes_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("report.html");
    let out = naocalib()
        .args(["solve", "--solver", "lm", "--report"])
        .arg(&path)
        .arg(sample())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("<!DOCTYPE html>"));
    assert!(text.contains("CamYaw") && text.contains("data:image/png;base64,"));
    // Not over an existing file without --force.
    let out = naocalib()
        .args(["solve", "--solver", "lm", "--report"])
        .arg(&path)
        .arg(sample())
        .output()
        .unwrap();
    crate::util::assert_clean_failure(&out, &["already exists"]);
}

#[test]
fn batch_report_holds_every_run() {
    let tmp = tempfile::tempdir().unwrap();
    for seed in [1, 2] {
        crate::util::simulate_small(&tmp.path().join(format!("robot/run{seed}")), seed);
    }
    let path = tmp.path().join("batch.html");
    let out = naocalib()
        .args(["batch", "--solver", "lm", "--no-progress", "--report"])
        .arg(&path)
        .arg(tmp.path().join("robot"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = roxmltree::Document::parse_with_options(
        &text,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("well-formed");
    check_self_contained(&doc, &text);
    assert!(text.contains("run1") && text.contains("run2"));
    assert!(
        doc.descendants()
            .any(|n| n.attribute("id") == Some("estimates"))
    );
    assert_eq!(
        doc.descendants()
            .filter(|n| n
                .attribute("id")
                .is_some_and(|id| id.starts_with("residuals-")))
            .count(),
        2
    );
}

#[test]
fn element_ids_are_unique() {
    let dataset = Dataset::load(&sample()).unwrap();
    let problem = Problem::from_dataset(&dataset, FixedSet::default()).unwrap();
    let lm = backend("lm", false).unwrap();
    let solution = calibrate(&problem, lm.as_ref(), &UncertaintyOptions::plain()).unwrap();
    let page = html::solve_page(&Run::new(&dataset, solution, None), &dataset).unwrap();
    let mut ids: Vec<&str> = page
        .match_indices(" id=\"")
        .map(|(i, m)| {
            let rest = &page[i + m.len()..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect();
    let n = ids.len();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), n, "duplicate ids");
}

#[test]
fn standing_offsets_are_in_the_report_when_compliance_and_play_are_estimated() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("robot");
    let out = naocalib()
        .args(["simulate", "--effects", "compliance,play", "--seed", "5"])
        .args(["--stances", "12"])
        .arg(&data)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let page = |name: &str, free: &[&str]| {
        let path = tmp.path().join(name);
        let out = naocalib()
            .args(["solve"])
            .arg(&data)
            .args(free)
            .arg("--report")
            .arg(&path)
            .output()
            .unwrap();
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}: {}", stderr(&out)));
        let options = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        };
        roxmltree::Document::parse_with_options(&text, options).expect("well-formed");
        text
    };
    let with = page("with.html", &["--free", "compliance,play"]);
    assert!(
        with.contains("Standing leg offsets"),
        "missing in the report"
    );
    assert!(with.contains("LKneePitch") && with.contains("tau_stand"));
    let without = page("without.html", &[]);
    assert!(!without.contains("Standing leg offsets"));
}

/// `solve --start-from CAL.toml --report`: the report shows what changed since that
/// calibration (previous, now, change, z) as the text report does; without `--start-from`
/// it has no such table.
#[test]
fn change_table_is_in_the_report_with_start_from_only() {
    let tmp = tempfile::tempdir().unwrap();
    // The robot's previous calibration: another robot's (its offsets differ by degrees).
    let simulate = |name: &str, seed: &str| {
        let data = tmp.path().join(name);
        let out = naocalib()
            .args(["simulate", "--seed", seed, "--stances", "12"])
            .arg(&data)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        data
    };
    let before = simulate("before", "21");
    let robot = simulate("robot", "22");
    let export = tmp.path().join("previous");
    let out = naocalib()
        .arg("solve")
        .arg(&before)
        .arg("--export")
        .arg(&export)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let previous_toml = export.join("calibration.toml");
    let previous = naocalib::export::read_calibration(&previous_toml).unwrap();
    let page = |name: &str, start_from: bool| {
        let path = tmp.path().join(name);
        let mut cmd = naocalib();
        cmd.arg("solve").arg(&robot).arg("--report").arg(&path);
        if start_from {
            cmd.arg("--start-from").arg(&previous_toml);
        }
        let out = cmd.output().unwrap();
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}: {}", stderr(&out)));
        let options = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(&text, options).expect("well-formed");
        // The rows of the change table: parameter → its cells.
        doc.descendants()
            .find(|n| n.attribute("id") == Some("changes"))
            .map(|table| {
                table
                    .children()
                    .filter(|r| r.has_tag_name("tr"))
                    .skip(1)
                    .map(|r| {
                        r.children()
                            .filter(|c| c.has_tag_name("td"))
                            .map(|c| {
                                c.descendants()
                                    .filter(|t| t.is_text())
                                    .map(|t| t.text().unwrap())
                                    .collect::<String>()
                            })
                            .collect::<Vec<String>>()
                    })
                    .collect::<Vec<_>>()
            })
    };
    let rows = page("with.html", true).expect("a change table with --start-from");
    assert!(
        page("without.html", false).is_none(),
        "a change table without --start-from"
    );
    let row = rows
        .iter()
        .find(|r| r[0] == "CamPitch")
        .unwrap_or_else(|| panic!("no CamPitch row: {rows:?}"));
    let number = |s: &str| s.trim_start_matches('+').parse::<f64>().unwrap();
    let (was, now, change) = (number(&row[1]), number(&row[2]), number(&row[3]));
    assert!((was - previous.value(naocalib::model::Param::CamPitch)).abs() < 1e-4);
    assert!((now - was - change).abs() < 2e-4, "{row:?}");
    // Two robots' cameras differ by far more than their one-sigma: |z| > 3 and marked.
    let marked = rows
        .iter()
        .filter(|r| {
            r[4].trim_start_matches(['+', '-'])
                .parse::<f64>()
                .unwrap_or(0.0)
                > 3.0
        })
        .count();
    assert!(marked > 0, "{rows:?}");
}

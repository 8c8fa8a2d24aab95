//! Property-based tests of every reader of user files: random bytes, and random mutations of
//! valid files, fed to the dataset reader (each of its four files), the result reader
//! (`naocalib::export`) and the image decoder. Each must give a result or an error,
//! never a panic; a dataset error must name a file of the dataset.
//!
//! Cases run: 4 × 256 (dataset: bytes and mutations, per file drawn at random) + 2 × 256
//! (result JSON) + 2 × 256 (images, with the `detect` feature) = 2048 per `cargo test`.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use naocalib::calibration::Calibration;
use naocalib::dataset::{CAPTURES_CSV, CORNERS_CSV, DATASET_TOML, Dataset, TRUTH_TOML};
use naocalib::model::Model;
use naocalib::sim::{SimOptions, simulate};
use proptest::prelude::*;
use proptest::test_runner::Config;

use crate::util::run;

const FILES: [&str; 4] = [DATASET_TOML, CAPTURES_CSV, CORNERS_CSV, TRUTH_TOML];

/// Values that have broken readers: huge, tiny, not finite, not numbers, empty.
const NASTY: [&str; 16] = [
    "1e20",
    "-1e308",
    "1e400",
    "nan",
    "-inf",
    "-0",
    "99999999999999999999",
    "0",
    "-1",
    "4294967296",
    "1e-320",
    "",
    "\"x\"",
    "[]",
    "{}",
    "\u{feff}",
];

fn config(cases: u32) -> Config {
    Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }
}

/// The files of a small valid dataset, and a result JSON of it.
struct Valid {
    files: Vec<(&'static str, Vec<u8>)>,
    result_json: Vec<u8>,
}

fn valid() -> &'static Valid {
    static VALID: OnceLock<Valid> = OnceLock::new();
    VALID.get_or_init(|| {
        let options = SimOptions {
            stances: 2,
            heads: 1,
            ..SimOptions::default()
        };
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("d");
        simulate(&Model::default(), &options)
            .unwrap()
            .write(&dir, false)
            .unwrap();
        let files = FILES
            .iter()
            .map(|&name| (name, std::fs::read(dir.join(name)).unwrap()))
            .collect();
        let out = run(&["solve", "--json", "--solver", "lm"], &dir);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        Valid {
            files,
            result_json: out.stdout,
        }
    })
}

/// One change to a file's bytes.
#[derive(Debug, Clone)]
enum Mutation {
    /// Replace the byte at (a fraction of the length) with this one.
    Set(f64, u8),
    /// Insert these bytes.
    Insert(f64, Vec<u8>),
    /// Remove up to this many bytes.
    Remove(f64, usize),
    /// Repeat the line at this position.
    DuplicateLine(f64),
    /// Replace the n-th number in the file with a nasty value.
    Number(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0.0..1.0, any::<u8>()).prop_map(|(p, b)| Mutation::Set(p, b)),
        (0.0..1.0, proptest::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(p, b)| Mutation::Insert(p, b)),
        (0.0..1.0, 1usize..64).prop_map(|(p, n)| Mutation::Remove(p, n)),
        (0.0..1.0).prop_map(Mutation::DuplicateLine),
        (0usize..400, 0..NASTY.len()).prop_map(|(n, v)| Mutation::Number(n, v)),
    ]
}

fn at(bytes: &[u8], p: f64) -> usize {
    ((bytes.len() as f64 * p) as usize).min(bytes.len())
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    match m {
        Mutation::Set(p, b) => {
            if !bytes.is_empty() {
                let i = at(bytes, *p).min(bytes.len() - 1);
                bytes[i] = *b;
            }
        }
        Mutation::Insert(p, b) => {
            let i = at(bytes, *p);
            bytes.splice(i..i, b.iter().copied());
        }
        Mutation::Remove(p, n) => {
            let i = at(bytes, *p);
            let end = (i + n).min(bytes.len());
            bytes.drain(i..end);
        }
        Mutation::DuplicateLine(p) => {
            let i = at(bytes, *p);
            let start = bytes[..i]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |k| k + 1);
            let end = bytes[i..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(bytes.len(), |k| i + k + 1);
            let line = bytes[start..end].to_vec();
            bytes.splice(start..start, line);
        }
        Mutation::Number(n, v) => {
            // The byte ranges of the numbers in the file (digits, signs, dots, exponents).
            let mut spans = Vec::new();
            let mut start = None;
            for (i, &b) in bytes.iter().enumerate() {
                let numeric = b.is_ascii_digit() || (start.is_some() && b"+-.eE".contains(&b));
                match (start, numeric) {
                    (None, true) => start = Some(i),
                    (Some(s), false) => {
                        spans.push(s..i);
                        start = None;
                    }
                    _ => {}
                }
            }
            if let Some(s) = start {
                spans.push(s..bytes.len());
            }
            if !spans.is_empty() {
                let span = spans[n % spans.len()].clone();
                bytes.splice(span, NASTY[*v].bytes());
            }
        }
    }
}

/// Writes the valid dataset into a fresh directory with `file` replaced by `bytes`, loads
/// it, and checks that an error names one of the dataset's files (or the directory).
fn load_with(file: usize, bytes: &[u8]) -> Result<(), TestCaseError> {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for (i, (name, good)) in valid().files.iter().enumerate() {
        let content = if i == file { bytes } else { good };
        std::fs::write(dir.join(name), content).unwrap();
    }
    for load in [Dataset::load, Dataset::load_without_corners] {
        if let Err(e) = load(dir) {
            let named: Vec<PathBuf> = FILES.iter().map(|f| dir.join(f)).collect();
            prop_assert!(
                named.iter().any(|p| p == e.path()) || e.path() == dir,
                "the error names no file of the dataset: {e}"
            );
            prop_assert!(!e.to_string().is_empty());
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn dataset_reader_survives_random_bytes(
        file in 0..FILES.len(),
        bytes in proptest::collection::vec(any::<u8>(), 0..512),
    ) {
        load_with(file, &bytes)?;
    }

    #[test]
    fn dataset_reader_survives_random_text(
        file in 0..FILES.len(),
        text in "[a-zA-Z0-9_.,=\\[\\]{}\"' +\\-\n#]{0,300}",
    ) {
        load_with(file, text.as_bytes())?;
    }

    #[test]
    fn dataset_reader_survives_mutations(
        file in 0..FILES.len(),
        mutations in proptest::collection::vec(mutation(), 1..6),
    ) {
        let mut bytes = valid().files[file].1.clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        load_with(file, &bytes)?;
    }

    #[test]
    fn dataset_reader_survives_nasty_numbers(
        file in 0..FILES.len(),
        picks in proptest::collection::vec((0usize..400, 0..NASTY.len()), 1..4),
    ) {
        let mut bytes = valid().files[file].1.clone();
        for (n, v) in picks {
            apply(&mut bytes, &Mutation::Number(n, v));
        }
        load_with(file, &bytes)?;
    }

    #[test]
    fn result_reader_survives_random_bytes(
        bytes in proptest::collection::vec(any::<u8>(), 0..512),
    ) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = Calibration::from_json(&text, Path::new("r.json"));
        let _ = Calibration::from_toml(&text, Path::new("r.toml"));
    }

    #[test]
    fn result_reader_survives_mutations(
        mutations in proptest::collection::vec(mutation(), 1..6),
    ) {
        let mut bytes = valid().result_json.clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let text = String::from_utf8_lossy(&bytes);
        let _ = Calibration::from_json(&text, Path::new("r.json"));
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("r.json");
        std::fs::write(&path, &bytes).unwrap();
        let _ = naocalib::export::read_calibration(&path);
    }
}

#[cfg(feature = "detect")]
mod images {
    use super::*;
    use naocalib::detect::decode_grey;
    use naocalib::sim::render::GreyImage;

    fn valid_images() -> &'static [Vec<u8>] {
        static IMAGES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
        IMAGES.get_or_init(|| {
            let (width, height) = (24u32, 16u32);
            let pixels = (0..width * height).map(|i| (i * 7 % 251) as u8).collect();
            let png = GreyImage {
                width,
                height,
                pixels,
            }
            .to_png()
            .unwrap();
            let mut pgm = format!("P5\n{width} {height}\n255\n").into_bytes();
            pgm.extend((0..width * height).map(|i| (i % 256) as u8));
            vec![png, pgm]
        })
    }

    proptest! {
        #![proptest_config(config(256))]

        #[test]
        fn image_decoder_survives_random_bytes(
            magic in 0usize..5,
            bytes in proptest::collection::vec(any::<u8>(), 0..512),
        ) {
            // Half of them start like a known format, to get past the signature check.
            let prefixes: [&[u8]; 5] = [b"", b"\x89PNG\r\n\x1a\n", b"\xff\xd8\xff", b"BM", b"P5\n"];
            let mut data = prefixes[magic].to_vec();
            data.extend(bytes);
            let _ = decode_grey(Path::new("i.png"), &data);
        }

        #[test]
        fn image_decoder_survives_mutations(
            which in 0usize..2,
            mutations in proptest::collection::vec(mutation(), 1..4),
        ) {
            let mut bytes = valid_images()[which].clone();
            for m in &mutations {
                apply(&mut bytes, m);
            }
            let _ = decode_grey(Path::new("i.png"), &bytes);
        }
    }
}

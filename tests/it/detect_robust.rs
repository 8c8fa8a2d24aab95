//! `naocalib detect` against hostile input and careless use: an image whose header claims
//! an enormous size, an absurd `-j`, overlays aimed at the dataset's own images, and
//! `--force` on images without any board.

use std::path::Path;

use crate::util::{assert_clean_failure, naocalib, stderr};
use naocalib::sim::render::GreyImage;

/// `simulate --images` of 2 stances × 1 head posture per leg (4 images) into `dir`.
fn rendered(dir: &Path) {
    let out = naocalib()
        .args(["simulate", "--images", "--stances", "2", "--heads", "1"])
        .args(["--seed", "9"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
}

/// CRC-32 (ISO-HDLC, as PNG uses) of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A PNG of a few dozen bytes whose header claims `width × height` 8-bit grey pixels.
fn lying_png(width: u32, height: u32) -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        png.extend((data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend(data);
        png.extend(&body);
        png.extend(crc32(&body).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 0, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
    chunk(b"IEND", &[]);
    png
}

#[test]
fn an_enormous_header_is_refused_before_decoding() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    let bomb = lying_png(200_000, 200_000);
    assert!(bomb.len() < 80, "{} bytes", bomb.len());
    std::fs::write(dir.join("images/0000.png"), &bomb).unwrap();
    // Through the library: a clear error naming the file, nothing allocated.
    let e = naocalib::detect::read_grey(&dir.join("images/0000.png")).unwrap_err();
    let message = e.to_string();
    assert!(message.contains("0000.png"), "{message}");
    assert!(message.contains("200000×200000"), "{message}");
    // Through the CLI: the image is reported, the others detected, no abort.
    let out = naocalib().arg("detect").arg(&dir).output().unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{:?}: {err}", out.status);
    assert!(
        err.contains("capture 0 (images/0000.png): error:") && err.contains("refused"),
        "{err}"
    );
    assert!(err.contains("3 found"), "{err}");
}

#[test]
fn a_huge_jobs_count_is_capped() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    let out = naocalib()
        .args(["detect", "-j", "1000000"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("--jobs 1000000 capped at"), "{err}");
    assert!(err.contains("4 found"), "{err}");
}

#[test]
fn overlays_never_replace_an_input_and_existing_ones_only_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    // An image named like the overlay that would be written next to it.
    std::fs::rename(
        dir.join("images/0000.png"),
        dir.join("images/capture_0000.png"),
    )
    .unwrap();
    let captures = std::fs::read_to_string(dir.join("captures.csv")).unwrap();
    std::fs::write(
        dir.join("captures.csv"),
        captures.replacen("images/0000.png", "images/capture_0000.png", 1),
    )
    .unwrap();
    let image = std::fs::read(dir.join("images/capture_0000.png")).unwrap();
    for force in [false, true] {
        let mut cmd = naocalib();
        cmd.args(["detect", "--overlay"]).arg(dir.join("images"));
        if force {
            cmd.arg("--force");
        }
        let out = cmd.arg(&dir).output().unwrap();
        assert_clean_failure(&out, &["capture_0000.png", "input"]);
        assert_eq!(
            std::fs::read(dir.join("images/capture_0000.png")).unwrap(),
            image
        );
    }
    // Elsewhere: written, then refused without --force, replaced with it.
    let overlays = tmp.path().join("overlays");
    let out = naocalib()
        .args(["detect", "--overlay"])
        .arg(&overlays)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let first = overlays.join("capture_0001.png");
    assert!(first.is_file());
    std::fs::write(&first, b"mine").unwrap();
    let out = naocalib()
        .args(["detect", "--force", "--overlay"])
        .arg(&overlays)
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert_ne!(std::fs::read(&first).unwrap(), b"mine");
    std::fs::write(&first, b"mine").unwrap();
    std::fs::remove_file(dir.join("corners.csv")).unwrap();
    let out = naocalib()
        .args(["detect", "--overlay"])
        .arg(&overlays)
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(&out, &["capture_0000.png", "--force"]);
    assert_eq!(std::fs::read(&first).unwrap(), b"mine");
    // No temporary file left behind.
    let names: Vec<_> = std::fs::read_dir(&overlays)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| n.ends_with(".png")), "{names:?}");
}

#[test]
fn force_without_any_board_keeps_corners_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("ds");
    rendered(&dir);
    let out = naocalib().arg("detect").arg(&dir).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let good = std::fs::read(dir.join("corners.csv")).unwrap();
    let blank = GreyImage {
        width: 640,
        height: 480,
        pixels: vec![120; 640 * 480],
    };
    for k in 0..4 {
        blank
            .write_png(&dir.join(format!("images/{k:04}.png")))
            .unwrap();
    }
    let out = naocalib()
        .args(["detect", "--force"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_clean_failure(
        &out,
        &["no vertex found in any of 4 images", "left as they were"],
    );
    assert_eq!(std::fs::read(dir.join("corners.csv")).unwrap(), good);
}

/// OpenCV is naocalib's plugin, loaded by the commands that detect and by no other: the
/// executable does not link it, a solve runs without it, and `detect` and `solve --detect`
/// without it (or with a file that is not it) stop before any image is read, naming the
/// file.
#[test]
fn opencv_is_loaded_only_to_detect_and_its_absence_is_named() {
    let exe = std::fs::read(assert_cmd::cargo::cargo_bin("naocalib")).unwrap();
    assert!(
        !exe.windows(10).any(|w| w == b"libopencv_"),
        "the executable names an OpenCV library"
    );
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("d");
    rendered(&dir);
    let missing = tmp.path().join("no-plugin.so");
    let solved = naocalib()
        .env("NAOCALIB_OPENCV_PLUGIN", &missing)
        .arg("solve")
        .arg(crate::util::sample())
        .output()
        .unwrap();
    assert!(solved.status.success(), "{}", stderr(&solved));
    let corners = std::fs::read(dir.join("corners.csv")).ok();
    let not_a_plugin = tmp.path().join("captures.so");
    std::fs::copy(dir.join("captures.csv"), &not_a_plugin).unwrap();
    for (plugin, why) in [(&missing, "cannot open"), (&not_a_plugin, "did not load")] {
        for args in [&["detect"][..], &["solve", "--detect"][..]] {
            let out = naocalib()
                .env("NAOCALIB_OPENCV_PLUGIN", plugin)
                .args(args)
                .arg(&dir)
                .output()
                .unwrap();
            assert_clean_failure(&out, &["OpenCV plugin", &plugin.display().to_string(), why]);
        }
    }
    assert_eq!(std::fs::read(dir.join("corners.csv")).ok(), corners);
}

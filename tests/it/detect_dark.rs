//! Pictures detection cannot use, said so: a picture too dark to show the board is named
//! too dark with its camera and brightness, not only "not found".

use crate::util::read_grey_png as read_png;
use naocalib::detect::{self, DetectOptions, Outcome};
use naocalib::model::{CameraId, Model};
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};

#[test]
fn a_picture_too_dark_to_show_the_board_is_said_so() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let options = SimOptions {
        seed: 3,
        stances: 2,
        heads: 1,
        px_noise: 0.0,
        joint_noise: 0.0,
        images: Some(ImageOutput {
            dir: dir.to_path_buf(),
            options: RenderOptions {
                blur: 0.8,
                noise: 2.0,
                seed: 3,
                ..RenderOptions::default()
            },
            force: false,
        }),
        ..SimOptions::default()
    };
    let model = Model::default();
    let mut dataset = simulate(&model, &options).unwrap();
    dataset.dir = dir.to_path_buf();
    let dark = dataset.captures[0].id;
    let image = |id: u64| {
        let c = dataset.captures.iter().find(|c| c.id == id).unwrap();
        dir.join(c.image.as_ref().unwrap())
    };
    let mut picture = read_png(&image(dark));
    // Underexposed: the signal down to a few grey levels under the sensor's noise.
    let mut state = 12345u32;
    for p in &mut picture.pixels {
        state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
        *p = *p / 64 + (state >> 29) as u8;
    }
    std::fs::write(image(dark), picture.to_png().unwrap()).unwrap();

    let results = detect::detect_dataset(&dataset, &DetectOptions::default(), &|_| {});
    for r in &results {
        let said = r.to_string();
        if r.capture == dark {
            let Outcome::TooDark { camera, brightness } = r.outcome else {
                panic!("{said}")
            };
            assert_eq!(camera, CameraId::Lower);
            assert!(brightness < 10.0, "{brightness}");
            assert!(said.contains("too dark"), "{said}");
        } else {
            assert!(matches!(r.outcome, Outcome::Found { .. }), "{said}");
        }
    }
}

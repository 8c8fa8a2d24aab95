//! Where a plan's boards lie in each camera's image: what determines a camera's
//! intrinsics is boards seen across its image, the centre and the corners, and not only
//! where the head aims them first.

use super::PlannedCapture;
use crate::model::{CameraId, Model, PARAMETER_COUNT};

/// Columns of the grid a camera's image is divided into.
pub const COLS: usize = 9;
/// Rows of that grid.
pub const ROWS: usize = 6;

/// The boards of one camera's captures in its image, at the parameters the plan was made
/// around.
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    /// The camera.
    pub camera: CameraId,
    /// Its captures in the plan.
    pub captures: usize,
    /// Board vertices per cell of a [`COLS`] × [`ROWS`] grid over the image, row by row
    /// from the top.
    pub cells: [[usize; COLS]; ROWS],
    /// The board centres' smallest and largest pixel coordinates: `[[u, v] least, [u, v]
    /// greatest]`.
    pub centres: [[f64; 2]; 2],
    /// The image size (px).
    pub size: [f64; 2],
}

impl Coverage {
    /// Cells of the grid some board vertex lies in.
    pub fn covered(&self) -> usize {
        self.cells.iter().flatten().filter(|n| **n > 0).count()
    }

    /// How many of the image's four corners (the corner thirds of its width and height)
    /// some board vertex reaches.
    pub fn corners(&self) -> usize {
        // The cells of the grid within a third of the width and height of each corner.
        let (cols, rows) = (COLS / 3, ROWS / 3);
        [(0, 0), (0, 1), (1, 0), (1, 1)]
            .iter()
            .filter(|(right, bottom)| {
                (0..rows).any(|r| {
                    (0..cols).any(|c| {
                        let row = if *bottom == 1 { ROWS - 1 - r } else { r };
                        let col = if *right == 1 { COLS - 1 - c } else { c };
                        self.cells[row][col] > 0
                    })
                })
            })
            .count()
    }

    /// The board centres' spread as fractions of the image's width and height.
    pub fn spread(&self) -> [f64; 2] {
        let [lo, hi] = self.centres;
        [
            (hi[0] - lo[0]) / self.size[0],
            (hi[1] - lo[1]) / self.size[1],
        ]
    }
}

/// The coverage of each camera with captures in `captures`, lower first, the boards
/// projected at the parameters `at` (the plan's centre of feasibility: zero, or the robot's
/// calibration with `--around`).
pub fn coverage(
    model: &Model,
    captures: &[PlannedCapture],
    at: &[f64; PARAMETER_COUNT],
) -> Vec<Coverage> {
    let vertices: Vec<_> = model.board.vertices().collect();
    CameraId::ALL
        .into_iter()
        .filter_map(|camera| {
            let intrinsics = model.intrinsics(camera);
            let (w, h) = (intrinsics.width as f64, intrinsics.height as f64);
            let mut out = Coverage {
                camera,
                captures: 0,
                cells: [[0; COLS]; ROWS],
                centres: [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]],
                size: [w, h],
            };
            for c in captures.iter().filter(|c| c.camera == camera) {
                let chains = model.chains_for(camera, c.side, &c.joints);
                let uv: Vec<[f64; 2]> = model
                    .project(&chains, at, &vertices)
                    .into_iter()
                    .flatten()
                    .collect();
                if uv.is_empty() {
                    continue;
                }
                out.captures += 1;
                let n = uv.len() as f64;
                let centre = [
                    uv.iter().map(|p| p[0]).sum::<f64>() / n,
                    uv.iter().map(|p| p[1]).sum::<f64>() / n,
                ];
                for (k, x) in centre.into_iter().enumerate() {
                    out.centres[0][k] = out.centres[0][k].min(x);
                    out.centres[1][k] = out.centres[1][k].max(x);
                }
                for p in &uv {
                    if (0.0..w).contains(&p[0]) && (0.0..h).contains(&p[1]) {
                        let col = ((p[0] / w * COLS as f64) as usize).min(COLS - 1);
                        let row = ((p[1] / h * ROWS as f64) as usize).min(ROWS - 1);
                        out.cells[row][col] += 1;
                    }
                }
            }
            (out.captures > 0).then_some(out)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{JointAngles, Side};
    use crate::plan::feasible::{self, Feasibility};

    #[test]
    fn a_board_aimed_at_a_corner_covers_it_and_one_at_the_centre_does_not() {
        use rand::SeedableRng;
        let model = Model::default();
        let f = Feasibility::default();
        let zero = [0.0; PARAMETER_COUNT];
        let (w, h) = (model.camera.width as f64, model.camera.height as f64);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
        let pool = feasible::candidates(
            &model,
            CameraId::Lower,
            Side::Left,
            20,
            1,
            false,
            8000,
            &f,
            0,
            &mut rng,
        );
        // A stance of the pool whose board the head can also bring to a corner.
        let aim = |joints: &JointAngles, target: [f64; 2]| {
            feasible::aim_head(&model, Side::Left, joints, target, f.joint_margin, &zero).map(
                |joints| PlannedCapture {
                    camera: CameraId::Lower,
                    side: Side::Left,
                    joints,
                },
            )
        };
        let (centre, corner) = pool
            .iter()
            .find_map(|c| {
                Some((
                    aim(&c.joints, [w / 2.0, h / 2.0])?,
                    aim(&c.joints, [0.2 * w, 0.2 * h])?,
                ))
            })
            .expect("a stance that can be aimed at a corner");
        let at_centre = coverage(&model, &[centre], &zero);
        assert_eq!(at_centre.len(), 1);
        assert_eq!(at_centre[0].captures, 1);
        assert_eq!(at_centre[0].corners(), 0);
        assert_eq!(at_centre[0].spread(), [0.0, 0.0]);
        let both = coverage(&model, &[centre, corner], &zero);
        assert_eq!(both[0].captures, 2);
        assert_eq!(both[0].corners(), 1);
        assert!(both[0].covered() > at_centre[0].covered());
        let [du, dv] = both[0].spread();
        assert!(
            (du - 0.3).abs() < 0.03 && (dv - 0.3).abs() < 0.03,
            "{du} {dv}"
        );
        // No upper captures, no upper coverage.
        assert!(both.iter().all(|c| c.camera == CameraId::Lower));
    }
}

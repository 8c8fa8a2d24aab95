//! Giving detected vertices their (row, col): OpenCV's order compared with the nominal
//! model's prediction, and the check that all points fit one homography.

use nalgebra::{DMatrix, Matrix3, Vector3};

/// A grid of inner vertices: `cols` per row, `rows` rows (OpenCV's `patternSize`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Grid {
    /// Vertices per row.
    pub cols: u32,
    /// Rows of vertices.
    pub rows: u32,
}

impl Grid {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        (self.cols * self.rows) as usize
    }

    /// Whether the grid has no vertex.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The (row, col) of OpenCV's point `k` under grid symmetry `m` (0 = OpenCV's own
    /// order, 1 = turned by 180°, 2 and 3 mirrored, 4 … 7 transposed, square grids only).
    fn map(&self, m: usize, k: usize) -> (u32, u32) {
        let (r, c) = ((k as u32) / self.cols, (k as u32) % self.cols);
        let (rl, cl) = (self.rows - 1, self.cols - 1);
        match m {
            0 => (r, c),
            1 => (rl - r, cl - c),
            2 => (rl - r, c),
            3 => (r, cl - c),
            4 => (c, r),
            5 => (cl - c, rl - r),
            6 => (c, rl - r),
            _ => (cl - c, r),
        }
    }

    fn symmetries(&self) -> usize {
        if self.rows == self.cols { 8 } else { 4 }
    }
}

/// How OpenCV's order relates to the board's (row-major) order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Order {
    /// The same.
    Same,
    /// Turned by 180°: both rows and columns reversed.
    Turned,
    /// Rows reversed (a mirror image of the board's order).
    RowsReversed,
    /// Columns reversed (a mirror image of the board's order).
    ColsReversed,
    /// Rows and columns swapped (square patterns only), in one of four ways.
    Transposed(u8),
}

impl Order {
    fn of(symmetry: usize) -> Order {
        match symmetry {
            0 => Order::Same,
            1 => Order::Turned,
            2 => Order::RowsReversed,
            3 => Order::ColsReversed,
            m => Order::Transposed(m as u8 - 4),
        }
    }
}

impl std::fmt::Display for Order {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Order::Same => write!(f, "OpenCV's order"),
            Order::Turned => write!(f, "OpenCV's order turned by 180°"),
            Order::RowsReversed => write!(f, "OpenCV's order with rows reversed"),
            Order::ColsReversed => write!(f, "OpenCV's order with columns reversed"),
            Order::Transposed(k) => write!(f, "OpenCV's order transposed ({k})"),
        }
    }
}

/// How OpenCV's points map to the board's vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Assignment {
    /// (row, col) of each detected point, in OpenCV's order.
    pub vertices: Vec<(u32, u32)>,
    /// How OpenCV's order relates to the board's.
    pub order: Order,
    /// In-image rotation of the detected board against the prediction (deg).
    pub rotation_deg: f64,
}

fn centred(points: &[[f64; 2]]) -> (Vec<[f64; 2]>, [f64; 2]) {
    let n = points.len() as f64;
    let mean = [
        points.iter().map(|p| p[0]).sum::<f64>() / n,
        points.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    (
        points
            .iter()
            .map(|p| [p[0] - mean[0], p[1] - mean[1]])
            .collect(),
        mean,
    )
}

fn orientation(p: &[[f64; 2]], grid: Grid) -> f64 {
    let at = |r: u32, c: u32| p[(r * grid.cols + c) as usize];
    let o = at(0, 0);
    let a = at(0, grid.cols - 1);
    let b = at(grid.rows - 1, 0);
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Assigns (row, col) to the `detected` points (OpenCV's order) from the `predicted`
/// positions of every vertex (row-major). Rejects, with the reason, a board that is
/// mirrored against the prediction, turned so far that its order cannot be told, much
/// larger or smaller than predicted, or far from where it is predicted.
pub fn assign(
    detected: &[[f64; 2]],
    predicted: &[[f64; 2]],
    grid: Grid,
    image_size: [f64; 2],
) -> Result<Assignment, String> {
    assert_eq!(detected.len(), grid.len());
    assert_eq!(predicted.len(), grid.len());
    let (pc, pmean) = centred(predicted);
    let p_orient = orientation(predicted, grid);
    let p_radius =
        (pc.iter().map(|p| p[0] * p[0] + p[1] * p[1]).sum::<f64>() / pc.len() as f64).sqrt();
    let mut candidates = Vec::new();
    let mut mirrored = 0;
    for m in 0..grid.symmetries() {
        let mut mapped = vec![[0.0; 2]; grid.len()];
        let mut vertices = Vec::with_capacity(grid.len());
        for (k, d) in detected.iter().enumerate() {
            let (r, c) = grid.map(m, k);
            mapped[(r * grid.cols + c) as usize] = *d;
            vertices.push((r, c));
        }
        if orientation(&mapped, grid) * p_orient <= 0.0 {
            mirrored += 1;
            continue;
        }
        let (dc, _) = centred(&mapped);
        let (mut cross, mut dot) = (0.0, 0.0);
        for (p, d) in pc.iter().zip(&dc) {
            cross += p[0] * d[1] - p[1] * d[0];
            dot += p[0] * d[0] + p[1] * d[1];
        }
        candidates.push((cross.atan2(dot).to_degrees(), m, vertices));
    }
    if candidates.is_empty() || mirrored == grid.symmetries() {
        return Err("the detected grid is mirrored against the model's prediction".into());
    }
    candidates.sort_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
    let (rotation_deg, m, vertices) = candidates.swap_remove(0);
    let limit = if grid.rows == grid.cols { 30.0 } else { 45.0 };
    if rotation_deg.abs() > limit {
        return Err(format!(
            "ambiguous order: the board appears turned by {rotation_deg:.0}° against the \
             model's prediction (more than {limit:.0}°)"
        ));
    }
    let (dc, dmean) = centred(detected);
    let d_radius =
        (dc.iter().map(|p| p[0] * p[0] + p[1] * p[1]).sum::<f64>() / dc.len() as f64).sqrt();
    let scale = d_radius / p_radius;
    if !(0.5..=2.0).contains(&scale) {
        return Err(format!(
            "the board appears {scale:.2} times the size the model predicts"
        ));
    }
    let shift = ((dmean[0] - pmean[0]).powi(2) + (dmean[1] - pmean[1]).powi(2)).sqrt();
    let limit = 0.2 * (image_size[0] + image_size[1]);
    if shift > limit {
        return Err(format!(
            "the board is {shift:.0} px from where the model predicts it (more than {limit:.0} px)"
        ));
    }
    Ok(Assignment {
        vertices,
        order: Order::of(m),
        rotation_deg,
    })
}

/// The homography `H` with `dst ≈ H · src` (least squares, normalised DLT), or `None` for
/// degenerate points.
pub fn homography(src: &[[f64; 2]], dst: &[[f64; 2]]) -> Option<Matrix3<f64>> {
    let n = src.len();
    if n < 4 || dst.len() != n {
        return None;
    }
    let normaliser = |p: &[[f64; 2]]| {
        let (c, mean) = centred(p);
        let d = c
            .iter()
            .map(|q| (q[0] * q[0] + q[1] * q[1]).sqrt())
            .sum::<f64>()
            / n as f64;
        if d < 1e-12 {
            return None;
        }
        let s = std::f64::consts::SQRT_2 / d;
        Some(Matrix3::new(
            s,
            0.0,
            -s * mean[0],
            0.0,
            s,
            -s * mean[1],
            0.0,
            0.0,
            1.0,
        ))
    };
    let ts = normaliser(src)?;
    let td = normaliser(dst)?;
    let mut a = DMatrix::<f64>::zeros(2 * n, 9);
    for i in 0..n {
        let s = ts * Vector3::new(src[i][0], src[i][1], 1.0);
        let d = td * Vector3::new(dst[i][0], dst[i][1], 1.0);
        let (x, y, u, v) = (s[0], s[1], d[0], d[1]);
        let r = 2 * i;
        a.row_mut(r)
            .copy_from_slice(&[-x, -y, -1.0, 0.0, 0.0, 0.0, u * x, u * y, u]);
        a.row_mut(r + 1)
            .copy_from_slice(&[0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v]);
    }
    let svd = (a.transpose() * &a).symmetric_eigen();
    let k = svd.eigenvalues.imin();
    let h = svd.eigenvectors.column(k);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let h = td.try_inverse()? * hn * ts;
    (h[(2, 2)].abs() > 1e-300).then(|| h / h[(2, 2)])
}

/// Applies a homography to a point.
pub fn apply(h: &Matrix3<f64>, p: [f64; 2]) -> [f64; 2] {
    let q = h * Vector3::new(p[0], p[1], 1.0);
    [q[0] / q[2], q[1] / q[2]]
}

/// The largest distance of `dst` from the homography fitted to `src → dst` (px), or
/// `None` when no homography can be fitted.
pub fn homography_residual(src: &[[f64; 2]], dst: &[[f64; 2]]) -> Option<f64> {
    let h = homography(src, dst)?;
    Some(
        src.iter()
            .zip(dst)
            .map(|(s, d)| {
                let q = apply(&h, *s);
                ((q[0] - d[0]).powi(2) + (q[1] - d[1]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRID: Grid = Grid { cols: 6, rows: 4 };

    fn board(angle_deg: f64, shift: [f64; 2]) -> Vec<[f64; 2]> {
        let (s, c) = angle_deg.to_radians().sin_cos();
        (0..4)
            .flat_map(|r| (0..6).map(move |c| (r as f64, c as f64)))
            .map(|(r, col)| {
                let (x, y) = (col * 20.0 - 50.0, r * 20.0 - 30.0);
                [
                    300.0 + shift[0] + c * x - s * y,
                    200.0 + shift[1] + s * x + c * y,
                ]
            })
            .collect()
    }

    #[test]
    fn keeps_or_turns_the_order() {
        let predicted = board(0.0, [0.0, 0.0]);
        let seen = board(10.0, [15.0, -8.0]);
        let a = assign(&seen, &predicted, GRID, [640.0, 480.0]).unwrap();
        assert_eq!(a.order, Order::Same);
        assert_eq!(a.vertices[7], (1, 1));
        assert!((a.rotation_deg - 10.0).abs() < 1e-9);
        let reversed: Vec<_> = seen.iter().rev().copied().collect();
        let a = assign(&reversed, &predicted, GRID, [640.0, 480.0]).unwrap();
        assert_eq!(a.order, Order::Turned);
        assert_eq!(a.vertices[0], (3, 5));
    }

    #[test]
    fn rejects_ambiguous_far_and_mirrored() {
        let predicted = board(0.0, [0.0, 0.0]);
        let e = assign(&board(90.0, [0.0, 0.0]), &predicted, GRID, [640.0, 480.0]);
        assert!(e.unwrap_err().contains("ambiguous"));
        let e = assign(&board(0.0, [300.0, 0.0]), &predicted, GRID, [640.0, 480.0]);
        assert!(e.unwrap_err().contains("from where"));
        let mirrored: Vec<_> = board(0.0, [0.0, 0.0])
            .iter()
            .map(|p| [600.0 - p[0], p[1]])
            .collect();
        // A mirror image is explained by a mirrored order (cols reversed), not rejected.
        let a = assign(&mirrored, &predicted, GRID, [640.0, 480.0]).unwrap();
        assert_eq!(a.vertices[0], (0, 5));
        assert_eq!(a.order, Order::ColsReversed);
    }

    #[test]
    fn homography_fits_a_projective_grid() {
        let h = Matrix3::new(1.1, 0.2, 30.0, -0.1, 0.9, 40.0, 0.001, 0.0005, 1.0);
        let src: Vec<[f64; 2]> = (0..24)
            .map(|k| [(k % 6) as f64 * 25.0, (k / 6) as f64 * 25.0])
            .collect();
        let mut dst: Vec<[f64; 2]> = src.iter().map(|p| apply(&h, *p)).collect();
        assert!(homography_residual(&src, &dst).unwrap() < 1e-8);
        dst.swap(3, 4);
        assert!(homography_residual(&src, &dst).unwrap() > 5.0);
    }
}

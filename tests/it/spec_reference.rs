//! The reference values of docs/MODEL.md: transforms and projections checked against the NAO
//! URDF, and the gravity torques of the extended model.

use naocalib::model::{Joint, JointAngles, Model, PARAMETER_COUNT, Param, Side, Vertex};

fn angles(values: [f64; 14]) -> JointAngles {
    JointAngles(values)
}

/// Pose A, in `Joint::ALL` order.
const POSE_A: [f64; 14] = [
    0.3, 0.2, -0.3, 0.1, -0.4, 0.8, -0.35, -0.05, -0.3, -0.1, -0.5, 0.9, -0.4, 0.07,
];
const POSE_B: [f64; 14] = [
    0.58, 0.422, 0.119, 0.761, -0.503, 1.694, -0.893, 0.647, 0.119, 0.235, -0.888, 1.285, 0.607,
    0.061,
];
const POSE_C: [f64; 14] = [
    -0.582, 0.222, -0.287, -0.046, -0.457, 1.241, -0.873, 0.292, -0.287, 0.342, -0.462, 0.354,
    -1.096, -0.519,
];
/// Table 2 run 1, in report units (deg / mm), docs/MODEL.md parameter order.
const RUN1: [f64; 21] = [
    0.4764, -4.5627, -1.7991, -2.2938, 0.9692, 0.2299, -1.1442, 1.6708, 0.0267, -0.9800, 0.1893,
    1.4916, -0.0156, 0.6081, -0.5310, -0.6010, -0.3878, 0.5075, 0.8058, -2.0173, 2.2007,
];

fn run1() -> Vec<f64> {
    let mut p = vec![0.0; PARAMETER_COUNT];
    for (i, v) in RUN1.iter().enumerate() {
        p[i] = Param::ALL[i].unit().from_report(*v);
    }
    p
}

fn assert_close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got:.6}, want {want:.6}"
    );
}

#[test]
fn pose_a_transforms_match_urdf() {
    let model = Model::default();
    let joints = angles(POSE_A);
    assert_eq!(joints.get(Joint::RAnkleRoll), 0.07);
    let zero = vec![0.0; PARAMETER_COUNT];
    let cam = model.robot.camera_chain(&joints).eval(&zero);
    for (i, want) in [50.8464, 15.7286, 218.8119].iter().enumerate() {
        assert_close(cam.translation[i], *want, 1e-3, "T_OC translation");
    }
    let rows = [
        [0.5991, -0.2955, 0.7441],
        [0.1853, 0.9553, 0.2302],
        [-0.7789, 0.0, 0.6272],
    ];
    for (got, want) in cam.rotation.iter().zip(&rows) {
        for (g, w) in got.iter().zip(want) {
            assert_close(*g, *w, 1e-4, "T_OC rotation");
        }
    }
    let left = model
        .robot
        .sole_chain(Side::Left, &joints, &[0.0; 6])
        .eval(&zero);
    for (i, want) in [40.6731, 74.8950, -227.0421].iter().enumerate() {
        assert_close(left.translation[i], *want, 1e-3, "T_OS left");
    }
    let right = model
        .robot
        .sole_chain(Side::Right, &joints, &[0.0; 6])
        .eval(&zero);
    for (i, want) in [50.8203, -75.8509, -220.5209].iter().enumerate() {
        assert_close(right.translation[i], *want, 1e-3, "T_OS right");
    }
}

fn check_projections(side: Side, pose: [f64; 14], table: [([u32; 2], [f64; 2], [f64; 2]); 4]) {
    let model = Model::default();
    let chains = model.chains(side, &angles(pose));
    let vertices: Vec<Vertex> = table
        .iter()
        .map(|(rc, _, _)| Vertex {
            row: rc[0],
            col: rc[1],
        })
        .collect();
    let zero = vec![0.0; PARAMETER_COUNT];
    let at_zero = model.project(&chains, &zero, &vertices);
    let at_run1 = model.project(&chains, &run1(), &vertices);
    for (k, (rc, want0, want1)) in table.iter().enumerate() {
        let got0 = at_zero[k].expect("in front of the camera");
        let got1 = at_run1[k].expect("in front of the camera");
        for i in 0..2 {
            assert_close(got0[i], want0[i], 1e-3, &format!("{side:?} {rc:?} α=0"));
            assert_close(got1[i], want1[i], 1e-3, &format!("{side:?} {rc:?} α=run1"));
        }
    }
}

#[test]
fn pose_b_left_board_projections() {
    check_projections(
        Side::Left,
        POSE_B,
        [
            ([0, 0], [107.8892, 323.1221], [94.8711, 359.7071]),
            ([0, 5], [212.6478, 197.4562], [203.8879, 231.7800]),
            ([3, 0], [72.7683, 251.2417], [61.7090, 285.6672]),
            ([3, 5], [198.9846, 123.1521], [191.7808, 157.6286]),
        ],
    );
}

#[test]
fn pose_c_right_board_projections() {
    check_projections(
        Side::Right,
        POSE_C,
        [
            ([0, 0], [338.4606, 379.0638], [328.7271, 433.6568]),
            ([0, 5], [415.5379, 198.7543], [403.1257, 246.4083]),
            ([3, 0], [200.0941, 357.1311], [188.2028, 405.8016]),
            ([3, 5], [237.6186, 161.6496], [228.1338, 205.6757]),
        ],
    );
}

/// The reference gravity torques at pose A (lying on its back, default sandal).
#[test]
fn pose_a_gravity_torques() {
    let model = Model::default();
    let joints = angles(POSE_A);
    let left =
        naocalib::model::gravity::leg_torques(&model.robot, &model.board, Side::Left, &joints);
    let right =
        naocalib::model::gravity::leg_torques(&model.robot, &model.board, Side::Right, &joints);
    let want_left = [0.7861, 0.3455, 1.3550, 0.6162, 0.0647, 0.0247];
    let want_right = [0.7307, -0.3333, 1.2896, 0.6048, 0.0533, -0.0243];
    for k in 0..6 {
        assert_close(left[k], want_left[k], 1e-4, &format!("left torque {k}"));
        assert_close(right[k], want_right[k], 1e-4, &format!("right torque {k}"));
    }
}

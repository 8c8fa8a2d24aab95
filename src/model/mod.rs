//! The kinematic model of the NAO, its two cameras and the checkerboard sandals.
//!
//! Everything here is written once and generic over [`Scalar`], so the same code gives
//! values and derivatives; the chains are data ([`Chain`]) so that the Ceres shim can
//! evaluate the same model on Jets.

pub mod board;
pub mod bounds;
pub mod camera;
pub mod chain;
pub mod gravity;
pub mod held;
pub mod joint;
pub mod parameters;
pub mod pose;
pub mod robot;
pub mod scalar;

pub use board::{Board, Vertex};
pub use camera::{Camera, CameraId, Projection};
pub use chain::{Affine, Chain, Step};
pub use joint::{JOINT_COUNT, Joint, JointAngles, head_pitch_limits};
pub use parameters::{
    FAMILIES, Family, FamilyInfo, FixedSet, PAPER_PARAMETERS, PARAMETER_COUNT, Param, ParamGroup,
    Unit,
};
pub use pose::{Axis, Pose};
pub use robot::{RobotGeometry, Side};
pub use scalar::Scalar;

/// Everything fixed about one robot and its sandals: geometry, camera intrinsics, board.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Model {
    /// Link lengths and fixed angles.
    pub robot: RobotGeometry,
    /// Lower camera intrinsics.
    pub camera: Camera,
    /// The sandal pattern and its mount (the same for both feet).
    pub board: Board,
    /// Upper camera intrinsics (`[upper_camera]` of `dataset.toml`), when given.
    pub upper_camera: Option<Camera>,
}

impl Model {
    /// The robot no `dataset.toml` describes: the defaults (SPEC §2–4) wearing naocalib's
    /// sandal, [`Board::turned`].
    pub fn unconfigured() -> Self {
        Model {
            board: Board::turned(),
            ..Model::default()
        }
    }
}

/// The chains of one capture, origin → camera and origin → board of the leg in view, and
/// the projection of the camera that took it.
#[derive(Debug, Clone, PartialEq)]
pub struct StanceChains {
    /// `T_OC` (docs/MODEL.md §2.2): origin → the capture's camera.
    pub camera: Chain,
    /// `T_OS · Rz(α_RotZ) · T(α_TransX, α_TransY, 0) · T_SB` (docs/MODEL.md §4).
    pub board: Chain,
    /// The capture's camera's projection `P`.
    pub projection: Projection,
}

impl StanceChains {
    /// `T_CB = T_OC⁻¹ · T_OB`: the board in the camera frame.
    pub fn camera_to_board<T: Scalar>(&self, params: &[T]) -> Pose<T> {
        self.camera
            .eval(params)
            .inverse_then(&self.board.eval(params))
    }

    /// Both chains with the `held` parameters frozen at `values` (see [`Chain::freeze`]).
    pub fn freeze(&self, held: &[bool; PARAMETER_COUNT], values: &[f64]) -> StanceChains {
        StanceChains {
            camera: self.camera.freeze(held, values),
            board: self.board.freeze(held, values),
            projection: self.projection.freeze(held, values),
        }
    }

    /// The parameters either chain depends on, without repeats (the projection's are not
    /// included: see [`Projection::params`]).
    pub fn params(&self) -> Vec<Param> {
        let mut out = self.camera.params();
        for p in self.board.params() {
            if !out.contains(&p) {
                out.push(p);
            }
        }
        out
    }
}

impl Model {
    /// The chains of a lower-camera capture of the board on `side`, with joint angles
    /// `joints` (the gravity torques of compliance and play computed from them).
    pub fn chains(&self, side: Side, joints: &JointAngles) -> StanceChains {
        self.chains_for(CameraId::Lower, side, joints)
    }

    /// The chains of a capture by `camera` of the board on `side`, with joint angles
    /// `joints`.
    pub fn chains_for(&self, camera: CameraId, side: Side, joints: &JointAngles) -> StanceChains {
        let [rot_z, trans_x, trans_y] = side.board_params();
        let torques = gravity::leg_torques(&self.robot, &self.board, side, joints);
        let board = self
            .robot
            .sole_chain(side, joints, &torques)
            .rotate(Axis::Z, Affine::param(rot_z))
            .translate(Axis::X, Affine::param(trans_x))
            .translate(Axis::Y, Affine::param(trans_y))
            .fixed(self.board.mount());
        StanceChains {
            camera: self.robot.camera_chain_of(camera, joints),
            board,
            projection: self.projection(camera),
        }
    }

    /// The intrinsics of `camera`. The upper camera's are `[upper_camera]`; a model without
    /// that table (which no dataset with upper-camera captures is) uses the lower camera's.
    pub fn intrinsics(&self, camera: CameraId) -> &Camera {
        match camera {
            CameraId::Lower => &self.camera,
            CameraId::Upper => self.upper_camera.as_ref().unwrap_or(&self.camera),
        }
    }

    /// The projection of `camera` as data: its a-priori intrinsics with its intrinsics and
    /// distortion parameters added (`Fx` … `K2`, `UpperFx` … `UpperK2`).
    pub fn projection(&self, camera: CameraId) -> Projection {
        self.intrinsics(camera).projection_of(camera)
    }

    /// Projects every vertex in `vertices` through the capture's camera for parameters
    /// `params` (docs/MODEL.md §2.5); `None` for a vertex behind the camera.
    pub fn project<T: Scalar>(
        &self,
        chains: &StanceChains,
        params: &[T],
        vertices: &[Vertex],
    ) -> Vec<Option<[T; 2]>> {
        let pose = chains.camera_to_board(params);
        self.project_posed(chains, &pose, params, vertices.iter().copied())
            .collect()
    }

    /// [`Model::project`] with the board's pose in the camera frame, `pose`
    /// ([`StanceChains::camera_to_board`] at `params`), already found.
    pub fn project_posed<'a, T: Scalar>(
        &'a self,
        chains: &'a StanceChains,
        pose: &'a Pose<T>,
        params: &'a [T],
        vertices: impl IntoIterator<Item = Vertex> + 'a,
    ) -> impl Iterator<Item = Option<[T; 2]>> + 'a {
        let coefficients = chains.projection.coefficients_at(params);
        vertices.into_iter().map(move |v| {
            let p = self.board.vertex_position(v).map(scalar::lift::<T>);
            chains
                .projection
                .project_with(&coefficients, &pose.apply(&p))
        })
    }

    /// The camera with the intrinsics and distortion parameters of `params` (internal
    /// units, indexed by [`Param::index`]) added: the true camera of a simulated robot.
    pub fn camera_at(&self, params: &[f64]) -> Camera {
        self.intrinsics_at(CameraId::Lower, params)
    }

    /// The true intrinsics of `camera` for the parameters `params`: its a-priori
    /// intrinsics with its corrections added.
    pub fn intrinsics_at(&self, camera: CameraId, params: &[f64]) -> Camera {
        self.intrinsics(camera).corrected(camera, params)
    }
}

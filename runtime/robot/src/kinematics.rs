//! Forward kinematics and Jacobians, computed into a preallocated [`RobotData`] workspace.

use nalgebra::{
    DMatrix, DVector, Isometry3, IsometryMatrix3, Matrix3, Matrix6xX, Rotation3, Translation3, UnitQuaternion, Vector3,
};

use super::{JointKind, Robot};

/// Preallocated per-configuration state and scratch buffers for one [`Robot`] (like pinocchio's `Data`).
///
/// [`Robot::forward_kinematics`] fills it for a configuration `q`; every other query
/// (poses, Jacobians, dynamics) then works on that configuration without allocating.
#[derive(Debug, Clone)]
pub struct RobotData {
    /// The configuration of the last [`Robot::forward_kinematics`] call.
    pub(crate) q: Vec<f64>,
    /// Body i's rotation relative to body i-1 (the base for i = 0).
    pub(crate) local_rot: Vec<Matrix3<f64>>,
    /// Body i's origin in body i-1's frame.
    pub(crate) local_pos: Vec<Vector3<f64>>,
    /// Body i's rotation in the base frame.
    pub(crate) rot: Vec<Matrix3<f64>>,
    /// Body i's origin in the base frame.
    pub(crate) pos: Vec<Vector3<f64>>,
    pub(crate) omega: Vec<Vector3<f64>>,
    pub(crate) omega_dot: Vec<Vector3<f64>>,
    pub(crate) force: Vec<Vector3<f64>>,
    pub(crate) moment: Vec<Vector3<f64>>,
    pub(crate) zeros: Vec<f64>,
    /// Scratch for the mass matrix of the damped stop (no allocation per tick).
    pub(crate) mass: DMatrix<f64>,
    pub(crate) kinematics_done: bool,
}

impl RobotData {
    /// Body `i`'s rotation in the base frame at the last [`Robot::forward_kinematics`].
    ///
    /// # Panics
    /// If `i` is not a body of the robot.
    pub fn body_rotation(&self, i: usize) -> &Matrix3<f64> {
        &self.rot[i]
    }

    /// Body `i`'s origin in the base frame at the last [`Robot::forward_kinematics`].
    ///
    /// # Panics
    /// If `i` is not a body of the robot.
    pub fn body_position(&self, i: usize) -> &Vector3<f64> {
        &self.pos[i]
    }
}

impl Robot {
    /// A workspace for this robot. Allocate once, reuse every tick.
    pub fn data(&self) -> RobotData {
        let n = self.dof();
        RobotData {
            q: vec![0.0; n],
            local_rot: vec![Matrix3::identity(); n],
            local_pos: vec![Vector3::zeros(); n],
            rot: vec![Matrix3::identity(); n],
            pos: vec![Vector3::zeros(); n],
            omega: vec![Vector3::zeros(); n],
            omega_dot: vec![Vector3::zeros(); n],
            force: vec![Vector3::zeros(); n],
            moment: vec![Vector3::zeros(); n],
            zeros: vec![0.0; n],
            mass: DMatrix::zeros(n, n),
            kinematics_done: false,
        }
    }

    /// Forward kinematics of every body for joint positions `q` (rad, m); the basis of every other query.
    ///
    /// # Panics
    /// If `q.len()` differs from [`Robot::dof`] (check user input with [`Robot::check_dof`]).
    pub fn forward_kinematics(&self, data: &mut RobotData, q: &[f64]) {
        assert_eq!(q.len(), self.dof(), "joint vector length must equal dof");
        data.q.copy_from_slice(q);
        let mut parent_rot = Matrix3::identity();
        let mut parent_pos = Vector3::zeros();
        for (idx, body) in self.bodies.iter().enumerate() {
            let (rot, pos) = match body.kind {
                JointKind::Revolute => (body.rot0 * axis_rotation(&body.axis, q[idx]), body.pos0),
                JointKind::Prismatic => (body.rot0, body.pos0 + body.rot0 * body.axis * q[idx]),
            };
            data.local_rot[idx] = rot;
            data.local_pos[idx] = pos;
            parent_pos += parent_rot * pos;
            parent_rot *= rot;
            data.rot[idx] = parent_rot;
            data.pos[idx] = parent_pos;
        }
        data.kinematics_done = true;
    }

    /// The pose of link `link` (index into [`Robot::links`]) in the base frame, rotation as a matrix.
    pub fn link_in_base_matrix(&self, data: &RobotData, link: usize) -> IsometryMatrix3<f64> {
        debug_assert!(data.kinematics_done, "call forward_kinematics first");
        let info = &self.links[link];
        match info.body {
            None => info.link_in_body,
            Some(body) => {
                let body_in_base = IsometryMatrix3::from_parts(
                    Translation3::from(data.pos[body]),
                    Rotation3::from_matrix_unchecked(data.rot[body]),
                );
                body_in_base * info.link_in_body
            }
        }
    }

    /// The pose of link `link` in the base frame.
    pub fn link_in_base(&self, data: &RobotData, link: usize) -> Isometry3<f64> {
        let pose = self.link_in_base_matrix(data, link);
        Isometry3::from_parts(pose.translation, UnitQuaternion::from_rotation_matrix(&pose.rotation))
    }

    /// The tool link's pose in the base frame.
    pub fn tool_in_base(&self, data: &RobotData) -> Isometry3<f64> {
        self.link_in_base(data, self.tool_link)
    }

    /// The geometric Jacobian of the tool link origin, base frame, rows `[vx vy vz wx wy wz]`.
    ///
    /// # Panics
    /// If `out` does not have one column per joint.
    pub fn tool_jacobian(&self, data: &RobotData, out: &mut Matrix6xX<f64>) {
        self.link_jacobian(data, self.tool_link, &Vector3::zeros(), out);
    }

    /// The geometric Jacobian of a point fixed to a link (`point_in_link`, in the link frame),
    /// base frame, rows `[vx vy vz wx wy wz]`. Joints after the link's body have zero columns.
    ///
    /// # Panics
    /// If `out` does not have one column per joint.
    pub fn link_jacobian(&self, data: &RobotData, link: usize, point_in_link: &Vector3<f64>, out: &mut Matrix6xX<f64>) {
        debug_assert!(data.kinematics_done, "call forward_kinematics first");
        assert_eq!(out.ncols(), self.dof(), "jacobian must have dof columns");
        out.fill(0.0);
        let info = &self.links[link];
        let Some(last_body) = info.body else {
            return;
        };
        let point_in_body = info.link_in_body * nalgebra::Point3::from(*point_in_link);
        let point = data.rot[last_body] * point_in_body.coords + data.pos[last_body];
        for (idx, body) in self.bodies.iter().enumerate().take(last_body + 1) {
            let axis = data.rot[idx] * body.axis;
            let (linear, angular) = match body.kind {
                JointKind::Revolute => (axis.cross(&(point - data.pos[idx])), axis),
                JointKind::Prismatic => (axis, Vector3::zeros()),
            };
            let mut column = out.column_mut(idx);
            column[0] = linear.x;
            column[1] = linear.y;
            column[2] = linear.z;
            column[3] = angular.x;
            column[4] = angular.y;
            column[5] = angular.z;
        }
    }

    /// Convenience: tool pose, tool Jacobian and gravity torques at `q`, allocating (not for a hot loop).
    pub fn evaluate(&self, q: &[f64]) -> (Isometry3<f64>, Matrix6xX<f64>, DVector<f64>) {
        let mut data = self.data();
        self.forward_kinematics(&mut data, q);
        let mut jacobian = Matrix6xX::zeros(self.dof());
        self.tool_jacobian(&data, &mut jacobian);
        let mut gravity = DVector::zeros(self.dof());
        self.gravity_torques(&mut data, gravity.as_mut_slice());
        (self.tool_in_base(&data), jacobian, gravity)
    }
}

/// Rotation by `angle` about the unit `axis` (Rodrigues), specialised for coordinate axes.
#[inline]
fn axis_rotation(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let (x, y, z) = (axis.x, axis.y, axis.z);
    Matrix3::new(
        t * x * x + c,
        t * x * y - s * z,
        t * x * z + s * y,
        t * x * y + s * z,
        t * y * y + c,
        t * y * z - s * x,
        t * x * z - s * y,
        t * y * z + s * x,
        t * z * z + c,
    )
}

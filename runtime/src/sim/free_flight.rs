//! Free flight: the steps in which no collider of the arm can reach any object, integrated
//! without rapier. Such a step produces no contact, so rapier's collision detection and
//! contact solver have nothing to do in it, and its multibody step is the arm's equations of
//! motion `M(q) q̈ = τ − C(q, q̇) q̇ − g(q)`, which the robot model (the same URDF masses,
//! centres of mass and inertias rapier's bodies carry) computes for a fraction of rapier's cost
//! (its multibody mass matrix alone is about 40 % of a whole closed-loop tick).
//!
//! The integration is rapier's: semi-implicit Euler (`q̇⁺ = q̇ + dt q̈`, then `q⁺ = q + dt q̇⁺`),
//! rapier's viscous joint damping implicit as rapier has it. One difference: rapier treats the
//! Coriolis and gyroscopic terms semi-implicitly (their derivative in `q̇`, times `dt`, in the
//! mass matrix it solves with), this explicitly: an O(dt) difference in free motion, about
//! 1e-9 rad a step at the skills' speeds, which the controller's feedback absorbs.
//!
//! A step is free when every collider's bounding sphere stays farther from every object's box
//! than [`CLEAR_MARGIN_M`] plus the farthest any point of the arm can move in the step, no joint
//! leaves its limits in it, and the scene has no moving object (a button's cap is a body rapier
//! moves). While the arm flies free, rapier's multibody keeps the state of the last rapier step;
//! the plant writes the arm's state back into it before the next step that needs rapier.
// `Real` is f32 or f64 depending on the rapier flavour: casts and conversions to it are identities in one.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use nalgebra::{DMatrix, Vector3};
use rapier3d::math::{Pose, Real, Rotation};
use rapier3d::prelude::{ColliderHandle, ColliderSet, RigidBodyHandle, RigidBodySet, SharedShape};

use super::convert::{from_vec3, iso_of, vec3};
use crate::robot::{Robot, RobotData};

/// How much closer than rapier's contact prediction distance (and the step's largest motion)
/// a shape of the arm may come to an object before rapier takes the steps again, m.
pub(super) const CLEAR_MARGIN_M: f64 = 0.001;

/// A rotation matrix as rapier's quaternion, directly (no iteration): for poses every step.
fn quat_of(rot: &nalgebra::Matrix3<f64>) -> Rotation {
    let q = nalgebra::UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(*rot));
    Rotation::from_xyzw(q.i as Real, q.j as Real, q.k as Real, q.w as Real)
}

/// A shape of the arm's colliders, fixed to a robot body, with a sphere that bounds it.
#[derive(Clone)]
struct Bound {
    /// The robot body (index into the robot's joints) the shape rides on.
    body: usize,
    /// The shape's pose on the body.
    in_body: Pose,
    shape: SharedShape,
    /// The bounding sphere's centre in the body's frame, m.
    center: Vector3<f64>,
    /// Its radius, m.
    radius: f64,
}

/// An object's collider: its pose and shape, and the box that bounds it in the world, m.
#[derive(Clone)]
struct Object {
    pose: Pose,
    shape: SharedShape,
    min: Vector3<f64>,
    max: Vector3<f64>,
}

impl std::fmt::Debug for Bound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Bound")
            .field("body", &self.body)
            .field("radius", &self.radius)
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for Object {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Object")
            .field("min", &self.min)
            .field("max", &self.max)
            .finish_non_exhaustive()
    }
}

/// The arm's state and workspace while it flies free of rapier.
#[derive(Debug, Clone)]
pub(super) struct FreeFlight {
    /// The robot model with the scene's gravity.
    robot: Robot,
    data: RobotData,
    /// Whether free flight may be used at all (no moving objects in the scene).
    allowed: bool,
    /// Whether the arm's state lives here (rapier's multibody is stale) rather than in rapier.
    pub(super) active: bool,
    /// Joint positions (rad) and velocities (rad/s): the arm's state while active, else the
    /// state to start from (loaded from rapier by the plant).
    pub(super) q: Vec<f64>,
    pub(super) qd: Vec<f64>,
    /// Whether `data` holds the kinematics at `q`.
    kinematics_at_q: bool,
    /// The displacement and velocity of each of rapier's multibody dofs, for writing the state back.
    pub(super) disp: Vec<Real>,
    /// rapier's viscous joint damping, N m s/rad.
    damping: f64,
    bounds: Vec<Bound>,
    objects: Vec<Object>,
    /// How close (m) a shape may come to an object before rapier takes over: rapier's contact
    /// prediction distance (no contact point is generated farther) plus [`CLEAR_MARGIN_M`].
    clearance: f64,
    /// An upper bound on any collider point's distance from any joint axis, m: a point moves at
    /// most `reach · Σ|q̇ᵢ|` m/s.
    reach: f64,
    mass: DMatrix<f64>,
    bias: Vec<f64>,
    acc: Vec<f64>,
    q_next: Vec<f64>,
    qd_next: Vec<f64>,
    zeros: Vec<f64>,
}

/// What the plant needs to set free flight up: the rapier world as built.
pub(super) struct World<'a> {
    pub(super) bodies: &'a RigidBodySet,
    pub(super) colliders: &'a ColliderSet,
    /// The arm's bodies, one per joint.
    pub(super) links: &'a [RigidBodyHandle],
    /// Every collider of the arm (the tool's and the other links').
    pub(super) arm: &'a [ColliderHandle],
    /// Every object's collider.
    pub(super) objects: &'a [ColliderHandle],
}

impl FreeFlight {
    /// Free flight for an arm `robot` (gravity `gravity`, base frame = world) in `world`;
    /// `moving_objects` forbids it (a scene with a body rapier must keep moving).
    pub(super) fn new(
        mut robot: Robot,
        gravity: Vector3<f64>,
        damping: f64,
        prediction_m: f64,
        world: &World<'_>,
        moving_objects: bool,
    ) -> Self {
        robot.set_gravity(gravity);
        let n = robot.dof();
        let mut bounds = Vec::with_capacity(world.arm.len());
        for handle in world.arm {
            let Some(collider) = world.colliders.get(*handle) else {
                continue;
            };
            let (Some(parent), Some(in_body)) = (collider.parent(), collider.position_wrt_parent()) else {
                continue;
            };
            let Some(body) = world.links.iter().position(|link| *link == parent) else {
                continue;
            };
            // A compound's parts one by one: each bounds tighter, and a distance query on a
            // part (a sphere, a cylinder) never allocates.
            let parts: Vec<(Pose, SharedShape)> = match collider.shape().as_compound() {
                Some(compound) => compound
                    .shapes()
                    .iter()
                    .map(|(pose, shape)| (*in_body * *pose, shape.clone()))
                    .collect(),
                None => vec![(*in_body, collider.shared_shape().clone())],
            };
            for (in_body, shape) in parts {
                let local = shape.compute_local_aabb();
                let center = iso_of(&in_body) * nalgebra::Point3::from(from_vec3(local.center()));
                bounds.push(Bound {
                    body,
                    in_body,
                    shape,
                    center: center.coords,
                    radius: from_vec3(local.half_extents()).norm(),
                });
            }
        }
        let mut objects = Vec::with_capacity(world.objects.len());
        for handle in world.objects {
            let Some(collider) = world.colliders.get(*handle) else {
                continue;
            };
            // Placed from the body: a collider's own pose is only synchronised by a step.
            let pose = match (
                collider.parent().and_then(|h| world.bodies.get(h)),
                collider.position_wrt_parent(),
            ) {
                (Some(body), Some(relative)) => *body.position() * *relative,
                _ => *collider.position(),
            };
            let aabb = collider.shape().compute_aabb(&pose);
            objects.push(Object {
                pose,
                shape: collider.shared_shape().clone(),
                min: from_vec3(aabb.mins),
                max: from_vec3(aabb.maxs),
            });
        }
        // Every joint lies within the chain's length of the base origin, and every collider
        // point within that length plus its sphere's offset and radius: their sum bounds its
        // distance from any joint axis.
        let chain: f64 = robot.bodies.iter().map(|body| body.pos0.norm()).sum();
        let reach = bounds
            .iter()
            .map(|bound| 2.0 * chain + bound.center.norm() + bound.radius)
            .fold(0.0, f64::max);
        FreeFlight {
            data: robot.data(),
            zeros: vec![0.0; n],
            allowed: !moving_objects && !bounds.is_empty(),
            active: false,
            kinematics_at_q: false,
            disp: vec![0.0; n],
            q: vec![0.0; n],
            qd: vec![0.0; n],
            damping,
            bounds,
            objects,
            clearance: prediction_m + CLEAR_MARGIN_M,
            reach,
            mass: DMatrix::zeros(n, n),
            bias: vec![0.0; n],
            acc: vec![0.0; n],
            q_next: vec![0.0; n],
            qd_next: vec![0.0; n],
            robot,
        }
    }

    /// Whether free flight may be used in this scene.
    pub(super) fn allowed(&self) -> bool {
        self.allowed
    }

    /// Marks `q` and `qd` as just loaded from rapier.
    pub(super) fn loaded(&mut self) {
        self.kinematics_at_q = false;
    }

    /// The rotation of robot body `body` in the base frame at `q`, valid after a successful
    /// [`FreeFlight::try_step`].
    pub(super) fn body_rotation(&self, body: usize) -> nalgebra::Matrix3<f64> {
        self.data.rot[body]
    }

    /// The pose of robot body `body` in the base frame at `q`, valid after a successful
    /// [`FreeFlight::try_step`].
    pub(super) fn body_pose(&self, body: usize) -> nalgebra::IsometryMatrix3<f64> {
        nalgebra::IsometryMatrix3::from_parts(
            nalgebra::Translation3::from(self.data.pos[body]),
            nalgebra::Rotation3::from_matrix_unchecked(self.data.rot[body]),
        )
    }

    /// Tries one free step of `dt` from the state in `q`, `qd` under joint torques `torque`:
    /// when no collider can come within [`CLEAR_MARGIN_M`] of an object and every joint stays
    /// strictly inside its limits, advances the state, marks the flight active and returns
    /// `true`; otherwise changes nothing and returns `false` (rapier must take the step).
    pub(super) fn try_step(&mut self, torque: &[f64], dt: f64) -> bool {
        if !self.allowed {
            return false;
        }
        let (q, qd) = (&self.q, &self.qd);
        if !self.kinematics_at_q {
            self.robot.forward_kinematics(&mut self.data, q);
            self.kinematics_at_q = true;
        }
        // rapier finds contacts at the step's start: none within its prediction distance, no
        // contact force in the step. The motion bound keeps a margin all the same.
        let speed_bound: f64 = qd.iter().map(|v| v.abs()).sum::<f64>() * self.reach;
        let margin = self.clearance + speed_bound * dt;
        for bound in &self.bounds {
            let (rot, pos) = (&self.data.rot[bound.body], &self.data.pos[bound.body]);
            let center = rot * bound.center + pos;
            for object in &self.objects {
                let outside = (object.min - center).sup(&(center - object.max)).sup(&Vector3::zeros());
                if outside.norm() - bound.radius > margin {
                    continue;
                }
                // Close by the spheres: the shapes' own distance decides.
                let body_pose = Pose::from_parts(vec3(pos), quat_of(rot));
                let distance = rapier3d::parry::query::distance(
                    &(body_pose * bound.in_body),
                    bound.shape.as_ref(),
                    &object.pose,
                    object.shape.as_ref(),
                );
                match distance {
                    Ok(found) if f64::from(found.distance) > margin => {}
                    _ => return false,
                }
            }
        }
        // q̈ = M⁻¹ (τ − C q̇ − g − d q̇⁺), the damping implicit: (M + dt d I) q̈ = τ − C q̇ − g − d q̇.
        self.robot
            .inverse_dynamics(&mut self.data, qd, &self.zeros, &mut self.bias);
        self.robot.mass_matrix(&mut self.data, &mut self.mass);
        let n = q.len();
        for idx in 0..n {
            self.mass[(idx, idx)] += dt * self.damping;
            self.acc[idx] = torque[idx] - self.bias[idx] - self.damping * qd[idx];
        }
        if !cholesky_solve_in_place(&mut self.mass, &mut self.acc) {
            return false;
        }
        for (idx, (lower, upper)) in self.robot.position_limits().enumerate() {
            self.qd_next[idx] = qd[idx] + dt * self.acc[idx];
            self.q_next[idx] = q[idx] + dt * self.qd_next[idx];
            let inside = self.q_next[idx] > lower && self.q_next[idx] < upper;
            if !inside || !self.q_next[idx].is_finite() || !self.qd_next[idx].is_finite() {
                return false;
            }
        }
        self.q.copy_from_slice(&self.q_next);
        self.qd.copy_from_slice(&self.qd_next);
        self.robot.forward_kinematics(&mut self.data, &self.q);
        self.active = true;
        true
    }
}

/// Solves `a x = b` for a symmetric positive definite `a` by Cholesky, in place (`a` becomes its
/// factor, `b` the solution), without allocating. `false` when `a` is not positive definite.
fn cholesky_solve_in_place(a: &mut DMatrix<f64>, b: &mut [f64]) -> bool {
    let n = b.len();
    for col in 0..n {
        let mut diag = a[(col, col)];
        for k in 0..col {
            diag -= a[(col, k)] * a[(col, k)];
        }
        if diag.is_nan() || diag <= 0.0 {
            return false;
        }
        let diag = diag.sqrt();
        a[(col, col)] = diag;
        for row in col + 1..n {
            let mut value = a[(row, col)];
            for k in 0..col {
                value -= a[(row, k)] * a[(col, k)];
            }
            a[(row, col)] = value / diag;
        }
    }
    for row in 0..n {
        let mut value = b[row];
        for k in 0..row {
            value -= a[(row, k)] * b[k];
        }
        b[row] = value / a[(row, row)];
    }
    for row in (0..n).rev() {
        let mut value = b[row];
        for k in row + 1..n {
            value -= a[(k, row)] * b[k];
        }
        b[row] = value / a[(row, row)];
    }
    true
}

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
//! A step is free when every shape of the arm stays farther from every object than rapier's
//! contact prediction distance plus [`CLEAR_MARGIN_M`] plus the farthest any point of the arm
//! can move in the step (bounding spheres first, then parry's distance), every joint starts and
//! ends the step strictly inside its limits (rapier's limit constraint acts only on a joint that
//! starts at or beyond a limit), and the scene has no moving object: any body rapier moves other
//! than the arm's links (a button's cap) or any impulse joint rules free flight out for the
//! whole run, since rapier would have to step it. While the arm flies free, rapier's multibody
//! keeps the state of the last rapier step; the plant writes the arm's state back into it before
//! the next step that needs rapier.
//!
//! **Why this is rapier's step.** rapier finds contacts at a step's start, at the positions the
//! step starts from, and generates no contact point between shapes farther apart than its
//! prediction distance; with every shape farther than that, its step has no contact constraint,
//! no joint limit constraint (every joint inside its limits) and no other moving body: its
//! multibody step is the free equations of motion. The motion bound is a margin on top: a step
//! that ends within the prediction distance is still taken free, but the next one is rapier's.
//! The wrist sensor reads contact wrenches only (no inertial load), so in free flight it reads a
//! zero wrench through the same noise, bias and filter.
//!
//! **The motion bound.** A point `p` of the arm moves at `Σᵢ q̇ᵢ aᵢ × (p − oᵢ)` (`aᵢ`, `oᵢ` joint
//! i's unit axis and a point on it), so at most `Σᵢ |q̇ᵢ| · |p − oᵢ|`. Every joint origin lies
//! within the chain's length `L = Σ |pos0|` of the base origin, every shape's bounding sphere
//! within `L` plus its centre's offset `c` plus its radius `r`: `|p − oᵢ| ≤ 2L + c + r`, the
//! `reach`, whatever the configuration and however the links turn (at least 1 m/m when a joint is
//! prismatic: it moves the points beyond it by its own displacement). The step moves the joints by
//! `dt q̇⁺` along a straight line in joint space (semi-implicit Euler), so no point moves farther
//! than `dt · reach · Σᵢ |q̇⁺ᵢ|`, the velocity after the step's acceleration.
//!
//! **Refusing without asking.** The same bound holds between any two configurations: every point
//! lies within `reach · Σᵢ |Δqᵢ|` of where it was (along the straight line between them, whatever
//! path the arm took), so a shape and an object found `d` apart are at most `d + reach · Σᵢ |Δqᵢ|`
//! apart later. After a step is refused for nearness, the next ones are refused without the
//! kinematics and distance queries for as long as that bound stays within the clearance: in
//! contact, most steps; the decisions are the queries' own (tested).
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

/// Rounding allowance of the nearness bound in [`FreeFlight::try_step`], m: a step whose bound
/// comes within this of the clearance is queried rather than refused outright.
const NEAR_ROUNDING_M: f64 = 1e-9;

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
    /// Whether the scene allows free flight at all (no moving objects).
    allowed: bool,
    /// Whether the plant's user allows it ([`FreeFlight::set_enabled`]; on by default).
    enabled: bool,
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
    /// The distance of the shape and object that last refused a step for nearness (m,
    /// `−∞` when their distance could not be computed), and the joint positions it was refused
    /// at, in `q_near`: see [`FreeFlight::try_step`].
    near: Option<f64>,
    q_near: Vec<f64>,
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
        let chain: f64 = robot.bodies().iter().map(|body| body.pos0.norm()).sum();
        // A prismatic joint moves every point beyond it by its own displacement: at most 1 m/m.
        let prismatic = robot
            .bodies()
            .iter()
            .any(|body| body.kind == crate::robot::JointKind::Prismatic);
        let reach = bounds
            .iter()
            .map(|bound| 2.0 * chain + bound.center.norm() + bound.radius)
            .fold(if prismatic { 1.0 } else { 0.0 }, f64::max);
        FreeFlight {
            data: robot.data(),
            zeros: vec![0.0; n],
            allowed: !moving_objects && !bounds.is_empty(),
            enabled: true,
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
            near: None,
            q_near: vec![0.0; n],
            mass: DMatrix::zeros(n, n),
            bias: vec![0.0; n],
            acc: vec![0.0; n],
            q_next: vec![0.0; n],
            qd_next: vec![0.0; n],
            robot,
        }
    }

    /// Whether free flight may be used: the scene allows it and the user has not switched it off.
    pub(super) fn allowed(&self) -> bool {
        self.allowed && self.enabled
    }

    /// Allows (`true`, the default) or forbids free flight. Forbidding it takes effect at the
    /// next step, which lands an active flight and is rapier's.
    pub(super) fn set_enabled(&mut self, enabled: bool) {
        self.enabled = enabled;
    }

    /// Marks `q` and `qd` as just loaded from rapier.
    pub(super) fn loaded(&mut self) {
        self.kinematics_at_q = false;
    }

    /// The rotation of robot body `body` in the base frame at `q`, valid after a successful
    /// [`FreeFlight::try_step`].
    pub(super) fn body_rotation(&self, body: usize) -> nalgebra::Matrix3<f64> {
        *self.data.body_rotation(body)
    }

    /// The pose of robot body `body` in the base frame at `q`, valid after a successful
    /// [`FreeFlight::try_step`].
    pub(super) fn body_pose(&self, body: usize) -> nalgebra::IsometryMatrix3<f64> {
        nalgebra::IsometryMatrix3::from_parts(
            nalgebra::Translation3::from(*self.data.body_position(body)),
            nalgebra::Rotation3::from_matrix_unchecked(*self.data.body_rotation(body)),
        )
    }

    /// Tries one free step of `dt` from the state in `q`, `qd` under joint torques `torque`:
    /// when every joint starts and ends the step strictly inside its limits and no shape of the
    /// arm comes within the clearance plus the step's motion bound of an object (see the module
    /// documentation), advances the state, marks the flight active and returns `true`;
    /// otherwise changes nothing and returns `false` (rapier must take the step).
    pub(super) fn try_step(&mut self, torque: &[f64], dt: f64) -> bool {
        if !self.allowed() {
            return false;
        }
        // rapier's limit constraint acts in a step that starts at or beyond a limit
        // (`RapierPlant::gate_joint_limits` switches it on by the same test).
        let inside = self
            .robot
            .position_limits()
            .zip(&self.q)
            .all(|((lower, upper), q)| *q > lower && *q < upper);
        if !inside {
            return false;
        }
        // The pair that last refused a step for nearness was `near` apart at `q_near`; a point of
        // the arm lies at most `reach · Σ|Δq|` from where it was at `q_near` (along the straight
        // line between the two configurations, whatever path the arm took; objects are static),
        // so their distance is still at most `near + reach · Σ|Δq|`. While that is within the
        // clearance (less a nanometre for rounding), the query below would refuse the step as
        // well: refuse it without the kinematics and the distance queries. In contact this is
        // most steps, and the refusals are the same as querying.
        if let Some(near) = self.near {
            let moved: f64 = self.q.iter().zip(&self.q_near).map(|(a, b)| (a - b).abs()).sum();
            if near + self.reach * moved + NEAR_ROUNDING_M <= self.clearance {
                return false;
            }
        }
        if !self.kinematics_at_q {
            self.robot.forward_kinematics(&mut self.data, &self.q);
            self.kinematics_at_q = true;
        }
        // First with the motion bound from the velocity at the step's start (cheap, and it
        // refuses the steps near contact before any dynamics), keeping the smallest distance
        // found: checked again below against the bound from the velocity after the step.
        let start_speed: f64 = self.qd.iter().map(|v| v.abs()).sum();
        let gap = match self.gap_beyond(self.clearance + dt * self.reach * start_speed) {
            Ok(gap) => {
                self.near = None;
                gap
            }
            Err(near) => {
                self.near = Some(near);
                self.q_near.copy_from_slice(&self.q);
                return false;
            }
        };
        // q̈ = M⁻¹ (τ − C q̇ − g − d q̇⁺), the damping implicit: (M + dt d I) q̈ = τ − C q̇ − g − d q̇.
        let (q, qd) = (&self.q, &self.qd);
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
        // The step moves the joints by dt q̇⁺: no point of the arm moves farther than this.
        let motion = dt * self.reach * self.qd_next.iter().map(|v| v.abs()).sum::<f64>();
        if gap <= self.clearance + motion {
            return false;
        }
        self.q.copy_from_slice(&self.q_next);
        self.qd.copy_from_slice(&self.qd_next);
        self.robot.forward_kinematics(&mut self.data, &self.q);
        self.active = true;
        true
    }

    /// The smallest distance between a shape of the arm (at the kinematics in `data`) and an
    /// object, or a lower bound on it (a bounding sphere's distance from an object's box) where
    /// that bound exceeds `margin`; `Err` with the distance of the first shape and object found
    /// within `margin` of each other (`−∞` when parry cannot tell their distance).
    fn gap_beyond(&self, margin: f64) -> Result<f64, f64> {
        let mut gap = f64::INFINITY;
        for bound in &self.bounds {
            let (rot, pos) = (self.data.body_rotation(bound.body), self.data.body_position(bound.body));
            let center = rot * bound.center + pos;
            for object in &self.objects {
                let outside = (object.min - center).sup(&(center - object.max)).sup(&Vector3::zeros());
                let sphere_gap = outside.norm() - bound.radius;
                if sphere_gap > margin {
                    gap = gap.min(sphere_gap);
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
                    Ok(found) if f64::from(found.distance) > margin => gap = gap.min(f64::from(found.distance)),
                    Ok(found) => return Err(f64::from(found.distance)),
                    Err(_) => return Err(f64::NEG_INFINITY),
                }
            }
        }
        Ok(gap)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::Plant;
    use crate::{RapierPlant, Scene};

    /// table.toml's arm with the table `drop_m` lower, started where the probe tip is 1 mm above
    /// the table (the scene itself starts it 5 cm higher).
    fn table_plant(drop_m: f64) -> RapierPlant {
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/table.toml");
        let mut scene = Scene::from_file(&path).expect("example scene loads");
        scene.set("table.z", &(0.275 - drop_m).to_string()).expect("valid z");
        scene
            .set("robot.q0", "[0.0, -0.5, 0.0, 1.5, 0.0, -1.1415926535897931, 0.0]")
            .expect("the start 1 mm above the table");
        RapierPlant::from_scene(&scene).expect("scene builds")
    }

    /// The gravity torques at `q`.
    fn gravity(robot: &Robot, q: &[f64]) -> Vec<f64> {
        let mut data = robot.data();
        robot.forward_kinematics(&mut data, q);
        let mut out = vec![0.0; robot.dof()];
        robot.gravity_torques(&mut data, &mut out);
        out
    }

    /// Uniform numbers in `[0, 1)` from a xorshift generator seeded with `seed` (not 0).
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Puts the flight at `q`, `qd` as if loaded from rapier.
    fn load(free: &mut FreeFlight, q: &[f64], qd: &[f64]) {
        free.q.copy_from_slice(q);
        free.qd.copy_from_slice(qd);
        free.active = false;
        free.loaded();
    }

    #[test]
    fn the_motion_bound_covers_every_point_of_every_shape() {
        // Random configurations and joint motions Δq (up to 0.3 rad a joint): no point of any
        // shape's bounding sphere moves farther than reach · Σ|Δqᵢ|. A point of a sphere moves
        // at most its centre's displacement plus its radius times the body's rotation angle.
        let plant = table_plant(5.0);
        let free = plant.free.as_ref().expect("built");
        let robot = &free.robot;
        let (mut before, mut after) = (robot.data(), robot.data());
        let mut uniform = uniform(0x2545_f491_4f6c_dd1d);
        let mut tightest: f64 = 0.0;
        for _ in 0..2000 {
            let q: Vec<f64> = robot
                .position_limits()
                .map(|(lo, hi)| lo + (hi - lo) * uniform())
                .collect();
            let dq: Vec<f64> = q.iter().map(|_| 0.6 * (uniform() - 0.5)).collect();
            let moved: Vec<f64> = q.iter().zip(&dq).map(|(q, d)| q + d).collect();
            robot.forward_kinematics(&mut before, &q);
            robot.forward_kinematics(&mut after, &moved);
            let bound = free.reach * dq.iter().map(|d| d.abs()).sum::<f64>();
            for shape in &free.bounds {
                let centre =
                    |data: &RobotData| *data.body_rotation(shape.body) * shape.center + *data.body_position(shape.body);
                let turn = nalgebra::Rotation3::from_matrix_unchecked(
                    after.body_rotation(shape.body) * before.body_rotation(shape.body).transpose(),
                )
                .angle();
                let farthest = (centre(&after) - centre(&before)).norm() + shape.radius * turn;
                assert!(farthest <= bound, "a point moved {farthest} m, bound {bound} m");
                tightest = tightest.max(farthest / bound);
            }
        }
        // The bound is conservative, not absurd: the fastest point uses a fair share of it.
        assert!(tightest > 0.1, "the fastest point moved {tightest} of the bound");
    }

    #[test]
    fn a_joint_at_or_beyond_its_limit_is_left_to_rapier() {
        // rapier's limit constraint acts in a step that starts beyond the limit, even when the
        // joint moves back in within it.
        let mut plant = table_plant(5.0);
        let robot = plant.robot().clone();
        let q0 = plant.observe().q.as_slice().to_vec();
        let (_, upper) = robot.position_limits().nth(3).expect("7 joints");
        let free = plant.free.as_mut().expect("built");
        let mut qd = vec![0.0; 7];
        qd[3] = -1.0;
        for (offset, free_step) in [(-2e-3, true), (0.0, false), (1e-4, false)] {
            let mut q = q0.clone();
            q[3] = upper + offset;
            load(free, &q, &qd);
            let tau = gravity(&robot, &q);
            assert_eq!(
                free.try_step(&tau, 1e-3),
                free_step,
                "joint 4 at its limit {offset:+} rad"
            );
        }
        // A step that would end beyond it is rapier's too.
        let mut q = q0.clone();
        q[3] = upper - 2e-4;
        qd[3] = 1.0;
        load(free, &q, &qd);
        assert!(!free.try_step(&gravity(&robot, &q), 1e-3));
    }

    #[test]
    fn a_step_the_nearness_bound_refuses_the_distance_query_refuses_too() {
        // The probe tip 1 mm above the table: refused for nearness, which leaves the bound. From
        // joint displacements around that configuration (log-uniform, 1e-5 to 0.1 rad a joint),
        // a flight that remembers the refusal and one that does not take the same decision;
        // near by, the bound refuses without querying, farther off the query decides.
        let mut plant = table_plant(0.0);
        let robot = plant.robot().clone();
        let q0 = plant.observe().q.as_slice().to_vec();
        let free = plant.free.as_mut().expect("built");
        load(free, &q0, &[0.0; 7]);
        assert!(!free.try_step(&gravity(&robot, &q0), 1e-3), "1 mm above the table");
        let near = free.near.expect("refused for nearness");
        assert!((0.0..0.0015).contains(&near), "the tip's distance {near} m");
        let refused = free.clone();
        let mut uniform = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut by_bound, mut queried, mut flew) = (0, 0, 0);
        for case in 0..600 {
            let scale = 10f64.powf(-5.0 + 4.0 * uniform());
            let q: Vec<f64> = q0.iter().map(|q| q + scale * (2.0 * uniform() - 1.0)).collect();
            let tau = gravity(&robot, &q);
            let mut remembering = refused.clone();
            load(&mut remembering, &q, &[0.0; 7]);
            let mut forgetting = remembering.clone();
            forgetting.near = None;
            let moved: f64 = q.iter().zip(&q0).map(|(a, b)| (a - b).abs()).sum();
            if near + refused.reach * moved + NEAR_ROUNDING_M <= refused.clearance {
                by_bound += 1;
            } else {
                queried += 1;
            }
            let free_step = forgetting.try_step(&tau, 1e-3);
            assert_eq!(remembering.try_step(&tau, 1e-3), free_step, "case {case}: {q:?}");
            flew += usize::from(free_step);
        }
        assert!(
            by_bound > 50 && queried > 50 && flew > 20,
            "{by_bound} by the bound, {queried} queried, {flew} free"
        );
    }

    #[test]
    fn the_motion_bound_takes_the_velocity_after_the_step() {
        // The probe tip 6.5 mm above the table, at rest: clear by 0.5 mm beyond the 6 mm
        // clearance. Holding still it flies free; a torque that accelerates the wrist to about
        // 1 rad/s within the step could carry it farther than that, so rapier takes the step
        // (a bound from the velocity at the step's start, zero, would have let it fly).
        let mut plant = table_plant(0.0055);
        let robot = plant.robot().clone();
        let q = plant.observe().q.as_slice().to_vec();
        let hold = gravity(&robot, &q);
        let free = plant.free.as_mut().expect("built");
        assert!((free.clearance - 0.006).abs() < 1e-12, "clearance {}", free.clearance);
        load(free, &q, &[0.0; 7]);
        assert!(free.try_step(&hold, 1e-3), "holding still 6.5 mm above the table");
        let mut mass = DMatrix::zeros(7, 7);
        robot.mass_matrix(&mut free.data, &mut mass);
        let mut kick = hold.clone();
        kick[5] += 1e3 * mass[(5, 5)];
        load(free, &q, &[0.0; 7]);
        assert!(!free.try_step(&kick, 1e-3), "kicked 6.5 mm above the table");
    }
}

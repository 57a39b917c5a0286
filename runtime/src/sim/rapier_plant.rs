//! The rapier plant: the robot as a rapier multibody with exact joint torques, the scene's objects and
//! the wrist sensor. The only file that touches rapier's (glam) types.
// `Real` is f32 or f64 depending on the rapier flavour: casts and conversions to it are identities in one.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use nalgebra::{DVector, Isometry3, IsometryMatrix3, Matrix3, UnitQuaternion, Vector3, Vector6};
use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::prelude::{
    ActiveHooks, CCDSolver, CoefficientCombineRule, ColliderBuilder, ColliderHandle, ColliderSet, DefaultBroadPhase,
    GenericJointBuilder, Group, ImpulseJointSet, IntegrationParameters, InteractionGroups, InteractionTestMode,
    IslandManager, JointAxesMask, JointAxis, MassProperties, MultibodyJointHandle, MultibodyJointSet, NarrowPhase,
    PairContacts, PhysicsPipeline, RigidBodyBuilder, RigidBodyHandle, RigidBodySet, SoftBodySet, SpringCoefficients,
};

use super::{ObjectKind, Scene, SceneError, SensorConfig, WristSensor};
use crate::plant::{saturate, Observation, Plant, PlantError};
use crate::robot::{JointKind, Robot, RobotError, Shape};

/// Why a simulation could not be built.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The scene file.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The robot description.
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// A robot the simulation cannot represent.
    #[error("robot `{robot}`: {reason}")]
    Unsupported {
        /// The robot's name.
        robot: String,
        /// What is not supported.
        reason: String,
    },
}

/// A spring-loaded button in the simulation.
#[derive(Debug, Clone)]
struct Button {
    name: String,
    joint: MultibodyJointHandle,
    cap: RigidBodyHandle,
    stiffness: f64,
    preload: f64,
    damping: f64,
}

/// Physics settings beyond the scene file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RapierOptions {
    /// Viscous damping rapier itself adds to every arm joint, N m s/rad. 0 = honest torque control
    /// (rapier's default would be 0.1).
    pub joint_damping: f64,
}

impl Default for RapierOptions {
    fn default() -> Self {
        RapierOptions { joint_damping: 0.0 }
    }
}

/// Whether the simulation runs in double precision (`rapier3d-f64`); `false` with `rapier3d` (f32).
pub const SIM_F64: bool = std::mem::size_of::<Real>() == 8;

/// The robot and scene simulated by rapier, 1 ms steps, torque-controlled.
///
/// **Precision.** rapier's scalar is [`Real`](rapier3d::math::Real): `f32` with the crate `rapier3d`
/// used today, `f64` with `rapier3d-f64` (this file compiles unchanged with either; switch with
/// `rapier3d = { package = "rapier3d-f64", version = "0.36.1" }` in the workspace manifest). See
/// [`SIM_F64`]. The controller and model stay in f64; conversion happens only at this plant's boundary.
/// In `f32` the multibody's gravity forces are off by f32 round-off (link poses about 3e-7 m off at
/// 1 m reach, generalized forces about 1e-5 N m on 30-50 N m), so τ = g(q) from the f64 model leaves
/// a residual acceleration up to 5e-5 rad/s² and the arm drifts up to 8e-4 rad over 5 s; in `f64`
/// the same code holds it to 2e-12 rad. Measured cost of `f64`: about 4 % (16.2 vs 16.9 µs a step
/// pressing on the table with the sensor on, release, 2-core VM). A 10 N press reads back within
/// 0.0002 N in both.
///
/// **Torques.** rapier has no "joint torque" input. Every step each joint torque τᵢ is applied as a
/// pure moment `+τᵢ aᵢ` on the child body and `−τᵢ aᵢ` on the parent (aᵢ the world joint axis); the
/// reduced-coordinate multibody projects link moments through Jᵀ, so this is exact. Commands are
/// saturated at the URDF effort limits. Joint position limits are rapier joint limits. Only the tool
/// (links from the sensor link on) collides with the scene; the arm links carry mass only.
///
/// **Buttons.** A button's cap is a light dynamic body on a prismatic multibody joint, pushed up by a spring
/// applied every step. Its lower stop is a fixed collider the tool rests on once the cap is fully pressed
/// (a joint limit alone chattered under a press), and tool-cap contacts are stiffened (1 kHz instead of
/// rapier's 30 Hz, which let the tool sink 14 mm into a 20 g cap at 10 N).
pub struct RapierPlant {
    robot: Robot,
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    islands: IslandManager,
    broad_phase: DefaultBroadPhase,
    narrow_phase: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    ccd: CCDSolver,
    gravity: Vector,
    root: RigidBodyHandle,
    links: Vec<RigidBodyHandle>,
    joints: Vec<MultibodyJointHandle>,
    tool_colliders: Vec<ColliderHandle>,
    sensor_body: usize,
    sensor_in_body: IsometryMatrix3<f64>,
    buttons: Vec<Button>,
    torque: Vec<f64>,
    sensor: WristSensor,
    ideal_wrench_base: Vector6<f64>,
    wrench_sensor: Vector6<f64>,
    wrench_base: Vector6<f64>,
    t: f64,
    dt: f64,
}

fn vec3(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as Real, v.y as Real, v.z as Real)
}

fn from_vec3(v: Vector) -> Vector3<f64> {
    Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

fn quat(rot: &Matrix3<f64>) -> Rotation {
    let q = UnitQuaternion::from_matrix(rot);
    Rotation::from_xyzw(q.i as Real, q.j as Real, q.k as Real, q.w as Real).normalize()
}

fn pose_of(iso: &IsometryMatrix3<f64>) -> Pose {
    Pose::from_parts(vec3(&iso.translation.vector), quat(iso.rotation.matrix()))
}

fn pose_of_quat(iso: &Isometry3<f64>) -> Pose {
    pose_of(&IsometryMatrix3::from_parts(
        iso.translation,
        iso.rotation.to_rotation_matrix(),
    ))
}

fn iso_of(pose: &Pose) -> IsometryMatrix3<f64> {
    let r = pose.rotation;
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        f64::from(r.w),
        f64::from(r.x),
        f64::from(r.y),
        f64::from(r.z),
    ));
    IsometryMatrix3::from_parts(
        nalgebra::Translation3::from(from_vec3(pose.translation)),
        q.to_rotation_matrix(),
    )
}

fn rpy_pose(xyz: [f64; 3], rpy: [f64; 3]) -> Pose {
    pose_of(&IsometryMatrix3::from_parts(
        nalgebra::Translation3::new(xyz[0], xyz[1], xyz[2]),
        nalgebra::Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    ))
}

/// rapier's cylinders and capsules run along y; URDF's and the scene's along z.
fn z_to_y() -> Pose {
    Pose::from_rotation(Rotation::from_rotation_x(std::f64::consts::FRAC_PI_2 as Real))
}

/// rapier mass properties; diagonal tensors go in as principal moments (no eigen-solve here; rapier may still
/// re-diagonalise when it sums them with the tool colliders' zero mass, which only permutes the axes).
fn mass_properties(mass: f64, com: &Vector3<f64>, inertia: &Matrix3<f64>) -> MassProperties {
    let off_diagonal = inertia[(0, 1)].abs() + inertia[(0, 2)].abs() + inertia[(1, 2)].abs();
    if off_diagonal == 0.0 {
        MassProperties::new(vec3(com), mass as Real, vec3(&inertia.diagonal()))
    } else {
        MassProperties::with_inertia_matrix(
            vec3(com),
            mass as Real,
            rapier3d::math::Matrix::from_cols(
                vec3(&inertia.column(0).into_owned()),
                vec3(&inertia.column(1).into_owned()),
                vec3(&inertia.column(2).into_owned()),
            ),
        )
    }
}

/// Natural frequency of the soft contacts between two moving bodies (tool and button cap), Hz.
const CAP_CONTACT_HZ: Real = 1000.0;
/// How far a button's joint limit lies beyond its hard stop, m: the limit is only a backstop, the stop
/// (a fixed collider) carries the press.
const BUTTON_LIMIT_MARGIN: Real = 0.001;

const TOOL_GROUP: Group = Group::GROUP_1;
const SCENE_GROUP: Group = Group::GROUP_2;

impl RapierPlant {
    /// Builds the simulation of a scene file: loads its URDF (relative to the scene), starts at `q0`.
    pub fn from_scene(scene: &Scene) -> Result<Self, SimError> {
        Self::from_scene_with(scene, RapierOptions::default())
    }

    /// Like [`RapierPlant::from_scene`], with extra physics options.
    pub fn from_scene_with(scene: &Scene, options: RapierOptions) -> Result<Self, SimError> {
        let spec = scene.spec();
        let robot = Robot::from_urdf_file(&scene.urdf_path(), spec.robot.tool.as_deref())?;
        Self::new(robot, scene, options)
    }

    /// Builds the simulation of a scene with an already loaded robot (the scene's `[robot] urdf`
    /// is not read again).
    pub fn new(robot: Robot, scene: &Scene, options: RapierOptions) -> Result<Self, SimError> {
        let spec = scene.spec();
        let n = robot.dof();
        let q0 = spec.robot.q0.clone().unwrap_or_else(|| vec![0.0; n]);
        if q0.len() != n {
            return Err(SceneError::Invalid {
                file: scene.file().to_owned(),
                key: "robot.q0".into(),
                value: format!("{q0:?}"),
                reason: format!("robot `{}` has {n} joints", robot.name()),
            }
            .into());
        }
        for (idx, (q, joint)) in q0.iter().zip(robot.joints()).enumerate() {
            if *q < joint.lower || *q > joint.upper {
                return Err(SceneError::Invalid {
                    file: scene.file().to_owned(),
                    key: format!("robot.q0.{idx}"),
                    value: q.to_string(),
                    reason: format!("outside the limits of joint `{}`", joint.name),
                }
                .into());
            }
        }
        if robot.joints().iter().any(|joint| joint.kind != JointKind::Revolute) {
            return Err(SimError::Unsupported {
                robot: robot.name().to_owned(),
                reason: "the simulated arm must have revolute joints only".into(),
            });
        }
        let sensor_link = robot.require_link(&spec.robot.sensor)?;
        let Some(sensor_body) = robot.links()[sensor_link].body else {
            return Err(SimError::Unsupported {
                robot: robot.name().to_owned(),
                reason: format!("sensor link `{}` does not move with the arm", spec.robot.sensor),
            });
        };
        let mut plant = RapierPlant {
            pipeline: PhysicsPipeline::new(),
            params: IntegrationParameters {
                dt: spec.sim.dt as Real,
                // One solver iteration reproduces the exact multibody dynamics (more substeps change
                // the accelerations); clustering would merge manifolds the sensor reads.
                num_solver_iterations: 1,
                contact_clustering: false,
                // rapier's contacts are soft springs of stiffness m ω², m the contact's effective mass. The
                // only contacts between two moving bodies are tool-button cap, where m is the 20 g cap's:
                // at the default 30 Hz that is 710 N/m, and a 10 N press sank the tool 14 mm into the cap.
                // At 1 kHz (7.9e5 N/m for a 20 g cap) the spring's 5 N leave 7 µm.
                contact_softness: SpringCoefficients::new(CAP_CONTACT_HZ, 10.0),
                // No warm start. With one solver iteration, a sliding contact's warm-started friction impulse
                // (at the Coulomb limit) pushed the probe off the drum through the arm's coupled normal and
                // tangential effective mass: the normal row then solved to zero, the friction bound fell to
                // zero, the step ended approaching, and the next one stopped it with twice the force. The
                // contact force alternated 0 / 25 N every step even with the joint torques frozen (the
                // sensor read 6.5 / 15 N), contour force_rms 23/24/22 %. A single point per manifold needs
                // no warm start to be solved exactly; without it contour 6/11/8 %, press 5 -> 2 %.
                warmstart_coefficient: 0.0,
                ..IntegrationParameters::default()
            },
            islands: IslandManager::new(),
            broad_phase: DefaultBroadPhase::new(),
            narrow_phase: NarrowPhase::new(),
            bodies: RigidBodySet::new(),
            colliders: ColliderSet::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            soft_bodies: SoftBodySet::new(),
            ccd: CCDSolver::new(),
            gravity: Vector::new(
                spec.sim.gravity[0] as Real,
                spec.sim.gravity[1] as Real,
                spec.sim.gravity[2] as Real,
            ),
            root: RigidBodyHandle::invalid(),
            links: Vec::with_capacity(n),
            joints: Vec::with_capacity(n),
            tool_colliders: Vec::new(),
            sensor_body,
            sensor_in_body: robot.links()[sensor_link].link_in_body,
            buttons: Vec::new(),
            torque: vec![0.0; n],
            sensor: WristSensor::new(spec.sensor),
            ideal_wrench_base: Vector6::zeros(),
            wrench_sensor: Vector6::zeros(),
            wrench_base: Vector6::zeros(),
            t: 0.0,
            dt: spec.sim.dt,
            robot,
        };
        plant.build_arm(&q0, sensor_link, options);
        plant.build_objects(scene);
        Ok(plant)
    }

    fn build_arm(&mut self, q0: &[f64], sensor_link: usize, options: RapierOptions) {
        let robot = &self.robot;
        let mut data = robot.data();
        robot.forward_kinematics(&mut data, &vec![0.0; robot.dof()]);
        self.root = self.bodies.insert(RigidBodyBuilder::fixed().can_sleep(false));
        let mut parent = self.root;
        for (idx, body) in robot.bodies.iter().enumerate() {
            let rb = RigidBodyBuilder::dynamic()
                .pose(pose_of(&IsometryMatrix3::from_parts(
                    nalgebra::Translation3::from(data.pos[idx]),
                    nalgebra::Rotation3::from_matrix_unchecked(data.rot[idx]),
                )))
                .additional_mass_properties(mass_properties(body.mass, &body.com, &body.inertia))
                .can_sleep(false);
            let handle = self.bodies.insert(rb);
            let align = Rotation::from_rotation_arc(Vector::X, vec3(&body.axis).normalize());
            let frame0 = Pose::from_parts(vec3(&body.pos0), quat(&body.rot0) * align);
            let info = &robot.joints()[idx];
            let mut joint = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
                .local_frame1(frame0)
                .local_frame2(Pose::from_rotation(align))
                .contacts_enabled(false);
            if info.lower.is_finite() && info.upper.is_finite() {
                joint = joint.limits(JointAxis::AngX, [info.lower as Real, info.upper as Real]);
            }
            let joint_handle = self
                .multibody_joints
                .insert(parent, handle, joint.build(), true)
                .expect("a chain of fresh bodies forms a valid multibody");
            self.links.push(handle);
            self.joints.push(joint_handle);
            parent = handle;
        }
        // Tool colliders: every link from the sensor link on, massless (the mass is in the body).
        for link in &robot.links()[sensor_link..] {
            let Some(body) = link.body else { continue };
            for collision in &link.collisions {
                let shape_in_body = pose_of(&link.link_in_body) * pose_of_quat(&collision.shape_in_link);
                let (builder, shape_pose) = match collision.shape {
                    Shape::Sphere { radius } => (ColliderBuilder::ball(radius as Real), shape_in_body),
                    Shape::Cuboid { size } => (
                        ColliderBuilder::cuboid(size.x as Real / 2.0, size.y as Real / 2.0, size.z as Real / 2.0),
                        shape_in_body,
                    ),
                    Shape::Cylinder { radius, length } => (
                        ColliderBuilder::cylinder(length as Real / 2.0, radius as Real),
                        shape_in_body * z_to_y(),
                    ),
                    Shape::Capsule { radius, length } => (
                        ColliderBuilder::capsule_z(length as Real / 2.0, radius as Real),
                        shape_in_body,
                    ),
                };
                let collider = builder
                    .position(shape_pose)
                    .density(0.0)
                    .friction(1.0e3)
                    .friction_combine_rule(CoefficientCombineRule::Min)
                    .restitution(0.0)
                    .collision_groups(InteractionGroups::new(
                        TOOL_GROUP,
                        SCENE_GROUP,
                        InteractionTestMode::And,
                    ));
                let handle = self
                    .colliders
                    .insert_with_parent(collider, self.links[body], &mut self.bodies);
                self.tool_colliders.push(handle);
            }
        }
        if let Some((multibody, _)) = self.multibody_joints.get_mut(self.joints[0]) {
            // Pitfall: a fresh multibody reports a free root until its kinematics run once.
            multibody.forward_kinematics(&self.bodies, true);
            multibody.damping_mut().fill(options.joint_damping as Real);
            let disp: Vec<Real> = q0.iter().map(|q| *q as Real).collect();
            multibody.apply_displacements(&disp);
            multibody.forward_kinematics(&self.bodies, true);
            multibody.update_rigid_bodies(&mut self.bodies, true);
        }
    }

    fn build_objects(&mut self, scene: &Scene) {
        let groups = InteractionGroups::new(SCENE_GROUP, TOOL_GROUP, InteractionTestMode::And);
        for (name, object) in &scene.spec().objects {
            let pose = rpy_pose(object.xyz, object.rpy);
            let friction = object.friction as Real;
            let material = |builder: ColliderBuilder| {
                builder
                    .friction(friction)
                    .friction_combine_rule(CoefficientCombineRule::Min)
                    .restitution(0.0)
                    .collision_groups(groups)
            };
            match object.kind {
                ObjectKind::Box => {
                    let size = object.size.unwrap_or([0.1; 3]);
                    let body = self.bodies.insert(RigidBodyBuilder::fixed().pose(pose));
                    let collider = material(ColliderBuilder::cuboid(
                        size[0] as Real / 2.0,
                        size[1] as Real / 2.0,
                        size[2] as Real / 2.0,
                    ));
                    self.colliders.insert_with_parent(collider, body, &mut self.bodies);
                }
                ObjectKind::Cylinder => {
                    let body = self.bodies.insert(RigidBodyBuilder::fixed().pose(pose));
                    let collider = material(
                        ColliderBuilder::cylinder(
                            object.length.unwrap_or(0.1) as Real / 2.0,
                            object.radius.unwrap_or(0.1) as Real,
                        )
                        .position(z_to_y())
                        // rapier 0.36 recycles a pair's contacts while the relative pose drifts less than
                        // 5 cm (`contact_recycling`): normal and gap stay frozen. Exact on flat faces, but a
                        // probe sliding over the drum rode the frozen tangent plane up to 5 mm off the
                        // surface, still pushed, then dropped back and re-impacted (150-440 N). Pairs with
                        // an active hook are never recycled; the hooks are `()`, which change nothing.
                        .active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
                    );
                    self.colliders.insert_with_parent(collider, body, &mut self.bodies);
                }
                ObjectKind::Button => {
                    let radius = object.radius.unwrap_or(0.02) as Real;
                    let height = object.height.unwrap_or(0.02) as Real;
                    let mass = object.mass.unwrap_or(0.02) as Real;
                    let travel = object.travel.unwrap_or(0.01) as Real;
                    let housing = self.bodies.insert(RigidBodyBuilder::fixed().pose(pose));
                    let cap = self.bodies.insert(
                        RigidBodyBuilder::dynamic()
                            .pose(pose)
                            .additional_mass_properties(MassProperties::new(
                                Vector::ZERO,
                                mass,
                                Vector::splat(mass * radius * radius / 2.0),
                            ))
                            .can_sleep(false),
                    );
                    let collider = material(
                        ColliderBuilder::cylinder(height / 2.0, radius)
                            .position(z_to_y())
                            .density(0.0),
                    );
                    self.colliders.insert_with_parent(collider, cap, &mut self.bodies);
                    // The lower stop is a fixed disc of the cap's radius whose top is where the cap's top is
                    // when fully pressed, hidden inside the cap at every depth (for travel < 3/4 height). The
                    // tool presses the cap down onto it and then rests on it as on a table. A joint limit
                    // alone does not hold: with one solver iteration the light cap, squeezed between the
                    // tool's warm-started contact and its (not warm-started) multibody limit, chattered, and
                    // the sensor read 5 to 90 N under a steady 10 to 40 N press.
                    let thickness = (height - travel).max(height / 4.0);
                    let stop = material(ColliderBuilder::cylinder(thickness / 2.0, radius).position(
                        Pose::from_translation(Vector::new(0.0, 0.0, height / 2.0 - travel - thickness / 2.0))
                            * z_to_y(),
                    ));
                    self.colliders.insert_with_parent(stop, housing, &mut self.bodies);
                    let align = Rotation::from_rotation_arc(Vector::X, Vector::Z);
                    let joint = GenericJointBuilder::new(JointAxesMask::LOCKED_PRISMATIC_AXES)
                        .local_frame1(Pose::from_rotation(align))
                        .local_frame2(Pose::from_rotation(align))
                        .limits(JointAxis::LinX, [-travel - BUTTON_LIMIT_MARGIN, 0.0])
                        .contacts_enabled(false)
                        .build();
                    let handle = self
                        .multibody_joints
                        .insert(housing, cap, joint, true)
                        .expect("a fresh body pair forms a valid multibody");
                    if let Some((multibody, _)) = self.multibody_joints.get_mut(handle) {
                        multibody.forward_kinematics(&self.bodies, true);
                        multibody.damping_mut().fill(0.0);
                    }
                    self.buttons.push(Button {
                        name: name.clone(),
                        joint: handle,
                        cap,
                        stiffness: object.stiffness.unwrap_or(500.0),
                        preload: object.preload_n.unwrap_or(0.0),
                        damping: object.damping.unwrap_or(0.0),
                    });
                }
            }
        }
    }

    /// The robot model the plant simulates.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The scene's step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The sensor settings.
    pub fn sensor_config(&self) -> &SensorConfig {
        self.sensor.config()
    }

    /// The torques actually applied at the last step (after saturation), N m.
    pub fn applied_torques(&self) -> &[f64] {
        &self.torque
    }

    /// The noise-free contact wrench on the tool about the sensor origin, base axes, as last simulated.
    pub fn ideal_wrench_base(&self) -> Vector6<f64> {
        self.ideal_wrench_base
    }

    /// How far button `name` is pressed in, m (0 at rest, its travel at the stop); `None` if no such button.
    pub fn button_depth(&self, name: &str) -> Option<f64> {
        let button = self.buttons.iter().find(|button| button.name == name)?;
        let (multibody, link_id) = self.multibody_joints.get(button.joint)?;
        let link = multibody.link(link_id)?;
        Some(-f64::from(link.joint.coords()[0]))
    }

    /// The pose of a simulated arm link (index into [`Robot::links`]) in the world frame.
    pub fn link_pose(&self, link: usize) -> Option<Isometry3<f64>> {
        let info = self.robot.links().get(link)?;
        let body_pose = match info.body {
            None => IsometryMatrix3::identity(),
            Some(body) => iso_of(self.bodies.get(self.links[body])?.position()),
        };
        let pose = body_pose * info.link_in_body;
        Some(Isometry3::from_parts(
            pose.translation,
            UnitQuaternion::from_rotation_matrix(&pose.rotation),
        ))
    }

    fn apply_joint_torques(&mut self) {
        for handle in &self.links {
            if let Some(rb) = self.bodies.get_mut(*handle) {
                rb.reset_torques(false);
                rb.reset_forces(false);
            }
        }
        for (idx, body) in self.robot.bodies.iter().enumerate() {
            let Some(rb) = self.bodies.get(self.links[idx]) else {
                continue;
            };
            let axis_world = rb.position().rotation * vec3(&body.axis);
            let moment = axis_world * self.torque[idx] as Real;
            if let Some(rb) = self.bodies.get_mut(self.links[idx]) {
                rb.add_torque(moment, true);
            }
            if idx > 0 {
                if let Some(parent) = self.bodies.get_mut(self.links[idx - 1]) {
                    parent.add_torque(-moment, true);
                }
            }
        }
        for button in &self.buttons {
            let Some((multibody, link_id)) = self.multibody_joints.get(button.joint) else {
                continue;
            };
            let Some(link) = multibody.link(link_id) else { continue };
            let depth = -f64::from(link.joint.coords()[0]);
            let speed = multibody
                .joint_velocity(link)
                .iter()
                .next()
                .map_or(0.0, |v| f64::from(*v));
            let push = button.preload + button.stiffness * depth - button.damping * speed;
            if let Some(cap) = self.bodies.get_mut(button.cap) {
                let axis = cap.position().rotation * Vector::Z;
                cap.reset_forces(false);
                cap.add_force(axis * push as Real, true);
            }
        }
    }

    /// Sums the contact wrenches on the tool colliders about the sensor origin (base axes).
    fn contact_wrench(&self) -> Vector6<f64> {
        let sensor_origin = self
            .bodies
            .get(self.links[self.sensor_body])
            .map(|rb| (iso_of(rb.position()) * self.sensor_in_body).translation.vector)
            .unwrap_or_else(Vector3::zeros);
        let inv_dt = 1.0 / f64::from(self.params.dt);
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for tool in &self.tool_colliders {
            for pair in self.narrow_phase.contact_pairs_with(*tool) {
                let PairContacts::Rigid(rigid) = &pair.contacts else {
                    continue;
                };
                let tool_is_first = pair.collider1 == *tool;
                let Some(tool_collider) = self.colliders.get(*tool) else {
                    continue;
                };
                let tool_pose = tool_collider.position();
                for manifold in rigid.solver_manifolds() {
                    let normal = from_vec3(manifold.data.normal);
                    for point in &manifold.points {
                        // rapier's impulses act on the first collider along the normal that points
                        // from the first to the second: the push on the first is −n λ.
                        let on_first = -(normal * f64::from(point.data.impulse)
                            + from_vec3(point.data.warmstart_tangent_world))
                            * inv_dt;
                        let (on_tool, local) = if tool_is_first {
                            (on_first, point.local_p1)
                        } else {
                            (-on_first, point.local_p2)
                        };
                        let at = from_vec3(tool_pose.transform_point(local));
                        force += on_tool;
                        moment += (at - sensor_origin).cross(&on_tool);
                    }
                }
            }
        }
        Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
    }

    fn sensor_rotation(&self) -> nalgebra::Rotation3<f64> {
        self.bodies
            .get(self.links[self.sensor_body])
            .map(|rb| (iso_of(rb.position()) * self.sensor_in_body).rotation)
            .unwrap_or_else(nalgebra::Rotation3::identity)
    }
}

impl Plant for RapierPlant {
    fn dof(&self) -> usize {
        self.robot.dof()
    }

    fn time(&self) -> f64 {
        self.t
    }

    fn observe_into(&self, out: &mut Observation) {
        out.t = self.t;
        if let Some((multibody, _)) = self.multibody_joints.get(self.joints[0]) {
            for (idx, handle) in self.joints.iter().enumerate() {
                let Some((_, link_id)) = self.multibody_joints.get(*handle) else {
                    continue;
                };
                let Some(link) = multibody.link(link_id) else { continue };
                out.q[idx] = f64::from(link.joint.coords()[3]);
                out.qd[idx] = multibody
                    .joint_velocity(link)
                    .iter()
                    .next()
                    .map_or(0.0, |v| f64::from(*v));
            }
        }
        out.wrench_sensor = self.wrench_sensor;
        out.wrench_base = self.wrench_base;
    }

    fn apply(&mut self, torques: &[f64]) -> Result<(), PlantError> {
        saturate(&self.robot, torques, &mut self.torque)
    }

    fn step(&mut self, dt: f64) -> Result<(), PlantError> {
        self.params.dt = dt as Real;
        self.apply_joint_torques();
        self.pipeline.step(
            self.gravity,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
        self.t += dt;
        let ideal = self.contact_wrench();
        self.ideal_wrench_base = ideal;
        let rot_t = self.sensor_rotation().inverse();
        let force = rot_t * Vector3::new(ideal[0], ideal[1], ideal[2]);
        let moment = rot_t * Vector3::new(ideal[3], ideal[4], ideal[5]);
        let ideal_sensor = Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z);
        self.wrench_sensor = self.sensor.measure(&ideal_sensor, dt);
        let rot = rot_t.inverse();
        let f_base = rot * Vector3::new(self.wrench_sensor[0], self.wrench_sensor[1], self.wrench_sensor[2]);
        let m_base = rot * Vector3::new(self.wrench_sensor[3], self.wrench_sensor[4], self.wrench_sensor[5]);
        self.wrench_base = Vector6::new(f_base.x, f_base.y, f_base.z, m_base.x, m_base.y, m_base.z);
        let mut state = Observation::zeros(self.dof());
        self.observe_into(&mut state);
        if let Some(idx) = (0..self.dof()).find(|idx| !state.q[*idx].is_finite() || !state.qd[*idx].is_finite()) {
            return Err(PlantError::NonFinite {
                t: self.t,
                joint: self.robot.joints()[idx].name.clone(),
            });
        }
        Ok(())
    }
}

impl std::fmt::Debug for RapierPlant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RapierPlant")
            .field("robot", &self.robot.name())
            .field("t", &self.t)
            .field("buttons", &self.buttons.len())
            .finish_non_exhaustive()
    }
}

/// Observed joint positions as an owned vector (for tests and tools).
pub fn joint_positions(plant: &impl Plant) -> DVector<f64> {
    plant.observe().q
}

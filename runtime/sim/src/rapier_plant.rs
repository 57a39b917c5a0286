//! The rapier plant: the robot as a rapier multibody with exact joint torques, the scene's objects
//! and the wrist sensor, stepped as a [`Plant`]. Building the world is in `build`, reading contacts
//! in `contact`, and every conversion to and from rapier's (glam) types in `convert`.
// `Real` is f32 or f64 depending on the rapier flavour: casts and conversions to it are identities in one.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use nalgebra::{DVector, Isometry3, IsometryMatrix3, UnitQuaternion, Vector6};
use rapier3d::math::{Real, Vector};
use rapier3d::prelude::{
    CCDSolver, ColliderHandle, ColliderSet, DefaultBroadPhase, ImpulseJointSet, IntegrationParameters, IslandManager,
    JointAxesMask, JointAxis, MultibodyJointHandle, MultibodyJointSet, NarrowPhase, PhysicsPipeline, RigidBodyHandle,
    RigidBodySet, SoftBodySet, SpringCoefficients,
};

use super::build::Button;
use super::convert::{iso_of, vec3};
use super::free_flight::{FreeFlight, World};
use super::stiffness::ContactTuner;
use super::witness::{StepState, Witness};
use super::{Scene, SceneError, SensorConfig, WristSensor};
use crate::plant::{saturate, ContactAudit, Observation, Plant, PlantError};
use crate::robot::{JointKind, Robot, RobotError};

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
    /// The tool starts inside an object: no real run starts that way.
    #[error("scene `{file}`: the tool starts {depth_mm:.1} mm inside object `{object}`; move the object or start the robot elsewhere (`robot.q0` or `robot.tool_start`)")]
    StartsInside {
        /// The scene file.
        file: String,
        /// The object.
        object: String,
        /// How deep \[mm\].
        depth_mm: f64,
    },
    /// A link of the arm starts inside an object.
    #[error("scene `{file}`: arm link `{link}` starts {depth_mm:.1} mm inside object `{object}`; move the object or start the robot elsewhere (`robot.q0` or `robot.tool_start`)")]
    ArmStartsInside {
        /// The scene file.
        file: String,
        /// The arm link.
        link: String,
        /// The object.
        object: String,
        /// How deep \[mm\].
        depth_mm: f64,
    },
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

/// How a plant's steps were taken: [`RapierPlant::step_counts`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepCounts {
    /// Steps in free flight: integrated from the robot model, rapier's pipeline skipped.
    pub free: u64,
    /// Steps rapier took.
    pub rapier: u64,
}

/// The robot and scene simulated by rapier, 1 ms steps, torque-controlled.
///
/// **Precision.** rapier's scalar is [`Real`](rapier3d::math::Real): `f32` with the crate `rapier3d`
/// used today, `f64` with `rapier3d-f64` (this file compiles unchanged with either; switch with
/// `rapier3d = { package = "rapier3d-f64", version = "0.36.1" }` in the workspace manifest). See
/// [`SIM_F64`](super::SIM_F64). The controller and model stay in f64; conversion happens only at this plant's boundary.
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
/// saturated at the URDF effort limits. Joint position limits are rapier joint limits.
///
/// **Contacts.** Every link with collision geometry collides with the scene's objects (never with
/// another link). The tool's contacts (links from the sensor link on) are the wrist sensor's
/// wrench; the other links' are reported as [`Observation::arm_contact_n`] and its link, which
/// the supervisor treats as a collision. Links fixed to the base get no colliders. An arm link's
/// contact with a fixed object has the same natural frequency as the tool's (rapier's softness is
/// global), so its stiffness `m ω²` scales with the link's effective mass `m`: stiffer near the
/// base, as a real arm's joint elasticity seen at a point nearer the base is. Cost: each arm
/// link is one (compound) collider, since a step updates every moving collider: about 0.9 µs a
/// step in free motion (18.0 vs 17.1 µs, 5 %) and within noise pressing on the table
/// (`benches/robot_sim.rs` has both); one collider per shape cost about 3 µs.
/// Contacts are found anew every step (rapier's contact recycling is off): no force while the
/// tool is more than 1 mm from every object. The same `m ω²` holds for the tool: the scene's
/// stiffness is exact along the base z at the start; along another normal it scales with the
/// arm's effective mass that way (at the table's start, 0.35 kg along x against 3.7 kg along z:
/// a side contact is about ten times softer).
///
/// **Free flight.** A step in which no shape of the arm is within rapier's contact prediction
/// distance (5 mm) plus 1 mm plus the step's largest motion of any point of the arm, and no joint
/// at or beyond a limit, cannot produce a contact or a limit impulse; in a scene in which nothing
/// but the arm moves (no dynamic body besides its links, no other joint: a button rules it out)
/// the plant then integrates the arm itself from the robot model, semi-implicit Euler as rapier,
/// and skips rapier's pipeline (see `free_flight`). rapier's multibody step costs about 5× more.
/// rapier's Coriolis term is semi-implicit, this one explicit: both are first order, and free
/// flight stays as close to the converged motion as rapier's own step (`runtime/tests/free_flight.rs`:
/// 1.8e-3 vs 1.8e-3 rad over 2 s of open-loop torques, 3.1e-4 vs 3.1e-4 rad for the hybrid
/// controller's 3 s circle; free vs rapier 4.3e-4 and 9.7e-5 rad). An impact magnifies any such
/// difference, as it does any rounding-level change (peaks move by a few tenths of a newton).
/// [`RapierPlant::set_free_flight`] switches it off (rapier takes every step);
/// [`RapierPlant::step_counts`] tells how many steps each took.
///
/// **Buttons.** A button's cap is a light dynamic body on a prismatic multibody joint, pushed up by a spring
/// applied every step. Its lower stop is a fixed collider the tool rests on once the cap is fully pressed
/// (a joint limit alone chattered under a press), and tool-cap contacts are stiffened (1 kHz instead of
/// rapier's 30 Hz, which let the tool sink 14 mm into a 20 g cap at 10 N).
pub struct RapierPlant {
    pub(super) robot: Robot,
    pub(super) pipeline: PhysicsPipeline,
    pub(super) params: IntegrationParameters,
    pub(super) islands: IslandManager,
    pub(super) broad_phase: DefaultBroadPhase,
    pub(super) narrow_phase: NarrowPhase,
    pub(super) bodies: RigidBodySet,
    pub(super) colliders: ColliderSet,
    pub(super) impulse_joints: ImpulseJointSet,
    pub(super) multibody_joints: MultibodyJointSet,
    pub(super) soft_bodies: SoftBodySet,
    pub(super) ccd: CCDSolver,
    pub(super) gravity: Vector,
    pub(super) root: RigidBodyHandle,
    pub(super) links: Vec<RigidBodyHandle>,
    pub(super) joints: Vec<MultibodyJointHandle>,
    /// Whether each arm joint has position limits (rapier joint limits on its angle).
    pub(super) limited: Vec<bool>,
    pub(super) tool_colliders: Vec<ColliderHandle>,
    /// The colliders of the arm's other links, with the link (index into [`Robot::links`]).
    pub(super) arm_colliders: Vec<(ColliderHandle, usize)>,
    /// The contact force on each link of [`Robot::links`] at the last step (base axes, N);
    /// only links with [`RapierPlant::arm_colliders`] are ever non-zero.
    pub(super) arm_forces: Vec<nalgebra::Vector3<f64>>,
    /// The largest of [`RapierPlant::arm_forces`] (N) and its link.
    pub(super) arm_contact: (f64, Option<usize>),
    /// Every scene object's colliders, with the object's name.
    pub(super) object_colliders: Vec<(ColliderHandle, String)>,
    pub(super) sensor_body: usize,
    pub(super) sensor_in_body: IsometryMatrix3<f64>,
    pub(super) buttons: Vec<Button>,
    pub(super) torque: Vec<f64>,
    pub(super) sensor: WristSensor,
    pub(super) ideal_wrench_base: Vector6<f64>,
    pub(super) wrench_sensor: Vector6<f64>,
    pub(super) wrench_base: Vector6<f64>,
    pub(super) t: f64,
    pub(super) dt: f64,
    /// The steps in which the arm flies free of every object, integrated without rapier
    /// (`None` until the world is built).
    pub(super) free: Option<FreeFlight>,
    /// Each joint's link id in the arm's multibody.
    pub(super) joint_links: Vec<usize>,
    /// Whether rapier has taken a step (free flight starts only after one: rapier sets masses
    /// and the active set up in its first step).
    pub(super) rapier_stepped: bool,
    /// How many steps rapier took, and how many the plant took in free flight.
    pub(super) steps_rapier: u64,
    pub(super) steps_free: u64,
    /// The contact witness (`None` only while a step checks it).
    pub(super) witness: Option<Witness>,
    /// The normal on the tool of its last step's contacts with fixed objects.
    pub(super) tool_normal: Option<nalgebra::Vector3<f64>>,
    /// Sets the contact frequency from the effective mass along that normal.
    pub(super) tuner: ContactTuner,
    /// Joint positions and velocities, scratch for the tuner.
    pub(super) q_scratch: Vec<f64>,
    pub(super) qd_scratch: Vec<f64>,
}

/// How deep a start may put a collider inside an object \[m\]: rapier's contact slop.
const START_SLOP_M: f64 = 1e-4;

/// The natural frequency (Hz) that gives a contact of `stiffness` N/m at the tool of `robot` at
/// `q`: `√(k / m) / 2π` with `m` the arm's effective mass along the base z,
/// `1 / (J_z M⁻¹ J_zᵀ)`. A singular configuration falls back to 2.5 kg.
fn static_contact_hz(robot: &Robot, q: &[f64], stiffness: f64) -> f64 {
    let m_eff = robot.tool_effective_mass(q, &nalgebra::Vector3::z()).unwrap_or(2.5);
    (stiffness / m_eff).sqrt() / (2.0 * std::f64::consts::PI)
}

/// The natural frequency (Hz) of contacts between two moving bodies (the tool and a button cap)
/// that gives the lightest cap's contact `stiffness` N/m; 1 kHz without buttons.
fn cap_contact_hz(scene: &Scene, stiffness: f64) -> f64 {
    let lightest = scene
        .spec()
        .objects
        .values()
        .filter(|object| object.kind == super::ObjectKind::Button)
        .map(|object| object.mass.unwrap_or(0.02))
        .fold(f64::INFINITY, f64::min);
    if lightest.is_finite() && lightest > 0.0 {
        (stiffness / lightest).sqrt() / (2.0 * std::f64::consts::PI)
    } else {
        1000.0
    }
}

impl RapierPlant {
    /// Builds the simulation of a scene file: loads its URDF (relative to the scene), starts at
    /// [`Scene::start_configuration`] (`robot.q0`, or the joint positions that put the tool at
    /// `robot.tool_start`).
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
        let plant = Self::build(robot, scene, options)?;
        plant.check_start(scene)?;
        Ok(plant)
    }

    /// The plant of a scene, without the start check.
    fn build(robot: Robot, scene: &Scene, options: RapierOptions) -> Result<Self, SimError> {
        let spec = scene.spec();
        let n = robot.dof();
        let q0 = scene.start_configuration(&robot)?;
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
        let witness = Witness::new(&robot, sensor_link, scene);
        let mut plant = RapierPlant {
            pipeline: PhysicsPipeline::new(),
            params: IntegrationParameters {
                dt: spec.sim.dt as Real,
                // One solver iteration reproduces the exact multibody dynamics (more substeps change
                // the accelerations); clustering would merge manifolds the sensor reads.
                num_solver_iterations: 1,
                // rapier follows each soft solve with a rigid "stabilization" pass that removes the
                // contact's softness from the velocity solve: an impact then stops in one step,
                // whatever the scene's stiffness (measured: 50 N at 20 mm/s with 5e4 N/m set).
                num_internal_stabilization_iterations: 0,
                contact_clustering: false,
                // rapier's contacts are soft springs of stiffness m ω², m the contact's effective mass. The
                // only contacts between two moving bodies are tool-button cap, where m is the light cap's:
                // at the default 30 Hz a 20 g cap gives 710 N/m, and a 10 N press sank the tool 14 mm into
                // it. The frequency is set so that the lightest cap's contact has the scene's stiffness,
                // like the contacts with fixed objects (a rigid cap contact made the cap's arrival on its
                // stop a 50 N impact at 25 mm/s).
                contact_softness: SpringCoefficients::new(
                    cap_contact_hz(scene, spec.sim.contact_stiffness) as Real,
                    spec.sim.contact_damping_ratio as Real,
                ),
                // Contacts with fixed objects: rapier's spring is m ω² for the contact's effective
                // mass m; the scene gives a stiffness, turned into ω with the arm's effective mass
                // at the tool along the base z at the start configuration (the approach direction
                // of most skills; it varies by tens of percent over the workspace).
                static_contact_softness: SpringCoefficients::new(
                    static_contact_hz(&robot, &q0, spec.sim.contact_stiffness) as Real,
                    spec.sim.contact_damping_ratio as Real,
                ),
                // No warm start. With one solver iteration, a sliding contact's warm-started friction impulse
                // (at the Coulomb limit) pushed the probe off the drum through the arm's coupled normal and
                // tangential effective mass: the normal row then solved to zero, the friction bound fell to
                // zero, the step ended approaching, and the next one stopped it with twice the force. The
                // contact force alternated 0 / 25 N every step even with the joint torques frozen (the
                // sensor read 6.5 / 15 N), contour force_rms 23/24/22 %. A single point per manifold needs
                // no warm start to be solved exactly; without it contour 6/11/8 %, press 5 -> 2 %.
                warmstart_coefficient: 0.0,
                // rapier builds a contact constraint (with an LU solve against the arm's mass matrix)
                // for every point within this distance of touching; 2 cm by default. A point farther
                // than a step's motion (under 1 mm at 1 kHz for anything the supervisor lets move)
                // gets zero impulse, so 5 mm changes no free motion, and lets the arm fly free of
                // rapier (`free_flight`) down to 6 mm from an object instead of 2.1 cm.
                normalized_prediction_distance: 0.005,
                // rapier 0.36 keeps a pair's contact points (normal, gap, the feature they lie on)
                // while the pair's relative pose drifts less than 5 cm from where they were found
                // (`contact_recycling`, on by default). A probe sliding on a box then rode the top
                // face's plane past the edge: 10 N at unchanged height with the tip 10-15 mm past
                // a table's end, a step 1 mm down met as a wall (12 N, 6.3 mm climb), a frozen
                // side-face contact 5 mm clear met at 394 N, a button cap's side 1.4 mm early;
                // on a drum, a frozen tangent plane. Every pair's contacts are found anew every
                // step: the contact is where the geometry is (`runtime/tests/contact_geometry.rs`
                // checks every tick of edges, steps, slots, seams, tilted boxes, drums and a
                // button against the analytic distance).
                contact_recycling: false,
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
            limited: robot
                .joints()
                .iter()
                .map(|joint| joint.lower.is_finite() && joint.upper.is_finite())
                .collect(),
            tool_colliders: Vec::new(),
            arm_colliders: Vec::new(),
            arm_forces: vec![nalgebra::Vector3::zeros(); robot.links().len()],
            arm_contact: (0.0, None),
            object_colliders: Vec::new(),
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
            free: None,
            joint_links: Vec::with_capacity(n),
            rapier_stepped: false,
            steps_rapier: 0,
            steps_free: 0,
            witness: Some(witness),
            tool_normal: None,
            tuner: ContactTuner::new(&robot, spec.sim.contact_stiffness),
            q_scratch: vec![0.0; n],
            qd_scratch: vec![0.0; n],
            robot,
        };
        plant.build_arm(&q0, sensor_link, options);
        plant.build_objects(scene);
        plant.joint_links = plant
            .joints
            .iter()
            .map(|handle| plant.multibody_joints.get(*handle).map_or(0, |(_, link_id)| link_id))
            .collect();
        let arm: Vec<ColliderHandle> = plant
            .tool_colliders
            .iter()
            .copied()
            .chain(plant.arm_colliders.iter().map(|(handle, _)| *handle))
            .collect();
        let objects: Vec<ColliderHandle> = plant.object_colliders.iter().map(|(handle, _)| *handle).collect();
        let world = World {
            bodies: &plant.bodies,
            colliders: &plant.colliders,
            links: &plant.links,
            arm: &arm,
            objects: &objects,
        };
        // Any body rapier moves besides the arm's links (a button's cap today, whatever an
        // object kind adds tomorrow), or any joint outside the arm's multibody, must be stepped by
        // rapier every step: free flight then never applies.
        let moving_objects = plant
            .bodies
            .iter()
            .any(|(handle, body)| !body.is_fixed() && !plant.links.contains(&handle))
            || plant.impulse_joints.iter().next().is_some()
            || plant.multibody_joints.multibodies().count() > 1;
        plant.free = Some(FreeFlight::new(
            plant.robot.clone(),
            nalgebra::Vector3::from(spec.sim.gravity),
            options.joint_damping,
            f64::from(plant.params.prediction_distance()),
            &world,
            moving_objects,
        ));
        Ok(plant)
    }

    /// Refuses a start with the tool or another link of the arm inside an object (deeper than
    /// 0.1 mm, rapier's contact slop).
    fn check_start(&self, scene: &Scene) -> Result<(), SimError> {
        if let Some((distance, object)) = self.start_clearance() {
            if distance < -START_SLOP_M {
                return Err(SimError::StartsInside {
                    file: scene.file().to_owned(),
                    object,
                    depth_mm: -distance * 1e3,
                });
            }
        }
        if let Some((distance, link, object)) = self.arm_start_clearance() {
            if distance < -START_SLOP_M {
                return Err(SimError::ArmStartsInside {
                    file: scene.file().to_owned(),
                    link,
                    object,
                    depth_mm: -distance * 1e3,
                });
            }
        }
        Ok(())
    }

    /// The smallest distance between the tool's colliders and any object as the plant was built
    /// (negative: how deep the tool starts inside), and that object's name; `None` when the
    /// scene has no objects or the tool no collider. Distances beyond 1 m read as 1 m.
    pub fn start_clearance(&self) -> Option<(f64, String)> {
        self.clearance_lifted(0.0)
    }

    /// [`RapierPlant::start_clearance`] with the tool moved `lift_m` up along the base z.
    fn clearance_lifted(&self, lift_m: f64) -> Option<(f64, String)> {
        let lift = rapier3d::math::Pose::from_parts(
            Vector::new(0.0, 0.0, lift_m as Real),
            rapier3d::math::Rotation::IDENTITY,
        );
        let mut closest: Option<(f64, String)> = None;
        for tool in &self.tool_colliders {
            if let Some((distance, name)) = self.closest_object(*tool, lift) {
                if closest.as_ref().is_none_or(|(d, _)| distance < *d) {
                    closest = Some((distance, name));
                }
            }
        }
        closest
    }

    /// The smallest distance between the colliders of the arm's other links (not the tool) and
    /// any object as the plant was built (negative: how deep a link starts inside), that link's
    /// name and the object's; `None` when the scene has no objects. Distances beyond 1 m read as
    /// 1 m.
    pub fn arm_start_clearance(&self) -> Option<(f64, String, String)> {
        let mut closest: Option<(f64, String, String)> = None;
        for (collider, link) in &self.arm_colliders {
            if let Some((distance, object)) = self.closest_object(*collider, rapier3d::math::Pose::IDENTITY) {
                if closest.as_ref().is_none_or(|(d, _, _)| distance < *d) {
                    closest = Some((distance, self.robot.links()[*link].name.clone(), object));
                }
            }
        }
        closest
    }

    /// The distance from `collider`, moved by `moved` in the world, to the nearest object, and
    /// that object's name (1 m for anything beyond 1 m).
    fn closest_object(&self, collider: ColliderHandle, moved: rapier3d::math::Pose) -> Option<(f64, String)> {
        let collider = self.colliders.get(collider)?;
        // Colliders follow their bodies only when the pipeline steps: place them from their
        // bodies, which the multibody's kinematics put at q0 (and objects on bodies of their own,
        // a button's cap, from theirs).
        let pose_of = |collider: &rapier3d::prelude::Collider| match (
            collider.parent().and_then(|h| self.bodies.get(h)),
            collider.position_wrt_parent(),
        ) {
            (Some(body), Some(relative)) => *body.position() * *relative,
            _ => *collider.position(),
        };
        let pose = moved * pose_of(collider);
        let mut closest: Option<(f64, String)> = None;
        for (handle, name) in &self.object_colliders {
            let Some(object) = self.colliders.get(*handle) else {
                continue;
            };
            let contact =
                rapier3d::parry::query::contact(&pose, collider.shape(), &pose_of(object), object.shape(), 1.0);
            let distance = match contact {
                Ok(Some(contact)) => f64::from(contact.dist),
                _ => 1.0,
            };
            if closest.as_ref().is_none_or(|(d, _)| distance < *d) {
                closest = Some((distance, name.clone()));
            }
        }
        closest
    }

    /// The start clearance of a scene ([`RapierPlant::start_clearance`]), measured without
    /// refusing a start inside an object.
    pub fn scene_start_clearance(robot: Robot, scene: &Scene) -> Result<Option<(f64, String)>, SimError> {
        let plant = Self::build(robot, scene, RapierOptions::default())?;
        Ok(plant.start_clearance())
    }

    /// How far the tool must move up along the base z from its start for every object to be at
    /// least `clearance_m` away (0 when it already is), to within 0.5 mm above; `None` when no
    /// lift up to `max_lift_m` clears it. The tool moves alone (the arm is not moved): the
    /// caller finds joint positions for the lifted pose and checks again.
    pub fn scene_lift_to_clear(
        robot: Robot,
        scene: &Scene,
        clearance_m: f64,
        max_lift_m: f64,
    ) -> Result<Option<f64>, SimError> {
        let plant = Self::build(robot, scene, RapierOptions::default())?;
        let clear = |lift: f64| plant.clearance_lifted(lift).is_none_or(|(d, _)| d >= clearance_m);
        if clear(0.0) {
            return Ok(Some(0.0));
        }
        // Scan up in 1 cm steps (objects can be thinner than a penetration depth says), then
        // bisect between the last blocked and the first clear height.
        let mut blocked = 0.0;
        let mut free = None;
        let mut lift = 0.01;
        while lift <= max_lift_m + 1e-12 {
            if clear(lift) {
                free = Some(lift);
                break;
            }
            blocked = lift;
            lift += 0.01;
        }
        let Some(mut free) = free else { return Ok(None) };
        while free - blocked > 5e-4 {
            let mid = 0.5 * (free + blocked);
            if clear(mid) {
                free = mid;
            } else {
                blocked = mid;
            }
        }
        Ok(Some(free))
    }

    /// Allows (`true`, the default) or forbids free flight: with `false` rapier takes every step,
    /// as it did before free flight existed, to check free flight against rapier or to time
    /// rapier alone. Free flight applies only where the scene allows it (no moving objects) and
    /// no shape of the arm can touch an object in the step, whatever this says.
    pub fn set_free_flight(&mut self, allowed: bool) {
        if let Some(free) = self.free.as_mut() {
            free.set_enabled(allowed);
        }
    }

    /// How many steps the plant took in free flight (the arm integrated from the robot model,
    /// rapier's pipeline skipped) and how many rapier took, since it was built.
    pub fn step_counts(&self) -> StepCounts {
        StepCounts {
            free: self.steps_free,
            rapier: self.steps_rapier,
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
        self.depth_of(self.buttons.iter().find(|button| button.name == name)?)
    }

    /// How far `button`'s cap is pressed in, m.
    fn depth_of(&self, button: &Button) -> Option<f64> {
        let (multibody, link_id) = self.multibody_joints.get(button.joint)?;
        let link = multibody.link(link_id)?;
        Some(-f64::from(link.joint.coords()[0]))
    }

    /// The pose of a simulated arm link (index into [`Robot::links`]) in the world frame.
    pub fn link_pose(&self, link: usize) -> Option<Isometry3<f64>> {
        let info = self.robot.links().get(link)?;
        let body_pose = match info.body {
            None => IsometryMatrix3::identity(),
            Some(body) => match self.free.as_ref().filter(|free| free.active) {
                Some(free) => free.body_pose(body),
                None => iso_of(self.bodies.get(self.links[body])?.position()),
            },
        };
        let pose = body_pose * info.link_in_body;
        Some(Isometry3::from_parts(
            pose.translation,
            UnitQuaternion::from_rotation_matrix(&pose.rotation),
        ))
    }

    /// Gives the coming step's contacts with fixed objects the scene's stiffness along the last
    /// contact normal ([`ContactTuner`]); without a contact the frequency stays as it was.
    fn tune_contact_stiffness(&mut self) {
        let Some(normal) = self.tool_normal else { return };
        let (mut q, mut qd) = (
            std::mem::take(&mut self.q_scratch),
            std::mem::take(&mut self.qd_scratch),
        );
        self.read_joint_state(&mut q, &mut qd);
        if let Some(hz) = self.tuner.frequency_hz(&self.robot, &q, &normal) {
            self.params.static_contact_softness.natural_frequency = hz as Real;
        }
        (self.q_scratch, self.qd_scratch) = (q, qd);
    }

    /// Checks the step just taken against the scene's geometry ([`Witness`]).
    fn witness_check(&mut self) {
        let Some(mut witness) = self.witness.take() else { return };
        let link_pose = |link: usize| self.link_pose(link);
        let depth = |name: &str| self.button_depth(name).unwrap_or(0.0);
        let tool = self
            .link_pose(self.robot.tool_link())
            .map_or_else(nalgebra::Vector3::zeros, |pose| pose.translation.vector);
        witness.check(&StepState {
            t_s: self.t,
            force: self.ideal_wrench_base.fixed_rows::<3>(0).into_owned(),
            link_pose: &link_pose,
            depth: &depth,
            tool,
        });
        self.witness = Some(witness);
    }

    /// The first joint whose position or velocity is not finite (what [`Plant::observe_into`]
    /// would report), without allocating an observation.
    fn first_non_finite_joint(&self) -> Option<usize> {
        let (multibody, _) = self.multibody_joints.get(self.joints[0])?;
        self.joints.iter().position(|handle| {
            let Some((_, link_id)) = self.multibody_joints.get(*handle) else {
                return false;
            };
            let Some(link) = multibody.link(link_id) else {
                return false;
            };
            let q = f64::from(link.joint.coords()[3]);
            let qd = multibody
                .joint_velocity(link)
                .iter()
                .next()
                .map_or(0.0, |v| f64::from(*v));
            !q.is_finite() || !qd.is_finite()
        })
    }

    /// Reads the arm's joint positions (rad) and velocities (rad/s) from rapier's multibody.
    fn read_joint_state(&self, q: &mut [f64], qd: &mut [f64]) {
        let Some((multibody, _)) = self.multibody_joints.get(self.joints[0]) else {
            return;
        };
        for (idx, link_id) in self.joint_links.iter().enumerate() {
            let Some(link) = multibody.link(*link_id) else { continue };
            q[idx] = f64::from(link.joint.coords()[3]);
            qd[idx] = multibody
                .joint_velocity(link)
                .iter()
                .next()
                .map_or(0.0, |v| f64::from(*v));
        }
    }

    /// Takes the step in free flight when nothing can touch anything in it (see
    /// [`super::free_flight`]): integrates the arm without rapier and reads the sensor with no
    /// contact. `false` when rapier must take the step (nothing changed then).
    fn free_step(&mut self, dt: f64) -> bool {
        if !self.rapier_stepped {
            return false;
        }
        let Some(mut free) = self.free.take() else {
            return false;
        };
        if free.allowed() && !free.active {
            self.read_joint_state(&mut free.q, &mut free.qd);
            free.loaded();
        }
        let stepped = free.try_step(&self.torque, dt);
        if stepped {
            let sensor_in_base = nalgebra::Rotation3::from_matrix_unchecked(free.body_rotation(self.sensor_body))
                * self.sensor_in_body.rotation;
            self.arm_forces
                .iter_mut()
                .for_each(|force| *force = nalgebra::Vector3::zeros());
            self.arm_contact = (0.0, None);
            self.read_sensor(Vector6::zeros(), sensor_in_base, dt);
        }
        self.free = Some(free);
        stepped
    }

    /// Ends a free flight: writes the arm's state back into rapier's multibody and places its
    /// bodies (their colliders follow at the next step).
    fn land(&mut self) {
        let Some(free) = self.free.as_mut().filter(|free| free.active) else {
            return;
        };
        free.active = false;
        let Some((multibody, _)) = self.multibody_joints.get_mut(self.joints[0]) else {
            return;
        };
        free.disp.iter_mut().for_each(|d| *d = 0.0);
        for (idx, link_id) in self.joint_links.iter().enumerate() {
            let Some(link) = multibody.link(*link_id) else { continue };
            let dof = link.assembly_id();
            free.disp[dof] = (free.q[idx] - f64::from(link.joint.coords()[3])) as Real;
        }
        multibody.apply_displacements(&free.disp);
        for (idx, link_id) in self.joint_links.iter().enumerate() {
            let Some(dof) = multibody.link(*link_id).map(|link| link.assembly_id()) else {
                continue;
            };
            multibody.generalized_velocity_mut()[dof] = free.qd[idx] as Real;
        }
        multibody.forward_kinematics(&self.bodies, true);
        multibody.update_rigid_bodies(&mut self.bodies, true);
    }

    /// Switches each limited joint's rapier limit on only while the joint stands at or beyond
    /// it. rapier builds a limit constraint for every limited joint every step (an LU solve with
    /// the arm's mass matrix each), but one whose joint lies inside its limits has impulse bounds
    /// [0, 0] and changes nothing; leaving it out gives the same step bit for bit, for less work.
    /// The test is rapier's own (`curr_pos < min`, `max < curr_pos` on the coordinate the
    /// constraint reads), taken inclusive.
    fn gate_joint_limits(&mut self) {
        for (handle, limited) in self.joints.iter().zip(&self.limited) {
            if !*limited {
                continue;
            }
            let Some((multibody, link_id)) = self.multibody_joints.get_mut(*handle) else {
                continue;
            };
            let Some(link) = multibody.link_mut(link_id) else {
                continue;
            };
            let limits = link.joint.data.limits[JointAxis::AngX as usize];
            let q = link.joint.coords()[JointAxis::AngX as usize];
            let inside = q > limits.min && q < limits.max;
            link.joint.data.limit_axes.set(JointAxesMask::ANG_X, !inside);
        }
    }

    fn apply_joint_torques(&mut self) {
        for handle in &self.links {
            if let Some(rb) = self.bodies.get_mut(*handle) {
                rb.reset_torques(false);
                rb.reset_forces(false);
            }
        }
        for (idx, body) in self.robot.bodies().iter().enumerate() {
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
        if let Some(free) = self.free.as_ref().filter(|free| free.active) {
            out.q.as_mut_slice().copy_from_slice(&free.q);
            out.qd.as_mut_slice().copy_from_slice(&free.qd);
        } else if let Some((multibody, _)) = self.multibody_joints.get(self.joints[0]) {
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
        (out.arm_contact_n, out.arm_contact_link) = self.arm_contact;
    }

    fn apply(&mut self, torques: &[f64]) -> Result<(), PlantError> {
        saturate(&self.robot, torques, &mut self.torque)
    }

    fn step(&mut self, dt: f64) -> Result<(), PlantError> {
        self.params.dt = dt as Real;
        if self.free_step(dt) {
            self.t += dt;
            self.steps_free += 1;
            self.witness_check();
            return Ok(());
        }
        self.land();
        self.rapier_stepped = true;
        self.steps_rapier += 1;
        self.gate_joint_limits();
        self.apply_joint_torques();
        self.tune_contact_stiffness();
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
        self.sense_contacts(dt);
        if let Some(idx) = self.first_non_finite_joint() {
            return Err(PlantError::NonFinite {
                t: self.t,
                joint: self.robot.joints()[idx].name.clone(),
            });
        }
        self.witness_check();
        Ok(())
    }

    fn take_contact_audit(&mut self) -> Option<ContactAudit> {
        self.witness.as_mut().map(Witness::take)
    }

    fn visit_parts(&self, visit: &mut dyn FnMut(&str, f64)) {
        for button in &self.buttons {
            if let Some(depth) = self.depth_of(button) {
                visit(&button.name, depth);
            }
        }
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

//! Building the rapier world from the robot model and the scene: the arm as a multibody of
//! revolute joints starting at `q0`, the tool's and the arm links' colliders, and the scene's
//! objects (boxes, cylinders, spring-loaded buttons).
// `Real` is f32 or f64 depending on the rapier flavour: casts and conversions to it are identities in one.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use nalgebra::IsometryMatrix3;
use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderBuilder, GenericJointBuilder, Group, InteractionGroups, InteractionTestMode,
    JointAxesMask, JointAxis, MassProperties, MultibodyJointHandle, RigidBodyBuilder, RigidBodyHandle, SharedShape,
};

use super::convert::{mass_properties, pose_of, pose_of_quat, quat, rpy_pose, vec3, z_to_y};
use super::rapier_plant::{RapierOptions, RapierPlant};
use super::{ObjectShape, Scene};
use crate::robot::Shape;

/// A spring-loaded button in the simulation.
#[derive(Debug, Clone)]
pub(super) struct Button {
    /// The scene object's name.
    pub(super) name: String,
    /// The cap's prismatic joint.
    pub(super) joint: MultibodyJointHandle,
    /// The cap's body.
    pub(super) cap: RigidBodyHandle,
    /// Spring stiffness \[N/m\].
    pub(super) stiffness: f64,
    /// Spring force at rest \[N\].
    pub(super) preload: f64,
    /// Damping \[N s/m\].
    pub(super) damping: f64,
}

/// How far a button's joint limit lies beyond its hard stop, m: the limit is only a backstop, the stop
/// (a fixed collider) carries the press.
const BUTTON_LIMIT_MARGIN: Real = 0.001;

const TOOL_GROUP: Group = Group::GROUP_1;
const SCENE_GROUP: Group = Group::GROUP_2;
const ARM_GROUP: Group = Group::GROUP_3;

/// The `user_data` of an arm link's collider: the link's index in [`crate::robot::Robot::links`]
/// plus one (0, every other collider's, means "not an arm link").
fn arm_link_tag(link_idx: usize) -> u128 {
    link_idx as u128 + 1
}

/// The arm link (index into [`crate::robot::Robot::links`]) a collider's `user_data` tags, if any.
pub(super) fn arm_link_of(user_data: u128) -> Option<usize> {
    user_data.checked_sub(1).and_then(|idx| usize::try_from(idx).ok())
}

/// A URDF collision shape as rapier's, and where it sits on its body (rapier's cylinders run
/// along y, URDF's along z).
fn link_shape(shape: &Shape, shape_in_body: Pose) -> (Pose, SharedShape) {
    match *shape {
        Shape::Sphere { radius } => (shape_in_body, SharedShape::ball(radius as Real)),
        Shape::Cuboid { size } => (
            shape_in_body,
            SharedShape::cuboid(size.x as Real / 2.0, size.y as Real / 2.0, size.z as Real / 2.0),
        ),
        Shape::Cylinder { radius, length } => (
            shape_in_body * z_to_y(),
            SharedShape::cylinder(length as Real / 2.0, radius as Real),
        ),
        Shape::Capsule { radius, length } => (
            shape_in_body,
            SharedShape::capsule_z(length as Real / 2.0, radius as Real),
        ),
    }
}

impl RapierPlant {
    /// Adds the arm (a multibody from a fixed root), moved to `q0`, the tool's colliders and the
    /// arm links' colliders.
    pub(super) fn build_arm(&mut self, q0: &[f64], sensor_link: usize, options: RapierOptions) {
        let robot = &self.robot;
        let mut data = robot.data();
        robot.forward_kinematics(&mut data, &vec![0.0; robot.dof()]);
        self.root = self.bodies.insert(RigidBodyBuilder::fixed().can_sleep(false));
        let mut parent = self.root;
        for (idx, body) in robot.bodies().iter().enumerate() {
            let rb = RigidBodyBuilder::dynamic()
                .pose(pose_of(&IsometryMatrix3::from_parts(
                    nalgebra::Translation3::from(*data.body_position(idx)),
                    nalgebra::Rotation3::from_matrix_unchecked(*data.body_rotation(idx)),
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
        // Colliders: the tool's (every link from the sensor link on: the wrist sensor measures
        // their contacts) and the arm's (the links before it on moving bodies), all massless
        // (the mass is in the body). Links fixed to the base get none: the base cannot move
        // into anything, and its contact with fixed objects would carry no force.
        let material = |builder: ColliderBuilder| {
            builder
                .density(0.0)
                .friction(1.0e3)
                .friction_combine_rule(CoefficientCombineRule::Min)
                .restitution(0.0)
        };
        for (link_idx, link) in robot.links().iter().enumerate() {
            let Some(body) = link.body else { continue };
            let shapes: Vec<(Pose, SharedShape)> = link
                .collisions
                .iter()
                .map(|collision| {
                    let shape_in_body = pose_of(&link.link_in_body) * pose_of_quat(&collision.shape_in_link);
                    link_shape(&collision.shape, shape_in_body)
                })
                .collect();
            if link_idx >= sensor_link {
                // One collider per shape, as the contact wrench has always been read.
                for (pose, shape) in shapes {
                    let collider = material(ColliderBuilder::new(shape).position(pose)).collision_groups(
                        InteractionGroups::new(TOOL_GROUP, SCENE_GROUP, InteractionTestMode::And),
                    );
                    let handle = self
                        .colliders
                        .insert_with_parent(collider, self.links[body], &mut self.bodies);
                    self.tool_colliders.push(handle);
                }
                continue;
            }
            // One collider per arm link (a compound of its shapes): a step updates every moving
            // collider, so three shapes on one collider cost a third. Arm links meet the scene
            // only: never each other nor the tool (adjacent links overlap at every joint), and
            // their contacts are not the sensor's.
            let builder = match shapes.len() {
                0 => continue,
                1 => {
                    let (pose, shape) = shapes.into_iter().next().expect("one shape");
                    ColliderBuilder::new(shape).position(pose)
                }
                _ => ColliderBuilder::compound(shapes),
            };
            let collider = material(builder)
                .collision_groups(InteractionGroups::new(ARM_GROUP, SCENE_GROUP, InteractionTestMode::And))
                .user_data(arm_link_tag(link_idx));
            let handle = self
                .colliders
                .insert_with_parent(collider, self.links[body], &mut self.bodies);
            self.arm_colliders.push((handle, link_idx));
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

    /// Adds the scene's objects.
    pub(super) fn build_objects(&mut self, scene: &Scene) {
        let groups = InteractionGroups::new(SCENE_GROUP, TOOL_GROUP | ARM_GROUP, InteractionTestMode::And);
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
            match object.shape() {
                ObjectShape::Box { size } => {
                    let body = self.bodies.insert(RigidBodyBuilder::fixed().pose(pose));
                    let collider = material(ColliderBuilder::cuboid(
                        size[0] as Real / 2.0,
                        size[1] as Real / 2.0,
                        size[2] as Real / 2.0,
                    ));
                    let handle = self.colliders.insert_with_parent(collider, body, &mut self.bodies);
                    self.object_colliders.push((handle, name.clone()));
                }
                ObjectShape::Cylinder { radius, length } => {
                    let body = self.bodies.insert(RigidBodyBuilder::fixed().pose(pose));
                    let collider = material(
                        ColliderBuilder::cylinder(length as Real / 2.0, radius as Real)
                            // Its contacts are found anew every step like every pair's (no
                            // recycling, see `RapierPlant`): a probe sliding over the drum follows its
                            // curve, not a frozen tangent plane.
                            .position(z_to_y()),
                    );
                    let handle = self.colliders.insert_with_parent(collider, body, &mut self.bodies);
                    self.object_colliders.push((handle, name.clone()));
                }
                ObjectShape::Button { radius, height, travel } => {
                    let (radius, height, travel) = (radius as Real, height as Real, travel as Real);
                    let mass = object.mass.unwrap_or(0.02) as Real;
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
                    let handle = self.colliders.insert_with_parent(collider, cap, &mut self.bodies);
                    self.object_colliders.push((handle, name.clone()));
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
                    // The stop hangs on a fixed body of its own: the housing roots the cap's multibody,
                    // and rapier gives contacts with a multibody link the soft-body (cap) softness,
                    // not the fixed-object one the scene's stiffness sets.
                    let stop_body = self.bodies.insert(RigidBodyBuilder::fixed().pose(pose));
                    let handle = self.colliders.insert_with_parent(stop, stop_body, &mut self.bodies);
                    self.object_colliders.push((handle, name.clone()));
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
}

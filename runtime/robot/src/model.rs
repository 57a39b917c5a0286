//! The robot model: a serial chain of rigid bodies read from a URDF, in f64 and SI units, and the
//! per-link and per-joint readers the chain builder (`chain.rs`) uses.

use std::path::Path;

use nalgebra::{Isometry3, IsometryMatrix3, Matrix3, Rotation3, SymmetricEigen, Translation3, Vector3};

use super::RobotError;

/// How a movable joint moves its child.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum JointKind {
    /// Rotation about the axis, in rad (URDF `revolute` and `continuous`).
    Revolute,
    /// Translation along the axis, in m.
    Prismatic,
}

/// A movable joint of the chain, in the order from the base to the tip.
#[derive(Debug, Clone, PartialEq)]
pub struct JointInfo {
    /// The URDF joint name.
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Unit axis in the joint (= child link) frame.
    pub axis: Vector3<f64>,
    /// Lower position limit in rad or m (`-inf` for continuous joints).
    pub lower: f64,
    /// Upper position limit in rad or m (`inf` for continuous joints).
    pub upper: f64,
    /// Velocity limit in rad/s or m/s.
    pub velocity: f64,
    /// Torque (force) limit in N m (N).
    pub effort: f64,
    /// Viscous damping from `<dynamics>`, N m s/rad (0 when absent). The model does not use it.
    pub damping: f64,
    /// Coulomb friction from `<dynamics>`, N m (0 when absent). The model does not use it.
    pub friction: f64,
    /// The link the joint hangs from.
    pub parent_link: String,
    /// The link the joint moves.
    pub child_link: String,
}

/// A primitive collision shape, in its link's frame. Exhaustive: a simulator builds each, and a
/// new shape must reach every match on it.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A ball.
    Sphere {
        /// Radius in m.
        radius: f64,
    },
    /// A box centred on its origin.
    Cuboid {
        /// Full extents along x, y, z in m.
        size: Vector3<f64>,
    },
    /// A cylinder along the local z axis, centred on its origin.
    Cylinder {
        /// Radius in m.
        radius: f64,
        /// Full length in m.
        length: f64,
    },
    /// A capsule along the local z axis (length of the straight part), centred on its origin.
    Capsule {
        /// Radius in m.
        radius: f64,
        /// Length of the cylindrical part in m.
        length: f64,
    },
}

/// A collision primitive attached to a link.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    /// The shape's pose in the link frame.
    pub shape_in_link: Isometry3<f64>,
    /// The shape.
    pub shape: Shape,
}

/// A link's mass properties as read from the URDF (link frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Mass in kg (0 for a massless frame).
    pub mass: f64,
    /// Centre of mass in the link frame, m.
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass, in link-frame axes, kg m².
    pub inertia: Matrix3<f64>,
}

/// A link of the chain, in the order from the base to the tip.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkInfo {
    /// The URDF link name.
    pub name: String,
    /// The movable joint (index into [`Robot::joints`]) whose body this link is rigidly attached to;
    /// `None` for links fixed to the base.
    pub body: Option<usize>,
    /// The link frame in its body's frame (or in the base frame when `body` is `None`).
    pub link_in_body: IsometryMatrix3<f64>,
    /// Mass properties as read.
    pub inertial: Inertial,
    /// Collision primitives (visuals are ignored).
    pub collisions: Vec<Collision>,
}

/// One moving body of the dynamics: everything rigidly attached after one movable joint
/// ([`Robot::bodies`]; a simulator builds its rigid bodies from them).
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Joint frame at zero position in the previous body's frame (the base frame for body 0).
    pub rot0: Matrix3<f64>,
    /// Translation part of the same transform.
    pub pos0: Vector3<f64>,
    /// Unit joint axis in this body's frame.
    pub axis: Vector3<f64>,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Mass of all links on this body, kg.
    pub mass: f64,
    /// Their centre of mass in the body frame.
    pub com: Vector3<f64>,
    /// Their inertia about `com`, in body axes.
    pub inertia: Matrix3<f64>,
}

/// A serial-chain robot: kinematics, mass properties and limits, independent of any simulator.
///
/// Built from a URDF by [`Robot::from_urdf_file`] or [`Robot::from_urdf_str`]. Fixed joints are folded
/// into their movable neighbours, so the dynamics run over one body per movable joint. Frames: the base
/// frame is the frame of the URDF's root link; every other frame is a URDF link frame.
/// Gravity is `(0, 0, -9.81)` m/s² in the base frame unless set with [`Robot::set_gravity`].
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    pub(crate) name: String,
    pub(crate) joints: Vec<JointInfo>,
    pub(crate) links: Vec<LinkInfo>,
    pub(crate) bodies: Vec<Body>,
    pub(crate) tool_link: usize,
    pub(crate) gravity: Vector3<f64>,
    /// What loading decided on the user's behalf (held branches, ignored base inertia, default
    /// limits), one line each, for `skillc robot`.
    pub(crate) notes: Vec<String>,
}

impl Robot {
    /// Reads a URDF file. `tool_link` names the tool link (default: the last link of the chain).
    pub fn from_urdf_file(path: &Path, tool_link: Option<&str>) -> Result<Robot, RobotError> {
        let text = std::fs::read_to_string(path).map_err(|source| RobotError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_urdf_named(&text, &path.display().to_string(), tool_link)
    }

    /// Reads URDF text. `tool_link` names the tool link (default: the last link of the chain).
    pub fn from_urdf_str(text: &str, tool_link: Option<&str>) -> Result<Robot, RobotError> {
        Self::from_urdf_named(text, "<string>", tool_link)
    }

    fn from_urdf_named(text: &str, file: &str, tool_link: Option<&str>) -> Result<Robot, RobotError> {
        super::chain::check_format(text, file)?;
        super::chain::check_numbers(text, file)?;
        let urdf = urdf_rs::read_from_string(text).map_err(|err| RobotError::Urdf {
            file: file.to_owned(),
            message: err.to_string().replace('\n', " "),
        })?;
        super::chain::build(&urdf, tool_link).map_err(|source| RobotError::InFile {
            file: file.to_owned(),
            source: Box::new(source),
        })
    }

    /// What loading decided on the user's behalf: branches held rigid, a fixed base's inertia
    /// ignored, default limits. Lines starting with `warning:` deserve a look.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The robot's URDF name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of movable joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The movable joints from base to tip.
    pub fn joints(&self) -> &[JointInfo] {
        &self.joints
    }

    /// The moving bodies of the dynamics, one per movable joint, from the base on.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// All links from base to tip.
    pub fn links(&self) -> &[LinkInfo] {
        &self.links
    }

    /// The index of a link in [`Robot::links`].
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|link| link.name == name)
    }

    /// Like [`Robot::link_index`], but an error naming the known links when absent.
    pub fn require_link(&self, name: &str) -> Result<usize, RobotError> {
        self.link_index(name)
            .ok_or_else(|| unknown_link(name, &self.name, &self.links))
    }

    /// The index of the tool link in [`Robot::links`].
    pub fn tool_link(&self) -> usize {
        self.tool_link
    }

    /// Makes another link the tool link (the point of the tool Jacobian and tool pose).
    pub fn set_tool_link(&mut self, name: &str) -> Result<(), RobotError> {
        self.tool_link = self.require_link(name)?;
        Ok(())
    }

    /// Gravity in the base frame, m/s².
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// Sets gravity in the base frame, m/s².
    pub fn set_gravity(&mut self, gravity: Vector3<f64>) {
        self.gravity = gravity;
    }

    /// Lower and upper position limits per joint.
    pub fn position_limits(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.joints.iter().map(|joint| (joint.lower, joint.upper))
    }

    /// Total mass moved by the joints (links on a body), kg.
    pub fn moving_mass(&self) -> f64 {
        self.bodies.iter().map(|body| body.mass).sum()
    }

    /// Checks that a joint vector has one entry per joint.
    pub fn check_dof(&self, got: usize) -> Result<(), RobotError> {
        if got == self.dof() {
            Ok(())
        } else {
            Err(RobotError::WrongDof {
                robot: self.name.clone(),
                expected: self.dof(),
                got,
            })
        }
    }
}

pub(super) fn unknown_link(name: &str, robot: &str, links: &[LinkInfo]) -> RobotError {
    RobotError::UnknownLink {
        name: name.to_owned(),
        robot: robot.to_owned(),
        known: links
            .iter()
            .map(|link| link.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
    }
}

fn finite(values: &[f64], item: impl FnOnce() -> String) -> Result<(), RobotError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(RobotError::NonFinite { item: item() })
    }
}

pub(super) fn pose(origin: &urdf_rs::Pose, item: impl Fn() -> String) -> Result<IsometryMatrix3<f64>, RobotError> {
    let [x, y, z] = origin.xyz.0;
    let [roll, pitch, yaw] = origin.rpy.0;
    finite(&[x, y, z, roll, pitch, yaw], item)?;
    Ok(IsometryMatrix3::from_parts(
        Translation3::new(x, y, z),
        Rotation3::from_euler_angles(roll, pitch, yaw),
    ))
}

fn to_quaternion_pose(iso: &IsometryMatrix3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        iso.translation,
        nalgebra::UnitQuaternion::from_rotation_matrix(&iso.rotation),
    )
}

pub(super) fn inertial(link: &urdf_rs::Link) -> Result<(Inertial, IsometryMatrix3<f64>), RobotError> {
    let urdf_inertial = &link.inertial;
    let frame = pose(&urdf_inertial.origin, || format!("link {} inertial origin", link.name))?;
    let mass = urdf_inertial.mass.value;
    let i = &urdf_inertial.inertia;
    finite(&[mass, i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz], || {
        format!("link {} inertial", link.name)
    })?;
    if mass < 0.0 {
        return Err(RobotError::NegativeMass {
            link: link.name.clone(),
            mass,
        });
    }
    let in_frame = Matrix3::new(i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz);
    if mass == 0.0 {
        // A massless link with a rotational inertia (Franka's `panda_link8`): physically odd
        // but simulable once lumped into a body with mass, as pinocchio does, so the tensor
        // is taken as given when it is positive semi-definite (the caller notes it).
        if in_frame.iter().any(|v| *v != 0.0) {
            let eigen = SymmetricEigen::new(in_frame);
            let scale = in_frame.abs().max().max(f64::MIN_POSITIVE);
            if eigen.eigenvalues.min() < -1e-12 * scale {
                return Err(RobotError::ZeroMass {
                    link: link.name.clone(),
                    eigenvalues: format!(
                        "{:.3e}, {:.3e}, {:.3e}",
                        eigen.eigenvalues[0], eigen.eigenvalues[1], eigen.eigenvalues[2]
                    ),
                });
            }
        }
    } else {
        let eigen = SymmetricEigen::new(in_frame);
        let min = eigen.eigenvalues.min();
        if min <= 0.0 {
            return Err(RobotError::InertiaNotSpd {
                link: link.name.clone(),
                eigenvalues: format!(
                    "{:.3e}, {:.3e}, {:.3e}",
                    eigen.eigenvalues[0], eigen.eigenvalues[1], eigen.eigenvalues[2]
                ),
            });
        }
    }
    let rot = frame.rotation.matrix();
    Ok((
        Inertial {
            mass,
            com: frame.translation.vector,
            inertia: rot * in_frame * rot.transpose(),
        },
        frame,
    ))
}

pub(super) fn collisions(link: &urdf_rs::Link) -> Result<Vec<Collision>, RobotError> {
    let mut out = Vec::with_capacity(link.collision.len());
    for (collision_idx, collision) in link.collision.iter().enumerate() {
        let item = || format!("link {} collision {collision_idx}", link.name);
        let frame = pose(&collision.origin, item)?;
        let shape = match &collision.geometry {
            urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius: *radius },
            urdf_rs::Geometry::Box { size } => Shape::Cuboid {
                size: Vector3::from(size.0),
            },
            urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
                radius: *radius,
                length: *length,
            },
            urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
                radius: *radius,
                length: *length,
            },
            // Meshes are not supported as collision shapes: the simulation uses primitives only.
            _ => continue,
        };
        let sizes: Vec<f64> = match &shape {
            Shape::Sphere { radius } => vec![*radius],
            Shape::Cuboid { size } => size.iter().copied().collect(),
            Shape::Cylinder { radius, length } | Shape::Capsule { radius, length } => {
                vec![*radius, *length]
            }
        };
        if sizes.iter().any(|s| !s.is_finite() || *s <= 0.0) {
            return Err(RobotError::NonFinite {
                item: format!("link {} collision {collision_idx} size", link.name),
            });
        }
        out.push(Collision {
            shape_in_link: to_quaternion_pose(&frame),
            shape,
        });
    }
    Ok(out)
}

/// Effort limit assumed for a chain joint whose URDF gives none (N m or N).
pub const DEFAULT_EFFORT: f64 = 100.0;

/// Velocity limit assumed for a chain joint whose URDF gives none (rad/s or m/s).
pub const DEFAULT_VELOCITY: f64 = 1.0;

/// Position limits assumed for a revolute chain joint whose URDF gives none (lower = upper = 0), rad.
pub const DEFAULT_REVOLUTE_RANGE: f64 = std::f64::consts::PI;

/// The movable joint's description, or `None` for a fixed joint. Missing limits of a joint on
/// the chain get the stated defaults with a note; impossible ones are errors.
pub(super) fn joint_info(joint: &urdf_rs::Joint, notes: &mut Vec<String>) -> Result<Option<JointInfo>, RobotError> {
    let kind = match joint.joint_type {
        urdf_rs::JointType::Fixed => return Ok(None),
        urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => JointKind::Revolute,
        urdf_rs::JointType::Prismatic => JointKind::Prismatic,
        ref other => {
            return Err(RobotError::UnsupportedJoint {
                joint: joint.name.clone(),
                kind: format!("{other:?}").to_lowercase(),
            })
        }
    };
    let axis = Vector3::from(joint.axis.xyz.0);
    let norm = axis.norm();
    if !norm.is_finite() || norm < 1e-9 {
        return Err(RobotError::BadAxis {
            joint: joint.name.clone(),
        });
    }
    let limit = &joint.limit;
    let (mut lower, mut upper) = if joint.joint_type == urdf_rs::JointType::Continuous {
        (f64::NEG_INFINITY, f64::INFINITY)
    } else {
        (limit.lower, limit.upper)
    };
    let bad = |reason: String| RobotError::BadLimit {
        joint: joint.name.clone(),
        reason,
    };
    if lower.is_nan() || upper.is_nan() || lower > upper {
        return Err(bad(format!("lower {lower} is above upper {upper}")));
    }
    if lower == 0.0 && upper == 0.0 && kind == JointKind::Revolute {
        (lower, upper) = (-DEFAULT_REVOLUTE_RANGE, DEFAULT_REVOLUTE_RANGE);
        notes.push(format!(
            "warning: joint `{}` gives no position limits (lower = upper = 0): using ±180°",
            joint.name
        ));
    }
    let mut effort = limit.effort;
    if effort == 0.0 {
        effort = DEFAULT_EFFORT;
        notes.push(format!(
            "warning: joint `{}` gives no effort limit: using {DEFAULT_EFFORT} {}",
            joint.name,
            if kind == JointKind::Revolute { "N m" } else { "N" }
        ));
    } else if effort.is_nan() || effort < 0.0 {
        return Err(bad(format!(
            "effort {effort} must be positive for a torque-controlled joint"
        )));
    }
    let mut velocity = limit.velocity;
    if velocity == 0.0 {
        velocity = DEFAULT_VELOCITY;
        notes.push(format!(
            "warning: joint `{}` gives no velocity limit: using {DEFAULT_VELOCITY} {}",
            joint.name,
            if kind == JointKind::Revolute { "rad/s" } else { "m/s" }
        ));
    } else if velocity.is_nan() || velocity < 0.0 {
        return Err(bad(format!("velocity {velocity} must be positive")));
    }
    let (damping, friction) = joint
        .dynamics
        .as_ref()
        .map_or((0.0, 0.0), |dynamics| (dynamics.damping, dynamics.friction));
    Ok(Some(JointInfo {
        name: joint.name.clone(),
        kind,
        axis: axis / norm,
        lower,
        upper,
        velocity,
        effort,
        damping,
        friction,
        parent_link: joint.parent.link.clone(),
        child_link: joint.child.link.clone(),
    }))
}

/// Adds `inertial` (in link frame) placed at `link_in_body` to the body's mass properties.
pub(super) fn lump(body: &mut Body, inertial: &Inertial, link_in_body: &IsometryMatrix3<f64>) {
    let rot = link_in_body.rotation.matrix();
    if inertial.mass == 0.0 {
        // A massless link's rotational inertia, if any, adds as given: with no mass it has no
        // parallel-axis term and does not move the centre of mass.
        body.inertia += rot * inertial.inertia * rot.transpose();
        return;
    }
    let com = link_in_body * nalgebra::Point3::from(inertial.com);
    let inertia = rot * inertial.inertia * rot.transpose();
    let total = body.mass + inertial.mass;
    let new_com = (body.com * body.mass + com.coords * inertial.mass) / total;
    let shift = |mass: f64, inertia: Matrix3<f64>, at: Vector3<f64>| {
        let d = at - new_com;
        inertia + mass * (Matrix3::identity() * d.dot(&d) - d * d.transpose())
    };
    body.inertia = shift(body.mass, body.inertia, body.com) + shift(inertial.mass, inertia, com.coords);
    body.com = new_com;
    body.mass = total;
}

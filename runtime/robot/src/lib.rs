//! The robot model (URDF, kinematics, dynamics, inverse kinematics) and the `Plant` interface a
//! controller drives: what every skillc process shares, the plant's and the controller's alike.
//!
//! The robot model: a serial chain read from a URDF (urdf-rs), with kinematics and rigid-body dynamics
//! in f64, independent of the simulator so the same code could drive a real arm.
//!
//! Typical hot-loop use, without allocation:
//! ```
//! # use skill_robot::Robot;
//! # let robot = Robot::from_urdf_str(skill_robot::LWR4_URDF, None).expect("bundled urdf");
//! let mut data = robot.data();
//! let mut jacobian = nalgebra::Matrix6xX::zeros(robot.dof());
//! let mut gravity = vec![0.0; robot.dof()];
//! robot.forward_kinematics(&mut data, &[0.0; 7]);
//! robot.tool_jacobian(&data, &mut jacobian);
//! robot.gravity_torques(&mut data, &mut gravity);
//! let tool_in_base = robot.tool_in_base(&data);
//! # assert!(tool_in_base.translation.z > 1.0);
//! ```
#![warn(missing_docs)]
pub mod plant;

mod builtin;
mod chain;
mod dynamics;
mod error;
mod ik;
mod inspect;
mod kinematics;
mod model;

pub use builtin::{BuiltinRobot, BUILTIN_ROBOTS, FR3, IIWA14, LWR4};
pub use dynamics::STOP_TIME_CONSTANT_S;
pub use error::RobotError;
pub use ik::LWR4_ELBOW_UP;
pub use inspect::{Inspection, JointSummary};
pub use kinematics::RobotData;
pub use model::{
    Collision, Inertial, JointInfo, JointKind, LinkInfo, Robot, Shape, DEFAULT_EFFORT, DEFAULT_REVOLUTE_RANGE,
    DEFAULT_VELOCITY,
};

/// The repo's KUKA LWR IV URDF with its probe tool (`examples/robots/lwr4.urdf`), compiled in so tests
/// and tools work without the examples folder.
pub const LWR4_URDF: &str = include_str!("../../../examples/robots/lwr4.urdf");

/// The LWR IV's flange link (DH frame 7), where the wrist force/torque sensor sits.
pub const LWR4_FLANGE: &str = "lwr_flange";

/// The LWR IV probe's tool link: the centre of the spherical tip.
pub const LWR4_TOOL: &str = "probe_tip";

//! The simulated plant: the robot as a torque-controlled rapier multibody in a scene read from a
//! TOML file, with a wrist force/torque sensor and a contact witness. Links no learner and no
//! controller.
//!
//! The simulation (docs/method.md §7): the robot as a torque-controlled rapier multibody in a
//! scene read from a TOML file, with a wrist force/torque sensor. rapier's own (glam) types never
//! leave this module: `convert` is the one place values cross between nalgebra and rapier.
#![warn(missing_docs)]

use skill_robot::{self as robot, plant};

mod build;
mod contact;
mod convert;
mod free_flight;
mod rapier_plant;
mod scene;
mod sensor;
mod stiffness;
mod witness;

pub use convert::SIM_F64;
pub use rapier_plant::{joint_positions, RapierOptions, RapierPlant, SimError, StepCounts};
pub use scene::{ObjectKind, ObjectShape, ObjectSpec, RobotSpec, Scene, SceneError, SceneSpec, SimSpec, ToolStart};
pub use sensor::{SensorConfig, WristSensor};

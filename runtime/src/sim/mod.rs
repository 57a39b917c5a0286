//! The simulation: the robot as a torque-controlled rapier multibody in a scene read from a TOML
//! file, with a wrist force/torque sensor. rapier's own (glam) types never leave this module.

mod rapier_plant;
mod scene;
mod sensor;

pub use rapier_plant::{joint_positions, RapierOptions, RapierPlant, SimError, SIM_F64};
pub use scene::{ObjectKind, ObjectSpec, RobotSpec, Scene, SceneError, SceneSpec, SimSpec};
pub use sensor::{SensorConfig, WristSensor};

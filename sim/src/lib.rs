//! The simulated plant: the robot as a torque-controlled rapier multibody in a scene read from a
//! TOML file, with a wrist force/torque sensor and a contact witness. Links no learner and no
//! controller.
#![warn(missing_docs)]
pub mod sim;

use skill_robot::{plant, robot};

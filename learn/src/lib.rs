//! Learning from one demonstration: reading and preparing demonstrations, segmentation,
//! constraint fitting, forces, phases, and the driver that runs a skill's learning plan; also
//! the synthetic demonstrations the tests and examples learn from.
#![warn(missing_docs)]
pub mod demo;
pub mod demogen;
pub mod learn;
pub mod rng;
pub mod skill;

use skill_model::dmp;
use skill_robot::robot;

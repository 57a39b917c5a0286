//! The skill engine and its controller: the hybrid position/force control law, the safety
//! supervisor, and the state machine that runs a learned skill against any `Plant`. Links neither
//! the simulator nor the learner.
#![warn(missing_docs)]
pub mod control;
pub mod exec;
pub mod safety;

use skill_model::{dmp, skill};
use skill_robot::{plant, robot};

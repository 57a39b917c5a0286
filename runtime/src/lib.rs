//! The skillc runtime: learning from a demonstration, the robot model, the hybrid controller and the simulation.
#![warn(missing_docs)]
pub mod demo;
pub mod robot;
pub mod dmp;
pub mod plant;
pub mod sim;
pub mod learn;
pub mod control;
pub mod demogen;
pub mod rng;
pub mod skill;
pub mod exec;

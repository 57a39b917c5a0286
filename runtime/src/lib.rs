//! The skillc runtime: learning from a demonstration, the robot model, the hybrid controller and the simulation.
#![warn(missing_docs)]
pub mod control;
pub mod demo;
pub mod demogen;
pub mod dmp;
pub mod exec;
pub mod learn;
pub mod plant;
pub mod rng;
pub mod robot;
pub mod safety;
pub mod sim;
pub mod skill;

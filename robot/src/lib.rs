//! The robot model (URDF, kinematics, dynamics, inverse kinematics) and the `Plant` interface a
//! controller drives: what every skillc process shares, the plant's and the controller's alike.
#![warn(missing_docs)]
pub mod plant;
pub mod robot;

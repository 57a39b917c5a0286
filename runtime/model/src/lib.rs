//! The learned skill as data: dynamic movement primitives (fitting and rollout), the learned-file
//! format and its checks. What the skill engine needs of learning, without the learner.
#![warn(missing_docs)]
pub mod constraint;
pub mod dmp;
pub mod skill;
pub mod wrench;

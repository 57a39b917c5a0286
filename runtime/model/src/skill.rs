//! The learned skill: the learned-file format ([`learned`]), its checks ([`validate`]) and the
//! kinematic preview ([`rollout`]).
//!
//! The learned file is robot-agnostic: motions and frames describe the FLANGE pose of the
//! demonstration (as recorded, docs/method.md §1). The runtime maps them to its control point (the tool)
//! with the robot's fixed flange-to-tool transform.

pub mod learned;
pub mod rollout;
pub mod validate;

pub use learned::{
    ir_hash, ContactBoundaries, FrameKind, FrameOrigin, FramePose, Learned, LearnedForce, LearnedFrame, LearnedMotion,
    LearnedSegment, NormalCheck, OnsetFrame, OnsetMove, PhaseReport, Quality, LEARNED_VERSION,
};

//! A skill bound to its demonstration: the learning driver that runs an IR learning plan
//! ([`driver`]), beside the learned-file format ([`learned`]) and the kinematic preview
//! ([`rollout`]) of `skill-model`.
//!
//! The learned file is robot-agnostic: motions and frames describe the FLANGE pose of the
//! demonstration (as recorded, docs/method.md §1). The runtime maps them to its control point (the tool)
//! with the robot's fixed flange-to-tool transform.

pub mod driver;
pub use skill_model::skill::{learned, rollout, validate};

pub use driver::{learn_skill, LearnError, LearnOptions, DEFAULT_FRICTION_MU};
pub use learned::{
    ir_hash, ContactBoundaries, FrameKind, FrameOrigin, FramePose, Learned, LearnedForce, LearnedFrame, LearnedMotion,
    LearnedSegment, NormalCheck, OnsetFrame, OnsetMove, PhaseReport, Quality, LEARNED_VERSION,
};

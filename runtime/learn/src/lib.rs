//! Learning from one demonstration: reading and preparing demonstrations, segmentation,
//! constraint fitting, forces, phases, and the driver that runs a skill's learning plan; also
//! the synthetic demonstrations the tests and examples learn from.
//!
//! Learning a skill's features from one demonstration: segmentation, constraints and compliant
//! frames, forces. Everything here is plain functions over [`crate::demo::Demo`] data driven by
//! serde-(de)serialisable config structs, so that a learning plan maps onto them directly.
//! That mapping is one module, [`ir_seam`]: the IR's enums become these configs there and
//! nowhere else. The driver that runs a skill's plan is [`crate::skill::driver`]; it segments
//! with [`segment::segment_demo`] like any other caller.
//!
//! What the driver calls for each plan element:
//!
//! | plan element | config | call |
//! |---|---|---|
//! | read the demonstration | [`crate::demo::ReadOptions`], [`crate::demo::PreprocessConfig`] | [`crate::demo::read_csv`], [`crate::demo::preprocess`] |
//! | segmentation (cluster, changepoint, max force, none) | [`segment::Segmentation::from_plan`] | [`segment::segment_demo`] |
//! | constraint frame of a segment | [`constraint::ConstraintConfig::from_candidates`] | [`constraint::fit_constraints`] → `chosen().frame` |
//! | force-aligned frame per sample / at a point | [`constraint::ForceFrameConfig`] | [`constraint::force_aligned_frames`] (on the force without its friction part), [`constraint::force_aligned_frame_at`] |
//! | constant force (slide) | [`force::ConstantForceConfig`] | the applied force along a frame axis, then [`force::constant_normal_force`] |
//! | force magnitude along a frame axis (contour) | [`crate::dmp::DmpConfig`] | the smoothed applied force along the axis, then [`crate::dmp::fit_scalar`] |
//! | force at a point, force threshold (touch) | — | the applied force along a frame axis at one sample |
//! | motion of a segment | [`crate::dmp::DmpConfig`] | [`crate::dmp::Dmp::fit_points`], [`crate::dmp::QuatDmp::fit`] |
//! | force DMP of a segment (press) | [`crate::dmp::DmpConfig`] | [`crate::dmp::fit_force`] on the smoothed applied force |
//!
//! The driver measures forces along frame axes itself because a frame may turn from sample to
//! sample; [`force::profile_along`], [`force::profile_along_axis`] and [`force::force_at`] are
//! the same measurements for callers with the frames at hand (the benches, the tests).
#![warn(missing_docs)]
pub mod demo;
pub mod demogen;
pub mod rng;
pub mod skill;

use skill_model::dmp;
use skill_robot as robot;

pub mod constraint;
pub mod force;
pub mod ir_seam;
pub mod phases;
pub mod segment;
pub mod strokes;

#[cfg(test)]
pub(crate) mod testutil;

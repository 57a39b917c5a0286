//! Learning a skill's features from one demonstration: segmentation, constraints and compliant
//! frames, forces. Everything here is plain functions over [`crate::demo::Demo`] data driven by
//! serde-(de)serialisable config structs, so that a learning plan maps onto them directly.
//! That mapping is one module, [`ir_seam`]: the IR's enums become these configs there and
//! nowhere else. The driver that runs a skill's plan is [`crate::skill::learn`]; it segments
//! with [`segment::segment_demo`] like any other caller.
//!
//! | plan element | config | call |
//! |---|---|---|
//! | read the demonstration | [`crate::demo::ReadOptions`], [`crate::demo::PreprocessConfig`] | [`crate::demo::read_csv`], [`crate::demo::preprocess`] |
//! | segmentation (cluster, changepoint, max force, none) | [`segment::Segmentation::from_plan`] | [`segment::segment_demo`] |
//! | constraint frame of a segment | [`constraint::ConstraintConfig::from_candidates`] | [`constraint::fit_constraints`] → `chosen().frame` |
//! | force-aligned frame per sample / at a point | [`constraint::ForceFrameConfig`] | [`constraint::force_aligned_frames`], [`constraint::force_aligned_frame_at`] |
//! | constant force (slide) | [`force::ConstantForceConfig`] | [`force::profile_along_axis`] then [`force::constant_normal_force`] |
//! | force profile along CF z (contour) | — | [`force::profile_along`] then [`crate::dmp::fit_scalar`] |
//! | force at a point (touch threshold) | — | [`force::force_at`] |
//! | motion of a segment | [`crate::dmp::DmpConfig`] | [`crate::dmp::Dmp::fit_points`], [`crate::dmp::QuatDmp::fit`] |
//! | force DMP of a segment (press) | [`crate::dmp::DmpConfig`] | [`crate::dmp::fit_force`] |

pub mod constraint;
pub mod force;
pub mod ir_seam;
pub mod segment;

#[cfg(test)]
pub(crate) mod testutil;

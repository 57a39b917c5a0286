//! Learning a skill's features from one demonstration: segmentation, constraints and compliant
//! frames, forces. Everything here is plain functions over [`crate::demo::Demo`] data driven by
//! serde-(de)serialisable config structs, so that a learning plan maps onto them directly.

pub mod constraint;
pub mod force;
pub mod segment;

#[cfg(test)]
pub(crate) mod testutil;

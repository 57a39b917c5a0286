//! The one seam between the IR's learning plan and the learning algorithms: every IR type that
//! has a runtime counterpart is converted here, and nowhere else.
//!
//! The runtime types stay because they carry what the IR leaves to the runtime: sample counts
//! where the IR has seconds, the block limit of time-feature clustering, `usize` counts, the
//! degrees of freedom of a constraint model, serde defaults for config files. IR types that
//! need nothing more (points, frame axes, force and threshold sources) are used as they are by
//! the driver ([`crate::skill::driver`]).

use skill_ir as ir;

use super::constraint::ConstraintConfig;
use super::segment::{
    ChangepointConfig, ClusterConfig, Cut, FeatureSet, Linkage, SegmentModel, Segmentation, Temporal, TouchConfig,
};

/// Time-feature clustering pre-aggregates the samples into at most this many blocks.
const TIME_FEATURE_MAX_BLOCKS: usize = 2000;

impl Segmentation {
    /// The segmentation `plan` asks for, on a demonstration sampled at `rate_hz` (which turns
    /// the plan's minimum segment length in seconds into samples for clustering).
    ///
    /// Change-point detection is told the template's segment count so that it merges down to
    /// it; the other methods are checked against it by [`super::segment::segment_demo`].
    pub fn from_plan(plan: &ir::LearnPlan, rate_hz: f64) -> Self {
        match &plan.segmentation {
            ir::Segmentation::None => Segmentation::None,
            ir::Segmentation::MaxForce => Segmentation::MaxForce(TouchConfig::default()),
            ir::Segmentation::Cluster {
                linkage,
                temporal,
                cut,
                min_length_s,
                features,
            } => Segmentation::Cluster(ClusterConfig {
                linkage: (*linkage).into(),
                temporal: (*temporal).into(),
                cut: (*cut).into(),
                min_segment_samples: (min_length_s * rate_hz).round().max(1.0) as usize,
                features: (*features).into(),
            }),
            ir::Segmentation::Changepoint {
                min_length_s,
                models,
                max_particles,
                features,
            } => Segmentation::Changepoint(ChangepointConfig {
                models: models.iter().map(|&model| model.into()).collect(),
                min_length_s: *min_length_s,
                max_particles: *max_particles as usize,
                expected_segments: Some(plan.segments as usize),
                features: (*features).into(),
                ..ChangepointConfig::default()
            }),
        }
    }
}

impl ConstraintConfig {
    /// The default fitting parameters, trying only `candidates`.
    pub fn from_candidates(candidates: &[ir::ConstraintModel]) -> Self {
        ConstraintConfig {
            candidates: candidates.iter().map(|&model| model.into()).collect(),
            ..ConstraintConfig::default()
        }
    }
}

impl From<ir::Linkage> for Linkage {
    fn from(linkage: ir::Linkage) -> Self {
        match linkage {
            ir::Linkage::Ward => Linkage::Ward,
            ir::Linkage::Complete => Linkage::Complete,
            ir::Linkage::Average => Linkage::Average,
            ir::Linkage::Single => Linkage::Single,
        }
    }
}

impl From<ir::Temporal> for Temporal {
    fn from(temporal: ir::Temporal) -> Self {
        match temporal {
            ir::Temporal::Connectivity { k } => Temporal::Connectivity { k: k as usize },
            ir::Temporal::TimeFeature { weight } => Temporal::TimeFeature {
                weight,
                max_blocks: TIME_FEATURE_MAX_BLOCKS,
            },
        }
    }
}

impl From<ir::Cut> for Cut {
    fn from(cut: ir::Cut) -> Self {
        match cut {
            ir::Cut::Count(segments) => Cut::Count {
                segments: segments as usize,
            },
            ir::Cut::Distance(threshold) => Cut::Distance { threshold },
        }
    }
}

impl From<ir::SegmentModel> for SegmentModel {
    fn from(model: ir::SegmentModel) -> Self {
        match model {
            ir::SegmentModel::Constant => SegmentModel::Constant,
            ir::SegmentModel::Linear => SegmentModel::Linear,
        }
    }
}

impl From<ir::SegmentFeatures> for FeatureSet {
    fn from(features: ir::SegmentFeatures) -> Self {
        FeatureSet {
            position: features.position,
            force: features.force,
            force_magnitude: features.force_magnitude,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraint::ConstraintKind;

    #[test]
    fn every_constraint_model_maps_to_the_runtime_kind_of_the_same_name() {
        for kind in ConstraintKind::ALL {
            let name = serde_json::to_value(kind).expect("serialises");
            let model: ir::ConstraintModel = serde_json::from_value(name).expect("the IR has it");
            assert_eq!(ConstraintKind::from(model), kind);
        }
    }

    #[test]
    fn segment_features_map_field_by_field() {
        let features = ir::SegmentFeatures {
            position: false,
            force: true,
            force_magnitude: true,
        };
        let set = FeatureSet::from(features);
        assert_eq!((set.position, set.force, set.force_magnitude), (false, true, true));
    }
}

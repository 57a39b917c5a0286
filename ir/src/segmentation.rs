//! How the demonstration is cut into segments: the methods and their settings.

use serde::{Deserialize, Serialize};

/// How the demonstration is cut into segments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Segmentation {
    /// The whole demonstration is one segment.
    None,
    /// Two segments split at the sample of largest force magnitude (touch).
    MaxForce,
    /// Agglomerative clustering over standardised position and force features.
    Cluster {
        /// The linkage criterion.
        linkage: Linkage,
        /// How time keeps clusters contiguous.
        temporal: Temporal,
        /// Where the dendrogram is cut.
        cut: Cut,
        /// Segments shorter than this are merged into a neighbour \[s\].
        min_length_s: f64,
        /// The demonstration channels clustered.
        features: SegmentFeatures,
    },
    /// Change-point detection in the style of CHAMP (Niekum et al. 2015).
    Changepoint {
        /// Minimum segment length \[s\].
        min_length_s: f64,
        /// Candidate models for a segment.
        models: Vec<SegmentModel>,
        /// Bound on the particle set.
        max_particles: u32,
        /// The demonstration channels modelled.
        features: SegmentFeatures,
    },
}

/// Which demonstration channels segmentation looks at (each standardised).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SegmentFeatures {
    /// The tool position (3 columns).
    pub position: bool,
    /// The force vector (3 columns).
    pub force: bool,
    /// The force magnitude (1 column), independent of direction.
    pub force_magnitude: bool,
}

impl Default for SegmentFeatures {
    fn default() -> Self {
        SegmentFeatures {
            position: true,
            force: true,
            force_magnitude: false,
        }
    }
}

/// Agglomerative linkage criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Linkage {
    /// Minimum increase of within-cluster variance.
    Ward,
    /// Maximum pairwise distance.
    Complete,
    /// Mean pairwise distance.
    Average,
    /// Minimum pairwise distance.
    Single,
}

/// The temporal constraint of clustering.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Temporal {
    /// Standardised time added as a feature, scaled by `weight`.
    TimeFeature {
        /// Weight of the time feature relative to the others.
        weight: f64,
    },
    /// Only clusters within `k` samples of each other in time may merge.
    Connectivity {
        /// Neighbourhood size in samples, 1 to [`MAX_CONNECTIVITY`].
        k: u32,
    },
}

/// The largest connectivity clustering takes: each sample links to `k` neighbours on either side
/// (16 bytes a link), so `k` sizes the clustering's memory (`32 k` bytes a sample) and work.
/// ±100 samples is 0.1 s of a 1 kHz demonstration either side, ten times the default.
pub const MAX_CONNECTIVITY: u32 = 100;

/// Where to cut the cluster dendrogram.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Cut {
    /// Stop at this many clusters.
    Count(u32),
    /// Stop merging at this linkage distance (standardised units).
    Distance(f64),
}

/// A candidate model for one change-point segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentModel {
    /// Constant mean with Gaussian noise.
    Constant,
    /// Linear in time with Gaussian noise.
    Linear,
}

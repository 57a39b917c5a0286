//! Segmentation of a demonstration into contiguous pieces: agglomerative clustering with a
//! temporal constraint ([`cluster`]), CHAMP-style change-point detection ([`changepoint`]) and
//! the split at the force peak ([`split_at_force_peak`]).

mod changepoint;
mod cluster;
mod features;
mod touch;

pub use self::changepoint::{
    changepoint, changepoint_demo, ChangepointConfig, LengthPrior, ModelSegment, SegmentModel,
};
pub use self::cluster::{cluster, cluster_demo, ClusterConfig, Cut, Linkage, Temporal};
pub use self::features::{standardise, FeatureSet, Features};
pub use self::touch::{split_at_force_peak, TouchConfig};

use serde::{Deserialize, Serialize};

use crate::demo::Demo;

/// A contiguous run of samples `start..end` (0-based, end exclusive).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Segment {
    /// First sample.
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
}

impl Segment {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// True for an empty segment.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }

    /// The sample range.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.start..self.end
    }

    /// Start and end time (s): the time of the first sample and of the last sample (so that
    /// consecutive segments share their boundary time only when they share a sample).
    pub fn times_s(&self, t_s: &[f64]) -> Option<(f64, f64)> {
        let last = self.end.checked_sub(1)?;
        Some((*t_s.get(self.start)?, *t_s.get(last)?))
    }
}

/// How to segment a demonstration: the segmentation part of a learning plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Segmentation {
    /// The whole demonstration is one segment.
    None,
    /// Agglomerative clustering with a temporal constraint.
    Cluster(ClusterConfig),
    /// CHAMP-style change-point detection.
    Changepoint(ChangepointConfig),
    /// Split at the force peak into approach and return (touch).
    MaxForce(TouchConfig),
}

impl Segmentation {
    /// The method's name as the source language writes it (`none`, `cluster`, ...).
    pub fn method(&self) -> &'static str {
        match self {
            Segmentation::None => "none",
            Segmentation::Cluster(_) => "cluster",
            Segmentation::Changepoint(_) => "changepoint",
            Segmentation::MaxForce(_) => "max_force",
        }
    }
}

/// Segments `demo` as `plan` says. With `expected` set, a different number of segments is an
/// error (the demonstration does not fit the template).
pub fn segment_demo(demo: &Demo, plan: &Segmentation, expected: Option<usize>) -> Result<Vec<Segment>, SegmentError> {
    let segments = match plan {
        Segmentation::None => {
            if demo.is_empty() {
                return Err(SegmentError::TooFewSamples { found: 0, required: 1 });
            }
            vec![Segment {
                start: 0,
                end: demo.len(),
            }]
        }
        Segmentation::Cluster(config) => cluster_demo(demo, config)?,
        Segmentation::Changepoint(config) => changepoint_demo(demo, config)?.into_iter().map(|m| m.segment).collect(),
        Segmentation::MaxForce(config) => split_at_force_peak(&demo.force_n, config)?.to_vec(),
    };
    match expected {
        Some(count) if segments.len() != count => Err(SegmentError::WrongCount {
            found: segments.len(),
            expected: count,
        }),
        _ => Ok(segments),
    }
}

/// Boundaries between consecutive segments (the `start` of every segment but the first).
pub fn boundaries(segments: &[Segment]) -> Vec<usize> {
    segments.iter().skip(1).map(|seg| seg.start).collect()
}

/// Problems segmenting a demonstration.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SegmentError {
    /// A configuration value is out of range.
    #[error("invalid segmentation parameter `{name}`: {reason}")]
    InvalidConfig {
        /// Parameter name.
        name: &'static str,
        /// Why it is rejected.
        reason: String,
    },
    /// Too few samples for what was asked.
    #[error("segmentation needs at least {required} samples, the demonstration has {found}")]
    TooFewSamples {
        /// Samples given.
        found: usize,
        /// Samples needed.
        required: usize,
    },
    /// The feature matrix does not match its declared shape.
    #[error("`{what}` has length {found}, expected {expected}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// NaN or infinite input.
    #[error("`{what}` is not finite at sample {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// 0-based sample index.
        index: usize,
    },
    /// The segmentation found a different number of segments than the template expects.
    #[error("found {found} segment(s), the template expects {expected}")]
    WrongCount {
        /// Segments found.
        found: usize,
        /// Segments expected.
        expected: usize,
    },
    /// The force never exceeds the contact threshold.
    #[error("no contact: the peak force {peak_n:.3} N stays below the threshold `{threshold_n}` N")]
    NoContact {
        /// Largest force magnitude (N).
        peak_n: f64,
        /// Threshold (N).
        threshold_n: f64,
    },
}

/// Turns per-sample labels into runs of equal labels.
pub(crate) fn runs(labels: &[usize]) -> Vec<Segment> {
    let mut out = Vec::new();
    let mut start = 0;
    for idx in 1..=labels.len() {
        if idx == labels.len() || labels[idx] != labels[start] {
            out.push(Segment { start, end: idx });
            start = idx;
        }
    }
    out
}

/// Ward merge cost of two runs of `data` (row-major, `dims` columns), from their sums.
fn ward_cost(sum_a: &[f64], n_a: f64, sum_b: &[f64], n_b: f64) -> f64 {
    let dist2: f64 = sum_a.iter().zip(sum_b).map(|(a, b)| (a / n_a - b / n_b).powi(2)).sum();
    n_a * n_b / (n_a + n_b) * dist2
}

/// Merges runs shorter than `min_len` into their more similar neighbour, then, when
/// `target_count` is given, merges the adjacent pair with the smallest Ward cost until that many
/// remain. Never leaves fewer than one segment.
pub(crate) fn tidy_segments(
    data: &[f64],
    dims: usize,
    mut segments: Vec<Segment>,
    min_len: usize,
    target_count: Option<usize>,
) -> Vec<Segment> {
    let sum_of = |seg: &Segment| {
        let mut sum = vec![0.0; dims];
        for row in data[seg.start * dims..seg.end * dims].chunks_exact(dims) {
            sum.iter_mut().zip(row).for_each(|(s, v)| *s += v);
        }
        sum
    };
    let mut sums: Vec<Vec<f64>> = segments.iter().map(sum_of).collect();
    let merge = |segments: &mut Vec<Segment>, sums: &mut Vec<Vec<f64>>, left: usize| {
        let right = segments.remove(left + 1);
        segments[left].end = right.end;
        let right_sum = sums.remove(left + 1);
        sums[left].iter_mut().zip(right_sum).for_each(|(a, b)| *a += b);
    };
    let cost = |segments: &[Segment], sums: &[Vec<f64>], left: usize| {
        ward_cost(
            &sums[left],
            segments[left].len() as f64,
            &sums[left + 1],
            segments[left + 1].len() as f64,
        )
    };
    loop {
        if segments.len() < 2 {
            break;
        }
        let Some((shortest, seg)) = segments.iter().enumerate().min_by_key(|(_, seg)| seg.len()) else {
            break;
        };
        if seg.len() >= min_len {
            break;
        }
        // Merge into the only neighbour, or the one with the smaller Ward cost.
        let left = if shortest + 1 == segments.len()
            || (shortest > 0 && cost(&segments, &sums, shortest - 1) <= cost(&segments, &sums, shortest))
        {
            shortest - 1
        } else {
            shortest
        };
        merge(&mut segments, &mut sums, left);
    }
    if let Some(target) = target_count {
        while segments.len() > target.max(1) {
            let left = (0..segments.len() - 1)
                .min_by(|&a, &b| cost(&segments, &sums, a).total_cmp(&cost(&segments, &sums, b)))
                .unwrap_or(0);
            merge(&mut segments, &mut sums, left);
        }
    }
    segments
}

#[cfg(test)]
mod reference;
#[cfg(test)]
mod tests;

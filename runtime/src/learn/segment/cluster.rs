//! Agglomerative clustering with a temporal constraint, producing contiguous segments.
//!
//! Two ways to keep clusters local in time (thesis 4.1.1):
//!
//! - [`Temporal::Connectivity`]: samples `i`, `j` are connected when `|i − j| ≤ k`, and only
//!   connected clusters merge. No `n × n` matrix is built: every cluster keeps a short list of
//!   its connected neighbours with their linkage distance, and a binary heap over neighbour pairs
//!   (with lazy deletion by version counters) yields the closest pair. Ward distances are
//!   recomputed exactly from cluster sizes and sums; for single, complete and average linkage
//!   the distances of connected pairs are updated with the Lance-Williams formulas, and where
//!   only one of the two merged clusters was connected to a neighbour its distance is carried
//!   over (as scikit-learn does). `O(n k log n)` time, `O(n k)` memory. A consequence worth
//!   knowing: with `k = 1` two contiguous clusters touch through one pair of samples only, so
//!   single, average and complete linkage all reduce to "split at the largest jumps between
//!   adjacent samples", which is fragile on noisy data; Ward (exact from the cluster means) or
//!   a larger `k` behave better.
//! - [`Temporal::TimeFeature`]: a scaled, standardised sample-index column is appended to the
//!   features and clustering is unconstrained. To avoid the `O(n²)` distance matrix the samples
//!   are first pre-aggregated into at most `max_blocks` contiguous blocks of equal length
//!   (boundaries are therefore found to within one block), and the blocks are clustered exactly
//!   with the nearest-neighbour-chain algorithm on a condensed `m (m − 1) / 2` matrix with
//!   Lance-Williams updates (`O(m²)` time and memory). Initial block distances: Ward uses the
//!   exact Ward distance of the blocks; the other linkages use the distance between block means.
//!
//! Linkage distances follow scipy: Ward's is `√(2 nₐ n_b / (nₐ + n_b)) ‖μₐ − μ_b‖`, which is the
//! Euclidean distance for single samples. Clusters are turned into runs of equal labels, runs
//! shorter than `min_segment_samples` are merged into their more similar neighbour, and with
//! [`Cut::Count`] adjacent runs are merged by smallest Ward cost until the count is reached.
//! When merging short runs leaves fewer segments than asked for (single, average and complete
//! linkage like to isolate a few outlying samples), the tree is cut lower, one cluster at a
//! time (up to 64 more), until the count is met. The merge sequence is computed once and
//! replayed with union-find for each cut.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use serde::{Deserialize, Serialize};

use super::features::{FeatureSet, Features};
use super::{runs, tidy_segments, Segment, SegmentError};
use crate::demo::Demo;

/// How the distance between two clusters is defined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Linkage {
    /// Increase of the within-cluster sum of squares.
    #[default]
    Ward,
    /// Largest distance between members.
    Complete,
    /// Mean distance between members.
    Average,
    /// Smallest distance between members.
    Single,
}

/// How clustering is kept local in time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Temporal {
    /// Only clusters containing samples at most `k` apart in time may merge.
    Connectivity {
        /// Neighbourhood in samples (1 = only adjacent samples).
        k: usize,
    },
    /// A standardised time column scaled by `weight` is added to the features.
    TimeFeature {
        /// Scale of the time column relative to the (unit-variance) other features.
        weight: f64,
        /// Samples are pre-aggregated into at most this many contiguous blocks.
        max_blocks: usize,
    },
}

impl Default for Temporal {
    fn default() -> Self {
        Temporal::Connectivity { k: 1 }
    }
}

/// Where the cluster tree is cut.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Cut {
    /// Exactly this many contiguous segments (when the demonstration is long enough).
    Count {
        /// Number of segments.
        segments: usize,
    },
    /// Stop merging when the closest pair is farther apart than `threshold` (in standardised
    /// feature units).
    Distance {
        /// Linkage distance.
        threshold: f64,
    },
}

impl Default for Cut {
    fn default() -> Self {
        Cut::Count { segments: 3 }
    }
}

/// Parameters of cluster-based segmentation.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClusterConfig {
    /// Linkage criterion.
    pub linkage: Linkage,
    /// Temporal constraint.
    pub temporal: Temporal,
    /// Where to cut the tree.
    pub cut: Cut,
    /// Runs shorter than this many samples are merged into a neighbour.
    pub min_segment_samples: usize,
    /// Which channels are features (standardised).
    pub features: FeatureSet,
}

/// Segments `demo` by clustering its standardised features.
pub fn cluster_demo(demo: &Demo, config: &ClusterConfig) -> Result<Vec<Segment>, SegmentError> {
    let features = Features::from_demo(demo, &config.features)?;
    cluster(&features, config)
}

/// Segments the rows of `features` (already scaled as wanted) into contiguous segments.
pub fn cluster(features: &Features, config: &ClusterConfig) -> Result<Vec<Segment>, SegmentError> {
    let n = features.len();
    let dims = features.dims;
    if dims == 0 || features.data.len() != n * dims {
        return Err(SegmentError::LengthMismatch {
            what: "features",
            expected: n * dims.max(1),
            found: features.data.len(),
        });
    }
    if let Some(index) = features.data.iter().position(|v| !v.is_finite()) {
        return Err(SegmentError::NonFinite {
            what: "features",
            index: index / dims,
        });
    }
    let target = match config.cut {
        Cut::Count { segments } => {
            if segments == 0 {
                return Err(SegmentError::InvalidConfig {
                    name: "segments",
                    reason: "at least one segment".to_owned(),
                });
            }
            Some(segments)
        }
        Cut::Distance { threshold } => {
            if !(threshold.is_finite() && threshold >= 0.0) {
                return Err(SegmentError::InvalidConfig {
                    name: "threshold",
                    reason: "must be a non-negative number".to_owned(),
                });
            }
            None
        }
    };
    let required = target.unwrap_or(1).max(2) * config.min_segment_samples.max(1);
    if n < required {
        return Err(SegmentError::TooFewSamples { found: n, required });
    }
    let (merges, unit_len) = match config.temporal {
        Temporal::Connectivity { k } => {
            if k == 0 {
                return Err(SegmentError::InvalidConfig {
                    name: "k",
                    reason: "at least one neighbour".to_owned(),
                });
            }
            (connectivity_merges(&features.data, dims, k, config.linkage), 1)
        }
        Temporal::TimeFeature { weight, max_blocks } => {
            if !(weight.is_finite() && weight >= 0.0) {
                return Err(SegmentError::InvalidConfig {
                    name: "weight",
                    reason: "must be a non-negative number".to_owned(),
                });
            }
            if max_blocks < 2 {
                return Err(SegmentError::InvalidConfig {
                    name: "max_blocks",
                    reason: "at least 2 blocks".to_owned(),
                });
            }
            time_feature_merges(&features.data, dims, weight, max_blocks, config.linkage)
        }
    };
    let n_units = n.div_ceil(unit_len);
    let segments_after = |n_merges: usize| {
        let labels = labels_after(&merges, n_units, n_merges, unit_len, n);
        tidy_segments(&features.data, dims, runs(&labels), config.min_segment_samples, target)
    };
    match config.cut {
        Cut::Count { segments } => {
            // Cutting at `segments` clusters can leave fewer segments once short runs are
            // merged; cut lower in the tree until the count is met (bounded search).
            let mut result = Vec::new();
            for clusters in segments..=(segments + 64).min(n_units).max(segments) {
                result = segments_after(n_units.saturating_sub(clusters).min(merges.len()));
                if result.len() >= segments {
                    break;
                }
            }
            Ok(result)
        }
        Cut::Distance { threshold } => {
            let n_merges = merges.iter().take_while(|merge| merge.0 <= threshold).count();
            Ok(segments_after(n_merges))
        }
    }
}

/// Sample labels after applying the first `n_merges` of `merges` (`(height, a, b)` over units of
/// `unit_len` consecutive samples).
fn labels_after(
    merges: &[(f64, usize, usize)],
    n_units: usize,
    n_merges: usize,
    unit_len: usize,
    n: usize,
) -> Vec<usize> {
    let mut parent: Vec<u32> = (0..n_units as u32).collect();
    for &(_, a, b) in &merges[..n_merges.min(merges.len())] {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        parent[rb] = ra as u32;
    }
    (0..n).map(|k| find(&mut parent, k / unit_len)).collect()
}

/// A heap entry: a connected pair and the versions of both clusters when it was pushed.
#[derive(Debug, Clone, Copy)]
struct Pair {
    dist: f64,
    a: u32,
    b: u32,
    version_a: u32,
    version_b: u32,
}

impl PartialEq for Pair {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Pair {}
impl PartialOrd for Pair {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Pair {
    // Reversed so that `BinaryHeap` pops the smallest distance (ties: earliest pair).
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .dist
            .total_cmp(&self.dist)
            .then_with(|| other.a.cmp(&self.a))
            .then_with(|| other.b.cmp(&self.b))
    }
}

fn find(parent: &mut [u32], mut x: usize) -> usize {
    let mut root = x;
    while parent[root] as usize != root {
        root = parent[root] as usize;
    }
    while parent[x] as usize != root {
        let next = parent[x] as usize;
        parent[x] = root as u32;
        x = next;
    }
    root
}

fn ward_distance(sum_a: &[f64], n_a: f64, sum_b: &[f64], n_b: f64) -> f64 {
    let dist2: f64 = sum_a.iter().zip(sum_b).map(|(a, b)| (a / n_a - b / n_b).powi(2)).sum();
    (2.0 * n_a * n_b / (n_a + n_b) * dist2).sqrt()
}

/// Lance-Williams update of the distance from the union of `a` and `b` to `c`.
fn lance_williams(linkage: Linkage, d_ac: f64, d_bc: f64, d_ab: f64, n_a: f64, n_b: f64, n_c: f64) -> f64 {
    match linkage {
        Linkage::Single => d_ac.min(d_bc),
        Linkage::Complete => d_ac.max(d_bc),
        Linkage::Average => (n_a * d_ac + n_b * d_bc) / (n_a + n_b),
        Linkage::Ward => (((n_a + n_c) * d_ac * d_ac + (n_b + n_c) * d_bc * d_bc - n_c * d_ab * d_ab)
            / (n_a + n_b + n_c))
            .max(0.0)
            .sqrt(),
    }
}

/// The full merge sequence `(height, a, b)` of connectivity-constrained clustering, in order.
fn connectivity_merges(data: &[f64], dims: usize, k: usize, linkage: Linkage) -> Vec<(f64, usize, usize)> {
    let n = data.len() / dims;
    let mut size = vec![1.0f64; n];
    let mut sum = data.to_vec();
    let mut alive = vec![true; n];
    let mut version = vec![0u32; n];
    let mut merges = Vec::with_capacity(n);
    let mut neighbours: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
    let mut heap = BinaryHeap::with_capacity(n * k * 2);
    for i in 0..n {
        for j in i + 1..(i + k + 1).min(n) {
            let dist = data[i * dims..(i + 1) * dims]
                .iter()
                .zip(&data[j * dims..(j + 1) * dims])
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            neighbours[i].push((j as u32, dist));
            neighbours[j].push((i as u32, dist));
            heap.push(Pair {
                dist,
                a: i as u32,
                b: j as u32,
                version_a: 0,
                version_b: 0,
            });
        }
    }
    // (neighbour, distance to a, distance to b)
    let mut merged: Vec<(u32, Option<f64>, Option<f64>)> = Vec::new();
    while let Some(pair) = heap.pop() {
        let (a, b) = (pair.a as usize, pair.b as usize);
        if !alive[a] || !alive[b] || version[a] != pair.version_a || version[b] != pair.version_b {
            continue;
        }
        // Merge b into a.
        merged.clear();
        for &(c, d) in &neighbours[a] {
            if c as usize != b {
                merged.push((c, Some(d), None));
            }
        }
        for &(c, d) in &neighbours[b] {
            if c as usize == a {
                continue;
            }
            match merged.iter_mut().find(|entry| entry.0 == c) {
                Some(entry) => entry.2 = Some(d),
                None => merged.push((c, None, Some(d))),
            }
        }
        let (n_a, n_b) = (size[a], size[b]);
        let (head, tail) = sum.split_at_mut(b.max(a) * dims);
        let (sum_a, sum_b) = if a < b {
            (&mut head[a * dims..(a + 1) * dims], &tail[..dims])
        } else {
            (&mut tail[..dims], &head[b * dims..(b + 1) * dims])
        };
        sum_a.iter_mut().zip(sum_b).for_each(|(x, y)| *x += y);
        size[a] = n_a + n_b;
        alive[b] = false;
        version[a] += 1;
        merges.push((pair.dist, a, b));
        neighbours[b] = Vec::new();
        let mut new_list = Vec::with_capacity(merged.len());
        for &(c, d_ac, d_bc) in &merged {
            let c_idx = c as usize;
            let dist = match linkage {
                Linkage::Ward => ward_distance(
                    &sum[a * dims..(a + 1) * dims],
                    size[a],
                    &sum[c_idx * dims..(c_idx + 1) * dims],
                    size[c_idx],
                ),
                _ => match (d_ac, d_bc) {
                    (Some(x), Some(y)) => lance_williams(linkage, x, y, pair.dist, n_a, n_b, size[c_idx]),
                    (Some(x), None) | (None, Some(x)) => x,
                    (None, None) => continue,
                },
            };
            new_list.push((c, dist));
            let list = &mut neighbours[c_idx];
            list.retain(|&(other, _)| other as usize != a && other as usize != b);
            list.push((a as u32, dist));
            heap.push(Pair {
                dist,
                a: a as u32,
                b: c,
                version_a: version[a],
                version_b: version[c_idx],
            });
        }
        neighbours[a] = new_list;
    }
    merges
}

fn condensed_index(m: usize, i: usize, j: usize) -> usize {
    let (i, j) = if i < j { (i, j) } else { (j, i) };
    i * m - i * (i + 1) / 2 + j - i - 1
}

/// The merge sequence `(height, a, b)` over blocks, sorted by height, and the block length.
fn time_feature_merges(
    data: &[f64],
    dims: usize,
    weight: f64,
    max_blocks: usize,
    linkage: Linkage,
) -> (Vec<(f64, usize, usize)>, usize) {
    let n = data.len() / dims;
    let block_len = n.div_ceil(max_blocks).max(1);
    let m = n.div_ceil(block_len);
    let aug = dims + 1;
    // Standardised index: (k - mean) / std of 0..n.
    let mean_idx = (n as f64 - 1.0) / 2.0;
    let std_idx = ((n as f64 * n as f64 - 1.0) / 12.0).sqrt().max(1e-12);
    let mut size = vec![0.0f64; m];
    let mut sum = vec![0.0f64; m * aug];
    for k in 0..n {
        let block = k / block_len;
        size[block] += 1.0;
        let row = &mut sum[block * aug..(block + 1) * aug];
        row[..dims]
            .iter_mut()
            .zip(&data[k * dims..(k + 1) * dims])
            .for_each(|(s, v)| *s += v);
        row[dims] += weight * (k as f64 - mean_idx) / std_idx;
    }
    let mut dist = vec![0.0f64; m * (m.saturating_sub(1)) / 2];
    for i in 0..m {
        for j in i + 1..m {
            let (sa, sb) = (&sum[i * aug..(i + 1) * aug], &sum[j * aug..(j + 1) * aug]);
            dist[condensed_index(m, i, j)] = match linkage {
                Linkage::Ward => ward_distance(sa, size[i], sb, size[j]),
                _ => sa
                    .iter()
                    .zip(sb)
                    .map(|(a, b)| (a / size[i] - b / size[j]).powi(2))
                    .sum::<f64>()
                    .sqrt(),
            };
        }
    }
    // Nearest-neighbour chain.
    let mut active = vec![true; m];
    let mut merges: Vec<(f64, usize, usize)> = Vec::with_capacity(m);
    let mut chain: Vec<usize> = Vec::with_capacity(m);
    let mut n_active = m;
    while n_active > 1 {
        if chain.is_empty() {
            if let Some(first) = active.iter().position(|&a| a) {
                chain.push(first);
            }
        }
        let a = chain[chain.len() - 1];
        let previous = if chain.len() >= 2 {
            Some(chain[chain.len() - 2])
        } else {
            None
        };
        let mut best = (f64::INFINITY, usize::MAX);
        if let Some(p) = previous {
            best = (dist[condensed_index(m, a, p)], p);
        }
        for c in 0..m {
            if c != a && active[c] {
                let d = dist[condensed_index(m, a, c)];
                if d < best.0 {
                    best = (d, c);
                }
            }
        }
        let (d_ab, b) = best;
        if Some(b) == previous {
            chain.pop();
            chain.pop();
            let (n_a, n_b) = (size[a], size[b]);
            for c in 0..m {
                if c != a && c != b && active[c] {
                    let (d_ac, d_bc) = (dist[condensed_index(m, a, c)], dist[condensed_index(m, b, c)]);
                    dist[condensed_index(m, b, c)] = lance_williams(linkage, d_ac, d_bc, d_ab, n_a, n_b, size[c]);
                }
            }
            active[a] = false;
            size[b] = n_a + n_b;
            merges.push((d_ab, a, b));
            n_active -= 1;
        } else {
            chain.push(b);
        }
    }
    // Reducible linkages give monotone heights, so sorting yields a valid merge order.
    merges.sort_by(|x, y| x.0.total_cmp(&y.0));
    (merges, block_len)
}

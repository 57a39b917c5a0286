//! Agglomerative clustering with a temporal constraint, producing contiguous segments.
//!
//! Two ways to keep clusters local in time (thesis 4.1.1):
//!
//! - [`Temporal::Connectivity`]: samples `i`, `j` are connected when `|i − j| ≤ k`, and only
//!   connected clusters merge. No `n × n` matrix is built: every cluster keeps a short list of
//!   its connected neighbours with their linkage distance and its own closest pair, and a
//!   tournament tree over clusters yields the closest pair of all. Ward distances are
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
            if k == 0 || k > skill_ir::MAX_CONNECTIVITY as usize {
                return Err(SegmentError::InvalidConfig {
                    name: "k",
                    reason: format!("between 1 and {} neighbours", skill_ir::MAX_CONNECTIVITY),
                });
            }
            // The links are addressed by u32 positions: 2k a sample to begin with, and room for
            // the clusters that outgrow theirs.
            let too_many = || SegmentError::InvalidConfig {
                name: "temporal",
                reason: format!(
                    "connectivity clustering of {n} samples with {k} neighbours either side needs more links \
                     than it can address; resample the demonstration to a lower rate or lower the connectivity"
                ),
            };
            if n.saturating_mul(2 * k) > (u32::MAX / 4) as usize {
                return Err(too_many());
            }
            let merges = connectivity_merges(&features.data, dims, k, config.linkage).ok_or_else(too_many)?;
            (merges, 1)
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

pub(super) fn ward_distance(sum_a: &[f64], n_a: f64, sum_b: &[f64], n_b: f64) -> f64 {
    let dist2: f64 = sum_a.iter().zip(sum_b).map(|(a, b)| (a / n_a - b / n_b).powi(2)).sum();
    (2.0 * n_a * n_b / (n_a + n_b) * dist2).sqrt()
}

/// Lance-Williams update of the distance from the union of `a` and `b` to `c`.
pub(super) fn lance_williams(linkage: Linkage, d_ac: f64, d_bc: f64, d_ab: f64, n_a: f64, n_b: f64, n_c: f64) -> f64 {
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

/// Marks a link whose pair the cluster owns (is the first member of, see
/// [`connectivity_merges`]); the other bits are the neighbour's index.
const OWNED: u32 = 1 << 31;
/// No cluster: the partner of a cluster that owns no pair.
const NONE: u32 = u32::MAX;

/// One link of a cluster: the neighbour (with the [`OWNED`] bit), the position of the
/// neighbour's link back in the arena, and the linkage distance.
#[derive(Debug, Clone, Copy)]
struct Link {
    other: u32,
    twin: u32,
    dist: f64,
}

impl Link {
    fn cluster(&self) -> usize {
        (self.other & !OWNED) as usize
    }
}

/// The links of every cluster in one arena, cluster `x`'s at `head[x].at..head[x].at +
/// head[x].len`. Every link knows where its twin (the neighbour's link back) is, so a merge
/// updates a neighbour's links in place without searching them. Clusters are laid out in sample
/// order, so neighbours in time have their links close in memory; a cluster's position, length
/// and capacity share one record, so finding its links costs one cache miss, not three.
struct Links {
    arena: Vec<Link>,
    head: Vec<Head>,
}

/// Where a cluster's links lie in the arena: `len` links from `at`, room for `cap`.
#[derive(Debug, Clone, Copy)]
struct Head {
    at: u32,
    len: u32,
    cap: u32,
}

impl Links {
    fn range(&self, x: usize) -> std::ops::Range<usize> {
        let Head { at, len, .. } = self.head[x];
        at as usize..(at + len) as usize
    }

    /// Replaces cluster `x`'s links, moving them to the end of the arena when they do not fit,
    /// and points every twin at its link's new position. `None` (nothing changed) when the
    /// arena would outgrow the positions a `u32` addresses.
    fn replace(&mut self, x: usize, links: &[Link]) -> Option<()> {
        let len = links.len() as u32;
        let head = &mut self.head[x];
        if len > head.cap {
            let cap = len.max(2 * head.cap);
            let new_len = self.arena.len() + cap as usize;
            if new_len > u32::MAX as usize {
                return None;
            }
            head.cap = cap;
            head.at = self.arena.len() as u32;
            self.arena.resize(
                new_len,
                Link {
                    other: NONE,
                    twin: NONE,
                    dist: 0.0,
                },
            );
        }
        head.len = len;
        let at = head.at as usize;
        self.arena[at..at + links.len()].copy_from_slice(links);
        for (pos, link) in (at..).zip(links) {
            self.arena[link.twin as usize].twin = pos as u32;
        }
        Some(())
    }

    /// Removes the link at `pos` of cluster `x` by moving its last link into the hole; returns
    /// the position the last link came from (`pos` itself when it was the last).
    fn swap_remove(&mut self, x: usize, pos: usize) -> usize {
        let head = &mut self.head[x];
        let last = (head.at + head.len - 1) as usize;
        head.len -= 1;
        if last != pos {
            let moved = self.arena[last];
            self.arena[pos] = moved;
            self.arena[moved.twin as usize].twin = pos as u32;
        }
        last
    }

    /// The smallest pair that cluster `x` owns, `(distance, partner)`, ties to the smaller
    /// partner; `(∞, NONE)` when it owns none.
    fn best_owned(&self, x: usize) -> (f64, u32) {
        let mut best = (f64::INFINITY, NONE);
        for link in &self.arena[self.range(x)] {
            if link.other & OWNED != 0 {
                let other = link.other & !OWNED;
                if best.1 == NONE || link.dist.total_cmp(&best.0).then(other.cmp(&best.1)) == Ordering::Less {
                    best = (link.dist, other);
                }
            }
        }
        best
    }
}

/// A tournament tree over the clusters' smallest owned pairs: node `i` holds the smallest pair
/// `(distance, first, second)` of its subtree (`second == NONE` for none), leaves from `leaves`.
struct Tournament {
    tree: Vec<(f64, u32, u32)>,
    leaves: usize,
}

impl Tournament {
    /// `best[x]` is cluster `x`'s smallest owned pair `(distance, partner)`.
    fn new(best: &[(f64, u32)]) -> Self {
        let leaves = best.len().next_power_of_two();
        let mut tree = vec![(f64::INFINITY, NONE, NONE); 2 * leaves];
        for (x, &(dist, partner)) in best.iter().enumerate() {
            tree[leaves + x] = (dist, x as u32, partner);
        }
        for node in (1..leaves).rev() {
            tree[node] = Self::better(tree[2 * node], tree[2 * node + 1]);
        }
        Self { tree, leaves }
    }

    /// The smaller of two pairs from disjoint subtrees; no pair loses to any pair.
    fn better(x: (f64, u32, u32), y: (f64, u32, u32)) -> (f64, u32, u32) {
        match (x.2 == NONE, y.2 == NONE) {
            (false, true) => x,
            (true, false) => y,
            (true, true) => x,
            (false, false) => match x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)) {
                Ordering::Greater => y,
                _ => x,
            },
        }
    }

    /// The partner in cluster `x`'s smallest owned pair (`NONE` for none).
    fn partner(&self, x: usize) -> u32 {
        self.tree[self.leaves + x].2
    }

    /// Sets cluster `x`'s smallest owned pair and updates the winners above it, stopping at
    /// the first node whose winner does not change (the nodes above it then cannot change).
    fn set(&mut self, x: usize, (dist, partner): (f64, u32)) {
        let mut node = self.leaves + x;
        self.tree[node] = (dist, x as u32, partner);
        while node > 1 {
            node /= 2;
            let winner = Self::better(self.tree[2 * node], self.tree[2 * node + 1]);
            let old = self.tree[node];
            if winner.0.to_bits() == old.0.to_bits() && winner.1 == old.1 && winner.2 == old.2 {
                break;
            }
            self.tree[node] = winner;
        }
    }

    /// The smallest pair `(distance, first, second)`, if any remains.
    fn top(&self) -> Option<(f64, usize, usize)> {
        let (dist, first, second) = *self.tree.get(1)?;
        (second != NONE).then_some((dist, first as usize, second as usize))
    }
}

/// The full merge sequence `(height, a, b)` of connectivity-constrained clustering, in order:
/// at every step the connected pair with the smallest linkage distance merges (`b` into `a`).
/// Needs fewer than 2³¹ samples and `2 n k` within `u32::MAX / 4` (checked by [`cluster`]); `None` when
/// the links outgrow the positions a `u32` addresses all the same.
///
/// Every connected pair of clusters is *owned* by one of its two clusters, its first member:
/// initially the earlier sample, afterwards the cluster that survived the most recent merge
/// involving either of them. Pairs are ordered by `(distance, first, second)`, so ties go to
/// the earliest pair. Each cluster keeps its [`Links`] and a [`Tournament`] over the clusters'
/// smallest owned pairs yields the smallest pair. A merge relinks the union's neighbours
/// through the twins; only neighbours whose smallest owned pair involved `a` or `b` rescan
/// their links, so a merge costs `O(k + log n)` for `k` neighbours in practice.
pub(super) fn connectivity_merges(
    data: &[f64],
    dims: usize,
    k: usize,
    linkage: Linkage,
) -> Option<Vec<(f64, usize, usize)>> {
    let n = data.len() / dims;
    assert!(n < OWNED as usize, "fewer than 2^31 samples (checked by `cluster`)");
    // Row x is cluster x's size and mean, `[size, mean...]`: a neighbour's Ward distance needs
    // both, and one row is one or two adjacent cache lines where two arrays cost two misses.
    // The mean is kept as `sum / size` so that a distance needs no division per column (the
    // same operations as dividing each time, so the same bits).
    let stride = dims + 1;
    let mut rows = vec![1.0f64; n * stride];
    for (row, sample) in rows.chunks_exact_mut(stride).zip(data.chunks_exact(dims)) {
        row[1..].copy_from_slice(sample);
    }
    let mut sum = data.to_vec();
    // A sample starts with at most 2k links, and the union of two neighbours in time has no
    // more; a cluster that outgrows its room moves to the arena's end (`Links::replace`).
    let cap = 2 * k as u32;
    let mut links = Links {
        arena: vec![
            Link {
                other: NONE,
                twin: NONE,
                dist: 0.0
            };
            n * cap as usize
        ],
        head: (0..n as u32)
            .map(|x| Head {
                at: x * cap,
                len: 0,
                cap,
            })
            .collect(),
    };
    for i in 0..n {
        for j in i + 1..(i + k + 1).min(n) {
            let dist = data[i * dims..(i + 1) * dims]
                .iter()
                .zip(&data[j * dims..(j + 1) * dims])
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            let (hi, hj) = (links.head[i], links.head[j]);
            let (pi, pj) = (hi.at + hi.len, hj.at + hj.len);
            links.arena[pi as usize] = Link {
                other: j as u32 | OWNED,
                twin: pj,
                dist,
            };
            links.arena[pj as usize] = Link {
                other: i as u32,
                twin: pi,
                dist,
            };
            links.head[i].len += 1;
            links.head[j].len += 1;
        }
    }
    let best: Vec<(f64, u32)> = (0..n).map(|x| links.best_owned(x)).collect();
    let mut tournament = Tournament::new(&best);
    let mut merges = Vec::with_capacity(n.saturating_sub(1));
    // Per neighbour c of the union: c, distance to a, distance to b, and the positions of c's
    // links back to a and to b. A cluster lists each neighbour once, so only b's neighbours are
    // looked up among a's, in this short list (kept in L1) rather than in a per-cluster array.
    let mut merged: Vec<Neighbour> = Vec::new();
    let mut new_links: Vec<Link> = Vec::new();
    while let Some((d_ab, a, b)) = tournament.top() {
        merged.clear();
        for link in &links.arena[links.range(a)] {
            let c = link.cluster();
            if c != b {
                merged.push(Neighbour {
                    c: c as u32,
                    to_a: Some((link.dist, link.twin)),
                    to_b: None,
                });
            }
        }
        let from_a = merged.len();
        for link in &links.arena[links.range(b)] {
            let c = link.cluster();
            if c == a {
                continue;
            }
            let back = Some((link.dist, link.twin));
            match merged[..from_a].iter_mut().find(|neighbour| neighbour.c == c as u32) {
                Some(neighbour) => neighbour.to_b = back,
                None => merged.push(Neighbour {
                    c: c as u32,
                    to_a: None,
                    to_b: back,
                }),
            }
        }
        let (n_a, n_b) = (rows[a * stride], rows[b * stride]);
        let (head, tail) = sum.split_at_mut(b.max(a) * dims);
        let (sum_a, sum_b) = if a < b {
            (&mut head[a * dims..(a + 1) * dims], &tail[..dims])
        } else {
            (&mut tail[..dims], &head[b * dims..(b + 1) * dims])
        };
        sum_a.iter_mut().zip(sum_b).for_each(|(x, y)| *x += y);
        let size_a = n_a + n_b;
        let row_a = &mut rows[a * stride..(a + 1) * stride];
        row_a[0] = size_a;
        for (m, s) in row_a[1..].iter_mut().zip(&sum[a * dims..(a + 1) * dims]) {
            *m = s / size_a;
        }
        merges.push((d_ab, a, b));
        links.head[b].len = 0;
        new_links.clear();
        for neighbour in &merged {
            let c = neighbour.c as usize;
            let n_c = rows[c * stride];
            let dist = match linkage {
                Linkage::Ward => {
                    let dist2: f64 = rows[a * stride + 1..(a + 1) * stride]
                        .iter()
                        .zip(&rows[c * stride + 1..(c + 1) * stride])
                        .map(|(x, y)| (x - y).powi(2))
                        .sum();
                    (2.0 * size_a * n_c / (size_a + n_c) * dist2).sqrt()
                }
                _ => match (neighbour.to_a, neighbour.to_b) {
                    (Some((x, _)), Some((y, _))) => lance_williams(linkage, x, y, d_ab, n_a, n_b, n_c),
                    (Some((x, _)), None) | (None, Some((x, _))) => x,
                    (None, None) => unreachable!("a neighbour of a or b"),
                },
            };
            // c keeps one link to the union, not owned by c: the one to a when it had one.
            let back = match (neighbour.to_a, neighbour.to_b) {
                (Some((_, to_a)), Some((_, to_b))) => {
                    let moved_from = links.swap_remove(c, to_b as usize);
                    if moved_from == to_a as usize {
                        to_b
                    } else {
                        to_a
                    }
                }
                (Some((_, pos)), None) | (None, Some((_, pos))) => pos,
                (None, None) => unreachable!("a neighbour of a or b"),
            };
            links.arena[back as usize] = Link {
                other: a as u32,
                twin: NONE,
                dist,
            };
            new_links.push(Link {
                other: c as u32 | OWNED,
                twin: back,
                dist,
            });
            let partner = tournament.partner(c) as usize;
            if partner == a || partner == b {
                tournament.set(c, links.best_owned(c));
            }
        }
        links.replace(a, &new_links)?;
        tournament.set(a, links.best_owned(a));
        tournament.set(b, (f64::INFINITY, NONE));
    }
    Some(merges)
}

/// A neighbour `c` of a merging pair: its distance to `a` and to `b` with the position of its
/// link back, for each that it is linked to.
#[derive(Debug, Clone, Copy)]
struct Neighbour {
    c: u32,
    to_a: Option<(f64, u32)>,
    to_b: Option<(f64, u32)>,
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

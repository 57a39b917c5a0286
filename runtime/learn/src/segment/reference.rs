//! Slow references for the connectivity clustering tests (compiled for tests only): the previous
//! heap-based implementation, which the tournament version must reproduce merge for merge, and
//! a brute-force Ward clustering that recomputes every connected pair at every step.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::cluster::{lance_williams, ward_distance, Linkage};

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

/// The merge sequence of connectivity-constrained clustering as the previous implementation
/// computed it: a binary heap over all connected pairs with lazy deletion by version counters.
pub(super) fn heap_merges(data: &[f64], dims: usize, k: usize, linkage: Linkage) -> Vec<(f64, usize, usize)> {
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

/// Ward clustering by brute force: at every step, every pair of clusters with members at most
/// `k` samples apart, distance from the cluster sums. Returns per merge the height and the two
/// merged clusters' members (sorted), in merge order. `O(n³ k)`: small inputs only.
pub(super) fn brute_force_ward(data: &[f64], dims: usize, k: usize) -> Vec<(f64, Vec<usize>, Vec<usize>)> {
    let n = data.len() / dims;
    let mut clusters: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
    let mut out = Vec::new();
    let sum_of = |members: &[usize]| {
        let mut sum = vec![0.0; dims];
        for &i in members {
            sum.iter_mut()
                .zip(&data[i * dims..(i + 1) * dims])
                .for_each(|(s, v)| *s += v);
        }
        sum
    };
    let connected = |x: &[usize], y: &[usize]| x.iter().any(|i| y.iter().any(|j| i.abs_diff(*j) <= k));
    loop {
        let mut best: Option<(f64, usize, usize)> = None;
        for x in 0..clusters.len() {
            for y in x + 1..clusters.len() {
                if !connected(&clusters[x], &clusters[y]) {
                    continue;
                }
                let (sx, sy) = (sum_of(&clusters[x]), sum_of(&clusters[y]));
                let d = ward_distance(&sx, clusters[x].len() as f64, &sy, clusters[y].len() as f64);
                if best.is_none_or(|(b, _, _)| d < b) {
                    best = Some((d, x, y));
                }
            }
        }
        let Some((d, x, y)) = best else { break };
        let merged_y = clusters.remove(y);
        out.push((d, clusters[x].clone(), merged_y.clone()));
        clusters[x].extend(merged_y);
        clusters[x].sort_unstable();
    }
    out
}

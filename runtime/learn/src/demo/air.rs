//! The in-air load: the force a real recording carries while the tool is in the air (the
//! hand's grip on the tool beyond the sensor, the tool's weight as the wrist turns, a bias that
//! wanders), found from the recording's own levels and removed (docs/method.md §1, "In-air load").
//!
//! A recording made by hand holds 1-5 N on the sensor between contacts, and that load moves by a
//! few newtons over a recording (measured on the LASA wiping and peeling sets: 0.3-2.8 N at the
//! start of a rim wipe, 1.0-5.8 N after its lift-off). A bias taken from the first still samples
//! leaves it in, so the air between contacts reads as light contact. Here the air's force vector
//! is followed through the recording and subtracted from every sample, contact included (the
//! load is on the sensor in contact too):
//!
//! 1. Samples in a run of [`FROZEN_RUN`] or more identical force vectors (a sensor that stopped
//!    streaming) are left out; the force is averaged over a centred window of [`SMOOTH_S`].
//! 2. The first air vector is the median of the samples whose force is among the lowest
//!    [`INITIAL_SHARE`]; the baseline `B(t)` starts as that vector everywhere.
//! 3. [`ITERATIONS`] times: the distance `d = |F − B(t)|` is split into an air and a contact level
//!    by Otsu's threshold (`a`, `c`: the medians below and above it; no contact when `c − a` is
//!    under [`MIN_CONTRAST_N`]); contacts are where `d` rises above `a + max(c − a, 2 N) / 2`
//!    until it falls below `a + (c − a) / 4`, gaps under [`MIN_GAP_S`] closed (a contact of any
//!    length counts, a tap too); the air is every sample [`AIR_MARGIN_S`] away from a contact, cut
//!    into stretches of at most [`ANCHOR_S`], each of which (when it is at least [`MIN_AIR_S`]
//!    long, its `d` stays at the air level, its vector lies within [`MAX_DRIFT_N`] of the first
//!    air vector and the tool is at least [`AIR_LIFT_M`] off the nearest contact's surface,
//!    along its force) gives an anchor: its time and median vector. `B(t)` is the line through the
//!    anchors, held before the first and after the last.
//! 4. A recording with no stretch of air found as such (all contact, or no contact), or whose
//!    anchors all lie within [`MIN_LOAD_N`] of zero, has no load: it is left as it is (a
//!    generated or already debiased one comes through unchanged).
//!
//! The anchors' own spread is the air's noise; a contact's force is then read against the air
//! around it, which is also how `../shared/tools/check_real.py`'s reference reads it.

use nalgebra::Vector3;

use crate::phases::median_of as median;

/// A run of at least this many bit-identical force vectors is a frozen sensor.
pub const FROZEN_RUN: usize = 5;
/// Width of the centred moving average \[s\] (its first zero at 10 Hz: tremor averages out).
pub const SMOOTH_S: f64 = 0.1;
/// The first air vector is the median of this share of the samples, those with the least force.
pub const INITIAL_SHARE: f64 = 0.3;
/// Alternations of levels, contacts and baseline.
pub const ITERATIONS: usize = 3;
/// Air and contact levels closer than this \[N\] mean the recording holds no contact.
pub const MIN_CONTRAST_N: f64 = 2.0;
/// Shorter gaps between contacts are closed \[s\].
pub const MIN_GAP_S: f64 = 0.3;
/// Air samples lie at least this far from every contact \[s\].
pub const AIR_MARGIN_S: f64 = 0.2;
/// A stretch of air shorter than this gives no anchor \[s\].
pub const MIN_AIR_S: f64 = 0.3;
/// A long stretch of air is cut into pieces of at most this long, one anchor each \[s\].
pub const ANCHOR_S: f64 = 2.0;
/// An anchor farther than this from the first air vector is no air \[N\]: a hand's load moves
/// by a few newtons, a light contact held still would move it by more.
pub const MAX_DRIFT_N: f64 = 6.0;
/// A baseline whose anchors all lie within this of zero \[N\] is no load.
pub const MIN_LOAD_N: f64 = 0.5;
/// Air is away from the surface: an anchor's stretch lies at least this far from the nearest
/// contact's mean position along that contact's force \[m\]. A light slide before a firm press
/// has the force level of a hand's load, but it stays on the surface.
pub const AIR_LIFT_M: f64 = 0.005;

/// The in-air load found in a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct AirLoad {
    /// The anchors: a time \[s\] and the air's force vector there \[N\], in time order.
    pub anchors: Vec<(f64, Vector3<f64>)>,
}

impl AirLoad {
    /// The load at time `t_s`: the line through the anchors, held beyond the first and last.
    pub fn at(&self, t_s: f64) -> Vector3<f64> {
        let anchors = &self.anchors;
        match anchors.iter().position(|(t, _)| *t > t_s) {
            None => anchors.last().map_or_else(Vector3::zeros, |(_, v)| *v),
            Some(0) => anchors[0].1,
            Some(k) => {
                let ((t0, v0), (t1, v1)) = (anchors[k - 1], anchors[k]);
                let u = if t1 > t0 { (t_s - t0) / (t1 - t0) } else { 0.0 };
                v0 + (v1 - v0) * u
            }
        }
    }

    /// The largest load \[N\].
    pub fn largest_n(&self) -> f64 {
        self.anchors.iter().map(|(_, v)| v.norm()).fold(0.0, f64::max)
    }

    /// How far the load moves over the recording: the largest distance between two anchors \[N\].
    pub fn drift_n(&self) -> f64 {
        let mut drift: f64 = 0.0;
        for (i, (_, a)) in self.anchors.iter().enumerate() {
            for (_, b) in &self.anchors[i + 1..] {
                drift = drift.max((a - b).norm());
            }
        }
        drift
    }
}

/// The in-air load of a recording with times `t_s`, tool positions `position_m` and forces
/// `force_n`, or `None` when it holds none worth removing (module docs).
pub fn air_load(t_s: &[f64], position_m: &[Vector3<f64>], force_n: &[Vector3<f64>]) -> Option<AirLoad> {
    let n = t_s.len().min(force_n.len()).min(position_m.len());
    let ok = live_samples(&force_n[..n]);
    if ok.iter().filter(|&&ok| ok).count() < 10 {
        return None;
    }
    let smooth = smoothed(&t_s[..n], &force_n[..n], &ok);
    let first = initial_air(&smooth, &ok)?;
    let mut load = AirLoad {
        anchors: vec![(t_s[0], first)],
    };
    // Only stretches of air found as such are evidence of a load: a recording that is all
    // contact (a tap) or holds no contact keeps its force as read.
    let mut found_air = false;
    for _ in 0..ITERATIONS {
        let d: Vec<f64> = (0..n).map(|k| (smooth[k] - load.at(t_s[k])).norm()).collect();
        let Some(levels) = Levels::of(&d, &ok) else {
            break;
        };
        let contacts = contacts(&t_s[..n], &d, &ok, &levels);
        let surfaces: Vec<Surface> = contacts
            .iter()
            .map(|&(s, e)| Surface::of(&position_m[s..e], &smooth[s..e], (t_s[s], t_s[e - 1])))
            .collect();
        let anchors = anchors(
            &t_s[..n],
            &position_m[..n],
            &smooth,
            &d,
            &ok,
            (&contacts, &surfaces),
            &levels,
            first,
        );
        if anchors.is_empty() {
            break;
        }
        found_air = true;
        load.anchors = anchors;
    }
    (found_air && load.largest_n() >= MIN_LOAD_N).then_some(load)
}

/// Whether each sample is live: finite and not inside a run of [`FROZEN_RUN`] equal non-zero
/// vectors.
fn live_samples(force_n: &[Vector3<f64>]) -> Vec<bool> {
    let n = force_n.len();
    let mut ok: Vec<bool> = force_n.iter().map(|f| f.iter().all(|x| x.is_finite())).collect();
    let mut start = 0;
    while start < n {
        let mut end = start + 1;
        while end < n && force_n[end] == force_n[start] {
            end += 1;
        }
        // Exact zeros are a noise-free recording's air (a generated one), not a stale reading.
        if end - start >= FROZEN_RUN && force_n[start] != Vector3::zeros() {
            ok[start..end].iter_mut().for_each(|live| *live = false);
        }
        start = end;
    }
    ok
}

/// The force averaged over the live samples within [`SMOOTH_S`]/2 of each sample (in time, so
/// that irregular sampling does not change the window).
fn smoothed(t_s: &[f64], force_n: &[Vector3<f64>], ok: &[bool]) -> Vec<Vector3<f64>> {
    let n = t_s.len();
    let mut sum = vec![Vector3::zeros(); n + 1];
    let mut count = vec![0usize; n + 1];
    for k in 0..n {
        let live = ok[k];
        sum[k + 1] = sum[k] + if live { force_n[k] } else { Vector3::zeros() };
        count[k + 1] = count[k] + usize::from(live);
    }
    let half = SMOOTH_S / 2.0;
    (0..n)
        .map(|k| {
            let lo = t_s.partition_point(|&t| t < t_s[k] - half);
            let hi = t_s.partition_point(|&t| t <= t_s[k] + half);
            let live = count[hi] - count[lo];
            if live == 0 {
                force_n[k]
            } else {
                (sum[hi] - sum[lo]) / live as f64
            }
        })
        .collect()
}

/// The component-wise median of the live samples whose force is among the lowest
/// [`INITIAL_SHARE`].
fn initial_air(smooth: &[Vector3<f64>], ok: &[bool]) -> Option<Vector3<f64>> {
    let mut norms: Vec<f64> = (0..smooth.len()).filter(|&k| ok[k]).map(|k| smooth[k].norm()).collect();
    if norms.is_empty() {
        return None;
    }
    norms.sort_by(f64::total_cmp);
    let cut = norms[((norms.len() - 1) as f64 * INITIAL_SHARE) as usize];
    let low: Vec<Vector3<f64>> = (0..smooth.len())
        .filter(|&k| ok[k] && smooth[k].norm() <= cut)
        .map(|k| smooth[k])
        .collect();
    Some(median_vector(&low))
}

/// The air and contact levels of the distances from the baseline.
struct Levels {
    /// Where a contact starts \[N\].
    enter: f64,
    /// Where it ends \[N\].
    leave: f64,
}

impl Levels {
    /// Otsu's split of the live distances into two levels; `None` when they are closer than
    /// [`MIN_CONTRAST_N`] (no contact).
    fn of(d: &[f64], ok: &[bool]) -> Option<Levels> {
        let live: Vec<f64> = d.iter().zip(ok).filter(|(_, ok)| **ok).map(|(d, _)| *d).collect();
        let threshold = otsu(&live)?;
        let (mut below, mut above): (Vec<f64>, Vec<f64>) = live.iter().partition(|&&d| d <= threshold);
        if below.is_empty() || above.is_empty() {
            return None;
        }
        let (air, contact) = (median(&mut below), median(&mut above));
        let span = contact - air;
        if span < MIN_CONTRAST_N {
            return None;
        }
        let enter = air + (0.5 * span).max(1.0);
        Some(Levels {
            enter,
            leave: (air + 0.25 * span).min(enter),
        })
    }
}

/// The threshold that best splits `values` into two classes (Otsu, over 256 bins).
fn otsu(values: &[f64]) -> Option<f64> {
    const BINS: usize = 256;
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi.is_nan() || hi <= lo {
        return None;
    }
    let width = (hi - lo) / BINS as f64;
    let mut histogram = [0usize; BINS];
    for &v in values {
        histogram[(((v - lo) / width) as usize).min(BINS - 1)] += 1;
    }
    let total = values.len() as f64;
    let centre = |bin: usize| lo + (bin as f64 + 0.5) * width;
    let sum_all: f64 = (0..BINS).map(|b| histogram[b] as f64 * centre(b)).sum();
    let (mut weight, mut sum, mut best, mut best_at) = (0.0, 0.0, -1.0, 0);
    for (bin, &count) in histogram.iter().enumerate().take(BINS - 1) {
        weight += count as f64;
        sum += count as f64 * centre(bin);
        if weight == 0.0 || weight == total {
            continue;
        }
        let (mean_low, mean_high) = (sum / weight, (sum_all - sum) / (total - weight));
        let between = weight * (total - weight) * (mean_low - mean_high).powi(2);
        if between > best {
            best = between;
            best_at = bin;
        }
    }
    Some(lo + (best_at + 1) as f64 * width)
}

/// The contacts: sample ranges `[start, end)` where `d` passes `enter` until it falls below
/// `leave` (a stretch of dead samples keeps the state), short gaps closed.
fn contacts(t_s: &[f64], d: &[f64], ok: &[bool], levels: &Levels) -> Vec<(usize, usize)> {
    let mut found: Vec<(usize, usize)> = Vec::new();
    let mut start = None;
    let mut last_live = 0;
    for k in 0..d.len() {
        if !ok[k] {
            continue;
        }
        match start {
            None if d[k] > levels.enter => start = Some(k),
            Some(s) if d[k] < levels.leave => {
                found.push((s, last_live + 1));
                start = None;
            }
            _ => {}
        }
        last_live = k;
    }
    if let Some(s) = start {
        found.push((s, last_live + 1));
    }
    let mut merged: Vec<(usize, usize)> = Vec::new();
    for (s, e) in found {
        if let Some(last) = merged.last_mut() {
            if t_s[s] - t_s[last.1 - 1] < MIN_GAP_S {
                last.1 = e;
                continue;
            }
        }
        merged.push((s, e));
    }
    // A short contact (a tap) is no phase, but it is no air either: it
    // stays, so that the air around it keeps its margin and no anchor sits on the tap.
    merged
}

/// Where a contact was: the tool's mean position, the force's mean direction, its times.
struct Surface {
    at: Vector3<f64>,
    normal: Vector3<f64>,
    span_s: (f64, f64),
}

impl Surface {
    fn of(position_m: &[Vector3<f64>], force_n: &[Vector3<f64>], span_s: (f64, f64)) -> Surface {
        let count = position_m.len().max(1) as f64;
        let at = position_m.iter().sum::<Vector3<f64>>() / count;
        let normal = force_n
            .iter()
            .sum::<Vector3<f64>>()
            .try_normalize(1e-9)
            .unwrap_or_else(Vector3::z);
        Surface { at, normal, span_s }
    }

    /// How far from this surface's contact `t_s` lies in time \[s\].
    fn apart_s(&self, t_s: f64) -> f64 {
        (self.span_s.0 - t_s).max(t_s - self.span_s.1).max(0.0)
    }
}

/// The anchors of the air between `contacts` (module docs, step 3).
#[allow(clippy::too_many_arguments)]
fn anchors(
    t_s: &[f64],
    position_m: &[Vector3<f64>],
    smooth: &[Vector3<f64>],
    d: &[f64],
    ok: &[bool],
    (contacts, surfaces): (&[(usize, usize)], &[Surface]),
    levels: &Levels,
    first: Vector3<f64>,
) -> Vec<(f64, Vector3<f64>)> {
    let n = t_s.len();
    let near_contact = |k: usize| {
        contacts
            .iter()
            .any(|&(s, e)| t_s[k] >= t_s[s] - AIR_MARGIN_S && t_s[k] <= t_s[e - 1] + AIR_MARGIN_S)
    };
    let air: Vec<bool> = (0..n).map(|k| ok[k] && !near_contact(k)).collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < n {
        if !air[k] {
            k += 1;
            continue;
        }
        let start = k;
        while k < n && air[k] {
            k += 1;
        }
        let (t0, t1) = (t_s[start], t_s[k - 1]);
        if t1 - t0 < MIN_AIR_S {
            continue;
        }
        let pieces = ((t1 - t0) / ANCHOR_S).ceil().max(1.0) as usize;
        let piece_s = (t1 - t0) / pieces as f64;
        for piece in 0..pieces {
            let (from, to) = (t0 + piece as f64 * piece_s, t0 + (piece + 1) as f64 * piece_s);
            let members: Vec<usize> = (start..k)
                .filter(|&j| t_s[j] >= from && (t_s[j] < to || (piece + 1 == pieces && t_s[j] <= to)))
                .collect();
            if members.is_empty() {
                continue;
            }
            let mut ds: Vec<f64> = members.iter().map(|&j| d[j]).collect();
            if median(&mut ds) > levels.leave {
                continue;
            }
            let vectors: Vec<Vector3<f64>> = members.iter().map(|&j| smooth[j]).collect();
            let vector = median_vector(&vectors);
            let positions: Vec<Vector3<f64>> = members.iter().map(|&j| position_m[j]).collect();
            let place = median_vector(&positions);
            let mid = 0.5 * (from + to);
            let off_surface = surfaces
                .iter()
                .min_by(|a, b| a.apart_s(mid).total_cmp(&b.apart_s(mid)))
                .is_none_or(|surface| (place - surface.at).dot(&surface.normal).abs() >= AIR_LIFT_M);
            if (vector - first).norm() <= MAX_DRIFT_N && off_surface {
                out.push((0.5 * (from + to), vector));
            }
        }
    }
    out
}

fn median_vector(vectors: &[Vector3<f64>]) -> Vector3<f64> {
    Vector3::from_fn(|axis, _| median(&mut vectors.iter().map(|v| v[axis]).collect::<Vec<_>>()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording at `rate` Hz: air with a load that drifts from `start` to `end`, and pushes of
    /// `push` N along -z over the given intervals, each with the load still on.
    fn recording(
        rate: f64,
        seconds: f64,
        start: Vector3<f64>,
        end: Vector3<f64>,
        pushes: &[(f64, f64)],
        push: f64,
    ) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let n = (rate * seconds) as usize;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / rate).collect();
        // On the surface (z = 0) while pushing, 5 cm above it otherwise, sliding along x.
        let p = t
            .iter()
            .map(|&t| {
                let pushing = pushes.iter().any(|&(a, b)| t >= a && t <= b);
                Vector3::new(0.01 * t, 0.0, if pushing { 0.0 } else { 0.05 })
            })
            .collect();
        let f = t
            .iter()
            .map(|&t| {
                let load = start + (end - start) * (t / seconds);
                let pushing = pushes.iter().any(|&(a, b)| t >= a && t <= b);
                let wobble = Vector3::new((7.0 * t).sin(), (5.0 * t).cos(), (3.0 * t).sin()) * 0.05;
                load + wobble
                    + if pushing {
                        Vector3::new(0.0, 0.0, -push)
                    } else {
                        Vector3::zeros()
                    }
            })
            .collect();
        (t, p, f)
    }

    #[test]
    fn a_drifting_load_between_contacts_is_followed() {
        let (start, end) = (Vector3::new(0.5, -0.3, 1.0), Vector3::new(2.5, 1.0, 4.0));
        let (t, p, f) = recording(100.0, 30.0, start, end, &[(4.0, 8.0), (12.0, 17.0), (22.0, 26.0)], 20.0);
        let load = air_load(&t, &p, &f).expect("a load");
        // Between contacts and inside them the line through the anchors is the load.
        for &at in &[2.0, 10.0, 15.0, 19.5, 28.0] {
            let truth = start + (end - start) * (at / 30.0);
            assert!(
                (load.at(at) - truth).norm() < 0.3,
                "at {at} s: {} vs {truth}",
                load.at(at)
            );
        }
        assert!(
            (load.drift_n() - (end - start).norm()).abs() < 1.0,
            "{}",
            load.drift_n()
        );
    }

    #[test]
    fn no_load_and_no_contact_give_nothing() {
        let zero = Vector3::zeros();
        let (t, p, f) = recording(1000.0, 10.0, zero, zero, &[(3.0, 6.0)], 10.0);
        assert_eq!(air_load(&t, &p, &f), None, "a debiased recording has no load to remove");
        let (t, p, f) = recording(
            100.0,
            10.0,
            Vector3::new(0.0, 0.0, 3.0),
            Vector3::new(0.0, 0.0, 3.0),
            &[],
            0.0,
        );
        // A constant force with no contact: no contrast, so no air found as such (the bias
        // step, not this one, removes a constant offset).
        assert_eq!(air_load(&t, &p, &f), None);
        // All contact, no air: a tap of 0.13 s at 1 kHz keeps its force.
        let t: Vec<f64> = (0..126).map(|k| f64::from(k) / 1000.0).collect();
        let p = vec![Vector3::zeros(); 126];
        let f: Vec<Vector3<f64>> = (0..126)
            .map(|k| Vector3::new(0.0, 0.0, 5.0 * (f64::from(k) / 25.0).min(1.0)))
            .collect();
        assert_eq!(air_load(&t, &p, &f), None);
    }

    #[test]
    fn a_light_slide_before_a_firm_press_is_contact_not_air() {
        // 5 N sliding on the surface, then 15 N pressing: the slide has a hand's load's level.
        let rate = 500.0;
        let n = (rate * 12.0) as usize;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / rate).collect();
        let on_surface = |t: f64| (2.0..=9.0).contains(&t);
        let p: Vec<Vector3<f64>> = t
            .iter()
            .map(|&t| Vector3::new(0.02 * t, 0.0, if on_surface(t) { 0.0 } else { 0.05 }))
            .collect();
        let f: Vec<Vector3<f64>> = t
            .iter()
            .map(|&t| {
                let push = if (6.0..=9.0).contains(&t) {
                    15.0
                } else if on_surface(t) {
                    5.0
                } else {
                    0.0
                };
                Vector3::new(0.02 * (11.0 * t).sin(), 0.0, push + 0.02 * (7.0 * t).cos())
            })
            .collect();
        assert_eq!(air_load(&t, &p, &f), None, "the slide's 5 N stays in the recording");
    }

    #[test]
    fn frozen_stretches_give_no_anchor() {
        let (start, end) = (Vector3::new(0.0, 0.0, 2.0), Vector3::new(0.0, 0.0, 4.0));
        let (t, p, mut f) = recording(100.0, 20.0, start, end, &[(5.0, 9.0), (13.0, 16.0)], 15.0);
        // The sensor froze at 12.7 N for a second in the air.
        for value in &mut f[1000..1100] {
            *value = Vector3::new(0.0, 0.0, 12.7);
        }
        let load = air_load(&t, &p, &f).expect("a load");
        assert!(
            (load.at(10.5) - (start + (end - start) * (10.5 / 20.0))).norm() < 0.3,
            "{}",
            load.at(10.5)
        );
    }
}

//! Contact phases: the stretches of a demonstration in which the tool is pushed, found from the
//! debiased force against its own noise, with hysteresis (docs/method.md §3, "Contact phases").
//!
//! A person wiping a part three times lifts the tool between the passes; a template that expects
//! one contact (the wipe's approach, contact, leave) must not learn one segment across all three.
//! The phases found here say how many contacts a recording holds, where each one starts and
//! ends (its onset and release, estimated from the rise and fall of the force, not from the
//! threshold crossing), and give the window of first firm contact that frames at a point use.
//!
//! 1. The force noise `σ` is the median over the three axes of `1.4826 · MAD(Δf) / √2` (first
//!    differences: a bias or a slow load does not count as noise).
//! 2. The force magnitude is averaged over a centred window of [`SMOOTH_S`] (at least 3 samples).
//!    A phase switches on where it exceeds `on = max(8 σ, 1 N)` and off where it falls below
//!    `off = on / 2`; phases shorter than [`MIN_PHASE_S`] are dropped, and gaps shorter than
//!    [`MIN_GAP_S`] are closed.
//! 3. A phase's onset is where its force left zero: along the phase's mean force direction the
//!    rise up to 70 % of the phase's median is fitted by `a · shape(t − t₀)` over three
//!    families of rise shapes (powers, minimum-jerk steps, first-order approaches), `t₀` on
//!    every sample of the second before the crossing; the release likewise, mirrored.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::demo::Demo;

/// Width of the centred moving average on the force magnitude \[s\].
pub const SMOOTH_S: f64 = 0.02;
/// A phase switches on at this many noise deviations (and at least [`MIN_ON_N`]).
pub const ON_FACTOR: f64 = 8.0;
/// The on-threshold is never below this \[N\].
pub const MIN_ON_N: f64 = 1.0;
/// Phases shorter than this are not contact phases \[s\].
pub const MIN_PHASE_S: f64 = 0.08;
/// Gaps shorter than this between two phases are closed \[s\].
pub const MIN_GAP_S: f64 = 0.15;
/// How far before the threshold crossing an onset is looked for \[s\].
const ONSET_SEARCH_S: f64 = 1.0;
/// The powers of the onset shape `(t − t₀)₊ᵖ`.
const ONSET_POWERS: [f64; 8] = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0];
/// The durations of the minimum-jerk and first-order onset shapes: this many, spaced
/// geometrically from [`RISE_SHORTEST_S`] to [`RISE_LONGEST_S`].
const RISE_DURATIONS: usize = 24;
/// The shortest rise the onset shapes describe \[s\].
const RISE_SHORTEST_S: f64 = 0.03;
/// The longest rise the onset shapes describe \[s\].
const RISE_LONGEST_S: f64 = 3.0;
/// The onset fit uses at most about this many samples of the rise (every k-th of a long one).
const ONSET_FIT_SAMPLES: usize = 300;
/// The onset fit covers the rise up to this share of the phase's median force.
const ONSET_LEVEL: f64 = 0.7;
/// The first in-contact window starts this long after the on-threshold crossing \[s\].
pub const WINDOW_START_S: f64 = 0.02;
/// ... and ends this long after it \[s\].
pub const WINDOW_END_S: f64 = 0.12;
/// The first in-contact window is timed from where the force reaches this share of the phase's median.
const FIRM_SHARE: f64 = 0.33;
/// The baseline before an onset is averaged over this long \[s\].
const BASELINE_S: f64 = 0.3;
/// The window holds at least this many samples (at 100 Hz, 20-50 ms is three).
const WINDOW_MIN_SAMPLES: usize = 5;

/// One contact phase, sample indices into the demonstration it was found in.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactPhase {
    /// First sample over the on-threshold.
    pub on: usize,
    /// One past the last sample over the off-threshold.
    pub off: usize,
    /// The estimated onset: the sample where the force left zero (`≤ on`).
    pub onset: usize,
    /// The estimated release: the first sample back at zero (`≥ off`, `≤ len`).
    pub release: usize,
    /// Median force magnitude over `on..off` \[N\].
    pub median_n: f64,
    /// Largest force magnitude \[N\].
    pub peak_n: f64,
}

impl ContactPhase {
    /// Duration from onset to release in `demo` \[s\].
    pub fn duration_s(&self, demo: &Demo) -> f64 {
        demo.t_s[self.release.min(demo.len()) - 1] - demo.t_s[self.onset]
    }
}

/// The phases of a demonstration and the thresholds that found them.
#[derive(Debug, Clone, PartialEq)]
pub struct Phases {
    /// In time order.
    pub phases: Vec<ContactPhase>,
    /// Force noise per axis \[N\].
    pub noise_n: f64,
    /// On-threshold \[N\].
    pub on_n: f64,
    /// Off-threshold \[N\].
    pub off_n: f64,
}

impl Phases {
    /// The longest phase (onset to release), 0-based; `None` without phases.
    pub fn longest(&self, demo: &Demo) -> Option<usize> {
        (0..self.phases.len()).max_by(|&a, &b| {
            self.phases[a]
                .duration_s(demo)
                .total_cmp(&self.phases[b].duration_s(demo))
                .then(b.cmp(&a))
        })
    }

    /// The phases as `4.10-13.20 s, 15.00-22.40 s`.
    pub fn describe(&self, demo: &Demo) -> String {
        self.phases
            .iter()
            .map(|p| {
                format!(
                    "{:.2}-{:.2} s",
                    demo.t_s[p.onset],
                    demo.t_s[p.release.min(demo.len()) - 1]
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Force noise per axis: the median over axes of the robust deviation of first differences.
pub fn force_noise_n(force_n: &[Vector3<f64>]) -> f64 {
    if force_n.len() < 3 {
        return 0.0;
    }
    let mut per_axis = [0.0; 3];
    for (axis, slot) in per_axis.iter_mut().enumerate() {
        let mut diffs: Vec<f64> = force_n.windows(2).map(|w| w[1][axis] - w[0][axis]).collect();
        let median = median_of(&mut diffs);
        let mut deviations: Vec<f64> = diffs.iter().map(|d| (d - median).abs()).collect();
        *slot = 1.4826 * median_of(&mut deviations) / std::f64::consts::SQRT_2;
    }
    median_of(&mut per_axis.to_vec())
}

/// The median of `values` (sorted in place): the mean of the middle two for an even count, 0 for
/// none.
pub(crate) fn median_of(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// Centred moving average of `values` over `half` samples each side (the window shrinks at the ends).
fn moving_average(values: &[f64], half: usize) -> Vec<f64> {
    let mut prefix = vec![0.0; values.len() + 1];
    for (k, v) in values.iter().enumerate() {
        prefix[k + 1] = prefix[k] + v;
    }
    (0..values.len())
        .map(|k| {
            let lo = k.saturating_sub(half);
            let hi = (k + half + 1).min(values.len());
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

fn samples_in(demo: &Demo, seconds: f64) -> usize {
    let rate = if demo.duration_s() > 0.0 {
        (demo.len() - 1) as f64 / demo.duration_s()
    } else {
        1.0
    };
    (seconds * rate).round().max(0.0) as usize
}

/// Finds the contact phases of a demonstration whose wrench is already debiased
/// ([`crate::demo::prepare`]).
pub fn contact_phases(demo: &Demo) -> Phases {
    let noise_n = force_noise_n(&demo.force_n);
    let on_n = (ON_FACTOR * noise_n).max(MIN_ON_N);
    let off_n = on_n / 2.0;
    let n = demo.len();
    let magnitude: Vec<f64> = demo.force_n.iter().map(|f| f.norm()).collect();
    let half = (samples_in(demo, SMOOTH_S) / 2).max(1);
    let smooth = moving_average(&magnitude, half);
    // Hysteresis.
    let mut raw: Vec<(usize, usize)> = Vec::new();
    let mut start = None;
    for (k, &f) in smooth.iter().enumerate() {
        match start {
            None if f > on_n => start = Some(k),
            Some(s) if f < off_n => {
                raw.push((s, k));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        raw.push((s, n));
    }
    // Close short gaps, then drop short phases.
    let mut merged: Vec<(usize, usize)> = Vec::new();
    for (s, e) in raw {
        if let Some(last) = merged.last_mut() {
            if demo.t_s[s] - demo.t_s[last.1.min(n - 1)] < MIN_GAP_S {
                last.1 = e;
                continue;
            }
        }
        merged.push((s, e));
    }
    let phases: Vec<ContactPhase> = merged
        .into_iter()
        .filter(|&(s, e)| demo.t_s[e - 1] - demo.t_s[s] >= MIN_PHASE_S)
        .map(|(on, off)| {
            let mut inside: Vec<f64> = magnitude[on..off].to_vec();
            let peak_n = inside.iter().copied().fold(0.0, f64::max);
            let median_n = median_of(&mut inside);
            ContactPhase {
                on,
                off,
                onset: on,
                release: off,
                median_n,
                peak_n,
            }
        })
        .collect();
    // Onsets and releases, each bounded by its neighbours.
    let mut located = phases.clone();
    for index in 0..phases.len() {
        let lower = if index == 0 { 0 } else { phases[index - 1].off };
        let upper = phases.get(index + 1).map_or(n, |p| p.on);
        let phase = &mut located[index];
        let direction = phase_direction(demo, phase);
        let along: Vec<f64> = demo.force_n.iter().map(|f| -f.dot(&direction)).collect();
        let along = moving_average(&along, half);
        let level = (ONSET_LEVEL * phase.median_n).max(on_n);
        phase.onset = edge(demo, &along, phase.on, lower, level, false);
        phase.release = edge(demo, &along, phase.off, upper, level, true);
    }
    Phases {
        phases: located,
        noise_n,
        on_n,
        off_n,
    }
}

/// The unit direction of the mean applied force over a phase (base z when it is zero).
fn phase_direction(demo: &Demo, phase: &ContactPhase) -> Vector3<f64> {
    let sum: Vector3<f64> = -demo.force_n[phase.on..phase.off].iter().sum::<Vector3<f64>>();
    sum.try_normalize(1e-12).unwrap_or_else(Vector3::z)
}

/// How a force leaves zero at `t₀`, as a function of the time since, up to its amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rise {
    /// `(t − t₀)ᵖ`: a ramp (`p = 1`) or a rise whose first derivatives vanish at the onset.
    Power(f64),
    /// The minimum-jerk step from rest to rest over this long: how a hand brings a force up.
    MinimumJerk(f64),
    /// `1 − e^(−(t − t₀)/τ)`: a first-order approach, as a compliant contact under a steady push.
    FirstOrder(f64),
}

impl Rise {
    /// Every shape the onset fit tries.
    fn all() -> impl Iterator<Item = Rise> {
        let ratio = (RISE_LONGEST_S / RISE_SHORTEST_S).powf(1.0 / (RISE_DURATIONS - 1) as f64);
        let durations = (0..RISE_DURATIONS).map(move |k| RISE_SHORTEST_S * ratio.powi(k as i32));
        ONSET_POWERS
            .into_iter()
            .map(Rise::Power)
            .chain(durations.clone().map(Rise::MinimumJerk))
            .chain(durations.map(Rise::FirstOrder))
    }

    /// The shape `since` seconds after the onset (zero before it).
    fn at(self, since: f64) -> f64 {
        if since <= 0.0 {
            return 0.0;
        }
        match self {
            Rise::Power(p) => since.powf(p),
            Rise::MinimumJerk(duration) => {
                let u = (since / duration).min(1.0);
                u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
            }
            Rise::FirstOrder(tau) => 1.0 - (-since / tau).exp(),
        }
    }
}

/// Where the force along the phase's direction left zero before `crossing` (`release`: where it
/// came back to zero after it), searched no farther than `bound`: the least-squares fit of
/// `a · shape(t − t₀)` (zero before `t₀`) to the samples from the search start to where the force
/// first reaches `level`, over every [`Rise`] shape; the best fit's `t₀`.
fn edge(demo: &Demo, along: &[f64], crossing: usize, bound: usize, level: f64, release: bool) -> usize {
    let n = along.len();
    let search = samples_in(demo, ONSET_SEARCH_S).max(2);
    // Index ranges in "time away from the contact" order, mapped back for a release.
    let (from, to) = if release {
        let crossing = crossing.min(n);
        (crossing, (crossing + search).min(bound.min(n)))
    } else {
        (crossing.saturating_sub(search).max(bound), crossing)
    };
    if to <= from + 2 {
        return crossing.min(n);
    }
    // The samples inside the contact up to `level`.
    let inner_end = if release {
        let mut k = crossing.min(n);
        while k > 0 && along[k - 1] < level && crossing - k < search {
            k -= 1;
        }
        k
    } else {
        let mut k = crossing;
        while k < n && along[k] < level && k - crossing < search {
            k += 1;
        }
        k
    };
    let window: Vec<usize> = if release {
        (inner_end..to).collect()
    } else {
        (from..inner_end.min(n)).collect()
    };
    if window.len() < 4 {
        return crossing.min(n);
    }
    // The force far from the contact (what debiasing left) is the model's zero.
    let quarter = window.len() / 4;
    let far: Vec<f64> = if release {
        window.iter().rev().take(quarter).map(|&k| along[k]).collect()
    } else {
        window.iter().take(quarter).map(|&k| along[k]).collect()
    };
    let zero = if far.is_empty() {
        0.0
    } else {
        far.iter().sum::<f64>() / far.len() as f64
    };
    // The force is averaged over 20 ms already: every k-th sample of a long rise says as much.
    let stride = (window.len() / ONSET_FIT_SAMPLES).max(1);
    // Time measured from the contact outwards is mirrored for a release so one fit serves both.
    let time = |k: usize| if release { -demo.t_s[k] } else { demo.t_s[k] };
    let fitted: Vec<(f64, f64)> = window
        .iter()
        .step_by(stride)
        .map(|&k| (time(k), along[k] - zero))
        .collect();
    let syy: f64 = fitted.iter().map(|(_, y)| y * y).sum();
    let candidates: Vec<usize> = if release {
        (crossing.min(n - 1)..to).collect()
    } else {
        (from..=crossing.min(n - 1)).collect()
    };
    let shapes: Vec<Rise> = Rise::all().collect();
    // The residual of the best shape with its least-squares amplitude, for an onset at `candidate`.
    let fit = |candidate: usize| -> f64 {
        let t0 = time(candidate);
        shapes
            .iter()
            .map(|&shape| {
                let (mut sxx, mut sxy) = (0.0, 0.0);
                for &(t, y) in &fitted {
                    let x = shape.at(t - t0);
                    sxx += x * x;
                    sxy += x * y;
                }
                if sxx > 1e-300 {
                    syy - sxy * sxy / sxx
                } else {
                    syy
                }
            })
            .fold(f64::INFINITY, f64::min)
    };
    // Coarse to fine over the candidates: every `step`-th, then every one around the best.
    let step = (candidates.len() / 100).max(1);
    let coarse = candidates
        .iter()
        .step_by(step)
        .map(|&c| (fit(c), c))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let Some((_, centre)) = coarse else {
        return crossing.min(n);
    };
    let (lo, hi) = (centre.saturating_sub(step), centre + step);
    let best = candidates
        .iter()
        .filter(|&&c| c >= lo && c <= hi)
        .map(|&c| (fit(c), c))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(centre, |(_, c)| c);
    if release {
        (best + 1).min(n)
    } else {
        best.min(n)
    }
}

/// The samples of a phase's first in-contact window: from [`WINDOW_START_S`] to
/// [`WINDOW_END_S`] past its on-threshold crossing, at least a few samples, within the phase.
pub fn first_contact_window(demo: &Demo, phase: &ContactPhase) -> std::ops::Range<usize> {
    // Firm contact: the force magnitude at a third of the phase's median (at least the on-threshold's crossing).
    let firm = (phase.on..phase.off)
        .find(|&k| demo.force_n[k].norm() >= FIRM_SHARE * phase.median_n)
        .unwrap_or(phase.on);
    let start = (firm + samples_in(demo, WINDOW_START_S)).min(phase.off.saturating_sub(1));
    let end = (firm + samples_in(demo, WINDOW_END_S)).max(start + WINDOW_MIN_SAMPLES);
    start..end.min(phase.off).max(start + 1)
}

/// The force the sensor read just before a phase's onset, from 300 ms (`BASELINE_S`) to 50 ms before
/// it (what debiasing left, or a hand's load), `None` when the onset is too near the start.
pub fn baseline_before(demo: &Demo, phase: &ContactPhase) -> Option<Vector3<f64>> {
    let end = phase.onset.checked_sub(samples_in(demo, 0.05))?;
    let start = phase.onset.checked_sub(samples_in(demo, BASELINE_S))?;
    (end > start + 2).then(|| demo.force_n[start..end].iter().sum::<Vector3<f64>>() / (end - start) as f64)
}

/// The part of a demonstration around one phase: from the middle of the gap before it (or the
/// start) to the middle of the gap after it (or the end), as a range of samples.
pub fn phase_window(phases: &[ContactPhase], index: usize, len: usize) -> std::ops::Range<usize> {
    let phase = &phases[index];
    let start = if index == 0 {
        0
    } else {
        let before = &phases[index - 1];
        (before.release + phase.onset) / 2
    };
    let end = phases
        .get(index + 1)
        .map_or(len, |after| (phase.release + after.onset).div_ceil(2));
    start..end.max(start + 1).min(len)
}

/// A copy of `demo` holding the samples of `range` (times kept as they were).
pub fn crop(demo: &Demo, range: std::ops::Range<usize>) -> Demo {
    Demo {
        source: demo.source.clone(),
        t_s: demo.t_s[range.clone()].to_vec(),
        position_m: demo.position_m[range.clone()].to_vec(),
        orientation: demo.orientation[range.clone()].to_vec(),
        force_n: demo.force_n[range.clone()].to_vec(),
        torque_nm: demo.torque_nm[range].to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;

    fn demo_with(force: impl Fn(f64) -> f64, seconds: f64, rate: f64) -> Demo {
        let n = (seconds * rate) as usize;
        let mut state = 7u64;
        let mut noise = move || {
            // A small deterministic noise: two uniform draws summed.
            let mut u = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            (u() + u()) * 0.3
        };
        let t_s: Vec<f64> = (0..n).map(|k| k as f64 / rate).collect();
        Demo {
            source: "test".into(),
            position_m: vec![Vector3::zeros(); n],
            orientation: vec![UnitQuaternion::identity(); n],
            force_n: t_s
                .iter()
                .map(|&t| Vector3::new(noise(), noise(), -force(t) + noise()))
                .collect(),
            torque_nm: vec![Vector3::zeros(); n],
            t_s,
        }
    }

    #[test]
    fn three_passes_are_three_phases_with_onsets_near_the_truth() {
        let pass = |t: f64, a: f64, b: f64| {
            if t < a || t > b {
                0.0
            } else {
                10.0 * ((t - a) / 0.1).min(1.0) * ((b - t) / 0.1).min(1.0)
            }
        };
        let demo = demo_with(
            |t| pass(t, 1.0, 3.0) + pass(t, 4.0, 7.0) + pass(t, 8.0, 9.0),
            10.0,
            500.0,
        );
        let found = contact_phases(&demo);
        assert_eq!(found.phases.len(), 3, "{found:?}");
        let truth = [(1.0, 3.0), (4.0, 7.0), (8.0, 9.0)];
        for (phase, (a, b)) in found.phases.iter().zip(truth) {
            assert!(
                (demo.t_s[phase.onset] - a).abs() < 0.03,
                "onset {} for {a}",
                demo.t_s[phase.onset]
            );
            assert!(
                (demo.t_s[phase.release - 1] - b).abs() < 0.03,
                "release {} for {b}",
                demo.t_s[phase.release - 1]
            );
            assert!((phase.median_n - 10.0).abs() < 0.5);
        }
        assert_eq!(found.longest(&demo), Some(1));
        let window = phase_window(&found.phases, 1, demo.len());
        assert!(window.start > found.phases[0].release && window.end < found.phases[2].onset);
    }

    #[test]
    fn smooth_rises_have_their_onsets_where_the_force_left_zero() {
        // A threshold crossing lies 150-300 ms inside these contacts; a power law alone put the
        // minimum-jerk onset about 40 ms late.
        let minimum_jerk = |u: f64| {
            let u = u.clamp(0.0, 1.0);
            u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
        };
        let first_order = |since: f64| 1.0 - (-since.max(0.0) / 0.15).exp();
        type Force = Box<dyn Fn(f64) -> f64>;
        let cases: [(&str, Force, f64, f64); 2] = [
            (
                "minimum jerk over 0.9 s",
                Box::new(move |t| 8.0 * (minimum_jerk((t - 2.0) / 0.9) - minimum_jerk((t - 4.0) / 0.9))),
                2.0,
                4.9,
            ),
            (
                "first order, τ = 0.15 s",
                Box::new(move |t| 8.0 * first_order(t - 2.0).min(first_order(4.5 - t))),
                2.0,
                4.5,
            ),
        ];
        for (name, force, onset, release) in cases {
            let demo = demo_with(force, 7.0, 1000.0);
            let found = contact_phases(&demo);
            assert_eq!(found.phases.len(), 1, "{name}: {found:?}");
            let phase = found.phases[0];
            let (got_onset, got_release) = (demo.t_s[phase.onset], demo.t_s[phase.release - 1]);
            assert!(
                (got_onset - onset).abs() < 0.025,
                "{name}: onset {got_onset} for {onset}"
            );
            assert!(
                (got_release - release).abs() < 0.025,
                "{name}: release {got_release} for {release}"
            );
        }
    }

    #[test]
    fn a_dip_shorter_than_the_gap_does_not_split_a_phase() {
        let demo = demo_with(
            |t| {
                if (2.0..6.0).contains(&t) && !(4.0..4.05).contains(&t) {
                    8.0
                } else {
                    0.0
                }
            },
            8.0,
            1000.0,
        );
        assert_eq!(contact_phases(&demo).phases.len(), 1);
    }

    #[test]
    fn noise_alone_is_no_phase() {
        let demo = demo_with(|_| 0.0, 5.0, 100.0);
        let found = contact_phases(&demo);
        assert!(found.phases.is_empty(), "{found:?}");
        assert!(found.noise_n > 0.1 && found.noise_n < 0.4, "noise {}", found.noise_n);
    }
}

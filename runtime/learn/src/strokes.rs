//! Cutting a contact phase into strokes: where its main direction of travel reverses (a
//! back-and-forth wipe's strokes, a circular wipe's half circles), found with hysteresis so
//! that tremor and sensor noise do not count as reversals.
//!
//! The main direction is the principal axis of the positions (the eigenvector of their
//! covariance with the largest eigenvalue). Along it the path is a signal `s(t)`; a reversal is
//! a turning point of `s` from which it moves back by more than a share of its whole range
//! ([`REVERSAL_SHARE`]), the "zigzag" rule of swing analysis. A circle's projection on its
//! principal axis is a sine, so a circular wipe turns twice a revolution, at the ends of that
//! axis.

use std::ops::Range;

use nalgebra::{Matrix3, Vector3};

/// How far, as a share of the whole range of travel along the main direction, the path must
/// come back from a turning point for it to count as a reversal. A hand-guided stroke covers
/// most of the range; a correction in mid-stroke or a wobble at a turn covers a few per cent.
pub const REVERSAL_SHARE: f64 = 0.25;

/// Travel along the main direction below which a phase is one stroke \[m\]: a millimetre is
/// within the tracking error of a compliant arm, not a stroke.
pub const MIN_TRAVEL_M: f64 = 1e-3;

/// The strokes of `positions` sampled at `t_s`: consecutive index ranges covering all of it,
/// each sharing its turning sample with the next (stroke `i` ends where stroke `i + 1` begins).
/// Strokes shorter than `min_length_s` are merged: a short first or last one into its
/// neighbour, a short one inside with both neighbours (so that strokes still alternate in
/// direction). One range (`0..n`) when the path never reverses.
pub fn find_strokes(t_s: &[f64], positions: &[Vector3<f64>], min_length_s: f64) -> Vec<Range<usize>> {
    let n = positions.len().min(t_s.len());
    if n < 3 {
        return whole(n);
    }
    let along = principal_axis(&positions[..n]);
    let s: Vec<f64> = positions[..n].iter().map(|p| p.dot(&along)).collect();
    let (lo, hi) = s.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    let range = hi - lo;
    if range.is_nan() || range < MIN_TRAVEL_M {
        return whole(n);
    }
    let mut turns = turning_points(&s, REVERSAL_SHARE * range);
    merge_short(&mut turns, t_s, n, min_length_s);
    bounds(&turns, n).windows(2).map(|w| w[0]..w[1] + 1).collect()
}

/// The first sample, the turning points and the last sample of `n`, in order: the ends of the
/// strokes.
fn bounds(turns: &[usize], n: usize) -> Vec<usize> {
    let mut bounds = Vec::with_capacity(turns.len() + 2);
    bounds.push(0);
    bounds.extend_from_slice(turns);
    bounds.push(n - 1);
    bounds
}

/// One stroke over all `n` samples.
fn whole(n: usize) -> Vec<Range<usize>> {
    std::iter::once(0..n).collect()
}

/// The unit direction of largest spread of `points` (any unit vector if they coincide).
fn principal_axis(points: &[Vector3<f64>]) -> Vector3<f64> {
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let covariance = points
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum::<Matrix3<f64>>();
    let eigen = covariance.symmetric_eigen();
    let largest = eigen.eigenvalues.imax();
    let axis = eigen.eigenvectors.column(largest).into_owned();
    if axis.norm() > 0.0 && axis.iter().all(|v| v.is_finite()) {
        axis.normalize()
    } else {
        Vector3::x()
    }
}

/// The turning points of `s`: indices of the extremes from which `s` comes back by more than
/// `hysteresis`, in order; highs and lows alternate. The path's first and last samples are not
/// turning points.
pub fn turning_points(s: &[f64], hysteresis: f64) -> Vec<usize> {
    #[derive(PartialEq)]
    enum Heading {
        Unknown,
        Up,
        Down,
    }
    let mut turns = Vec::new();
    let (mut high, mut low) = (0, 0);
    let mut heading = Heading::Unknown;
    for (k, &value) in s.iter().enumerate().skip(1) {
        if value > s[high] {
            high = k;
        }
        if value < s[low] {
            low = k;
        }
        if heading != Heading::Down && s[high] - value > hysteresis {
            // Came down from the high: the high was a turn if the path had been going up.
            if heading == Heading::Up {
                turns.push(high);
            }
            heading = Heading::Down;
            low = k;
        } else if heading != Heading::Up && value - s[low] > hysteresis {
            if heading == Heading::Down {
                turns.push(low);
            }
            heading = Heading::Up;
            high = k;
        }
    }
    turns
}

/// Removes turning points until every stroke between `0`, the turns and `n - 1` lasts at least
/// `min_length_s`: the shortest stroke first; at either end by dropping its one inner turn, in
/// the middle by dropping both of its turns (three strokes become one, going the same way).
fn merge_short(turns: &mut Vec<usize>, t_s: &[f64], n: usize, min_length_s: f64) {
    loop {
        let bounds = bounds(turns, n);
        let shortest = bounds
            .windows(2)
            .enumerate()
            .map(|(i, w)| (i, t_s[w[1]] - t_s[w[0]]))
            .filter(|(_, length)| *length < min_length_s)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((stroke, _)) = shortest else { return };
        if turns.is_empty() {
            return;
        }
        let last = bounds.len() - 2;
        if stroke == 0 {
            turns.remove(0);
        } else if stroke == last {
            turns.pop();
        } else {
            // Stroke `i` runs from turn `i - 1` to turn `i`.
            turns.drain(stroke - 1..=stroke);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// `count` strokes of `length_m` along `direction`, each taking `stroke_s` with a
    /// minimum-jerk profile, sampled at `rate_hz`, plus a sideways sway and Gaussian noise.
    fn back_and_forth(
        count: usize,
        length_m: f64,
        stroke_s: f64,
        rate_hz: f64,
        noise_m: f64,
    ) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<f64>) {
        let direction = Vector3::new(0.6, 0.8, 0.0);
        let side = Vector3::new(-0.8, 0.6, 0.0);
        let mut rng = SplitMix64::new(3);
        let total = count as f64 * stroke_s;
        let samples = (total * rate_hz) as usize + 1;
        let mut t_s = Vec::with_capacity(samples);
        let mut points = Vec::with_capacity(samples);
        for k in 0..samples {
            let t = k as f64 / rate_hz;
            let stroke = ((t / stroke_s) as usize).min(count - 1);
            let u = ((t - stroke as f64 * stroke_s) / stroke_s).clamp(0.0, 1.0);
            let progress = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
            let along = if stroke.is_multiple_of(2) {
                progress
            } else {
                1.0 - progress
            };
            let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * noise_m;
            let sway = side * (0.08 * length_m) * (std::f64::consts::PI * along).sin();
            t_s.push(t);
            points.push(Vector3::new(0.5, 0.0, 0.3) + direction * (length_m * along) + sway + noise);
        }
        let turns = (1..count).map(|i| i as f64 * stroke_s).collect();
        (t_s, points, turns)
    }

    #[test]
    fn a_back_and_forth_is_cut_at_its_reversals() {
        for (count, noise_m) in [(1, 0.0), (2, 0.0), (5, 0.0), (8, 2e-4)] {
            let (t_s, points, truth) = back_and_forth(count, 0.12, 0.8, 1000.0, noise_m);
            let strokes = find_strokes(&t_s, &points, 0.15);
            assert_eq!(strokes.len(), count, "{count} strokes, noise {noise_m}");
            assert_eq!(strokes[0].start, 0);
            assert_eq!(strokes.last().map(|r| r.end), Some(points.len()));
            for (pair, turn_s) in strokes.windows(2).zip(&truth) {
                assert_eq!(pair[0].end - 1, pair[1].start, "strokes share their turning sample");
                // A minimum-jerk stroke is flat at its ends: noise moves the turning sample a
                // little along the flat part.
                let found_s = t_s[pair[1].start];
                assert!((found_s - turn_s).abs() < 0.06, "turn at {found_s} s, truth {turn_s} s");
            }
        }
    }

    #[test]
    fn a_circle_turns_twice_a_revolution() {
        let rate_hz = 100.0;
        let period_s = 2.0;
        let (t_s, points): (Vec<f64>, Vec<Vector3<f64>>) = (0..=(3.0 * period_s * rate_hz) as usize)
            .map(|k| {
                let t = k as f64 / rate_hz;
                let phase = 2.0 * std::f64::consts::PI * t / period_s;
                (t, Vector3::new(0.05 * phase.cos(), 0.05 * phase.sin(), 0.3))
            })
            .collect();
        let strokes = find_strokes(&t_s, &points, 0.15);
        // Three revolutions starting at an end of the principal axis: six half circles.
        assert_eq!(strokes.len(), 6, "{strokes:?}");
        for stroke in &strokes {
            let length_s = t_s[stroke.end - 1] - t_s[stroke.start];
            assert!((length_s - 1.0).abs() < 0.1, "half circle of {length_s} s");
        }
    }

    #[test]
    fn short_strokes_are_merged_and_tiny_travel_is_one_stroke() {
        // A 1 mm-wide jitter is not a stroke.
        let (t_s, points, _) = back_and_forth(6, 0.5e-3, 0.5, 1000.0, 0.0);
        assert_eq!(find_strokes(&t_s, &points, 0.15).len(), 1);
        // Strokes of 0.1 s all fall under a 0.15 s minimum: merged until none is shorter.
        let (t_s, points, _) = back_and_forth(5, 0.05, 0.1, 1000.0, 0.0);
        let strokes = find_strokes(&t_s, &points, 0.15);
        assert!(strokes.len() < 5, "{strokes:?}");
        for stroke in &strokes {
            assert!(t_s[stroke.end - 1] - t_s[stroke.start] >= 0.15 - 1e-9);
        }
        // Degenerate inputs.
        assert_eq!(find_strokes(&[], &[], 0.1), vec![0..0]);
        assert_eq!(find_strokes(&[0.0, 1.0], &[Vector3::zeros(); 2], 0.1), vec![0..2]);
    }
}

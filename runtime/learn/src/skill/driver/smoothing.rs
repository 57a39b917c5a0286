//! Moving-average smoothing of force and position profiles before they are differentiated.

use nalgebra::Vector3;

/// Force profiles are smoothed over this window before a DMP is fitted to them: fitting
/// differentiates twice, and white sensor noise differentiated twice swamps the forcing term.
const FORCE_SMOOTHING_S: f64 = 0.04;

/// The moving-average window for samples at times `t` (odd, at least 1).
pub(super) fn smoothing_window(t: &[f64]) -> usize {
    let duration = t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0);
    let rate = if duration > 0.0 {
        (t.len() - 1) as f64 / duration
    } else {
        1.0
    };
    ((FORCE_SMOOTHING_S * rate).round() as usize) | 1
}

/// Two passes of a centred moving average of `window` samples (a triangular kernel); the
/// window shrinks at the ends so the ends are not pulled towards zero.
pub(super) fn smooth(values: &[f64], window: usize) -> Vec<f64> {
    let pass = |input: &[f64]| -> Vec<f64> {
        let n = input.len();
        let half = window / 2;
        let mut prefix = Vec::with_capacity(n + 1);
        prefix.push(0.0);
        for v in input {
            prefix.push(prefix[prefix.len() - 1] + v);
        }
        (0..n)
            .map(|k| {
                let reach = half.min(k).min(n - 1 - k);
                let (a, b) = (k - reach, k + reach + 1);
                (prefix[b] - prefix[a]) / (b - a) as f64
            })
            .collect()
    };
    pass(&pass(values))
}

pub(super) fn smooth_points(points: &[Vector3<f64>], window: usize) -> Vec<Vector3<f64>> {
    let channels: Vec<Vec<f64>> = (0..3)
        .map(|c| smooth(&points.iter().map(|p| p[c]).collect::<Vec<_>>(), window))
        .collect();
    (0..points.len())
        .map(|k| Vector3::new(channels[0][k], channels[1][k], channels[2][k]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothing_keeps_lines_and_removes_alternating_noise() {
        let line: Vec<f64> = (0..100).map(|k| 0.5 * k as f64).collect();
        let smoothed = smooth(&line, 9);
        for (a, b) in line.iter().zip(&smoothed) {
            assert!((a - b).abs() < 1e-9, "a line is kept exactly, ends included");
        }
        let noisy: Vec<f64> = (0..100).map(|k| if k % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let smoothed = smooth(&noisy, 9);
        assert!(smoothed[10..90].iter().all(|v| v.abs() < 0.05));
    }
}

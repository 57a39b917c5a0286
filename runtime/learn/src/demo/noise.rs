//! Estimating the white noise on a sampled signal from the residual of a local polynomial fit
//! (docs/method.md §1).

use nalgebra::Vector3;

/// `σ = 1.4826 · MAD` for normally distributed residuals.
const MAD_TO_SIGMA: f64 = 1.4826;

/// The standard deviation of the white noise on `values` sampled at times `t` (any spacing),
/// or `None` for fewer than five samples.
///
/// Every inner sample is predicted by the cubic through its two neighbours on each side
/// (leave-one-out) and the residual divided by its noise gain `√(1 + Σ wᵢ²)`, where `wᵢ` are the
/// cubic's interpolation weights; the estimate is `1.4826 × median |residual|`. The cubic is
/// exact for the smooth motion up to a term `x⁗ Δt⁴ / 6` (0.4 µm at 100 Hz for 2 Hz motion of
/// 10 cm amplitude), and the median ignores the few samples where the signal has a kink
/// (touch-down).
pub fn noise_std(t: &[f64], values: &[f64]) -> Option<f64> {
    let n = t.len().min(values.len());
    if n < 5 {
        return None;
    }
    let mut residuals: Vec<f64> = (2..n - 2)
        .map(|k| {
            let others = [k - 2, k - 1, k + 1, k + 2];
            let mut predicted = 0.0;
            let mut gain = 1.0;
            for &i in &others {
                let weight: f64 = others
                    .iter()
                    .filter(|&&j| j != i)
                    .map(|&j| (t[k] - t[j]) / (t[i] - t[j]))
                    .product();
                predicted += weight * values[i];
                gain += weight * weight;
            }
            ((values[k] - predicted) / gain.sqrt()).abs()
        })
        .collect();
    let mid = residuals.len() / 2;
    let (_, median, _) = residuals.select_nth_unstable_by(mid, f64::total_cmp);
    Some(MAD_TO_SIGMA * *median)
}

/// The position noise per axis \[m\]: the root mean square of the three axes' [`noise_std`].
pub fn position_noise_m(t: &[f64], positions: &[Vector3<f64>]) -> Option<f64> {
    let mut sum = 0.0;
    for axis in 0..3 {
        let channel: Vec<f64> = positions.iter().map(|p| p[axis]).collect();
        sum += noise_std(t, &channel)?.powi(2);
    }
    Some((sum / 3.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn the_noise_on_a_smooth_signal_is_found_at_any_spacing() {
        let mut rng = SplitMix64::new(3);
        for (rate_hz, jitter) in [(1000.0, 0.0), (100.0, 0.0), (100.0, 0.3)] {
            let t: Vec<f64> = (0..3000)
                .map(|k| (k as f64 + jitter * rng.range(-1.0, 1.0)) / rate_hz)
                .collect();
            let clean = |t: f64| 0.1 * (2.0 * std::f64::consts::PI * 0.5 * t).sin() + 0.02 * t * t;
            assert!(noise_std(&t, &t.iter().map(|&t| clean(t)).collect::<Vec<_>>()).expect("enough") < 1e-6);
            let noisy: Vec<f64> = t.iter().map(|&t| clean(t) + 2e-4 * rng.normal()).collect();
            let found = noise_std(&t, &noisy).expect("enough samples");
            assert!((found - 2e-4).abs() < 2e-5, "{rate_hz} Hz, jitter {jitter}: {found}");
        }
    }
}

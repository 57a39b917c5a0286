//! Zero-phase low-pass filtering (Butterworth sections run forwards and backwards).

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::{Demo, DemoError};

/// Order of the low-pass section; it runs forwards and backwards, which doubles the order,
/// squares the magnitude response (the cut-off is where the gain is 1/2) and cancels the phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FilterOrder {
    /// First-order section (bilinear transform of `1 / (1 + s/ωc)`).
    First,
    /// Second-order Butterworth section.
    #[default]
    Second,
}

/// Low-pass filters positions, orientations (per quaternion component, then renormalised, which
/// is accurate because the quaternions are sign-continuous and change little per sample), forces
/// and torques of `demo` with cut-off `cutoff_hz`, without phase lag.
///
/// Needs evenly spaced samples: the spacing may vary by at most 1 % around the mean.
pub fn low_pass(demo: &Demo, cutoff_hz: f64, order: FilterOrder) -> Result<Demo, DemoError> {
    let rate_hz = even_rate(demo)?;
    filter_even(demo, rate_hz, cutoff_hz, order, true)
}

/// Low-pass filters only the motion of `demo` (positions and orientations, as [`low_pass`]);
/// forces and torques are kept as they are. Any spacing: irregular samples are filtered on a
/// uniform grid at four times their mean rate (linear interpolation, slerp) and read back at
/// their own times by linear interpolation, which biases a smooth signal by `Δt² ẍ / 12` at most
/// (14 µm at 100 Hz and 2 m/s²).
pub fn low_pass_motion(demo: &Demo, cutoff_hz: f64, order: FilterOrder) -> Result<Demo, DemoError> {
    match even_rate(demo) {
        Ok(rate_hz) => filter_even(demo, rate_hz, cutoff_hz, order, false),
        Err(DemoError::IrregularSampling { .. }) => {
            let grid = super::resample(demo, 4.0 / demo.mean_dt_s())?;
            let grid_rate_hz = 4.0 / demo.mean_dt_s();
            let filtered = filter_even(&grid, grid_rate_hz, cutoff_hz, order, false)?;
            let mut out = demo.clone();
            let last = filtered.len() - 1;
            for (k, &t) in demo.t_s.iter().enumerate() {
                let x = (t - filtered.t_s[0]) * grid_rate_hz;
                let seg = (x.floor().max(0.0) as usize).min(last - 1);
                let u = x - seg as f64;
                let (a, b) = (seg, seg + 1);
                out.position_m[k] = filtered.position_m[a] + (filtered.position_m[b] - filtered.position_m[a]) * u;
                let coords = filtered.orientation[a].coords * (1.0 - u) + filtered.orientation[b].coords * u;
                out.orientation[k] = UnitQuaternion::from_quaternion(Quaternion::from(coords));
            }
            Ok(out)
        }
        Err(err) => Err(err),
    }
}

/// The rate of evenly spaced samples (every period within 1 % of the mean).
fn even_rate(demo: &Demo) -> Result<f64, DemoError> {
    if demo.len() < 3 {
        return Err(DemoError::TooFewSamples {
            file: demo.source.clone(),
            found: demo.len(),
            required: 3,
        });
    }
    let mean_dt = demo.mean_dt_s();
    let (mut min_dt, mut max_dt) = (f64::INFINITY, 0.0f64);
    for pair in demo.t_s.windows(2) {
        let dt = pair[1] - pair[0];
        min_dt = min_dt.min(dt);
        max_dt = max_dt.max(dt);
    }
    if max_dt > 1.01 * mean_dt || min_dt < 0.99 * mean_dt {
        return Err(DemoError::IrregularSampling {
            file: demo.source.clone(),
            min_dt_s: min_dt,
            max_dt_s: max_dt,
        });
    }
    Ok(1.0 / mean_dt)
}

/// Filters evenly spaced `demo`: the motion, and the wrench when `wrench` is set.
fn filter_even(demo: &Demo, rate_hz: f64, cutoff_hz: f64, order: FilterOrder, wrench: bool) -> Result<Demo, DemoError> {
    if !(cutoff_hz.is_finite() && cutoff_hz > 0.0 && cutoff_hz < 0.5 * rate_hz) {
        return Err(DemoError::InvalidParameter {
            name: "lowpass_cutoff_hz",
            value: cutoff_hz,
            reason: format!(
                "the cut-off must lie between 0 and the Nyquist rate {:.1} Hz",
                0.5 * rate_hz
            ),
        });
    }
    if demo.len() < 4 {
        // Too short to pad and filter: nothing to smooth (and `clamp` below needs 3 ≤ len − 1).
        return Ok(demo.clone());
    }
    let section = Biquad::low_pass(cutoff_hz, rate_hz, order);
    let pad = ((3.0 * rate_hz / cutoff_hz).ceil() as usize).clamp(3, demo.len() - 1);
    let mut scratch = Vec::with_capacity(demo.len() + 2 * pad);
    let mut channel = vec![0.0; demo.len()];
    let mut out = demo.clone();

    let mut filter_vectors = |values: &mut [Vector3<f64>]| {
        for axis in 0..3 {
            channel.iter_mut().zip(values.iter()).for_each(|(c, v)| *c = v[axis]);
            section.filtfilt(&mut channel, pad, &mut scratch);
            values.iter_mut().zip(&channel).for_each(|(v, c)| v[axis] = *c);
        }
    };
    filter_vectors(&mut out.position_m);
    if wrench {
        filter_vectors(&mut out.force_n);
        filter_vectors(&mut out.torque_nm);
    }
    let mut coords: Vec<nalgebra::Vector4<f64>> = out.orientation.iter().map(|q| q.coords).collect();
    for axis in 0..4 {
        channel.iter_mut().zip(&coords).for_each(|(c, q)| *c = q[axis]);
        section.filtfilt(&mut channel, pad, &mut scratch);
        coords.iter_mut().zip(&channel).for_each(|(q, c)| q[axis] = *c);
    }
    for (q, c) in out.orientation.iter_mut().zip(&coords) {
        *q = UnitQuaternion::from_quaternion(Quaternion::from(*c));
    }
    Ok(out)
}

/// A second-order IIR section in transposed direct form II.
#[derive(Debug, Clone, Copy)]
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
}

impl Biquad {
    fn low_pass(cutoff_hz: f64, rate_hz: f64, order: FilterOrder) -> Self {
        let k = (std::f64::consts::PI * cutoff_hz / rate_hz).tan();
        match order {
            FilterOrder::First => {
                let norm = 1.0 / (1.0 + k);
                Self {
                    b: [k * norm, k * norm, 0.0],
                    a: [(k - 1.0) * norm, 0.0],
                }
            }
            FilterOrder::Second => {
                let sqrt2 = std::f64::consts::SQRT_2;
                let norm = 1.0 / (1.0 + sqrt2 * k + k * k);
                let b0 = k * k * norm;
                Self {
                    b: [b0, 2.0 * b0, b0],
                    a: [2.0 * (k * k - 1.0) * norm, (1.0 - sqrt2 * k + k * k) * norm],
                }
            }
        }
    }

    /// Filters `x` in one direction, starting from the steady state for `x[0]`.
    fn run(&self, x: &mut [f64]) {
        let Some(&x0) = x.first() else { return };
        let mut z2 = (self.b[2] - self.a[1]) * x0;
        let mut z1 = (self.b[1] - self.a[0]) * x0 + z2;
        for value in x.iter_mut() {
            let input = *value;
            let output = self.b[0] * input + z1;
            z1 = self.b[1] * input - self.a[0] * output + z2;
            z2 = self.b[2] * input - self.a[1] * output;
            *value = output;
        }
    }

    /// Zero-phase filtering with odd extension by `pad` samples at both ends (as `filtfilt`).
    ///
    /// The extension is mirrored about a line fitted to the first (last) `pad / 3` samples
    /// evaluated at the end, not about the raw end sample: a plain odd extension pins the output
    /// to the (noisy) end sample.
    fn filtfilt(&self, x: &mut [f64], pad: usize, scratch: &mut Vec<f64>) {
        let n = x.len();
        let window = (pad / 3).clamp(2, n);
        let start_pivot = end_value(x[..window].iter().copied());
        let end_pivot = end_value(x[n - window..].iter().rev().copied());
        scratch.clear();
        scratch.extend((1..=pad).rev().map(|k| 2.0 * start_pivot - x[k]));
        scratch.extend_from_slice(x);
        scratch.extend((1..=pad).map(|k| 2.0 * end_pivot - x[n - 1 - k]));
        self.run(scratch);
        scratch.reverse();
        self.run(scratch);
        scratch.reverse();
        x.copy_from_slice(&scratch[pad..pad + n]);
    }
}

/// The value at index 0 of the least-squares line through `values` (indexed 0, 1, ...).
fn end_value(values: impl Iterator<Item = f64> + Clone) -> f64 {
    let (mut n, mut sum_i, mut sum_ii, mut sum_v, mut sum_iv) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (idx, value) in values.enumerate() {
        let i = idx as f64;
        n += 1.0;
        sum_i += i;
        sum_ii += i * i;
        sum_v += value;
        sum_iv += i * value;
    }
    let det = n * sum_ii - sum_i * sum_i;
    if det.abs() < 1e-12 {
        return sum_v / n.max(1.0);
    }
    (sum_ii * sum_v - sum_i * sum_iv) / det
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine_demo(rate_hz: f64, freqs_hz: &[(f64, f64)]) -> Demo {
        let n = (2.0 * rate_hz) as usize;
        let t_s: Vec<f64> = (0..n).map(|k| k as f64 / rate_hz).collect();
        let signal = |t: f64| {
            freqs_hz
                .iter()
                .map(|(f, a)| a * (2.0 * std::f64::consts::PI * f * t).sin())
                .sum::<f64>()
        };
        Demo {
            source: "synthetic".into(),
            position_m: t_s.iter().map(|&t| Vector3::new(signal(t), 0.0, 0.0)).collect(),
            orientation: t_s.iter().map(|_| UnitQuaternion::identity()).collect(),
            force_n: t_s.iter().map(|&t| Vector3::new(0.0, 0.0, 10.0 + signal(t))).collect(),
            torque_nm: t_s.iter().map(|_| Vector3::zeros()).collect(),
            t_s,
        }
    }

    #[test]
    fn low_pass_keeps_slow_signal_and_removes_fast_noise() {
        for (rate_hz, order) in [
            (100.0, FilterOrder::Second),
            (1000.0, FilterOrder::Second),
            (1000.0, FilterOrder::First),
        ] {
            let clean = sine_demo(rate_hz, &[(0.5, 1.0)]);
            let noisy = sine_demo(rate_hz, &[(0.5, 1.0), (40.0, 0.2)]);
            let filtered = low_pass(&noisy, 5.0, order).expect("valid cut-off");
            let n = clean.len();
            let rms = |range: std::ops::Range<usize>| {
                let len = range.len() as f64;
                (range
                    .map(|k| (clean.force_n[k] - filtered.force_n[k]).norm_squared())
                    .sum::<f64>()
                    / len)
                    .sqrt()
            };
            // 40 Hz at 0.2 with a 5 Hz cut-off: the second order (run twice) leaves < 0.2 * (5/40)^4
            // inside, the first order < 0.2 * (5/40)^2; the ends keep some of the end noise.
            // The first order also damps the 0.5 Hz signal by 1 %.
            let inside = if order == FilterOrder::First { 0.01 } else { 0.001 };
            let (rms_inside, rms_all) = (rms(n / 20..n - n / 20), rms(0..n));
            assert!(rms_inside < inside, "rate {rate_hz} {order:?}: rms inside {rms_inside}");
            assert!(rms_all < 0.012, "rate {rate_hz} {order:?}: rms {rms_all}");
        }
    }

    #[test]
    fn cutoff_above_nyquist_and_irregular_sampling_are_rejected() {
        let demo = sine_demo(100.0, &[(0.5, 1.0)]);
        assert!(matches!(
            low_pass(&demo, 60.0, FilterOrder::Second),
            Err(DemoError::InvalidParameter { .. })
        ));
        let mut irregular = demo.clone();
        irregular.t_s[10] += 0.004;
        assert!(matches!(
            low_pass(&irregular, 5.0, FilterOrder::Second),
            Err(DemoError::IrregularSampling { .. })
        ));
    }
}

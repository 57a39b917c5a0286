//! Gaussian basis functions in phase, centred evenly in time, and the forcing term they form.

use serde::{Deserialize, Serialize};

use super::exp::exp_in_place;

/// Bases whose log-value lies more than this below the largest one are treated as zero
/// (relative weight below `exp(−25)` ≈ `1.4e-11`).
pub(crate) const LOG_CUTOFF: f64 = 25.0;

/// The Gaussian bases `ψᵢ(s) = exp(−hᵢ (s − cᵢ)²)` of a DMP (see the [module docs](super)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Basis {
    /// Centres `cᵢ` in phase, decreasing from 1 to `exp(−α_s)`.
    pub centers: Vec<f64>,
    /// Inverse widths `hᵢ`.
    pub widths: Vec<f64>,
    /// Decay rate of the canonical system the centres were placed for.
    pub alpha_s: f64,
}

/// The bases that matter at one phase: `values[k]` is `ψ_{first+k}(s) · exp(−log_scale)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    pub(crate) first: usize,
    pub(crate) len: usize,
    pub(crate) log_scale: f64,
}

impl Basis {
    /// `n_basis` bases evenly spaced in time over `[0, τ]` for decay rate `alpha_s`.
    pub fn new(n_basis: usize, alpha_s: f64, width_factor: f64) -> Self {
        let n = n_basis.max(2);
        let centers: Vec<f64> = (0..n).map(|i| (-alpha_s * i as f64 / (n - 1) as f64).exp()).collect();
        let widths = (0..n)
            .map(|i| {
                let spacing = if i + 1 < n {
                    centers[i] - centers[i + 1]
                } else {
                    centers[i - 1] - centers[i]
                };
                width_factor / (spacing * spacing)
            })
            .collect();
        Self {
            centers,
            widths,
            alpha_s,
        }
    }

    /// Number of bases.
    pub fn len(&self) -> usize {
        self.centers.len()
    }

    /// True when there are no bases.
    pub fn is_empty(&self) -> bool {
        self.centers.is_empty()
    }

    /// Evaluates the non-negligible bases at phase `s` into `out[first..first + len]` (`out`
    /// needs [`Basis::len`] entries), scaled by `exp(−log_scale)`. Allocation-free.
    pub(crate) fn eval(&self, s: f64, out: &mut [f64]) -> Window {
        let n = self.len();
        let u = if s > 0.0 {
            -s.ln() / self.alpha_s * (n - 1) as f64
        } else {
            (n - 1) as f64
        };
        self.eval_near(s, u, out)
    }

    /// True once phase `s` has passed the last centre, the demonstration's end. A rollout
    /// drops its learned term there (`f(s) − (g − x₀) s`) and settles on its goal as the
    /// critically damped spring it is. The bases were fitted on phases from 1 down to the last
    /// centre only; below it the normalised blend hands over to the last basis alone, and even
    /// the blend at the end is mostly edge effect: the fit reads `f / s` with `s` down to
    /// `exp(−α_s)`, so the noise of the last samples' second derivative is amplified a
    /// hundredfold into the last weights. A press's force profile fitted to 0.56 N RMS rose to
    /// 168 N just past its end when the blend was extrapolated, and still to 72 N when it was
    /// held at its end value and faded over 5 % of `τ`. On a clean fit the term is near zero at
    /// the end (the demonstration ends at its goal, at rest), so dropping it changes nothing.
    pub(crate) fn ended(&self, s: f64) -> bool {
        self.centers.last().is_some_and(|&end| s < end)
    }

    /// As [`Basis::eval`], with the caller supplying `u = t / τ · (N − 1)`, the fractional
    /// index of the basis centred at this phase (saves a logarithm when the time is known).
    pub(crate) fn eval_near(&self, s: f64, u: f64, out: &mut [f64]) -> Window {
        let n = self.len();
        let log_value = |i: usize| -self.widths[i] * (s - self.centers[i]).powi(2);
        let centre = (u.round().max(0.0) as usize).min(n - 1);
        // Values are scaled relative to the basis nearest in time, which is within a factor
        // `exp(width_factor / 4)` of the largest one: no underflow, and a single pass. The
        // window's log-values are found first and exponentiated together (vectorised).
        let log_scale = log_value(centre);
        out[centre] = 0.0;
        let mut first = centre;
        while first > 0 {
            let value = log_value(first - 1) - log_scale;
            if value < -LOG_CUTOFF {
                break;
            }
            first -= 1;
            out[first] = value;
        }
        let mut end = centre + 1;
        while end < n {
            let value = log_value(end) - log_scale;
            if value < -LOG_CUTOFF {
                break;
            }
            out[end] = value;
            end += 1;
        }
        exp_in_place(&mut out[first..end]);
        Window {
            first,
            len: end - first,
            log_scale,
        }
    }

    /// The forcing term `Σ wᵢ ψᵢ(s) / Σ ψᵢ(s) · s`, using `scratch`; returns 0 when `weights`
    /// or `scratch` have fewer than [`Basis::len`] entries, and past the last centre, where a
    /// rollout drops it (the demonstration ends there; see the rollouts).
    pub fn forcing(&self, weights: &[f64], s: f64, scratch: &mut [f64]) -> f64 {
        if weights.len() < self.len()
            || scratch.len() < self.len()
            || self.widths.len() != self.len()
            || self.is_empty()
        {
            return 0.0;
        }
        if self.ended(s) {
            return 0.0;
        }
        let window = self.eval(s, scratch);
        let range = window.first..window.first + window.len;
        let (num, den) = scratch[range.clone()]
            .iter()
            .zip(&weights[range])
            .fold((0.0, 0.0), |(num, den), (psi, w)| (num + psi * w, den + psi));
        num / den * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_matches_full_evaluation() {
        let basis = Basis::new(50, 100f64.ln(), 1.0);
        let mut out = vec![0.0; 50];
        for k in 0..=200 {
            let s = (-(100f64.ln()) * k as f64 / 150.0).exp();
            let window = basis.eval(s, &mut out);
            let full: Vec<f64> = (0..50)
                .map(|i| (-basis.widths[i] * (s - basis.centers[i]).powi(2)).exp())
                .collect();
            let full_sum: f64 = full.iter().sum();
            let window_sum: f64 =
                out[window.first..window.first + window.len].iter().sum::<f64>() * window.log_scale.exp();
            if full_sum > 1e-200 {
                assert!(
                    (window_sum - full_sum).abs() <= 1e-10 * full_sum,
                    "s {s}: {window_sum} vs {full_sum}"
                );
            }
            assert!(window.len <= 16, "window of {} bases", window.len);
            // Normalised values stay defined far past the last centre, where plain exp
            // underflows (the rollouts' forcing fades there, so `eval` itself is checked).
            let weights = vec![2.0; 50];
            let r = window.first..window.first + window.len;
            let (num, den) = out[r.clone()]
                .iter()
                .zip(&weights[r])
                .fold((0.0, 0.0), |(n, d), (p, w)| (n + p * w, d + p));
            assert!((num / den - 2.0).abs() < 1e-12);
            if s >= basis.centers[49] {
                assert!((basis.forcing(&weights, s, &mut out) - 2.0 * s).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn forcing_is_the_blend_up_to_the_end_and_nothing_past_it() {
        let basis = Basis::new(30, 100f64.ln(), 2.0);
        let weights: Vec<f64> = (0..30).map(|i| if i % 2 == 0 { 300.0 } else { -250.0 }).collect();
        let mut out = vec![0.0; 30];
        let end = basis.centers[29];
        for s in [1.0, 0.5, 0.1, end * 1.01, end] {
            let window = basis.eval(s, &mut out);
            let r = window.first..window.first + window.len;
            let (num, den) = out[r.clone()]
                .iter()
                .zip(&weights[r])
                .fold((0.0, 0.0), |(n, d), (p, w)| (n + p * w, d + p));
            assert_eq!(basis.forcing(&weights, s, &mut out), num / den * s, "s {s}");
        }
        for s in [end * 0.999, end * 0.5, 1e-9] {
            assert_eq!(basis.forcing(&weights, s, &mut out), 0.0, "s {s}");
        }
    }
}

//! Estimating forcing-term weights (LWR or ridge) and differentiating sampled trajectories.

use nalgebra::DMatrix;

use super::basis::Basis;
use super::{DmpError, Regression};

/// Fits one weight vector per target channel. `phases[t]` is the phase of sample `t`,
/// `times[t]` its time as a fraction of `τ`, and `targets[c]\[t\]` the forcing-term value channel
/// `c` must produce there.
pub(crate) fn fit_weights(
    basis: &Basis,
    regression: Regression,
    phases: &[f64],
    times: &[f64],
    targets: &[&[f64]],
) -> Result<Vec<Vec<f64>>, DmpError> {
    let n = basis.len();
    let index_scale = (n - 1) as f64;
    let mut scratch = vec![0.0; n];
    match regression {
        Regression::Lwr => {
            let mut den = vec![0.0; n];
            let mut num = vec![vec![0.0; n]; targets.len()];
            for (t, &s) in phases.iter().enumerate() {
                let window = basis.eval_near(s, times[t] * index_scale, &mut scratch);
                let scale = window.log_scale.exp();
                for i in window.first..window.first + window.len {
                    let psi = scratch[i] * scale;
                    den[i] += psi * s * s;
                    for (num_c, target) in num.iter_mut().zip(targets) {
                        num_c[i] += psi * s * target[t];
                    }
                }
            }
            Ok(num
                .into_iter()
                .map(|num_c| {
                    num_c
                        .iter()
                        .zip(&den)
                        .map(|(a, b)| if *b > 1e-300 { a / b } else { 0.0 })
                        .collect()
                })
                .collect())
        }
        Regression::Ridge { lambda } => {
            let mut gram = vec![0.0; n * n];
            let mut rhs = vec![vec![0.0; n]; targets.len()];
            for (t, &s) in phases.iter().enumerate() {
                let window = basis.eval_near(s, times[t] * index_scale, &mut scratch);
                let range = window.first..window.first + window.len;
                let sum: f64 = scratch[range.clone()].iter().sum();
                let factor = s / sum;
                scratch[range.clone()].iter_mut().for_each(|psi| *psi *= factor);
                for i in range.clone() {
                    let phi_i = scratch[i];
                    let row = &mut gram[i * n..(i + 1) * n];
                    for j in i..range.end {
                        row[j] += phi_i * scratch[j];
                    }
                    for (rhs_c, target) in rhs.iter_mut().zip(targets) {
                        rhs_c[i] += phi_i * target[t];
                    }
                }
            }
            let trace: f64 = (0..n).map(|i| gram[i * n + i]).sum();
            let mut matrix = DMatrix::from_fn(n, n, |i, j| if i <= j { gram[i * n + j] } else { gram[j * n + i] });
            let ridge = lambda * trace / n as f64 + 1e-14 * trace / n as f64;
            for i in 0..n {
                matrix[(i, i)] += ridge;
            }
            let cholesky = matrix.cholesky().ok_or(DmpError::Singular)?;
            Ok(rhs
                .into_iter()
                .map(|rhs_c| cholesky.solve(&nalgebra::DVector::from_vec(rhs_c)).as_slice().to_vec())
                .collect())
        }
    }
}

/// The three-point stencil at sample `k` of times `t` (at least 3): the middle sample and the
/// weights of the first and of the second derivative (see [`Stencil`]).
pub(crate) fn stencil_at(t: &[f64], k: usize) -> (usize, [f64; 3], [f64; 3]) {
    let mid = k.clamp(1, t.len() - 2);
    let (ta, tb, tc, tk) = (t[mid - 1], t[mid], t[mid + 1], t[k]);
    let (da, db, dc) = (
        1.0 / ((ta - tb) * (ta - tc)),
        1.0 / ((tb - ta) * (tb - tc)),
        1.0 / ((tc - ta) * (tc - tb)),
    );
    (
        mid,
        [
            ((tk - tb) + (tk - tc)) * da,
            ((tk - ta) + (tk - tc)) * db,
            ((tk - ta) + (tk - tb)) * dc,
        ],
        [2.0 * da, 2.0 * db, 2.0 * dc],
    )
}

/// Weights of the three-point stencils for the first and second derivative at every sample of
/// (possibly irregular) times `t`: the derivative of the quadratic through each sample and its
/// two neighbours (one-sided at the ends). Computed once and shared by all channels.
pub(crate) struct Stencil {
    /// Index of the middle sample of each stencil.
    mid: Vec<usize>,
    first: Vec<[f64; 3]>,
    second: Vec<[f64; 3]>,
}

impl Stencil {
    pub(crate) fn new(t: &[f64]) -> Self {
        let n = t.len();
        let mut stencil = Self {
            mid: Vec::with_capacity(n),
            first: Vec::with_capacity(n),
            second: Vec::with_capacity(n),
        };
        for k in 0..n {
            let (mid, first, second) = stencil_at(t, k);
            stencil.mid.push(mid);
            stencil.first.push(first);
            stencil.second.push(second);
        }
        stencil
    }

    /// First and second derivatives of `x` into `dx` and `ddx`.
    pub(crate) fn apply(&self, x: &[f64], dx: &mut [f64], ddx: &mut [f64]) {
        for k in 0..self.mid.len() {
            let m = self.mid[k];
            let (a, b, c) = (x[m - 1], x[m], x[m + 1]);
            let (w1, w2) = (self.first[k], self.second[k]);
            dx[k] = w1[0] * a + w1[1] * b + w1[2] * c;
            ddx[k] = w2[0] * a + w2[1] * b + w2[2] * c;
        }
    }
}

/// First and second time derivatives of `x` sampled at times `t` (see [`Stencil`]).
#[cfg(test)]
pub(crate) fn derivatives(t: &[f64], x: &[f64], dx: &mut [f64], ddx: &mut [f64]) {
    Stencil::new(t).apply(x, dx, ddx);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_a_quadratic_are_exact_on_irregular_samples() {
        let t: Vec<f64> = (0..20).map(|k| 0.1 * k as f64 + 0.02 * ((k % 3) as f64)).collect();
        let x: Vec<f64> = t.iter().map(|t| 3.0 * t * t - t + 2.0).collect();
        let (mut dx, mut ddx) = (vec![0.0; 20], vec![0.0; 20]);
        derivatives(&t, &x, &mut dx, &mut ddx);
        for k in 0..20 {
            assert!((dx[k] - (6.0 * t[k] - 1.0)).abs() < 1e-9, "dx[{k}] = {}", dx[k]);
            assert!((ddx[k] - 6.0).abs() < 1e-7, "ddx[{k}] = {}", ddx[k]);
        }
    }
}

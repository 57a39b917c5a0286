//! Estimating forcing-term weights (LWR or ridge) and differentiating sampled trajectories.

use nalgebra::DMatrix;

use super::basis::Basis;
use super::{DmpError, Regression};

/// Fits one weight vector per target channel. `phases[t]` is the phase of sample `t` and
/// `targets[c][t]` the forcing-term value channel `c` must produce there.
pub(crate) fn fit_weights(
    basis: &Basis,
    regression: Regression,
    phases: &[f64],
    targets: &[&[f64]],
) -> Result<Vec<Vec<f64>>, DmpError> {
    let n = basis.len();
    let mut scratch = vec![0.0; n];
    match regression {
        Regression::Lwr => {
            let mut den = vec![0.0; n];
            let mut num = vec![vec![0.0; n]; targets.len()];
            for (t, &s) in phases.iter().enumerate() {
                let window = basis.eval(s, &mut scratch);
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
                let window = basis.eval(s, &mut scratch);
                let range = window.first..window.first + window.len;
                let sum: f64 = scratch[range.clone()].iter().sum();
                let factor = s / sum;
                scratch[range.clone()]
                    .iter_mut()
                    .for_each(|psi| *psi *= factor);
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
            let mut matrix = DMatrix::from_fn(n, n, |i, j| {
                if i <= j {
                    gram[i * n + j]
                } else {
                    gram[j * n + i]
                }
            });
            let ridge = lambda * trace / n as f64 + 1e-14 * trace / n as f64;
            for i in 0..n {
                matrix[(i, i)] += ridge;
            }
            let cholesky = matrix.cholesky().ok_or(DmpError::Singular)?;
            Ok(rhs
                .into_iter()
                .map(|rhs_c| {
                    cholesky
                        .solve(&nalgebra::DVector::from_vec(rhs_c))
                        .as_slice()
                        .to_vec()
                })
                .collect())
        }
    }
}

/// First and second time derivatives of `x` sampled at (possibly irregular) times `t`, by the
/// derivative of the quadratic through each sample and its two neighbours (one-sided at the ends).
pub(crate) fn derivatives(t: &[f64], x: &[f64], dx: &mut [f64], ddx: &mut [f64]) {
    let n = t.len();
    for k in 0..n {
        let mid = k.clamp(1, n - 2);
        let (a, b, c) = (mid - 1, mid, mid + 1);
        let (ta, tb, tc, tk) = (t[a], t[b], t[c], t[k]);
        let (da, db, dc) = (
            (ta - tb) * (ta - tc),
            (tb - ta) * (tb - tc),
            (tc - ta) * (tc - tb),
        );
        dx[k] = x[a] * ((tk - tb) + (tk - tc)) / da
            + x[b] * ((tk - ta) + (tk - tc)) / db
            + x[c] * ((tk - ta) + (tk - tb)) / dc;
        ddx[k] = 2.0 * (x[a] / da + x[b] / db + x[c] / dc);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_a_quadratic_are_exact_on_irregular_samples() {
        let t: Vec<f64> = (0..20)
            .map(|k| 0.1 * k as f64 + 0.02 * ((k % 3) as f64))
            .collect();
        let x: Vec<f64> = t.iter().map(|t| 3.0 * t * t - t + 2.0).collect();
        let (mut dx, mut ddx) = (vec![0.0; 20], vec![0.0; 20]);
        derivatives(&t, &x, &mut dx, &mut ddx);
        for k in 0..20 {
            assert!(
                (dx[k] - (6.0 * t[k] - 1.0)).abs() < 1e-9,
                "dx[{k}] = {}",
                dx[k]
            );
            assert!((ddx[k] - 6.0).abs() < 1e-7, "ddx[{k}] = {}", ddx[k]);
        }
    }
}

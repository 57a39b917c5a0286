//! Estimating forcing-term weights (LWR or ridge) and differentiating sampled trajectories.

use nalgebra::DMatrix;

use super::basis::{Basis, LOG_CUTOFF};
use super::exp::exp_in_place;
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
    let mut fit = WeightFit::new(basis, regression, targets.len());
    let mut block_targets = vec![[0.0; BLOCK]; targets.len()];
    for block in (0..phases.len()).step_by(BLOCK) {
        let len = BLOCK.min(phases.len() - block);
        for (dst, target) in block_targets.iter_mut().zip(targets) {
            dst[..len].copy_from_slice(&target[block..block + len]);
        }
        fit.add_block(&phases[block..block + len], &times[block..block + len], &block_targets);
    }
    fit.finish()
}

/// Bases evaluated together on the fast path of [`WeightFit::add_block`]: the nearest basis in time
/// and 4 before, 3 after it, which holds every basis above the cutoff at the default width
/// (`width_factor` 2 reaches 4 bases back and 3 ahead).
const LANES: usize = 8;
/// Samples added together by [`WeightFit::add_block`].
pub(crate) const BLOCK: usize = 64;
/// Lanes before the nearest basis.
const BEFORE: usize = 4;
/// Padding of the bases and sums on each side, so that lanes never index out of range.
const PAD: usize = 2 * LANES;

/// `u.round()` for `u ≥ 0` (as `usize`), without the libm call `round` is without SSE4.1.
#[inline]
fn nearest(u: f64) -> usize {
    let whole = u.max(0.0) as usize;
    if u - whole as f64 >= 0.5 {
        whole + 1
    } else {
        whole
    }
}

/// The weight estimate, fed one sample at a time (no per-sample storage): the ridge normal
/// equations (upper triangle of `ΦᵀΦ` and `Φᵀf` per channel) or LWR's sums per basis.
///
/// The bases above the cutoff at a sample (those [`Basis::eval_near`] returns) are evaluated in
/// [`LANES`] fixed lanes around the nearest one, lanes outside the window set to exactly 0, so
/// the updates are fixed-length loops the compiler vectorises; a sample whose bases do not fit
/// the lanes (a narrow basis spacing, few bases) takes [`Basis::eval_near`] instead. Both add the
/// same products in the same order, and a zero lane adds exactly 0, so the sums are those of a
/// plain loop over the window.
pub(crate) struct WeightFit<'a> {
    basis: &'a Basis,
    regression: Regression,
    index_scale: f64,
    scratch: Vec<f64>,
    /// Centres and widths with [`PAD`] entries either side (centre −1, width 10³⁰⁰: far below
    /// the cutoff), indexed by basis + [`PAD`].
    centers: Vec<f64>,
    widths: Vec<f64>,
    /// Row length of `gram` and of each channel's row of `sums`.
    stride: usize,
    /// Ridge: `ΦᵀΦ`, row-major, upper triangle; LWR: `Σ ψᵢ s²` (one row). Indexed by
    /// basis + [`PAD`].
    gram: Vec<f64>,
    /// Ridge: `Φᵀf`; LWR: `Σ ψᵢ s f`; channel-major, one row of `stride` per channel.
    sums: Vec<f64>,
    channels: usize,
}

impl<'a> WeightFit<'a> {
    pub(crate) fn new(basis: &'a Basis, regression: Regression, channels: usize) -> Self {
        let n = basis.len();
        let stride = n + 2 * PAD;
        let padded = |values: &[f64], pad: f64| {
            let mut out = vec![pad; stride];
            out[PAD..PAD + n].copy_from_slice(values);
            out
        };
        let gram = match regression {
            Regression::Lwr => vec![0.0; stride],
            Regression::Ridge { .. } => vec![0.0; stride * stride],
        };
        Self {
            basis,
            regression,
            index_scale: (n - 1) as f64,
            scratch: vec![0.0; n],
            centers: padded(&basis.centers, -1.0),
            widths: padded(&basis.widths, 1e300),
            stride,
            gram,
            sums: vec![0.0; channels * stride],
            channels,
        }
    }

    /// The log-values of the bases at phase `s` in the lanes around basis `centre`, relative to
    /// it (as [`Basis::eval_near`]), and the mask of the lanes above the cutoff; `None` when the
    /// bases above the cutoff do not fit the lanes.
    #[inline]
    fn lanes(&self, s: f64, centre: usize, values: &mut [f64; LANES]) -> Option<u32> {
        let log_value = |p: usize| -self.widths[p] * (s - self.centers[p]).powi(2);
        let log_scale = log_value(centre + PAD);
        let first = centre + PAD - BEFORE;
        // The bases just outside the lanes must be below the cutoff.
        let outside = [log_value(first - 1), log_value(first + LANES)];
        if outside.iter().any(|&value| value - log_scale >= -LOG_CUTOFF) {
            return None;
        }
        let mut mask = 0u32;
        for (lane, value) in values.iter_mut().enumerate() {
            *value = log_value(first + lane) - log_scale;
            mask |= u32::from(*value >= -LOG_CUTOFF) << lane;
        }
        // `eval_near`'s window is the run of bases above the cutoff around the centre: the
        // lanes above it must be one contiguous run (they always are: a basis's value falls
        // with its distance in time from the sample; the check costs nothing).
        let run = mask >> mask.trailing_zeros();
        (run & (run + 1) == 0).then_some(mask)
    }

    /// Adds up to [`BLOCK`] samples: phases `s[j]`, times `time[j]` (fractions of `τ`) and
    /// forcing-term values `targets[c][j]` (one array per channel), in order. Done in stages
    /// over the block (log-values, exponentials, sums), each a fixed-length loop; the sums
    /// receive the same products in the same order as sample by sample.
    pub(crate) fn add_block(&mut self, s: &[f64], time: &[f64], targets: &[[f64; BLOCK]]) {
        let n = self.basis.len();
        let len = s.len().min(time.len()).min(BLOCK);
        let mut values = [[0.0; LANES]; BLOCK];
        let mut first = [0usize; BLOCK];
        let mut masks = [0u32; BLOCK];
        let mut fast = [false; BLOCK];
        for j in 0..len {
            let u = time[j] * self.index_scale;
            let centre = nearest(u).min(n - 1);
            first[j] = centre + PAD - BEFORE;
            if let Some(mask) = self.lanes(s[j], centre, &mut values[j]) {
                (masks[j], fast[j]) = (mask, true);
            }
        }
        exp_in_place(values[..len].as_flattened_mut());
        // Lanes outside the window are exactly 0.
        for (row, &mask) in values[..len].iter_mut().zip(&masks) {
            for (lane, value) in row.iter_mut().enumerate() {
                if mask & (1 << lane) == 0 {
                    *value = 0.0;
                }
            }
        }
        for j in 0..len {
            if !fast[j] {
                let sample: Vec<f64> = targets.iter().take(self.channels).map(|target| target[j]).collect();
                self.add_window(s[j], time[j] * self.index_scale, &sample);
                continue;
            }
            match self.regression {
                Regression::Lwr => self.add_lwr(s[j], first[j], &values[j], targets, j),
                Regression::Ridge { .. } => self.add_ridge(s[j], first[j], &values[j], targets, j),
            }
        }
    }

    /// Ridge: the sums of sample `j`, whose relative basis values `psi` sit in the lanes from
    /// padded index `first`.
    #[inline]
    fn add_ridge(&mut self, s: f64, first: usize, psi: &[f64; LANES], targets: &[[f64; BLOCK]], j: usize) {
        let stride = self.stride;
        let sum: f64 = psi.iter().sum();
        let factor = s / sum;
        let mut phi = [0.0; LANES];
        for (dst, value) in phi.iter_mut().zip(psi) {
            *dst = value * factor;
        }
        // Row `a` of the upper triangle takes lanes `a..LANES`: 36 products, not 64 (what lay
        // past the last lane added products of 0, and every product here is ≥ +0, so leaving
        // them out changes no bit).
        for a in 0..LANES {
            let phi_a = phi[a];
            let at = (first + a) * stride + first + a;
            let row = &mut self.gram[at..at + LANES - a];
            for (g, &phi_b) in row.iter_mut().zip(&phi[a..]) {
                *g += phi_a * phi_b;
            }
        }
        for (c, target) in targets.iter().enumerate().take(self.channels) {
            let target = target[j];
            let row = &mut self.sums[c * stride + first..c * stride + first + LANES];
            for (rhs, &phi_i) in row.iter_mut().zip(&phi[..LANES]) {
                *rhs += phi_i * target;
            }
        }
    }

    /// LWR: as [`WeightFit::add_ridge`].
    #[inline]
    fn add_lwr(&mut self, s: f64, first: usize, psi: &[f64; LANES], targets: &[[f64; BLOCK]], j: usize) {
        let stride = self.stride;
        let scale = (-self.widths[first + BEFORE] * (s - self.centers[first + BEFORE]).powi(2)).exp();
        let mut scaled = [0.0; LANES];
        // Lanes outside the window stay exactly 0 (even if the scale overflows).
        for (dst, &value) in scaled.iter_mut().zip(psi) {
            *dst = if value != 0.0 { value * scale } else { 0.0 };
        }
        for (den, &psi_i) in self.gram[first..first + LANES].iter_mut().zip(&scaled) {
            *den += psi_i * s * s;
        }
        for (c, target) in targets.iter().enumerate().take(self.channels) {
            let target = target[j];
            let row = &mut self.sums[c * stride + first..c * stride + first + LANES];
            for (num, &psi_i) in row.iter_mut().zip(&scaled) {
                *num += psi_i * s * target;
            }
        }
    }

    /// [`WeightFit::add_block`] through [`Basis::eval_near`], for any window.
    fn add_window(&mut self, s: f64, u: f64, targets: &[f64]) {
        let stride = self.stride;
        let window = self.basis.eval_near(s, u, &mut self.scratch);
        let (first, end) = (window.first, window.first + window.len);
        let psi = &mut self.scratch[first..end];
        match self.regression {
            Regression::Lwr => {
                let scale = window.log_scale.exp();
                for (a, &value) in psi.iter().enumerate() {
                    let i = PAD + first + a;
                    let psi_i = value * scale;
                    self.gram[i] += psi_i * s * s;
                    for (c, &target) in targets.iter().enumerate().take(self.channels) {
                        self.sums[c * stride + i] += psi_i * s * target;
                    }
                }
            }
            Regression::Ridge { .. } => {
                let sum: f64 = psi.iter().sum();
                let factor = s / sum;
                psi.iter_mut().for_each(|value| *value *= factor);
                let phi: &[f64] = psi;
                for (a, &phi_i) in phi.iter().enumerate() {
                    let i = PAD + first + a;
                    let row = &mut self.gram[i * stride + i..i * stride + PAD + end];
                    for (g, &phi_j) in row.iter_mut().zip(&phi[a..]) {
                        *g += phi_i * phi_j;
                    }
                    for (c, &target) in targets.iter().enumerate().take(self.channels) {
                        self.sums[c * stride + i] += phi_i * target;
                    }
                }
            }
        }
    }

    /// The weights, `weights[channel]\[basis\]`.
    pub(crate) fn finish(self) -> Result<Vec<Vec<f64>>, DmpError> {
        let (n, stride) = (self.basis.len(), self.stride);
        let channel_sums = |c: usize| &self.sums[c * stride + PAD..c * stride + PAD + n];
        match self.regression {
            Regression::Lwr => Ok((0..self.channels)
                .map(|c| {
                    channel_sums(c)
                        .iter()
                        .zip(&self.gram[PAD..PAD + n])
                        .map(|(a, b)| if *b > 1e-300 { a / b } else { 0.0 })
                        .collect()
                })
                .collect()),
            Regression::Ridge { lambda } => {
                let gram = |i: usize, j: usize| self.gram[(PAD + i) * stride + PAD + j];
                let trace: f64 = (0..n).map(|i| gram(i, i)).sum();
                let mut matrix = DMatrix::from_fn(n, n, |i, j| if i <= j { gram(i, j) } else { gram(j, i) });
                let ridge = lambda * trace / n as f64 + 1e-14 * trace / n as f64;
                for i in 0..n {
                    matrix[(i, i)] += ridge;
                }
                let cholesky = matrix.cholesky().ok_or(DmpError::Singular)?;
                Ok((0..self.channels)
                    .map(|c| {
                        cholesky
                            .solve(&nalgebra::DVector::from_column_slice(channel_sums(c)))
                            .as_slice()
                            .to_vec()
                    })
                    .collect())
            }
        }
    }
}

/// The three-point stencil at sample `k` of times `t` (at least 3): the middle sample and the
/// weights of the first and of the second derivative (see [`Stencil`]).
pub(crate) fn stencil_at(t: &[f64], k: usize) -> (usize, [f64; 3], [f64; 3]) {
    let mid = k.clamp(1, t.len() - 2);
    let (first, second) = stencil_weights(t[mid - 1], t[mid], t[mid + 1], t[k]);
    (mid, first, second)
}

/// The weights of the first and second derivative at time `tk` of the quadratic through the
/// samples at times `ta`, `tb`, `tc`.
#[inline]
pub(crate) fn stencil_weights(ta: f64, tb: f64, tc: f64, tk: f64) -> ([f64; 3], [f64; 3]) {
    let (da, db, dc) = (
        1.0 / ((ta - tb) * (ta - tc)),
        1.0 / ((tb - ta) * (tb - tc)),
        1.0 / ((tc - ta) * (tc - tb)),
    );
    (
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

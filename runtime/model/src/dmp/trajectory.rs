//! [`Dmp`]: a set of 1-D DMPs (Cartesian coordinates, force components) sharing one phase.

use nalgebra::SVector;
use serde::{Deserialize, Serialize};

use super::basis::Basis;
use super::canonical::CanonicalSystem;
use super::exp::exp_in_place;
use super::fit::{stencil_weights, WeightFit, BLOCK};
use super::rollout::DmpRollout;
use super::{check_times, DmpConfig, DmpError};

/// Shared consistency checks of a learned DMP's parts.
pub(crate) fn validate_parts(basis: &Basis, tau_s: f64, weights: &[Vec<f64>], n_dims: usize) -> Result<(), DmpError> {
    let n = basis.len();
    if basis.widths.len() != n || n < 2 {
        return Err(DmpError::LengthMismatch {
            what: "basis.widths",
            expected: n,
            found: basis.widths.len(),
        });
    }
    if !(tau_s.is_finite() && tau_s > 0.0) {
        return Err(DmpError::InvalidConfig {
            name: "tau_s",
            reason: "must be a positive number of seconds".to_owned(),
        });
    }
    if weights.len() != n_dims {
        return Err(DmpError::LengthMismatch {
            what: "weights",
            expected: n_dims,
            found: weights.len(),
        });
    }
    for channel in weights {
        if channel.len() != n {
            return Err(DmpError::LengthMismatch {
                what: "weights",
                expected: n,
                found: channel.len(),
            });
        }
        if let Some(index) = channel.iter().position(|w| !w.is_finite()) {
            return Err(DmpError::NonFinite { what: "weights", index });
        }
    }
    Ok(())
}

/// A learned multi-channel DMP: one transformation system per channel, one canonical system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dmp {
    /// Parameters it was learned with.
    pub config: DmpConfig,
    /// The basis functions.
    pub basis: Basis,
    /// Duration of the demonstration (s): the default `τ`.
    pub tau_s: f64,
    /// Demonstrated start, one value per channel (units of the channel).
    pub start: Vec<f64>,
    /// Demonstrated goal, one value per channel.
    pub goal: Vec<f64>,
    /// Forcing-term weights, `weights[channel]\[basis\]`.
    pub weights: Vec<Vec<f64>>,
    /// Demonstrated initial velocity `ẋ(0)`, one value per channel (units per second).
    /// A rollout from the demonstrated start begins with it, so that profiles that start
    /// moving (a force rising at touch-down) are reproduced; `restart_from` starts at rest.
    #[serde(default)]
    pub start_velocity: Vec<f64>,
}

impl Dmp {
    /// Learns a DMP from `channels[c]\[k\]` sampled at times `t_s[k]` (any spacing).
    pub fn fit(config: &DmpConfig, t_s: &[f64], channels: &[&[f64]]) -> Result<Self, DmpError> {
        config.validate()?;
        check_times(t_s, "trajectory")?;
        for channel in channels {
            if channel.len() != t_s.len() {
                return Err(DmpError::LengthMismatch {
                    what: "channel",
                    expected: t_s.len(),
                    found: channel.len(),
                });
            }
            if let Some(index) = channel.iter().position(|v| !v.is_finite()) {
                return Err(DmpError::NonFinite { what: "channel", index });
            }
        }
        Self::fit_checked(config, t_s, channels.len(), |c, k| channels[c][k])
    }

    /// Learns a DMP from `D`-dimensional points (e.g. positions, forces) at times `t_s`.
    pub fn fit_points<const D: usize>(
        config: &DmpConfig,
        t_s: &[f64],
        points: &[SVector<f64, D>],
    ) -> Result<Self, DmpError> {
        config.validate()?;
        check_times(t_s, "trajectory")?;
        if D > 0 && points.len() != t_s.len() {
            return Err(DmpError::LengthMismatch {
                what: "channel",
                expected: t_s.len(),
                found: points.len(),
            });
        }
        for axis in 0..D {
            if let Some(index) = points.iter().position(|p| !p[axis].is_finite()) {
                return Err(DmpError::NonFinite { what: "channel", index });
            }
        }
        Self::fit_checked(config, t_s, D, |c, k| points[k][c])
    }

    /// The fit proper, on checked inputs: `value(c, k)` is channel `c` at sample `k`. One pass
    /// over the samples for all channels: the stencil weights are computed once per sample and
    /// each sample's forcing-term values go straight into the weight estimate (nothing is
    /// stored per sample).
    fn fit_checked(
        config: &DmpConfig,
        t_s: &[f64],
        n_channels: usize,
        value: impl Fn(usize, usize) -> f64,
    ) -> Result<Self, DmpError> {
        let n = t_s.len();
        let t0 = t_s[0];
        let tau = t_s[n - 1] - t0;
        let alpha_s = config.alpha_s;
        let (k, d) = (config.stiffness, config.damping());
        let start: Vec<f64> = (0..n_channels).map(|c| value(c, 0)).collect();
        let goal: Vec<f64> = (0..n_channels).map(|c| value(c, n - 1)).collect();
        let mut start_velocity = vec![0.0; n_channels];
        let basis = Basis::new(config.n_basis, config.alpha_s, config.width_factor);
        let mut fit = WeightFit::new(&basis, config.regression, n_channels);
        // Per block: times (shifted to start at 0) and values with one neighbour either side,
        // the stencil weights, phases, time fractions, and each channel's forcing-term targets.
        let mut times = [0.0; BLOCK + 2];
        let mut values = vec![[0.0; BLOCK + 2]; n_channels];
        let mut targets = vec![[0.0; BLOCK]; n_channels];
        let (mut w1, mut w2) = ([[0.0; 3]; BLOCK], [[0.0; 3]; BLOCK]);
        let (mut phases, mut fractions) = ([0.0; BLOCK], [0.0; BLOCK]);
        for block in (0..n).step_by(BLOCK) {
            let len = BLOCK.min(n - block);
            // Entry j is sample `block + j − 1` (clamped; the end samples are redone below).
            let neighbour = |j: usize| (block + j).saturating_sub(1).min(n - 1);
            for (j, time) in times[..len + 2].iter_mut().enumerate() {
                *time = t_s[neighbour(j)] - t0;
            }
            for (c, row) in values.iter_mut().enumerate() {
                for (j, x) in row[..len + 2].iter_mut().enumerate() {
                    *x = value(c, neighbour(j));
                }
            }
            for j in 0..len {
                (w1[j], w2[j]) = stencil_weights(times[j], times[j + 1], times[j + 2], times[j + 1]);
                // The canonical system's phase `exp(−α_s t / τ)`, as `CanonicalSystem::phase`.
                phases[j] = -alpha_s * times[j + 1] / tau;
                fractions[j] = times[j + 1] / tau;
            }
            exp_in_place(&mut phases[..len]);
            for ((row, target), (&x0, &g)) in values.iter().zip(&mut targets).zip(start.iter().zip(&goal)) {
                for j in 0..len {
                    let (a, b, e) = (row[j], row[j + 1], row[j + 2]);
                    let dx = w1[j][0] * a + w1[j][1] * b + w1[j][2] * e;
                    let ddx = w2[j][0] * a + w2[j][1] * b + w2[j][2] * e;
                    target[j] = (tau * tau * ddx + d * tau * dx) / k - (g - b) + (g - x0) * phases[j];
                }
            }
            // The first and last samples take the stencil of their inner neighbours.
            for idx in [0, n - 1] {
                if !(block..block + len).contains(&idx) {
                    continue;
                }
                let (j, mid) = (idx - block, idx.clamp(1, n - 2));
                let (a, b) = stencil_weights(t_s[mid - 1] - t0, t_s[mid] - t0, t_s[mid + 1] - t0, t_s[idx] - t0);
                (w1[j], w2[j]) = (a, b);
                for (c, target) in targets.iter_mut().enumerate() {
                    let (a, b, e) = (value(c, mid - 1), value(c, mid), value(c, mid + 1));
                    let dx = w1[j][0] * a + w1[j][1] * b + w1[j][2] * e;
                    let ddx = w2[j][0] * a + w2[j][1] * b + w2[j][2] * e;
                    let (x0, g) = (start[c], goal[c]);
                    target[j] = (tau * tau * ddx + d * tau * dx) / k - (g - value(c, idx)) + (g - x0) * phases[j];
                    if idx == 0 {
                        start_velocity[c] = dx;
                    }
                }
            }
            fit.add_block(&phases[..len], &fractions[..len], &targets);
        }
        let weights = fit.finish()?;
        Ok(Self {
            config: config.clone(),
            basis,
            tau_s: tau,
            start,
            goal,
            weights,
            start_velocity,
        })
    }

    /// Checks internal consistency (channel counts, basis sizes, finite values), e.g. after
    /// deserialising a DMP from a file. Rollouts of an inconsistent DMP do nothing.
    pub fn validate(&self) -> Result<(), DmpError> {
        self.config.validate()?;
        validate_parts(&self.basis, self.tau_s, &self.weights, self.start.len())?;
        if self.goal.len() != self.start.len() {
            return Err(DmpError::LengthMismatch {
                what: "goal",
                expected: self.start.len(),
                found: self.goal.len(),
            });
        }
        if let Some(index) = self.start.iter().chain(&self.goal).position(|v| !v.is_finite()) {
            return Err(DmpError::NonFinite {
                what: "start or goal",
                index,
            });
        }
        Ok(())
    }

    /// Number of channels.
    pub fn n_dims(&self) -> usize {
        self.start.len()
    }

    /// The canonical system.
    pub fn canonical(&self) -> CanonicalSystem {
        CanonicalSystem {
            alpha_s: self.config.alpha_s,
        }
    }

    /// A rollout at the demonstrated start, goal and `τ` (change them with its setters).
    pub fn rollout(&self) -> DmpRollout {
        DmpRollout::new(self)
    }

    /// Convenience: rolls out from the demonstrated start for `duration_s` at step `dt_s` and
    /// returns the sampled positions `out[k]\[channel\]` at `t = k dt` (including `t = 0`).
    pub fn reproduce(&self, dt_s: f64, duration_s: f64) -> Vec<Vec<f64>> {
        let mut rollout = self.rollout();
        let steps = (duration_s / dt_s).round() as usize;
        let mut out = Vec::with_capacity(steps + 1);
        out.push(rollout.position().to_vec());
        for _ in 0..steps {
            rollout.step(self, dt_s);
            out.push(rollout.position().to_vec());
        }
        out
    }
}

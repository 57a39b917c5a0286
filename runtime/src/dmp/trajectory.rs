//! [`Dmp`]: a set of 1-D DMPs (Cartesian coordinates, force components) sharing one phase.

use nalgebra::SVector;
use serde::{Deserialize, Serialize};

use super::basis::Basis;
use super::canonical::CanonicalSystem;
use super::fit::{fit_weights, stencil_at};
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
        let n = t_s.len();
        let t0 = t_s[0];
        let tau = t_s[n - 1] - t0;
        let times: Vec<f64> = t_s.iter().map(|t| t - t0).collect();
        let canonical = CanonicalSystem {
            alpha_s: config.alpha_s,
        };
        let phases: Vec<f64> = times.iter().map(|&t| canonical.phase(t, tau)).collect();
        let fractions: Vec<f64> = times.iter().map(|&t| t / tau).collect();
        let (k, d) = (config.stiffness, config.damping());
        // One pass over the samples for all channels: the stencil weights are computed once per
        // sample and no derivative arrays are stored.
        let mut targets = vec![vec![0.0; n]; channels.len()];
        let start: Vec<f64> = channels.iter().map(|channel| channel[0]).collect();
        let goal: Vec<f64> = channels.iter().map(|channel| channel[n - 1]).collect();
        let mut start_velocity = vec![0.0; channels.len()];
        for idx in 0..n {
            let (mid, w1, w2) = stencil_at(&times, idx);
            let s = phases[idx];
            for (c, (channel, target)) in channels.iter().zip(&mut targets).enumerate() {
                let (a, b, e) = (channel[mid - 1], channel[mid], channel[mid + 1]);
                let dx = w1[0] * a + w1[1] * b + w1[2] * e;
                let ddx = w2[0] * a + w2[1] * b + w2[2] * e;
                let (x0, g) = (start[c], goal[c]);
                target[idx] = (tau * tau * ddx + d * tau * dx) / k - (g - channel[idx]) + (g - x0) * s;
                if idx == 0 {
                    start_velocity[c] = dx;
                }
            }
        }
        let basis = Basis::new(config.n_basis, config.alpha_s, config.width_factor);
        let target_refs: Vec<&[f64]> = targets.iter().map(Vec::as_slice).collect();
        let weights = fit_weights(&basis, config.regression, &phases, &fractions, &target_refs)?;
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

    /// Learns a DMP from `D`-dimensional points (e.g. positions, forces) at times `t_s`.
    pub fn fit_points<const D: usize>(
        config: &DmpConfig,
        t_s: &[f64],
        points: &[SVector<f64, D>],
    ) -> Result<Self, DmpError> {
        let channels: Vec<Vec<f64>> = (0..D).map(|axis| points.iter().map(|p| p[axis]).collect()).collect();
        let refs: Vec<&[f64]> = channels.iter().map(Vec::as_slice).collect();
        Self::fit(config, t_s, &refs)
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

//! [`DmpRollout`]: integrating a [`Dmp`] step by step without allocating.

use super::trajectory::Dmp;
use super::DmpError;

/// The running state of a [`Dmp`]: position, scaled velocity `v = τ ẋ`, phase, and the start,
/// goal and `τ` in force now. All buffers are allocated once in [`DmpRollout::new`];
/// [`DmpRollout::step`] does not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct DmpRollout {
    x: Vec<f64>,
    v: Vec<f64>,
    start: Vec<f64>,
    goal: Vec<f64>,
    tau_s: f64,
    s: f64,
    t_s: f64,
    scratch: Vec<f64>,
}

impl DmpRollout {
    /// A rollout at the demonstrated start with the demonstrated initial velocity, aiming at
    /// the demonstrated goal.
    pub fn new(dmp: &Dmp) -> Self {
        let mut v = vec![0.0; dmp.n_dims()];
        for (v, xd) in v.iter_mut().zip(&dmp.start_velocity) {
            *v = dmp.tau_s * xd;
        }
        Self {
            x: dmp.start.clone(),
            v,
            start: dmp.start.clone(),
            goal: dmp.goal.clone(),
            tau_s: dmp.tau_s,
            s: 1.0,
            t_s: 0.0,
            scratch: vec![0.0; dmp.basis.len()],
        }
    }

    /// Current position, one value per channel.
    pub fn position(&self) -> &[f64] {
        &self.x
    }

    /// Current velocity `ẋ = v / τ`, written into `out` (one value per channel).
    pub fn velocity_into(&self, out: &mut [f64]) {
        for (o, v) in out.iter_mut().zip(&self.v) {
            *o = v / self.tau_s;
        }
    }

    /// Current phase `s`.
    pub fn phase(&self) -> f64 {
        self.s
    }

    /// Time since the (re)start (s).
    pub fn time_s(&self) -> f64 {
        self.t_s
    }

    /// Current goal.
    pub fn goal(&self) -> &[f64] {
        &self.goal
    }

    /// Current `τ` (s).
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }

    /// Changes the goal; takes effect at the next step (allowed while running).
    pub fn set_goal(&mut self, goal: &[f64]) -> Result<(), DmpError> {
        copy_checked(&mut self.goal, goal, "goal")
    }

    /// Changes the start `x₀` used by the `−K (g − x₀) s` term (allowed while running).
    pub fn set_start(&mut self, start: &[f64]) -> Result<(), DmpError> {
        copy_checked(&mut self.start, start, "start")
    }

    /// Changes `τ` (allowed while running); larger is slower.
    pub fn set_tau(&mut self, tau_s: f64) -> Result<(), DmpError> {
        if !(tau_s.is_finite() && tau_s > 0.0) {
            return Err(DmpError::InvalidConfig {
                name: "tau_s",
                reason: "must be a positive number of seconds".to_owned(),
            });
        }
        self.tau_s = tau_s;
        Ok(())
    }

    /// Restarts at rest from `position` (which also becomes the start), with phase 1.
    pub fn restart_from(&mut self, position: &[f64]) -> Result<(), DmpError> {
        copy_checked(&mut self.start, position, "start")?;
        self.x.copy_from_slice(position);
        self.v.iter_mut().for_each(|v| *v = 0.0);
        self.s = 1.0;
        self.t_s = 0.0;
        Ok(())
    }

    /// Advances by `dt_s` (semi-implicit Euler; steps longer than `0.02 τ / √K` are split).
    /// `dmp` must be the DMP this rollout was made from; a step with a non-positive `dt_s` or an
    /// inconsistent DMP (see [`Dmp::validate`]) does nothing.
    pub fn step(&mut self, dmp: &Dmp, dt_s: f64) {
        let usable =
            dt_s.is_finite() && dt_s > 0.0 && consistent(&self.scratch, &dmp.basis, &dmp.weights, self.x.len());
        if !usable {
            return;
        }
        let k = dmp.config.stiffness;
        let d = dmp.config.damping();
        let canonical = dmp.canonical();
        let max_step = 0.02 * self.tau_s / k.sqrt();
        let substeps = (dt_s / max_step).ceil().max(1.0) as usize;
        let h = dt_s / substeps as f64;
        for _ in 0..substeps {
            // The learned term `f(s) − (g − x₀) s`, dropped past the demonstration's end.
            let ended = dmp.basis.ended(self.s);
            let window = dmp.basis.eval(self.s, &mut self.scratch);
            let range = window.first..window.first + window.len;
            let den: f64 = self.scratch[range.clone()].iter().sum();
            for c in 0..self.x.len() {
                let num: f64 = self.scratch[range.clone()]
                    .iter()
                    .zip(&dmp.weights[c][range.clone()])
                    .map(|(p, w)| p * w)
                    .sum();
                let (g, x0, x) = (self.goal[c], self.start[c], self.x[c]);
                let learned = if ended { 0.0 } else { (num / den - (g - x0)) * self.s };
                let accel = k * (g - x) - d * self.v[c] + k * learned;
                self.v[c] += h * accel / self.tau_s;
                self.x[c] += h * self.v[c] / self.tau_s;
            }
            self.s = canonical.step(self.s, h, self.tau_s);
            self.t_s += h;
        }
    }
}

/// True when a rollout's buffers fit `basis` and `weights` (cheap; guards against a DMP that
/// was deserialised inconsistently or is not the one the rollout was made from).
pub(crate) fn consistent(scratch: &[f64], basis: &super::Basis, weights: &[Vec<f64>], n_dims: usize) -> bool {
    let n = basis.len();
    scratch.len() == n && basis.widths.len() == n && weights.len() == n_dims && weights.iter().all(|w| w.len() == n)
}

fn copy_checked(dst: &mut [f64], src: &[f64], what: &'static str) -> Result<(), DmpError> {
    if dst.len() != src.len() {
        return Err(DmpError::LengthMismatch {
            what,
            expected: dst.len(),
            found: src.len(),
        });
    }
    if let Some(index) = src.iter().position(|v| !v.is_finite()) {
        return Err(DmpError::NonFinite { what, index });
    }
    dst.copy_from_slice(src);
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::dmp::{Dmp, DmpConfig};

    #[test]
    fn past_its_end_a_rollout_settles_on_the_goal_without_overshoot() {
        // A press-like force profile: up to 8 N, held, and partly released, cut at 5 N while
        // still falling at 21 N/s (a segment boundary placed inside the release).
        let t: Vec<f64> = (0..=1684).map(|k| k as f64 * 1e-3).collect();
        let f: Vec<f64> = t
            .iter()
            .map(|&t| {
                let release = if t > 1.4 {
                    -3.0 * ((t - 1.4) / 0.284).powi(2)
                } else {
                    0.0
                };
                8.0 * (1.0 - (-t / 0.08).exp()) + release
            })
            .collect();
        let config = DmpConfig {
            n_basis: 30,
            ..DmpConfig::default()
        };
        let dmp = Dmp::fit(&config, &t, &[&f]).expect("valid profile");
        let goal = dmp.goal[0];
        let mut rollout = dmp.rollout();
        let (mut worst_in, mut worst_past): (f64, f64) = (0.0, 0.0);
        for demonstrated in &f[1..] {
            rollout.step(&dmp, 1e-3);
            worst_in = worst_in.max((rollout.position()[0] - demonstrated).abs());
        }
        for _ in 0..1684 {
            rollout.step(&dmp, 1e-3);
            worst_past = worst_past.max((rollout.position()[0] - goal).abs());
        }
        assert!(worst_in < 0.2, "{worst_in} N off the profile");
        // From 21 N/s a critically damped spring (ω = √K / τ ≈ 7.4 rad/s) goes ≈ 21 / (7.4 e)
        // ≈ 1 N past its goal (measured 1.06 N). With the learned term extrapolated past the end
        // (≈ −7 N there, decaying with the phase) it went 3.9 N past.
        assert!(worst_past < 1.5, "{worst_past} N from the goal past the end");
        assert!((rollout.position()[0] - goal).abs() < 0.05, "not settled");
    }
}

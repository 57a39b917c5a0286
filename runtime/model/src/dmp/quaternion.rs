//! The quaternion DMP of Ude et al. 2014 (thesis eq. 4.6-4.7) with log/exp maps.
//!
//! ```text
//! τ η̇ = K δ(q, g) − D η − K δ(q₀, g) s + K f(s),     τ q̇ = ½ η ∗ q,
//! δ(q₁, q₂) = 2 log(q₂ ∗ q̄₁)
//! ```
//!
//! `δ(q₁, q₂)` is the rotation vector (axis times angle, base frame) that turns `q₁` into `q₂`
//! along the shorter way, and `q(t + h) = exp(h η / (2 τ)) ∗ q(t)` integrates the orientation on
//! the sphere. `D = 2 √K` as for the 1-D systems. The three components of `f` share the phase.
//!
//! Limitation: the log map takes the shorter way, so every demonstrated orientation must be
//! less than π away from the goal (otherwise `δ(q, g)` flips sign along the way and the
//! reproduction degrades there).

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::basis::Basis;
use super::canonical::CanonicalSystem;
use super::fit::{fit_weights, Stencil};
use super::rollout::consistent;
use super::{check_times, DmpConfig, DmpError};

/// `δ(q₁, q₂) = 2 log(q₂ ∗ q̄₁)`: the rotation vector taking `q₁` to `q₂` (base frame).
pub fn quat_error(q1: &UnitQuaternion<f64>, q2: &UnitQuaternion<f64>) -> Vector3<f64> {
    (q2 * q1.inverse()).scaled_axis()
}

/// A learned orientation DMP.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuatDmp {
    /// Parameters it was learned with.
    pub config: DmpConfig,
    /// The basis functions.
    pub basis: Basis,
    /// Duration of the demonstration (s).
    pub tau_s: f64,
    /// Demonstrated start orientation (base frame).
    pub start: UnitQuaternion<f64>,
    /// Demonstrated goal orientation (base frame).
    pub goal: UnitQuaternion<f64>,
    /// Forcing-term weights for the three tangent-space components, `weights[axis]\[basis\]`.
    pub weights: Vec<Vec<f64>>,
}

impl QuatDmp {
    /// Learns an orientation DMP from unit quaternions sampled at times `t_s` (any spacing; the
    /// quaternions need not be sign-continuous, the log map takes the shorter way).
    pub fn fit(config: &DmpConfig, t_s: &[f64], orientation: &[UnitQuaternion<f64>]) -> Result<Self, DmpError> {
        config.validate()?;
        check_times(t_s, "orientation")?;
        if orientation.len() != t_s.len() {
            return Err(DmpError::LengthMismatch {
                what: "orientation",
                expected: t_s.len(),
                found: orientation.len(),
            });
        }
        if let Some(index) = orientation.iter().position(|q| !q.coords.iter().all(|c| c.is_finite())) {
            return Err(DmpError::NonFinite {
                what: "orientation",
                index,
            });
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

        // Angular velocity (base frame) from the quadratic through each sample and its
        // neighbours, in the tangent space at the middle one.
        let mut omega = vec![[0.0f64; 3]; n];
        for k in 0..n {
            let mid = k.clamp(1, n - 2);
            let (a, b, c) = (mid - 1, mid, mid + 1);
            let (ta, tb, tc, tk) = (times[a], times[b], times[c], times[k]);
            let ra = quat_error(&orientation[b], &orientation[a]);
            let rc = quat_error(&orientation[b], &orientation[c]);
            let (da, dc) = ((ta - tb) * (ta - tc), (tc - ta) * (tc - tb));
            let w = ra * (((tk - tb) + (tk - tc)) / da) + rc * (((tk - ta) + (tk - tb)) / dc);
            omega[k] = [w.x, w.y, w.z];
        }
        let (k_gain, d_gain) = (config.stiffness, config.damping());
        let (start, goal) = (orientation[0], orientation[n - 1]);
        let start_error = quat_error(&start, &goal);
        let mut targets = vec![vec![0.0; n]; 3];
        let (mut w_axis, mut dw, mut unused) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let errors: Vec<Vector3<f64>> = orientation.iter().map(|q| quat_error(q, &goal)).collect();
        let stencil = Stencil::new(&times);
        for axis in 0..3 {
            w_axis.iter_mut().zip(&omega).for_each(|(dst, w)| *dst = w[axis]);
            stencil.apply(&w_axis, &mut dw, &mut unused);
            for idx in 0..n {
                targets[axis][idx] = (tau * tau * dw[idx] + d_gain * tau * w_axis[idx]) / k_gain - errors[idx][axis]
                    + start_error[axis] * phases[idx];
            }
        }
        let basis = Basis::new(config.n_basis, config.alpha_s, config.width_factor);
        let refs: Vec<&[f64]> = targets.iter().map(Vec::as_slice).collect();
        let weights = fit_weights(&basis, config.regression, &phases, &fractions, &refs)?;
        Ok(Self {
            config: config.clone(),
            basis,
            tau_s: tau,
            start,
            goal,
            weights,
        })
    }

    /// Checks internal consistency, e.g. after deserialising. Rollouts of an inconsistent DMP
    /// do nothing.
    pub fn validate(&self) -> Result<(), DmpError> {
        self.config.validate()?;
        super::trajectory::validate_parts(&self.basis, self.tau_s, &self.weights, 3)
    }

    /// A rollout at the demonstrated start, goal and `τ`.
    pub fn rollout(&self) -> QuatRollout {
        QuatRollout {
            q: self.start,
            eta: Vector3::zeros(),
            start: self.start,
            goal: self.goal,
            tau_s: self.tau_s,
            s: 1.0,
            t_s: 0.0,
            scratch: vec![0.0; self.basis.len()],
        }
    }

    /// Convenience: the orientations at `t = k dt` for `duration_s`, from the demonstrated start.
    pub fn reproduce(&self, dt_s: f64, duration_s: f64) -> Vec<UnitQuaternion<f64>> {
        let mut rollout = self.rollout();
        let steps = (duration_s / dt_s).round() as usize;
        let mut out = Vec::with_capacity(steps + 1);
        out.push(rollout.orientation());
        for _ in 0..steps {
            rollout.step(self, dt_s);
            out.push(rollout.orientation());
        }
        out
    }
}

/// The running state of a [`QuatDmp`]; [`QuatRollout::step`] does not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct QuatRollout {
    q: UnitQuaternion<f64>,
    eta: Vector3<f64>,
    start: UnitQuaternion<f64>,
    goal: UnitQuaternion<f64>,
    tau_s: f64,
    s: f64,
    t_s: f64,
    scratch: Vec<f64>,
}

impl QuatRollout {
    /// Current orientation.
    pub fn orientation(&self) -> UnitQuaternion<f64> {
        self.q
    }

    /// The time constant it runs with \[s\].
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }

    /// Current angular velocity `ω = η / τ` \[rad/s\], base frame.
    pub fn angular_velocity(&self) -> Vector3<f64> {
        self.eta / self.tau_s
    }

    /// Current phase.
    pub fn phase(&self) -> f64 {
        self.s
    }

    /// Changes the goal (allowed while running).
    pub fn set_goal(&mut self, goal: UnitQuaternion<f64>) {
        self.goal = goal;
    }

    /// Changes the start used by the `δ(q₀, g) s` term (allowed while running).
    pub fn set_start(&mut self, start: UnitQuaternion<f64>) {
        self.start = start;
    }

    /// Changes `τ` (allowed while running).
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

    /// Restarts at rest from `orientation` (which also becomes the start), with phase 1.
    pub fn restart_from(&mut self, orientation: UnitQuaternion<f64>) {
        self.q = orientation;
        self.start = orientation;
        self.eta = Vector3::zeros();
        self.s = 1.0;
        self.t_s = 0.0;
    }

    /// Advances by `dt_s` (steps longer than `0.02 τ / √K` are split).
    pub fn step(&mut self, dmp: &QuatDmp, dt_s: f64) {
        let usable = dt_s.is_finite() && dt_s > 0.0 && consistent(&self.scratch, &dmp.basis, &dmp.weights, 3);
        if !usable {
            return;
        }
        let k = dmp.config.stiffness;
        let d = dmp.config.damping();
        let canonical = CanonicalSystem {
            alpha_s: dmp.config.alpha_s,
        };
        let substeps = (dt_s / (0.02 * self.tau_s / k.sqrt())).ceil().max(1.0) as usize;
        let h = dt_s / substeps as f64;
        let start_error = quat_error(&self.start, &self.goal);
        for _ in 0..substeps {
            // The learned term `f(s) − δ(q₀, g) s`, dropped past the demonstration's end.
            let ended = dmp.basis.ended(self.s);
            let window = dmp.basis.eval(self.s, &mut self.scratch);
            let range = window.first..window.first + window.len;
            let den: f64 = self.scratch[range.clone()].iter().sum();
            let mut blend = Vector3::zeros();
            for axis in 0..3 {
                let num: f64 = self.scratch[range.clone()]
                    .iter()
                    .zip(&dmp.weights[axis][range.clone()])
                    .map(|(p, w)| p * w)
                    .sum();
                blend[axis] = num / den;
            }
            let learned = if ended {
                Vector3::zeros()
            } else {
                (blend - start_error) * self.s
            };
            let error = quat_error(&self.q, &self.goal);
            let accel = error * k - self.eta * d + learned * k;
            self.eta += accel * (h / self.tau_s);
            self.q = UnitQuaternion::from_scaled_axis(self.eta * (h / self.tau_s)) * self.q;
            self.s = canonical.step(self.s, h, self.tau_s);
            self.t_s += h;
        }
    }
}

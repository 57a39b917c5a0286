//! Dynamic Movement Primitives: 1-D DMPs sharing one canonical system, the quaternion DMP, force DMPs.
//!
//! # Parameterisation (docs/method.md §2)
//!
//! Each channel `x` (a Cartesian coordinate or a force component) is one transformation system
//!
//! ```text
//! τ v̇ = K (g − x) − D v − K (g − x₀) s + K f(s),      τ ẋ = v,
//! ```
//!
//! driven by the canonical system `τ ṡ = −α_s s` (`s(0) = 1`, so `s(t) = exp(−α_s t / τ)`),
//! with the forcing term `f(s) = Σᵢ wᵢ ψᵢ(s) / Σᵢ ψᵢ(s) · s` and Gaussian bases
//! `ψᵢ(s) = exp(−hᵢ (s − cᵢ)²)`.
//!
//! **Damping.** The thesis writes `D = β = α/4`, which is critically damped only in the Ijspeert
//! parameterisation (spring `α β`, damper `α`). Here the spring is `K` itself, so we use
//! `D = 2 √K`, which makes the unforced system `τ² ẍ + D τ ẋ + K x = 0` exactly critically
//! damped for every `K`. The default `K = 156.25` gives `D = 25`, the classic `α = 25, β = α/4`.
//!
//! **Bases** have centres evenly spaced in *time*: `cᵢ = exp(−α_s · i / (N − 1))`, `i = 0..N`,
//! covering `t ∈ [0, τ]`, and widths `hᵢ = width_factor / (cᵢ − cᵢ₊₁)²` (the last basis reuses
//! the previous spacing), so that a basis has decayed to `exp(−width_factor)` at its
//! neighbour's centre.
//!
//! **Time.** `τ` is the duration of the demonstration; a rollout with the same `τ` reproduces it
//! at its own speed, `τ' = 2 τ` takes twice as long. Rollouts run at any `dt` (large steps are
//! split internally) and start, goal and `τ` may change while running.
//!
//! **Orientation** uses the quaternion DMP of Ude et al. 2014 ([`QuatDmp`]): one 3-D system in the
//! tangent space with `δ(q₁, q₂) = 2 log(q₂ ∗ q̄₁)` and integration by the exponential map, never
//! per-component quaternion DMPs.

mod basis;
mod canonical;
mod exp;
mod fit;
mod force;
mod quaternion;
mod rollout;
mod trajectory;

pub use self::basis::Basis;
pub use self::canonical::CanonicalSystem;
pub use self::force::{fit_force, fit_scalar};
pub use self::quaternion::{quat_error, QuatDmp, QuatRollout};
pub use self::rollout::DmpRollout;
pub use self::trajectory::Dmp;

use serde::{Deserialize, Serialize};

/// How the forcing-term weights are estimated from the demonstration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Regression {
    /// Locally weighted regression (thesis appendix A.1.1, Schaal): each weight is fitted on
    /// its own, weighted by its basis, `wᵢ = Σ ψᵢ s f / Σ ψᵢ s²`.
    Lwr,
    /// Ridge regression of all weights at once on the normalised bases:
    /// `w = (ΦᵀΦ + λ' I)⁻¹ Φᵀ f` with `λ' = lambda · trace(ΦᵀΦ) / N`.
    Ridge {
        /// Relative regularisation (dimensionless, e.g. `1e-9`).
        lambda: f64,
    },
}

/// Parameters of a DMP, shared by all its channels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DmpConfig {
    /// Number of Gaussian basis functions `N` (at least 2).
    pub n_basis: usize,
    /// Spring constant `K` (dimensionless, in units of `τ`); the damping is `D = 2 √K`.
    pub stiffness: f64,
    /// Decay rate `α_s` of the canonical system: the phase is `exp(−α_s)` at `t = τ`.
    pub alpha_s: f64,
    /// Basis overlap: a basis has decayed to `exp(−width_factor)` at its neighbour's centre.
    pub width_factor: f64,
    /// Weight estimation.
    pub regression: Regression,
}

impl Default for DmpConfig {
    fn default() -> Self {
        Self {
            n_basis: 50,
            stiffness: 156.25,
            alpha_s: 100f64.ln(),
            width_factor: 2.0,
            regression: Regression::Ridge { lambda: 1e-9 },
        }
    }
}

impl DmpConfig {
    /// The critically damped damping `D = 2 √K`.
    pub fn damping(&self) -> f64 {
        2.0 * self.stiffness.sqrt()
    }

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), DmpError> {
        let bad = |name: &'static str, reason: &str| {
            Err(DmpError::InvalidConfig {
                name,
                reason: reason.to_owned(),
            })
        };
        if !(2..=10_000).contains(&self.n_basis) {
            return bad("n_basis", "between 2 and 10000 basis functions");
        }
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return bad("stiffness", "must be a positive number");
        }
        if !(self.alpha_s.is_finite() && self.alpha_s > 0.0) {
            return bad("alpha_s", "must be a positive number");
        }
        if !(self.width_factor.is_finite() && self.width_factor > 0.0) {
            return bad("width_factor", "must be a positive number");
        }
        if let Regression::Ridge { lambda } = self.regression {
            if !(lambda.is_finite() && lambda >= 0.0) {
                return bad("lambda", "must be a non-negative number");
            }
        }
        Ok(())
    }
}

/// Problems fitting or running a DMP.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DmpError {
    /// A configuration value is out of range.
    #[error("invalid DMP parameter `{name}`: {reason}")]
    InvalidConfig {
        /// Parameter name.
        name: &'static str,
        /// Why it is rejected.
        reason: String,
    },
    /// Too few samples to estimate velocities and accelerations.
    #[error("`{what}` has {found} sample(s), a DMP needs at least {required}")]
    TooFewSamples {
        /// What was being fitted.
        what: &'static str,
        /// Samples given.
        found: usize,
        /// Samples needed.
        required: usize,
    },
    /// Times and values differ in length, or a start/goal has the wrong dimension.
    #[error("`{what}` has length {found}, expected {expected}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// Time does not strictly increase.
    #[error("time does not increase at sample {index} of `t_s`")]
    TimeNotIncreasing {
        /// 0-based sample index.
        index: usize,
    },
    /// NaN or infinite input.
    #[error("`{what}` is not finite at sample {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// 0-based sample index.
        index: usize,
    },
    /// The ridge normal equations could not be solved.
    #[error("the `ridge` normal equations are singular: increase `lambda`")]
    Singular,
}

/// Checks times: enough samples, finite, strictly increasing.
pub(crate) fn check_times(t_s: &[f64], what: &'static str) -> Result<(), DmpError> {
    if t_s.len() < 3 {
        return Err(DmpError::TooFewSamples {
            what,
            found: t_s.len(),
            required: 3,
        });
    }
    for (index, t) in t_s.iter().enumerate() {
        if !t.is_finite() {
            return Err(DmpError::NonFinite { what: "t_s", index });
        }
        if index > 0 && *t <= t_s[index - 1] {
            return Err(DmpError::TimeNotIncreasing { index });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;

//! The canonical system `τ ṡ = −α_s s` shared by all channels of a DMP.

use serde::{Deserialize, Serialize};

/// The canonical system: the phase `s` decays from 1 towards 0 as `exp(−α_s t / τ)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CanonicalSystem {
    /// Decay rate `α_s`.
    pub alpha_s: f64,
}

impl CanonicalSystem {
    /// The phase at time `t_s` for time constant `tau_s`.
    pub fn phase(&self, t_s: f64, tau_s: f64) -> f64 {
        (-self.alpha_s * t_s / tau_s).exp()
    }

    /// Advances phase `s` by `dt_s` exactly (valid for any step and for `τ` changing between steps).
    pub fn step(&self, s: f64, dt_s: f64, tau_s: f64) -> f64 {
        s * (-self.alpha_s * dt_s / tau_s).exp()
    }

    /// The time at which the phase equals `s` (inverse of [`CanonicalSystem::phase`]).
    pub fn time_of(&self, s: f64, tau_s: f64) -> f64 {
        -s.ln() * tau_s / self.alpha_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stepping_matches_closed_form_and_inverts() {
        let cs = CanonicalSystem { alpha_s: 4.0 };
        let mut s = 1.0;
        for _ in 0..1000 {
            s = cs.step(s, 0.002, 2.0);
        }
        assert!((s - cs.phase(2.0, 2.0)).abs() < 1e-12);
        assert!((cs.time_of(s, 2.0) - 2.0).abs() < 1e-9);
    }
}

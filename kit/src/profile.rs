//! The desired force of a learned force over its phase, sampled from one rollout: what the
//! eval's metrics judge a trial against and what the plots draw as the learned force.

use skill_runtime::skill::LearnedForce;

/// A learned force's desired value \[N\] every `period_s`, from the start of its phase to half
/// its duration past the end (magnitude along z; for a force vector, its magnitude), from one
/// rollout that holds its value from its duration on. Past the samples the last value holds: see
/// [`DesiredProfile::at`].
#[derive(Debug, Clone, PartialEq)]
pub struct DesiredProfile {
    period_s: f64,
    values: Vec<f64>,
}

impl DesiredProfile {
    /// Samples `force`.
    pub fn new(force: &LearnedForce, period_s: f64) -> Self {
        let values = match force {
            LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } => {
                let mut rollout = dmp.rollout();
                let steps = (dmp.tau_s * 1.5 / period_s).ceil() as usize;
                let mut values = Vec::with_capacity(steps + 1);
                for step in 0..=steps {
                    // A profile ends at its duration and holds its last value, as the
                    // controller's does (past it, without the learned term, a force that
                    // dropped steeply swings on: a contour's 0.6 N end swung to -22 N).
                    if step > 0 && rollout.time_s() < rollout.tau_s() {
                        rollout.step(dmp, period_s);
                    }
                    values.push(rollout.position().iter().map(|v| v * v).sum::<f64>().sqrt());
                }
                values
            }
            other => vec![other.value_n().unwrap_or(0.0)],
        };
        DesiredProfile { period_s, values }
    }

    /// The desired force `t` seconds into the phase.
    pub fn at(&self, t: f64) -> f64 {
        let index = ((t / self.period_s).max(0.0) as usize).min(self.values.len() - 1);
        self.values[index]
    }

    /// The largest desired force.
    pub fn peak(&self) -> f64 {
        self.values.iter().copied().fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use skill_runtime::dmp::{fit_scalar, DmpConfig};

    #[test]
    fn a_force_that_drops_steeply_at_its_end_holds_its_end_value() {
        // A contour's force: a 0.25 s touch-down, 7 + 3 sin(π s) N, a 50 ms lift-off to zero.
        let duration = 5.5;
        let t_s: Vec<f64> = (0..=5500).map(|k| k as f64 * 1e-3).collect();
        let values: Vec<f64> = t_s
            .iter()
            .map(|&t| {
                let profile = 7.0 + 3.0 * (std::f64::consts::PI * t / duration).sin();
                profile * (t / 0.25).min(1.0) * ((duration - t) / 0.05).min(1.0)
            })
            .collect();
        let dmp = fit_scalar(&DmpConfig::default(), &t_s, &values).expect("fits");
        let profile = DesiredProfile::new(&LearnedForce::Magnitude { dmp }, 0.01);
        assert!(
            (profile.peak() - 10.0).abs() < 0.3,
            "peak {} N for 10 N",
            profile.peak()
        );
        let end = profile.at(duration + 0.02);
        assert!(end < 1.5, "{end} N at the end");
        for t in [5.6, 6.0, 7.0, 8.0] {
            assert_eq!(profile.at(t), end, "at {t} s");
        }
    }
}

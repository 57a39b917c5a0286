//! The desired force of a learned force over its phase, sampled from one rollout: what the
//! eval's metrics judge a trial against and what the plots draw as the learned force.

use skill_runtime::skill::LearnedForce;

/// A learned force's desired value \[N\] every `period_s`, from the start of its phase until it
/// settles (magnitude along z; for a force vector, its magnitude), from one rollout. Past the end
/// the last value holds: see [`DesiredProfile::at`].
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
                    if step > 0 {
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

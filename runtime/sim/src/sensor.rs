//! The wrist force/torque sensor model: ideal contact wrench, then bias, seeded white noise and a
//! first-order low-pass, like a real strain-gauge wrist sensor.
//!
//! Sign convention (docs/method.md §1): the sensor measures the force the environment exerts on the tool.

use nalgebra::Vector6;
use serde::{Deserialize, Serialize};

/// Sensor settings (the `[sensor]` table of a scene file). Defaults resemble a real wrist sensor
/// (ATI Mini45 class after taring): 0.2 N / 0.005 N m noise, no bias, a 200 Hz low-pass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorConfig {
    /// Standard deviation of the white noise on each force axis, N (0 = none).
    pub noise_force_n: f64,
    /// Standard deviation of the white noise on each moment axis, N m (0 = none).
    pub noise_torque_nm: f64,
    /// Constant offset added to the reading `[fx fy fz mx my mz]` in the sensor frame.
    pub bias: [f64; 6],
    /// Cut-off of the first-order low-pass, Hz (0 or negative = no filter).
    pub cutoff_hz: f64,
    /// Seed of the noise generator: equal seeds give bit-identical runs.
    pub seed: u64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        SensorConfig {
            noise_force_n: 0.2,
            noise_torque_nm: 0.005,
            bias: [0.0; 6],
            cutoff_hz: 200.0,
            seed: 0,
        }
    }
}

impl SensorConfig {
    /// A perfect sensor: no noise, no bias, no filter.
    pub fn ideal() -> Self {
        SensorConfig {
            noise_force_n: 0.0,
            noise_torque_nm: 0.0,
            bias: [0.0; 6],
            cutoff_hz: 0.0,
            seed: 0,
        }
    }
}

/// The sensor's state: filter memory and noise generator.
#[derive(Debug, Clone)]
pub struct WristSensor {
    config: SensorConfig,
    rng: SplitMix64,
    filtered: Vector6<f64>,
    primed: bool,
}

impl WristSensor {
    /// A sensor with the given settings.
    pub fn new(config: SensorConfig) -> Self {
        WristSensor {
            config,
            rng: SplitMix64(config.seed),
            filtered: Vector6::zeros(),
            primed: false,
        }
    }

    /// The settings.
    pub fn config(&self) -> &SensorConfig {
        &self.config
    }

    /// Feeds the ideal wrench (sensor frame) of one step of `dt_s` and returns the reading.
    pub fn measure(&mut self, ideal: &Vector6<f64>, dt_s: f64) -> Vector6<f64> {
        let mut raw = *ideal;
        for axis in 0..6 {
            let sigma = if axis < 3 {
                self.config.noise_force_n
            } else {
                self.config.noise_torque_nm
            };
            raw[axis] += self.config.bias[axis];
            if sigma > 0.0 {
                raw[axis] += sigma * self.rng.normal();
            }
        }
        if self.config.cutoff_hz > 0.0 {
            if !self.primed {
                self.filtered = raw;
                self.primed = true;
            } else {
                let tau = 1.0 / (2.0 * std::f64::consts::PI * self.config.cutoff_hz);
                let alpha = dt_s / (tau + dt_s);
                self.filtered += (raw - self.filtered) * alpha;
            }
            self.filtered
        } else {
            raw
        }
    }
}

/// splitmix64: tiny, fast, seedable; plenty for sensor noise (no cryptographic use).
#[derive(Debug, Clone)]
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal by Box-Muller (one of the pair is discarded: simple and deterministic).
    fn normal(&mut self) -> f64 {
        let radius = (-2.0 * self.uniform().ln()).sqrt();
        radius * (2.0 * std::f64::consts::PI * self.uniform()).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_has_configured_spread_and_filter_removes_bias_free_mean() {
        let mut sensor = WristSensor::new(SensorConfig {
            cutoff_hz: 0.0,
            ..SensorConfig::default()
        });
        let ideal = Vector6::new(0.0, 0.0, 10.0, 0.0, 0.0, 0.0);
        let samples: Vec<f64> = (0..20_000).map(|_| sensor.measure(&ideal, 1e-3)[2]).collect();
        let mean = samples.iter().sum::<f64>() / samples.len() as f64;
        let var = samples.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / samples.len() as f64;
        assert!((mean - 10.0).abs() < 0.01, "mean {mean}");
        assert!((var.sqrt() - 0.2).abs() < 0.01, "sigma {}", var.sqrt());
    }

    #[test]
    fn low_pass_reaches_step_with_its_time_constant() {
        let mut sensor = WristSensor::new(SensorConfig {
            cutoff_hz: 10.0,
            ..SensorConfig::ideal()
        });
        sensor.measure(&Vector6::zeros(), 1e-3);
        let step = Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        // After one time constant (15.9 ms at 10 Hz) a first-order filter reads about 63 %.
        let mut reading = Vector6::zeros();
        for _ in 0..16 {
            reading = sensor.measure(&step, 1e-3);
        }
        assert!((reading[0] - 0.63).abs() < 0.03, "{}", reading[0]);
    }

    #[test]
    fn bias_is_added_and_same_seed_repeats() {
        let config = SensorConfig {
            bias: [1.0, 0.0, 0.0, 0.0, 0.0, 0.5],
            seed: 7,
            ..SensorConfig::default()
        };
        let run = || {
            let mut sensor = WristSensor::new(config);
            (0..100)
                .map(|_| sensor.measure(&Vector6::zeros(), 1e-3))
                .collect::<Vec<_>>()
        };
        assert_eq!(run(), run());
        let mut ideal = WristSensor::new(SensorConfig {
            bias: [1.0, 0.0, 0.0, 0.0, 0.0, 0.5],
            ..SensorConfig::ideal()
        });
        let reading = ideal.measure(&Vector6::zeros(), 1e-3);
        assert_eq!(reading[0], 1.0);
        assert_eq!(reading[5], 0.5);
    }
}

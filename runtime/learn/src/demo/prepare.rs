//! The preprocessing every learning run applies: the time checks, the wrench's frame, bias and
//! sign, the noise estimate, and either the template's own preprocessing or the default
//! smoothing of the motion (docs/method.md §1).

use std::fmt;

use super::filter::{low_pass_motion, FilterOrder};
use super::noise::position_noise_m;
use super::timing::{check_timing, median_step_s};
use super::wrench::{prepare_wrench, WrenchOptions, WrenchReport};
use super::{frozen_force_share, preprocess, Demo, DemoError, DemoWarning, PreprocessConfig, FROZEN_FORCE_SHARE};

/// The top of the band hand-guided motion occupies \[Hz\]: voluntary arm motion stays below
/// about 5 Hz, physiological tremor sits at 8-12 Hz with amplitudes of a tenth of a millimetre.
pub const MOTION_BAND_HZ: f64 = 10.0;

/// The default cut-off of the motion low-pass \[Hz\]: twice the motion band, where the
/// zero-phase second-order section (gain `1 / (1 + (f/F)⁴)`) keeps 94 % of 10 Hz and 99.6 % of
/// 5 Hz content, while at 1 kHz it removes all but about 5 % of the variance of white noise
/// (the band above it is 24 times wider) and, above all, the noise's second derivative, which
/// grows with `f²` and is what the forcing-term fit sees.
pub const DEFAULT_MOTION_CUTOFF_HZ: f64 = 2.0 * MOTION_BAND_HZ;

/// The cut-off stays at most this fraction of the sample rate: the section's stop band (gain
/// 1/17 at twice the cut-off) must lie below the Nyquist rate, and the bilinear transform's
/// warping stays small.
const MAX_CUTOFF_PER_RATE: f64 = 0.2;

/// Above this position noise \[m\] unsmoothed positions are called noisy: a 0.05 mm noise at
/// 1 kHz already moved a rollout by 6-11 mm RMS before motions were smoothed by default.
const NOISY_POSITION_M: f64 = 2e-5;

/// The default motion cut-off for samples at `rate_hz` \[Hz\], or `None` when the rate is too
/// low to filter without touching the motion band (below 50 Hz): [`DEFAULT_MOTION_CUTOFF_HZ`],
/// lowered to a fifth of the rate for rates under 100 Hz.
pub fn default_motion_cutoff_hz(rate_hz: f64) -> Option<f64> {
    let cutoff = DEFAULT_MOTION_CUTOFF_HZ.min(MAX_CUTOFF_PER_RATE * rate_hz);
    (cutoff >= MOTION_BAND_HZ).then_some(cutoff)
}

/// How the demonstration was smoothed before learning.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Smoothing {
    /// Positions and orientations low-passed at the default cut-off for the rate \[Hz\].
    DefaultMotion {
        /// The cut-off \[Hz\].
        cutoff_hz: f64,
    },
    /// Everything low-passed at the cut-off the template or `--lowpass` gave \[Hz\].
    Requested {
        /// The cut-off \[Hz\].
        cutoff_hz: f64,
    },
    /// Not smoothed: switched off (`--lowpass 0`).
    Off,
    /// Not smoothed: the rate is too low to filter without touching the motion.
    RateTooLow {
        /// The rate \[Hz\].
        rate_hz: f64,
    },
}

impl fmt::Display for Smoothing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Smoothing::DefaultMotion { cutoff_hz } => {
                write!(f, "motion low-pass {cutoff_hz:.0} Hz (default)")
            }
            Smoothing::Requested { cutoff_hz } => write!(f, "low-pass {cutoff_hz:.1} Hz"),
            Smoothing::Off => f.write_str("no smoothing (switched off)"),
            Smoothing::RateTooLow { rate_hz } => {
                write!(f, "no smoothing ({rate_hz:.0} Hz is too slow to filter)")
            }
        }
    }
}

/// A demonstration ready to learn from, with what was done to it and found on the way.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// The demonstration after preprocessing.
    pub demo: Demo,
    /// Warnings (gaps, noise).
    pub warnings: Vec<DemoWarning>,
    /// Estimated position noise per axis of the demonstration as read \[m\].
    pub position_noise_m: Option<f64>,
    /// How it was smoothed.
    pub smoothing: Smoothing,
    /// The wrench's frame, bias and sign, as found and settled.
    pub wrench: WrenchReport,
}

/// Prepares `demo` for learning: checks its time column ([`check_timing`]), settles its
/// wrench ([`prepare_wrench`]: frame, bias, sign), estimates its position noise, resamples it
/// when `config` says so, then low-passes it at `config`'s cut-off (everything) or, when there
/// is none, its motion at [`default_motion_cutoff_hz`]. A cut-off of 0 switches smoothing off.
pub fn prepare(demo: &Demo, config: &PreprocessConfig, wrench: &WrenchOptions) -> Result<Prepared, DemoError> {
    let mut warnings = check_timing(demo)?;
    let share = frozen_force_share(&demo.force_n);
    if share > FROZEN_FORCE_SHARE {
        warnings.push(DemoWarning::FrozenForce {
            file: demo.source.clone(),
            share,
        });
    }
    let (mut settled, report) = prepare_wrench(demo, wrench);
    if !wrench.keep_bias {
        if let Some(load) = super::air::air_load(&settled.t_s, &settled.position_m, &settled.force_n) {
            for (t, force) in settled.t_s.iter().zip(settled.force_n.iter_mut()) {
                *force -= load.at(*t);
            }
            warnings.push(DemoWarning::AirLoad {
                file: demo.source.clone(),
                largest_n: load.largest_n(),
                drift_n: load.drift_n(),
            });
        }
    }
    let wrench = report;
    let demo = &settled;
    let position_noise_m = position_noise_m(&demo.t_s, &demo.position_m);
    let explicit = PreprocessConfig {
        lowpass_cutoff_hz: config.lowpass_cutoff_hz.filter(|&hz| hz != 0.0),
        ..config.clone()
    };
    let mut out = preprocess(demo, &explicit)?;
    let smoothing = match config.lowpass_cutoff_hz {
        Some(0.0) => Smoothing::Off,
        Some(cutoff_hz) => Smoothing::Requested { cutoff_hz },
        None => {
            let rate_hz = 1.0 / median_step_s(&out.t_s);
            match default_motion_cutoff_hz(rate_hz) {
                Some(cutoff_hz) if out.len() >= 3 => {
                    out = low_pass_motion(&out, cutoff_hz, FilterOrder::Second)?;
                    Smoothing::DefaultMotion { cutoff_hz }
                }
                _ => Smoothing::RateTooLow { rate_hz },
            }
        }
    };
    if let Some(noise) = position_noise_m {
        if noise > NOISY_POSITION_M && matches!(smoothing, Smoothing::Off | Smoothing::RateTooLow { .. }) {
            warnings.push(DemoWarning::NoisyPositions {
                file: demo.source.clone(),
                noise_m: noise,
            });
        }
    }
    Ok(Prepared {
        demo: out,
        warnings,
        position_noise_m,
        smoothing,
        wrench,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_cutoff_follows_the_rate() {
        assert_eq!(default_motion_cutoff_hz(1000.0), Some(20.0));
        assert_eq!(default_motion_cutoff_hz(100.0), Some(20.0));
        assert_eq!(default_motion_cutoff_hz(74.0), Some(0.2 * 74.0));
        assert_eq!(default_motion_cutoff_hz(40.0), None);
    }

    #[test]
    fn a_force_that_stops_streaming_is_reported_as_frozen() {
        use crate::demogen::{generate, StdSkill};
        let generated = generate(StdSkill::Slide, 13);
        let mut demo = Demo {
            source: "slide.csv".into(),
            t_s: generated.samples.iter().map(|s| s.t_s).collect(),
            position_m: generated.samples.iter().map(|s| s.position_m).collect(),
            orientation: generated.samples.iter().map(|s| s.orientation).collect(),
            force_n: generated.samples.iter().map(|s| s.force_n).collect(),
            torque_nm: generated.samples.iter().map(|s| s.torque_nm).collect(),
        };
        let frozen = |demo: &Demo| {
            let prepared = prepare(demo, &PreprocessConfig::default(), &WrenchOptions::default()).expect("prepares");
            prepared
                .warnings
                .iter()
                .any(|w| matches!(w, DemoWarning::FrozenForce { .. }))
        };
        assert!(!frozen(&demo), "a streaming sensor's noise changes every sample");
        // The stream repeats each value ten times (a sensor at a tenth of the pose's rate): 90 %.
        for k in 0..demo.force_n.len() {
            demo.force_n[k] = demo.force_n[k - k % 10];
        }
        assert!((frozen_force_share(&demo.force_n) - 0.9).abs() < 0.01);
        assert!(frozen(&demo));
    }
}

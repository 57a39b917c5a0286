//! Variations of a generated demonstration (issue 26): more contact passes, position noise,
//! another rate, a slower or faster person, a tilted surface.

use nalgebra::{UnitQuaternion, Vector3};

use super::{Demonstration, TruthSurface, RATE_HZ, SURFACE_Z_M};
use crate::rng::SplitMix64;

/// How a generated demonstration departs from the shipped one (issue 26): more contact passes,
/// position noise, another rate, a slower or faster person, a tilted surface. The default
/// changes nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct Variation {
    /// Contact passes of a wipe, the tool lifted 4 cm between them, each at its own force
    /// (1: the shipped wipe; the other skills ignore it).
    pub passes: usize,
    /// White noise added to every position coordinate \[m\] (a low-grade tracker).
    pub position_noise_m: f64,
    /// The output rate \[Hz\]: every `round(1000 / rate)`-th sample is kept.
    pub rate_hz: f64,
    /// Every time multiplied by this (above 1: a slower person).
    pub time_scale: f64,
    /// The whole scene turned about base x through the surface's point \[rad\].
    pub tilt_rad: f64,
    /// A wipe over a curved part (a car door's fender) when above zero: the strokes run back and
    /// forth across the drum of `cylinder.toml`, over its crown from minus to plus this angle
    /// \[deg\] (at most 60), in continuous contact, the force along the surface's normal
    /// turning with it (the other skills ignore it).
    pub curve_deg: f64,
}

impl Default for Variation {
    fn default() -> Self {
        Variation {
            passes: 1,
            position_noise_m: 0.0,
            rate_hz: RATE_HZ,
            time_scale: 1.0,
            tilt_rad: 0.0,
            curve_deg: 0.0,
        }
    }
}

/// Applies a variation's noise, rate, time scale and tilt to a generated demonstration.
pub(super) fn vary(demo: &mut Demonstration, seed: u64, variation: &Variation) {
    let step = (RATE_HZ / variation.rate_hz).round().max(1.0) as usize;
    if step > 1 {
        demo.samples = demo.samples.iter().step_by(step).copied().collect();
        demo.truth.rate_hz = RATE_HZ / step as f64;
    }
    let scale = variation.time_scale;
    if scale != 1.0 {
        for sample in &mut demo.samples {
            sample.t_s *= scale;
        }
        for segment in &mut demo.truth.segments {
            segment.start_s *= scale;
            segment.end_s *= scale;
        }
        for turn in &mut demo.truth.turns_s {
            *turn *= scale;
        }
        demo.truth.peak_time_s *= scale;
        demo.truth.rate_hz /= scale;
    }
    if let Some(last) = demo.samples.last() {
        if let Some(segment) = demo.truth.segments.last_mut() {
            segment.end_s = last.t_s;
        }
    }
    if variation.position_noise_m > 0.0 {
        let mut rng = SplitMix64::new(seed ^ 0x05ee_d0f0_015e);
        for sample in &mut demo.samples {
            sample.position_m += Vector3::new(rng.normal(), rng.normal(), rng.normal()) * variation.position_noise_m;
        }
    }
    if variation.tilt_rad != 0.0 {
        let turn = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), variation.tilt_rad);
        let pivot = Vector3::new(0.55, 0.0, SURFACE_Z_M);
        for sample in &mut demo.samples {
            sample.position_m = pivot + turn * (sample.position_m - pivot);
            sample.orientation = turn * sample.orientation;
            sample.force_n = turn * sample.force_n;
            sample.torque_nm = turn * sample.torque_nm;
        }
        let bias = Vector3::from(demo.truth.sensor_bias_n);
        demo.truth.sensor_bias_n = (turn * bias).into();
        demo.truth.surface = match &demo.truth.surface {
            TruthSurface::Plane { point_m, normal } => TruthSurface::Plane {
                point_m: (pivot + turn * (Vector3::from(*point_m) - pivot)).into(),
                normal: (turn * Vector3::from(*normal)).into(),
            },
            TruthSurface::Cylinder {
                axis_point_m,
                axis,
                radius_m,
            } => TruthSurface::Cylinder {
                axis_point_m: (pivot + turn * (Vector3::from(*axis_point_m) - pivot)).into(),
                axis: (turn * Vector3::from(*axis)).into(),
                radius_m: *radius_m,
            },
        };
    }
}

//! How a person guides the arm: the tool's geometry, minimum-jerk reaching with a warped pace,
//! smooth tremor-like signals, the phases a demonstration is made of, and the force profile of a
//! hand pressing on a surface.

use nalgebra::{UnitQuaternion, Vector3};
use std::f64::consts::PI;

use super::{SCENE_Q0, SURFACE_Z_M, TIP_RADIUS_M};
use crate::rng::SplitMix64;
use crate::robot::{Robot, LWR4_FLANGE, LWR4_TOOL, LWR4_URDF};

/// The height of the tip's centre on the table, the button cap or the drum's top \[m\].
pub(super) const CONTACT_Z_M: f64 = SURFACE_Z_M + TIP_RADIUS_M;

/// A random amount of warp for a phase's pace (see [`warp`]).
pub(super) fn warp_of(rng: &mut SplitMix64) -> f64 {
    rng.range(-0.15, 0.15)
}

/// The tool geometry at the scenes' start configuration.
pub(super) struct Tool {
    pub(super) orientation: UnitQuaternion<f64>,
    pub(super) tip_in_flange: Vector3<f64>,
}

pub(super) fn tool() -> Tool {
    let robot = Robot::from_urdf_str(LWR4_URDF, Some(LWR4_TOOL)).expect("the bundled URDF loads");
    let flange = robot.require_link(LWR4_FLANGE).expect("the bundled URDF has a flange");
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, &SCENE_Q0);
    let flange_pose = robot.link_in_base(&data, flange);
    let tip = robot.tool_in_base(&data);
    Tool {
        orientation: flange_pose.rotation,
        tip_in_flange: flange_pose
            .inverse_transform_point(&tip.translation.vector.into())
            .coords,
    }
}

/// Minimum-jerk progress `10u³ − 15u⁴ + 6u⁵` on `[0, 1]`.
pub(super) fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
}

/// A monotone random warp of `[0, 1]` onto itself: people do not move at a steady pace.
pub(super) fn warp(u: f64, amount: f64) -> f64 {
    u + amount * (2.0 * PI * u).sin() / (2.0 * PI)
}

/// A smooth random signal: a few sinusoids with random phases.
#[derive(Debug, Clone)]
pub(super) struct Wobble {
    terms: Vec<(f64, f64, Vector3<f64>)>,
}

impl Wobble {
    pub(super) fn new(rng: &mut SplitMix64, amplitude: f64, low_hz: f64, high_hz: f64, count: usize) -> Self {
        let terms = (0..count)
            .map(|_| {
                let direction = Vector3::new(rng.normal(), rng.normal(), rng.normal());
                let direction = direction / direction.norm().max(1e-9);
                (
                    rng.range(low_hz, high_hz),
                    rng.range(0.0, 2.0 * PI),
                    direction * amplitude / (count as f64).sqrt(),
                )
            })
            .collect();
        Wobble { terms }
    }

    pub(super) fn at(&self, t: f64) -> Vector3<f64> {
        self.terms
            .iter()
            .map(|(hz, phase, v)| v * (2.0 * PI * hz * t + phase).sin())
            .sum()
    }
}

/// The state of the tip at one instant, before noise and the flange transform.
#[derive(Debug, Clone, Copy)]
pub(super) struct TipState {
    /// Tip centre \[m\].
    pub(super) position: Vector3<f64>,
    /// Outward surface normal at the contact (meaningful when `normal_force > 0`).
    pub(super) normal: Vector3<f64>,
    /// Normal force the surface exerts on the tool \[N\] (0 in free space).
    pub(super) normal_force: f64,
}

/// A phase of the demonstration: a duration and the tip state over local progress `u ∈ \[0, 1\]`.
pub(super) struct Phase {
    pub(super) label: &'static str,
    pub(super) duration_s: f64,
    pub(super) state: Box<dyn Fn(f64, f64) -> TipState>,
}

fn free(from: Vector3<f64>, to: Vector3<f64>, warp_amount: f64) -> Box<dyn Fn(f64, f64) -> TipState> {
    Box::new(move |u, _t| TipState {
        position: from + (to - from) * min_jerk(warp(u, warp_amount)),
        normal: Vector3::z(),
        normal_force: 0.0,
    })
}

/// How long a person holds still before and after a demonstration \[s\].
pub(super) const REST_S: f64 = 0.4;

/// Holding still at `at` for [`REST_S`], as a person does before and after a demonstration.
pub(super) fn rest(at: Vector3<f64>) -> Phase {
    Phase {
        label: "rest",
        duration_s: REST_S,
        state: free(at, at, 0.0),
    }
}

/// A free-space phase from `from` to `to` with a warped minimum-jerk profile.
pub(super) fn moving(
    label: &'static str,
    duration_s: f64,
    from: Vector3<f64>,
    to: Vector3<f64>,
    warp_amount: f64,
) -> Phase {
    Phase {
        label,
        duration_s,
        state: free(from, to, warp_amount),
    }
}

/// The normal force of a person pressing steadily at `level` over a contact phase of length
/// `total` ([`touch_down_lift_off`]), varying by ±4 % at 0.7 Hz (at `t`, with `phase`).
pub(super) fn pressing(local: f64, total: f64, level: f64, t: f64, phase: f64) -> f64 {
    touch_down_lift_off(local, total, level) * (1.0 + 0.04 * (2.0 * PI * 0.7 * t + phase).sin())
}

/// The normal force profile of a contact phase of length `total`: a touch-down overshoot of
/// 35 % decaying in about 80 ms, the steady `level`, and a 150 ms lift-off ramp.
pub(super) fn touch_down_lift_off(local: f64, total: f64, level: f64) -> f64 {
    let rise = 0.06;
    let lift = 0.15;
    let envelope = if local < rise {
        0.5 * (1.0 - (PI * local / rise).cos()) * 1.35
    } else {
        1.0 + 0.35 * (-(local - rise) / 0.08).exp()
    };
    let release = if local > total - lift {
        ((total - local) / lift).clamp(0.0, 1.0)
    } else {
        1.0
    };
    level * envelope * release
}

//! Synthetic kinesthetic demonstrations of the standard skills, made the way a person
//! guides the arm, in the geometry of the shipped scenes (`examples/scenes/`), with the ground
//! truth written beside each so tests and benches know the right answers.
//!
//! What imitates a person:
//! - minimum-jerk reaching between waypoints, with each phase's speed profile warped at random
//!   (a person neither moves at constant speed nor repeats a timing);
//! - hand tremor (about 0.15 mm at 8-11 Hz) and slow wander in free space; in contact only the
//!   tangential part remains, the surface holds the normal;
//! - touch-down overshoot of the normal force and a lift-off ramp, slow force variation while
//!   pressing, Coulomb friction against the sliding direction;
//! - wrist sensor noise (0.15 N, 4 mN m white) and a constant bias (about 0.2 N).
//!
//! Columns follow docs/method.md §1: the flange pose in the base frame and the wrench the environment
//! exerts on the tool, in the base frame, with the moment about the flange (sensor origin).
//! The flange-to-tip offset and the starting orientation come from the bundled LWR-IV model at
//! the scenes' start configuration, so a demonstration and a reproduction share one geometry.

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt::Write as _;

use crate::rng::SplitMix64;
use crate::robot::{Robot, LWR4_FLANGE, LWR4_TOOL, LWR4_URDF};

/// The scenes' start configuration \[rad\] (`examples/scenes/*.toml`, `robot.q0`).
pub const SCENE_Q0: [f64; 7] = [0.0, -0.5, 0.0, 1.5, 0.0, -1.141_592_653_589_793_1, 0.0];

/// Radius of the probe's spherical tip \[m\].
pub const TIP_RADIUS_M: f64 = 0.01;

/// Sampling rate of the generated demonstrations \[Hz\].
pub const RATE_HZ: f64 = 1000.0;

/// Height of the table top, the button cap and the drum's top in the shipped scenes \[m\].
pub const SURFACE_Z_M: f64 = 0.300;

/// The standard skills with a shipped demonstration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StdSkill {
    /// Touch the table and come back.
    Touch,
    /// Press the spring-loaded button.
    Press,
    /// Slide over the table at a constant force.
    Slide,
    /// Follow the drum's curved surface with a varying force.
    Contour,
    /// Wipe the table back and forth with a constant force: several strokes in one contact.
    Wipe,
    /// Press the table to a force, hold it for 2 s, release and retract.
    PressHold,
    /// Move along a curved path down to the table and stop there in light contact (the
    /// recording ends in contact).
    GuardedMove,
    /// Tap the table twice, at two spots 5 cm apart, with a hop between the taps.
    DoubleTap,
    /// Slide over the table at a light force, press harder where the slide ends, retract.
    SlideThenPress,
}

impl StdSkill {
    /// All nine: the thesis's four, in the order it presents them last to first, the wipe, then
    /// the skills of the larger library (issue 12).
    pub const ALL: [StdSkill; 9] = [
        StdSkill::Touch,
        StdSkill::Press,
        StdSkill::Slide,
        StdSkill::Contour,
        StdSkill::Wipe,
        StdSkill::PressHold,
        StdSkill::GuardedMove,
        StdSkill::DoubleTap,
        StdSkill::SlideThenPress,
    ];

    /// The skill's name (also its file stem).
    pub fn name(self) -> &'static str {
        match self {
            StdSkill::Touch => "touch",
            StdSkill::Press => "press",
            StdSkill::Slide => "slide",
            StdSkill::Contour => "contour",
            StdSkill::Wipe => "wipe",
            StdSkill::PressHold => "press_hold",
            StdSkill::GuardedMove => "guarded_move",
            StdSkill::DoubleTap => "double_tap",
            StdSkill::SlideThenPress => "slide_then_press",
        }
    }

    /// The shipped scene it is demonstrated in.
    pub fn scene(self) -> &'static str {
        match self {
            StdSkill::Touch
            | StdSkill::Slide
            | StdSkill::Wipe
            | StdSkill::PressHold
            | StdSkill::GuardedMove
            | StdSkill::DoubleTap
            | StdSkill::SlideThenPress => "table.toml",
            StdSkill::Press => "button.toml",
            StdSkill::Contour => "cylinder.toml",
        }
    }

    /// The seed of the shipped demonstration.
    pub fn default_seed(self) -> u64 {
        match self {
            StdSkill::Touch => 11,
            StdSkill::Press => 12,
            StdSkill::Slide => 13,
            StdSkill::Contour => 14,
            StdSkill::Wipe => 15,
            StdSkill::PressHold => 16,
            StdSkill::GuardedMove => 17,
            StdSkill::DoubleTap => 18,
            StdSkill::SlideThenPress => 19,
        }
    }
}

/// One sample of a demonstration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time \[s\].
    pub t_s: f64,
    /// Flange position, base frame \[m\].
    pub position_m: Vector3<f64>,
    /// Flange orientation, base frame.
    pub orientation: UnitQuaternion<f64>,
    /// Force the environment exerts on the tool, base frame \[N\].
    pub force_n: Vector3<f64>,
    /// Moment of that force about the flange, base frame \[N m\].
    pub torque_nm: Vector3<f64>,
}

/// A segment of the ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthSegment {
    /// What the person was doing.
    pub label: String,
    /// Start \[s\].
    pub start_s: f64,
    /// End \[s\].
    pub end_s: f64,
}

/// The surface touched, in the base frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TruthSurface {
    /// A plane: a point on it and its outward normal.
    Plane {
        /// A point on the plane \[m\].
        point_m: [f64; 3],
        /// Outward normal (from the surface towards the tool).
        normal: [f64; 3],
    },
    /// A cylinder: a point on its axis, the axis direction and the radius.
    Cylinder {
        /// A point on the axis \[m\].
        axis_point_m: [f64; 3],
        /// Unit axis direction.
        axis: [f64; 3],
        /// Radius \[m\].
        radius_m: f64,
    },
}

/// What the generator knows about a demonstration: the answers learning should find.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroundTruth {
    /// The skill.
    pub skill: StdSkill,
    /// The scene file it matches.
    pub scene: String,
    /// The generator seed.
    pub seed: u64,
    /// Sampling rate \[Hz\].
    pub rate_hz: f64,
    /// The probe tip centre in the flange frame \[m\].
    pub tip_in_flange_m: [f64; 3],
    /// Tip radius \[m\].
    pub tip_radius_m: f64,
    /// Phases in time order.
    pub segments: Vec<TruthSegment>,
    /// The surface.
    pub surface: TruthSurface,
    /// The characteristic applied force \[N\]: the constant force (slide), the peak (touch,
    /// press) or the mean along the normal while contouring.
    pub force_n: f64,
    /// Time of the force peak \[s\] (touch: the contact point).
    pub peak_time_s: f64,
    /// Coulomb friction coefficient used.
    pub friction: f64,
    /// Standard deviation of the sensor's force noise \[N\].
    pub sensor_noise_n: f64,
    /// The constant sensor bias added to the force \[N\].
    pub sensor_bias_n: [f64; 3],
    /// Where the strokes of a multi-stroke contact turn \[s\] (empty for the others).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub turns_s: Vec<f64>,
    /// The steady applied force of each contact phase in time order \[N\] when there are
    /// several (double tap: each tap; slide then press: the slide, then the press); empty for
    /// the others.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phase_forces_n: Vec<f64>,
    /// How long the force was held at its level \[s\] (press and hold; absent for the others).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_s: Option<f64>,
}

/// A generated demonstration.
#[derive(Debug, Clone, PartialEq)]
pub struct Demonstration {
    /// Samples at [`RATE_HZ`].
    pub samples: Vec<Sample>,
    /// What it contains.
    pub truth: GroundTruth,
}

/// The tool geometry at the scenes' start configuration.
struct Tool {
    orientation: UnitQuaternion<f64>,
    tip_in_flange: Vector3<f64>,
}

fn tool() -> Tool {
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
fn min_jerk(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
}

/// A monotone random warp of `[0, 1]` onto itself: people do not move at a steady pace.
fn warp(u: f64, amount: f64) -> f64 {
    u + amount * (2.0 * PI * u).sin() / (2.0 * PI)
}

/// A smooth random signal: a few sinusoids with random phases.
#[derive(Debug, Clone)]
struct Wobble {
    terms: Vec<(f64, f64, Vector3<f64>)>,
}

impl Wobble {
    fn new(rng: &mut SplitMix64, amplitude: f64, low_hz: f64, high_hz: f64, count: usize) -> Self {
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

    fn at(&self, t: f64) -> Vector3<f64> {
        self.terms
            .iter()
            .map(|(hz, phase, v)| v * (2.0 * PI * hz * t + phase).sin())
            .sum()
    }
}

/// The state of the tip at one instant, before noise and the flange transform.
#[derive(Debug, Clone, Copy)]
struct TipState {
    /// Tip centre \[m\].
    position: Vector3<f64>,
    /// Outward surface normal at the contact (meaningful when `normal_force > 0`).
    normal: Vector3<f64>,
    /// Normal force the surface exerts on the tool \[N\] (0 in free space).
    normal_force: f64,
}

/// A phase of the demonstration: a duration and the tip state over local progress `u ∈ \[0, 1\]`.
struct Phase {
    label: &'static str,
    duration_s: f64,
    state: Box<dyn Fn(f64, f64) -> TipState>,
}

fn free(from: Vector3<f64>, to: Vector3<f64>, warp_amount: f64) -> Box<dyn Fn(f64, f64) -> TipState> {
    Box::new(move |u, _t| TipState {
        position: from + (to - from) * min_jerk(warp(u, warp_amount)),
        normal: Vector3::z(),
        normal_force: 0.0,
    })
}

/// How long a person holds still before and after a demonstration \[s\].
const REST_S: f64 = 0.4;

/// Holding still at `at` for [`REST_S`], as a person does before and after a demonstration.
fn rest(at: Vector3<f64>) -> Phase {
    Phase {
        label: "rest",
        duration_s: REST_S,
        state: free(at, at, 0.0),
    }
}

/// A free-space phase from `from` to `to` with a warped minimum-jerk profile.
fn moving(label: &'static str, duration_s: f64, from: Vector3<f64>, to: Vector3<f64>, warp_amount: f64) -> Phase {
    Phase {
        label,
        duration_s,
        state: free(from, to, warp_amount),
    }
}

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

/// Generates the demonstration of `skill` with `seed`.
pub fn generate(skill: StdSkill, seed: u64) -> Demonstration {
    generate_varied(skill, seed, &Variation::default())
}

/// Generates the demonstration of `skill` with `seed`, varied as `variation` says.
pub fn generate_varied(skill: StdSkill, seed: u64, variation: &Variation) -> Demonstration {
    let mut demo = generate_at_1khz(skill, seed, variation);
    vary(&mut demo, seed, variation);
    demo
}

/// Applies a variation's noise, rate, time scale and tilt to a generated demonstration.
fn vary(demo: &mut Demonstration, seed: u64, variation: &Variation) {
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

fn generate_at_1khz(skill: StdSkill, seed: u64, variation: &Variation) -> Demonstration {
    let mut rng = SplitMix64::new(seed);
    let tool = tool();
    let contact_z = SURFACE_Z_M + TIP_RADIUS_M;
    let warp_of = |rng: &mut SplitMix64| rng.range(-0.15, 0.15);
    let mut phases: Vec<Phase> = Vec::new();
    let mut turns_s = Vec::new();
    let mut phase_forces_n = Vec::new();
    let mut hold_s = None;
    let surface;
    let friction;
    let force_n;
    let up = Vector3::z();

    match skill {
        StdSkill::Slide => {
            friction = 0.4;
            let f0 = 10.0;
            force_n = f0;
            let hover = Vector3::new(0.48, -0.08, 0.365);
            let c1 = Vector3::new(0.48, -0.08, contact_z);
            let c2 = Vector3::new(0.62, 0.07, contact_z);
            let leave = Vector3::new(0.64, 0.09, 0.37);
            let (w1, w2, w3) = (warp_of(&mut rng), warp_of(&mut rng), warp_of(&mut rng));
            let slow_phase = rng.range(0.0, 2.0 * PI);
            let settle = 0.25;
            let slide_s = rng.range(4.0, 4.4);
            let contact_s = settle + slide_s + settle;
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(1.5, 1.8), hover, c1, w1));
            phases.push(Phase {
                label: "slide",
                duration_s: contact_s,
                state: Box::new(move |u, t| {
                    let local = u * contact_s;
                    let s = ((local - settle) / slide_s).clamp(0.0, 1.0);
                    let progress = min_jerk(warp(s, w2));
                    let lateral = Vector3::new(0.0, 0.02 * (PI * progress).sin(), 0.0);
                    let position = c1 + (c2 - c1) * progress + lateral;
                    let force = pressing(local, contact_s, f0, t, slow_phase);
                    TipState {
                        position,
                        normal: up,
                        normal_force: force,
                    }
                }),
            });
            phases.push(moving("leave", rng.range(1.4, 1.7), c2, leave, w3));
            phases.push(rest(leave));
            surface = TruthSurface::Plane {
                point_m: [0.55, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
        StdSkill::Wipe => {
            friction = 0.4;
            let f0 = 8.0;
            force_n = f0;
            // A curved part: the drum of `cylinder.toml` (axis along y through (0.5466, ·, 0.15),
            // radius 0.15 m), wiped across its crown.
            let curved = variation.curve_deg > 0.0;
            let drum_centre = Vector3::new(0.5466, 0.0, 0.15);
            let drum_radius = 0.15 + TIP_RADIUS_M;
            let half_arc = variation.curve_deg.min(60.0).to_radians();
            let (first_angle, last_angle) = (-half_arc, half_arc);
            let radial = |angle: f64| Vector3::new(angle.sin(), 0.0, angle.cos());
            let (hover, c1, c2, leave) = if curved {
                let c1 = drum_centre + radial(first_angle) * drum_radius;
                let c2 = drum_centre + radial(last_angle) * drum_radius;
                (c1 + up * 0.06, c1, c2, c1 + Vector3::new(0.02, 0.02, 0.065))
            } else {
                (
                    Vector3::new(0.50, -0.06, 0.365),
                    Vector3::new(0.50, -0.06, contact_z),
                    Vector3::new(0.60, 0.04, contact_z),
                    Vector3::new(0.52, -0.04, 0.37),
                )
            };
            // Where the tip is and the surface's normal there, `along` the stroke (0 at `c1`, 1
            // at `c2`) and `bow` to its side.
            let side = if curved {
                Vector3::y()
            } else {
                Vector3::new(-(c2 - c1).y, (c2 - c1).x, 0.0).normalize()
            };
            let place = move |along: f64, bow: f64| {
                if curved {
                    let normal = radial(first_angle + (last_angle - first_angle) * along);
                    (drum_centre + normal * drum_radius + side * bow, normal)
                } else {
                    (c1 + (c2 - c1) * along + side * bow, up)
                }
            };
            let (w1, w3) = (warp_of(&mut rng), warp_of(&mut rng));
            // Four strokes: out, back, out, back, each with its own timing and a sideways bow
            // (a hand does not retrace its path).
            let draw_strokes = |rng: &mut SplitMix64| -> Vec<(f64, f64, f64)> {
                (0..4)
                    .map(|_| (rng.range(0.9, 1.2), warp_of(rng), rng.range(-0.012, 0.012)))
                    .collect()
            };
            let strokes = draw_strokes(&mut rng);
            let settle = 0.25;
            let approach_s = rng.range(1.5, 1.8);
            let slow_phase = rng.range(0.0, 2.0 * PI);
            phases.push(rest(hover));
            phases.push(moving("approach", approach_s, hover, c1, w1));
            let mut at = REST_S + approach_s;
            let mut pass = |strokes: Vec<(f64, f64, f64)>, level: f64, at: f64, phases: &mut Vec<Phase>| {
                let wiping_s: f64 = strokes.iter().map(|s| s.0).sum();
                let contact_s = settle + wiping_s + settle;
                let mut turn = at + settle;
                for stroke in &strokes[..strokes.len() - 1] {
                    turn += stroke.0;
                    turns_s.push(turn);
                }
                phases.push(Phase {
                    label: "wipe",
                    duration_s: contact_s,
                    state: Box::new(move |u, t| {
                        let local = u * contact_s;
                        let mut begin = settle;
                        let mut along = 0.0;
                        let mut bow = 0.0;
                        for (k, (duration, warp_amount, sway)) in strokes.iter().enumerate() {
                            if local >= begin {
                                let progress =
                                    min_jerk(warp(((local - begin) / duration).clamp(0.0, 1.0), *warp_amount));
                                along = if k.is_multiple_of(2) { progress } else { 1.0 - progress };
                                bow = sway * (PI * progress).sin();
                            }
                            begin += duration;
                        }
                        let (position, normal) = place(along, bow);
                        let force = pressing(local, contact_s, level, t, slow_phase);
                        TipState {
                            position,
                            normal,
                            normal_force: force,
                        }
                    }),
                });
                contact_s
            };
            at += pass(strokes, f0, at, &mut phases);
            // More passes (variants only): lift 4 cm, come back down and wipe again, each pass
            // at its own force.
            if variation.passes > 1 {
                phase_forces_n.push(f0);
            }
            for _ in 1..variation.passes {
                let top = c1 + up * 0.04;
                let (lift_s, back_s) = (rng.range(0.8, 1.0), rng.range(0.8, 1.0));
                phases.push(moving("lift", lift_s, c1, top, warp_of(&mut rng)));
                phases.push(moving("return", back_s, top, c1, warp_of(&mut rng)));
                at += lift_s + back_s;
                let strokes = draw_strokes(&mut rng);
                let level = rng.range(6.0, 14.0);
                phase_forces_n.push(level);
                at += pass(strokes, level, at, &mut phases);
            }
            phases.push(moving("leave", rng.range(1.4, 1.7), c1, leave, w3));
            phases.push(rest(leave));
            surface = if curved {
                TruthSurface::Cylinder {
                    axis_point_m: drum_centre.into(),
                    axis: [0.0, 1.0, 0.0],
                    radius_m: 0.15,
                }
            } else {
                TruthSurface::Plane {
                    point_m: [0.55, 0.0, SURFACE_Z_M],
                    normal: [0.0, 0.0, 1.0],
                }
            };
        }
        StdSkill::Touch => {
            friction = 0.4;
            let peak = 4.0;
            force_n = peak;
            let hover = Vector3::new(0.5466, 0.0, 0.37);
            let contact = Vector3::new(0.5466, 0.0, contact_z);
            let back = Vector3::new(0.5466, 0.02, 0.37);
            let (w1, w2) = (warp_of(&mut rng), warp_of(&mut rng));
            let (rise, fall) = (rng.range(0.08, 0.1), rng.range(0.1, 0.12));
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(2.0, 2.3), hover, contact, w1));
            phases.push(Phase {
                label: "touch",
                duration_s: rise + fall,
                state: Box::new(move |u, _t| {
                    let local = u * (rise + fall);
                    let force = if local < rise {
                        peak * 0.5 * (1.0 - (PI * local / rise).cos())
                    } else {
                        peak * 0.5 * (1.0 + (PI * (local - rise) / fall).cos())
                    };
                    TipState {
                        position: contact,
                        normal: up,
                        normal_force: force,
                    }
                }),
            });
            phases.push(moving("return", rng.range(1.9, 2.2), contact, back, w2));
            phases.push(rest(back));
            surface = TruthSurface::Plane {
                point_m: [0.5466, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
        StdSkill::Press => {
            friction = 0.6;
            let peak = 8.0;
            force_n = peak;
            // The button of `button.toml`: 2 N preload, 400 N/m, 8 mm of travel.
            let (preload, stiffness, travel) = (2.0, 400.0, 0.008);
            let hover = Vector3::new(0.5466, 0.0, 0.37);
            let contact = Vector3::new(0.5466, 0.0, contact_z);
            let back = Vector3::new(0.5466, -0.02, 0.37);
            let (w1, w2) = (warp_of(&mut rng), warp_of(&mut rng));
            let (rise, hold, release) = (rng.range(0.8, 1.0), rng.range(0.7, 0.9), rng.range(0.9, 1.1));
            let total = rise + hold + release;
            let wobble_phase = rng.range(0.0, 2.0 * PI);
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(1.9, 2.2), hover, contact, w1));
            phases.push(Phase {
                label: "press",
                duration_s: total,
                state: Box::new(move |u, t| {
                    let local = u * total;
                    let mut force = if local < rise {
                        peak * min_jerk(local / rise)
                    } else if local < rise + hold {
                        peak * (1.0 + 0.03 * (2.0 * PI * 1.3 * t + wobble_phase).sin())
                    } else {
                        peak * (1.0 - min_jerk((local - rise - hold) / release))
                    };
                    force = force.max(0.0);
                    let depth = ((force - preload) / stiffness).clamp(0.0, travel);
                    TipState {
                        position: contact - up * depth,
                        normal: up,
                        normal_force: force,
                    }
                }),
            });
            phases.push(moving("retract", rng.range(1.5, 1.8), contact, back, w2));
            phases.push(rest(back));
            surface = TruthSurface::Plane {
                point_m: [0.5466, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
        StdSkill::Contour => {
            friction = 0.3;
            // The drum of `cylinder.toml`: axis along y through (0.5466, ·, 0.15), radius 0.15 m.
            let centre = Vector3::new(0.5466, 0.0, 0.15);
            let radius = 0.15 + TIP_RADIUS_M;
            let (start_angle, end_angle) = (-30f64.to_radians(), 30f64.to_radians());
            let radial = move |angle: f64| Vector3::new(angle.sin(), 0.0, angle.cos());
            let hover = centre + radial(start_angle) * (radius + 0.06);
            let c1 = centre + radial(start_angle) * radius;
            let c2 = centre + radial(end_angle) * radius;
            let leave = centre + radial(end_angle) * (radius + 0.06);
            let (w1, w2, w3) = (warp_of(&mut rng), warp_of(&mut rng), warp_of(&mut rng));
            let settle = 0.25;
            let follow_s = rng.range(4.8, 5.2);
            let contact_s = settle + follow_s + settle;
            let (base, swing) = (7.0, 3.0);
            // Mean of base + swing·sin(π s) over the contour.
            force_n = base + swing * 2.0 / PI;
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(1.5, 1.8), hover, c1, w1));
            phases.push(Phase {
                label: "contour",
                duration_s: contact_s,
                state: Box::new(move |u, _t| {
                    let local = u * contact_s;
                    let s = ((local - settle) / follow_s).clamp(0.0, 1.0);
                    let progress = min_jerk(warp(s, w2));
                    let angle = start_angle + (end_angle - start_angle) * progress;
                    let normal = radial(angle);
                    let mut position = centre + normal * radius;
                    position.y = 0.01 * (PI * progress).sin();
                    let profile = base + swing * (PI * s).sin();
                    let force = touch_down_lift_off(local, contact_s, 1.0) * profile;
                    TipState {
                        position,
                        normal,
                        normal_force: force,
                    }
                }),
            });
            phases.push(moving("leave", rng.range(1.4, 1.7), c2, leave, w3));
            phases.push(rest(leave));
            surface = TruthSurface::Cylinder {
                axis_point_m: centre.into(),
                axis: [0.0, 1.0, 0.0],
                radius_m: 0.15,
            };
        }

        StdSkill::PressHold => {
            friction = 0.5;
            let level = 12.0;
            force_n = level;
            let hover = Vector3::new(0.5466, 0.0, 0.37);
            let contact = Vector3::new(0.5466, 0.0, contact_z);
            let back = Vector3::new(0.5466, 0.02, 0.37);
            let (w1, w2) = (warp_of(&mut rng), warp_of(&mut rng));
            // A person leans in over a few tenths of a second, holds the force as steadily as a
            // hand can (±3 % at about 1 Hz) for the 2 s asked, and lets go a little faster.
            let (rise, release) = (rng.range(0.35, 0.45), rng.range(0.25, 0.35));
            let hold = 2.0;
            hold_s = Some(hold);
            let total = rise + hold + release;
            let wobble_phase = rng.range(0.0, 2.0 * PI);
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(1.9, 2.2), hover, contact, w1));
            phases.push(Phase {
                label: "press_hold",
                duration_s: total,
                state: Box::new(move |u, t| {
                    let local = u * total;
                    let force = if local < rise {
                        level * min_jerk(local / rise)
                    } else if local < rise + hold {
                        level * (1.0 + 0.03 * (2.0 * PI * 0.9 * t + wobble_phase).sin())
                    } else {
                        level * (1.0 - min_jerk((local - rise - hold) / release))
                    };
                    TipState {
                        position: contact,
                        normal: up,
                        normal_force: force.max(0.0),
                    }
                }),
            });
            phases.push(moving("retract", rng.range(1.5, 1.8), contact, back, w2));
            phases.push(rest(back));
            surface = TruthSurface::Plane {
                point_m: [0.5466, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
        StdSkill::GuardedMove => {
            friction = 0.4;
            let level = 3.0;
            force_n = level;
            let start = Vector3::new(0.5466, 0.0, 0.37);
            let goal = Vector3::new(0.60, 0.07, contact_z);
            let w1 = warp_of(&mut rng);
            let move_s = rng.range(2.6, 3.0);
            let hold_phase = rng.range(0.0, 2.0 * PI);
            phases.push(rest(start));
            // Across first, then down: the sideways travel ends before the tool meets the table,
            // which it meets nearly straight down (a person lowers a tool onto a surface).
            phases.push(Phase {
                label: "move",
                duration_s: move_s,
                state: Box::new(move |u, _t| {
                    let across = min_jerk(warp((u / 0.85).clamp(0.0, 1.0), w1));
                    let down = min_jerk(((u - 0.25) / 0.75).clamp(0.0, 1.0));
                    let mut position = start + (goal - start) * across;
                    position.z = start.z + (goal.z - start.z) * down;
                    TipState {
                        position,
                        normal: up,
                        normal_force: 0.0,
                    }
                }),
            });
            // The light touch-down and the steady hold; the recording ends in contact.
            let contact_s = rng.range(1.2, 1.4);
            phases.push(Phase {
                label: "contact",
                duration_s: contact_s,
                state: Box::new(move |u, t| TipState {
                    position: goal,
                    normal: up,
                    normal_force: pressing(u * contact_s, f64::INFINITY, level, t, hold_phase),
                }),
            });
            surface = TruthSurface::Plane {
                point_m: [0.55, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
        StdSkill::DoubleTap => {
            friction = 0.4;
            let (first, second) = (5.0, 6.0);
            force_n = first;
            phase_forces_n = vec![first, second];
            let hover = Vector3::new(0.52, -0.05, 0.37);
            let spot1 = Vector3::new(0.52, -0.02, contact_z);
            let spot2 = Vector3::new(0.56, 0.01, contact_z);
            let leave = Vector3::new(0.58, 0.03, 0.37);
            let (w1, w2, w3) = (warp_of(&mut rng), warp_of(&mut rng), warp_of(&mut rng));
            let wobble_phase = rng.range(0.0, 2.0 * PI);
            // A tap: down, a short press at a steady force (long enough to be a tap one means,
            // half a second), up.
            let tap = |label: &'static str, at: Vector3<f64>, level: f64, duration_s: f64| Phase {
                label,
                duration_s,
                state: Box::new(move |u, t| TipState {
                    position: at,
                    normal: up,
                    normal_force: touch_down_lift_off(u * duration_s, duration_s, level)
                        * (1.0 + 0.03 * (2.0 * PI * 1.1 * t + wobble_phase).sin()),
                }),
            };
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(1.8, 2.1), hover, spot1, w1));
            phases.push(tap("tap", spot1, first, rng.range(0.55, 0.65)));
            // The hop: up 2.5 cm nearly straight, across, and down nearly straight onto the
            // second spot.
            let height = 0.025;
            phases.push(Phase {
                label: "hop",
                duration_s: rng.range(1.1, 1.3),
                state: Box::new(move |u, _t| {
                    let across = min_jerk(warp(((u - 0.15) / 0.7).clamp(0.0, 1.0), w2));
                    let lift = if u < 0.5 {
                        min_jerk(u / 0.4)
                    } else {
                        1.0 - min_jerk((u - 0.55) / 0.45)
                    };
                    let mut position = spot1 + (spot2 - spot1) * across;
                    position.z += height * lift;
                    TipState {
                        position,
                        normal: up,
                        normal_force: 0.0,
                    }
                }),
            });
            phases.push(tap("tap", spot2, second, rng.range(0.55, 0.65)));
            phases.push(moving("leave", rng.range(1.4, 1.7), spot2, leave, w3));
            phases.push(rest(leave));
            surface = TruthSurface::Plane {
                point_m: [0.55, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
        StdSkill::SlideThenPress => {
            friction = 0.4;
            let (light, firm) = (5.0, 15.0);
            force_n = light;
            phase_forces_n = vec![light, firm];
            let hover = Vector3::new(0.48, -0.08, 0.365);
            let c1 = Vector3::new(0.48, -0.08, contact_z);
            let c2 = Vector3::new(0.60, 0.02, contact_z);
            let leave = Vector3::new(0.62, 0.04, 0.37);
            let (w1, w2, w3) = (warp_of(&mut rng), warp_of(&mut rng), warp_of(&mut rng));
            let slow_phase = rng.range(0.0, 2.0 * PI);
            // One slow variation of the hand's force (±4 % at 0.7 Hz) over both contact phases.
            let vary = move |t: f64| 1.0 + 0.04 * (2.0 * PI * 0.7 * t + slow_phase).sin();
            let (settle, pause) = (0.25, 0.15);
            let slide_s = rng.range(3.0, 3.4);
            let sliding_s = settle + slide_s + pause;
            let (ramp, hold, release) = (rng.range(0.35, 0.45), rng.range(0.9, 1.1), rng.range(0.25, 0.35));
            let pressing_s = ramp + hold + release;
            phases.push(rest(hover));
            phases.push(moving("approach", rng.range(1.5, 1.8), hover, c1, w1));
            phases.push(Phase {
                label: "slide",
                duration_s: sliding_s,
                state: Box::new(move |u, t| {
                    let local = u * sliding_s;
                    let s = ((local - settle) / slide_s).clamp(0.0, 1.0);
                    let progress = min_jerk(warp(s, w2));
                    let lateral = Vector3::new(0.0, 0.015 * (PI * progress).sin(), 0.0);
                    TipState {
                        position: c1 + (c2 - c1) * progress + lateral,
                        normal: up,
                        normal_force: touch_down_lift_off(local, f64::INFINITY, light) * vary(t),
                    }
                }),
            });
            // At the slide's end, still: lean in to the firm force, hold it, let go.
            phases.push(Phase {
                label: "press",
                duration_s: pressing_s,
                state: Box::new(move |u, t| {
                    let local = u * pressing_s;
                    let level = if local < ramp {
                        light + (firm - light) * min_jerk(local / ramp)
                    } else if local < ramp + hold {
                        firm
                    } else {
                        firm * (1.0 - min_jerk((local - ramp - hold) / release))
                    };
                    TipState {
                        position: c2,
                        normal: up,
                        normal_force: level * vary(t),
                    }
                }),
            });
            phases.push(moving("leave", rng.range(1.4, 1.7), c2, leave, w3));
            phases.push(rest(leave));
            surface = TruthSurface::Plane {
                point_m: [0.55, 0.0, SURFACE_Z_M],
                normal: [0.0, 0.0, 1.0],
            };
        }
    }

    // Person and sensor imperfections.
    let tremor = Wobble::new(&mut rng, 0.15e-3, 8.0, 11.0, 3);
    let wander = Wobble::new(&mut rng, 0.4e-3, 0.2, 0.6, 2);
    let wrist = Wobble::new(&mut rng, 0.2f64.to_radians(), 6.0, 9.0, 2);
    let drift = Wobble::new(&mut rng, 0.5f64.to_radians(), 0.1, 0.3, 2);
    let force_noise = 0.15;
    let torque_noise = 0.004;
    let bias = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.2;
    let torque_bias = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.005;

    let dt = 1.0 / RATE_HZ;
    let mut samples = Vec::new();
    let mut segments = Vec::new();
    let mut t0 = 0.0;
    let mut previous_tip: Option<Vector3<f64>> = None;
    let mut peak = (0.0f64, 0.0f64);
    for phase in &phases {
        let n = (phase.duration_s * RATE_HZ).round() as usize;
        let start_s = t0;
        for k in 0..n {
            let t = t0 + k as f64 * dt;
            let u = k as f64 / n as f64;
            let state = (phase.state)(u, t);
            let in_contact = state.normal_force > 0.0;
            // In contact, static friction holds the tip against the hand's tremor: the tremor
            // shows in the force instead, and only the intended path slides.
            let shake = if in_contact {
                Vector3::zeros()
            } else {
                tremor.at(t) + wander.at(t)
            };
            let tip = state.position + shake;
            let velocity = previous_tip.map_or(Vector3::zeros(), |p| (tip - p) / dt);
            previous_tip = Some(tip);
            let tangential = velocity - state.normal * state.normal.dot(&velocity);
            let friction_force = -tangential * (friction * state.normal_force / tangential.norm().max(0.005));
            let hand = if in_contact {
                tremor.at(t) * (state.normal_force * 400.0)
            } else {
                Vector3::zeros()
            };
            let force = state.normal * state.normal_force + friction_force + hand;
            if state.normal_force > peak.1 {
                peak = (t, state.normal_force);
            }
            let rotation_vector = wrist.at(t) + drift.at(t);
            let orientation = UnitQuaternion::from_scaled_axis(rotation_vector) * tool.orientation;
            let flange = tip - orientation * tool.tip_in_flange;
            let contact_point = tip - state.normal * TIP_RADIUS_M;
            let torque = (contact_point - flange).cross(&force);
            let noise = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * force_noise;
            let torque_noise_v = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * torque_noise;
            samples.push(Sample {
                t_s: t,
                position_m: flange,
                orientation,
                force_n: force + bias + noise,
                torque_nm: torque + torque_bias + torque_noise_v,
            });
        }
        t0 += n as f64 * dt;
        if phase.label != "rest" {
            segments.push(TruthSegment {
                label: phase.label.to_string(),
                start_s,
                end_s: t0,
            });
        }
    }
    // The rests belong to the neighbouring motion: the first to the approach, the last to the leaving.
    if let Some(first) = segments.first_mut() {
        first.start_s = 0.0;
    }
    if let Some(last) = segments.last_mut() {
        last.end_s = t0 - dt;
    }

    Demonstration {
        samples,
        truth: GroundTruth {
            skill,
            scene: if skill == StdSkill::Wipe && variation.curve_deg > 0.0 {
                "cylinder.toml".to_string()
            } else {
                skill.scene().to_string()
            },
            seed,
            rate_hz: RATE_HZ,
            tip_in_flange_m: tool.tip_in_flange.into(),
            tip_radius_m: TIP_RADIUS_M,
            segments,
            surface,
            force_n,
            peak_time_s: peak.0,
            friction,
            sensor_noise_n: force_noise,
            sensor_bias_n: bias.into(),
            turns_s,
            phase_forces_n,
            hold_s,
        },
    }
}

/// The normal force of a person pressing steadily at `level` over a contact phase of length
/// `total` ([`touch_down_lift_off`]), varying by ±4 % at 0.7 Hz (at `t`, with `phase`).
fn pressing(local: f64, total: f64, level: f64, t: f64, phase: f64) -> f64 {
    touch_down_lift_off(local, total, level) * (1.0 + 0.04 * (2.0 * PI * 0.7 * t + phase).sin())
}

/// The normal force profile of a contact phase of length `total`: a touch-down overshoot of
/// 35 % decaying in about 80 ms, the steady `level`, and a 150 ms lift-off ramp.
fn touch_down_lift_off(local: f64, total: f64, level: f64) -> f64 {
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

/// The demonstration as CSV with the columns of docs/method.md §1 (6 decimals: µm, µN).
pub fn to_csv(demo: &Demonstration) -> String {
    let mut out = String::with_capacity(demo.samples.len() * 120);
    out.push_str("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
    for sample in &demo.samples {
        let q = sample.orientation.quaternion();
        let _ = writeln!(
            out,
            "{:.4},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.4},{:.4},{:.4},{:.5},{:.5},{:.5}",
            sample.t_s,
            sample.position_m.x,
            sample.position_m.y,
            sample.position_m.z,
            q.w,
            q.i,
            q.j,
            q.k,
            sample.force_n.x,
            sample.force_n.y,
            sample.force_n.z,
            sample.torque_nm.x,
            sample.torque_nm.y,
            sample.torque_nm.z,
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generation_is_deterministic_and_seed_dependent() {
        let a = generate(StdSkill::Slide, 5);
        let b = generate(StdSkill::Slide, 5);
        let c = generate(StdSkill::Slide, 6);
        assert_eq!(to_csv(&a), to_csv(&b));
        assert_ne!(to_csv(&a), to_csv(&c));
    }

    #[test]
    fn the_tip_stays_on_the_surface_while_the_force_is_on() {
        for skill in StdSkill::ALL {
            let demo = generate(skill, skill.default_seed());
            let tip_offset = Vector3::from(demo.truth.tip_in_flange_m);
            for sample in &demo.samples {
                let tip = sample.position_m + sample.orientation * tip_offset;
                let normal_force = (sample.force_n - Vector3::from(demo.truth.sensor_bias_n)).norm();
                let gap = match &demo.truth.surface {
                    TruthSurface::Plane { point_m, normal } => {
                        (tip - Vector3::from(*point_m)).dot(&Vector3::from(*normal)) - TIP_RADIUS_M
                    }
                    TruthSurface::Cylinder {
                        axis_point_m, radius_m, ..
                    } => {
                        let d = tip - Vector3::from(*axis_point_m);
                        (d.x * d.x + d.z * d.z).sqrt() - radius_m - TIP_RADIUS_M
                    }
                };
                assert!(
                    gap > -0.0085,
                    "{skill:?}: the tip goes {gap} m into the surface at {}",
                    sample.t_s
                );
                if normal_force > 3.0 && skill != StdSkill::Press {
                    assert!(
                        gap.abs() < 1e-3,
                        "{skill:?}: pressing {normal_force} N while {gap} m away at {}",
                        sample.t_s
                    );
                }
            }
        }
    }

    #[test]
    fn ground_truth_segments_cover_the_demonstration_in_order() {
        for skill in StdSkill::ALL {
            let demo = generate(skill, skill.default_seed());
            let segments = &demo.truth.segments;
            let expected = match skill {
                StdSkill::GuardedMove => 2,
                StdSkill::SlideThenPress => 4,
                StdSkill::DoubleTap => 5,
                _ => 3,
            };
            assert_eq!(segments.len(), expected, "{skill:?}");
            assert_eq!(segments[0].start_s, 0.0);
            for pair in segments.windows(2) {
                assert!((pair[0].end_s - pair[1].start_s).abs() < 1e-9);
            }
            let last = demo.samples.last().expect("samples").t_s;
            assert!((segments[segments.len() - 1].end_s - last).abs() < 1e-9);
        }
    }
}

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
//!
//! The parts: `person` (how a person moves and presses), `pressing` and `sliding` (each skill's
//! phases, by family), `record` (the phases sampled with the person's and the sensor's
//! imperfections), `vary` ([`Variation`]), `csv_text` ([`to_csv`]).

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

mod csv_text;
mod person;
mod pressing;
mod record;
mod sliding;
mod vary;

#[cfg(test)]
mod tests;

pub use csv_text::to_csv;
pub use vary::Variation;

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

/// Generates the demonstration of `skill` with `seed`.
pub fn generate(skill: StdSkill, seed: u64) -> Demonstration {
    generate_varied(skill, seed, &Variation::default())
}

/// Generates the demonstration of `skill` with `seed`, varied as `variation` says.
pub fn generate_varied(skill: StdSkill, seed: u64, variation: &Variation) -> Demonstration {
    let mut demo = record::generate_at_1khz(skill, seed, variation);
    vary::vary(&mut demo, seed, variation);
    demo
}

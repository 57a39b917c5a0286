//! The serde state-machine IR: the one contract between the skillc compiler and its runtime.
//!
//! A [`Program`] is what `skillc compile` writes: every skill a `.skill` file defines or
//! imports, lowered to a flat arena of states and transitions with index ids, each with
//! its learning plan, plus the file's tasks. The runtime never re-parses source: it reads
//! this, and the [`SourceSpan`]s let it point runtime messages back at the `.skill` text.
//!
//! Conventions used by every field:
//! - Quantities are SI: metres, seconds, newtons, newton-metres, radians; the unit is in
//!   the field name (`_m`, `_s`, `_n`, `_mps`, `_hz`) or its doc.
//! - Axes are ordered `x y z rx ry rz`: translations then rotations about the frame's axes.
//! - Forces are the force the ROBOT applies to the environment (the negative of what the
//!   wrist sensor measures, which is the force the environment exerts on the tool), so a
//!   positive force along a contact frame's z presses into the surface.
//! - Segments are 0-based here (`segment 1` in source is `SegmentIdx(0)`).

#![warn(missing_docs)]

use serde::{Deserialize, Serialize};

/// The IR format version. Bump on every change to the serialized form.
///
/// - 1: the first format.
/// - 2: skills and task steps may carry supervisor [`Limit`]s, active states an [`Approach`]
///   and a [`LiftOffSpec`], and guards may be [`Guard::Held`] (all optional: a version 1 file
///   reads as a version 2 file without them).
/// - 3: a motion may be learned as [`Strokes`] and an active state may [`ActiveState::repeat`]
///   its motion (both optional: a version 2 file reads as a version 3 file without them).
/// - 4: guards may be [`Guard::Moved`], [`Guard::MovedDistance`], [`Guard::ForceMagnitude`] and
///   [`Guard::MomentMagnitude`] (new variants only: a version 3 file reads as a version 4 file).
///   Version 5 adds [`Guard::Speed`], [`Guard::Entered`] and [`Point::PeakForceIn`].
/// - 5: a skill lists its [`Param`]s, a task step may carry the skill specialised with the
///   parameters it sets ([`Step::specialised`]) and may start at a pose an earlier step found
///   ([`Step::at`]) (all optional: a version 4 file reads as a version 5 file without them).
/// - 6: an active state may [`ActiveState::capture`] the tool's pose at entry under a name and
///   place its motion's goal at a captured pose ([`ActiveState::motion_at`]) (both optional: a
///   version 5 file reads as a version 6 file without them).
/// - 7: the goal at a captured pose may be moved on by an offset in a frame's axes
///   ([`ActiveState::motion_at_offset`]), a capture may be taken once
///   ([`ActiveState::capture_once`]), a transition may only watch ([`Transition::watch`]), and
///   guards may be [`Guard::MovedSince`] (all optional or new variants: a version 6 file reads
///   as a version 7 file).
/// - 8: a task step may learn from one contact phase of its demonstration ([`Step::phase`])
///   (optional: a version 7 file reads as a version 8 file without it).
pub const IR_VERSION: u32 = 8;

/// An offset from a captured pose: [`ActiveState::motion_at_offset`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AtOffset {
    /// The offset along the frame's x, y and z, metres.
    pub offset_m: [f64; 3],
    /// The frame whose axes the offset is given in.
    pub frame: FrameRef,
}

/// A compiled `.skill` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Program {
    /// Always [`IR_VERSION`] when written by this compiler.
    pub ir_version: u32,
    /// The file that was compiled, as named on the command line.
    pub source: String,
    /// Every skill defined in the file or in the files it imports, in import order.
    pub skills: Vec<Skill>,
    /// The file's tasks.
    pub tasks: Vec<Task>,
}

impl Program {
    /// The skill with this name.
    pub fn skill(&self, name: &str) -> Option<&Skill> {
        self.skills.iter().find(|skill| skill.name == name)
    }

    /// The task with this name.
    pub fn task(&self, name: &str) -> Option<&Task> {
        self.tasks.iter().find(|task| task.name == name)
    }
}

/// Where something was written, for messages that point at the `.skill` text.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SourceSpan {
    /// The file, as named on the command line or as resolved from an import.
    pub file: String,
    /// 1-based line of the first character.
    pub line: u32,
    /// 1-based column (in characters) of the first character.
    pub column: u32,
    /// Byte offset of the first character.
    pub start: u32,
    /// Byte offset one past the last character.
    pub end: u32,
}

macro_rules! id {
    ($(#[doc = $doc:literal])* $name:ident) => {
        $(#[doc = $doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The index into its arena.
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

id!(
    /// Index into [`Skill::states`].
    StateId
);
id!(
    /// Index into [`Skill::transitions`].
    TransitionId
);
id!(
    /// Index into [`LearnPlan::frames`].
    FrameId
);
id!(
    /// Index into [`LearnPlan::motions`].
    MotionId
);
id!(
    /// Index into [`LearnPlan::forces`].
    ForceId
);
id!(
    /// Index into [`LearnPlan::thresholds`].
    ThresholdId
);
id!(
    /// A 0-based segment of the demonstration, in time order.
    SegmentIdx
);

/// One skill template, lowered.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Skill {
    /// The skill's name.
    pub name: String,
    /// Its doc comment, lines joined with `\n` (empty when none).
    pub doc: String,
    /// What to learn from the demonstration.
    pub learn: LearnPlan,
    /// The state the skill starts in (the first declared state).
    pub initial: StateId,
    /// All states; `states[id.0]` has id `id`.
    pub states: Vec<State>,
    /// All transitions; `transitions[id.0]` has id `id`.
    pub transitions: Vec<Transition>,
    /// The safety supervisor's limits the skill sets (`limits { }`), in source order: applied
    /// over the runtime's defaults, before a task step's and the command line's. Left out of the
    /// JSON when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub limits: Vec<Limit>,
    /// The skill's parameters (`param hold = 2 s`) with the values this IR was compiled with:
    /// they are already substituted into the states and limits, and listed here for reports.
    /// Left out of the JSON when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub params: Vec<Param>,
    /// Where the skill is written.
    pub span: SourceSpan,
}

/// A skill parameter and the value it was compiled with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Param {
    /// Its name.
    pub name: String,
    /// The value in SI units (a plain number for a dimensionless parameter; 0 for a vector).
    pub value_si: f64,
    /// A vector parameter's three values in SI units (`param lift = [0 mm, 0 mm, 5 mm]`).
    /// Left out of the JSON for a number or a quantity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vector_si: Option<[f64; 3]>,
    /// The SI unit of the value (`s`, `m`, `N`, ...), empty for a plain number.
    pub unit: String,
    /// Who set the value.
    pub set_by: ParamSource,
    /// Its doc comment (empty when none).
    pub doc: String,
}

/// Who set a parameter's value.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "name", rename_all = "snake_case")]
pub enum ParamSource {
    /// The declaration's default.
    Default,
    /// The command line (`--param NAME=VALUE`).
    CommandLine,
    /// A task step, by name.
    Step(String),
}

/// One safety-supervisor limit set by name in a skill's `limits { }` block or a task step's
/// `limits: { }` argument.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Limit {
    /// Its name: one of [`LIMITS`].
    pub name: String,
    /// The value in the SI unit of its [`LimitDim`] (see [`LimitDim::si_unit`]); `None`
    /// (`inf` in source) switches the check off.
    pub value_si: Option<f64>,
    /// Its doc comment (empty when none).
    pub doc: String,
    /// Where it is written.
    pub span: SourceSpan,
}

impl Limit {
    /// The value in SI units, `f64::INFINITY` for a check switched off.
    pub fn value(&self) -> f64 {
        self.value_si.unwrap_or(f64::INFINITY)
    }
}

/// The dimension of a limit's value, which fixes the units it may be written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LimitDim {
    /// A force \[N\].
    Force,
    /// A moment \[N m\].
    Moment,
    /// A linear speed \[m/s\].
    Speed,
    /// An angular speed \[rad/s\].
    AngularSpeed,
    /// An angle \[rad\].
    Angle,
    /// A plain number (a fraction of something the robot file gives).
    Fraction,
    /// A duration \[s\].
    Duration,
    /// A length \[m\].
    Length,
}

impl LimitDim {
    /// The SI unit a value of this dimension is stored in (`"fraction"` for a plain number).
    pub fn si_unit(self) -> &'static str {
        match self {
            LimitDim::Force => "N",
            LimitDim::Moment => "N m",
            LimitDim::Speed => "m/s",
            LimitDim::AngularSpeed => "rad/s",
            LimitDim::Angle => "rad",
            LimitDim::Fraction => "fraction",
            LimitDim::Duration => "s",
            LimitDim::Length => "m",
        }
    }
}

/// A limit the safety supervisor enforces and that can be set by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LimitSpec {
    /// The name in `limits { }`, in a step's `limits: { }` and in `--limit NAME=VALUE`.
    pub name: &'static str,
    /// The dimension of its value.
    pub dim: LimitDim,
    /// What it bounds, for help texts.
    pub what: &'static str,
}

/// THE table of the supervisor's named limits. The compiler checks `limits { }` against it and
/// the runtime's `safety::LIMIT_NAMES` is this table (a runtime test checks that
/// `Limits::set` accepts exactly these names), so the two cannot drift apart.
pub const LIMITS: &[LimitSpec] = &[
    LimitSpec {
        name: "force",
        dim: LimitDim::Force,
        what: "the largest force the tool applies",
    },
    LimitSpec {
        name: "moment",
        dim: LimitDim::Moment,
        what: "the largest moment the tool applies about the tool point",
    },
    LimitSpec {
        name: "speed",
        dim: LimitDim::Speed,
        what: "the largest tool-point speed",
    },
    LimitSpec {
        name: "angular_speed",
        dim: LimitDim::AngularSpeed,
        what: "the largest tool angular speed",
    },
    LimitSpec {
        name: "joint_margin",
        dim: LimitDim::Angle,
        what: "the smallest distance of a joint from its position limits",
    },
    LimitSpec {
        name: "joint_speed",
        dim: LimitDim::Fraction,
        what: "the largest joint speed as a fraction of the robot file's velocity limit",
    },
    LimitSpec {
        name: "saturation",
        dim: LimitDim::Duration,
        what: "the longest time a joint torque may stay at its effort limit",
    },
    LimitSpec {
        name: "tracking",
        dim: LimitDim::Length,
        what: "the largest position error on position-controlled axes",
    },
    LimitSpec {
        name: "tracking_angle",
        dim: LimitDim::Angle,
        what: "the largest orientation error on position-controlled rotation axes",
    },
    LimitSpec {
        name: "arm_contact",
        dim: LimitDim::Force,
        what: "the largest contact force on an arm link other than the tool",
    },
];

/// The entry of [`LIMITS`] named `name`.
pub fn limit_spec(name: &str) -> Option<&'static LimitSpec> {
    LIMITS.iter().find(|spec| spec.name == name)
}

/// The learning plan: how to segment the demonstration and which features to extract.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnPlan {
    /// How to cut the demonstration into segments.
    pub segmentation: Segmentation,
    /// The number of segments the skill needs; learning fails when it finds another count.
    pub segments: u32,
    /// Low-pass cut-off applied to the demonstration before learning \[Hz\], if any.
    pub lowpass_hz: Option<f64>,
    /// Resampling rate applied before learning \[Hz\], if any.
    pub resample_hz: Option<f64>,
    /// Compliant frames to learn.
    pub frames: Vec<FrameDecl>,
    /// Motions (position + orientation DMPs) to learn.
    pub motions: Vec<MotionDecl>,
    /// Desired forces to learn.
    pub forces: Vec<ForceDecl>,
    /// Scalar thresholds to learn.
    pub thresholds: Vec<ThresholdDecl>,
}

/// How the demonstration is cut into segments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Segmentation {
    /// The whole demonstration is one segment.
    None,
    /// Two segments split at the sample of largest force magnitude (touch).
    MaxForce,
    /// Agglomerative clustering over standardised position and force features.
    Cluster {
        /// The linkage criterion.
        linkage: Linkage,
        /// How time keeps clusters contiguous.
        temporal: Temporal,
        /// Where the dendrogram is cut.
        cut: Cut,
        /// Segments shorter than this are merged into a neighbour \[s\].
        min_length_s: f64,
        /// The demonstration channels clustered.
        features: SegmentFeatures,
    },
    /// Change-point detection in the style of CHAMP (Niekum et al. 2015).
    Changepoint {
        /// Minimum segment length \[s\].
        min_length_s: f64,
        /// Candidate models for a segment.
        models: Vec<SegmentModel>,
        /// Bound on the particle set.
        max_particles: u32,
        /// The demonstration channels modelled.
        features: SegmentFeatures,
    },
}

/// Which demonstration channels segmentation looks at (each standardised).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SegmentFeatures {
    /// The tool position (3 columns).
    pub position: bool,
    /// The force vector (3 columns).
    pub force: bool,
    /// The force magnitude (1 column), independent of direction.
    pub force_magnitude: bool,
}

impl Default for SegmentFeatures {
    fn default() -> Self {
        SegmentFeatures {
            position: true,
            force: true,
            force_magnitude: false,
        }
    }
}

/// Agglomerative linkage criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Linkage {
    /// Minimum increase of within-cluster variance.
    Ward,
    /// Maximum pairwise distance.
    Complete,
    /// Mean pairwise distance.
    Average,
    /// Minimum pairwise distance.
    Single,
}

/// The temporal constraint of clustering.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Temporal {
    /// Standardised time added as a feature, scaled by `weight`.
    TimeFeature {
        /// Weight of the time feature relative to the others.
        weight: f64,
    },
    /// Only clusters within `k` samples of each other in time may merge.
    Connectivity {
        /// Neighbourhood size in samples, 1 to [`MAX_CONNECTIVITY`].
        k: u32,
    },
}

/// The largest connectivity clustering takes: each sample links to `k` neighbours on either side
/// (16 bytes a link), so `k` sizes the clustering's memory (`32 k` bytes a sample) and work.
/// ±100 samples is 0.1 s of a 1 kHz demonstration either side, ten times the default.
pub const MAX_CONNECTIVITY: u32 = 100;

/// Where to cut the cluster dendrogram.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "value", rename_all = "snake_case")]
pub enum Cut {
    /// Stop at this many clusters.
    Count(u32),
    /// Stop merging at this linkage distance (standardised units).
    Distance(f64),
}

/// A candidate model for one change-point segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SegmentModel {
    /// Constant mean with Gaussian noise.
    Constant,
    /// Linear in time with Gaussian noise.
    Linear,
}

/// A named compliant frame to learn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameDecl {
    /// Its name.
    pub name: String,
    /// How it is obtained.
    pub source: FrameSource,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// The six geometric constraint models (Subramani et al. 2018). What each leaves free and the
/// frame it gives are those of the runtime's fit (`skill_runtime::learn::constraint`,
/// docs/method.md §4); "into the surface" is along the mean applied force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstraintModel {
    /// A point of the tool stays at one point and the tool rotates freely (a ball joint);
    /// origin at the point, z along the mean applied force.
    FixedPoint,
    /// A point of the tool moves on a plane and the tool rotates freely; z is the plane's
    /// normal, into the surface.
    PointOnPlane,
    /// The tool slides on a plane and rotates only about its normal; z is the normal, into the
    /// surface, x the main direction of motion.
    Planar,
    /// The tool translates along an axis and rotates about it (a peg in a hole; `cylinder` in
    /// source); z along the axis in the direction of travel, x from the axis towards the tool.
    ConcentricCylinder,
    /// The tool translates along a line without rotating (a drawer); x along the line in the
    /// direction of travel, z along the applied force made perpendicular to the line.
    Prismatic,
    /// The tool rotates about a fixed axis (a hinge); z along the axis, x from the axis
    /// towards the tool.
    AxialRotation,
}

/// A point in the demonstration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "at", content = "segment", rename_all = "snake_case")]
pub enum Point {
    /// The first sample of a segment.
    Start(SegmentIdx),
    /// The last sample of a segment (for `max_force`, the end of segment 0 is the force peak).
    End(SegmentIdx),
    /// The sample of largest force magnitude.
    PeakForce,
    /// The sample of largest force magnitude within a segment (`peak_force(segment N)`).
    PeakForceIn(SegmentIdx),
}

/// How a frame is obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrameSource {
    /// Fit constraint models on a segment and keep the best scoring of `candidates`.
    Constraint {
        /// The segment fitted.
        segment: SegmentIdx,
        /// The models tried; one model means that model is imposed.
        candidates: Vec<ConstraintModel>,
    },
    /// z along the applied force at every sample of a segment (a moving frame).
    ForceAlignedSamples {
        /// The segment.
        segment: SegmentIdx,
    },
    /// z along the applied force at one point; origin at the tool position there.
    ForceAlignedAt {
        /// The point.
        point: Point,
    },
    /// A literal frame in the robot base frame.
    Fixed {
        /// Origin \[m\], base frame.
        origin_m: [f64; 3],
        /// Orientation as a unit quaternion `[w, x, y, z]`, base frame.
        quaternion_wxyz: [f64; 4],
    },
}

/// A named motion: a position DMP and a quaternion DMP of one segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotionDecl {
    /// Its name.
    pub name: String,
    /// The segment learned.
    pub segment: SegmentIdx,
    /// Gaussian basis functions per channel.
    pub basis: u32,
    /// `strokes(...)`: the segment is also cut into strokes at the reversals of its motion, and
    /// each stroke learned as a motion of its own (a wipe's back-and-forth, a circle's halves).
    /// Left out of the JSON when the motion is a plain `dmp`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strokes: Option<Strokes>,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// How a motion's segment is cut into strokes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Strokes {
    /// A stroke shorter than this is merged into its neighbour \[s\].
    pub min_length_s: f64,
}

/// A named desired force.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForceDecl {
    /// Its name.
    pub name: String,
    /// How it is obtained.
    pub source: ForceSource,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// A reference to a frame: a learned one or a built-in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "id", rename_all = "snake_case")]
pub enum FrameRef {
    /// The robot base frame.
    Base,
    /// The tool frame, moving with the tool.
    Tool,
    /// A learned frame.
    Learned(FrameId),
}

/// A frame axis, `x y z rx ry rz` as 0..6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// Translation along x.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation about x.
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
}

impl Axis {
    /// All axes in order.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::Rx, Axis::Ry, Axis::Rz];

    /// The axis from its source name.
    pub fn from_name(name: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|axis| axis.name() == name)
    }

    /// The source name: `x`, `rz`, ...
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
            Axis::Rx => "rx",
            Axis::Ry => "ry",
            Axis::Rz => "rz",
        }
    }

    /// 0..6 in `x y z rx ry rz` order.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Whether it is a rotation.
    pub fn is_rotation(self) -> bool {
        self.index() >= 3
    }
}

/// A frame axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameAxis {
    /// The frame.
    pub frame: FrameRef,
    /// The axis.
    pub axis: Axis,
}

/// How a desired force is obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ForceSource {
    /// Constant: the mean applied force along `along` over the lowest-variance in-contact
    /// region of a segment (thesis 4.2.2, slide).
    Constant {
        /// The segment.
        segment: SegmentIdx,
        /// The direction measured.
        along: FrameAxis,
    },
    /// The applied force along `along` at one point (touch).
    At {
        /// The point.
        point: Point,
        /// The direction measured.
        along: FrameAxis,
    },
    /// DMPs of the applied force vector of a segment, in the base frame (press).
    Dmp {
        /// The segment.
        segment: SegmentIdx,
        /// Basis functions per channel.
        basis: u32,
    },
    /// The magnitude of the applied force along a (usually moving) frame's axis over a
    /// segment, learned as a 1-D DMP (contour).
    Magnitude {
        /// The segment.
        segment: SegmentIdx,
        /// The direction measured.
        along: FrameAxis,
        /// Basis functions.
        basis: u32,
    },
    /// A literal force \[N\] along the z axis of the state's control frame.
    Literal {
        /// The force \[N\].
        value_n: f64,
    },
    /// No desired force: force-controlled axes regulate to zero (pure compliance) and the
    /// force is only watched by guards.
    Tracked,
}

/// A named scalar threshold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThresholdDecl {
    /// Its name.
    pub name: String,
    /// How it is obtained.
    pub source: ThresholdSource,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// How a threshold is obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ThresholdSource {
    /// `scale` times the applied force along `along` at `point` \[N\].
    ForceAt {
        /// The point.
        point: Point,
        /// The direction measured.
        along: FrameAxis,
        /// Multiplier on the learned value.
        scale: f64,
    },
    /// A literal value \[N or Nm\].
    Literal {
        /// The value in SI units.
        value: f64,
    },
}

/// One state of the machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Its id (its index in [`Skill::states`]).
    pub id: StateId,
    /// Its name.
    pub name: String,
    /// Its doc comment (empty when none).
    pub doc: String,
    /// What it does.
    pub kind: StateKind,
    /// Where it is written.
    pub span: SourceSpan,
}

/// Active states control the robot; terminal states end the skill.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum StateKind {
    /// A state that commands the robot.
    Active(Box<ActiveState>),
    /// The skill ends here.
    Terminal {
        /// Success or failure.
        outcome: Outcome,
        /// A message for the user, if written.
        message: Option<String>,
    },
}

/// How a skill ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The skill did what it was for.
    Success,
    /// It did not.
    Failure,
}

/// What an active state commands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActiveState {
    /// The motion run in this state, started from the pose at entry; `None` holds the entry pose.
    pub motion: Option<MotionId>,
    /// `move M relative`: the motion is moved as a whole so that it starts at the entry pose,
    /// its goal by the same offset (the demonstrated shape, where the state began); otherwise it
    /// runs from the entry pose to its demonstrated goal. Left out of the JSON when `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub motion_relative: bool,
    /// `move M at NAME`: the motion's goal is moved (as a whole, orientation goal unchanged) so
    /// that its position goal is the tool point's position that `capture NAME` stored; the run
    /// fails, naming the capture, when the state is entered before any capture of NAME. Never
    /// with [`ActiveState::motion_relative`]. Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_at: Option<String>,
    /// `move M at NAME + [x, y, z] in FRAME`: the goal lands at the captured position moved by
    /// this offset, in metres along `FRAME`'s axes as they are when the state is entered. Only
    /// with [`ActiveState::motion_at`]. Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion_at_offset: Option<AtOffset>,
    /// `capture NAME`: on entering the state, the tool point's pose (base frame) is stored under
    /// NAME for the rest of the run; entering again overwrites it (unless
    /// [`ActiveState::capture_once`]). Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capture: Option<String>,
    /// `capture NAME once`: the state captures only while NAME holds no pose yet, so a loop's
    /// later passes keep the first one. Left out of the JSON when `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub capture_once: bool,
    /// The compliant frame in which selection and stiffness are given.
    pub frame: FrameRef,
    /// Per axis (`x y z rx ry rz` of `frame`): position (`true`, S = 1) or force control.
    pub position_controlled: [bool; 6],
    /// Stiffness per axis in `frame`: N/m for x y z, Nm/rad for rx ry rz.
    pub stiffness: [f64; 6],
    /// The desired force for the force-controlled axes, if any.
    pub force: Option<ForceId>,
    /// The PI force controller's gains.
    pub gains: ForceGains,
    /// Actions run once when the state is entered, in order.
    pub entry: Vec<EntryAction>,
    /// Outgoing transitions in priority order: the first whose guard holds fires.
    pub transitions: Vec<TransitionId>,
    /// How the state meets the contact it expects, if it says so (`approach within ... at ...`);
    /// without it the runtime chooses from the state's force guards and search. Left out of the
    /// JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub approach: Option<Approach>,
    /// How the state lifts off the contact it is entered in, if it says so (`lift off 2 cm at
    /// 10 mm/s`, or `lift off 0 mm` for no lift); without it the runtime's default lift applies.
    /// Either way only a state entered in contact that runs a motion under pure position control
    /// and approaches no contact lifts off. Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lift_off: Option<LiftOffSpec>,
    /// `repeat N`: run the state's motion N times, each from where the last ended (a motion
    /// learned as strokes runs N strokes). `None`: once, or a strokes motion's demonstrated count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeat: Option<u32>,
}

/// A declared lift-off (`lift off 2 cm at 10 mm/s`): on entering the state in contact the tool
/// first moves `distance_m` along the contact normal, away from the surface, at `speed_mps`
/// (the motion waits), and afterwards is never commanded nearer the surface than that. Not
/// scaled by a task's speed factor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LiftOffSpec {
    /// How far to lift \[m\], zero or positive; zero switches the lift off for the state.
    pub distance_m: f64,
    /// Lift speed \[m/s\]: positive when `distance_m` is; unused (and zero when not written,
    /// `lift off 0 mm`) when `distance_m` is zero.
    pub speed_mps: f64,
}

/// A declared guarded approach (`approach within 10 cm at 25 mm/s`): within `within_m` of the
/// state's motion goal the motion's clock slows so that the commanded flange speed (the tool's,
/// up to its rotation) is at most `speed_mps`. Not scaled by a task's speed factor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Approach {
    /// Distance from the motion's goal where the slow approach begins \[m\].
    pub within_m: f64,
    /// Largest speed in that zone \[m/s\].
    pub speed_mps: f64,
}

/// Gains of the PI force controller on the force-controlled axes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ForceGains {
    /// Proportional gain on the force error [dimensionless: N of command per N of error].
    pub kp: f64,
    /// Integral gain \[1/s\].
    pub ki: f64,
    /// Clamp on each component of the integral term \[N\]; `None` leaves it unbounded.
    pub integral_limit_n: Option<f64>,
}

/// An action run when a state is entered.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "action", rename_all = "snake_case")]
pub enum EntryAction {
    /// Zero the force controller's integral.
    ResetIntegral,
    /// Take the current sensor reading as the zero of the force sensor.
    Tare,
    /// Move the state's motion goal by `distance_m` along an axis.
    ShiftGoal {
        /// The direction.
        along: FrameAxis,
        /// The distance \[m\] (negative moves against the axis).
        distance_m: f64,
    },
}

/// A transition of the machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Transition {
    /// Its id.
    pub id: TransitionId,
    /// The state it leaves.
    pub from: StateId,
    /// When it fires.
    pub guard: Guard,
    /// What it does.
    pub action: TransitionAction,
    /// The guard as written, for messages and graphs.
    pub guard_text: String,
    /// `on watch ...`: the guard watches for a limit; a force in it does not make the state
    /// approach a contact (slow its motion near the goal). Left out of the JSON when `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub watch: bool,
    /// Where it is written.
    pub span: SourceSpan,
}

/// What a transition does when its guard holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TransitionAction {
    /// Enter another state (or re-enter this one), running its entry actions.
    Goto {
        /// The target.
        target: StateId,
    },
    /// The touch/press adaptation (thesis Fig. 4.16, case II): stay in the state and move the
    /// motion goal along `along` at `speed_mps`, up to `max_m` in total; when the bound is
    /// reached and the guard holds again, enter `then`.
    Extend {
        /// The direction.
        along: FrameAxis,
        /// Speed of the goal \[m/s\].
        speed_mps: f64,
        /// Total extension bound \[m\].
        max_m: f64,
        /// The state entered when the bound is exhausted.
        then: StateId,
    },
}

/// A guard expression.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Guard {
    /// All of them hold.
    And {
        /// The operands.
        all: Vec<Guard>,
    },
    /// Any of them holds.
    Or {
        /// The operands.
        any: Vec<Guard>,
    },
    /// It does not hold.
    Not {
        /// The operand.
        guard: Box<Guard>,
    },
    /// The applied force (N, translation axes) or torque (Nm, rotation axes) along a frame
    /// axis compared with a threshold.
    Force {
        /// The axis measured.
        along: FrameAxis,
        /// The comparison.
        op: Comparison,
        /// The right-hand side.
        rhs: Threshold,
    },
    /// The tool point's displacement since the state was entered, along a frame axis (the
    /// axis's direction now), compared with `value`: metres along a translation axis; radians
    /// about a rotation axis (the tool's rotation since entry, as a rotation vector in the base
    /// frame, projected onto the axis).
    Moved {
        /// The axis measured.
        along: FrameAxis,
        /// The comparison.
        op: Comparison,
        /// The right-hand side \[m or rad\].
        value: f64,
    },
    /// The distance of the tool point from where it was when the state was entered, in any
    /// direction, compared with `value_m`.
    MovedDistance {
        /// The comparison.
        op: Comparison,
        /// The right-hand side \[m\].
        value_m: f64,
    },
    /// The distance of the tool point from where `capture NAME` kept it (`moved since NAME`),
    /// compared with `value_m`; false while the run has not captured NAME.
    MovedSince {
        /// The capture measured from.
        capture: String,
        /// The comparison.
        op: Comparison,
        /// The right-hand side \[m\].
        value_m: f64,
    },
    /// How many times the run has entered `state` (the current state's entry included)
    /// compared with `count`: `entered(tap) >= 2` repeats a group of states a set number of
    /// times.
    Entered {
        /// The state counted.
        state: StateId,
        /// The comparison.
        op: Comparison,
        /// The right-hand side.
        count: u32,
    },
    /// The tool point's measured linear speed compared with `value_mps`.
    Speed {
        /// The comparison.
        op: Comparison,
        /// The right-hand side \[m/s\].
        value_mps: f64,
    },
    /// The length of the applied force \[N\] compared with a threshold (scaled by a task
    /// step's `force_scale` as [`Guard::Force`]'s is).
    ForceMagnitude {
        /// The comparison.
        op: Comparison,
        /// The right-hand side \[N\].
        rhs: Threshold,
    },
    /// The length of the applied moment about the tool point \[Nm\] compared with a threshold
    /// (scaled by a task step's `force_scale`).
    MomentMagnitude {
        /// The comparison.
        op: Comparison,
        /// The right-hand side \[Nm\].
        rhs: Threshold,
    },
    /// Every DMP the state runs (motion and force profile) has finished, including any extension.
    MotionDone,
    /// Every force-controlled axis is within `tolerance_n` of its desired force.
    ForceReached {
        /// Tolerance \[N\].
        tolerance_n: f64,
    },
    /// At least `duration_s` has passed since the state was entered.
    Dwell {
        /// Duration \[s\].
        duration_s: f64,
    },
    /// Like `Dwell`, but reported as a timeout when it fires.
    Timeout {
        /// Duration \[s\].
        duration_s: f64,
    },
    /// `guard` has held at every evaluation for at least `duration_s` without a break
    /// (`force_reached within 0.5 N for 100 ms`). The time restarts whenever `guard` does not
    /// hold and when the state is entered, so it never holds earlier than `duration_s` after
    /// entry.
    Held {
        /// The guard that must keep holding.
        guard: Box<Guard>,
        /// How long \[s\], positive.
        duration_s: f64,
    },
}

/// A comparison operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Comparison {
    /// `>=`
    Ge,
    /// `>`
    Gt,
    /// `<=`
    Le,
    /// `<`
    Lt,
}

impl Comparison {
    /// Evaluates `lhs OP rhs`.
    pub fn holds(self, lhs: f64, rhs: f64) -> bool {
        match self {
            Comparison::Ge => lhs >= rhs,
            Comparison::Gt => lhs > rhs,
            Comparison::Le => lhs <= rhs,
            Comparison::Lt => lhs < rhs,
        }
    }
}

/// The right-hand side of a force comparison.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Threshold {
    /// A learned threshold.
    Learned {
        /// The threshold.
        id: ThresholdId,
    },
    /// A learned constant force, used as a threshold.
    Force {
        /// The force.
        id: ForceId,
    },
    /// A literal \[N or Nm\].
    Literal {
        /// The value.
        value: f64,
    },
}

/// A task: skill invocations run in sequence, each starting where the last ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// Its name.
    pub name: String,
    /// Its doc comment.
    pub doc: String,
    /// The steps, in order.
    pub steps: Vec<Step>,
    /// Steps that run only when a failing step names them.
    pub fallbacks: Vec<Step>,
    /// Where it is written.
    pub span: SourceSpan,
}

/// One skill invocation in a task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Step {
    /// The step's name.
    pub name: String,
    /// The skill run, by name (a key into [`Program::skills`]).
    pub skill: String,
    /// Where its features come from.
    pub input: StepInput,
    /// Adjustments to the learned skill.
    pub overrides: Overrides,
    /// Safety limits the step sets (`limits: { force: 30 N }`), applied after the skill's own
    /// and before the command line's. Left out of the JSON when empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub limits: Vec<Limit>,
    /// What happens when it fails.
    pub on_failure: OnFailure,
    /// The skill as this step runs it, when the step sets some of its parameters
    /// (`press_hold(demo: "...", hold: 5 s)`): [`Step::skill`] compiled with those values.
    /// `None` runs [`Program::skills`]' skill of that name. Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specialised: Option<Box<Skill>>,
    /// `at: find.settle`: the step's goals move so that the goal of its first state's motion
    /// lands where the tool point was when step `find` entered its state `settle` (plus
    /// [`Overrides::goal_offset_m`]). Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<Anchor>,
    /// `phase: 2`: learn from the demonstration's second contact phase (1-based), as
    /// `skillc learn --phase 2` does, so that the steps of a task can learn from the phases of
    /// one recording. Only with [`StepInput::Demo`]. Left out of the JSON when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase: Option<u32>,
    /// Where it is written.
    pub span: SourceSpan,
}

/// A pose found by an earlier step of a task: where the tool point was when that step entered
/// one of its skill's states (the first time).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Anchor {
    /// The earlier step's name.
    pub step: String,
    /// The state of that step's skill.
    pub state: String,
}

impl Step {
    /// The skill this step runs: its specialised skill, or the program's skill of its name.
    pub fn skill_in<'p>(&'p self, program: &'p Program) -> Option<&'p Skill> {
        self.specialised.as_deref().or_else(|| program.skill(&self.skill))
    }
}

/// Where a step's learned features come from. Paths are resolved against the directory of
/// the file that declares the task.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "path", rename_all = "snake_case")]
pub enum StepInput {
    /// Learn from this demonstration CSV first.
    Demo(String),
    /// Use this learned file.
    Learned(String),
}

/// Adjustments applied to a learned skill when a task runs it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Overrides {
    /// Multiplier on every desired force and force threshold.
    pub force_scale: f64,
    /// Multiplier on motion speed (2 runs twice as fast).
    pub speed_factor: f64,
    /// Offset added to every motion goal \[m\], base frame.
    pub goal_offset_m: [f64; 3],
}

impl Default for Overrides {
    fn default() -> Self {
        Overrides {
            force_scale: 1.0,
            speed_factor: 1.0,
            goal_offset_m: [0.0; 3],
        }
    }
}

/// A task's failure policy for one step.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "policy", content = "fallback", rename_all = "snake_case")]
pub enum OnFailure {
    /// Stop the task; it fails.
    Abort,
    /// Run this fallback (an index into [`Task::fallbacks`]), then stop; the task fails.
    Fallback(u32),
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version 1 program: no limits, no approach.
    fn version_1() -> serde_json::Value {
        let span = serde_json::json!({"file": "a.skill", "line": 1, "column": 1, "start": 0, "end": 1});
        serde_json::json!({
            "ir_version": 1,
            "source": "a.skill",
            "skills": [{
                "name": "s", "doc": "",
                "learn": {
                    "segmentation": {"method": "none"}, "segments": 1, "lowpass_hz": null,
                    "resample_hz": null, "frames": [], "motions": [], "forces": [], "thresholds": []
                },
                "initial": 0,
                "states": [{
                    "id": 0, "name": "go", "doc": "",
                    "kind": {
                        "kind": "active", "motion": null, "frame": {"kind": "base"},
                        "position_controlled": [true, true, true, true, true, true],
                        "stiffness": [1500.0, 1500.0, 1500.0, 150.0, 150.0, 150.0], "force": null,
                        "gains": {"kp": 0.5, "ki": 5.0, "integral_limit_n": 10.0},
                        "entry": [], "transitions": []
                    },
                    "span": span
                }],
                "transitions": [],
                "span": span
            }],
            "tasks": [{
                "name": "t", "doc": "",
                "steps": [{
                    "name": "a", "skill": "s", "input": {"kind": "demo", "path": "d.csv"},
                    "overrides": {"force_scale": 1.0, "speed_factor": 1.0, "goal_offset_m": [0.0, 0.0, 0.0]},
                    "on_failure": {"policy": "abort"},
                    "span": span
                }],
                "fallbacks": [],
                "span": span
            }]
        })
    }

    #[test]
    fn a_version_1_program_reads_and_writes_back_unchanged() {
        let old = version_1();
        let program: Program = serde_json::from_value(old.clone()).expect("version 1 reads");
        let skill = &program.skills[0];
        assert!(skill.limits.is_empty());
        let StateKind::Active(active) = &skill.states[0].kind else {
            panic!("an active state")
        };
        assert_eq!(active.approach, None);
        assert_eq!(active.lift_off, None);
        assert!(program.tasks[0].steps[0].limits.is_empty());
        // Empty limits and no approach are left out, so skills that use neither serialise (and
        // hash) as before.
        assert_eq!(serde_json::to_value(&program).expect("writes"), old);
    }

    #[test]
    fn held_guards_and_lift_offs_serialise_by_name_and_read_back() {
        let held = Guard::Held {
            guard: Box::new(Guard::ForceReached { tolerance_n: 0.5 }),
            duration_s: 0.1,
        };
        let json = serde_json::to_value(&held).expect("writes");
        assert_eq!(
            json,
            serde_json::json!({
                "kind": "held",
                "guard": {"kind": "force_reached", "tolerance_n": 0.5},
                "duration_s": 0.1
            })
        );
        assert_eq!(serde_json::from_value::<Guard>(json).expect("reads"), held);
        let lift = LiftOffSpec {
            distance_m: 0.02,
            speed_mps: 0.01,
        };
        let json = serde_json::to_value(lift).expect("writes");
        assert_eq!(json, serde_json::json!({"distance_m": 0.02, "speed_mps": 0.01}));
        assert_eq!(serde_json::from_value::<LiftOffSpec>(json).expect("reads"), lift);
    }

    #[test]
    fn limit_names_are_unique_and_found() {
        for (index, spec) in LIMITS.iter().enumerate() {
            assert!(LIMITS[index + 1..].iter().all(|other| other.name != spec.name));
            assert_eq!(limit_spec(spec.name), Some(spec));
        }
        assert_eq!(limit_spec("forse"), None);
        let off = Limit {
            name: "force".into(),
            value_si: None,
            doc: String::new(),
            span: SourceSpan {
                file: String::new(),
                line: 1,
                column: 1,
                start: 0,
                end: 0,
            },
        };
        assert_eq!(off.value(), f64::INFINITY);
    }
}

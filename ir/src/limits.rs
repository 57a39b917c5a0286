//! The safety supervisor's named limits: the ones a skill or a task step sets, and the table of
//! every name, its dimension and its SI unit.

use crate::SourceSpan;
use serde::{Deserialize, Serialize};

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

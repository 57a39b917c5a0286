//! The transitions of the machine and the guard expressions that fire them.

use crate::{ForceId, FrameAxis, SourceSpan, StateId, ThresholdId, TransitionId};
use serde::{Deserialize, Serialize};

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

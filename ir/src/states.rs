//! The states of the machine: what an active state commands and does on entry.

use crate::{ForceId, FrameAxis, FrameRef, MotionId, SourceSpan, StateId, TransitionId};
use serde::{Deserialize, Serialize};

/// An offset from a captured pose: [`ActiveState::motion_at_offset`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AtOffset {
    /// The offset along the frame's x, y and z, metres.
    pub offset_m: [f64; 3],
    /// The frame whose axes the offset is given in.
    pub frame: FrameRef,
}

/// One state of the machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Its id (its index in [`Skill::states`](crate::Skill::states)).
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

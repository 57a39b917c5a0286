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

mod axes;
mod learn;
mod limits;
mod program;
mod segmentation;
mod states;
mod task;
mod transitions;

pub use axes::{Axis, FrameAxis, FrameRef};
pub use learn::{
    ConstraintModel, ForceDecl, ForceSource, FrameDecl, FrameSource, LearnPlan, MotionDecl, Point, Strokes,
    ThresholdDecl, ThresholdSource,
};
pub use limits::{limit_spec, Limit, LimitDim, LimitSpec, LIMITS};
pub use program::{Param, ParamSource, Program, Skill};
pub use segmentation::{Cut, Linkage, SegmentFeatures, SegmentModel, Segmentation, Temporal, MAX_CONNECTIVITY};
pub use states::{ActiveState, Approach, AtOffset, EntryAction, ForceGains, LiftOffSpec, Outcome, State, StateKind};
pub use task::{Anchor, OnFailure, Overrides, Step, StepInput, Task};
pub use transitions::{Comparison, Guard, Threshold, Transition, TransitionAction};

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

#[cfg(test)]
mod tests;

//! Tasks: the skill invocations they run in sequence, with their inputs, adjustments and
//! failure policies.

use crate::{Limit, Program, Skill, SourceSpan};
use serde::{Deserialize, Serialize};

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

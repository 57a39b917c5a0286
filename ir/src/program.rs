//! The program, its skills and their parameters: the top of the IR.

use crate::{LearnPlan, Limit, SourceSpan, State, StateId, Task, Transition};
use serde::{Deserialize, Serialize};

/// A compiled `.skill` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Program {
    /// Always [`IR_VERSION`](crate::IR_VERSION) when written by this compiler.
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

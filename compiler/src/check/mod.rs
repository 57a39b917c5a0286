//! Checking: resolves names, units, segments and axes of a parsed skill, analyses its state
//! machine, and builds the IR as it goes. Every problem is reported; nothing stops at the first.
//!
//! Resolution and lowering are one walk here: each resolved value already is its IR form,
//! and the IR is only kept when the walk reported no error. The walk is one [`Checker`]
//! whose methods are spread over this module's files by job: [`values`] (numbers, units,
//! call arguments), [`scope`] (names), [`learn`], [`segments`], [`frames`] and [`forces`]
//! (the learn block, whose functions [`signatures`] lists), [`limits`] (the supervisor's
//! limits of a skill or a task step), [`params`] (skill parameters, substituted into the states
//! and limits before they are checked), [`arith`] (arithmetic on values, folded to literals once
//! the parameters are in), [`states`], [`guards`], [`captures`] (`capture NAME`
//! and `move M at NAME`) and [`reach`] (the state machine), and [`task`].

mod arith;
mod captures;
mod forces;
mod frames;
mod guards;
mod learn;
mod limits;
mod params;
mod reach;
mod scope;
mod segments;
mod signatures;
mod states;
mod task;
mod values;

use crate::ast;
use crate::diag::{did_you_mean, Code, Diag, Severity};
use crate::source::{SourceFile, Span};
use scope::SkillScope;
use signatures::Signature;
use skill_ir as ir;

pub use learn::{DEFAULT_FORCE_BASIS, DEFAULT_MOTION_BASIS};
pub use params::ParamSetting;
pub(crate) use signatures::public_table as learn_function_table;
pub use states::{DEFAULT_GAINS, DEFAULT_STIFFNESS};
pub(crate) use task::SkillFacts;

/// "did you mean `x`?" for the candidate nearest to `name`, preferring the function `name` is
/// an alias of.
fn suggest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str> + Clone) -> Option<String> {
    if let Some(alias) = Signature::alias_of(name) {
        if candidates.clone().into_iter().any(|c| c == alias) {
            return Some(format!("did you mean `{alias}`?"));
        }
    }
    did_you_mean(name, candidates).map(|found| format!("did you mean `{found}`?"))
}

/// `` `a`, `b`, `c` ``.
fn join_ticked(items: &[&str]) -> String {
    items
        .iter()
        .map(|item| format!("`{item}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The checker of one file.
pub(crate) struct Checker<'a> {
    file: usize,
    src: &'a SourceFile,
    diags: &'a mut Vec<Diag>,
}

impl<'a> Checker<'a> {
    pub(crate) fn new(file: usize, src: &'a SourceFile, diags: &'a mut Vec<Diag>) -> Self {
        Checker { file, src, diags }
    }
}

impl Checker<'_> {
    fn report(&mut self, diag: Diag) {
        self.diags.push(diag);
    }

    fn diag(&self, code: Code, span: Span, message: impl Into<String>, label: impl Into<String>) -> Diag {
        Diag::new(code, self.file, span, message, label)
    }

    pub(crate) fn ir_span(&self, span: Span) -> ir::SourceSpan {
        let (line, column) = self.src.line_col(span.start);
        ir::SourceSpan {
            file: self.src.name.clone(),
            line: line as u32,
            column: column as u32,
            start: span.start as u32,
            end: span.end as u32,
        }
    }

    fn error_count(&self) -> usize {
        self.diags
            .iter()
            .filter(|d| d.file == self.file && d.severity() == Severity::Error)
            .count()
    }

    /// Checks one skill and returns its IR when it has no error.
    pub(crate) fn skill(&mut self, skill: &ast::Skill) -> Option<ir::Skill> {
        let errors_before = self.error_count();
        let mut scope = SkillScope::default();
        let learn = self.learn(&skill.learn, &mut scope);
        let limits = self.skill_limits(&skill.limits);
        let (states, transitions, initial) = self.states(skill, &mut scope);
        if self.error_count() == errors_before {
            // After an error, a name may look unused only because its use did not resolve.
            self.unused(&scope);
        }
        let (learn, initial) = (learn?, initial?);
        if self.error_count() > errors_before {
            return None;
        }
        Some(ir::Skill {
            name: skill.name.name.clone(),
            doc: skill.doc.join("\n"),
            learn,
            initial,
            states,
            transitions,
            limits,
            params: Vec::new(),
            span: self.ir_span(skill.name.span),
        })
    }
}

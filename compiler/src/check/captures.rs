//! Poses a run keeps: `capture NAME` in a state and `move M at NAME`: the names resolved against
//! the skill's captures, clashes with learned names and parameters, captures no move uses, and
//! states that the run may reach before any capture of the name they move to.

use std::collections::VecDeque;

use super::scope::SkillScope;
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, StmtKind};
use crate::diag::Code;
use crate::source::Span;

/// A name some state captures.
pub(super) struct Capture {
    /// The name.
    pub(super) name: String,
    /// Where it is first captured.
    pub(super) span: Span,
    /// The states (indices among the skill's states) that capture it.
    pub(super) states: Vec<usize>,
    /// Whether a `move ... at NAME` uses it.
    pub(super) used: bool,
}

/// The names `state` captures.
fn captures_of(state: &ast::State) -> impl Iterator<Item = &ast::Ident> {
    statements(state).filter_map(|stmt| match &stmt.kind {
        StmtKind::Capture { name, .. } => Some(name),
        _ => None,
    })
}

/// The `at NAME` of `state`'s moves.
fn moves_at(state: &ast::State) -> impl Iterator<Item = &ast::Ident> {
    statements(state).filter_map(|stmt| match &stmt.kind {
        StmtKind::Move { at, .. } => at.as_ref(),
        _ => None,
    })
}

/// The `since NAME` of `state`'s guards (`moved since NAME >= D`).
fn guards_since(state: &ast::State) -> Vec<&ast::Ident> {
    fn walk<'g>(guard: &'g ast::Guard, out: &mut Vec<&'g ast::Ident>) {
        match &guard.kind {
            ast::GuardKind::Or(guards) | ast::GuardKind::And(guards) => guards.iter().for_each(|g| walk(g, out)),
            ast::GuardKind::Not(inner) | ast::GuardKind::Held { guard: inner, .. } => walk(inner, out),
            ast::GuardKind::Moved { since: Some(name), .. } => out.push(name),
            _ => {}
        }
    }
    let mut out = Vec::new();
    for stmt in statements(state) {
        if let StmtKind::Transition { guard, .. } = &stmt.kind {
            walk(guard, &mut out);
        }
    }
    out
}

fn statements(state: &ast::State) -> std::slice::Iter<'_, ast::Stmt> {
    match &state.body {
        ast::StateBody::Active(stmts) => stmts.iter(),
        ast::StateBody::Terminal { .. } => [].iter(),
    }
}

impl Checker<'_> {
    /// Collects the names `states` (the skill's states, in order, without duplicates) capture
    /// into `scope`, reporting a name that a learned feature or a parameter already has: `at
    /// NAME` reads as a place, and one name for two things would be read as either.
    pub(super) fn collect_captures(&mut self, skill: &ast::Skill, states: &[&ast::State], scope: &mut SkillScope) {
        for (index, state) in states.iter().enumerate() {
            // A second `capture` in a state is an error of its own (`duplicate_statement`).
            for name in captures_of(state).take(1) {
                if let Some(known) = scope.captures.iter_mut().find(|c| c.name == name.name) {
                    if !known.states.contains(&index) {
                        known.states.push(index);
                    }
                    continue;
                }
                let learned = skill.learn.iter().find_map(|decl| {
                    decl.name
                        .as_ref()
                        .filter(|learned| learned.name == name.name)
                        .map(|learned| (learned.span, decl.kind.keyword()))
                });
                let param = skill
                    .params
                    .iter()
                    .find(|param| param.name.name == name.name)
                    .map(|param| (param.name.span, "parameter"));
                if let Some((span, kind)) = learned.or(param) {
                    let diag = self
                        .diag(
                            Code::DuplicateName,
                            name.span,
                            format!("`{}` names a capture and a {kind}", name.name),
                            "capture",
                        )
                        .label(span, format!("the {kind}"))
                        .help(format!(
                            "a capture's name must not be a learned name or a parameter: rename the capture, e.g. `{}_pose`",
                            name.name
                        ));
                    self.report(diag);
                    continue;
                }
                scope.captures.push(Capture {
                    name: name.name.clone(),
                    span: name.span,
                    states: vec![index],
                    used: false,
                });
            }
        }
    }

    /// `move MOTION at NAME`: the capture NAME, when a state captures it and the move is not
    /// also `relative`.
    pub(super) fn move_at(
        &mut self,
        motion: &ast::Ident,
        at: &ast::Ident,
        relative: bool,
        scope: &mut SkillScope,
    ) -> Option<String> {
        self.capture_named(at, scope)?;
        if relative {
            let diag = self
                .diag(
                    Code::RelativeAndAt,
                    at.span,
                    format!("`move {}` is both `relative` and `at {}`", motion.name, at.name),
                    "choose one",
                )
                .help(format!(
                    "`relative` runs the demonstrated shape from where the state begins, `at {1}` ends the motion \
                     at the captured pose: write `move {0} at {1}` or `move {0} relative`",
                    motion.name, at.name
                ));
            self.report(diag);
            return None;
        }
        Some(at.name.clone())
    }

    /// The capture `at` names, marked used; `unknown_capture` (with the nearest name) when no
    /// state captures it.
    pub(super) fn capture_named(&mut self, at: &ast::Ident, scope: &mut SkillScope) -> Option<String> {
        let Some(capture) = scope.captures.iter_mut().find(|c| c.name == at.name) else {
            let names: Vec<&str> = scope.captures.iter().map(|c| c.name.as_str()).collect();
            let help = suggest(&at.name, names.iter().copied()).unwrap_or_else(|| {
                let state = scope.state_names.contains(&at.name);
                match (state, names.is_empty()) {
                    (true, _) => format!(
                        "`{0}` is a state: add `capture {0}` to it to keep the pose where the run enters it",
                        at.name
                    ),
                    (false, true) => format!(
                        "add `capture {}` to the state whose entry pose the motion should end at (e.g. the state a contact guard enters)",
                        at.name
                    ),
                    (false, false) => format!("the skill captures {}", join_ticked(&names)),
                }
            });
            let diag = self
                .diag(
                    Code::UnknownCapture,
                    at.span,
                    format!("no state captures `{}`", at.name),
                    "never captured",
                )
                .help(help);
            self.report(diag);
            return None;
        };
        capture.used = true;
        Some(at.name.clone())
    }

    /// Captures no move uses.
    pub(super) fn unused_captures(&mut self, scope: &SkillScope) {
        for capture in scope.captures.iter().filter(|c| !c.used) {
            let diag = self
                .diag(
                    Code::UnusedCapture,
                    capture.span,
                    format!(
                        "`{}` is captured but no `move ... at {}` or `moved since` uses it",
                        capture.name, capture.name
                    ),
                    "never used",
                )
                .help(format!(
                    "remove the `capture`, or end a motion there with `move MOTION at {}`",
                    capture.name
                ));
            self.report(diag);
        }
    }

    /// States with `move ... at NAME` that the run can reach from the initial state (index 0)
    /// without entering a state that captures NAME: whether the run takes such a path depends
    /// on guards, so it is a warning, and the run fails there if it does. `successors` are the
    /// states' transition targets (indices).
    pub(super) fn at_before_capture(&mut self, states: &[&ast::State], successors: &[Vec<usize>], scope: &SkillScope) {
        for capture in scope.captures.iter().filter(|c| c.used) {
            let capturing = |index: usize| capture.states.contains(&index);
            let mut reached = vec![false; states.len()];
            let mut queue = VecDeque::new();
            if !capturing(0) {
                reached[0] = true;
                queue.push_back(0usize);
            }
            while let Some(at) = queue.pop_front() {
                for &next in &successors[at] {
                    if !reached[next] && !capturing(next) {
                        reached[next] = true;
                        queue.push_back(next);
                    }
                }
            }
            let capturers: Vec<&str> = capture
                .states
                .iter()
                .map(|&index| states[index].name.name.as_str())
                .collect();
            for (index, state) in states.iter().enumerate().filter(|(index, _)| reached[*index]) {
                let uses = moves_at(state)
                    .map(|at| (at, "the run fails if it takes that path"))
                    .chain(
                        guards_since(state)
                            .into_iter()
                            .map(|at| (at, "`moved since` is false on that path")),
                    );
                for (at, consequence) in uses.filter(|(at, _)| at.name == capture.name) {
                    let diag = self
                        .diag(
                            Code::AtBeforeCapture,
                            at.span,
                            format!(
                                "state `{}` can be reached before `{}` is captured",
                                states[index].name.name, capture.name
                            ),
                            "may not be captured yet",
                        )
                        .label(capture.span, "captured here")
                        .help(format!(
                            "`{}` is captured on entering {}; a path from `{}` reaches `{}` without entering it, and \
                             {consequence}",
                            capture.name,
                            join_ticked(&capturers),
                            states[0].name.name,
                            state.name.name
                        ));
                    self.report(diag);
                }
            }
        }
    }
}

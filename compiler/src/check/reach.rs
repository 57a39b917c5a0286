//! Reachability of a skill's state machine: states never reached, dead ends, and states from
//! which no terminal can be reached.

use super::Checker;
use crate::ast;
use crate::diag::Code;
use std::collections::VecDeque;

impl Checker<'_> {
    /// Reachability from the initial state, and a path to a terminal from every state.
    pub(super) fn graph(&mut self, states: &[&ast::State], successors: &[Vec<usize>], terminal: &[bool]) {
        let n = states.len();
        let mut reached = vec![false; n];
        let mut queue = VecDeque::from([0usize]);
        reached[0] = true;
        while let Some(at) = queue.pop_front() {
            for &next in &successors[at] {
                if !reached[next] {
                    reached[next] = true;
                    queue.push_back(next);
                }
            }
        }
        let is_terminal = |index: usize| terminal[index];
        let mut reaches_terminal: Vec<bool> = (0..n).map(is_terminal).collect();
        loop {
            let mut changed = false;
            for index in 0..n {
                if !reaches_terminal[index] && successors[index].iter().any(|&next| reaches_terminal[next]) {
                    reaches_terminal[index] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        let initial_name = &states[0].name.name;
        for index in 0..n {
            let state = states[index];
            if !reached[index] {
                let diag = self
                    .diag(
                        Code::UnreachableState,
                        state.name.span,
                        format!("state `{}` can never be reached", state.name.name),
                        "no transition leads here",
                    )
                    .help(format!(
                        "add a transition to it, or remove it; the skill starts in `{initial_name}`"
                    ));
                self.report(diag);
                continue;
            }
            if is_terminal(index) {
                continue;
            }
            if successors[index].is_empty() {
                let diag = self
                    .diag(
                        Code::DeadEnd,
                        state.name.span,
                        format!("state `{}` has no way out", state.name.name),
                        "no outgoing transition",
                    )
                    .help("add `on motion_done -> NEXT` or `on timeout 10 s -> NEXT`");
                self.report(diag);
            } else if !reaches_terminal[index] {
                let diag = self
                    .diag(
                        Code::NoTerminalPath,
                        state.name.span,
                        format!("no terminal state can be reached from `{}`", state.name.name),
                        "the skill can never end from here",
                    )
                    .help("add a transition towards a `terminal` state");
                self.report(diag);
            }
        }
    }
}

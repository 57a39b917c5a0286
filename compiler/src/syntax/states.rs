//! Lowering of states: active states and their statements, terminal states, and the targets
//! of transitions.

use super::guards::guard;
use super::values::{arg, axis_ref, expr, string};
use super::{doc_text, ident, span_of};
use crate::ast::*;
use pest::iterators::Pair;
use skill_grammar::Rule;

pub(super) fn state(pair: Pair<'_, Rule>) -> State {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut name = None;
    let mut body = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => name = Some(ident(inner)),
            Rule::state_entry => body.push(stmt(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in state"),
        }
    }
    State {
        doc,
        name: name.expect("grammar: state has a name"),
        body: StateBody::Active(body),
        span,
    }
}

pub(super) fn terminal(pair: Pair<'_, Rule>) -> State {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut idents = Vec::new();
    let mut message = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => idents.push(ident(inner)),
            Rule::string => message = Some(string(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in terminal"),
        }
    }
    let mut idents = idents.into_iter();
    let name = idents.next().expect("grammar: terminal has a name");
    let outcome = idents.next().expect("grammar: terminal has an outcome");
    State {
        doc,
        name,
        body: StateBody::Terminal { outcome, message },
        span,
    }
}

fn stmt(pair: Pair<'_, Rule>) -> Stmt {
    let mut doc = Vec::new();
    let mut stmt_pair = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            _ => stmt_pair = Some(inner),
        }
    }
    let pair = stmt_pair.expect("grammar: state entry has a statement");
    let span = span_of(&pair);
    let rule = pair.as_rule();
    let mut inner = pair.into_inner();
    let kind = match rule {
        Rule::move_stmt => {
            let motion = ident(inner.next().expect("grammar: move names a motion"));
            let mut start = None;
            let mut at = None;
            let mut offset = None;
            for part in inner {
                match part.as_rule() {
                    Rule::move_at => {
                        let mut parts = part.into_inner();
                        at = parts.next().map(ident);
                        offset = parts.next().map(|offset_pair| {
                            let mut inner = offset_pair.into_inner();
                            AtOffset {
                                value: expr(inner.next().expect("grammar: an offset has a value")),
                                frame: inner.next().map(ident),
                            }
                        });
                    }
                    rule => start = Some(rule),
                }
            }
            StmtKind::Move {
                motion,
                from_current: start == Some(Rule::from_current),
                relative: start == Some(Rule::move_relative),
                at,
                offset,
            }
        }
        Rule::control_stmt => {
            let mut groups = Vec::new();
            let mut frame = None;
            for part in inner {
                match part.as_rule() {
                    Rule::control_group => groups.push(control_group(part)),
                    Rule::ident => frame = Some(ident(part)),
                    rule => unreachable!("grammar: unexpected {rule:?} in control"),
                }
            }
            StmtKind::Control { groups, frame }
        }
        Rule::stiffness_stmt => StmtKind::Stiffness(inner.map(axis_value).collect()),
        Rule::apply_stmt => StmtKind::Apply(ident(inner.next().expect("grammar: apply names a force"))),
        Rule::gains_stmt => StmtKind::Gains(inner.map(arg).collect()),
        Rule::entry_stmt => StmtKind::Entry(inner.map(expr).collect()),
        Rule::approach_stmt => {
            let _keyword = inner.next().expect("grammar: approach keyword");
            let within = expr(inner.next().expect("grammar: approach has a distance"));
            let speed = expr(inner.next().expect("grammar: approach has a speed"));
            StmtKind::Approach { within, speed }
        }
        Rule::lift_off_stmt => {
            let _lift = inner.next().expect("grammar: lift keyword");
            let _off = inner.next().expect("grammar: off keyword");
            let distance = expr(inner.next().expect("grammar: lift off has a distance"));
            let speed = inner.next().map(expr);
            StmtKind::LiftOff { distance, speed }
        }
        Rule::repeat_stmt => {
            let _keyword = inner.next().expect("grammar: repeat keyword");
            StmtKind::Repeat(expr(inner.next().expect("grammar: repeat has a count")))
        }
        Rule::capture_stmt => {
            let _keyword = inner.next().expect("grammar: capture keyword");
            StmtKind::Capture {
                name: ident(inner.next().expect("grammar: capture names a pose")),
                once: inner.next().map(|pair| span_of(&pair)),
            }
        }
        Rule::transition => {
            let watch = match inner.peek() {
                Some(pair) if pair.as_rule() == Rule::watch_kw => inner.next().map(|pair| span_of(&pair)),
                _ => None,
            };
            let guard_pair = inner.next().expect("grammar: transition has a guard");
            let target_pair = inner.next().expect("grammar: transition has a target");
            StmtKind::Transition {
                watch,
                guard: guard(guard_pair),
                target: target(target_pair),
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} in state"),
    };
    Stmt { doc, kind, span }
}

fn control_group(pair: Pair<'_, Rule>) -> ControlGroup {
    let mut inner = pair.into_inner();
    let mode = inner.next().expect("grammar: control group has a mode");
    let axes = axis_set(inner.next().expect("grammar: control group has axes"));
    ControlGroup {
        force: mode.as_str() == "force",
        mode_span: span_of(&mode),
        axes,
    }
}

fn axis_set(pair: Pair<'_, Rule>) -> AxisSet {
    let span = span_of(&pair);
    let idents: Vec<Ident> = pair
        .into_inner()
        .filter(|p| p.as_rule() == Rule::ident)
        .map(ident)
        .collect();
    if idents.is_empty() {
        AxisSet::All(span)
    } else {
        AxisSet::List(idents)
    }
}

fn axis_value(pair: Pair<'_, Rule>) -> AxisValue {
    let mut inner = pair.into_inner();
    let axes = axis_set(inner.next().expect("grammar: axis value has axes"));
    let value = expr(inner.next().expect("grammar: axis value has a value"));
    AxisValue { axes, value }
}

fn target(pair: Pair<'_, Rule>) -> Target {
    match pair.as_rule() {
        Rule::ident => Target::State(ident(pair)),
        Rule::extend => {
            let span = span_of(&pair);
            let mut inner = pair.into_inner();
            let axis = axis_ref(inner.next().expect("grammar: extend has an axis"));
            let speed = expr(inner.next().expect("grammar: extend has a speed"));
            let max = expr(inner.next().expect("grammar: extend has a bound"));
            let then = ident(inner.next().expect("grammar: extend has a then state"));
            Target::Extend {
                axis,
                speed,
                max,
                then,
                span,
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} as target"),
    }
}

//! Lowering of a file's top-level items: skills with their parameters, `learn` and `limits`
//! blocks, and tasks with their steps.

use super::states::{state, terminal};
use super::values::{arg, expr, parse_integer};
use super::{doc_text, ident, span_of};
use crate::ast::*;
use pest::iterators::Pair;
use skill_grammar::Rule;

pub(super) fn skill(pair: Pair<'_, Rule>) -> Skill {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut name = None;
    let mut params = Vec::new();
    let mut learn = Vec::new();
    let mut limits = Vec::new();
    let mut states = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => name = Some(ident(inner)),
            Rule::param_decl => params.push(param_decl(inner)),
            Rule::learn => learn.extend(inner.into_inner().map(learn_entry)),
            Rule::limits => limits.extend(inner.into_inner().map(limit_entry)),
            Rule::state => states.push(state(inner)),
            Rule::terminal => states.push(terminal(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in skill"),
        }
    }
    Skill {
        doc,
        name: name.expect("grammar: skill has a name"),
        params,
        learn,
        limits,
        states,
        span,
    }
}

fn param_decl(pair: Pair<'_, Rule>) -> ParamDecl {
    let (doc, name, value) = named_value(pair, "a parameter");
    ParamDecl {
        doc,
        span: name.span.to(value.span),
        name,
        value,
    }
}

/// The doc comment, name and value of `NAME = VALUE` or `NAME: VALUE` (a parameter, a limit);
/// `what` names it in the grammar's invariants.
fn named_value(pair: Pair<'_, Rule>, what: &str) -> (Vec<String>, Ident, Expr) {
    let mut doc = Vec::new();
    let mut name = None;
    let mut value = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::param_kw => {}
            Rule::ident | Rule::key if name.is_none() => name = Some(ident(inner)),
            _ => value = Some(expr(inner)),
        }
    }
    let name = name.unwrap_or_else(|| panic!("grammar: {what} has a name"));
    let value = value.unwrap_or_else(|| panic!("grammar: {what} has a value"));
    (doc, name, value)
}

fn learn_entry(pair: Pair<'_, Rule>) -> LearnDecl {
    let mut doc = Vec::new();
    let mut decl = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            _ => decl = Some(inner),
        }
    }
    let decl = decl.expect("grammar: learn entry has a declaration");
    let span = span_of(&decl);
    let rule = decl.as_rule();
    let mut inner = decl.into_inner();
    let kind = match rule {
        Rule::segments_decl => LearnKind::Segments,
        Rule::frame_decl => LearnKind::Frame,
        Rule::motion_decl => LearnKind::Motion,
        Rule::force_decl => LearnKind::Force,
        Rule::threshold_decl => LearnKind::Threshold,
        Rule::preprocess_decl => {
            let keyword = inner.next().expect("grammar: preprocess keyword");
            if keyword.as_str() == "lowpass" {
                LearnKind::Lowpass
            } else {
                LearnKind::Resample
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} in learn"),
    };
    let mut name = None;
    let mut value = None;
    let mut expect = None;
    for part in inner {
        match part.as_rule() {
            Rule::ident if name.is_none() && value.is_none() && !matches!(kind, LearnKind::Segments) => {
                name = Some(ident(part))
            }
            Rule::expect_clause => {
                let integer = part.into_inner().next().expect("grammar: expect has an integer");
                expect = Some((parse_integer(integer.as_str()), span_of(&integer)));
            }
            _ => value = Some(expr(part)),
        }
    }
    LearnDecl {
        doc,
        kind,
        name,
        value: value.expect("grammar: learn declaration has a value"),
        expect,
        span,
    }
}

fn limit_entry(pair: Pair<'_, Rule>) -> LimitEntry {
    let (doc, name, value) = named_value(pair, "a limit");
    // Like a learn declaration's, the span starts after the doc comment.
    LimitEntry {
        doc,
        span: name.span.to(value.span),
        name,
        value,
    }
}

pub(super) fn task(pair: Pair<'_, Rule>) -> Task {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut name = None;
    let mut steps = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => name = Some(ident(inner)),
            Rule::task_entry => steps.push(step(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in task"),
        }
    }
    Task {
        doc,
        name: name.expect("grammar: task has a name"),
        steps,
        span,
    }
}

fn step(pair: Pair<'_, Rule>) -> Step {
    let mut doc = Vec::new();
    let mut step_pair = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            _ => step_pair = Some(inner),
        }
    }
    let pair = step_pair.expect("grammar: task entry has a step");
    let span = span_of(&pair);
    let fallback = pair.as_rule() == Rule::fallback;
    let mut inner = pair.into_inner();
    let name = ident(inner.next().expect("grammar: step has a name"));
    let call_pair = inner.next().expect("grammar: step has a call");
    let mut call_inner = call_pair.into_inner();
    let skill = ident(call_inner.next().expect("grammar: call has a name"));
    let args = call_inner.map(arg).collect();
    let on_failure = inner.next().map(|policy| {
        let part = policy.into_inner().next().expect("grammar: on failure has a policy");
        match part.as_rule() {
            Rule::abort => OnFailure::Abort(span_of(&part)),
            _ => OnFailure::Fallback(ident(part)),
        }
    });
    Step {
        doc,
        fallback,
        name,
        skill,
        args,
        on_failure,
        span,
    }
}

//! Lowering of guards: `and`, `or`, `not`, `for`, and the comparisons and tests they combine.

use super::values::{axis_ref, expr};
use super::{ident, span_of};
use crate::ast::*;
use pest::iterators::Pair;
use skill_grammar::Rule;

pub(super) fn guard(pair: Pair<'_, Rule>) -> Guard {
    let span = span_of(&pair);
    match pair.as_rule() {
        Rule::guard | Rule::guard_and => {
            let is_or = pair.as_rule() == Rule::guard;
            let mut parts: Vec<Guard> = Vec::new();
            for part in pair.into_inner().map(guard) {
                // `(a and b) and c` is `a and b and c`: flatten so that the formatter's
                // output, which drops redundant parentheses, parses back to the same tree.
                match part.kind {
                    GuardKind::Or(inner) if is_or => parts.extend(inner),
                    GuardKind::And(inner) if !is_or => parts.extend(inner),
                    kind => parts.push(Guard { kind, span: part.span }),
                }
            }
            if parts.len() == 1 {
                return parts.pop().expect("one part");
            }
            Guard {
                kind: if is_or {
                    GuardKind::Or(parts)
                } else {
                    GuardKind::And(parts)
                },
                span,
            }
        }
        Rule::guard_held => {
            let mut inner = pair.into_inner();
            let held = guard(inner.next().expect("grammar: guard_held has a guard"));
            if inner.next().is_none() {
                return held;
            }
            let duration = expr(inner.next().expect("grammar: `for` has a duration"));
            Guard {
                kind: GuardKind::Held {
                    guard: Box::new(held),
                    duration,
                },
                span,
            }
        }
        Rule::guard_not => {
            let mut inner = pair.into_inner();
            let first = inner.next().expect("grammar: guard_not is not empty");
            if first.as_rule() == Rule::not_kw {
                let negated = guard(inner.next().expect("grammar: not has an operand"));
                Guard {
                    kind: GuardKind::Not(Box::new(negated)),
                    span,
                }
            } else {
                guard(first)
            }
        }
        Rule::force_cmp => {
            let mut inner = pair.into_inner();
            let axis = axis_ref(inner.next().expect("grammar: force() has an axis"));
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Force { axis, op, rhs },
                span,
            }
        }
        Rule::moved_cmp => {
            let mut inner = pair.into_inner().skip(1).peekable();
            let axis = match inner.peek().map(Pair::as_rule) {
                Some(Rule::axis_ref) => Some(axis_ref(inner.next().expect("peeked"))),
                _ => None,
            };
            let (since, since_keyword) = match inner.peek().map(Pair::as_rule) {
                Some(Rule::since_clause) => {
                    let mut clause = inner.next().expect("peeked").into_inner();
                    let keyword = clause.next().map(|k| span_of(&k));
                    (clause.next().map(ident), keyword)
                }
                _ => (None, None),
            };
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Moved {
                    axis,
                    since,
                    since_keyword,
                    op,
                    rhs,
                },
                span,
            }
        }
        Rule::magnitude_cmp => {
            let mut inner = pair.into_inner();
            let moment = inner.next().expect("grammar: magnitude keyword").as_str() == "moment_magnitude";
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Magnitude { moment, op, rhs },
                span,
            }
        }
        Rule::entered_cmp => {
            let mut inner = pair.into_inner();
            let _keyword = inner.next().expect("grammar: entered keyword");
            let state = ident(inner.next().expect("grammar: entered names a state"));
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Entered { state, op, rhs },
                span,
            }
        }
        Rule::speed_cmp => {
            let mut inner = pair.into_inner();
            let _keyword = inner.next().expect("grammar: speed keyword");
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Speed { op, rhs },
                span,
            }
        }
        Rule::timed => {
            let mut inner = pair.into_inner();
            let timeout = inner.next().expect("grammar: timed keyword").as_str() == "timeout";
            let duration = expr(inner.next().expect("grammar: timed has a duration"));
            Guard {
                kind: GuardKind::Timed { timeout, duration },
                span,
            }
        }
        Rule::reached => {
            let tolerance = expr(
                pair.into_inner()
                    .next()
                    .expect("grammar: force_reached has a tolerance"),
            );
            Guard {
                kind: GuardKind::ForceReached(tolerance),
                span,
            }
        }
        Rule::named_guard => {
            let name = ident(pair.into_inner().next().expect("grammar: named guard has a name"));
            Guard {
                kind: GuardKind::Named(name),
                span,
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} in guard"),
    }
}

fn cmp_op(pair: Pair<'_, Rule>) -> CmpOp {
    match pair.as_str() {
        ">=" => CmpOp::Ge,
        ">" => CmpOp::Gt,
        "<=" => CmpOp::Le,
        _ => CmpOp::Lt,
    }
}

/// The operator and right-hand side that end every comparison guard (`>= 6 mm`).
fn comparison<'i>(inner: &mut impl Iterator<Item = Pair<'i, Rule>>) -> (CmpOp, Expr) {
    let op = cmp_op(inner.next().expect("grammar: comparison operator"));
    let rhs = expr(inner.next().expect("grammar: comparison has a right-hand side"));
    (op, rhs)
}

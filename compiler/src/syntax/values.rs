//! Lowering of values: expressions with their arithmetic, call arguments, numbers, strings,
//! integers and frame axes.

use super::{ident, span_of};
use crate::ast::*;
use pest::iterators::Pair;
use skill_grammar::Rule;

pub(super) fn arg(pair: Pair<'_, Rule>) -> Arg {
    let span = span_of(&pair);
    let mut key = None;
    let mut value = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::key => key = Some(ident(inner)),
            _ => value = Some(expr(inner)),
        }
    }
    Arg {
        key,
        value: value.expect("grammar: argument has a value"),
        span,
    }
}

pub(super) fn axis_ref(pair: Pair<'_, Rule>) -> AxisRef {
    let span = span_of(&pair);
    let mut inner = pair.into_inner();
    let frame = ident(inner.next().expect("grammar: axis ref has a frame"));
    let axis = ident(inner.next().expect("grammar: axis ref has an axis"));
    AxisRef { frame, axis, span }
}

fn number(pair: Pair<'_, Rule>) -> Number {
    let text = pair.as_str().to_string();
    // The grammar admits only decimal literals, which always parse (perhaps to infinity, checked later).
    let value = text.parse().unwrap_or(f64::NAN);
    Number { text, value }
}

pub(super) fn string(pair: Pair<'_, Rule>) -> String {
    let raw = pair.into_inner().next().map_or("", |inner| inner.as_str());
    let mut out = String::with_capacity(raw.len());
    let mut chars = raw.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(other) => out.push(other),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}

pub(super) fn expr(pair: Pair<'_, Rule>) -> Expr {
    let span = span_of(&pair);
    let kind = match pair.as_rule() {
        Rule::quantity => {
            let mut inner = pair.into_inner();
            let number_pair = inner.next().expect("grammar: quantity has a number");
            let unit = ident(inner.next().expect("grammar: quantity has a unit"));
            ExprKind::Quantity {
                number: number(number_pair),
                unit,
            }
        }
        Rule::number => ExprKind::Number(number(pair)),
        Rule::string => ExprKind::Str(string(pair)),
        Rule::list => ExprKind::List(pair.into_inner().map(expr).collect()),
        Rule::record => ExprKind::Record(pair.into_inner().map(arg).collect()),
        Rule::segment_ref => {
            let integer = pair.into_inner().next().expect("grammar: segment has an index");
            ExprKind::Segment(parse_integer(integer.as_str()))
        }
        Rule::call => {
            let mut inner = pair.into_inner();
            let name = ident(inner.next().expect("grammar: call has a name"));
            ExprKind::Call {
                name,
                args: inner.map(arg).collect(),
            }
        }
        Rule::axis_ref => ExprKind::Axis(axis_ref(pair)),
        Rule::ident => ExprKind::Name(ident(pair)),
        Rule::negated => {
            let mut inner = pair.into_inner();
            let _op = inner.next().expect("grammar: negation has its `-`");
            ExprKind::Neg(Box::new(expr(inner.next().expect("grammar: negation has an operand"))))
        }
        Rule::sum | Rule::product => {
            let mut inner = pair.into_inner();
            let first = inner.next().expect("grammar: a chain has a first operand");
            if inner.peek().is_none() {
                // A value without an operator at this level (its span is the operand's: the
                // chain's takes the whitespace after it).
                return expr(first);
            }
            let first = Box::new(expr(first));
            let mut rest = Vec::new();
            while let (Some(op), Some(operand)) = (inner.next(), inner.next()) {
                let op = match op.as_str() {
                    "+" => BinOp::Add,
                    "-" => BinOp::Sub,
                    "*" => BinOp::Mul,
                    _ => BinOp::Div,
                };
                rest.push((op, expr(operand)));
            }
            ExprKind::Arith { first, rest }
        }
        rule => unreachable!("grammar: unexpected {rule:?} as value"),
    };
    Expr { kind, span }
}

pub(super) fn parse_integer(text: &str) -> u64 {
    // The grammar admits only digits; an absurdly long integer saturates and is range-checked later.
    text.parse().unwrap_or(u64::MAX)
}

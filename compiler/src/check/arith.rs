//! Arithmetic on quantities (`-inset`, `depth + 2 mm`, `2 * hold`, `(a + b) / 2`), folded to
//! one literal once the skill's parameters are substituted, so that every later check (units,
//! ranges, never-fires) sees the value the skill runs with.
//!
//! The rules are those of physical quantities: `+` and `-` join values of one dimension (a
//! length and a length; a number and a number), `*` and `/` scale a value by a plain number,
//! and `-` negates. A product or a quotient of two quantities has no dimension skillc knows
//! (`mm * mm`), so it is refused rather than guessed. The result keeps the unit of the value it
//! started from (`depth + 2 mm` with `depth = 15 mm` is `17 mm`), so messages about it read in
//! the author's units.

use super::Checker;
use crate::ast::{self, BinOp, ExprKind};
use crate::diag::{Code, Diag};
use crate::source::Span;
use crate::units::{self, Dim};

/// A value met while folding.
#[derive(Debug, Clone)]
enum Value {
    Number(f64),
    /// `si` in SI units; `unit` names the unit to write the result in.
    Quantity {
        si: f64,
        dim: Dim,
        unit: &'static str,
    },
    /// A list of numbers or quantities (`[0 mm, 0 mm, 5 mm]`), computed component by component.
    Vector(Vec<Value>),
}

impl Value {
    fn describe(&self) -> &'static str {
        match self {
            Value::Number(_) => "a plain number",
            Value::Quantity { dim, .. } => dim.describe(),
            Value::Vector(_) => "a list",
        }
    }

    fn finite(&self) -> bool {
        match self {
            Value::Number(v) | Value::Quantity { si: v, .. } => v.is_finite(),
            Value::Vector(items) => items.iter().all(Value::finite),
        }
    }
}

/// Why an expression does not fold.
#[derive(Debug)]
pub(crate) struct ArithError {
    code: Code,
    span: Span,
    message: String,
    label: &'static str,
    help: String,
}

impl ArithError {
    fn new(code: Code, span: Span, message: String, label: &'static str, help: impl Into<String>) -> Self {
        ArithError {
            code,
            span,
            message,
            label,
            help: help.into(),
        }
    }

    /// The diagnostic, for file `file`.
    pub(crate) fn into_diag(self, file: usize) -> Diag {
        Diag::new(self.code, file, self.span, self.message, self.label).help(self.help)
    }
}

/// Replaces every arithmetic expression inside `expr` by the literal it computes. The folded
/// literal is spanned over the whole expression it replaces.
pub(crate) fn fold(expr: &mut ast::Expr) -> Result<(), ArithError> {
    match &mut expr.kind {
        ExprKind::Neg(_) | ExprKind::Arith { .. } => {
            let value = evaluate(expr)?;
            expr.kind = literal(&value, expr.span);
            Ok(())
        }
        ExprKind::List(items) => items.iter_mut().try_for_each(fold),
        ExprKind::Record(args) | ExprKind::Call { args, .. } => {
            args.iter_mut().try_for_each(|arg| fold(&mut arg.value))
        }
        _ => Ok(()),
    }
}

impl Checker<'_> {
    /// [`fold`], reporting a failure in this checker's file; whether it folded.
    pub(super) fn fold_reporting(&mut self, expr: &mut ast::Expr) -> bool {
        self.fold_in(expr, self.file)
    }

    /// [`fold`], reporting a failure in file `file` (a setting written in another file).
    pub(super) fn fold_in(&mut self, expr: &mut ast::Expr, file: usize) -> bool {
        match fold(expr) {
            Ok(()) => true,
            Err(error) => {
                self.report(error.into_diag(file));
                false
            }
        }
    }
}

fn evaluate(expr: &ast::Expr) -> Result<Value, ArithError> {
    let value = match &expr.kind {
        ExprKind::Number(number) => Value::Number(number.value),
        ExprKind::Quantity { number, unit } => {
            let Some(&(name, dim, factor)) = units::UNITS.iter().find(|(name, _, _)| *name == unit.name) else {
                return Err(ArithError::new(
                    Code::UnknownUnit,
                    unit.span,
                    format!("unknown unit `{}`", unit.name),
                    "unknown unit",
                    format!(
                        "units skillc knows: {}",
                        units::UNITS.iter().map(|(n, _, _)| *n).collect::<Vec<_>>().join(", ")
                    ),
                ));
            };
            Value::Quantity {
                si: number.value * factor,
                dim,
                unit: name,
            }
        }
        ExprKind::Neg(inner) => negate(evaluate(inner)?),
        ExprKind::List(items) => {
            let mut values = Vec::with_capacity(items.len());
            for item in items {
                match evaluate(item)? {
                    Value::Vector(_) => {
                        return Err(ArithError::new(
                            Code::BadArithmetic,
                            item.span,
                            "arithmetic on a list of lists".to_string(),
                            "a list inside a list",
                            "a list's items are numbers or quantities",
                        ))
                    }
                    value => values.push(value),
                }
            }
            Value::Vector(values)
        }
        ExprKind::Arith { first, rest } => {
            let mut value = evaluate(first)?;
            for (op, operand) in rest {
                value = combine(*op, value, evaluate(operand)?, expr.span.start, operand.span)?;
            }
            value
        }
        ExprKind::Name(name) => {
            return Err(ArithError::new(
                Code::BadArithmetic,
                name.span,
                format!("`{}` is not a parameter of this skill", name.name),
                "not a number",
                "arithmetic takes numbers, quantities and the skill's parameters \
                 (in a parameter's default, the parameters declared before it)",
            ))
        }
        other => {
            return Err(ArithError::new(
                Code::BadArithmetic,
                expr.span,
                format!("arithmetic on {}", kind_name(other)),
                "not a number",
                "arithmetic takes numbers, quantities and the skill's parameters",
            ))
        }
    };
    if !value.finite() {
        return Err(ArithError::new(
            Code::OutOfRange,
            expr.span,
            "the value is not finite".to_string(),
            "too large",
            "use values of a physical size",
        ));
    }
    Ok(value)
}

fn negate(value: Value) -> Value {
    match value {
        Value::Number(v) => Value::Number(-v),
        Value::Quantity { si, dim, unit } => Value::Quantity { si: -si, dim, unit },
        Value::Vector(items) => Value::Vector(items.into_iter().map(negate).collect()),
    }
}

/// `lhs op rhs`, where the expression so far starts at byte `start` and `rhs` is at `rhs_span`.
/// Lists combine component by component: a list `±` a list of as many items, a list scaled by
/// or divided by a plain number.
fn combine(op: BinOp, lhs: Value, rhs: Value, start: usize, rhs_span: Span) -> Result<Value, ArithError> {
    use Value::{Number, Vector};
    let each = |pairs: Vec<(Value, Value)>| -> Result<Value, ArithError> {
        let items = pairs
            .into_iter()
            .map(|(x, y)| combine(op, x, y, start, rhs_span))
            .collect::<Result<_, _>>()?;
        Ok(Vector(items))
    };
    match (op, lhs, rhs) {
        (BinOp::Add | BinOp::Sub, Vector(a), Vector(b)) if a.len() == b.len() => each(a.into_iter().zip(b).collect()),
        (BinOp::Mul | BinOp::Div, Vector(items), k @ Number(_)) => {
            each(items.into_iter().map(|x| (x, k.clone())).collect())
        }
        (BinOp::Mul, k @ Number(_), Vector(items)) => each(items.into_iter().map(|x| (k.clone(), x)).collect()),
        (op, lhs @ Vector(_), rhs) | (op, lhs, rhs @ Vector(_)) => {
            let (lhs, rhs) = (describe_sized(&lhs), describe_sized(&rhs));
            let (message, help) = match op {
                BinOp::Add => (
                    format!("adds {lhs} and {rhs}"),
                    "add lists of as many items, component by component",
                ),
                BinOp::Sub => (
                    format!("subtracts {lhs} and {rhs}"),
                    "subtract lists of as many items, component by component",
                ),
                BinOp::Mul => (
                    format!("multiplies {lhs} by {rhs}"),
                    "scale a list by a plain number: `2 * back`",
                ),
                BinOp::Div => (
                    format!("divides {lhs} by {rhs}"),
                    "divide a list by a plain number: `back / 2`",
                ),
            };
            Err(ArithError::new(
                Code::BadArithmetic,
                Span::new(start, rhs_span.end),
                message,
                "not component by component",
                help,
            ))
        }
        (_, lhs, rhs) => combine_scalars(op, lhs, rhs, Span::new(start, rhs_span.end), rhs_span),
    }
}

/// A value's description with a list's length: `a list of 3 values`.
fn describe_sized(value: &Value) -> String {
    match value {
        Value::Vector(items) => format!("a list of {} values", items.len()),
        other => other.describe().to_string(),
    }
}

/// `lhs op rhs` for two numbers or quantities; `whole` spans the expression so far.
fn combine_scalars(op: BinOp, lhs: Value, rhs: Value, whole: Span, rhs_span: Span) -> Result<Value, ArithError> {
    use Value::{Number, Quantity};
    let mismatch = |lhs: &Value, rhs: &Value, verb: &str| {
        ArithError::new(
            Code::UnitMismatch,
            whole,
            format!("{verb} {} and {}", lhs.describe(), rhs.describe()),
            "different dimensions",
            match (lhs, rhs) {
                (Number(_), Quantity { unit, .. }) | (Quantity { unit, .. }, Number(_)) => {
                    format!("give both sides a unit, e.g. `{unit}`")
                }
                _ => "add or subtract values of one dimension".to_string(),
            },
        )
    };
    let value = match op {
        BinOp::Add | BinOp::Sub => {
            let sign = if op == BinOp::Add { 1.0 } else { -1.0 };
            let verb = if op == BinOp::Add { "adds" } else { "subtracts" };
            match (&lhs, &rhs) {
                (Number(a), Number(b)) => Number(a + sign * b),
                (Quantity { si: a, dim, unit }, Quantity { si: b, dim: other, .. }) if dim == other => Quantity {
                    si: a + sign * b,
                    dim: *dim,
                    unit,
                },
                _ => return Err(mismatch(&lhs, &rhs, verb)),
            }
        }
        BinOp::Mul => match (&lhs, &rhs) {
            (Number(a), Number(b)) => Number(a * b),
            (Number(k), Quantity { si, dim, unit }) | (Quantity { si, dim, unit }, Number(k)) => Quantity {
                si: si * k,
                dim: *dim,
                unit,
            },
            _ => {
                return Err(ArithError::new(
                    Code::BadArithmetic,
                    whole,
                    format!("multiplies {} by {}", lhs.describe(), rhs.describe()),
                    "no such dimension",
                    "scale a quantity by a plain number: `2 * hold`",
                ))
            }
        },
        BinOp::Div => {
            let divisor = match &rhs {
                Number(b) => *b,
                Quantity { .. } | Value::Vector(_) => {
                    return Err(ArithError::new(
                        Code::BadArithmetic,
                        whole,
                        format!("divides {} by {}", lhs.describe(), rhs.describe()),
                        "no such dimension",
                        "divide by a plain number: `depth / 2`",
                    ))
                }
            };
            if divisor == 0.0 {
                return Err(ArithError::new(
                    Code::BadArithmetic,
                    rhs_span,
                    "division by zero".to_string(),
                    "zero",
                    "divide by a number other than 0",
                ));
            }
            match lhs {
                Number(a) => Number(a / divisor),
                Quantity { si, dim, unit } => Quantity {
                    si: si / divisor,
                    dim,
                    unit,
                },
                // Lists never get here: `combine` takes them apart first.
                vector @ Value::Vector(_) => vector,
            }
        }
    };
    Ok(value)
}

/// The literal of a folded value, in the unit the value carries.
fn literal(value: &Value, span: Span) -> ExprKind {
    match *value {
        Value::Vector(ref items) => ExprKind::List(
            items
                .iter()
                .map(|item| ast::Expr {
                    kind: literal(item, span),
                    span,
                })
                .collect(),
        ),
        Value::Number(v) => ExprKind::Number(ast::Number {
            text: number_text(v + 0.0),
            value: v + 0.0,
        }),
        Value::Quantity { si, unit, .. } => {
            let factor = units::lookup(unit).map_or(1.0, |(_, factor)| factor);
            // `-[0 mm, 0 mm, 5 mm]` has no -0 mm.
            let v = si / factor + 0.0;
            ExprKind::Quantity {
                number: ast::Number {
                    text: number_text(v),
                    value: v,
                },
                unit: ast::Ident {
                    name: unit.to_string(),
                    span,
                },
            }
        }
    }
}

/// A number as a literal would write it: whole numbers without a point (`4`, which counts
/// accept), others to 9 decimals with trailing zeros dropped (`17` for 17.000000000000004).
fn number_text(v: f64) -> String {
    let rounded = (v * 1e9).round() / 1e9;
    if rounded == rounded.trunc() && rounded.abs() < 1e15 {
        return format!("{}", rounded as i64);
    }
    if v.abs() < 1e-6 || v.abs() >= 1e15 {
        return format!("{v:e}");
    }
    let text = format!("{v:.9}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn kind_name(kind: &ExprKind) -> &'static str {
    match kind {
        ExprKind::Str(_) => "a string",
        ExprKind::List(_) => "a list",
        ExprKind::Record(_) => "a record",
        ExprKind::Segment(_) => "a segment",
        ExprKind::Call { .. } => "a function call",
        ExprKind::Axis(_) => "a frame's axis",
        _ => "this value",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ast::Expr;

    fn span() -> Span {
        Span { start: 0, end: 1 }
    }

    fn q(v: f64, unit: &str) -> Expr {
        Expr {
            kind: ExprKind::Quantity {
                number: ast::Number {
                    text: v.to_string(),
                    value: v,
                },
                unit: ast::Ident {
                    name: unit.to_string(),
                    span: span(),
                },
            },
            span: span(),
        }
    }

    fn n(v: f64) -> Expr {
        Expr {
            kind: ExprKind::Number(ast::Number {
                text: v.to_string(),
                value: v,
            }),
            span: span(),
        }
    }

    fn bin(op: BinOp, lhs: Expr, rhs: Expr) -> Expr {
        Expr {
            kind: ExprKind::Arith {
                first: Box::new(lhs),
                rest: vec![(op, rhs)],
            },
            span: span(),
        }
    }

    fn folded(mut expr: Expr) -> Result<(f64, String, String), Code> {
        fold(&mut expr).map_err(|e| e.code)?;
        match expr.kind {
            ExprKind::Number(number) => Ok((number.value, number.text, String::new())),
            ExprKind::Quantity { number, unit } => Ok((number.value, number.text, unit.name)),
            other => panic!("not a literal: {other:?}"),
        }
    }

    #[test]
    fn sums_keep_the_left_unit_and_convert_the_right() {
        let (v, text, unit) = folded(bin(BinOp::Add, q(15.0, "mm"), q(2.0, "cm"))).unwrap();
        assert!((v - 35.0).abs() < 1e-9, "{v}");
        assert_eq!((text.as_str(), unit.as_str()), ("35", "mm"));
        let (v, _, unit) = folded(bin(BinOp::Sub, q(1.0, "s"), q(250.0, "ms"))).unwrap();
        assert!((v - 0.75).abs() < 1e-12);
        assert_eq!(unit, "s");
    }

    #[test]
    fn scaling_negation_and_counts() {
        let (v, _, unit) = folded(bin(BinOp::Mul, n(2.0), q(1.5, "s"))).unwrap();
        assert_eq!((v, unit.as_str()), (3.0, "s"));
        let (v, _, _) = folded(bin(BinOp::Div, q(10.0, "N"), n(4.0))).unwrap();
        assert_eq!(v, 2.5);
        let neg = Expr {
            kind: ExprKind::Neg(Box::new(q(15.0, "mm"))),
            span: span(),
        };
        assert_eq!(folded(neg).unwrap().0, -15.0);
        // A count stays whole-looking, so `repeat 2 * 3` is a count.
        let (_, text, unit) = folded(bin(BinOp::Mul, n(2.0), n(3.0))).unwrap();
        assert_eq!((text.as_str(), unit.as_str()), ("6", ""));
        // 0.1 + 0.2 reads as written, not as 0.30000000000000004.
        assert_eq!(folded(bin(BinOp::Add, n(0.1), n(0.2))).unwrap().1, "0.3");
    }

    #[test]
    fn refuses_what_has_no_dimension_or_no_value() {
        assert_eq!(
            folded(bin(BinOp::Add, q(1.0, "mm"), q(1.0, "N"))).unwrap_err(),
            Code::UnitMismatch
        );
        assert_eq!(
            folded(bin(BinOp::Add, q(1.0, "mm"), n(1.0))).unwrap_err(),
            Code::UnitMismatch
        );
        assert_eq!(
            folded(bin(BinOp::Mul, q(1.0, "mm"), q(1.0, "mm"))).unwrap_err(),
            Code::BadArithmetic
        );
        assert_eq!(
            folded(bin(BinOp::Div, q(1.0, "mm"), q(1.0, "mm"))).unwrap_err(),
            Code::BadArithmetic
        );
        assert_eq!(
            folded(bin(BinOp::Div, q(1.0, "mm"), n(0.0))).unwrap_err(),
            Code::BadArithmetic
        );
        assert_eq!(
            folded(bin(BinOp::Mul, q(1e308, "m"), n(10.0))).unwrap_err(),
            Code::OutOfRange
        );
        let name = Expr {
            kind: ExprKind::Name(ast::Ident {
                name: "depth".into(),
                span: span(),
            }),
            span: span(),
        };
        assert_eq!(
            folded(bin(BinOp::Add, name, q(1.0, "mm"))).unwrap_err(),
            Code::BadArithmetic
        );
    }

    fn list(items: Vec<Expr>) -> Expr {
        Expr {
            kind: ExprKind::List(items),
            span: span(),
        }
    }

    /// The folded list's items in SI, or the error's code.
    fn folded_list(mut expr: Expr) -> Result<Vec<f64>, Code> {
        fold(&mut expr).map_err(|e| e.code)?;
        let ExprKind::List(items) = &expr.kind else {
            panic!("a list: {expr:?}")
        };
        Ok(items
            .iter()
            .map(|item| match &item.kind {
                ExprKind::Quantity { number, unit } => number.value * units::lookup(&unit.name).expect("a unit").1,
                ExprKind::Number(number) => number.value,
                other => panic!("{other:?}"),
            })
            .collect())
    }

    #[test]
    fn lists_negate_add_and_scale_component_by_component() {
        let back = || list(vec![q(0.0, "mm"), q(1.0, "cm"), q(5.0, "mm")]);
        let neg = Expr {
            kind: ExprKind::Neg(Box::new(back())),
            span: span(),
        };
        assert_eq!(folded_list(neg), Ok(vec![0.0, -0.01, -0.005]));
        let sum = bin(BinOp::Add, back(), list(vec![q(1.0, "mm"), q(0.0, "m"), q(-5.0, "mm")]));
        let sum = folded_list(sum).unwrap();
        assert!((sum[0] - 0.001).abs() < 1e-15 && (sum[1] - 0.01).abs() < 1e-15 && sum[2].abs() < 1e-15);
        assert_eq!(folded_list(bin(BinOp::Mul, n(2.0), back())), Ok(vec![0.0, 0.02, 0.01]));
        assert_eq!(
            folded_list(bin(BinOp::Div, back(), n(2.0))),
            Ok(vec![0.0, 0.005, 0.0025])
        );
        // What is not component by component, or mixes dimensions within a component.
        let pair = || list(vec![q(1.0, "mm"), q(1.0, "mm")]);
        for (expr, code) in [
            (bin(BinOp::Add, back(), q(2.0, "mm")), Code::BadArithmetic),
            (bin(BinOp::Mul, back(), back()), Code::BadArithmetic),
            (bin(BinOp::Mul, q(2.0, "mm"), back()), Code::BadArithmetic),
            (bin(BinOp::Div, n(2.0), back()), Code::BadArithmetic),
            (bin(BinOp::Sub, back(), pair()), Code::BadArithmetic),
            (bin(BinOp::Div, back(), n(0.0)), Code::BadArithmetic),
            (
                bin(BinOp::Add, back(), list(vec![q(1.0, "mm"), q(1.0, "N"), q(1.0, "mm")])),
                Code::UnitMismatch,
            ),
            (
                list(vec![q(1.0, "mm"), bin(BinOp::Add, pair(), pair())]),
                Code::BadArithmetic,
            ),
        ] {
            let wrapped = Expr {
                kind: ExprKind::Neg(Box::new(expr)),
                span: span(),
            };
            assert_eq!(folded_list(wrapped).err(), Some(code));
        }
    }

    #[test]
    fn a_chain_folds_left_to_right() {
        // 1 s - 250 ms - 250 ms = 0.5 s (not 1 s - (250 ms - 250 ms)).
        let chain = Expr {
            kind: ExprKind::Arith {
                first: Box::new(q(1.0, "s")),
                rest: vec![(BinOp::Sub, q(250.0, "ms")), (BinOp::Sub, q(250.0, "ms"))],
            },
            span: span(),
        };
        assert!((folded(chain).unwrap().0 - 0.5).abs() < 1e-12);
        // 12 / 2 / 3 = 2.
        let chain = Expr {
            kind: ExprKind::Arith {
                first: Box::new(n(12.0)),
                rest: vec![(BinOp::Div, n(2.0)), (BinOp::Div, n(3.0))],
            },
            span: span(),
        };
        assert_eq!(folded(chain).unwrap().0, 2.0);
    }

    #[test]
    fn folds_inside_lists_and_calls() {
        let mut list = Expr {
            kind: ExprKind::List(vec![q(0.0, "mm"), bin(BinOp::Mul, n(-1.0), q(5.0, "mm"))]),
            span: span(),
        };
        fold(&mut list).unwrap();
        let ExprKind::List(items) = &list.kind else {
            unreachable!()
        };
        assert!(matches!(&items[0].kind, ExprKind::Quantity { number, .. } if number.value == 0.0));
        assert!(matches!(&items[1].kind, ExprKind::Quantity { number, .. } if number.value == -5.0));
    }
}

//! Values in arguments: quantities with units, plain numbers, counts, strings, lists of three,
//! names from a fixed set, and the binding of call arguments to parameters.

use super::signatures::Signature;
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, ExprKind};
use crate::diag::{did_you_mean, Code};
use crate::source::Span;
use crate::units::{self, Dim};
use std::collections::HashMap;

/// The arguments of one call, bound to parameter names, with what a report of a missing one
/// needs: the function's name, the call's span and an example.
pub(super) struct Args<'e> {
    pub(super) function: &'e str,
    pub(super) example: &'e str,
    pub(super) span: Span,
    pub(super) bound: HashMap<&'static str, &'e ast::Expr>,
}

impl<'e> Args<'e> {
    /// The argument given for `param`.
    pub(super) fn get(&self, param: &str) -> Option<&'e ast::Expr> {
        self.bound.get(param).copied()
    }
}

impl Checker<'_> {
    /// A quantity of dimension `dim`, in SI units.
    pub(super) fn quantity(&mut self, expr: &ast::Expr, dim: Dim, what: &str) -> Option<f64> {
        match &expr.kind {
            ExprKind::Quantity { number, unit } => {
                let Some((found, factor)) = units::lookup(&unit.name) else {
                    let candidates: Vec<&str> = units::UNITS.iter().map(|(name, _, _)| *name).collect();
                    let help = did_you_mean(&unit.name, candidates.iter().copied())
                        .map(|found| format!("did you mean `{found}`?"))
                        .unwrap_or_else(|| format!("units of {}: {}", dim, units::units_of(dim).join(", ")));
                    let diag = self
                        .diag(
                            Code::UnknownUnit,
                            unit.span,
                            format!("unknown unit `{}`", unit.name),
                            "not a unit skillc knows",
                        )
                        .help(help);
                    self.report(diag);
                    return None;
                };
                if found != dim {
                    let diag = self
                        .diag(
                            Code::UnitMismatch,
                            expr.span,
                            format!("{what} must be {dim}, found {found}"),
                            format!("`{}` is {found}", unit.name),
                        )
                        .help(format!("use a unit for {dim}: {}", units::units_of(dim).join(", ")));
                    self.report(diag);
                    return None;
                }
                self.finite(number.value * factor, expr.span, what)
            }
            ExprKind::Number(number) => {
                let diag = self
                    .diag(
                        Code::MissingUnit,
                        expr.span,
                        format!("{what} needs a unit"),
                        format!("{dim} without a unit"),
                    )
                    .help(format!("write `{} {}`", number.text, dim.example_unit()));
                self.report(diag);
                None
            }
            _ => {
                let diag = self.diag(
                    Code::BadArgument,
                    expr.span,
                    format!("{what} must be {dim}, like `{}`", example_quantity(dim)),
                    "not a quantity",
                );
                self.report(diag);
                None
            }
        }
    }

    /// `value`, or `None` after reporting that it is not finite.
    fn finite(&mut self, value: f64, span: Span, what: &str) -> Option<f64> {
        if value.is_finite() {
            return Some(value);
        }
        let diag = self.diag(Code::OutOfRange, span, format!("{what} is not finite"), "too large");
        self.report(diag);
        None
    }

    /// A plain number (gains, scales, weights).
    pub(super) fn plain_number(&mut self, expr: &ast::Expr, what: &str) -> Option<f64> {
        match &expr.kind {
            ExprKind::Number(number) => self.finite(number.value, expr.span, what),
            ExprKind::Quantity { unit, number } => {
                let diag = self
                    .diag(
                        Code::UnitMismatch,
                        expr.span,
                        format!("{what} is a plain number, not a quantity"),
                        format!("remove `{}`", unit.name),
                    )
                    .help(format!("write `{}`", number.text));
                self.report(diag);
                None
            }
            _ => {
                let diag = self.diag(
                    Code::BadArgument,
                    expr.span,
                    format!("{what} must be a number"),
                    "not a number",
                );
                self.report(diag);
                None
            }
        }
    }

    /// A positive integer that fits in `u32`, written as digits or in any form whose value is
    /// whole (`1e3`, `2.0`: a `--param taps=1e3` is a thousand taps).
    pub(super) fn count(&mut self, expr: &ast::Expr, what: &str) -> Option<u32> {
        match &expr.kind {
            ExprKind::Number(number) if whole_number(&number.text).is_some() => {
                match u32::try_from(whole_number(&number.text).unwrap_or(u64::MAX)) {
                    Ok(value) if value > 0 => Some(value),
                    _ => {
                        let diag = self.diag(
                            Code::OutOfRange,
                            expr.span,
                            format!("{what} must be between 1 and {}", u32::MAX),
                            "out of range",
                        );
                        self.report(diag);
                        None
                    }
                }
            }
            _ => {
                // A quantity (often a parameter's value put in its place) is named by its
                // dimension: "must be a whole number" alone reads as if `10 s` were a fraction.
                let (message, label) = match &expr.kind {
                    ExprKind::Quantity { number, unit } => match units::lookup(&unit.name) {
                        Some((dim, _)) => (
                            format!(
                                "{what} must be a whole number, not {} (`{} {}`)",
                                dim.describe(),
                                number.text,
                                unit.name
                            ),
                            "not a count",
                        ),
                        None => (format!("{what} must be a whole number"), "not a count"),
                    },
                    _ => (format!("{what} must be a whole number"), "not a count"),
                };
                let diag = self
                    .diag(Code::BadArgument, expr.span, message, label)
                    .help("a count is a plain number without a unit: `3`");
                self.report(diag);
                None
            }
        }
    }

    pub(super) fn positive(&mut self, value: Option<f64>, span: Span, what: &str) -> Option<f64> {
        match value {
            Some(v) if v > 0.0 => Some(v),
            Some(_) => {
                let diag = self.diag(
                    Code::OutOfRange,
                    span,
                    format!("{what} must be positive"),
                    "zero or negative",
                );
                self.report(diag);
                None
            }
            None => None,
        }
    }

    pub(super) fn string(&mut self, expr: &ast::Expr, what: &str) -> Option<String> {
        match &expr.kind {
            ExprKind::Str(text) => Some(text.clone()),
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        format!("{what} must be a string"),
                        "not a string",
                    )
                    .help("put the path in double quotes");
                self.report(diag);
                None
            }
        }
    }

    /// Binds call arguments to parameter names. The first `positional` parameters may be
    /// given without a key. Reports unknown, repeated and surplus arguments.
    pub(super) fn bind_args<'e>(
        &mut self,
        function: &str,
        args: &'e [ast::Arg],
        params: &[&'static str],
        positional: usize,
    ) -> HashMap<&'static str, &'e ast::Expr> {
        let takes = || {
            if params.is_empty() {
                format!("`{function}` takes no arguments")
            } else {
                format!("`{function}` takes {}", join_ticked(params))
            }
        };
        let mut bound: HashMap<&'static str, &'e ast::Expr> = HashMap::new();
        let mut next_positional = 0;
        for arg in args {
            let param = match &arg.key {
                Some(key) => match params.iter().find(|p| **p == key.name) {
                    Some(param) => *param,
                    None => {
                        let help = suggest(&key.name, params.iter().copied()).unwrap_or_else(takes);
                        let diag = self
                            .diag(
                                Code::BadArgument,
                                key.span,
                                format!("unknown argument `{}` of `{function}`", key.name),
                                "unknown argument",
                            )
                            .help(help);
                        self.report(diag);
                        continue;
                    }
                },
                None => {
                    if next_positional >= positional {
                        let help = if params.is_empty() {
                            takes()
                        } else {
                            format!("name it: {}", takes())
                        };
                        let diag = self
                            .diag(
                                Code::BadArgument,
                                arg.span,
                                format!("too many positional arguments to `{function}`"),
                                "unexpected argument",
                            )
                            .help(help);
                        self.report(diag);
                        continue;
                    }
                    next_positional += 1;
                    params[next_positional - 1]
                }
            };
            if bound.insert(param, &arg.value).is_some() {
                let diag = self.diag(
                    Code::BadArgument,
                    arg.span,
                    format!("argument `{param}` of `{function}` given twice"),
                    "repeated argument",
                );
                self.report(diag);
            }
        }
        bound
    }

    /// Binds the arguments of a call of a learn function to its signature.
    pub(super) fn bind<'e>(&mut self, sig: &'static Signature, span: Span, args: &'e [ast::Arg]) -> Args<'e> {
        Args {
            function: sig.name,
            example: sig.example,
            span,
            bound: self.bind_args(sig.name, args, sig.params, sig.positional),
        }
    }

    /// Reports that the call lacks `param`.
    pub(super) fn missing(&mut self, args: &Args<'_>, param: &str) {
        self.missing_arg(args.function, param, args.span, args.example);
    }

    pub(super) fn missing_arg(&mut self, function: &str, param: &str, span: Span, example: &str) {
        let diag = self
            .diag(
                Code::BadArgument,
                span,
                format!("`{function}` needs the argument `{param}`"),
                format!("`{param}` missing"),
            )
            .help(format!("write `{example}`"));
        self.report(diag);
    }

    /// A required argument, or `None` after reporting it missing.
    pub(super) fn required<'e>(&mut self, args: &Args<'e>, param: &str) -> Option<&'e ast::Expr> {
        let expr = args.get(param);
        if expr.is_none() {
            self.missing(args, param);
        }
        expr
    }

    pub(super) fn enum_name<T: Copy>(
        &mut self,
        expr: &ast::Expr,
        what: &str,
        options: &[(&'static str, T)],
    ) -> Option<T> {
        let names: Vec<&str> = options.iter().map(|(name, _)| *name).collect();
        if let ExprKind::Name(name) = &expr.kind {
            if let Some((_, value)) = options.iter().find(|(n, _)| *n == name.name) {
                return Some(*value);
            }
            let diag = self
                .diag(
                    Code::BadArgument,
                    name.span,
                    format!("unknown {what} `{}`", name.name),
                    format!("not {what}"),
                )
                .help(
                    suggest(&name.name, names.iter().copied())
                        .unwrap_or_else(|| format!("use one of {}", join_ticked(&names))),
                );
            self.report(diag);
            return None;
        }
        let diag = self
            .diag(
                Code::BadArgument,
                expr.span,
                format!("expected {what}"),
                format!("not {what}"),
            )
            .help(format!("use one of {}", join_ticked(&names)));
        self.report(diag);
        None
    }

    pub(super) fn vector3(&mut self, expr: &ast::Expr, dim: Dim, what: &str) -> Option<[f64; 3]> {
        match &expr.kind {
            ExprKind::List(items) if items.len() == 3 => {
                let mut out = [0.0; 3];
                let mut ok = true;
                for (slot, item) in out.iter_mut().zip(items) {
                    match self.quantity(item, dim, what) {
                        Some(value) => *slot = value,
                        None => ok = false,
                    }
                }
                ok.then_some(out)
            }
            _ => {
                let unit = dim.example_unit();
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        format!("{what} must be a list of 3 values"),
                        "expected 3 values",
                    )
                    .help(format!("write `[0 {unit}, 0 {unit}, 0 {unit}]`"));
                self.report(diag);
                None
            }
        }
    }
}

fn example_quantity(dim: Dim) -> String {
    format!("5 {}", dim.example_unit())
}

/// The value of a number literal when it is whole and not negative (`3`, `1e3`, `2.0`),
/// saturating at `u64::MAX` (a whole number too large to count is out of range, not "not
/// whole"); `None` for a fraction, a negative number or NaN.
pub(super) fn whole_number(text: &str) -> Option<u64> {
    if !text.contains(['.', 'e', 'E', '-', '+']) {
        return Some(text.parse::<u64>().unwrap_or(u64::MAX));
    }
    let value: f64 = text.parse().ok()?;
    if value.is_infinite() && value > 0.0 {
        return Some(u64::MAX);
    }
    // `as` saturates at u64::MAX.
    (value.is_finite() && value >= 0.0 && value.fract() == 0.0).then_some(value as u64)
}

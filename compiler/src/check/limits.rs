//! Safety limits: a skill's `limits { }` block and a task step's `limits: { }` argument,
//! checked against the supervisor's one table of names and dimensions ([`ir::LIMITS`]) and
//! lowered to [`ir::Limit`]s in SI units.

use super::{join_ticked, suggest, Checker};
use crate::ast::{self, ExprKind};
use crate::diag::Code;
use crate::source::Span;
use crate::units::Dim;
use skill_ir as ir;
use std::collections::HashMap;

/// The dimension of the language's units for a limit's dimension; `None` for a plain number.
fn unit_dim(dim: ir::LimitDim) -> Option<Dim> {
    match dim {
        ir::LimitDim::Force => Some(Dim::Force),
        ir::LimitDim::Moment => Some(Dim::Torque),
        ir::LimitDim::Speed => Some(Dim::Speed),
        ir::LimitDim::AngularSpeed => Some(Dim::AngularSpeed),
        ir::LimitDim::Angle => Some(Dim::Angle),
        ir::LimitDim::Duration => Some(Dim::Time),
        ir::LimitDim::Length => Some(Dim::Length),
        ir::LimitDim::Fraction => None,
    }
}

impl Checker<'_> {
    /// The entries of a skill's `limits` blocks, in source order.
    pub(super) fn skill_limits(&mut self, entries: &[ast::LimitEntry]) -> Vec<ir::Limit> {
        let mut seen = HashMap::new();
        entries
            .iter()
            .filter_map(|entry| self.limit(&entry.name, &entry.value, &entry.doc, entry.span, &mut seen))
            .collect()
    }

    /// A task step's `limits: { force: 30 N }` argument.
    pub(super) fn step_limits(&mut self, expr: &ast::Expr) -> Vec<ir::Limit> {
        let ExprKind::Record(entries) = &expr.kind else {
            let diag = self
                .diag(
                    Code::BadArgument,
                    expr.span,
                    "`limits` must be a block of limits",
                    "not a block",
                )
                .help("write `limits: { force: 30 N, speed: 100 mm/s }`");
            self.report(diag);
            return Vec::new();
        };
        let mut seen = HashMap::new();
        let mut out = Vec::new();
        for entry in entries {
            let Some(name) = &entry.key else {
                let diag = self
                    .diag(Code::BadArgument, entry.span, "a limit needs a name", "which limit?")
                    .help(format!(
                        "write `NAME: VALUE`, e.g. `force: 30 N`; limits: {}",
                        limit_names()
                    ));
                self.report(diag);
                continue;
            };
            out.extend(self.limit(name, &entry.value, &[], entry.span, &mut seen));
        }
        out
    }

    /// One `name: value`: a known name, given once, a positive value of its dimension or `inf`.
    fn limit(
        &mut self,
        name: &ast::Ident,
        value: &ast::Expr,
        doc: &[String],
        span: Span,
        seen: &mut HashMap<String, Span>,
    ) -> Option<ir::Limit> {
        let Some(spec) = ir::limit_spec(&name.name) else {
            let help = suggest(&name.name, ir::LIMITS.iter().map(|spec| spec.name))
                .unwrap_or_else(|| format!("the supervisor's limits are {}", limit_names()));
            let diag = self
                .diag(
                    Code::UnknownLimit,
                    name.span,
                    format!("unknown limit `{}`", name.name),
                    "not a limit of the safety supervisor",
                )
                .help(help);
            self.report(diag);
            return None;
        };
        if let Some(earlier) = seen.get(spec.name) {
            let diag = self
                .diag(
                    Code::DuplicateLimit,
                    name.span,
                    format!("limit `{}` is set twice", spec.name),
                    "set again here",
                )
                .label(*earlier, "first set here")
                .help("keep one of them");
            self.report(diag);
            return None;
        }
        seen.insert(spec.name.to_string(), name.span);
        let what = format!("the `{}` limit", spec.name);
        let value_si = match &value.kind {
            // `inf` switches the check off, whatever the unit.
            ExprKind::Name(word) if word.name == "inf" => None,
            _ => {
                let number = match unit_dim(spec.dim) {
                    Some(dim) => self.quantity(value, dim, &what),
                    None => self.plain_number(value, &what),
                }?;
                if number <= 0.0 {
                    let diag = self
                        .diag(
                            Code::NonPositiveLimit,
                            value.span,
                            format!("{what} must be positive"),
                            "zero or negative",
                        )
                        .help(format!("to switch the check off, write `{}: inf`", spec.name));
                    self.report(diag);
                    return None;
                }
                Some(number)
            }
        };
        Some(ir::Limit {
            name: spec.name.to_string(),
            value_si,
            doc: doc.join("\n"),
            span: self.ir_span(span),
        })
    }
}

/// `` `force`, `moment`, ... `` for help lines.
fn limit_names() -> String {
    let names: Vec<&str> = ir::LIMITS.iter().map(|spec| spec.name).collect();
    join_ticked(&names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units;

    #[test]
    fn every_limit_dimension_has_units_in_the_language() {
        for spec in ir::LIMITS {
            if let Some(dim) = unit_dim(spec.dim) {
                assert!(!units::units_of(dim).is_empty(), "{}", spec.name);
                let si = units::UNITS
                    .iter()
                    .find(|(_, d, factor)| *d == dim && *factor == 1.0)
                    .expect("an SI unit");
                assert_eq!(si.0.replace("Nm", "N m"), spec.dim.si_unit(), "{}", spec.name);
            }
        }
    }
}

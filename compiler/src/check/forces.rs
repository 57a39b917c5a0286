//! `force P = ...` and `threshold T = ...`: desired forces and learned thresholds
//! (docs/method.md §5).

use super::scope::SkillScope;
use super::signatures::{Function, Produces, Signature};
use super::{join_ticked, suggest, Checker, DEFAULT_FORCE_BASIS};
use crate::ast::{self, ExprKind};
use crate::diag::Code;
use crate::units::{self, Dim};
use skill_ir as ir;

impl Checker<'_> {
    pub(super) fn force_source(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::ForceSource> {
        let find = |name: &ast::Ident| Signature::find(Produces::Force, &name.name);
        match &expr.kind {
            ExprKind::Quantity { .. } => {
                let value_n = self.quantity(expr, Dim::Force, "a literal force")?;
                Some(ir::ForceSource::Literal { value_n })
            }
            ExprKind::Number(_) => {
                self.quantity(expr, Dim::Force, "a literal force");
                None
            }
            // `tracked` is written as a bare name, every other force source as a call.
            ExprKind::Name(name) if find(name).is_some_and(|sig| sig.function == Function::Tracked) => {
                Some(ir::ForceSource::Tracked)
            }
            ExprKind::Call { name, args } => {
                let Some(sig) = find(name).filter(|sig| sig.function != Function::Tracked) else {
                    let functions = Signature::names(Produces::Force);
                    let diag = self
                        .diag(
                            Code::UnknownFunction,
                            name.span,
                            format!("unknown force source `{}`", name.name),
                            "not a force source",
                        )
                        .help(suggest(&name.name, functions.iter().copied()).unwrap_or_else(|| {
                            format!("forces come from {}, or a literal like `5 N`", join_ticked(&functions))
                        }));
                    self.report(diag);
                    return None;
                };
                let args = self.bind(sig, expr.span, args);
                match sig.function {
                    Function::Constant => {
                        let segment = self.required_segment(&args, scope);
                        let along = self.along(&args, scope);
                        Some(ir::ForceSource::Constant {
                            segment: segment?,
                            along: along?,
                        })
                    }
                    Function::ForceAt => {
                        let point = self.required_point(&args, scope);
                        let along = self.along(&args, scope);
                        Some(ir::ForceSource::At {
                            point: point?,
                            along: along?,
                        })
                    }
                    Function::Dmp => {
                        let segment = self.required_segment(&args, scope);
                        let basis = self.basis(&args, DEFAULT_FORCE_BASIS);
                        Some(ir::ForceSource::Dmp {
                            segment: segment?,
                            basis: basis?,
                        })
                    }
                    Function::Magnitude => {
                        let segment = self.required_segment(&args, scope);
                        let along = self.along(&args, scope);
                        let basis = self.basis(&args, DEFAULT_FORCE_BASIS);
                        Some(ir::ForceSource::Magnitude {
                            segment: segment?,
                            along: along?,
                            basis: basis?,
                        })
                    }
                    _ => unreachable!("only force functions produce a force"),
                }
            }
            ExprKind::Name(name) => {
                let diag = self
                    .diag(Code::UnknownFunction, name.span, format!("unknown force source `{}`", name.name), "not a force source")
                    .help(
                        suggest(&name.name, Signature::names(Produces::Force))
                            .unwrap_or_else(|| "write a call such as `constant(segment 2, along: surface.z)`, a literal like `5 N`, or `tracked`".to_string()),
                    );
                self.report(diag);
                None
            }
            _ => {
                let diag = self
                    .diag(Code::BadArgument, expr.span, "not a force source", "expected a force source")
                    .help("write `constant(segment 2, along: surface.z)`, `dmp(segment 2)`, a literal like `5 N`, or `tracked`");
                self.report(diag);
                None
            }
        }
    }

    pub(super) fn threshold_source(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::ThresholdSource> {
        if let ExprKind::Call { name, args } = &expr.kind {
            if let Some(sig) = Signature::find(Produces::Threshold, &name.name) {
                let args = self.bind(sig, expr.span, args);
                return match sig.function {
                    Function::ForceAt => {
                        let point = self.required_point(&args, scope);
                        let along = self.along(&args, scope);
                        let scale = match args.get("scale") {
                            Some(scale) => {
                                let value = self.plain_number(scale, "the scale");
                                self.positive(value, scale.span, "the scale")
                            }
                            None => Some(1.0),
                        };
                        Some(ir::ThresholdSource::ForceAt {
                            point: point?,
                            along: along?,
                            scale: scale?,
                        })
                    }
                    _ => unreachable!("only `force_at` produces a threshold"),
                };
            }
        }
        match &expr.kind {
            ExprKind::Quantity { unit, .. } => {
                let dim = match units::lookup(&unit.name) {
                    Some((Dim::Torque, _)) => Dim::Torque,
                    _ => Dim::Force,
                };
                let value = self.quantity(expr, dim, "a threshold")?;
                Some(ir::ThresholdSource::Literal { value })
            }
            ExprKind::Number(_) => {
                self.quantity(expr, Dim::Force, "a threshold");
                None
            }
            ExprKind::Call { name, .. } | ExprKind::Name(name) => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown threshold source `{}`", name.name),
                        "not a threshold source",
                    )
                    .help(
                        suggest(&name.name, Signature::names(Produces::Threshold)).unwrap_or_else(|| {
                            "thresholds are learned by `force_at(POINT, along: FRAME.z)` or written like `3 N`"
                                .to_string()
                        }),
                    );
                self.report(diag);
                None
            }
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        "not a threshold source",
                        "expected a threshold",
                    )
                    .help("write `force_at(end(segment 1), along: contact.z)` or a literal like `3 N`");
                self.report(diag);
                None
            }
        }
    }
}

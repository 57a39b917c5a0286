//! `segments = ...`: the segmentation method of the demonstration, its features and its cut;
//! and references to the segments and points of the demonstration it yields.

use super::scope::SkillScope;
use super::signatures::{Function, Produces, Signature};
use super::values::Args;
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, ExprKind};
use crate::diag::Code;
use crate::source::Span;
use crate::units::Dim;
use skill_ir as ir;

impl Checker<'_> {
    pub(super) fn segmentation(&mut self, decl: &ast::LearnDecl, scope: &mut SkillScope) -> Option<ir::Segmentation> {
        scope.segments_span = Some(decl.span);
        let (name, args, call_span) = match &decl.value.kind {
            ExprKind::Name(name) => (name, &[][..], decl.value.span),
            ExprKind::Call { name, args } => (name, &args[..], decl.value.span),
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        decl.value.span,
                        "`segments` must name a segmentation method",
                        "not a method",
                    )
                    .help("use `none`, `max_force`, `cluster(...)` or `changepoint(...)`");
                self.report(diag);
                return None;
            }
        };
        let expect = decl.expect;
        let Some(sig) = Signature::find(Produces::Segmentation, &name.name) else {
            let methods = Signature::names(Produces::Segmentation);
            let diag = self
                .diag(
                    Code::UnknownFunction,
                    name.span,
                    format!("unknown segmentation method `{}`", name.name),
                    "not a segmentation method",
                )
                .help(
                    suggest(&name.name, methods.iter().copied())
                        .unwrap_or_else(|| format!("use one of {}", join_ticked(&methods))),
                );
            self.report(diag);
            return None;
        };
        let (method, implied) = match sig.function {
            Function::NoSegments | Function::MaxForce if !args.is_empty() => {
                let diag = self.diag(
                    Code::BadArgument,
                    call_span,
                    format!("`{}` takes no arguments", name.name),
                    "remove the arguments",
                );
                self.report(diag);
                return None;
            }
            Function::NoSegments => (ir::Segmentation::None, Some(1)),
            Function::MaxForce => (ir::Segmentation::MaxForce, Some(2)),
            Function::Cluster => {
                let bound = self.bind(sig, call_span, args);
                let linkage = match bound.get("linkage") {
                    None => ir::Linkage::Ward,
                    Some(expr) => self.enum_name(
                        expr,
                        "the linkage",
                        &[
                            ("ward", ir::Linkage::Ward),
                            ("complete", ir::Linkage::Complete),
                            ("average", ir::Linkage::Average),
                            ("single", ir::Linkage::Single),
                        ],
                    )?,
                };
                let temporal = match (bound.get("time_weight"), bound.get("connectivity")) {
                    (Some(_), Some(connectivity)) => {
                        let diag = self
                            .diag(
                                Code::BadArgument,
                                connectivity.span,
                                "`cluster` takes either `time_weight` or `connectivity`, not both",
                                "second temporal constraint",
                            )
                            .help("keep `connectivity` for long demonstrations: it never builds an n×n matrix");
                        self.report(diag);
                        return None;
                    }
                    (Some(weight), None) => {
                        let value = self.plain_number(weight, "the time weight");
                        let weight = self.positive(value, weight.span, "the time weight")?;
                        ir::Temporal::TimeFeature { weight }
                    }
                    (None, Some(k)) => {
                        let value = self.count(k, "the connectivity")?;
                        if value > ir::MAX_CONNECTIVITY {
                            let diag = self
                                .diag(
                                    Code::OutOfRange,
                                    k.span,
                                    format!("the connectivity must be between 1 and {}", ir::MAX_CONNECTIVITY),
                                    "too many neighbours",
                                )
                                .help(
                                    "each sample links to this many neighbours on either side, which sizes the \
                                     clustering's memory and work; 10 (the default) suits most demonstrations",
                                );
                            self.report(diag);
                        }
                        // Reported; checking goes on with the largest allowed (no cascade).
                        ir::Temporal::Connectivity {
                            k: value.min(ir::MAX_CONNECTIVITY),
                        }
                    }
                    (None, None) => ir::Temporal::Connectivity { k: 10 },
                };
                let min_length_s = match bound.get("min_length") {
                    Some(expr) => {
                        let value = self.quantity(expr, Dim::Time, "the minimum segment length");
                        self.positive(value, expr.span, "the minimum segment length")?
                    }
                    None => 0.1,
                };
                let (cut, implied) = match bound.get("cut") {
                    Some(expr) => self.cut(expr)?,
                    None => match expect {
                        Some((n, span)) => (ir::Cut::Count(self.expect_count(n, span)?), None),
                        None => {
                            let diag = self
                                .diag(
                                    Code::BadArgument,
                                    call_span,
                                    "`cluster` needs a cut: a segment count or a distance",
                                    "where to cut?",
                                )
                                .help("write `cut: count(3)` or `cut: distance(2.5)`, or add `expect 3`");
                            self.report(diag);
                            return None;
                        }
                    },
                };
                let features = self.features(bound.get("features"))?;
                (
                    ir::Segmentation::Cluster {
                        linkage,
                        temporal,
                        cut,
                        min_length_s,
                        features,
                    },
                    implied,
                )
            }
            Function::Changepoint => {
                let bound = self.bind(sig, call_span, args);
                let min_length_s = match bound.get("min_length") {
                    Some(expr) => {
                        let value = self.quantity(expr, Dim::Time, "the minimum segment length");
                        self.positive(value, expr.span, "the minimum segment length")?
                    }
                    None => 0.1,
                };
                let models = match bound.get("models") {
                    None => vec![ir::SegmentModel::Constant, ir::SegmentModel::Linear],
                    Some(expr) => match &expr.kind {
                        ExprKind::List(items) if !items.is_empty() => {
                            let mut models = Vec::new();
                            for item in items {
                                let model = self.enum_name(
                                    item,
                                    "a segment model",
                                    &[
                                        ("constant", ir::SegmentModel::Constant),
                                        ("linear", ir::SegmentModel::Linear),
                                    ],
                                )?;
                                models.push(model);
                            }
                            models
                        }
                        _ => {
                            let diag = self
                                .diag(
                                    Code::BadArgument,
                                    expr.span,
                                    "`models` must be a list of segment models",
                                    "not a list",
                                )
                                .help("write `models: [constant, linear]`");
                            self.report(diag);
                            return None;
                        }
                    },
                };
                let max_particles = match bound.get("particles") {
                    Some(expr) => self.count(expr, "the particle bound")?,
                    None => 100,
                };
                let features = self.features(bound.get("features"))?;
                (
                    ir::Segmentation::Changepoint {
                        min_length_s,
                        models,
                        max_particles,
                        features,
                    },
                    None,
                )
            }
            _ => unreachable!("only segmentation methods produce a segmentation"),
        };
        scope.segment_count = match (implied, expect) {
            (Some(implied), Some((n, span))) if u64::from(implied) != n => {
                let diag = self
                    .diag(
                        Code::ExpectMismatch,
                        span,
                        format!("`{}` yields {implied} segments, not {n}", name.name),
                        format!("expects {n}"),
                    )
                    .help(format!("write `expect {implied}` or drop it"));
                self.report(diag);
                Some(implied)
            }
            (Some(implied), _) => Some(implied),
            (None, Some((n, span))) => self.expect_count(n, span),
            (None, None) => None,
        };
        Some(method)
    }

    /// `features: [position, force, force_magnitude]` (default position and force).
    fn features(&mut self, expr: Option<&ast::Expr>) -> Option<ir::SegmentFeatures> {
        let Some(expr) = expr else {
            return Some(ir::SegmentFeatures::default());
        };
        let ExprKind::List(items) = &expr.kind else {
            let diag = self
                .diag(Code::BadArgument, expr.span, "`features` must be a list", "not a list")
                .help("write `features: [position, force_magnitude]`");
            self.report(diag);
            return None;
        };
        let mut features = ir::SegmentFeatures {
            position: false,
            force: false,
            force_magnitude: false,
        };
        for item in items {
            match self.enum_name(
                item,
                "segmentation feature",
                &[("position", 0), ("force", 1), ("force_magnitude", 2)],
            )? {
                0 => features.position = true,
                1 => features.force = true,
                _ => features.force_magnitude = true,
            }
        }
        if !(features.position || features.force || features.force_magnitude) {
            let diag = self.diag(
                Code::BadArgument,
                expr.span,
                "`features` is empty",
                "nothing to segment on",
            );
            self.report(diag);
            return None;
        }
        Some(features)
    }

    fn expect_count(&mut self, n: u64, span: Span) -> Option<u32> {
        match u32::try_from(n) {
            Ok(n) if n > 0 => Some(n),
            _ => {
                let diag = self.diag(
                    Code::OutOfRange,
                    span,
                    "the expected segment count must be at least 1",
                    "out of range",
                );
                self.report(diag);
                None
            }
        }
    }

    fn cut(&mut self, expr: &ast::Expr) -> Option<(ir::Cut, Option<u32>)> {
        if let ExprKind::Call { name, args } = &expr.kind {
            if let Some(sig) = Signature::find(Produces::Cut, &name.name) {
                let args = self.bind(sig, expr.span, args);
                return match sig.function {
                    Function::Count => {
                        let n = self.required(&args, "n")?;
                        let n = self.count(n, "the segment count")?;
                        Some((ir::Cut::Count(n), Some(n)))
                    }
                    Function::Distance => {
                        let d = self.required(&args, "d")?;
                        let value = self.plain_number(d, "the cut distance");
                        let d = self.positive(value, d.span, "the cut distance")?;
                        Some((ir::Cut::Distance(d), None))
                    }
                    _ => unreachable!("only `count` and `distance` produce a cut"),
                };
            }
        }
        let diag = self
            .diag(
                Code::BadArgument,
                expr.span,
                "`cut` must be `count(N)` or `distance(D)`",
                "not a cut",
            )
            .help("write `cut: count(3)`");
        self.report(diag);
        None
    }

    pub(super) fn segment(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::SegmentIdx> {
        let ExprKind::Segment(n) = expr.kind else {
            let diag = self
                .diag(Code::BadArgument, expr.span, "expected a segment", "not a segment")
                .help("write `segment 1` (segments count from 1)");
            self.report(diag);
            return None;
        };
        if n == 0 {
            let diag = self
                .diag(
                    Code::OutOfRange,
                    expr.span,
                    "segments count from 1",
                    "there is no segment 0",
                )
                .help("write `segment 1` for the first segment");
            self.report(diag);
            return None;
        }
        match scope.segment_count {
            Some(count) if n > u64::from(count) => {
                let mut diag = self
                    .diag(
                        Code::SegmentOutOfRange,
                        expr.span,
                        format!("segment {n} does not exist: the segmentation yields {count}"),
                        format!("beyond segment {count}"),
                    )
                    .help(format!("refer to segments 1 to {count}, or change the segmentation"));
                if let Some(span) = scope.segments_span {
                    diag = diag.label(span, format!("{count} segments declared here"));
                }
                self.report(diag);
                None
            }
            Some(_) => Some(ir::SegmentIdx((n - 1) as u32)),
            None => {
                if !scope.reported_unknown_count {
                    scope.reported_unknown_count = true;
                    let mut diag = self
                        .diag(
                            Code::SegmentCountUnknown,
                            expr.span,
                            "segments are referenced but their number is unknown",
                            "which segments exist?",
                        )
                        .help("add `expect N` to the `segments` declaration");
                    if let Some(span) = scope.segments_span {
                        diag = diag.label(span, "this segmentation does not fix a count");
                    }
                    self.report(diag);
                }
                None
            }
        }
    }

    /// The required `segment` argument of a call, resolved.
    pub(super) fn required_segment(&mut self, args: &Args<'_>, scope: &mut SkillScope) -> Option<ir::SegmentIdx> {
        let expr = self.required(args, "segment")?;
        self.segment(expr, scope)
    }

    /// The required `point` argument of a call, resolved.
    pub(super) fn required_point(&mut self, args: &Args<'_>, scope: &mut SkillScope) -> Option<ir::Point> {
        let expr = self.required(args, "point")?;
        self.point(expr, scope)
    }

    /// A point of the demonstration: `peak_force` (over the whole demonstration),
    /// `peak_force(segment N)`, `end(segment N)` or `start(segment N)`.
    pub(super) fn point(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::Point> {
        let sig = match &expr.kind {
            ExprKind::Name(name) | ExprKind::Call { name, .. } => Signature::find(Produces::Point, &name.name),
            _ => None,
        };
        match (&expr.kind, sig) {
            (ExprKind::Name(_), Some(sig)) if sig.function == Function::PeakForce => return Some(ir::Point::PeakForce),
            (ExprKind::Call { args, .. }, Some(sig)) if sig.function == Function::PeakForce => {
                let args = self.bind(sig, expr.span, args);
                return Some(ir::Point::PeakForceIn(self.required_segment(&args, scope)?));
            }
            (ExprKind::Call { args, .. }, Some(sig)) if matches!(sig.function, Function::End | Function::Start) => {
                let args = self.bind(sig, expr.span, args);
                let segment = self.required_segment(&args, scope)?;
                return Some(if sig.function == Function::End {
                    ir::Point::End(segment)
                } else {
                    ir::Point::Start(segment)
                });
            }
            _ => {}
        }
        let help = match &expr.kind {
            ExprKind::Name(name) | ExprKind::Call { name, .. } => {
                suggest(&name.name, Signature::names(Produces::Point))
            }
            _ => None,
        };
        let diag = self
            .diag(
                Code::BadArgument,
                expr.span,
                "expected a point of the demonstration",
                "not a point",
            )
            .help(help.unwrap_or_else(|| {
                "write `end(segment 1)`, `start(segment 2)`, `peak_force` or `peak_force(segment 2)`".to_string()
            }));
        self.report(diag);
        None
    }
}

//! Checking: resolves names, units, segments and axes of a parsed skill, analyses its state
//! machine, and builds the IR as it goes. Every problem is reported; nothing stops at the first.
//!
//! Resolution and lowering are one walk here: each resolved value already is its IR form,
//! and the IR is only kept when the walk reported no error.

use crate::ast::{self, AxisSet, ExprKind, GuardKind, LearnKind, StmtKind};
use crate::diag::{did_you_mean, Code, Diag, Severity};
use crate::source::{SourceFile, Span};
use crate::units::{self, Dim};
use skill_ir as ir;
use std::collections::{HashMap, VecDeque};

/// Default stiffness per axis in the compliant frame: N/m for x y z, Nm/rad for rx ry rz.
/// Values of the order used for Cartesian impedance control on the LWR-IV.
pub const DEFAULT_STIFFNESS: [f64; 6] = [1500.0, 1500.0, 1500.0, 150.0, 150.0, 150.0];

/// Default PI force gains when a state writes no `gains`.
pub const DEFAULT_GAINS: ir::ForceGains = ir::ForceGains {
    kp: 0.5,
    ki: 5.0,
    integral_limit_n: Some(10.0),
};

/// Default number of DMP basis functions of a motion.
pub const DEFAULT_MOTION_BASIS: u32 = 50;

/// Default number of DMP basis functions of a force profile.
pub const DEFAULT_FORCE_BASIS: u32 = 30;

/// Names of the frames every skill has.
const BUILTIN_FRAMES: [&str; 2] = ["base", "tool"];

/// Guards written as a bare name.
const NAMED_GUARDS: [&str; 1] = ["motion_done"];

/// Learning functions by kind of declaration, for did-you-mean.
const FRAME_FUNCTIONS: &[&str] = &[
    "fixed_point",
    "point_on_plane",
    "planar",
    "cylinder",
    "prismatic",
    "axial_rotation",
    "constraint",
    "force_aligned",
    "fixed",
];
const SEGMENT_METHODS: &[&str] = &["none", "max_force", "cluster", "changepoint"];
const FORCE_FUNCTIONS: &[&str] = &["constant", "force_at", "dmp", "magnitude", "tracked"];

/// Common aliases people type for a canonical name.
fn alias_of(name: &str) -> Option<&'static str> {
    Some(match name {
        "plane" => "planar",
        "concentric_cylinder" => "cylinder",
        "hinge" => "axial_rotation",
        "point" => "fixed_point",
        "peak" | "max_force_point" => "peak_force",
        _ => return None,
    })
}

fn suggest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str> + Clone) -> Option<String> {
    if let Some(alias) = alias_of(name) {
        if candidates.clone().into_iter().any(|c| c == alias) {
            return Some(format!("did you mean `{alias}`?"));
        }
    }
    did_you_mean(name, candidates).map(|found| format!("did you mean `{found}`?"))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SymKind {
    Frame,
    Motion,
    Force,
    Threshold,
}

impl SymKind {
    fn describe(self) -> &'static str {
        match self {
            SymKind::Frame => "a frame",
            SymKind::Motion => "a motion",
            SymKind::Force => "a force",
            SymKind::Threshold => "a threshold",
        }
    }
}

#[derive(Debug, Clone)]
struct Sym {
    kind: SymKind,
    id: u32,
    span: Span,
    used: bool,
}

/// The checker of one file.
pub(crate) struct Checker<'a> {
    file: usize,
    src: &'a SourceFile,
    diags: &'a mut Vec<Diag>,
}

/// What a skill needs from the checker of its learn block.
struct SkillScope {
    symbols: HashMap<String, Sym>,
    segment_count: Option<u32>,
    segments_span: Option<Span>,
    reported_unknown_count: bool,
    force_sources: Vec<ir::ForceSource>,
}

impl<'a> Checker<'a> {
    pub(crate) fn new(file: usize, src: &'a SourceFile, diags: &'a mut Vec<Diag>) -> Self {
        Checker { file, src, diags }
    }

    fn report(&mut self, diag: Diag) {
        self.diags.push(diag);
    }

    fn diag(&self, code: Code, span: Span, message: impl Into<String>, label: impl Into<String>) -> Diag {
        Diag::new(code, self.file, span, message, label)
    }

    pub(crate) fn ir_span(&self, span: Span) -> ir::SourceSpan {
        let (line, column) = self.src.line_col(span.start);
        ir::SourceSpan {
            file: self.src.name.clone(),
            line: line as u32,
            column: column as u32,
            start: span.start as u32,
            end: span.end as u32,
        }
    }

    // ------------------------------------------------------------ values

    /// A quantity of dimension `dim`, in SI units.
    fn quantity(&mut self, expr: &ast::Expr, dim: Dim, what: &str) -> Option<f64> {
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
                let value = number.value * factor;
                if !value.is_finite() {
                    let diag = self.diag(
                        Code::OutOfRange,
                        expr.span,
                        format!("{what} is not finite"),
                        "too large",
                    );
                    self.report(diag);
                    return None;
                }
                Some(value)
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

    /// A plain number (gains, scales, weights).
    fn plain_number(&mut self, expr: &ast::Expr, what: &str) -> Option<f64> {
        match &expr.kind {
            ExprKind::Number(number) if number.value.is_finite() => Some(number.value),
            ExprKind::Number(_) => {
                let diag = self.diag(
                    Code::OutOfRange,
                    expr.span,
                    format!("{what} is not finite"),
                    "too large",
                );
                self.report(diag);
                None
            }
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

    /// A positive integer that fits in `u32`.
    fn count(&mut self, expr: &ast::Expr, what: &str) -> Option<u32> {
        match &expr.kind {
            ExprKind::Number(number) if !number.text.contains(['.', 'e', 'E', '-']) => {
                match number.text.parse::<u32>() {
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
                let diag = self.diag(
                    Code::BadArgument,
                    expr.span,
                    format!("{what} must be a whole number"),
                    "not a count",
                );
                self.report(diag);
                None
            }
        }
    }

    fn positive(&mut self, value: Option<f64>, span: Span, what: &str) -> Option<f64> {
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

    fn string(&mut self, expr: &ast::Expr, what: &str) -> Option<String> {
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
    fn bind_args<'e>(
        &mut self,
        function: &str,
        args: &'e [ast::Arg],
        params: &[&'static str],
        positional: usize,
    ) -> HashMap<&'static str, &'e ast::Expr> {
        let mut bound: HashMap<&'static str, &'e ast::Expr> = HashMap::new();
        let mut next_positional = 0;
        for arg in args {
            let param = match &arg.key {
                Some(key) => match params.iter().find(|p| **p == key.name) {
                    Some(param) => *param,
                    None => {
                        let help = suggest(&key.name, params.iter().copied()).unwrap_or_else(|| {
                            if params.is_empty() {
                                format!("`{function}` takes no arguments")
                            } else {
                                format!("`{function}` takes {}", join_ticked(params))
                            }
                        });
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
                            format!("`{function}` takes no arguments")
                        } else {
                            format!("name it: `{function}` takes {}", join_ticked(params))
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

    fn missing_arg(&mut self, function: &str, param: &str, span: Span, example: &str) {
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

    // ------------------------------------------------------------ skills

    /// Checks one skill and returns its IR when it has no error.
    pub(crate) fn skill(&mut self, skill: &ast::Skill) -> Option<ir::Skill> {
        let errors_before = self.error_count();
        let mut scope = SkillScope {
            symbols: HashMap::new(),
            segment_count: None,
            segments_span: None,
            reported_unknown_count: false,
            force_sources: Vec::new(),
        };
        let learn = self.learn(&skill.learn, &mut scope);
        let (states, transitions, initial) = self.states(skill, &mut scope);
        if self.error_count() == errors_before {
            // After an error, a name may look unused only because its use did not resolve.
            self.unused(&scope);
        }
        let (learn, initial) = (learn?, initial?);
        if self.error_count() > errors_before {
            return None;
        }
        Some(ir::Skill {
            name: skill.name.name.clone(),
            doc: skill.doc.join("\n"),
            learn,
            initial,
            states,
            transitions,
            span: self.ir_span(skill.name.span),
        })
    }

    fn error_count(&self) -> usize {
        self.diags
            .iter()
            .filter(|d| d.file == self.file && d.severity() == Severity::Error)
            .count()
    }

    fn learn(&mut self, decls: &[ast::LearnDecl], scope: &mut SkillScope) -> Option<ir::LearnPlan> {
        // Pass 1: names, ids and the segment count, so later declarations can refer to earlier
        // and later ones alike.
        let mut counters = [0u32; 4];
        let mut segments_decl: Option<&ast::LearnDecl> = None;
        let mut lowpass_decl: Option<&ast::LearnDecl> = None;
        let mut resample_decl: Option<&ast::LearnDecl> = None;
        for decl in decls {
            let kind = match decl.kind {
                LearnKind::Frame => SymKind::Frame,
                LearnKind::Motion => SymKind::Motion,
                LearnKind::Force => SymKind::Force,
                LearnKind::Threshold => SymKind::Threshold,
                LearnKind::Segments | LearnKind::Lowpass | LearnKind::Resample => {
                    let slot = match decl.kind {
                        LearnKind::Segments => &mut segments_decl,
                        LearnKind::Lowpass => &mut lowpass_decl,
                        _ => &mut resample_decl,
                    };
                    if let Some(earlier) = slot {
                        let diag = self
                            .diag(
                                Code::DuplicateStatement,
                                decl.span,
                                format!("`{}` is declared twice", decl.kind.keyword()),
                                "second declaration",
                            )
                            .label(earlier.span, "first declared here")
                            .help("keep one of them");
                        self.report(diag);
                    } else {
                        *slot = Some(decl);
                    }
                    continue;
                }
            };
            let name = decl
                .name
                .as_ref()
                .expect("grammar: named learn declarations have a name");
            if BUILTIN_FRAMES.contains(&name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        name.span,
                        format!("`{}` is a built-in frame", name.name),
                        "redeclares a built-in",
                    )
                    .help("choose another name");
                self.report(diag);
                continue;
            }
            if let Some(earlier) = scope.symbols.get(&name.name) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        name.span,
                        format!("`{}` is declared twice", name.name),
                        "second declaration",
                    )
                    .label(earlier.span, "first declared here")
                    .help("rename one of them");
                self.report(diag);
                continue;
            }
            let slot = &mut counters[kind as usize];
            scope.symbols.insert(
                name.name.clone(),
                Sym {
                    kind,
                    id: *slot,
                    span: name.span,
                    used: false,
                },
            );
            *slot += 1;
        }

        let segmentation = match segments_decl {
            Some(decl) => self.segmentation(decl, scope),
            None => {
                scope.segment_count = Some(1);
                Some(ir::Segmentation::None)
            }
        };
        let lowpass_hz = lowpass_decl.and_then(|decl| {
            let value = self.quantity(&decl.value, Dim::Frequency, "the low-pass cut-off");
            self.positive(value, decl.value.span, "the low-pass cut-off")
        });
        let resample_hz = resample_decl.and_then(|decl| {
            let value = self.quantity(&decl.value, Dim::Frequency, "the resampling rate");
            self.positive(value, decl.value.span, "the resampling rate")
        });

        // Pass 2: resolve every declaration. Forces come before thresholds so that thresholds
        // may refer to learned constant forces.
        let mut frames = Vec::new();
        let mut motions = Vec::new();
        let mut forces = Vec::new();
        let mut thresholds = Vec::new();
        let mut ok = segmentation.is_some();
        for decl in decls {
            let Some(name) = &decl.name else { continue };
            // Skip declarations that were rejected as duplicates in pass 1.
            match scope.symbols.get(&name.name) {
                Some(sym) if sym.span == name.span => {}
                _ => {
                    ok = false;
                    continue;
                }
            }
            let span = self.ir_span(name.span);
            match decl.kind {
                LearnKind::Frame => match self.frame_source(&decl.value, scope) {
                    Some(source) => frames.push(ir::FrameDecl {
                        name: name.name.clone(),
                        source,
                        span,
                    }),
                    None => ok = false,
                },
                LearnKind::Motion => match self.motion(&decl.value, scope) {
                    Some((segment, basis)) => motions.push(ir::MotionDecl {
                        name: name.name.clone(),
                        segment,
                        basis,
                        span,
                    }),
                    None => ok = false,
                },
                LearnKind::Force => match self.force_source(&decl.value, scope) {
                    Some(source) => {
                        scope.force_sources.push(source.clone());
                        forces.push(ir::ForceDecl {
                            name: name.name.clone(),
                            source,
                            span,
                        })
                    }
                    None => {
                        scope.force_sources.push(ir::ForceSource::Tracked);
                        ok = false
                    }
                },
                LearnKind::Threshold => match self.threshold_source(&decl.value, scope) {
                    Some(source) => thresholds.push(ir::ThresholdDecl {
                        name: name.name.clone(),
                        source,
                        span,
                    }),
                    None => ok = false,
                },
                _ => {}
            }
        }
        if !ok {
            return None;
        }
        Some(ir::LearnPlan {
            segmentation: segmentation?,
            segments: scope.segment_count.unwrap_or(1),
            lowpass_hz,
            resample_hz,
            frames,
            motions,
            forces,
            thresholds,
        })
    }

    fn segmentation(&mut self, decl: &ast::LearnDecl, scope: &mut SkillScope) -> Option<ir::Segmentation> {
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
        let (method, implied) = match name.name.as_str() {
            "none" if args.is_empty() => (ir::Segmentation::None, Some(1)),
            "max_force" if args.is_empty() => (ir::Segmentation::MaxForce, Some(2)),
            "none" | "max_force" => {
                let diag = self.diag(
                    Code::BadArgument,
                    call_span,
                    format!("`{}` takes no arguments", name.name),
                    "remove the arguments",
                );
                self.report(diag);
                return None;
            }
            "cluster" => {
                let bound = self.bind_args(
                    "cluster",
                    args,
                    &[
                        "linkage",
                        "time_weight",
                        "connectivity",
                        "cut",
                        "min_length",
                        "features",
                    ],
                    0,
                );
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
                    (None, Some(k)) => ir::Temporal::Connectivity {
                        k: self.count(k, "the connectivity")?,
                    },
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
                let features = self.features(bound.get("features").copied())?;
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
            "changepoint" => {
                let bound = self.bind_args(
                    "changepoint",
                    args,
                    &["min_length", "models", "particles", "features"],
                    0,
                );
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
                let features = self.features(bound.get("features").copied())?;
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
            other => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown segmentation method `{other}`"),
                        "not a segmentation method",
                    )
                    .help(
                        suggest(other, SEGMENT_METHODS.iter().copied())
                            .unwrap_or_else(|| format!("use one of {}", join_ticked(SEGMENT_METHODS))),
                    );
                self.report(diag);
                return None;
            }
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
            match name.name.as_str() {
                "count" => {
                    let bound = self.bind_args("count", args, &["n"], 1);
                    let Some(n) = bound.get("n") else {
                        self.missing_arg("count", "n", expr.span, "count(3)");
                        return None;
                    };
                    let n = self.count(n, "the segment count")?;
                    return Some((ir::Cut::Count(n), Some(n)));
                }
                "distance" => {
                    let bound = self.bind_args("distance", args, &["d"], 1);
                    let Some(d) = bound.get("d") else {
                        self.missing_arg("distance", "d", expr.span, "distance(2.5)");
                        return None;
                    };
                    let value = self.plain_number(d, "the cut distance");
                    let d = self.positive(value, d.span, "the cut distance")?;
                    return Some((ir::Cut::Distance(d), None));
                }
                _ => {}
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

    fn enum_name<T: Copy>(&mut self, expr: &ast::Expr, what: &str, options: &[(&'static str, T)]) -> Option<T> {
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

    fn segment(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::SegmentIdx> {
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

    /// A required segment argument: resolved, or reported missing with an example.
    fn required_segment(
        &mut self,
        expr: Option<&&ast::Expr>,
        function: &str,
        span: Span,
        example: &str,
        scope: &mut SkillScope,
    ) -> Option<ir::SegmentIdx> {
        match expr {
            Some(expr) => self.segment(expr, scope),
            None => {
                self.missing_arg(function, "segment", span, example);
                None
            }
        }
    }

    /// A required point argument: resolved, or reported missing with an example.
    fn required_point(
        &mut self,
        expr: Option<&&ast::Expr>,
        function: &str,
        span: Span,
        example: &str,
        scope: &mut SkillScope,
    ) -> Option<ir::Point> {
        match expr {
            Some(expr) => self.point(expr, scope),
            None => {
                self.missing_arg(function, "point", span, example);
                None
            }
        }
    }

    fn point(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::Point> {
        match &expr.kind {
            ExprKind::Name(name) if name.name == "peak_force" => return Some(ir::Point::PeakForce),
            ExprKind::Call { name, args } if name.name == "end" || name.name == "start" => {
                let bound = self.bind_args(&name.name, args, &["segment"], 1);
                let Some(segment) = bound.get("segment") else {
                    self.missing_arg(&name.name, "segment", expr.span, &format!("{}(segment 1)", name.name));
                    return None;
                };
                let segment = self.segment(segment, scope)?;
                return Some(if name.name == "end" {
                    ir::Point::End(segment)
                } else {
                    ir::Point::Start(segment)
                });
            }
            _ => {}
        }
        let help = match &expr.kind {
            ExprKind::Name(name) | ExprKind::Call { name, .. } => suggest(&name.name, ["peak_force", "end", "start"]),
            _ => None,
        };
        let diag = self
            .diag(
                Code::BadArgument,
                expr.span,
                "expected a point of the demonstration",
                "not a point",
            )
            .help(help.unwrap_or_else(|| "write `end(segment 1)`, `start(segment 2)` or `peak_force`".to_string()));
        self.report(diag);
        None
    }

    /// Looks a name up in the skill's scope, reporting unknown names and wrong kinds.
    fn resolve(&mut self, name: &ast::Ident, want: SymKind, scope: &mut SkillScope) -> Option<u32> {
        if let Some(sym) = scope.symbols.get_mut(&name.name) {
            sym.used = true;
            if sym.kind == want {
                return Some(sym.id);
            }
            let (kind, span) = (sym.kind, sym.span);
            let mut diag = self
                .diag(
                    Code::WrongKind,
                    name.span,
                    format!("`{}` is {}, not {}", name.name, kind.describe(), want.describe()),
                    format!("expected {}", want.describe()),
                )
                .label(span, format!("declared as {} here", kind.describe()));
            let same_kind: Vec<&str> = scope
                .symbols
                .iter()
                .filter(|(_, s)| s.kind == want)
                .map(|(n, _)| n.as_str())
                .collect();
            if want == SymKind::Motion && same_kind.is_empty() {
                diag = diag.help("no motion is learned: declare one in `learn`, e.g. `motion path = dmp(segment 1)`");
            } else if !same_kind.is_empty() {
                let mut sorted = same_kind;
                sorted.sort_unstable();
                diag = diag.help(format!("{}s declared here: {}", kind_noun(want), join_ticked(&sorted)));
            }
            self.report(diag);
            return None;
        }
        let mut candidates: Vec<&str> = scope
            .symbols
            .iter()
            .filter(|(_, s)| s.kind == want)
            .map(|(n, _)| n.as_str())
            .collect();
        if want == SymKind::Frame {
            candidates.extend(BUILTIN_FRAMES);
        }
        candidates.sort_unstable();
        let help = suggest(&name.name, candidates.iter().copied()).or_else(|| {
            if candidates.is_empty() {
                Some(format!(
                    "declare it in `learn`: `{} {} = ...`",
                    kind_noun(want),
                    name.name
                ))
            } else {
                Some(format!(
                    "{}s declared here: {}",
                    kind_noun(want),
                    join_ticked(&candidates)
                ))
            }
        });
        let diag = self
            .diag(
                Code::UnknownName,
                name.span,
                format!("unknown {} `{}`", kind_noun(want), name.name),
                format!("no {} of this name", kind_noun(want)),
            )
            .maybe_help(help);
        self.report(diag);
        None
    }

    fn frame_ref(&mut self, name: &ast::Ident, scope: &mut SkillScope) -> Option<ir::FrameRef> {
        match name.name.as_str() {
            "base" => Some(ir::FrameRef::Base),
            "tool" => Some(ir::FrameRef::Tool),
            _ => self
                .resolve(name, SymKind::Frame, scope)
                .map(|id| ir::FrameRef::Learned(ir::FrameId(id))),
        }
    }

    fn axis(&mut self, name: &ast::Ident) -> Option<ir::Axis> {
        if let Some(axis) = ir::Axis::from_name(&name.name) {
            return Some(axis);
        }
        let names: Vec<&str> = ir::Axis::ALL.iter().map(|a| a.name()).collect();
        let diag = self
            .diag(
                Code::UnknownAxis,
                name.span,
                format!("unknown axis `{}`", name.name),
                "not an axis",
            )
            .help(match name.name.as_str() {
                "position" | "force" => {
                    "separate control groups with a comma: `control force z, position x y rx ry rz`".to_string()
                }
                _ => {
                    suggest(&name.name, names.iter().copied()).unwrap_or_else(|| "axes are x y z rx ry rz".to_string())
                }
            });
        self.report(diag);
        None
    }

    /// `frame.axis`; `translation` demands x, y or z.
    fn frame_axis(
        &mut self,
        axis_ref: &ast::AxisRef,
        translation: bool,
        scope: &mut SkillScope,
    ) -> Option<ir::FrameAxis> {
        let frame = self.frame_ref(&axis_ref.frame, scope);
        let axis = self.axis(&axis_ref.axis)?;
        if translation && axis.is_rotation() {
            let diag = self
                .diag(
                    Code::UnknownAxis,
                    axis_ref.axis.span,
                    format!("`{}` is a rotation; a direction needs x, y or z", axis.name()),
                    "not a direction",
                )
                .help(format!("write `{}.z`", axis_ref.frame.name));
            self.report(diag);
            return None;
        }
        Some(ir::FrameAxis { frame: frame?, axis })
    }

    fn along(
        &mut self,
        expr: Option<&&ast::Expr>,
        function: &str,
        span: Span,
        scope: &mut SkillScope,
    ) -> Option<ir::FrameAxis> {
        match expr {
            Some(expr) => match &expr.kind {
                ExprKind::Axis(axis_ref) => self.frame_axis(axis_ref, true, scope),
                _ => {
                    let diag = self
                        .diag(
                            Code::BadArgument,
                            expr.span,
                            "`along` must be a frame axis",
                            "not a frame axis",
                        )
                        .help("write `along: contact.z`");
                    self.report(diag);
                    None
                }
            },
            None => {
                self.missing_arg(function, "along", span, &format!("{function}(..., along: contact.z)"));
                None
            }
        }
    }

    fn basis(&mut self, expr: Option<&&ast::Expr>, default: u32) -> Option<u32> {
        match expr {
            Some(expr) => {
                let n = self.count(expr, "the number of basis functions")?;
                if n > 10_000 {
                    let diag = self
                        .diag(
                            Code::OutOfRange,
                            expr.span,
                            "more than 10000 basis functions",
                            "too many",
                        )
                        .help("20 to 100 basis functions reproduce a demonstration closely");
                    self.report(diag);
                    return None;
                }
                Some(n)
            }
            None => Some(default),
        }
    }

    fn frame_source(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::FrameSource> {
        let (name, args) = match &expr.kind {
            ExprKind::Call { name, args } => (name, args),
            ExprKind::Name(name) => {
                let help = suggest(&name.name, FRAME_FUNCTIONS.iter().copied())
                    .map(|s| format!("{s} frames are learned by a call, like `planar(segment 2)`"))
                    .unwrap_or_else(|| {
                        "write a call such as `planar(segment 2)` or `force_aligned(at: peak_force)`".to_string()
                    });
                let code = if FRAME_FUNCTIONS.contains(&name.name.as_str()) {
                    Code::BadArgument
                } else {
                    Code::UnknownFunction
                };
                let diag = self
                    .diag(
                        code,
                        expr.span,
                        format!("`{}` is not a way to learn a frame", name.name),
                        "expected a call",
                    )
                    .help(help);
                self.report(diag);
                return None;
            }
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        "a frame is learned by a call",
                        "not a frame source",
                    )
                    .help("write `planar(segment 2)` or `force_aligned(at: peak_force)`");
                self.report(diag);
                return None;
            }
        };
        let model = match name.name.as_str() {
            "fixed_point" => Some(ir::ConstraintModel::FixedPoint),
            "point_on_plane" => Some(ir::ConstraintModel::PointOnPlane),
            "planar" => Some(ir::ConstraintModel::Planar),
            "cylinder" => Some(ir::ConstraintModel::ConcentricCylinder),
            "prismatic" => Some(ir::ConstraintModel::Prismatic),
            "axial_rotation" => Some(ir::ConstraintModel::AxialRotation),
            _ => None,
        };
        if let Some(model) = model {
            let bound = self.bind_args(&name.name, args, &["segment"], 1);
            let Some(segment) = bound.get("segment") else {
                self.missing_arg(&name.name, "segment", expr.span, &format!("{}(segment 2)", name.name));
                return None;
            };
            let segment = self.segment(segment, scope)?;
            return Some(ir::FrameSource::Constraint {
                segment,
                candidates: vec![model],
            });
        }
        match name.name.as_str() {
            "constraint" => {
                let bound = self.bind_args("constraint", args, &["segment", "models"], 1);
                let segment = self.required_segment(
                    bound.get("segment"),
                    "constraint",
                    expr.span,
                    "constraint(segment 2)",
                    scope,
                );
                let candidates = match bound.get("models") {
                    None => vec![
                        ir::ConstraintModel::FixedPoint,
                        ir::ConstraintModel::PointOnPlane,
                        ir::ConstraintModel::Planar,
                        ir::ConstraintModel::ConcentricCylinder,
                        ir::ConstraintModel::Prismatic,
                        ir::ConstraintModel::AxialRotation,
                    ],
                    Some(list) => {
                        let ExprKind::List(items) = &list.kind else {
                            let diag = self
                                .diag(Code::BadArgument, list.span, "`models` must be a list", "not a list")
                                .help("write `models: [planar, cylinder]`");
                            self.report(diag);
                            return None;
                        };
                        let options = [
                            ("fixed_point", ir::ConstraintModel::FixedPoint),
                            ("point_on_plane", ir::ConstraintModel::PointOnPlane),
                            ("planar", ir::ConstraintModel::Planar),
                            ("cylinder", ir::ConstraintModel::ConcentricCylinder),
                            ("prismatic", ir::ConstraintModel::Prismatic),
                            ("axial_rotation", ir::ConstraintModel::AxialRotation),
                        ];
                        let mut models = Vec::new();
                        for item in items {
                            models.push(self.enum_name(item, "constraint model", &options)?);
                        }
                        if models.is_empty() {
                            let diag = self.diag(Code::BadArgument, list.span, "`models` is empty", "no model to fit");
                            self.report(diag);
                            return None;
                        }
                        models
                    }
                };
                Some(ir::FrameSource::Constraint {
                    segment: segment?,
                    candidates,
                })
            }
            "force_aligned" => {
                let bound = self.bind_args("force_aligned", args, &["segment", "at"], 1);
                match (bound.get("segment"), bound.get("at")) {
                    (Some(segment), None) => Some(ir::FrameSource::ForceAlignedSamples {
                        segment: self.segment(segment, scope)?,
                    }),
                    (None, Some(at)) => Some(ir::FrameSource::ForceAlignedAt {
                        point: self.point(at, scope)?,
                    }),
                    (Some(_), Some(at)) => {
                        let diag = self
                            .diag(
                                Code::BadArgument,
                                at.span,
                                "`force_aligned` takes a segment (a frame per sample) or `at` (one frame), not both",
                                "second source",
                            )
                            .help("drop the segment for one frame at a point");
                        self.report(diag);
                        None
                    }
                    (None, None) => {
                        self.missing_arg(
                            "force_aligned",
                            "segment",
                            expr.span,
                            "force_aligned(segment 2)` or `force_aligned(at: peak_force)",
                        );
                        None
                    }
                }
            }
            "fixed" => {
                let bound = self.bind_args("fixed", args, &["origin", "rpy"], 0);
                let origin = match bound.get("origin") {
                    Some(origin) => self.vector3(origin, Dim::Length, "the origin")?,
                    None => [0.0; 3],
                };
                let rpy = match bound.get("rpy") {
                    Some(rpy) => self.vector3(rpy, Dim::Angle, "the roll-pitch-yaw angles")?,
                    None => [0.0; 3],
                };
                Some(ir::FrameSource::Fixed {
                    origin_m: origin,
                    quaternion_wxyz: quaternion_from_rpy(rpy),
                })
            }
            other => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown frame source `{other}`"),
                        "not a frame source",
                    )
                    .help(
                        suggest(other, FRAME_FUNCTIONS.iter().copied())
                            .unwrap_or_else(|| format!("frames come from {}", join_ticked(FRAME_FUNCTIONS))),
                    );
                self.report(diag);
                None
            }
        }
    }

    fn vector3(&mut self, expr: &ast::Expr, dim: Dim, what: &str) -> Option<[f64; 3]> {
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

    fn motion(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<(ir::SegmentIdx, u32)> {
        match &expr.kind {
            ExprKind::Call { name, args } if name.name == "dmp" => {
                let bound = self.bind_args("dmp", args, &["segment", "basis"], 1);
                let segment = self.required_segment(bound.get("segment"), "dmp", expr.span, "dmp(segment 1)", scope);
                let basis = self.basis(bound.get("basis"), DEFAULT_MOTION_BASIS);
                Some((segment?, basis?))
            }
            ExprKind::Call { name, .. } | ExprKind::Name(name) => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown motion source `{}`", name.name),
                        "not a motion source",
                    )
                    .help("motions are learned as `dmp(segment N)`");
                self.report(diag);
                None
            }
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        "a motion is learned by `dmp(segment N)`",
                        "not a motion source",
                    )
                    .help("write `dmp(segment 1)`");
                self.report(diag);
                None
            }
        }
    }

    fn force_source(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::ForceSource> {
        match &expr.kind {
            ExprKind::Quantity { .. } => {
                let value_n = self.quantity(expr, Dim::Force, "a literal force")?;
                Some(ir::ForceSource::Literal { value_n })
            }
            ExprKind::Number(_) => {
                self.quantity(expr, Dim::Force, "a literal force");
                None
            }
            ExprKind::Name(name) if name.name == "tracked" => Some(ir::ForceSource::Tracked),
            ExprKind::Call { name, args } => match name.name.as_str() {
                "constant" => {
                    let bound = self.bind_args("constant", args, &["segment", "along"], 1);
                    let segment = self.required_segment(
                        bound.get("segment"),
                        "constant",
                        expr.span,
                        "constant(segment 2, along: surface.z)",
                        scope,
                    );
                    let along = self.along(bound.get("along"), "constant", expr.span, scope);
                    Some(ir::ForceSource::Constant {
                        segment: segment?,
                        along: along?,
                    })
                }
                "force_at" => {
                    let bound = self.bind_args("force_at", args, &["point", "along"], 1);
                    let point = self.required_point(
                        bound.get("point"),
                        "force_at",
                        expr.span,
                        "force_at(end(segment 1), along: contact.z)",
                        scope,
                    );
                    let along = self.along(bound.get("along"), "force_at", expr.span, scope);
                    Some(ir::ForceSource::At {
                        point: point?,
                        along: along?,
                    })
                }
                "dmp" => {
                    let bound = self.bind_args("dmp", args, &["segment", "basis"], 1);
                    let segment =
                        self.required_segment(bound.get("segment"), "dmp", expr.span, "dmp(segment 2)", scope);
                    let basis = self.basis(bound.get("basis"), DEFAULT_FORCE_BASIS);
                    Some(ir::ForceSource::Dmp {
                        segment: segment?,
                        basis: basis?,
                    })
                }
                "magnitude" => {
                    let bound = self.bind_args("magnitude", args, &["segment", "along", "basis"], 1);
                    let segment = self.required_segment(
                        bound.get("segment"),
                        "magnitude",
                        expr.span,
                        "magnitude(segment 2, along: surface.z)",
                        scope,
                    );
                    let along = self.along(bound.get("along"), "magnitude", expr.span, scope);
                    let basis = self.basis(bound.get("basis"), DEFAULT_FORCE_BASIS);
                    Some(ir::ForceSource::Magnitude {
                        segment: segment?,
                        along: along?,
                        basis: basis?,
                    })
                }
                other => {
                    let diag = self
                        .diag(
                            Code::UnknownFunction,
                            name.span,
                            format!("unknown force source `{other}`"),
                            "not a force source",
                        )
                        .help(suggest(other, FORCE_FUNCTIONS.iter().copied()).unwrap_or_else(|| {
                            format!(
                                "forces come from {}, or a literal like `5 N`",
                                join_ticked(FORCE_FUNCTIONS)
                            )
                        }));
                    self.report(diag);
                    None
                }
            },
            ExprKind::Name(name) => {
                let diag = self
                    .diag(Code::UnknownFunction, name.span, format!("unknown force source `{}`", name.name), "not a force source")
                    .help(
                        suggest(&name.name, FORCE_FUNCTIONS.iter().copied())
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

    fn threshold_source(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::ThresholdSource> {
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
            ExprKind::Call { name, args } if name.name == "force_at" => {
                let bound = self.bind_args("force_at", args, &["point", "along", "scale"], 1);
                let point = self.required_point(
                    bound.get("point"),
                    "force_at",
                    expr.span,
                    "force_at(end(segment 1), along: contact.z)",
                    scope,
                );
                let along = self.along(bound.get("along"), "force_at", expr.span, scope);
                let scale = match bound.get("scale") {
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
            ExprKind::Call { name, .. } | ExprKind::Name(name) => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown threshold source `{}`", name.name),
                        "not a threshold source",
                    )
                    .help(suggest(&name.name, ["force_at"]).unwrap_or_else(|| {
                        "thresholds are learned by `force_at(POINT, along: FRAME.z)` or written like `3 N`".to_string()
                    }));
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

    // ------------------------------------------------------------ states

    fn states(
        &mut self,
        skill: &ast::Skill,
        scope: &mut SkillScope,
    ) -> (Vec<ir::State>, Vec<ir::Transition>, Option<ir::StateId>) {
        let mut ids: HashMap<&str, (ir::StateId, Span)> = HashMap::new();
        let mut unique: Vec<&ast::State> = Vec::new();
        for state in &skill.states {
            if let Some((_, earlier)) = ids.get(state.name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        state.name.span,
                        format!("state `{}` is declared twice", state.name.name),
                        "second declaration",
                    )
                    .label(*earlier, "first declared here")
                    .help("rename one of them");
                self.report(diag);
                continue;
            }
            ids.insert(&state.name.name, (ir::StateId(unique.len() as u32), state.name.span));
            unique.push(state);
        }
        if unique.is_empty() {
            let diag = self
                .diag(Code::NoStates, skill.name.span, format!("skill `{}` has no state", skill.name.name), "nothing to run")
                .help("add a state, e.g. `state approach { move path from current\n on motion_done -> done }` and `terminal done: success`");
            self.report(diag);
            return (Vec::new(), Vec::new(), None);
        }
        let state_names: Vec<&str> = unique.iter().map(|s| s.name.name.as_str()).collect();

        let mut states = Vec::new();
        let mut transitions = Vec::new();
        for (index, state) in unique.iter().enumerate() {
            let id = ir::StateId(index as u32);
            let kind = match &state.body {
                ast::StateBody::Terminal { outcome, message } => {
                    let outcome = match outcome.name.as_str() {
                        "success" => Some(ir::Outcome::Success),
                        "failure" => Some(ir::Outcome::Failure),
                        other => {
                            let diag = self
                                .diag(
                                    Code::UnknownOutcome,
                                    outcome.span,
                                    format!("unknown outcome `{other}`"),
                                    "not an outcome",
                                )
                                .help(
                                    suggest(other, ["success", "failure"])
                                        .unwrap_or_else(|| "a terminal is `success` or `failure`".to_string()),
                                );
                            self.report(diag);
                            None
                        }
                    };
                    outcome.map(|outcome| ir::StateKind::Terminal {
                        outcome,
                        message: message.clone(),
                    })
                }
                ast::StateBody::Active(stmts) => self
                    .active_state(id, stmts, state, &ids, &state_names, scope, &mut transitions)
                    .map(|active| ir::StateKind::Active(Box::new(active))),
            };
            if let Some(kind) = kind {
                states.push(ir::State {
                    id,
                    name: state.name.name.clone(),
                    doc: state.doc.join("\n"),
                    kind,
                    span: self.ir_span(state.name.span),
                });
            }
        }
        // The machine's shape comes from the source, so it is analysed even when guards or
        // statements have errors; only unknown targets make the analysis meaningless.
        let mut successors: Vec<Vec<usize>> = vec![Vec::new(); unique.len()];
        let mut targets_known = true;
        for (index, state) in unique.iter().enumerate() {
            let ast::StateBody::Active(stmts) = &state.body else {
                continue;
            };
            for stmt in stmts {
                let StmtKind::Transition { target, .. } = &stmt.kind else {
                    continue;
                };
                let name = match target {
                    ast::Target::State(name) => name,
                    ast::Target::Extend { then, .. } => then,
                };
                match ids.get(name.name.as_str()) {
                    Some((target, _)) => successors[index].push(target.index()),
                    None => targets_known = false,
                }
            }
        }
        if targets_known {
            let terminal: Vec<bool> = unique
                .iter()
                .map(|state| matches!(state.body, ast::StateBody::Terminal { .. }))
                .collect();
            self.graph(&unique, &successors, &terminal);
        }
        (states, transitions, Some(ir::StateId(0)))
    }

    #[allow(clippy::too_many_arguments)] // One call site; the pieces are the checker's context.
    fn active_state(
        &mut self,
        id: ir::StateId,
        stmts: &[ast::Stmt],
        state: &ast::State,
        ids: &HashMap<&str, (ir::StateId, Span)>,
        state_names: &[&str],
        scope: &mut SkillScope,
        transitions: &mut Vec<ir::Transition>,
    ) -> Option<ir::ActiveState> {
        let errors_before = self.error_count();
        let mut seen: HashMap<&'static str, Span> = HashMap::new();
        let mut motion = None;
        let mut frame = ir::FrameRef::Base;
        let mut position_controlled = [true; 6];
        let mut control_span = None;
        let mut stiffness = DEFAULT_STIFFNESS;
        let mut force = None;
        let mut apply_span = None;
        let mut gains = DEFAULT_GAINS;
        let mut gains_span = None;
        let mut entry = Vec::new();
        let mut state_transitions: Vec<(ir::Transition, &ast::Guard, Span)> = Vec::new();

        for stmt in stmts {
            let keyword = match &stmt.kind {
                StmtKind::Move { .. } => Some("move"),
                StmtKind::Control { .. } => Some("control"),
                StmtKind::Stiffness(_) => Some("stiffness"),
                StmtKind::Apply(_) => Some("apply"),
                StmtKind::Gains(_) => Some("gains"),
                StmtKind::Entry(_) => Some("entry"),
                StmtKind::Transition { .. } => None,
            };
            if let Some(keyword) = keyword {
                if let Some(earlier) = seen.get(keyword) {
                    let diag = self
                        .diag(
                            Code::DuplicateStatement,
                            stmt.span,
                            format!("state `{}` has two `{keyword}` statements", state.name.name),
                            "second one",
                        )
                        .label(*earlier, "first one here")
                        .help(format!("a state has at most one `{keyword}`; merge them"));
                    self.report(diag);
                    continue;
                }
                seen.insert(keyword, stmt.span);
            }
            match &stmt.kind {
                StmtKind::Move { motion: name, .. } => {
                    motion = self.resolve(name, SymKind::Motion, scope).map(ir::MotionId);
                }
                StmtKind::Control {
                    groups,
                    frame: frame_name,
                } => {
                    control_span = Some(stmt.span);
                    if let Some(name) = frame_name {
                        if let Some(resolved) = self.frame_ref(name, scope) {
                            frame = resolved;
                        }
                    }
                    if let Some(selection) = self.selection(groups, stmt.span) {
                        position_controlled = selection;
                    }
                }
                StmtKind::Stiffness(values) => self.stiffness(values, &mut stiffness),
                StmtKind::Apply(name) => {
                    apply_span = Some(stmt.span);
                    force = self.resolve(name, SymKind::Force, scope).map(ir::ForceId);
                }
                StmtKind::Gains(args) => {
                    gains_span = Some(stmt.span);
                    gains = self.gains(args);
                }
                StmtKind::Entry(actions) => {
                    for action in actions {
                        if let Some(action) = self.entry_action(action, scope) {
                            entry.push(action);
                        }
                    }
                }
                StmtKind::Transition { guard, target } => {
                    let resolved_guard = self.guard(guard, scope);
                    let action = self.target(target, ids, state_names, scope);
                    if let (Some(resolved_guard), Some(action)) = (resolved_guard, action) {
                        let transition = ir::Transition {
                            id: ir::TransitionId(0),
                            from: id,
                            guard: resolved_guard,
                            action,
                            guard_text: self
                                .src
                                .slice(guard.span)
                                .split_whitespace()
                                .collect::<Vec<_>>()
                                .join(" "),
                            span: self.ir_span(stmt.span),
                        };
                        state_transitions.push((transition, guard, stmt.span));
                    }
                }
            }
        }

        let has_force_axes = position_controlled.iter().any(|p| !p);
        if has_force_axes && force.is_none() && apply_span.is_none() {
            let span = control_span.unwrap_or(state.name.span);
            let diag = self
                .diag(
                    Code::MissingForceSource,
                    span,
                    format!("state `{}` force-controls axes but applies no force", state.name.name),
                    "force-controlled axes here",
                )
                .help(
                    "add `apply NAME` with a force from `learn`, or declare `force NAME = tracked` for pure compliance",
                );
            self.report(diag);
        }
        if !has_force_axes {
            if let Some(span) = apply_span {
                let diag = self
                    .diag(
                        Code::ForceWithoutForceAxes,
                        span,
                        format!(
                            "state `{}` applies a force but controls no axis in force",
                            state.name.name
                        ),
                        "this force is ignored",
                    )
                    .help("make an axis force-controlled, e.g. `control force z, position x y rx ry rz in FRAME`");
                self.report(diag);
            }
        }
        if has_force_axes && gains_span.is_some() && gains.integral_limit_n.is_none() && gains.ki > 0.0 {
            let diag = self
                .diag(
                    Code::NoIntegralLimit,
                    gains_span.unwrap_or(state.name.span),
                    format!("the force integral of state `{}` is unbounded", state.name.name),
                    "no `limit`",
                )
                .help("add `limit: 10 N` so the integral cannot wind up while contact is lost");
            self.report(diag);
        }

        // A `move` that failed to resolve still runs a motion: judge guards by what was written.
        let writes_move = seen.contains_key("move");
        self.transition_analysis(state, &state_transitions, writes_move, force, has_force_axes, scope);

        if self.error_count() > errors_before {
            return None;
        }
        let mut ids_out = Vec::new();
        for (mut transition, _, _) in state_transitions {
            transition.id = ir::TransitionId(transitions.len() as u32);
            ids_out.push(transition.id);
            transitions.push(transition);
        }
        Some(ir::ActiveState {
            motion,
            frame,
            position_controlled,
            stiffness,
            force,
            gains,
            entry,
            transitions: ids_out,
        })
    }

    /// The axes of a `control` statement as position (`true`) or force (`false`).
    fn selection(&mut self, groups: &[ast::ControlGroup], span: Span) -> Option<[bool; 6]> {
        let mut assigned: [Option<(bool, Span)>; 6] = [None; 6];
        let mut ok = true;
        for group in groups {
            for (axis, axis_span) in self.axis_list(&group.axes) {
                let Some(axis) = axis else {
                    ok = false;
                    continue;
                };
                if let Some((_, earlier)) = assigned[axis.index()] {
                    let diag = self
                        .diag(
                            Code::RepeatedAxis,
                            axis_span,
                            format!("axis `{}` is assigned twice", axis.name()),
                            "again here",
                        )
                        .label(earlier, "first assigned here")
                        .help("name each of x y z rx ry rz once");
                    self.report(diag);
                    ok = false;
                    continue;
                }
                assigned[axis.index()] = Some((!group.force, axis_span));
            }
        }
        let missing: Vec<&str> = ir::Axis::ALL
            .iter()
            .filter(|axis| assigned[axis.index()].is_none())
            .map(|axis| axis.name())
            .collect();
        if ok && !missing.is_empty() {
            let diag = self
                .diag(
                    Code::MissingAxis,
                    span,
                    format!("`control` leaves {} unassigned", join_ticked(&missing)),
                    "not every axis is assigned",
                )
                .help(format!("add `, position {}`", missing.join(" ")));
            self.report(diag);
            ok = false;
        }
        ok.then(|| assigned.map(|slot| slot.is_none_or(|(position, _)| position)))
    }

    fn axis_list(&mut self, axes: &AxisSet) -> Vec<(Option<ir::Axis>, Span)> {
        match axes {
            AxisSet::All(span) => ir::Axis::ALL.iter().map(|axis| (Some(*axis), *span)).collect(),
            AxisSet::List(names) => names.iter().map(|name| (self.axis(name), name.span)).collect(),
        }
    }

    fn stiffness(&mut self, values: &[ast::AxisValue], stiffness: &mut [f64; 6]) {
        let mut assigned: [Option<Span>; 6] = [None; 6];
        for value in values {
            let axes = self.axis_list(&value.axes);
            let translation = axes.iter().any(|(axis, _)| axis.is_some_and(|a| !a.is_rotation()));
            let rotation = axes.iter().any(|(axis, _)| axis.is_some_and(|a| a.is_rotation()));
            if translation && rotation {
                let diag = self
                    .diag(
                        Code::UnitMismatch,
                        value.axes.span(),
                        "one stiffness cannot serve translations and rotations",
                        "mixes x y z with rx ry rz",
                    )
                    .help("write `x y z: 1500 N/m, rx ry rz: 150 Nm/rad`");
                self.report(diag);
                continue;
            }
            let dim = if rotation { Dim::RotStiffness } else { Dim::Stiffness };
            let Some(k) = self.quantity(&value.value, dim, "the stiffness") else {
                continue;
            };
            if k <= 0.0 {
                let diag = self
                    .diag(
                        Code::NonPositiveStiffness,
                        value.value.span,
                        "stiffness must be positive",
                        "zero or negative",
                    )
                    .help("to let an axis comply, force-control it with `control force ...` instead");
                self.report(diag);
                continue;
            }
            for (axis, span) in axes {
                let Some(axis) = axis else { continue };
                if let Some(earlier) = assigned[axis.index()] {
                    let diag = self
                        .diag(
                            Code::RepeatedAxis,
                            span,
                            format!("stiffness of `{}` is given twice", axis.name()),
                            "again here",
                        )
                        .label(earlier, "first given here");
                    self.report(diag);
                    continue;
                }
                assigned[axis.index()] = Some(span);
                stiffness[axis.index()] = k;
            }
        }
    }

    fn gains(&mut self, args: &[ast::Arg]) -> ir::ForceGains {
        let bound = self.bind_args("gains", args, &["kp", "ki", "limit"], 0);
        let mut gains = ir::ForceGains {
            kp: DEFAULT_GAINS.kp,
            ki: DEFAULT_GAINS.ki,
            integral_limit_n: None,
        };
        for (name, slot) in [("kp", &mut gains.kp), ("ki", &mut gains.ki)] {
            if let Some(expr) = bound.get(name) {
                if let Some(value) = self.plain_number(expr, &format!("the gain `{name}`")) {
                    if value < 0.0 {
                        let diag = self
                            .diag(
                                Code::NegativeGain,
                                expr.span,
                                format!("the gain `{name}` is negative"),
                                "negative gain",
                            )
                            .help(
                                "force gains are zero or positive; a negative gain pushes away from the desired force",
                            );
                        self.report(diag);
                    } else {
                        *slot = value;
                    }
                }
            }
        }
        if let Some(expr) = bound.get("limit") {
            if let Some(value) = self.quantity(expr, Dim::Force, "the integral limit") {
                if value < 0.0 {
                    let diag = self
                        .diag(
                            Code::NegativeGain,
                            expr.span,
                            "the integral limit is negative",
                            "negative limit",
                        )
                        .help("write a positive bound such as `limit: 10 N`");
                    self.report(diag);
                } else {
                    gains.integral_limit_n = Some(value);
                }
            }
        }
        gains
    }

    fn entry_action(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::EntryAction> {
        const ACTIONS: [&str; 3] = ["reset_integral", "tare", "shift_goal"];
        match &expr.kind {
            ExprKind::Name(name) if name.name == "reset_integral" => Some(ir::EntryAction::ResetIntegral),
            ExprKind::Name(name) if name.name == "tare" => Some(ir::EntryAction::Tare),
            ExprKind::Call { name, args } if name.name == "shift_goal" => {
                let bound = self.bind_args("shift_goal", args, &["along", "by"], 0);
                let along = self.along(bound.get("along"), "shift_goal", expr.span, scope);
                let distance = match bound.get("by") {
                    Some(by) => self.quantity(by, Dim::Length, "the goal shift"),
                    None => {
                        self.missing_arg("shift_goal", "by", expr.span, "shift_goal(along: contact.z, by: 5 mm)");
                        None
                    }
                };
                Some(ir::EntryAction::ShiftGoal {
                    along: along?,
                    distance_m: distance?,
                })
            }
            ExprKind::Name(name) | ExprKind::Call { name, .. } => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown entry action `{}`", name.name),
                        "not an action",
                    )
                    .help(
                        suggest(&name.name, ACTIONS)
                            .unwrap_or_else(|| format!("entry actions are {}", join_ticked(&ACTIONS))),
                    );
                self.report(diag);
                None
            }
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        "not an entry action",
                        "expected an action",
                    )
                    .help(format!("entry actions are {}", join_ticked(&ACTIONS)));
                self.report(diag);
                None
            }
        }
    }

    fn target(
        &mut self,
        target: &ast::Target,
        ids: &HashMap<&str, (ir::StateId, Span)>,
        state_names: &[&str],
        scope: &mut SkillScope,
    ) -> Option<ir::TransitionAction> {
        match target {
            ast::Target::State(name) => self
                .state_ref(name, ids, state_names)
                .map(|target| ir::TransitionAction::Goto { target }),
            ast::Target::Extend {
                axis, speed, max, then, ..
            } => {
                let along = self.frame_axis(axis, true, scope);
                let speed_value = self.quantity(speed, Dim::Speed, "the extension speed");
                let speed_mps = self.positive(speed_value, speed.span, "the extension speed");
                let max_value = self.quantity(max, Dim::Length, "the extension bound");
                let max_m = self.positive(max_value, max.span, "the extension bound");
                let then = self.state_ref(then, ids, state_names);
                Some(ir::TransitionAction::Extend {
                    along: along?,
                    speed_mps: speed_mps?,
                    max_m: max_m?,
                    then: then?,
                })
            }
        }
    }

    fn state_ref(
        &mut self,
        name: &ast::Ident,
        ids: &HashMap<&str, (ir::StateId, Span)>,
        state_names: &[&str],
    ) -> Option<ir::StateId> {
        if let Some((id, _)) = ids.get(name.name.as_str()) {
            return Some(*id);
        }
        let help = suggest(&name.name, state_names.iter().copied())
            .unwrap_or_else(|| format!("states: {}", join_ticked(state_names)));
        let diag = self
            .diag(
                Code::UnknownName,
                name.span,
                format!("unknown state `{}`", name.name),
                "no state of this name",
            )
            .help(help);
        self.report(diag);
        None
    }

    fn guard(&mut self, guard: &ast::Guard, scope: &mut SkillScope) -> Option<ir::Guard> {
        match &guard.kind {
            GuardKind::Or(parts) | GuardKind::And(parts) => {
                let resolved: Vec<Option<ir::Guard>> = parts.iter().map(|part| self.guard(part, scope)).collect();
                let resolved: Option<Vec<ir::Guard>> = resolved.into_iter().collect();
                let resolved = resolved?;
                Some(if matches!(guard.kind, GuardKind::Or(_)) {
                    ir::Guard::Or { any: resolved }
                } else {
                    ir::Guard::And { all: resolved }
                })
            }
            GuardKind::Not(inner) => Some(ir::Guard::Not {
                guard: Box::new(self.guard(inner, scope)?),
            }),
            GuardKind::Force { axis, op, rhs } => {
                let along = self.frame_axis(axis, false, scope);
                let dim = match along {
                    Some(along) if along.axis.is_rotation() => Dim::Torque,
                    _ => Dim::Force,
                };
                let rhs = match &rhs.kind {
                    ExprKind::Name(name) => self.threshold_ref(name, dim, scope),
                    _ => self
                        .quantity(rhs, dim, "the threshold")
                        .map(|value| ir::Threshold::Literal { value }),
                };
                let op = match op {
                    ast::CmpOp::Ge => ir::Comparison::Ge,
                    ast::CmpOp::Gt => ir::Comparison::Gt,
                    ast::CmpOp::Le => ir::Comparison::Le,
                    ast::CmpOp::Lt => ir::Comparison::Lt,
                };
                Some(ir::Guard::Force {
                    along: along?,
                    op,
                    rhs: rhs?,
                })
            }
            GuardKind::Timed { timeout, duration } => {
                let what = if *timeout { "the timeout" } else { "the dwell time" };
                let value = self.quantity(duration, Dim::Time, what)?;
                if value < 0.0 {
                    let diag = self.diag(
                        Code::OutOfRange,
                        duration.span,
                        format!("{what} is negative"),
                        "negative duration",
                    );
                    self.report(diag);
                    return None;
                }
                Some(if *timeout {
                    ir::Guard::Timeout { duration_s: value }
                } else {
                    ir::Guard::Dwell { duration_s: value }
                })
            }
            GuardKind::ForceReached(tolerance) => {
                let value = self.quantity(tolerance, Dim::Force, "the force tolerance");
                let tolerance_n = self.positive(value, tolerance.span, "the force tolerance")?;
                Some(ir::Guard::ForceReached { tolerance_n })
            }
            GuardKind::Named(name) => {
                if name.name == "motion_done" {
                    return Some(ir::Guard::MotionDone);
                }
                let help = match name.name.as_str() {
                    "timeout" | "dwell" => format!("`{}` needs a duration: `{} 5 s`", name.name, name.name),
                    "force_reached" => "write `force_reached within 1 N`".to_string(),
                    "contact" => "contact is a force guard: `force(contact.z) >= touch`".to_string(),
                    other => suggest(
                        other,
                        NAMED_GUARDS
                            .iter()
                            .copied()
                            .chain(["timeout", "dwell", "force_reached"]),
                    )
                    .unwrap_or_else(|| {
                        "guards are `motion_done`, `force(F.z) >= X`, `force_reached within X`, `timeout T`, `dwell T`"
                            .to_string()
                    }),
                };
                let diag = self
                    .diag(
                        Code::UnknownGuard,
                        name.span,
                        format!("unknown guard `{}`", name.name),
                        "not a guard",
                    )
                    .help(help);
                self.report(diag);
                None
            }
        }
    }

    fn threshold_ref(&mut self, name: &ast::Ident, dim: Dim, scope: &mut SkillScope) -> Option<ir::Threshold> {
        match scope.symbols.get_mut(&name.name) {
            Some(sym) if sym.kind == SymKind::Threshold => {
                sym.used = true;
                Some(ir::Threshold::Learned {
                    id: ir::ThresholdId(sym.id),
                })
            }
            Some(sym) if sym.kind == SymKind::Force => {
                sym.used = true;
                let (id, span) = (sym.id, sym.span);
                match scope.force_sources.get(id as usize) {
                    Some(
                        ir::ForceSource::Constant { .. } | ir::ForceSource::At { .. } | ir::ForceSource::Literal { .. },
                    ) => {
                        if dim == Dim::Torque {
                            let diag = self
                                .diag(
                                    Code::UnitMismatch,
                                    name.span,
                                    format!("`{}` is a force; a rotation axis compares torques", name.name),
                                    "a force",
                                )
                                .help("compare a rotation axis with a torque, like `0.5 Nm`");
                            self.report(diag);
                            return None;
                        }
                        Some(ir::Threshold::Force { id: ir::ForceId(id) })
                    }
                    _ => {
                        let diag = self
                            .diag(
                                Code::WrongKind,
                                name.span,
                                format!("`{}` is not a constant force and cannot be a threshold", name.name),
                                "a profile, not a value",
                            )
                            .label(span, "declared here")
                            .help(
                                "declare a threshold: `threshold touch = force_at(end(segment 1), along: contact.z)`",
                            );
                        self.report(diag);
                        None
                    }
                }
            }
            _ => self
                .resolve(name, SymKind::Threshold, scope)
                .map(|id| ir::Threshold::Learned {
                    id: ir::ThresholdId(id),
                }),
        }
    }

    /// Guards that can never fire, repeated guards, and contact waits without a way out.
    fn transition_analysis(
        &mut self,
        state: &ast::State,
        transitions: &[(ir::Transition, &ast::Guard, Span)],
        has_motion: bool,
        force: Option<ir::ForceId>,
        has_force_axes: bool,
        scope: &SkillScope,
    ) {
        let force_profile = force
            .and_then(|id| scope.force_sources.get(id.index()))
            .is_some_and(|source| matches!(source, ir::ForceSource::Dmp { .. } | ir::ForceSource::Magnitude { .. }));
        for (index, (transition, guard, _)) in transitions.iter().enumerate() {
            // Atoms that cannot hold in this state.
            if let Some(reason) = impossible_atom(&transition.guard, has_motion || force_profile, has_force_axes) {
                let diag = self
                    .diag(Code::NeverFires, guard.span, "this transition can never fire", reason.0)
                    .help(reason.1);
                self.report(diag);
                continue;
            }
            if unsatisfiable(&transition.guard) {
                let diag = self
                    .diag(
                        Code::NeverFires,
                        guard.span,
                        "this transition can never fire",
                        "this guard contradicts itself",
                    )
                    .help("remove the contradicting condition");
                self.report(diag);
                continue;
            }
            for (earlier, earlier_guard, _) in &transitions[..index] {
                if earlier.guard == transition.guard {
                    let diag = self
                        .diag(
                            Code::DuplicateGuard,
                            guard.span,
                            "this guard repeats an earlier one",
                            "same guard",
                        )
                        .label(earlier_guard.span, "first written here; it always fires first")
                        .help("remove one of the two transitions");
                    self.report(diag);
                    break;
                }
                if implies(&transition.guard, &earlier.guard) {
                    let diag = self
                        .diag(
                            Code::NeverFires,
                            guard.span,
                            "this transition can never fire",
                            "whenever this holds, the earlier guard holds too",
                        )
                        .label(earlier_guard.span, "this earlier transition fires first")
                        .help("reorder the transitions or make this guard weaker than the earlier one");
                    self.report(diag);
                    break;
                }
            }
        }
        let all_force_only = !transitions.is_empty()
            && transitions
                .iter()
                .all(|(transition, _, _)| only_force_atoms(&transition.guard));
        if all_force_only {
            let diag = self
                .diag(
                    Code::ContactWaitWithoutTimeout,
                    state.name.span,
                    format!("state `{}` waits for a force with no timeout", state.name.name),
                    "may wait forever if contact never comes",
                )
                .help("add `on timeout 10 s -> STATE` or `on motion_done -> STATE`");
            self.report(diag);
        }
    }

    /// Reachability from the initial state, and a path to a terminal from every state.
    fn graph(&mut self, states: &[&ast::State], successors: &[Vec<usize>], terminal: &[bool]) {
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

    fn unused(&mut self, scope: &SkillScope) {
        let mut unused: Vec<(&String, &Sym)> = scope.symbols.iter().filter(|(_, sym)| !sym.used).collect();
        unused.sort_by_key(|(_, sym)| sym.span);
        for (name, sym) in unused {
            let diag = self
                .diag(
                    Code::Unused,
                    sym.span,
                    format!("{} `{name}` is learned but never used", kind_noun(sym.kind)),
                    "unused",
                )
                .help("use it in a state or remove it: learning it costs time");
            self.report(diag);
        }
    }

    // ------------------------------------------------------------ tasks

    /// Checks one task against the skills in scope and returns its IR when it has no error.
    pub(crate) fn task(&mut self, task: &ast::Task, skills: &[&str], base_dir: &str) -> Option<ir::Task> {
        let errors_before = self.error_count();
        let mut names: HashMap<&str, (Span, bool)> = HashMap::new();
        let mut fallback_index: HashMap<&str, u32> = HashMap::new();
        for step in &task.steps {
            if let Some((earlier, _)) = names.get(step.name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        step.name.span,
                        format!("step `{}` is declared twice", step.name.name),
                        "second declaration",
                    )
                    .label(*earlier, "first declared here")
                    .help("rename one of them");
                self.report(diag);
                continue;
            }
            names.insert(&step.name.name, (step.name.span, step.fallback));
            if step.fallback {
                let next = fallback_index.len() as u32;
                fallback_index.insert(&step.name.name, next);
            }
        }
        if !task.steps.iter().any(|step| !step.fallback) {
            let diag = self
                .diag(
                    Code::NoStates,
                    task.name.span,
                    format!("task `{}` has no step", task.name.name),
                    "nothing to run",
                )
                .help("add `step NAME = SKILL(demo: \"demo.csv\")`");
            self.report(diag);
        }
        let mut steps = Vec::new();
        let mut fallbacks = Vec::new();
        for step in &task.steps {
            if !skills.contains(&step.skill.name.as_str()) {
                let help = suggest(&step.skill.name, skills.iter().copied()).unwrap_or_else(|| {
                    if skills.is_empty() {
                        "no skill is in scope: `import \"path/to/skill.skill\"`".to_string()
                    } else {
                        format!(
                            "skills in scope: {}; import others with `import \"path.skill\"`",
                            join_ticked(skills)
                        )
                    }
                });
                let diag = self
                    .diag(
                        Code::UnknownName,
                        step.skill.span,
                        format!("unknown skill `{}`", step.skill.name),
                        "no skill of this name",
                    )
                    .help(help);
                self.report(diag);
            }
            let bound = self.bind_args(
                &step.skill.name,
                &step.args,
                &["demo", "learned", "force_scale", "speed", "goal_offset"],
                0,
            );
            let input = match (bound.get("demo"), bound.get("learned")) {
                (Some(demo), None) => self
                    .string(demo, "`demo`")
                    .map(|path| ir::StepInput::Demo(join_path(base_dir, &path))),
                (None, Some(learned)) => self
                    .string(learned, "`learned`")
                    .map(|path| ir::StepInput::Learned(join_path(base_dir, &path))),
                (Some(_), Some(learned)) => {
                    let diag = self
                        .diag(
                            Code::BadArgument,
                            learned.span,
                            "a step takes `demo` or `learned`, not both",
                            "second source",
                        )
                        .help("give the demonstration to learn from, or the file already learned");
                    self.report(diag);
                    None
                }
                (None, None) => {
                    let span = step.span;
                    self.missing_arg(
                        &step.skill.name,
                        "demo",
                        span,
                        &format!(
                            "{}(demo: \"demos/{}.csv\")` or `learned: \"....json\"",
                            step.skill.name, step.skill.name
                        ),
                    );
                    None
                }
            };
            let mut overrides = ir::Overrides::default();
            if let Some(expr) = bound.get("force_scale") {
                let value = self.plain_number(expr, "the force scale");
                if let Some(value) = self.positive(value, expr.span, "the force scale") {
                    overrides.force_scale = value;
                }
            }
            if let Some(expr) = bound.get("speed") {
                let value = self.plain_number(expr, "the speed factor");
                if let Some(value) = self.positive(value, expr.span, "the speed factor") {
                    overrides.speed_factor = value;
                }
            }
            if let Some(expr) = bound.get("goal_offset") {
                if let Some(offset) = self.vector3(expr, Dim::Length, "the goal offset") {
                    overrides.goal_offset_m = offset;
                }
            }
            let on_failure = match &step.on_failure {
                None | Some(ast::OnFailure::Abort(_)) => Some(ir::OnFailure::Abort),
                Some(ast::OnFailure::Fallback(name)) => {
                    match (fallback_index.get(name.name.as_str()), names.get(name.name.as_str())) {
                        (Some(index), _) => Some(ir::OnFailure::Fallback(*index)),
                        (None, Some((span, _))) => {
                            let diag = self
                                .diag(
                                    Code::WrongKind,
                                    name.span,
                                    format!("`{}` is a step, not a fallback", name.name),
                                    "not a fallback",
                                )
                                .label(*span, "declared as a step here")
                                .help(format!("declare it with `fallback {} = ...`", name.name));
                            self.report(diag);
                            None
                        }
                        (None, None) => {
                            let fallback_names: Vec<&str> = fallback_index.keys().copied().collect();
                            let help = suggest(&name.name, fallback_names.iter().copied()).unwrap_or_else(|| {
                                format!("declare it: `fallback {} = SKILL(demo: \"...\")`", name.name)
                            });
                            let diag = self
                                .diag(
                                    Code::UnknownName,
                                    name.span,
                                    format!("unknown fallback `{}`", name.name),
                                    "no fallback of this name",
                                )
                                .help(help);
                            self.report(diag);
                            None
                        }
                    }
                }
            };
            if let (Some(input), Some(on_failure)) = (input, on_failure) {
                let lowered = ir::Step {
                    name: step.name.name.clone(),
                    skill: step.skill.name.clone(),
                    input,
                    overrides,
                    on_failure,
                    span: self.ir_span(step.span),
                };
                if step.fallback {
                    fallbacks.push(lowered);
                } else {
                    steps.push(lowered);
                }
            }
        }
        if self.error_count() > errors_before {
            return None;
        }
        Some(ir::Task {
            name: task.name.name.clone(),
            doc: task.doc.join("\n"),
            steps,
            fallbacks,
            span: self.ir_span(task.name.span),
        })
    }
}

/// Joins a path written in a file to that file's directory, lexically (no IO).
pub(crate) fn join_path(base_dir: &str, path: &str) -> String {
    if path.starts_with('/') || base_dir.is_empty() {
        return path.to_string();
    }
    let mut parts: Vec<&str> = base_dir.split('/').filter(|p| !p.is_empty() && *p != ".").collect();
    let absolute = base_dir.starts_with('/');
    for part in path.split('/') {
        match part {
            "" | "." => {}
            ".." if parts.last().is_some_and(|last| *last != "..") => {
                parts.pop();
            }
            _ => parts.push(part),
        }
    }
    let joined = parts.join("/");
    if absolute {
        format!("/{joined}")
    } else if joined.is_empty() {
        ".".to_string()
    } else {
        joined
    }
}

fn kind_noun(kind: SymKind) -> &'static str {
    match kind {
        SymKind::Frame => "frame",
        SymKind::Motion => "motion",
        SymKind::Force => "force",
        SymKind::Threshold => "threshold",
    }
}

fn join_ticked(items: &[&str]) -> String {
    items
        .iter()
        .map(|item| format!("`{item}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn example_quantity(dim: Dim) -> String {
    format!("5 {}", dim.example_unit())
}

/// Roll-pitch-yaw (fixed axes x, then y, then z) to a unit quaternion `[w, x, y, z]`.
fn quaternion_from_rpy([roll, pitch, yaw]: [f64; 3]) -> [f64; 4] {
    let (sr, cr) = (roll / 2.0).sin_cos();
    let (sp, cp) = (pitch / 2.0).sin_cos();
    let (sy, cy) = (yaw / 2.0).sin_cos();
    [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]
}

/// The conjunctive atoms of a guard (the guard itself when it is not an `and`).
fn conjuncts(guard: &ir::Guard) -> Vec<&ir::Guard> {
    match guard {
        ir::Guard::And { all } => all.iter().flat_map(conjuncts).collect(),
        other => vec![other],
    }
}

/// Whether `a` holding guarantees `b` holds, for the atom forms we can compare.
fn atom_implies(a: &ir::Guard, b: &ir::Guard) -> bool {
    use ir::Guard::*;
    if a == b {
        return true;
    }
    match (a, b) {
        (_, Dwell { duration_s } | Timeout { duration_s }) if *duration_s == 0.0 => true,
        (
            Dwell { duration_s: da } | Timeout { duration_s: da },
            Dwell { duration_s: db } | Timeout { duration_s: db },
        ) => da >= db,
        (
            Force {
                along: la,
                op: oa,
                rhs: ir::Threshold::Literal { value: va },
            },
            Force {
                along: lb,
                op: ob,
                rhs: ir::Threshold::Literal { value: vb },
            },
        ) if la == lb => {
            use ir::Comparison::*;
            match (oa, ob) {
                (Ge | Gt, Ge) => va >= vb,
                (Gt, Gt) => va >= vb,
                (Ge, Gt) => va > vb,
                (Le | Lt, Le) => va <= vb,
                (Lt, Lt) => va <= vb,
                (Le, Lt) => va < vb,
                _ => false,
            }
        }
        _ => false,
    }
}

/// Whether `later ⇒ earlier` for conjunctions of atoms: every atom of `earlier` follows from
/// some atom of `later`. Disjunctions and negations are compared only for equality.
fn implies(later: &ir::Guard, earlier: &ir::Guard) -> bool {
    let later_atoms = conjuncts(later);
    conjuncts(earlier)
        .iter()
        .all(|needed| later_atoms.iter().any(|have| atom_implies(have, needed)))
}

/// Whether a conjunction contradicts itself: `a and not a`, or disjoint literal force bounds.
fn unsatisfiable(guard: &ir::Guard) -> bool {
    let atoms = conjuncts(guard);
    for (i, a) in atoms.iter().enumerate() {
        for b in &atoms[i + 1..] {
            if let ir::Guard::Not { guard } = a {
                if guard.as_ref() == *b {
                    return true;
                }
            }
            if let ir::Guard::Not { guard } = b {
                if guard.as_ref() == *a {
                    return true;
                }
            }
            if let (
                ir::Guard::Force {
                    along: la,
                    op: oa,
                    rhs: ir::Threshold::Literal { value: va },
                },
                ir::Guard::Force {
                    along: lb,
                    op: ob,
                    rhs: ir::Threshold::Literal { value: vb },
                },
            ) = (a, b)
            {
                if la == lb {
                    use ir::Comparison::*;
                    let lower_upper =
                        |lo_op: ir::Comparison, lo: f64, hi_op: ir::Comparison, hi: f64| match (lo_op, hi_op) {
                            (Ge, Le) => lo > hi,
                            (Ge | Gt, Le | Lt) => lo >= hi,
                            _ => false,
                        };
                    if matches!(oa, Ge | Gt) && matches!(ob, Le | Lt) && lower_upper(*oa, *va, *ob, *vb) {
                        return true;
                    }
                    if matches!(ob, Ge | Gt) && matches!(oa, Le | Lt) && lower_upper(*ob, *vb, *oa, *va) {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// An atom of a conjunction that cannot hold in this state, with a label and a help line.
fn impossible_atom(guard: &ir::Guard, runs_dmp: bool, has_force_axes: bool) -> Option<(&'static str, &'static str)> {
    for atom in conjuncts(guard) {
        match atom {
            ir::Guard::MotionDone if !runs_dmp => {
                return Some((
                    "`motion_done` in a state that runs no motion",
                    "add `move NAME` to the state, or wait with `dwell T` instead",
                ))
            }
            ir::Guard::ForceReached { .. } if !has_force_axes => {
                return Some((
                    "`force_reached` in a state with no force-controlled axis",
                    "force-control an axis, or compare the force: `force(FRAME.z) >= X`",
                ))
            }
            _ => {}
        }
    }
    None
}

/// Whether every atom of a guard is a force comparison (a wait that needs contact).
fn only_force_atoms(guard: &ir::Guard) -> bool {
    match guard {
        ir::Guard::And { all } => all.iter().all(only_force_atoms),
        ir::Guard::Or { any } => any.iter().all(only_force_atoms),
        ir::Guard::Not { guard } => only_force_atoms(guard),
        ir::Guard::Force { .. } => true,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_path_is_lexical() {
        assert_eq!(join_path("examples/tasks", "../demos/a.csv"), "examples/demos/a.csv");
        assert_eq!(join_path("", "a.csv"), "a.csv");
        assert_eq!(join_path("a", "/abs/b.csv"), "/abs/b.csv");
        assert_eq!(join_path("/x/y", "./z.skill"), "/x/y/z.skill");
        assert_eq!(join_path("..", "../a"), "../../a");
    }

    #[test]
    fn rpy_quaternion_matches_known_rotations() {
        let q = quaternion_from_rpy([std::f64::consts::PI, 0.0, 0.0]);
        assert!((q[0]).abs() < 1e-12 && (q[1] - 1.0).abs() < 1e-12);
        let q = quaternion_from_rpy([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q[0] - h).abs() < 1e-12 && (q[3] - h).abs() < 1e-12);
    }

    #[test]
    fn longer_timeouts_imply_shorter_ones() {
        let short = ir::Guard::Timeout { duration_s: 1.0 };
        let long = ir::Guard::Dwell { duration_s: 2.0 };
        assert!(implies(&long, &short));
        assert!(!implies(&short, &long));
        let both = ir::Guard::And {
            all: vec![ir::Guard::MotionDone, long.clone()],
        };
        assert!(implies(&both, &short));
        assert!(!implies(&short, &both));
    }
}

//! The `learn` block: declared names and their ids, preprocessing, and the declarations in
//! order (segments, then frames, motions, forces and thresholds); motions and DMP bases.

use super::scope::{SkillScope, Sym, SymKind, BUILTIN_FRAMES};
use super::signatures::{Function, Produces, Signature};
use super::values::Args;
use super::Checker;
use crate::ast::{self, ExprKind, LearnKind};
use crate::diag::Code;
use crate::units::Dim;
use skill_ir as ir;

/// Default number of DMP basis functions of a motion.
pub const DEFAULT_MOTION_BASIS: u32 = 50;

/// The default shortest stroke of `strokes(...)` \[s\]: a hand-guided stroke takes a few
/// tenths of a second at least; shorter runs between reversals are jitter at a turn.
pub(super) const DEFAULT_STROKE_MIN_LENGTH_S: f64 = 0.15;

/// Default number of DMP basis functions of a force profile.
pub const DEFAULT_FORCE_BASIS: u32 = 30;

impl Checker<'_> {
    pub(super) fn learn(&mut self, decls: &[ast::LearnDecl], scope: &mut SkillScope) -> Option<ir::LearnPlan> {
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
                    Some(source) => {
                        if let ir::FrameSource::Fixed { quaternion_wxyz, .. } = source {
                            if let Some(sym) = scope.symbols.get(&name.name) {
                                scope.fixed_frames.insert(sym.id, quaternion_wxyz);
                            }
                        }
                        frames.push(ir::FrameDecl {
                            name: name.name.clone(),
                            source,
                            span,
                        })
                    }
                    None => ok = false,
                },
                LearnKind::Motion => match self.motion(&decl.value, scope) {
                    Some((segment, basis, strokes)) => motions.push(ir::MotionDecl {
                        name: name.name.clone(),
                        segment,
                        basis,
                        strokes,
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

    /// The number of basis functions of a DMP: the `basis` argument, or `default`.
    pub(super) fn basis(&mut self, args: &Args<'_>, default: u32) -> Option<u32> {
        let Some(expr) = args.get("basis") else {
            return Some(default);
        };
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

    /// A motion's source: `dmp(segment N [, basis: B])` or `strokes(segment N [, basis: B,
    /// min_length: T])`, as the segment, the basis count and the strokes, if any.
    fn motion(
        &mut self,
        expr: &ast::Expr,
        scope: &mut SkillScope,
    ) -> Option<(ir::SegmentIdx, u32, Option<ir::Strokes>)> {
        let (name, args) = match &expr.kind {
            ExprKind::Call { name, args } => (name, Some(args)),
            ExprKind::Name(name) => (name, None),
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
                return None;
            }
        };
        let (Some(sig), Some(args)) = (Signature::find(Produces::Motion, &name.name), args) else {
            let diag = self
                .diag(
                    Code::UnknownFunction,
                    name.span,
                    format!("unknown motion source `{}`", name.name),
                    "not a motion source",
                )
                .help("motions are learned as `dmp(segment N)`");
            self.report(diag);
            return None;
        };
        let args = self.bind(sig, expr.span, args);
        let segment = self.required_segment(&args, scope);
        let strokes = match sig.function {
            Function::Strokes => {
                let min_length_s = match args.get("min_length") {
                    Some(expr) => {
                        let value = self.quantity(expr, Dim::Time, "the minimum stroke length");
                        self.positive(value, expr.span, "the minimum stroke length")?
                    }
                    None => DEFAULT_STROKE_MIN_LENGTH_S,
                };
                Some(ir::Strokes { min_length_s })
            }
            _ => None,
        };
        let basis = self.basis(&args, DEFAULT_MOTION_BASIS);
        Some((segment?, basis?, strokes))
    }
}

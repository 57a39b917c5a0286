//! Names in a skill's scope: learned frames, motions, forces and thresholds, the built-in
//! frames, frame axes (and the `along` argument), and the warning for names never used.

use super::values::Args;
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, ExprKind};
use crate::diag::Code;
use crate::source::Span;
use skill_ir as ir;
use std::collections::HashMap;

/// Names of the frames every skill has.
pub(super) const BUILTIN_FRAMES: [&str; 2] = ["base", "tool"];

/// The kinds of name a `learn` block declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SymKind {
    Frame,
    Motion,
    Force,
    Threshold,
}

impl SymKind {
    pub(super) fn describe(self) -> &'static str {
        match self {
            SymKind::Frame => "a frame",
            SymKind::Motion => "a motion",
            SymKind::Force => "a force",
            SymKind::Threshold => "a threshold",
        }
    }
}

/// One declared name: its kind, its id among names of that kind, and whether it is used.
#[derive(Debug, Clone)]
pub(super) struct Sym {
    pub(super) kind: SymKind,
    pub(super) id: u32,
    pub(super) span: Span,
    pub(super) used: bool,
}

/// What a skill needs from the checker of its learn block.
#[derive(Default)]
pub(super) struct SkillScope {
    pub(super) symbols: HashMap<String, Sym>,
    pub(super) segment_count: Option<u32>,
    pub(super) segments_span: Option<Span>,
    pub(super) reported_unknown_count: bool,
    pub(super) force_sources: Vec<ir::ForceSource>,
    /// The orientation (`[w, x, y, z]`, base frame) of each literal `fixed(...)` frame, by id.
    pub(super) fixed_frames: HashMap<u32, [f64; 4]>,
    /// Every state's id by name (for `entered(STATE)`).
    pub(super) state_ids: HashMap<String, u32>,
    /// The states' names in order.
    pub(super) state_names: Vec<String>,
    /// Every name a state captures (`capture NAME`), with where it is first captured and
    /// whether a `move ... at NAME` uses it.
    pub(super) captures: Vec<super::captures::Capture>,
}

impl Checker<'_> {
    /// Looks a name up in the skill's scope, reporting unknown names and wrong kinds.
    pub(super) fn resolve(&mut self, name: &ast::Ident, want: SymKind, scope: &mut SkillScope) -> Option<u32> {
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

    pub(super) fn frame_ref(&mut self, name: &ast::Ident, scope: &mut SkillScope) -> Option<ir::FrameRef> {
        match name.name.as_str() {
            "base" => Some(ir::FrameRef::Base),
            "tool" => Some(ir::FrameRef::Tool),
            _ => self
                .resolve(name, SymKind::Frame, scope)
                .map(|id| ir::FrameRef::Learned(ir::FrameId(id))),
        }
    }

    pub(super) fn axis(&mut self, name: &ast::Ident) -> Option<ir::Axis> {
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
    pub(super) fn frame_axis(
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

    /// The required `along` argument of a call: a translation axis of a frame.
    pub(super) fn along(&mut self, args: &Args<'_>, scope: &mut SkillScope) -> Option<ir::FrameAxis> {
        let Some(expr) = args.get("along") else {
            let function = args.function;
            self.missing_arg(
                function,
                "along",
                args.span,
                &format!("{function}(..., along: contact.z)"),
            );
            return None;
        };
        match &expr.kind {
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
        }
    }

    pub(super) fn unused(&mut self, scope: &SkillScope) {
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
}

fn kind_noun(kind: SymKind) -> &'static str {
    match kind {
        SymKind::Frame => "frame",
        SymKind::Motion => "motion",
        SymKind::Force => "force",
        SymKind::Threshold => "threshold",
    }
}

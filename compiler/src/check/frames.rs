//! `frame F = ...`: compliant frames learned from constraints or forces, or written literally
//! (docs/method.md §4).

use super::scope::SkillScope;
use super::signatures::{Function, Produces, Signature};
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, ExprKind};
use crate::diag::Code;
use crate::units::Dim;
use skill_ir as ir;

impl Checker<'_> {
    pub(super) fn frame_source(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::FrameSource> {
        let (name, args) = match &expr.kind {
            ExprKind::Call { name, args } => (name, args),
            ExprKind::Name(name) => {
                let help = suggest(&name.name, Signature::names(Produces::Frame))
                    .map(|s| format!("{s} frames are learned by a call, like `planar(segment 2)`"))
                    .unwrap_or_else(|| {
                        "write a call such as `planar(segment 2)` or `force_aligned(at: peak_force)`".to_string()
                    });
                let code = if Signature::find(Produces::Frame, &name.name).is_some() {
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
        let Some(sig) = Signature::find(Produces::Frame, &name.name) else {
            let functions = Signature::names(Produces::Frame);
            let diag = self
                .diag(
                    Code::UnknownFunction,
                    name.span,
                    format!("unknown frame source `{}`", name.name),
                    "not a frame source",
                )
                .help(
                    suggest(&name.name, functions.iter().copied())
                        .unwrap_or_else(|| format!("frames come from {}", join_ticked(&functions))),
                );
            self.report(diag);
            return None;
        };
        let args = self.bind(sig, expr.span, args);
        match sig.function {
            Function::Model(model) => Some(ir::FrameSource::Constraint {
                segment: self.required_segment(&args, scope)?,
                candidates: vec![model],
            }),
            Function::Constraint => {
                let segment = self.required_segment(&args, scope);
                let models = Signature::constraint_models();
                let candidates = match args.get("models") {
                    None => models.iter().map(|(_, model)| *model).collect(),
                    Some(list) => {
                        let ExprKind::List(items) = &list.kind else {
                            let diag = self
                                .diag(Code::BadArgument, list.span, "`models` must be a list", "not a list")
                                .help("write `models: [planar, cylinder]`");
                            self.report(diag);
                            return None;
                        };
                        let mut chosen = Vec::new();
                        for item in items {
                            chosen.push(self.enum_name(item, "constraint model", &models)?);
                        }
                        if chosen.is_empty() {
                            let diag = self.diag(Code::BadArgument, list.span, "`models` is empty", "no model to fit");
                            self.report(diag);
                            return None;
                        }
                        chosen
                    }
                };
                Some(ir::FrameSource::Constraint {
                    segment: segment?,
                    candidates,
                })
            }
            Function::ForceAligned => match (args.get("segment"), args.get("at")) {
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
                    self.missing(&args, "segment");
                    None
                }
            },
            Function::Fixed => {
                let origin = match args.get("origin") {
                    Some(origin) => self.vector3(origin, Dim::Length, "the origin")?,
                    None => [0.0; 3],
                };
                let rpy = match args.get("rpy") {
                    Some(rpy) => self.vector3(rpy, Dim::Angle, "the roll-pitch-yaw angles")?,
                    None => [0.0; 3],
                };
                Some(ir::FrameSource::Fixed {
                    origin_m: origin,
                    quaternion_wxyz: quaternion_from_rpy(rpy),
                })
            }
            _ => unreachable!("only frame functions produce a frame"),
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_quaternion_matches_known_rotations() {
        let q = quaternion_from_rpy([std::f64::consts::PI, 0.0, 0.0]);
        assert!((q[0]).abs() < 1e-12 && (q[1] - 1.0).abs() < 1e-12);
        let q = quaternion_from_rpy([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q[0] - h).abs() < 1e-12 && (q[3] - h).abs() < 1e-12);
    }
}

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
                let origin_span = args.get("origin").map(|origin| origin.span);
                self.origin_near_base(origin, origin_span.is_some(), origin_span.unwrap_or(expr.span));
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

/// How near the robot base a literal frame's origin may lie before the checker asks whether it
/// was meant \[m\]: the base of an arm is no place for a contact (the LWR-IV's first link alone
/// is 11 cm tall), and an origin written in the tool's or a table's coordinates lands there.
pub(super) const NEAR_BASE_M: f64 = 0.1;

impl Checker<'_> {
    /// `fixed(origin: [0 m, 0 m, 5 cm])`: a literal origin is in the base frame, so one within
    /// [`NEAR_BASE_M`] of the base's origin is most likely meant relative to something else.
    fn origin_near_base(&mut self, origin: [f64; 3], written: bool, span: crate::source::Span) {
        let distance = origin.iter().map(|x| x * x).sum::<f64>().sqrt();
        if distance >= NEAR_BASE_M {
            return;
        }
        let (message, label) = match (written, distance == 0.0) {
            (false, _) => (
                "this frame's origin is the robot base".to_string(),
                "no `origin:`: it defaults to the base's",
            ),
            (true, true) => ("this frame's origin is the robot base".to_string(), "in the base frame"),
            (true, false) => (
                format!("this frame's origin is {:.1} cm from the robot base", distance * 100.0),
                "in the base frame, metres",
            ),
        };
        let diag = self.diag(Code::FrameAtBase, span, message, label).help(
            "a literal frame's origin is in the robot base frame: give where the contact is (the table top, \
                 e.g. `origin: [0.55 m, 0 m, 0.25 m]`), or learn the frame from the demonstration \
                 (`force_aligned(at: end(segment 1))`) to have it at the tool point",
        );
        self.report(diag);
    }
}

/// The base-frame direction of a frame's axis when the checker knows it: `base`'s own axes and
/// a literal `fixed(...)` frame's (`None` for learned frames and `tool`).
pub(super) fn known_direction(
    axis: ir::FrameAxis,
    fixed_frames: &std::collections::HashMap<u32, [f64; 4]>,
) -> Option<[f64; 3]> {
    let unit = match axis.axis {
        ir::Axis::X | ir::Axis::Rx => [1.0, 0.0, 0.0],
        ir::Axis::Y | ir::Axis::Ry => [0.0, 1.0, 0.0],
        ir::Axis::Z | ir::Axis::Rz => [0.0, 0.0, 1.0],
    };
    match axis.frame {
        ir::FrameRef::Base => Some(unit),
        ir::FrameRef::Tool => None,
        ir::FrameRef::Learned(id) => fixed_frames.get(&id.0).map(|q| rotate(*q, unit)),
    }
}

/// `v` rotated by the unit quaternion `[w, x, y, z]`.
fn rotate([w, x, y, z]: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    // v + 2 w (u × v) + 2 u × (u × v), u = (x, y, z).
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let u = [x, y, z];
    let t = cross(u, v);
    let tt = cross(u, t);
    [
        v[0] + 2.0 * (w * t[0] + tt[0]),
        v[1] + 2.0 * (w * t[1] + tt[1]),
        v[2] + 2.0 * (w * t[2] + tt[2]),
    ]
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

    #[test]
    fn a_frame_turned_over_has_its_z_pointing_down() {
        let over = quaternion_from_rpy([std::f64::consts::PI, 0.0, 0.0]);
        let z = rotate(over, [0.0, 0.0, 1.0]);
        assert!((z[2] + 1.0).abs() < 1e-12, "{z:?}");
        let yawed = quaternion_from_rpy([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        let x = rotate(yawed, [1.0, 0.0, 0.0]);
        assert!((x[1] - 1.0).abs() < 1e-12, "{x:?}");
    }
}

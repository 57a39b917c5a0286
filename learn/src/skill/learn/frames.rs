//! Learning a plan's compliant frames: constraint fits, force-aligned frames (per sample or at
//! a point) and literal frames.

use nalgebra::{Isometry3, Vector3};
use skill_ir as ir;

use super::smoothing::{smooth_points, smoothing_window};
use super::{LearnError, Learner, CONTACT_N};
use crate::learn::constraint::{
    fit_constraints, force_aligned_frame_at, force_aligned_frames, CompliantFrame, ConstraintConfig, ConstraintKind,
    ForceFrameConfig,
};
use crate::skill::learned::{ConstraintQuality, FrameKind, FramePose, LearnedFrame, NormalCheck};

/// Per-sample frames are stored every this many seconds.
const FRAME_SAMPLE_PERIOD_S: f64 = 0.01;

/// The friction coefficient the normal check assumes unless told otherwise: a cloth, sponge,
/// rubber or plastic tip on a hard surface ranges from 0.3 to 0.8, and 0.5 bounds the contact
/// force's lean from the surface normal at `atan 0.5 = 26.6°` (docs/method.md §4).
pub const DEFAULT_FRICTION_MU: f64 = 0.5;

impl Learner<'_> {
    pub(super) fn frame(&mut self, decl: &ir::FrameDecl) -> Result<LearnedFrame, LearnError> {
        let demo = self.demo;
        let wrap = |source| LearnError::Frame {
            name: decl.name.clone(),
            source,
        };
        Ok(match &decl.source {
            ir::FrameSource::Constraint { segment, candidates } => {
                let range = self.seg(*segment).range();
                let config = ConstraintConfig::from_candidates(candidates);
                let report = fit_constraints(
                    &demo.position_m[range.clone()],
                    &demo.orientation[range.clone()],
                    &demo.force_n[range],
                    &config,
                )
                .map_err(wrap)?;
                let chosen = report.chosen();
                self.quality.constraints.insert(
                    decl.name.clone(),
                    report
                        .fits
                        .iter()
                        .enumerate()
                        .map(|(index, fit)| ConstraintQuality {
                            kind: fit.kind.into(),
                            residual_m: fit.residual_m,
                            residual_rad: fit.residual_rad,
                            force_agreement: fit.force_agreement,
                            chosen: index == report.best,
                        })
                        .collect(),
                );
                let mut frame = chosen.frame;
                if matches!(chosen.kind, ConstraintKind::Planar | ConstraintKind::PointOnPlane) {
                    if let Some((check, checked)) = self.check_normal(&decl.name, segment.index(), &frame) {
                        frame = checked;
                        self.quality.normals.insert(decl.name.clone(), check);
                    }
                }
                let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                LearnedFrame::Constant(FramePose::from_isometry(chosen.kind.into(), &pose, None))
            }
            ir::FrameSource::ForceAlignedSamples { segment } => {
                let seg = self.seg(*segment);
                let range = seg.range();
                let normal_force = without_friction(
                    &demo.t_s[range.clone()],
                    &demo.position_m[range.clone()],
                    &demo.force_n[range.clone()],
                );
                let frames = force_aligned_frames(&normal_force, &demo.position_m[range], &ForceFrameConfig::default())
                    .map_err(wrap)?;
                let t0 = demo.t_s[seg.start];
                let mut poses = Vec::new();
                let mut next_t = 0.0;
                for (offset, frame) in frames.iter().enumerate() {
                    let t = demo.t_s[seg.start + offset] - t0;
                    if t + 1e-9 >= next_t || offset + 1 == frames.len() {
                        let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                        poses.push(FramePose::from_isometry(FrameKind::ForceAligned, &pose, Some(t)));
                        next_t = t + FRAME_SAMPLE_PERIOD_S;
                    }
                }
                LearnedFrame::Samples(poses)
            }
            ir::FrameSource::ForceAlignedAt { point } => {
                let index = self.point(*point);
                // The force of the first in-contact window, not of one sample: at a contact's
                // onset one sample's force is mostly noise (docs/method.md §4).
                let frame = match super::phases::window_force(demo, self.phases, index) {
                    Some((mean, report)) => {
                        self.quality.onset_frames.insert(decl.name.clone(), report);
                        force_aligned_frame_at(
                            &[mean],
                            &demo.position_m[index..=index],
                            0,
                            &ForceFrameConfig::default(),
                        )
                    }
                    None => {
                        force_aligned_frame_at(&demo.force_n, &demo.position_m, index, &ForceFrameConfig::default())
                    }
                }
                .map_err(wrap)?;
                let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                LearnedFrame::Constant(FramePose::from_isometry(FrameKind::ForceAligned, &pose, None))
            }
            ir::FrameSource::Fixed {
                origin_m,
                quaternion_wxyz,
            } => LearnedFrame::Constant(FramePose {
                kind: FrameKind::Fixed,
                origin: *origin_m,
                quaternion_wxyz: *quaternion_wxyz,
                t_s: None,
            }),
        })
    }
}

impl Learner<'_> {
    /// Checks a fitted plane's normal against the mean applied force over its segment's
    /// samples in contact (docs/method.md §4). Within the friction cone (`atan µ`) the frame is
    /// kept; beyond it the force cannot have come from that surface, and z is replaced by the
    /// direction of the mean applied force without its friction ([`steady_friction`]), x kept
    /// as near as possible. `None` when no sample of the segment is in contact.
    fn check_normal(
        &mut self,
        name: &str,
        segment: usize,
        frame: &CompliantFrame,
    ) -> Option<(NormalCheck, CompliantFrame)> {
        let demo = self.demo;
        let range = self.segments[segment].range();
        let contact: Vec<usize> = range.clone().filter(|&k| demo.force_n[k].norm() >= CONTACT_N).collect();
        if contact.is_empty() {
            return None;
        }
        let applied: Vector3<f64> = -contact.iter().map(|&k| demo.force_n[k]).sum::<Vector3<f64>>();
        let direction = applied.try_normalize(1e-12)?;
        let z = frame.z_axis();
        let angle = z.dot(&direction).clamp(-1.0, 1.0).acos();
        let cone = self.friction_mu.atan();
        let (friction, normal_force) = steady_friction(
            &demo.t_s[range.clone()],
            &demo.position_m[range.clone()],
            &demo.force_n[range.clone()],
        );
        let mut check = NormalCheck {
            segment: segment + 1,
            fitted_z: z.into(),
            force_direction: direction.into(),
            angle_deg: angle.to_degrees(),
            cone_deg: cone.to_degrees(),
            friction,
            replaced: false,
        };
        if angle <= cone {
            return Some((check, *frame));
        }
        let free: Vector3<f64> = -contact
            .iter()
            .map(|&k| normal_force[k - range.start])
            .sum::<Vector3<f64>>();
        let new_z = free.try_normalize(1e-12).unwrap_or(direction);
        let x = frame.x_axis();
        let replaced = match (x - new_z * x.dot(&new_z)).try_normalize(1e-6) {
            Some(new_x) => CompliantFrame::from_axes(frame.origin_m, new_x, new_z.cross(&new_x), new_z),
            None => CompliantFrame::z_aligned(frame.origin_m, &new_z),
        };
        check.replaced = true;
        let v = |a: &Vector3<f64>| format!("[{:+.3}, {:+.3}, {:+.3}]", a.x, a.y, a.z);
        self.warnings.push(format!(
            "frame `{name}`: the normal {} fitted to segment {} is {:.1}° from the mean applied force {} there, outside the friction cone ({:.1}° at µ = {}): a force along it would be {:.0} % short, so z follows the applied force without friction (µ ≈ {friction:.2}) {} instead (if the surface is flat and the forces are suspect, check their frame and sign, or allow more friction with --friction)",
            v(&z),
            segment + 1,
            angle.to_degrees(),
            v(&direction),
            cone.to_degrees(),
            self.friction_mu,
            100.0 * (1.0 - angle.cos()),
            v(&new_z),
        ));
        Some((check, replaced))
    }
}

/// The friction coefficient of a segment and its forces without that friction.
///
/// A surface pushes perpendicular to the motion whatever its shape, and friction pushes
/// against the motion in proportion to the normal force. So where the tool slides (faster than
/// 5 mm/s, force at least 1 N) the force's component along the direction of travel over its
/// component across it estimates −µ; the median over the segment is the steady friction
/// (clamped at 0: a force leaning *along* the motion is not friction, and is kept). The force
/// without friction adds `µ |f⊥| v̂` back to each sliding sample. Unlike removing everything
/// along the motion, this leaves a force that leans sideways (the disagreement the normal
/// check is about) as it is, wherever the path turns.
fn steady_friction(t: &[f64], position: &[Vector3<f64>], force: &[Vector3<f64>]) -> (f64, Vec<Vector3<f64>>) {
    let n = position.len();
    let smoothed = smooth_points(position, smoothing_window(t));
    let direction: Vec<Option<Vector3<f64>>> = (0..n)
        .map(|k| {
            let velocity = central_velocity(t, &smoothed, k);
            (velocity.norm() >= 0.005 && force[k].norm() >= CONTACT_N).then(|| velocity.normalize())
        })
        .collect();
    let mut ratios: Vec<f64> = (0..n)
        .filter_map(|k| {
            let along = direction[k]?;
            let tangential = force[k].dot(&along);
            let across = (force[k] - along * tangential).norm();
            (across > 0.0).then(|| -tangential / across)
        })
        .collect();
    let friction = if ratios.is_empty() {
        0.0
    } else {
        let mid = ratios.len() / 2;
        let (_, median, _) = ratios.select_nth_unstable_by(mid, f64::total_cmp);
        median.max(0.0)
    };
    let free = (0..n)
        .map(|k| match direction[k] {
            Some(along) => {
                let across = (force[k] - along * force[k].dot(&along)).norm();
                force[k] + along * (friction * across)
            }
            None => force[k],
        })
        .collect();
    (friction, free)
}

/// The velocity at sample `k` by central differences of `points` (one-sided at the ends; zero
/// where the time does not advance).
fn central_velocity(t: &[f64], points: &[Vector3<f64>], k: usize) -> Vector3<f64> {
    let n = points.len();
    let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
    let dt = t[b] - t[a];
    if dt > 0.0 {
        (points[b] - points[a]) / dt
    } else {
        Vector3::zeros()
    }
}

/// The measured forces without their component along the direction of motion.
///
/// While sliding, friction tilts the contact force against the motion by up to atan(µ) (17° at
/// µ = 0.3); a frame aligned with the raw force would put its z 17° off the surface normal, and
/// position control along its x would then push into and pull off the surface. Friction acts
/// along the sliding direction, so removing the force component along the (smoothed) velocity
/// leaves the normal force. Where the tool hardly moves (below 5 mm/s) the force is kept as is.
fn without_friction(t: &[f64], position: &[Vector3<f64>], force: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let n = position.len();
    let window = smoothing_window(t);
    let smoothed = smooth_points(position, window);
    (0..n)
        .map(|k| {
            let velocity = central_velocity(t, &smoothed, k);
            let speed = velocity.norm();
            if speed < 0.005 {
                force[k]
            } else {
                let along = velocity / speed;
                force[k] - along * force[k].dot(&along)
            }
        })
        .collect()
}

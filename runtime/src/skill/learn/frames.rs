//! Learning a plan's compliant frames: constraint fits, force-aligned frames (per sample or at
//! a point) and literal frames.

use nalgebra::{Isometry3, Vector3};
use skill_ir as ir;

use super::smoothing::{smooth_points, smoothing_window};
use super::{LearnError, Learner};
use crate::learn::constraint::{
    fit_constraints, force_aligned_frame_at, force_aligned_frames, ConstraintConfig, ForceFrameConfig,
};
use crate::skill::learned::{ConstraintQuality, FrameKind, FramePose, LearnedFrame};

/// Per-sample frames are stored every this many seconds.
const FRAME_SAMPLE_PERIOD_S: f64 = 0.01;

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
                let pose = Isometry3::from_parts(chosen.frame.origin_m.into(), chosen.frame.orientation);
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
                let frame =
                    force_aligned_frame_at(&demo.force_n, &demo.position_m, index, &ForceFrameConfig::default())
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
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            let dt = t[b] - t[a];
            let velocity = if dt > 0.0 {
                (smoothed[b] - smoothed[a]) / dt
            } else {
                Vector3::zeros()
            };
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

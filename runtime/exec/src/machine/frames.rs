//! Compliant frames and axes as they are now: a learned frame at the running motion's time, its
//! origin at the tool point where that is meant, turned onto a followed contact normal.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use skill_ir as ir;

use super::follow::NormalFollow;
use super::Machine;
use crate::rig::Rig;

impl Machine<'_, '_> {
    /// A compliant frame's pose now (origin moved to the tool point where that is meant).
    pub(super) fn frame_pose(&self, frame: ir::FrameRef, rig: &Rig<'_>, t: f64) -> Isometry3<f64> {
        let tool = rig.tool();
        let at_tool = |rotation: UnitQuaternion<f64>| Isometry3::from_parts(tool.translation, rotation);
        match frame {
            ir::FrameRef::Base => at_tool(UnitQuaternion::identity()),
            ir::FrameRef::Tool => tool,
            ir::FrameRef::Learned(id) => {
                let learned = self.bound.frames[id.index()];
                let clock = if self.motion.is_some() {
                    self.motion_clock_s
                } else {
                    self.time_in_state(t)
                };
                let speed = self
                    .motion
                    .as_ref()
                    .map_or(self.overrides.speed_factor, |m| m.rollout.speed);
                let elapsed = match self.frame_segment_order(id.index()) {
                    // A frame per sample of a later segment holds its first pose (the approach
                    // to a contour meets the drum where the contour starts), of an earlier one
                    // its last (the leaving lifts off where the contour ended).
                    Some(std::cmp::Ordering::Less) => 0.0,
                    Some(std::cmp::Ordering::Greater) => f64::INFINITY,
                    _ => self.strokes_demo_time_s().unwrap_or(clock * speed),
                };
                let pose = learned.at(elapsed);
                let rotation = match self.follow {
                    Some(NormalFollow {
                        frame: followed,
                        z: Some(z),
                        ..
                    }) if followed == frame => {
                        let learned_z = pose.rotation * Vector3::z();
                        UnitQuaternion::rotation_between(&learned_z, &z)
                            .map_or(pose.rotation, |turn| turn * pose.rotation)
                    }
                    _ => pose.rotation,
                };
                match learned.kind().origin() {
                    crate::skill::FrameOrigin::Learned => Isometry3::from_parts(pose.translation, rotation),
                    crate::skill::FrameOrigin::AtTool => at_tool(rotation),
                }
            }
        }
    }

    /// For a strokes motion, the demonstration time within its segment the running stroke has
    /// reached \[s\]: the demonstrated strokes before it plus its own progress. Each stroke runs
    /// at its own speed (slowed for the tool speed limit or not), so one clock times them all
    /// wrong; past the demonstrated strokes the runs alternate the last two
    /// ([`crate::skill::LearnedMotion::piece`]) and so do their times. `None` for other motions.
    fn strokes_demo_time_s(&self) -> Option<f64> {
        let motion = self.motion.as_ref()?;
        let strokes = &self.bound.motions[motion.id].strokes;
        let k = strokes.len();
        let index = match k {
            0 => return None,
            1 => 0,
            _ if motion.run < k => motion.run,
            _ => k - 2 + (motion.run - k) % 2,
        };
        let before: f64 = strokes[..index].iter().map(|stroke| stroke.position.tau_s).sum();
        let rollout = &motion.rollout.position;
        let progress = if rollout.tau_s() > 0.0 {
            (rollout.time_s() / rollout.tau_s()).clamp(0.0, 1.0)
        } else {
            1.0
        };
        Some(before + progress * strokes[index].position.tau_s)
    }

    /// Where the current state's motion lies against the segment learned frame `id` was
    /// learned from: `Less` when the motion's segment is earlier, `Equal` when it is that
    /// segment; `None` without a motion or for a frame not learned from a segment.
    fn frame_segment_order(&self, id: usize) -> Option<std::cmp::Ordering> {
        let motion = self.motion.as_ref()?;
        let learn = &self.skill().learn;
        let frame_segment = match &learn.frames.get(id)?.source {
            ir::FrameSource::Constraint { segment, .. } | ir::FrameSource::ForceAlignedSamples { segment } => {
                segment.index()
            }
            _ => return None,
        };
        Some(learn.motions.get(motion.id)?.segment.index().cmp(&frame_segment))
    }

    pub(super) fn axis_vector(&self, along: &ir::FrameAxis, rig: &Rig<'_>) -> Vector3<f64> {
        let rotation = self.frame_pose(along.frame, rig, rig.time_s()).rotation;
        rotation * unit(along.axis)
    }
}

fn unit(axis: ir::Axis) -> Vector3<f64> {
    match axis {
        ir::Axis::X | ir::Axis::Rx => Vector3::x(),
        ir::Axis::Y | ir::Axis::Ry => Vector3::y(),
        ir::Axis::Z | ir::Axis::Rz => Vector3::z(),
    }
}

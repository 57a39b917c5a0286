//! Two ways a state's command departs from its learned motion at a contact: the lift-off of a
//! state that leaves one, and the compliant frame that follows the measured contact normal.

use nalgebra::{UnitQuaternion, Vector3};
use skill_ir as ir;

use super::entry::GUARD_SPEED_MPS;
use super::Machine;
use crate::bind::BoundSkill;
use crate::rig::Rig;

/// A state that leaves a contact with a learned motion first lifts the tool off along the
/// contact normal, with its motion paused, and afterwards never commands the tool back nearer
/// the surface it left than the lift: a learned path that starts with the tail of the
/// demonstrator's push (it does: segments split where the force peaks) would press into the
/// surface again.
#[derive(Debug, Clone, Copy)]
pub(super) struct LiftOff {
    /// Unit direction away from the surface (against the force the tool applied), base frame.
    pub(super) away: Vector3<f64>,
    /// The tool point where the state was entered, base frame.
    pub(super) from: Vector3<f64>,
    /// How far to lift \[m\].
    pub(super) distance_m: f64,
    /// Lift speed \[m/s\].
    pub(super) speed_mps: f64,
    /// Lifted so far \[m\].
    pub(super) done_m: f64,
}

impl LiftOff {
    pub(super) fn lifting(&self) -> bool {
        self.done_m < self.distance_m
    }
}

/// How far a state that leaves a contact lifts off first \[m\]: clear of the surface's
/// compliance and of sensor noise, short enough to cost a fraction of a second.
pub(super) const LIFT_OFF_M: f64 = 0.01;

/// Lift-off speed \[m/s\]: the contact-safe speed.
pub(super) const LIFT_OFF_SPEED_MPS: f64 = GUARD_SPEED_MPS;

/// The compliant frame of a state that moves while it pushes along its z (a contour, a slide, a
/// wipe) follows the contact normal the wrist measures (docs/method.md §7, following the
/// normal): its learned orientation is turned by the smallest rotation that takes its z onto
/// the direction the tool pushes, with the friction taken out along the tool's velocity. A
/// learned frame holds the demonstrated surface's directions, sample by sample; a drum moved
/// 2 cm sideways or a table tilted 8° has other normals under the same path, and force control
/// along a z 10-30° off them leaks the position loop's stiffness into the force.
#[derive(Debug, Clone, Copy)]
pub(super) struct NormalFollow {
    /// The frame followed (the state's compliant frame).
    pub(super) frame: ir::FrameRef,
    /// The estimate: the unit direction the tool pushes the surface along, base frame; `None`
    /// until the state's first command.
    pub(super) z: Option<Vector3<f64>>,
    /// Run time of the last update \[s\].
    pub(super) last_s: f64,
}

/// The time constant of the normal estimate \[s\]: several periods of a hand's 8-12 Hz tremor
/// and of the sensor's noise, a few millimetres of stroke at the shipped 5-10 cm/s.
const FOLLOW_TAU_S: f64 = 0.08;

/// The slowest tool speed at which the normal estimate is updated \[m/s\]: friction acts along
/// the sliding direction only while the tool slides; at a stroke's reversal it may point
/// anywhere in the tangent plane, up to the friction coefficient times the normal force.
pub(super) const FOLLOW_MIN_SPEED_MPS: f64 = 0.01;

/// The least force the tool must push along the estimate for it to be updated \[N\].
pub(super) const FOLLOW_MIN_FORCE_N: f64 = 2.0;

/// The most the followed z may turn away from the learned one \[rad\] (30°): a surface that
/// turns farther is another task, and the estimate is not trusted to lead the frame there.
pub(super) const FOLLOW_MAX_TILT_RAD: f64 = std::f64::consts::FRAC_PI_6;

impl NormalFollow {
    /// The frame a state follows, if it does: a learned frame placed at the tool (its
    /// orientation learned from a surface or a force), of a state with a motion and a desired
    /// force, force-controlled along z and position-controlled along x and y.
    pub(super) fn of(bound: &BoundSkill<'_>, active: &ir::ActiveState, t: f64) -> Option<NormalFollow> {
        active.motion?;
        active.force?;
        let [x, y, z, ..] = active.position_controlled;
        let ir::FrameRef::Learned(id) = active.frame else {
            return None;
        };
        let at_tool = bound.frames[id.index()].kind().origin() == crate::skill::FrameOrigin::AtTool;
        (x && y && !z && at_tool).then_some(NormalFollow {
            frame: active.frame,
            z: None,
            last_s: t,
        })
    }

    /// Updates the estimate at run time `t` from the applied force and the tool's velocity (base
    /// frame), with `learned_z` the learned frame's z now; returns the estimate.
    pub(super) fn update(
        &mut self,
        t: f64,
        applied: &Vector3<f64>,
        velocity: &Vector3<f64>,
        learned_z: &Vector3<f64>,
    ) -> Vector3<f64> {
        let dt = (t - self.last_s).max(0.0);
        self.last_s = t;
        let mut z = self.z.unwrap_or(*learned_z);
        let speed = velocity.norm();
        if applied.dot(&z) > FOLLOW_MIN_FORCE_N && speed > FOLLOW_MIN_SPEED_MPS {
            let sliding = velocity / speed;
            let pushing = applied - sliding * applied.dot(&sliding);
            if let Some(measured) = pushing.try_normalize(1e-9) {
                let alpha = dt / (FOLLOW_TAU_S + dt);
                z = (z + (measured - z) * alpha).try_normalize(1e-12).unwrap_or(z);
            }
        }
        let tilt = learned_z.angle(&z);
        if tilt > FOLLOW_MAX_TILT_RAD {
            if let Some(turn) = UnitQuaternion::rotation_between(learned_z, &z) {
                z = turn.powf(FOLLOW_MAX_TILT_RAD / tilt) * learned_z;
            }
        }
        self.z = Some(z);
        z
    }
}

impl Machine<'_, '_> {
    /// Updates the contact normal the current state's frame follows, if it follows one.
    pub(super) fn follow_normal(&mut self, rig: &Rig<'_>, t: f64) {
        let Some(mut follow) = self.follow else { return };
        // The learned frame's own z now: the estimate is turned from it.
        let learned = NormalFollow { z: None, ..follow };
        self.follow = Some(learned);
        let learned_z = self.frame_pose(follow.frame, rig, t).rotation * Vector3::z();
        let state = rig.controller.state();
        let applied = state.applied.fixed_rows::<3>(0).into_owned();
        let velocity = state.twist.fixed_rows::<3>(0).into_owned();
        follow.update(t, &applied, &velocity, &learned_z);
        self.follow = Some(follow);
    }
}

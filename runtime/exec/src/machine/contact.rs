//! The watch over the contact of a state that pushes while it moves (docs/method.md §7, lost
//! contact): when the force has stayed below half the desired one for too long, mid-stroke.

use nalgebra::Vector3;
use skill_ir as ir;

use super::guards::Sensed;
use super::Machine;
use crate::rig::Rig;

/// How long the force of a state that pushes while it moves may stay below half its desired
/// force before the contact counts as lost \[s\]: the force axis follows a drop of 5 mm in that
/// time at its speed limit (25 mm/s), so a step down or a dip the surface has is not a loss, and
/// a tool that ran off the surface is at most a few millimetres below it when the run stops.
pub(super) const LOST_CONTACT_S: f64 = 0.2;

/// A contact lost within this much of the end of a state's stroke is no failure \[m\]: the
/// motion's remaining path, measured in the directions under position control, from its
/// commanded position to its goal (a slide whose surface ends where the slide does).
pub(super) const LOST_CONTACT_STROKE_M: f64 = 0.005;

/// The applied force above which a state is entered in contact \[N\] (several times the wrist
/// sensor's noise).
pub(super) const IN_CONTACT_N: f64 = 1.0;

/// Whether the contact a pushing, moving state holds has been lost: armed once the applied
/// force along the desired force reaches half of it in the state, it counts the time since the
/// force was last at half the desired force or more. Ticks whose desired force is below
/// [`IN_CONTACT_N`] (a profile that releases) expect no contact and restart the count.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ContactWatch {
    armed: bool,
    /// Run time of the last tick with the force at half the desired force or more \[s\].
    last_held_s: f64,
    /// The tool point then (base frame) \[m\].
    last_held_tool_m: Vector3<f64>,
    /// The motion's stroke left then \[m\] (see [`LOST_CONTACT_STROKE_M`]) and its runs left
    /// after the current one.
    stroke_left_m: f64,
    runs_left: usize,
}

/// A contact lost mid-stroke: when, where and how much of the stroke was left.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LostContact {
    /// Run time at which the loss was confirmed \[s\].
    pub(crate) t_s: f64,
    /// Run time of the last tick in contact \[s\].
    pub(crate) since_s: f64,
    /// The tool point then, where the contact was lost (base frame) \[m\].
    pub(crate) lost_at_m: Vector3<f64>,
    /// The tool point now (base frame) \[m\].
    pub(crate) tool_m: Vector3<f64>,
    /// The stroke left where the contact was lost \[m\], and the runs left after that one.
    pub(crate) stroke_left_m: f64,
    pub(crate) runs_left: usize,
    /// The desired force's magnitude and the applied force along it now \[N\].
    pub(crate) desired_n: f64,
    pub(crate) applied_n: f64,
}

impl Machine<'_, '_> {
    /// Watches the contact of a state that controls a force along a translation while its
    /// motion runs (docs/method.md §7, lost contact): the contact is lost when the applied force
    /// along the desired one has stayed below half of it for longer than [`LOST_CONTACT_S`]
    /// after reaching it in the state, and the motion had more than [`LOST_CONTACT_STROKE_M`]
    /// of its path left, or runs still to make, when it was last in contact. States without a
    /// motion (a press in place), or before the force was first reached, are never judged.
    pub(crate) fn lost_contact(
        &mut self,
        active: &ir::ActiveState,
        sensed: &Sensed,
        rig: &Rig<'_>,
        t: f64,
    ) -> Option<LostContact> {
        let forcing = active.position_controlled[..3].contains(&false);
        let motion = self.motion.as_ref()?;
        let desired_n = self.target_force.norm();
        if !forcing || desired_n < IN_CONTACT_N {
            self.contact.last_held_s = t;
            return None;
        }
        let applied_n = sensed.applied.fixed_rows::<3>(0).dot(&(self.target_force / desired_n));
        if applied_n >= 0.5 * desired_n {
            // The path left in the directions under position control: the force axis's own
            // component is where the surface is, not how far the stroke goes.
            let position = Vector3::from_column_slice(motion.rollout.position.position());
            let goal = Vector3::from_column_slice(motion.rollout.position.goal());
            let left = goal - position;
            let z = self.last_frame_z;
            self.contact = ContactWatch {
                armed: true,
                last_held_s: t,
                last_held_tool_m: rig.tool().translation.vector,
                stroke_left_m: (left - z * left.dot(&z)).norm(),
                runs_left: motion.runs.saturating_sub(motion.run + 1),
            };
            return None;
        }
        let watch = self.contact;
        if !watch.armed || t - watch.last_held_s <= LOST_CONTACT_S {
            return None;
        }
        (watch.runs_left > 0 || watch.stroke_left_m > LOST_CONTACT_STROKE_M).then(|| LostContact {
            t_s: t,
            since_s: watch.last_held_s,
            lost_at_m: watch.last_held_tool_m,
            tool_m: rig.tool().translation.vector,
            stroke_left_m: watch.stroke_left_m,
            runs_left: watch.runs_left,
            desired_n,
            applied_n,
        })
    }
}

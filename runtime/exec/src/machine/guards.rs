//! Guards: what they see this tick ([`Sensed`]), held guards' timers, the evaluation of a guard,
//! and the choice of at most one transition a tick.

use std::collections::HashMap;

use nalgebra::{Vector3, Vector6};
use skill_ir as ir;

use super::{Extension, Machine, RunningMotion};
use crate::control::Command;
use crate::rig::Rig;

/// Where a held guard (`G for D`) sits: the index of its transition and its place in a
/// pre-order walk of that transition's guard. Every guard of the state is walked in full at
/// every evaluation, so the place is the same each time.
pub(super) type HeldKey = (usize, usize);

/// Since when the guard of each held guard (`G for D`) of the current state has held without a
/// break, as run time \[s\]. Cleared when a state is entered, so a hold never counts time from
/// before the state.
#[derive(Debug, Default)]
pub(super) struct HeldTimers {
    since: HashMap<HeldKey, f64>,
}

impl HeldTimers {
    pub(super) fn clear(&mut self) {
        self.since.clear();
    }

    /// Records whether the guard of held guard `key` holds at run time `t`, and returns whether
    /// it has held at every evaluation since at least `duration_s` ago (compared as `dwell` is).
    pub(super) fn update(&mut self, key: HeldKey, holds: bool, t: f64, duration_s: f64) -> bool {
        if !holds {
            self.since.remove(&key);
            return false;
        }
        let since = *self.since.entry(key).or_insert(t);
        t - since >= duration_s
    }
}

/// What guards see this tick.
pub(crate) struct Sensed {
    /// The applied wrench at the tool point, base frame.
    pub(super) applied: Vector6<f64>,
    /// The largest force error over the force-controlled axes (compliant frame), if any.
    pub(super) force_error_max: Option<f64>,
    /// The largest force error over the force-controlled translations \[N\], if any.
    pub(super) force_lag_n: Option<f64>,
}

impl Sensed {
    /// What the rig's controller measured, judged against the last command (if any) with the
    /// state's own desired force (`force_reached` waits for it, not for a force on its ramp).
    pub(crate) fn of(rig: &Rig<'_>, last_cmd: Option<&Command>, target_force: Vector3<f64>) -> Self {
        let applied = rig.controller.state().applied;
        let (force_error_max, force_lag_n) =
            last_cmd.map_or((None, None), |cmd| force_errors(cmd, &target_force, &applied));
        Sensed {
            applied,
            force_error_max,
            force_lag_n,
        }
    }
}

impl Machine<'_, '_> {
    fn scaled_threshold(&self, threshold: ir::Threshold) -> f64 {
        let scale = self.overrides.force_scale;
        match threshold {
            ir::Threshold::Learned { id } => self.bound.thresholds[id.index()] * scale,
            ir::Threshold::Force { id } => self.bound.forces[id.index()].value_n().unwrap_or(0.0) * scale,
            ir::Threshold::Literal { value } => value * scale,
        }
    }

    /// Whether every DMP of the state has run out (and any extension is used up and settled).
    fn motion_done(&self, t: f64) -> bool {
        let motion_finished = self.motion.as_ref().is_none_or(RunningMotion::finished);
        let profile_finished = self.force_profile.as_ref().is_none_or(|p| p.time_s() >= p.tau_s());
        let runs_something = self.motion.is_some() || self.force_profile.is_some();
        let extension_finished = self
            .extension
            .as_ref()
            .is_none_or(|e| e.exhausted_at_s.is_some_and(|at| t - at >= 0.2));
        runs_something && motion_finished && profile_finished && extension_finished
    }

    /// Whether `guard` holds now. `place` is where the next held guard of the transition sits
    /// (see [`HeldKey`]). `and` and `or` evaluate every operand, without short cuts, so that every
    /// held guard sees its guard at every evaluation.
    fn guard(&mut self, guard: &ir::Guard, sensed: &Sensed, rig: &Rig<'_>, t: f64, place: &mut HeldKey) -> bool {
        match guard {
            ir::Guard::And { all } => {
                let mut holds = true;
                for g in all {
                    holds &= self.guard(g, sensed, rig, t, place);
                }
                holds
            }
            ir::Guard::Or { any } => {
                let mut holds = false;
                for g in any {
                    holds |= self.guard(g, sensed, rig, t, place);
                }
                holds
            }
            ir::Guard::Not { guard } => !self.guard(guard, sensed, rig, t, place),
            ir::Guard::Held { guard, duration_s } => {
                let key = *place;
                place.1 += 1;
                let holds = self.guard(guard, sensed, rig, t, place);
                self.hold_timers.update(key, holds, t, *duration_s)
            }
            ir::Guard::Force { along, op, rhs } => {
                let axis = self.axis_vector(along, rig);
                let value = if along.axis.is_rotation() {
                    sensed.applied.fixed_rows::<3>(3).dot(&axis)
                } else {
                    sensed.applied.fixed_rows::<3>(0).dot(&axis)
                };
                op.holds(value, self.scaled_threshold(*rhs))
            }
            ir::Guard::Moved { along, op, value } => {
                let axis = self.axis_vector(along, rig);
                let tool = rig.tool();
                let moved = if along.axis.is_rotation() {
                    (tool.rotation * self.entry_tool.rotation.inverse())
                        .scaled_axis()
                        .dot(&axis)
                } else {
                    (tool.translation.vector - self.entry_tool.translation.vector).dot(&axis)
                };
                op.holds(moved, *value)
            }
            ir::Guard::MovedDistance { op, value_m } => {
                let moved = rig.tool().translation.vector - self.entry_tool.translation.vector;
                op.holds(moved.norm(), *value_m)
            }
            ir::Guard::MovedSince { capture, op, value_m } => self.captures.get(capture).is_some_and(|kept| {
                op.holds(
                    (rig.tool().translation.vector - kept.translation.vector).norm(),
                    *value_m,
                )
            }),
            ir::Guard::ForceMagnitude { op, rhs } => {
                op.holds(sensed.applied.fixed_rows::<3>(0).norm(), self.scaled_threshold(*rhs))
            }
            ir::Guard::MomentMagnitude { op, rhs } => {
                op.holds(sensed.applied.fixed_rows::<3>(3).norm(), self.scaled_threshold(*rhs))
            }
            ir::Guard::Entered { state, op, count } => {
                let entries = self.entries.get(state.index()).copied().unwrap_or(0);
                op.holds(f64::from(entries), f64::from(*count))
            }
            ir::Guard::Speed { op, value_mps } => {
                op.holds(rig.controller.state().twist.fixed_rows::<3>(0).norm(), *value_mps)
            }
            ir::Guard::MotionDone => self.motion_done(t),
            ir::Guard::ForceReached { tolerance_n } => sensed.force_error_max.is_some_and(|e| e <= *tolerance_n),
            ir::Guard::Dwell { duration_s } | ir::Guard::Timeout { duration_s } => self.time_in_state(t) >= *duration_s,
        }
    }

    /// Evaluates the active state's guards in priority order and returns the transition taken
    /// (target state, transition index), if any: at most one a tick. A holding `extend` guard
    /// starts its goal extension instead, and leaves once the extension is used up.
    pub(crate) fn choose(
        &mut self,
        active: &ir::ActiveState,
        sensed: &Sensed,
        rig: &Rig<'_>,
        t: f64,
    ) -> Option<(ir::StateId, usize)> {
        let skill = self.skill();
        // Every guard is evaluated, also after the one that fires, so that held guards see
        // their guards at every tick.
        let mut holds = std::mem::take(&mut self.guard_holds);
        holds.clear();
        for id in &active.transitions {
            let mut place = (id.index(), 0);
            let held = self.guard(&skill.transitions[id.index()].guard, sensed, rig, t, &mut place);
            holds.push(held);
        }
        let mut next = None;
        for (transition_id, &holds) in active.transitions.iter().zip(&holds) {
            let transition = &skill.transitions[transition_id.index()];
            if !holds {
                continue;
            }
            match &transition.action {
                ir::TransitionAction::Goto { target } => {
                    next = Some((*target, transition_id.index()));
                    break;
                }
                ir::TransitionAction::Extend {
                    along,
                    speed_mps,
                    max_m,
                    then,
                } => {
                    match &self.extension {
                        Some(extension) if extension.transition == transition_id.index() => {
                            if extension.exhausted_at_s.is_some() {
                                next = Some((*then, transition_id.index()));
                                break;
                            }
                            // Still extending: this guard holding again changes nothing.
                        }
                        _ => {
                            let axis = self.axis_vector(along, rig);
                            self.extension = Some(Extension {
                                transition: transition_id.index(),
                                axis,
                                speed_mps: speed_mps * self.overrides.speed_factor,
                                max_m: *max_m,
                                done_m: 0.0,
                                exhausted_at_s: None,
                                from_tool: rig.tool().translation.vector,
                            });
                            break;
                        }
                    }
                }
            }
        }
        self.guard_holds = holds;
        if let Some(extension) = &mut self.extension {
            if extension.exhausted_at_s.is_none() && extension.done_m >= extension.max_m {
                extension.exhausted_at_s = Some(t);
            }
        }
        next
    }
}

/// The largest force error over the force-controlled axes of `cmd`, in the compliant frame,
/// against `target_force` (the state's own, before any ramp) and the commanded moments: over all
/// of them, and over the translations only \[N\] (`None` where no such axis is force-controlled).
fn force_errors(cmd: &Command, target_force: &Vector3<f64>, applied: &Vector6<f64>) -> (Option<f64>, Option<f64>) {
    let rotation = cmd.frame.rotation.inverse();
    let desired = (
        rotation * target_force,
        rotation * cmd.wrench.fixed_rows::<3>(3).into_owned(),
    );
    let measured = (
        rotation * applied.fixed_rows::<3>(0).into_owned(),
        rotation * applied.fixed_rows::<3>(3).into_owned(),
    );
    let worst = |axes: std::ops::Range<usize>| {
        axes.filter(|&axis| !cmd.position[axis])
            .map(|axis| {
                if axis < 3 {
                    (desired.0[axis] - measured.0[axis]).abs()
                } else {
                    (desired.1[axis - 3] - measured.1[axis - 3]).abs()
                }
            })
            .reduce(f64::max)
    };
    let forces = worst(0..3);
    let moments = worst(3..6);
    let all = match (forces, moments) {
        (Some(f), Some(m)) => Some(f.max(m)),
        (f, m) => f.or(m),
    };
    (all, forces)
}

//! Entering a state: restarting its motion and force profile from the current pose, its goal
//! offset, lift-off and guarded approach, and its entry actions.

use nalgebra::{Isometry3, Vector3};
use skill_ir as ir;

use super::contact::{ContactWatch, IN_CONTACT_N};
use super::follow::{LiftOff, NormalFollow, LIFT_OFF_M, LIFT_OFF_SPEED_MPS};
use super::{Machine, RunningMotion};
use crate::control::travel::TravelFeedForward;
use crate::dmp::DmpError;
use crate::motion::{motion_start, offset_to_place, start_profile, MotionRollout};
use crate::rig::Rig;
use crate::run::ExecError;
use crate::skill::LearnedForce;

/// How a state that expects contact approaches it: within `zone_m` of its motion's goal (flange
/// positions) the motion's time runs slower, so that the tool moves at most `speed_mps`.
#[derive(Debug, Clone, Copy)]
pub(super) struct GuardedApproach {
    pub(super) zone_m: f64,
    pub(super) speed_mps: f64,
}

/// The contact-safe speed of a guarded approach without a search speed of its own \[m/s\]: the
/// controller's force-axis speed limit, for the same reason (an impact at `v` peaks near `v √(k m)`).
pub(super) const GUARD_SPEED_MPS: f64 = 0.025;

/// How far before the expected contact a guarded approach slows down when the state declares no
/// search range \[m\] (scene changes of a few centimetres).
const GUARD_ZONE_M: f64 = 0.03;

/// The guarded approach of a state with a motion: the one it declares (`approach within D at
/// V`), whatever its guards; otherwise, if it waits for contact (a force guard on one of its
/// transitions, `on watch` guards left out), its search (`extend ... at V, up to D`) gives the speed and the zone, and
/// without one [`GUARD_SPEED_MPS`] within [`GUARD_ZONE_M`].
fn guarded_approach(skill: &ir::Skill, active: &ir::ActiveState) -> Option<GuardedApproach> {
    active.motion?;
    if let Some(declared) = active.approach {
        return Some(GuardedApproach {
            zone_m: declared.within_m,
            speed_mps: declared.speed_mps,
        });
    }
    let mut expects_contact = false;
    let mut search = None;
    for id in &active.transitions {
        let transition = &skill.transitions[id.index()];
        // `on watch ...` looks out for a limit; it expects no contact.
        expects_contact |= !transition.watch && mentions_force(&transition.guard);
        if let ir::TransitionAction::Extend { speed_mps, max_m, .. } = transition.action {
            search = Some(GuardedApproach {
                zone_m: max_m.max(GUARD_ZONE_M),
                speed_mps: speed_mps.min(GUARD_SPEED_MPS),
            });
        }
    }
    expects_contact.then(|| {
        search.unwrap_or(GuardedApproach {
            zone_m: GUARD_ZONE_M,
            speed_mps: GUARD_SPEED_MPS,
        })
    })
}

fn mentions_force(guard: &ir::Guard) -> bool {
    match guard {
        ir::Guard::And { all } => all.iter().any(mentions_force),
        ir::Guard::Or { any } => any.iter().any(mentions_force),
        ir::Guard::Not { guard } | ir::Guard::Held { guard, .. } => mentions_force(guard),
        ir::Guard::Force { .. } | ir::Guard::ForceMagnitude { .. } | ir::Guard::MomentMagnitude { .. } => true,
        _ => false,
    }
}

impl Machine<'_, '_> {
    /// Enters a state at run time `t`: restart its motion from the flange pose, run entry actions.
    pub(crate) fn enter(&mut self, state: ir::StateId, t: f64, rig: &mut Rig<'_>) -> Result<(), ExecError> {
        let was_forcing = self
            .active()
            .is_some_and(|active| active.position_controlled.contains(&false));
        if let Some(extension) = &self.extension {
            let travelled = extension
                .axis
                .dot(&(rig.tool().translation.vector - extension.from_tool));
            self.found_offset += extension.axis * travelled.clamp(0.0, extension.done_m);
        }
        self.state = state;
        if let Some(count) = self.entries.get_mut(state.index()) {
            *count = count.saturating_add(1);
        }
        self.entered_s = t;
        self.extension = None;
        self.motion = None;
        self.force_profile = None;
        self.guarded = None;
        self.motion_clock_s = 0.0;
        self.lift = None;
        self.ramp_from = None;
        self.clock_rate = 1.0;
        self.hold_timers.clear();
        self.contact = ContactWatch::default();
        self.follow = None;
        self.travel = None;
        let flange = rig.flange();
        self.held = flange;
        self.entry_tool = rig.tool();
        let Some(active) = self.active() else { return Ok(()) };
        if let Some(name) = &active.capture {
            if !(active.capture_once && self.captures.contains_key(name)) {
                self.captures.insert(name.clone(), self.entry_tool);
            }
        }
        self.guarded = guarded_approach(self.skill(), active);
        self.follow = NormalFollow::of(self.bound, active, t);
        // Pressing in place along the compliant z: the tool's travel along it is the give of
        // what it presses (a moving state travels along z with the surface's shape too).
        if !active.position_controlled[2] && active.motion.is_none() {
            self.travel = Some(TravelFeedForward::new());
        }
        let applied = rig.controller.state().applied.fixed_rows::<3>(0).into_owned();
        let forcing = active.position_controlled.contains(&false);
        if forcing && !was_forcing {
            self.ramp_from = Some((t, applied));
        }
        // Leaving a contact on a learned path under pure position control: lift off first, away
        // from the force the tool applied or, when a force profile has let it drop to nothing
        // (a press that releases), against the compliant z it was controlled along.
        let in_contact = applied.norm() > IN_CONTACT_N || was_forcing;
        if active.motion.is_some() && !forcing && self.guarded.is_none() && in_contact {
            let away = if applied.norm() > IN_CONTACT_N {
                -applied.normalize()
            } else if self.target_force.norm() > 1e-3 {
                // The force it was asked to push with points into the surface.
                -self.target_force.normalize()
            } else {
                -self.last_frame_z
            };
            // As the state declares (`lift off D at V`, not scaled by the task's speed; `lift
            // off 0 mm` for none), or by default.
            let (distance_m, speed_mps) = match active.lift_off {
                Some(declared) => (declared.distance_m, declared.speed_mps),
                None => (LIFT_OFF_M, LIFT_OFF_SPEED_MPS * self.overrides.speed_factor.min(1.0)),
            };
            if distance_m > 0.0 {
                self.lift = Some(LiftOff {
                    away,
                    from: rig.tool().translation.vector,
                    distance_m,
                    speed_mps,
                    done_m: 0.0,
                });
            }
        }
        let speed = self.overrides.speed_factor;
        if let Some(motion_id) = active.motion {
            let learned = self.bound.motions[motion_id.index()];
            let lever = rig.flange_to_tool().translation.vector.norm();
            let max_speed = rig.limits().tool_speed_mps;
            // `move M relative`: the goal moves by the offset of the entry pose from the
            // motion's demonstrated start. A task step's `goal_offset` is not added again: the
            // entry pose carries it already (the state began where the offset goals led). Other
            // motions move by the step's offset and by what earlier extensions found.
            // `move M at NAME`: the goal moves to where the tool point was captured, and on by
            // `+ OFFSET in FRAME` along that frame's axes as they are at this entry.
            let offset = if let Some(name) = &active.motion_at {
                let shift = active.motion_at_offset.as_ref().map_or_else(Vector3::zeros, |at| {
                    self.frame_pose(at.frame, rig, t).rotation * Vector3::from(at.offset_m)
                });
                self.capture_offset(name, motion_id, rig.flange_to_tool(), shift)?
            } else if active.motion_relative {
                flange.translation.vector - motion_start(learned).translation.vector
            } else {
                Vector3::from(self.overrides.goal_offset_m) + self.found_offset
            };
            let rollout = MotionRollout::start(learned.piece(0), &flange, offset.into(), speed, max_speed, lever)
                .map_err(|err| self.motion_error(&self.skill().learn.motions[motion_id.index()].name, &err))?;
            self.motion = Some(RunningMotion {
                id: motion_id.index(),
                rollout,
                run: 0,
                runs: active.repeat.map_or(learned.default_runs(), |n| n as usize),
                offset,
                speed,
                max_tool_speed_mps: max_speed,
                lever_m: lever,
            });
        }
        if let Some(force_id) = active.force {
            if let LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } = self.bound.forces[force_id.index()] {
                let rollout = start_profile(dmp, speed)
                    .map_err(|err| self.motion_error(&self.skill().learn.forces[force_id.index()].name, &err))?;
                self.force_profile = Some(rollout);
            }
        }
        for action in &active.entry {
            match action {
                ir::EntryAction::ResetIntegral => rig.controller.reset_integral(),
                ir::EntryAction::Tare => {
                    let obs = rig.observation().clone();
                    rig.controller.tare(&obs);
                }
                ir::EntryAction::ShiftGoal { along, distance_m } => {
                    let axis = self.axis_vector(along, rig);
                    let shift = axis * *distance_m;
                    match &mut self.motion {
                        Some(motion) => {
                            motion.offset += shift;
                            motion.rollout.goal += shift;
                            let goal = motion.rollout.goal;
                            let result = motion.rollout.position.set_goal(goal.as_slice());
                            self.check_goal(result)?;
                        }
                        None => self.held.translation.vector += shift,
                    }
                }
            }
        }
        Ok(())
    }

    /// The goal offset that ends motion `motion_id` of the current state at capture `name`; an
    /// error naming the capture and the state when the run has not captured it.
    fn capture_offset(
        &self,
        name: &str,
        motion_id: ir::MotionId,
        flange_to_tool: &Isometry3<f64>,
        shift: Vector3<f64>,
    ) -> Result<Vector3<f64>, ExecError> {
        let motion_name = &self.skill().learn.motions[motion_id.index()].name;
        let Some(pose) = self.captures.get(name) else {
            let capturing: Vec<String> = self
                .skill()
                .states
                .iter()
                .filter(|state| match &state.kind {
                    ir::StateKind::Active(active) => active.capture.as_deref() == Some(name),
                    ir::StateKind::Terminal { .. } => false,
                })
                .map(|state| format!("`{}`", state.name))
                .collect();
            let where_ = match capturing.is_empty() {
                true => "no state captures it".to_string(),
                false => format!("`capture {name}` is in {}, not entered before", capturing.join(", ")),
            };
            return Err(ExecError::NotCaptured {
                state: self.state().name.clone(),
                message: format!(
                    "state `{}` moves `{motion_name}` at `{name}`, but the run has not captured `{name}` ({where_})",
                    self.state().name
                ),
            });
        };
        offset_to_place(
            self.bound.motions[motion_id.index()],
            (pose.translation.vector + shift).into(),
            flange_to_tool,
        )
        .map(Vector3::from)
        .ok_or_else(|| ExecError::Motion {
            state: self.state().name.clone(),
            motion: motion_name.clone(),
            reason: "its goal is not a position to place".to_string(),
        })
    }

    /// The error for a motion or force profile `name` of the current state that could not be set up.
    pub(super) fn motion_error(&self, name: &str, err: &DmpError) -> ExecError {
        ExecError::Motion {
            state: self.state().name.clone(),
            motion: name.to_string(),
            reason: err.to_string(),
        }
    }

    /// Turns a failed goal change of the running motion into an error.
    pub(super) fn check_goal(&self, result: Result<(), DmpError>) -> Result<(), ExecError> {
        result.map_err(|err| {
            let id = self.motion.as_ref().map_or(0, |m| m.id);
            self.motion_error(&self.skill().learn.motions[id].name, &err)
        })
    }
}

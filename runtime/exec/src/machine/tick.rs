//! What an active state does each tick: advance its motion, force profile, extension and
//! lift-off, start the next run of a repeated motion, and build its command for the controller.

use nalgebra::{Vector3, Vector6};
use skill_ir as ir;

use super::guards::Sensed;
use super::profile::{moving_profile_rate, profile_rate, push_only, FORCE_RAMP_S};
use super::Machine;
use crate::control::Command;
use crate::motion::MotionRollout;
use crate::rig::Rig;
use crate::run::ExecError;
use crate::skill::LearnedForce;

impl Machine<'_, '_> {
    /// Advances the DMPs and extension by `dt`; a force profile's clock runs slower while the
    /// applied force lags it (see [`profile_rate`]).
    pub(crate) fn advance(&mut self, dt: f64, sensed: &Sensed) -> Result<(), ExecError> {
        if let Some(extension) = &mut self.extension {
            if extension.exhausted_at_s.is_none() {
                extension.done_m = (extension.done_m + extension.speed_mps * dt).min(extension.max_m);
            }
            let shift = extension.axis * extension.done_m;
            if let Some(motion) = &mut self.motion {
                let goal = motion.rollout.goal + shift;
                let result = motion.rollout.position.set_goal(goal.as_slice());
                self.check_goal(result)?;
            }
        }
        if let Some(lift) = &mut self.lift {
            if lift.lifting() {
                lift.done_m = (lift.done_m + lift.speed_mps * dt).min(lift.distance_m);
                // The motion waits until the tool is off the surface.
                return Ok(());
            }
        }
        if self.motion.as_ref().is_some_and(|m| m.run_finished() && !m.finished()) {
            self.next_run()?;
        }
        if let Some(motion) = &mut self.motion {
            let learned = self.bound.motions[motion.id].piece(motion.run);
            // Guarded approach: near the goal, run the motion's clock slower (a DMP's time
            // scaling), so the desired speed stays at the contact-safe speed.
            // Not during a search: its goal moves at the search speed already.
            let mut step = dt;
            if let (Some(guard), None) = (self.guarded, &self.extension) {
                let position = Vector3::from_column_slice(motion.rollout.position.position());
                let goal = Vector3::from_column_slice(motion.rollout.position.goal());
                motion.rollout.position.velocity_into(&mut self.velocity);
                let speed = Vector3::from(self.velocity).norm();
                if (goal - position).norm() < guard.zone_m && speed > guard.speed_mps {
                    step = dt * guard.speed_mps / speed;
                }
            }
            motion.rollout.step(learned, step);
            self.motion_clock_s += step;
            self.clock_rate = step / dt;
        }
        let profile_dmp =
            self.active()
                .and_then(|active| active.force)
                .and_then(|id| match self.bound.forces[id.index()] {
                    LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } => Some(dmp),
                    _ => None,
                });
        if let (Some(profile), Some(dmp)) = (&mut self.force_profile, profile_dmp) {
            let rate = match self.motion {
                Some(_) => moving_profile_rate(sensed.force_lag_n),
                None => {
                    // The profile's own rate along the compliant z, at full clock.
                    profile.velocity_into(&mut self.force_velocity[..profile.position().len()]);
                    let nominal = match profile.position().len() {
                        1 => self.force_velocity[0],
                        _ => Vector3::from(self.force_velocity).dot(&self.last_frame_z),
                    } * self.overrides.force_scale;
                    let travel = self.travel.as_ref().and_then(|travel| travel.clock_rate(nominal));
                    profile_rate(sensed.force_lag_n).min(travel.unwrap_or(1.0))
                }
            };
            // A profile ends at its duration and holds its last value: past it, without the
            // learned term, a force that dropped steeply would swing on (a contour's 0.6 N end
            // to -22 N) while a guard or a slowed motion keeps the state.
            if profile.time_s() < profile.tau_s() {
                profile.step(dmp, dt * rate);
            }
        }
        Ok(())
    }

    /// Starts the next run of the state's motion where the last one ended (its commanded
    /// flange pose), towards the next piece's goal moved by the offset fixed at entry: runs
    /// chain without a jump and do not drift.
    fn next_run(&mut self) -> Result<(), ExecError> {
        let Some(motion) = &self.motion else { return Ok(()) };
        let learned = self.bound.motions[motion.id];
        let run = motion.run + 1;
        let from = motion.rollout.flange();
        let started = MotionRollout::start(
            learned.piece(run),
            &from,
            motion.offset.into(),
            motion.speed,
            motion.max_tool_speed_mps,
            motion.lever_m,
        );
        let rollout = started.map_err(|err| self.motion_error(&self.skill().learn.motions[motion.id].name, &err))?;
        if let Some(motion) = &mut self.motion {
            motion.rollout = rollout;
            motion.run = run;
        }
        // Each run replays its segment from the start, and its per-sample frames with it (a
        // strokes motion times them by its stroke instead: `strokes_demo_time_s`).
        self.motion_clock_s = 0.0;
        Ok(())
    }

    /// The command of the current (active) state.
    pub(crate) fn command(&mut self, active: &ir::ActiveState, rig: &Rig<'_>, t: f64) -> Command {
        let (flange, flange_v, omega) = match &self.motion {
            Some(motion) => {
                motion.rollout.position.velocity_into(&mut self.velocity);
                // A slowed clock slows the path's velocity too (the feed-forward the
                // controller tracks), not only the path.
                let rate = if self.lift.is_some_and(|lift| lift.lifting()) {
                    0.0
                } else {
                    self.clock_rate
                };
                (
                    motion.rollout.flange(),
                    Vector3::from(self.velocity) * rate,
                    motion.rollout.orientation.angular_velocity() * rate,
                )
            }
            None => {
                let mut held = self.held;
                if let Some(extension) = &self.extension {
                    held.translation.vector += extension.axis * extension.done_m;
                }
                (held, Vector3::zeros(), Vector3::zeros())
            }
        };
        let (mut pose, mut twist) = rig.tool_command(&flange, &flange_v, &omega);
        if let Some(lift) = &self.lift {
            let p = pose.translation.vector;
            let above = (p - lift.from).dot(&lift.away);
            if above < lift.done_m {
                pose.translation.vector += lift.away * (lift.done_m - above);
            }
            if lift.lifting() {
                let v = lift.away * lift.speed_mps;
                twist = Vector6::new(v.x, v.y, v.z, 0.0, 0.0, 0.0);
            }
        }
        self.follow_normal(rig, t);
        let frame = self.frame_pose(active.frame, rig, t);
        let scale = self.overrides.force_scale;
        let z = frame.rotation * Vector3::z();
        self.last_frame_z = z;
        let force = match active.force.map(|id| self.bound.forces[id.index()]) {
            None => Vector3::zeros(),
            Some(LearnedForce::Dmp { .. }) => {
                let p = self.force_profile.as_ref().map_or([0.0; 3], |r| {
                    let x = r.position();
                    [x[0], x[1], x[2]]
                });
                let force = Vector3::from(p) * scale;
                if self.motion.is_none() {
                    push_only(force, &z)
                } else {
                    force
                }
            }
            Some(LearnedForce::Magnitude { .. }) => {
                // A magnitude acts along the compliant z by definition, moving or not: a fit that
                // dips below zero would pull the tool off the surface (a drum's contour, -3.9 N
                // 0.4 s into its follow), so it asks for nothing there instead.
                let force = z * self.force_profile.as_ref().map_or(0.0, |r| r.position()[0]) * scale;
                push_only(force, &z)
            }
            Some(other) => z * other.value_n().unwrap_or(0.0) * scale,
        };
        self.target_force = force;
        // At the switch to force control the desired force ramps from what the tool applied.
        let force = match self.ramp_from {
            Some((t0, from)) if t - t0 < FORCE_RAMP_S => from + (force - from) * ((t - t0) / FORCE_RAMP_S).max(0.0),
            _ => force,
        };
        let force_twist = match &mut self.travel {
            Some(travel) => {
                let applied = rig.controller.state().applied.fixed_rows::<3>(0).dot(&z);
                let desired = force.dot(&z);
                travel.update(t, rig.tool().translation.vector.dot(&z), applied, desired);
                let limit = rig
                    .controller
                    .gains()
                    .force_axis_speed_limit(desired - applied, desired);
                let v = z * travel.velocity(limit);
                travel.set_speed_limit(limit);
                Vector6::new(v.x, v.y, v.z, 0.0, 0.0, 0.0)
            }
            None => Vector6::zeros(),
        };
        Command {
            pose,
            twist,
            wrench: Vector6::new(force.x, force.y, force.z, 0.0, 0.0, 0.0),
            force_twist,
            frame,
            position: active.position_controlled,
            stiffness: active.stiffness,
            kp: active.gains.kp,
            ki: active.gains.ki,
            integral_limit: active.gains.integral_limit_n,
        }
    }
}

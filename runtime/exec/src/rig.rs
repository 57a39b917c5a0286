//! The robot side of a run: the plant and the controller behind one interface that senses,
//! acts and logs a tick, the fixed flange-to-tool transform, and the free-space move to a start
//! pose (pre-positioning) that comes before a skill or a replay.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};

use super::log::{JointValues, RunLog, Tick};
use super::run::{ExecError, ExecOptions};
use crate::control::{Command, HybridController};
use crate::plant::{Observation, Plant};
use crate::robot::RobotError;
use crate::safety::{Limits, SafetyStats, Supervisor, REFLEX_HOLD_S};

/// The contact force that stops pre-positioning \[N\]: well above wrist-sensor noise (0.2 N
/// and a few times that), well below a force that harms a part.
pub(super) const PREPOSE_CONTACT_N: f64 = 5.0;

/// The robot side of a run: plant, controller, and the flange-to-tool transform.
pub struct Rig<'p> {
    /// The plant driven.
    pub plant: &'p mut dyn Plant,
    /// The controller.
    pub controller: HybridController,
    flange_to_tool: Isometry3<f64>,
    supervisor: Supervisor,
    obs: Observation,
    torques: Vec<f64>,
    t_s: f64,
}

impl std::fmt::Debug for Rig<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Rig")
            .field("t_s", &self.t_s)
            .field("flange_to_tool", &self.flange_to_tool)
            .finish()
    }
}

impl<'p> Rig<'p> {
    /// A rig; `flange_link` is the link whose pose demonstrations record.
    pub fn new(plant: &'p mut dyn Plant, controller: HybridController, flange_link: &str) -> Result<Self, RobotError> {
        let robot = controller.robot();
        let flange = robot.require_link(flange_link)?;
        let mut data = robot.data();
        let obs = plant.observe();
        robot.check_dof(obs.q.len())?;
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        let flange_to_tool = robot.link_in_base(&data, flange).inverse() * robot.tool_in_base(&data);
        let torques = vec![0.0; obs.q.len()];
        let supervisor = Supervisor::new(robot, Limits::for_skill(0.0, None));
        Ok(Rig {
            plant,
            controller,
            flange_to_tool,
            supervisor,
            obs,
            torques,
            t_s: 0.0,
        })
    }

    /// Run time so far \[s\].
    pub fn time_s(&self) -> f64 {
        self.t_s
    }

    /// The fixed transform from the flange to the tool point.
    pub fn flange_to_tool(&self) -> &Isometry3<f64> {
        &self.flange_to_tool
    }

    /// The last observation.
    pub fn observation(&self) -> &Observation {
        &self.obs
    }

    /// Sets the supervisor's limits for what runs next (statistics are kept).
    pub fn set_limits(&mut self, limits: Limits) {
        self.supervisor.set_limits(limits);
    }

    /// The limits in force.
    pub fn limits(&self) -> &Limits {
        self.supervisor.limits()
    }

    /// The safety figures since the last [`Rig::reset_safety_stats`].
    pub fn safety_stats(&self) -> &SafetyStats {
        self.supervisor.stats()
    }

    /// Starts the safety figures afresh (one run or task step each).
    pub fn reset_safety_stats(&mut self) {
        self.supervisor.reset_stats();
    }

    pub(super) fn sense(&mut self) {
        self.plant.observe_into(&mut self.obs);
        self.controller.observe(&self.obs);
    }

    pub(super) fn tool(&self) -> Isometry3<f64> {
        self.controller.state().tool
    }

    pub(super) fn flange(&self) -> Isometry3<f64> {
        self.tool() * self.flange_to_tool.inverse()
    }

    /// Computes torques for `cmd`, has the supervisor check the tick, applies them, steps the
    /// plant and logs the tick. A violation is a reflex: the arm is brought to a damped stop for
    /// [`REFLEX_HOLD_S`] (logged as state `reflex`) and [`ExecError::Reflex`] ends the run.
    pub(super) fn act(
        &mut self,
        cmd: &Command,
        state: u32,
        state_name: &str,
        mut log: Option<&mut RunLog>,
        dt: f64,
    ) -> Result<(), ExecError> {
        let torques = self.controller.torques(&self.obs, cmd, dt);
        self.torques.copy_from_slice(torques);
        if let Some(log) = log.as_deref_mut() {
            let tick = tick_record(self.t_s, state, cmd, &self.controller, &self.torques, &self.obs);
            log.record(tick, &*self.plant);
        }
        let checked = self
            .supervisor
            .check(self.t_s, dt, &self.obs, self.controller.state(), cmd, &self.torques);
        if let Err(violation) = checked {
            self.reflex_stop(log, dt)?;
            return Err(ExecError::Reflex {
                state: state_name.to_string(),
                violation: Box::new(violation),
            });
        }
        self.apply_and_step(state_name, dt)
    }

    fn apply_and_step(&mut self, state_name: &str, dt: f64) -> Result<(), ExecError> {
        let t_s = self.t_s;
        let wrap = |source| ExecError::Plant {
            state: state_name.to_string(),
            t_s,
            source,
        };
        self.plant.apply(&self.torques).map_err(wrap)?;
        self.plant.step(dt).map_err(wrap)?;
        self.t_s += dt;
        Ok(())
    }

    /// The reflex: gravity compensation and joint damping for [`REFLEX_HOLD_S`], whatever the
    /// controller wanted. Logged as state `reflex`, the command shown as a hold where the tool is.
    fn reflex_stop(&mut self, mut log: Option<&mut RunLog>, dt: f64) -> Result<(), ExecError> {
        let state = log.as_deref_mut().map_or(0, |log| log.state_index("reflex"));
        let steps = (REFLEX_HOLD_S / dt).round() as usize;
        // A plant across a link holds the stop itself: with the link's delay in the loop the
        // joint damping could ring (the torques below are still computed, applied and logged).
        self.plant.hold_damped_stop();
        for step in 0..steps {
            if step > 0 {
                self.sense();
                self.supervisor.record_stop(self.controller.state());
            }
            self.supervisor.stop_torques(&self.obs, &mut self.torques);
            if let Some(log) = log.as_deref_mut() {
                let tool = self.controller.state().tool;
                let pose = if tool.translation.vector.iter().all(|v| v.is_finite()) {
                    tool
                } else {
                    Isometry3::identity()
                };
                let hold = Command::hold(pose, [0.0; 6]);
                let tick = tick_record(self.t_s, state, &hold, &self.controller, &self.torques, &self.obs);
                log.record(tick, &*self.plant);
            }
            self.apply_and_step("reflex", dt)?;
        }
        self.sense();
        self.supervisor.record_stop(self.controller.state());
        Ok(())
    }

    /// The tool pose and twist commanded for a flange pose and twist.
    pub(super) fn tool_command(
        &self,
        flange: &Isometry3<f64>,
        flange_v: &Vector3<f64>,
        omega: &Vector3<f64>,
    ) -> (Isometry3<f64>, Vector6<f64>) {
        let tool = flange * self.flange_to_tool;
        let lever = flange.rotation * self.flange_to_tool.translation.vector;
        let v = flange_v + omega.cross(&lever);
        (tool, Vector6::new(v.x, v.y, v.z, omega.x, omega.y, omega.z))
    }

    /// Pure impedance control towards `pose` (tool point) with feed-forward `twist`: every axis
    /// position-controlled, the frame at the tool point with the base's axes. Pre-positioning and
    /// the replay baseline command this.
    pub(super) fn impedance_hold(&self, pose: Isometry3<f64>, twist: Vector6<f64>, stiffness: [f64; 6]) -> Command {
        let mut cmd = Command::hold(pose, stiffness);
        cmd.twist = twist;
        cmd.frame = Isometry3::from_parts(self.tool().translation, UnitQuaternion::identity());
        cmd
    }

    /// Moves the flange to `target` in free space along a minimum-jerk path, then holds briefly;
    /// stops and holds where it is when the tool meets something ([`PREPOSE_CONTACT_N`]). The
    /// move's duration is [`prepose_duration`]'s: within the run's speed limits and `--speed`.
    pub(super) fn prepose(
        &mut self,
        target: &Isometry3<f64>,
        options: &ExecOptions,
        log: &mut Option<&mut RunLog>,
    ) -> Result<(), ExecError> {
        self.sense();
        let start = self.flange();
        let distance = (target.translation.vector - start.translation.vector).norm();
        let angle = start.rotation.angle_to(&target.rotation);
        let lever = self.flange_to_tool.translation.vector.norm();
        let duration = prepose_duration(
            distance,
            angle,
            lever,
            options.overrides.speed_factor,
            self.supervisor.limits(),
        );
        let hold = 0.3;
        let state = log.as_mut().map_or(0, |log| log.state_index("prepose"));
        let steps = ((duration + hold) / options.dt_s).round() as usize;
        // A guarded move: something in the way stops it where it is felt, and what runs next
        // starts from there (its first motion runs from the current pose).
        let mut stopped_at: Option<f64> = None;
        for step in 0..steps {
            if step > 0 {
                self.sense();
            }
            let force = self.obs.wrench_base.fixed_rows::<3>(0).norm();
            if stopped_at.is_none() && force > PREPOSE_CONTACT_N {
                stopped_at = Some(step as f64 * options.dt_s);
            }
            if let Some(stop_s) = stopped_at {
                if step as f64 * options.dt_s > stop_s + hold {
                    break;
                }
                let cmd = self.impedance_hold(self.tool(), Vector6::zeros(), options.replay_stiffness);
                self.act(&cmd, state, "prepose", log.as_deref_mut(), options.dt_s)?;
                continue;
            }
            let u = (step as f64 * options.dt_s / duration).min(1.0);
            let s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
            let position = start.translation.vector.lerp(&target.translation.vector, s);
            let rotation = start.rotation.slerp(&target.rotation, s);
            let flange = Isometry3::from_parts(Translation3::from(position), rotation);
            let (pose, _) = self.tool_command(&flange, &Vector3::zeros(), &Vector3::zeros());
            let cmd = self.impedance_hold(pose, Vector6::zeros(), options.replay_stiffness);
            self.act(&cmd, state, "prepose", log.as_deref_mut(), options.dt_s)?;
        }
        Ok(())
    }
}

/// The nominal pre-positioning speeds, m/s and rad/s (times `--speed`), and the shortest and
/// longest nominal move, s.
const PREPOSE_SPEED_MPS: f64 = 0.08;
const PREPOSE_ANGULAR_SPEED_RADPS: f64 = 0.5;
const PREPOSE_NOMINAL_S: (f64, f64) = (1.0, 8.0);
/// The fraction of a speed limit the pre-positioning path may command at its peak: the
/// impedance's tracking lag and the sensor's noise stay well inside the rest.
pub(super) const PREPOSE_LIMIT_FRACTION: f64 = 0.8;
/// A minimum-jerk path of length `d` over `T` peaks at `15/8 d / T`.
const MIN_JERK_PEAK: f64 = 1.875;

/// How long the pre-positioning move of the flange over `distance_m` and `angle_rad` takes, s:
/// the nominal 8 cm/s and 0.5 rad/s (between 1 and 8 s) slowed by `speed_factor` (`--speed`,
/// a task's speed), and never so short that the minimum-jerk path's peak exceeds
/// [`PREPOSE_LIMIT_FRACTION`] of the run's limits on the tool point's speed (the flange's plus
/// the turn on the `lever_m` from flange to tool point) or angular speed.
pub(super) fn prepose_duration(
    distance_m: f64,
    angle_rad: f64,
    lever_m: f64,
    speed_factor: f64,
    limits: &Limits,
) -> f64 {
    let factor = if speed_factor.is_finite() && speed_factor > 0.0 {
        speed_factor
    } else {
        1.0
    };
    let nominal = (distance_m / PREPOSE_SPEED_MPS)
        .max(angle_rad / PREPOSE_ANGULAR_SPEED_RADPS)
        .clamp(PREPOSE_NOMINAL_S.0, PREPOSE_NOMINAL_S.1)
        / factor;
    let within = |length: f64, limit: f64| {
        let duration = MIN_JERK_PEAK * length / (PREPOSE_LIMIT_FRACTION * limit);
        if duration.is_finite() {
            duration
        } else {
            0.0
        }
    };
    nominal
        .max(within(distance_m + angle_rad * lever_m, limits.tool_speed_mps))
        .max(within(angle_rad, limits.tool_angular_speed_radps))
}

fn tick_record(
    t_s: f64,
    state: u32,
    cmd: &Command,
    controller: &HybridController,
    torques: &[f64],
    obs: &Observation,
) -> Tick {
    let measured = &controller.state().tool;
    let pose7 = |pose: &Isometry3<f64>| {
        let q = pose.rotation.quaternion();
        let p = pose.translation.vector;
        [p.x, p.y, p.z, q.w, q.i, q.j, q.k]
    };
    let rotation_inv = cmd.frame.rotation.inverse();
    let in_frame = |w: &Vector6<f64>| {
        let f = rotation_inv * w.fixed_rows::<3>(0).into_owned();
        let m = rotation_inv * w.fixed_rows::<3>(3).into_owned();
        [f.x, f.y, f.z, m.x, m.y, m.z]
    };
    let applied = controller.state().applied;
    let mut desired_cf = in_frame(&cmd.wrench);
    let mut selection = 0u8;
    for (axis, position) in cmd.position.iter().enumerate() {
        if *position {
            selection |= 1 << axis;
            desired_cf[axis] = 0.0;
        }
    }
    let frame = cmd.frame.rotation.quaternion();
    Tick {
        t_s,
        state,
        desired: pose7(&cmd.pose),
        measured: pose7(measured),
        wrench_base: [applied[0], applied[1], applied[2], applied[3], applied[4], applied[5]],
        wrench_cf: in_frame(&applied),
        desired_cf,
        frame: [frame.w, frame.i, frame.j, frame.k],
        selection,
        torques: JointValues::from_slices(&[torques]),
        joint_state: JointValues::from_slices(&[obs.q.as_slice(), obs.qd.as_slice()]),
    }
}

//! The tick loop: state machine, DMPs, command assembly, controller, plant.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use skill_ir as ir;

use super::bind::BoundSkill;
use super::log::{RunLog, Tick};
use crate::control::{Command, HybridController};
use crate::dmp::{DmpRollout, QuatRollout};
use crate::plant::{Observation, Plant, PlantError};
use crate::robot::RobotError;
use crate::skill::{Learned, LearnedForce};

/// How a run is carried out.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecOptions {
    /// Control period \[s\] (1 ms, as on the LWR's fast research interface).
    pub dt_s: f64,
    /// A run longer than this fails \[s\].
    pub max_duration_s: f64,
    /// Task overrides (force scale, speed, goal offset).
    pub overrides: ir::Overrides,
    /// First move to the demonstration's start pose in free space, as an operator would.
    pub prepose: bool,
    /// Record every tick.
    pub log: bool,
    /// Stiffness of the replay baseline and of the pre-positioning move, per axis (N/m, N m/rad).
    pub replay_stiffness: [f64; 6],
}

impl Default for ExecOptions {
    fn default() -> Self {
        ExecOptions {
            dt_s: 0.001,
            max_duration_s: 120.0,
            overrides: ir::Overrides::default(),
            prepose: true,
            log: true,
            replay_stiffness: [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0],
        }
    }
}

/// Why a run could not go on (a skill reaching a failure state is not an error).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExecError {
    /// The plant failed (e.g. its state became NaN).
    #[error("the plant failed in state `{state}` at t = {t_s:.3} s")]
    Plant {
        /// The state.
        state: String,
        /// Run time.
        t_s: f64,
        /// Why.
        #[source]
        source: PlantError,
    },
    /// The robot model does not fit the run.
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// A DMP could not be set up (non-finite goal or start).
    #[error("cannot start motion `{motion}` in state `{state}`: {reason}")]
    Motion {
        /// The state.
        state: String,
        /// The motion.
        motion: String,
        /// Why.
        reason: String,
    },
}

/// A time in one state.
#[derive(Debug, Clone, PartialEq)]
pub struct Visit {
    /// The state's name.
    pub state: String,
    /// Entry \[s\].
    pub enter_s: f64,
    /// Exit \[s\].
    pub exit_s: f64,
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct RunReport {
    /// Success or failure.
    pub outcome: ir::Outcome,
    /// The terminal state reached, if any.
    pub terminal: Option<String>,
    /// A message for the user (for failures: the state, the guard and where it is written).
    pub message: String,
    /// States in the order visited.
    pub visits: Vec<Visit>,
    /// Run time \[s\].
    pub duration_s: f64,
}

/// The robot side of a run: plant, controller, and the flange-to-tool transform.
pub struct Rig<'p> {
    /// The plant driven.
    pub plant: &'p mut dyn Plant,
    /// The controller.
    pub controller: HybridController,
    flange_to_tool: Isometry3<f64>,
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
        Ok(Rig {
            plant,
            controller,
            flange_to_tool,
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

    fn sense(&mut self) {
        self.plant.observe_into(&mut self.obs);
        self.controller.observe(&self.obs);
    }

    fn tool(&self) -> Isometry3<f64> {
        self.controller.state().tool
    }

    fn flange(&self) -> Isometry3<f64> {
        self.tool() * self.flange_to_tool.inverse()
    }

    /// Computes and applies torques for `cmd`, steps the plant, and logs the tick.
    fn act(
        &mut self,
        cmd: &Command,
        state: u32,
        state_name: &str,
        log: Option<&mut RunLog>,
        dt: f64,
    ) -> Result<(), ExecError> {
        let torques = self.controller.torques(&self.obs, cmd, dt);
        self.torques.copy_from_slice(torques);
        if let Some(log) = log {
            log.ticks
                .push(tick_record(self.t_s, state, cmd, &self.controller, &self.torques));
        }
        let wrap = |source| ExecError::Plant {
            state: state_name.to_string(),
            t_s: self.t_s,
            source,
        };
        self.plant.apply(&self.torques).map_err(wrap)?;
        self.plant.step(dt).map_err(|source| ExecError::Plant {
            state: state_name.to_string(),
            t_s: self.t_s,
            source,
        })?;
        self.t_s += dt;
        Ok(())
    }

    /// The tool pose and twist commanded for a flange pose and twist.
    fn tool_command(
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

    /// Moves the flange to `target` in free space along a minimum-jerk path, then holds briefly.
    fn prepose(
        &mut self,
        target: &Isometry3<f64>,
        options: &ExecOptions,
        log: &mut Option<&mut RunLog>,
    ) -> Result<(), ExecError> {
        self.sense();
        let start = self.flange();
        let distance = (target.translation.vector - start.translation.vector).norm();
        let angle = start.rotation.angle_to(&target.rotation);
        let duration = (distance / 0.08).max(angle / 0.5).clamp(1.0, 8.0);
        let hold = 0.3;
        let state = log.as_mut().map_or(0, |log| log.state_index("prepose"));
        let steps = ((duration + hold) / options.dt_s).round() as usize;
        for step in 0..steps {
            if step > 0 {
                self.sense();
            }
            let u = (step as f64 * options.dt_s / duration).min(1.0);
            let s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
            let position = start.translation.vector.lerp(&target.translation.vector, s);
            let rotation = start.rotation.slerp(&target.rotation, s);
            let flange = Isometry3::from_parts(Translation3::from(position), rotation);
            let (pose, _) = self.tool_command(&flange, &Vector3::zeros(), &Vector3::zeros());
            let mut cmd = Command::hold(pose, options.replay_stiffness);
            cmd.frame = Isometry3::from_parts(self.tool().translation, UnitQuaternion::identity());
            self.act(&cmd, state, "prepose", log.as_deref_mut(), options.dt_s)?;
        }
        Ok(())
    }
}

fn tick_record(t_s: f64, state: u32, cmd: &Command, controller: &HybridController, torques: &[f64]) -> Tick {
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
    let z = cmd.frame.rotation * Vector3::z();
    Tick {
        t_s,
        state,
        desired: pose7(&cmd.pose),
        measured: pose7(measured),
        wrench_base: [applied[0], applied[1], applied[2], applied[3], applied[4], applied[5]],
        wrench_cf: in_frame(&applied),
        desired_cf,
        frame_z: [z.x, z.y, z.z],
        selection,
        torques: torques.to_vec(),
    }
}

/// The flange pose at the start of a learned motion.
fn motion_start(motion: &crate::skill::LearnedMotion) -> Isometry3<f64> {
    let p = &motion.position.start;
    Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), motion.orientation.start)
}

/// The learned motions in segment order.
fn motions_in_order(learned: &Learned) -> Vec<(&String, &crate::skill::LearnedMotion)> {
    let mut order: Vec<_> = learned.motions.iter().collect();
    order.sort_by_key(|(name, motion)| (motion.segment, (*name).clone()));
    order
}

/// A running motion: position and orientation rollouts.
struct RunningMotion {
    id: usize,
    position: DmpRollout,
    orientation: QuatRollout,
    goal: Vector3<f64>,
}

/// A running goal extension (touch/press case II).
struct Extension {
    transition: usize,
    axis: Vector3<f64>,
    speed_mps: f64,
    max_m: f64,
    done_m: f64,
    exhausted_at_s: Option<f64>,
}

/// The state of the machine between ticks.
struct Machine<'b, 'a> {
    bound: &'b BoundSkill<'a>,
    overrides: ir::Overrides,
    state: ir::StateId,
    entered_s: f64,
    held: Isometry3<f64>,
    motion: Option<RunningMotion>,
    force_profile: Option<DmpRollout>,
    extension: Option<Extension>,
    velocity: [f64; 3],
}

/// What guards see this tick.
struct Sensed {
    /// The applied wrench at the tool point, base frame.
    applied: Vector6<f64>,
    /// The largest force error over the force-controlled axes (compliant frame), if any.
    force_error_max: Option<f64>,
}

impl<'b, 'a> Machine<'b, 'a> {
    fn skill(&self) -> &'a ir::Skill {
        self.bound.skill
    }

    fn active(&self) -> Option<&'a ir::ActiveState> {
        match &self.skill().states[self.state.index()].kind {
            ir::StateKind::Active(active) => Some(active),
            ir::StateKind::Terminal { .. } => None,
        }
    }

    /// Enters a state at run time `t`: restart its motion from the flange pose, run entry actions.
    fn enter(&mut self, state: ir::StateId, t: f64, rig: &mut Rig<'_>) -> Result<(), ExecError> {
        self.state = state;
        self.entered_s = t;
        self.extension = None;
        self.motion = None;
        self.force_profile = None;
        let flange = rig.flange();
        self.held = flange;
        let Some(active) = self.active() else { return Ok(()) };
        let name = &self.skill().states[state.index()].name;
        let speed = self.overrides.speed_factor;
        if let Some(motion_id) = active.motion {
            let learned = self.bound.motions[motion_id.index()];
            let motion_name = self.skill().learn.motions[motion_id.index()].name.clone();
            let fail = |reason: String| ExecError::Motion {
                state: name.clone(),
                motion: motion_name.clone(),
                reason,
            };
            let mut position = learned.position.rollout();
            let mut orientation = learned.orientation.rollout();
            let p = flange.translation.vector;
            position.restart_from(p.as_slice()).map_err(|e| fail(e.to_string()))?;
            orientation.restart_from(flange.rotation);
            let offset = Vector3::from(self.overrides.goal_offset_m);
            let goal = Vector3::from_column_slice(&learned.position.goal) + offset;
            position.set_goal(goal.as_slice()).map_err(|e| fail(e.to_string()))?;
            position
                .set_tau(learned.position.tau_s / speed)
                .map_err(|e| fail(e.to_string()))?;
            orientation
                .set_tau(learned.orientation.tau_s / speed)
                .map_err(|e| fail(e.to_string()))?;
            self.motion = Some(RunningMotion {
                id: motion_id.index(),
                position,
                orientation,
                goal,
            });
        }
        if let Some(force_id) = active.force {
            if let LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } = self.bound.forces[force_id.index()] {
                let mut rollout = dmp.rollout();
                // Tau changes cannot fail for a positive duration divided by a positive factor.
                let _ = rollout.set_tau(dmp.tau_s / speed);
                self.force_profile = Some(rollout);
            }
        }
        for action in &active.entry {
            match action {
                ir::EntryAction::ResetIntegral => rig.controller.reset_integral(),
                ir::EntryAction::Tare => {
                    let obs = rig.obs.clone();
                    rig.controller.tare(&obs);
                }
                ir::EntryAction::ShiftGoal { along, distance_m } => {
                    let axis = self.axis_vector(along, rig);
                    let shift = axis * *distance_m;
                    match &mut self.motion {
                        Some(motion) => {
                            motion.goal += shift;
                            let goal = motion.goal;
                            let _ = motion.position.set_goal(goal.as_slice());
                        }
                        None => self.held.translation.vector += shift,
                    }
                }
            }
        }
        Ok(())
    }

    fn time_in_state(&self, t: f64) -> f64 {
        t - self.entered_s
    }

    /// A compliant frame's pose now (origin moved to the tool point where that is meant).
    fn frame_pose(&self, frame: ir::FrameRef, rig: &Rig<'_>, t: f64) -> Isometry3<f64> {
        let tool = rig.tool();
        let at_tool = |rotation: UnitQuaternion<f64>| Isometry3::from_parts(tool.translation, rotation);
        match frame {
            ir::FrameRef::Base => at_tool(UnitQuaternion::identity()),
            ir::FrameRef::Tool => tool,
            ir::FrameRef::Learned(id) => {
                let learned = self.bound.frames[id.index()];
                let elapsed = self.time_in_state(t) * self.overrides.speed_factor;
                let pose = learned.at(elapsed);
                match learned.kind() {
                    "fixed_point" | "axial_rotation" | "fixed" => pose,
                    _ => at_tool(pose.rotation),
                }
            }
        }
    }

    fn axis_vector(&self, along: &ir::FrameAxis, rig: &Rig<'_>) -> Vector3<f64> {
        let rotation = self.frame_pose(along.frame, rig, rig.t_s).rotation;
        rotation * unit(along.axis)
    }

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
        let motion_finished = self
            .motion
            .as_ref()
            .is_none_or(|m| m.position.time_s() >= m.position.tau_s());
        let profile_finished = self.force_profile.as_ref().is_none_or(|p| p.time_s() >= p.tau_s());
        let runs_something = self.motion.is_some() || self.force_profile.is_some();
        let extension_finished = self
            .extension
            .as_ref()
            .is_none_or(|e| e.exhausted_at_s.is_some_and(|at| t - at >= 0.2));
        runs_something && motion_finished && profile_finished && extension_finished
    }

    fn guard(&self, guard: &ir::Guard, sensed: &Sensed, rig: &Rig<'_>, t: f64) -> bool {
        match guard {
            ir::Guard::And { all } => all.iter().all(|g| self.guard(g, sensed, rig, t)),
            ir::Guard::Or { any } => any.iter().any(|g| self.guard(g, sensed, rig, t)),
            ir::Guard::Not { guard } => !self.guard(guard, sensed, rig, t),
            ir::Guard::Force { along, op, rhs } => {
                let axis = self.axis_vector(along, rig);
                let value = if along.axis.is_rotation() {
                    sensed.applied.fixed_rows::<3>(3).dot(&axis)
                } else {
                    sensed.applied.fixed_rows::<3>(0).dot(&axis)
                };
                op.holds(value, self.scaled_threshold(*rhs))
            }
            ir::Guard::MotionDone => self.motion_done(t),
            ir::Guard::ForceReached { tolerance_n } => sensed.force_error_max.is_some_and(|e| e <= *tolerance_n),
            ir::Guard::Dwell { duration_s } | ir::Guard::Timeout { duration_s } => self.time_in_state(t) >= *duration_s,
        }
    }

    /// Advances the DMPs and extension by `dt`.
    fn advance(&mut self, dt: f64) {
        if let Some(extension) = &mut self.extension {
            if extension.exhausted_at_s.is_none() {
                extension.done_m = (extension.done_m + extension.speed_mps * dt).min(extension.max_m);
            }
            let shift = extension.axis * extension.done_m;
            if let Some(motion) = &mut self.motion {
                let goal = motion.goal + shift;
                let _ = motion.position.set_goal(goal.as_slice());
            }
        }
        if let Some(motion) = &mut self.motion {
            let learned = self.bound.motions[motion.id];
            motion.position.step(&learned.position, dt);
            motion.orientation.step(&learned.orientation, dt);
        }
        let profile_dmp =
            self.active()
                .and_then(|active| active.force)
                .and_then(|id| match self.bound.forces[id.index()] {
                    LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } => Some(dmp),
                    _ => None,
                });
        if let (Some(profile), Some(dmp)) = (&mut self.force_profile, profile_dmp) {
            profile.step(dmp, dt);
        }
    }

    /// The command of the current (active) state.
    fn command(&mut self, active: &ir::ActiveState, rig: &Rig<'_>, t: f64) -> Command {
        let (flange, flange_v, omega) = match &self.motion {
            Some(motion) => {
                let p = Vector3::from_column_slice(motion.position.position());
                motion.position.velocity_into(&mut self.velocity);
                (
                    Isometry3::from_parts(Translation3::from(p), motion.orientation.orientation()),
                    Vector3::from(self.velocity),
                    motion.orientation.angular_velocity(),
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
        let (pose, twist) = rig.tool_command(&flange, &flange_v, &omega);
        let frame = self.frame_pose(active.frame, rig, t);
        let scale = self.overrides.force_scale;
        let z = frame.rotation * Vector3::z();
        let force = match active.force.map(|id| self.bound.forces[id.index()]) {
            None => Vector3::zeros(),
            Some(LearnedForce::Dmp { .. }) => {
                let p = self.force_profile.as_ref().map_or([0.0; 3], |r| {
                    let x = r.position();
                    [x[0], x[1], x[2]]
                });
                Vector3::from(p) * scale
            }
            Some(LearnedForce::Magnitude { .. }) => {
                z * self.force_profile.as_ref().map_or(0.0, |r| r.position()[0]) * scale
            }
            Some(other) => z * other.value_n().unwrap_or(0.0) * scale,
        };
        Command {
            pose,
            twist,
            wrench: Vector6::new(force.x, force.y, force.z, 0.0, 0.0, 0.0),
            frame,
            position: active.position_controlled,
            stiffness: active.stiffness,
            kp: active.gains.kp,
            ki: active.gains.ki,
            integral_limit: active.gains.integral_limit_n,
        }
    }
}

fn unit(axis: ir::Axis) -> Vector3<f64> {
    match axis {
        ir::Axis::X | ir::Axis::Rx => Vector3::x(),
        ir::Axis::Y | ir::Axis::Ry => Vector3::y(),
        ir::Axis::Z | ir::Axis::Rz => Vector3::z(),
    }
}

/// The largest force error over the force-controlled axes, in the compliant frame.
fn force_error(cmd: &Command, applied: &Vector6<f64>) -> Option<f64> {
    let rotation = cmd.frame.rotation.inverse();
    let desired = (
        rotation * cmd.wrench.fixed_rows::<3>(0).into_owned(),
        rotation * cmd.wrench.fixed_rows::<3>(3).into_owned(),
    );
    let measured = (
        rotation * applied.fixed_rows::<3>(0).into_owned(),
        rotation * applied.fixed_rows::<3>(3).into_owned(),
    );
    let mut worst: Option<f64> = None;
    for axis in 0..6 {
        if cmd.position[axis] {
            continue;
        }
        let error = if axis < 3 {
            desired.0[axis] - measured.0[axis]
        } else {
            desired.1[axis - 3] - measured.1[axis - 3]
        };
        worst = Some(worst.map_or(error.abs(), |w: f64| w.max(error.abs())));
    }
    worst
}

fn location(span: &ir::SourceSpan) -> String {
    format!("{}:{}:{}", span.file, span.line, span.column)
}

/// Runs a bound skill on a rig until a terminal state (or the time limit).
pub fn run_skill(
    bound: &BoundSkill<'_>,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    mut log: Option<&mut RunLog>,
) -> Result<RunReport, ExecError> {
    let skill = bound.skill;
    let start_s = rig.t_s;
    if options.prepose {
        if let Some((_, first)) = motions_in_order(bound.learned).first() {
            let mut target = motion_start(first);
            target.translation.vector += Vector3::from(options.overrides.goal_offset_m);
            rig.prepose(&target, options, &mut log)?;
        }
    }
    let run_start = rig.t_s;
    rig.sense();
    let mut machine = Machine {
        bound,
        overrides: options.overrides,
        state: skill.initial,
        entered_s: rig.t_s,
        held: rig.flange(),
        motion: None,
        force_profile: None,
        extension: None,
        velocity: [0.0; 3],
    };
    machine.enter(skill.initial, rig.t_s, rig)?;
    let mut visits = vec![Visit {
        state: skill.states[skill.initial.index()].name.clone(),
        enter_s: rig.t_s - start_s,
        exit_s: 0.0,
    }];
    let mut last_cmd: Option<Command> = None;
    let dt = options.dt_s;
    loop {
        let t = rig.t_s;
        let state = &skill.states[machine.state.index()];
        if let ir::StateKind::Terminal { outcome, message } = &state.kind {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            let text = message.clone().unwrap_or_else(|| match outcome {
                ir::Outcome::Success => format!("reached `{}`", state.name),
                ir::Outcome::Failure => format!("ended in failure state `{}`", state.name),
            });
            return Ok(RunReport {
                outcome: *outcome,
                terminal: Some(state.name.clone()),
                message: text,
                visits,
                duration_s: t - start_s,
            });
        }
        if t - run_start > options.max_duration_s {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            return Ok(RunReport {
                outcome: ir::Outcome::Failure,
                terminal: None,
                message: format!(
                    "the run exceeded {:.0} s in state `{}` ({})",
                    options.max_duration_s,
                    state.name,
                    location(&state.span)
                ),
                visits,
                duration_s: t - start_s,
            });
        }
        let active = machine.active().expect("terminal states returned above");
        let sensed = Sensed {
            applied: rig.controller.state().applied,
            force_error_max: last_cmd
                .as_ref()
                .and_then(|cmd| force_error(cmd, &rig.controller.state().applied)),
        };

        // At most one transition per tick, in priority order.
        let mut next: Option<(ir::StateId, usize)> = None;
        for transition_id in &active.transitions {
            let transition = &skill.transitions[transition_id.index()];
            if !machine.guard(&transition.guard, &sensed, rig, t) {
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
                    match &machine.extension {
                        Some(extension) if extension.transition == transition_id.index() => {
                            if extension.exhausted_at_s.is_some() {
                                next = Some((*then, transition_id.index()));
                                break;
                            }
                            // Still extending: this guard holding again changes nothing.
                        }
                        _ => {
                            let axis = machine.axis_vector(along, rig);
                            machine.extension = Some(Extension {
                                transition: transition_id.index(),
                                axis,
                                speed_mps: speed_mps * options.overrides.speed_factor,
                                max_m: *max_m,
                                done_m: 0.0,
                                exhausted_at_s: None,
                            });
                            break;
                        }
                    }
                }
            }
        }
        if let Some(extension) = &mut machine.extension {
            if extension.exhausted_at_s.is_none() && extension.done_m >= extension.max_m {
                extension.exhausted_at_s = Some(t);
            }
        }
        if let Some((target, transition)) = next {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            let transition = &skill.transitions[transition];
            visits.push(Visit {
                state: skill.states[target.index()].name.clone(),
                enter_s: t - start_s,
                exit_s: 0.0,
            });
            machine.enter(target, t, rig)?;
            if let ir::StateKind::Terminal {
                outcome: ir::Outcome::Failure,
                message,
            } = &skill.states[target.index()].kind
            {
                let from = &skill.states[transition.from.index()].name;
                let why = message
                    .clone()
                    .unwrap_or_else(|| format!("ended in failure state `{}`", skill.states[target.index()].name));
                let timed_out = matches!(transition.guard, ir::Guard::Timeout { .. });
                let text = format!(
                    "{why}: {} `on {}` in state `{from}` ({})",
                    if timed_out { "timed out on" } else { "left by" },
                    transition.guard_text,
                    location(&transition.span)
                );
                return Ok(RunReport {
                    outcome: ir::Outcome::Failure,
                    terminal: Some(skill.states[target.index()].name.clone()),
                    message: text,
                    visits,
                    duration_s: t - start_s,
                });
            }
            continue;
        }

        machine.advance(dt);
        let cmd = machine.command(active, rig, t);
        let state_index = log.as_mut().map_or(0, |log| log.state_index(&state.name));
        rig.act(&cmd, state_index, &state.name, log.as_deref_mut(), dt)?;
        rig.sense();
        last_cmd = Some(cmd);
    }
}

/// The thesis's baseline: the demonstration replayed under pure impedance control, with no
/// force control and no contact adaptation. Segments run in order: a segment with a learned
/// motion replays it from the current pose; a segment without one (e.g. the press itself)
/// holds the pose for the segment's duration, as the demonstration did.
pub fn run_replay(
    learned: &Learned,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    mut log: Option<&mut RunLog>,
) -> Result<RunReport, ExecError> {
    let start_s = rig.t_s;
    let order = motions_in_order(learned);
    if options.prepose {
        if let Some((_, first)) = order.first() {
            let mut target = motion_start(first);
            target.translation.vector += Vector3::from(options.overrides.goal_offset_m);
            rig.prepose(&target, options, &mut log)?;
        }
    }
    let mut visits = Vec::new();
    let dt = options.dt_s;
    let speed = options.overrides.speed_factor;
    let mut velocity = [0.0; 3];
    rig.sense();
    let mut held = rig.flange();
    for (segment_index, segment) in learned.segments.iter().enumerate() {
        let motion = order.iter().find(|(_, motion)| motion.segment == segment_index);
        let state_name = match motion {
            Some((name, _)) => format!("replay:{name}"),
            None => format!("replay:segment {}", segment_index + 1),
        };
        let state = log.as_mut().map_or(0, |log| log.state_index(&state_name));
        let enter_s = rig.t_s - start_s;
        match motion {
            Some((name, motion)) => {
                let mut position = motion.position.rollout();
                let mut orientation = motion.orientation.rollout();
                let fail = |reason: String| ExecError::Motion {
                    state: state_name.clone(),
                    motion: (*name).clone(),
                    reason,
                };
                position
                    .restart_from(held.translation.vector.as_slice())
                    .map_err(|e| fail(e.to_string()))?;
                orientation.restart_from(held.rotation);
                let goal =
                    Vector3::from_column_slice(&motion.position.goal) + Vector3::from(options.overrides.goal_offset_m);
                position.set_goal(goal.as_slice()).map_err(|e| fail(e.to_string()))?;
                position
                    .set_tau(motion.position.tau_s / speed)
                    .map_err(|e| fail(e.to_string()))?;
                orientation
                    .set_tau(motion.orientation.tau_s / speed)
                    .map_err(|e| fail(e.to_string()))?;
                let steps = ((motion.position.tau_s / speed) / dt).round() as usize;
                for _ in 0..steps {
                    position.step(&motion.position, dt);
                    orientation.step(&motion.orientation, dt);
                    position.velocity_into(&mut velocity);
                    let p = Vector3::from_column_slice(position.position());
                    held = Isometry3::from_parts(Translation3::from(p), orientation.orientation());
                    let (pose, twist) =
                        rig.tool_command(&held, &Vector3::from(velocity), &orientation.angular_velocity());
                    let mut cmd = Command::hold(pose, options.replay_stiffness);
                    cmd.twist = twist;
                    cmd.frame = Isometry3::from_parts(rig.tool().translation, UnitQuaternion::identity());
                    rig.act(&cmd, state, &state_name, log.as_deref_mut(), dt)?;
                    rig.sense();
                }
            }
            None => {
                let steps = (((segment.end_s - segment.start_s) / speed) / dt).round() as usize;
                let (pose, _) = rig.tool_command(&held, &Vector3::zeros(), &Vector3::zeros());
                for _ in 0..steps {
                    let mut cmd = Command::hold(pose, options.replay_stiffness);
                    cmd.frame = Isometry3::from_parts(rig.tool().translation, UnitQuaternion::identity());
                    rig.act(&cmd, state, &state_name, log.as_deref_mut(), dt)?;
                    rig.sense();
                }
            }
        }
        visits.push(Visit {
            state: state_name,
            enter_s,
            exit_s: rig.t_s - start_s,
        });
    }
    Ok(RunReport {
        outcome: ir::Outcome::Success,
        terminal: None,
        message: "replayed every segment".to_string(),
        visits,
        duration_s: rig.t_s - start_s,
    })
}

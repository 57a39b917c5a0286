//! One simulated run from files' worth of inputs: a scene, a bound skill (or a replay), options.
//! Used by `skillc run` and `skillc eval`.

use super::{
    logs_csv as csv, offset_to_place, run_replay, run_skill, BoundSkill, ExecError, ExecOptions, Rig, RunLog, RunReport,
};
use crate::control::{ControllerGains, HybridController};
use crate::plant::Plant;
use crate::robot::{Robot, RobotError};
use crate::sim::{RapierPlant, Scene, SimError};
use crate::skill::Learned;

/// Why a simulated run could not be set up or carried out.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// Building the simulation failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The robot model does not fit.
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// The run failed.
    #[error(transparent)]
    Exec(#[from] ExecError),
}

/// What to run.
#[derive(Debug, Clone, Copy)]
pub enum Mode<'b, 'a> {
    /// The skill's state machine.
    Skill(&'b BoundSkill<'a>),
    /// The replay baseline of a learned file.
    Replay(&'b Learned),
}

/// Builds the scene's simulation and runs `mode` in it.
pub fn simulate(scene: &Scene, mode: Mode<'_, '_>, options: &ExecOptions) -> Result<(RunReport, RunLog), SessionError> {
    with_rig(scene, |rig| simulate_on(rig, mode, options))
}

/// Runs `mode` on `plant`, an arm that `robot` (the scene's, [`scene_robot`]) models and that is
/// not simulated here (a plant in another process, over `skill-transport`): the controller is
/// the one [`simulate`] builds, from that robot, the scene's wrist sensor and the plant's first
/// state.
pub fn run_on_plant(
    scene: &Scene,
    robot: Robot,
    plant: &mut dyn Plant,
    mode: Mode<'_, '_>,
    options: &ExecOptions,
) -> Result<(RunReport, RunLog), SessionError> {
    with_plant_rig(scene, robot, plant, |rig| simulate_on(rig, mode, options))
}

/// Builds the scene's simulation, the controller (null space pulled to the start
/// configuration) and the rig, and hands the rig to `run`.
fn with_rig<T>(scene: &Scene, run: impl FnOnce(&mut Rig<'_>) -> Result<T, SessionError>) -> Result<T, SessionError> {
    let mut plant = RapierPlant::from_scene(scene)?;
    let controller = scene_controller(scene, &plant)?;
    let mut rig = Rig::new(&mut plant, controller, &scene.spec().robot.sensor)?;
    run(&mut rig)
}

/// [`with_rig`] on a plant that is not built here.
fn with_plant_rig<T>(
    scene: &Scene,
    robot: Robot,
    plant: &mut dyn Plant,
    run: impl FnOnce(&mut Rig<'_>) -> Result<T, SessionError>,
) -> Result<T, SessionError> {
    let controller = controller_at(scene, robot, plant.observe().q.as_slice())?;
    let mut rig = Rig::new(plant, controller, &scene.spec().robot.sensor)?;
    run(&mut rig)
}

/// The scene's robot model (its URDF and tool), as [`RapierPlant::from_scene`] loads it.
pub fn scene_robot(scene: &Scene) -> Result<Robot, RobotError> {
    Robot::from_urdf_file(&scene.urdf_path(), scene.spec().robot.tool.as_deref())
}

/// The controller [`simulate`] runs `plant` (built from `scene`) with: default gains, the
/// scene's wrist sensor, the null space pulled towards the start configuration.
pub fn scene_controller(scene: &Scene, plant: &RapierPlant) -> Result<HybridController, RobotError> {
    controller_at(scene, plant.robot().clone(), plant.observe().q.as_slice())
}

fn controller_at(scene: &Scene, robot: Robot, q0: &[f64]) -> Result<HybridController, RobotError> {
    HybridController::new(robot, &scene.spec().robot.sensor, q0, ControllerGains::default())
}

fn simulate_on(
    rig: &mut Rig<'_>,
    mode: Mode<'_, '_>,
    options: &ExecOptions,
) -> Result<(RunReport, RunLog), SessionError> {
    let mut log = RunLog::tapped(options.tap.as_ref(), None);
    let log_ref = if options.log { Some(&mut log) } else { None };
    let report = match mode {
        Mode::Skill(bound) => run_skill(bound, rig, options, log_ref)?,
        Mode::Replay(learned) => run_replay(learned, rig, options, log_ref)?,
    };
    Ok((report, log))
}

/// One step of a task as it ran.
#[derive(Debug, Clone)]
pub struct StepReport {
    /// The step's name.
    pub step: String,
    /// The skill it ran.
    pub skill: String,
    /// Whether it was a fallback.
    pub fallback: bool,
    /// How it ended.
    pub report: RunReport,
    /// Its ticks, with its own state names (empty unless [`ExecOptions::log`]).
    pub log: RunLog,
}

/// A task as it ran: its steps in order (a failed step's fallback after it) and the outcome.
#[derive(Debug, Clone)]
pub struct TaskRun {
    /// The steps run.
    pub steps: Vec<StepReport>,
    /// Success when every step succeeded.
    pub outcome: skill_ir::Outcome,
}

impl TaskRun {
    /// Every tick of the task as CSV, one row per tick, each state written `<step>/<state>`.
    pub fn to_csv(&self) -> String {
        let logs: Vec<(Option<&str>, &RunLog)> = self
            .steps
            .iter()
            .map(|step| (Some(step.step.as_str()), &step.log))
            .collect();
        csv(&logs)
    }

    /// Ticks over all steps.
    pub fn ticks(&self) -> usize {
        self.steps.iter().map(|step| step.log.ticks.len()).sum()
    }
}

/// A task step ready to run: its IR step and its bound skill.
#[derive(Debug)]
pub struct TaskStep<'b, 'a> {
    /// The step.
    pub step: &'b skill_ir::Step,
    /// Its skill with learned features.
    pub bound: BoundSkill<'a>,
}

/// Runs a task's steps in sequence on one simulated robot, each starting where the last ended
/// (only the first moves to its demonstration's start first). A failing step runs its fallback,
/// if it names one, and the task stops as a failure.
pub fn simulate_task(
    scene: &Scene,
    steps: &[TaskStep<'_, '_>],
    fallbacks: &[TaskStep<'_, '_>],
    options: &ExecOptions,
) -> Result<TaskRun, SessionError> {
    with_rig(scene, |rig| task_on(rig, steps, fallbacks, options))
}

/// [`simulate_task`] on a plant that is not simulated here (see [`run_on_plant`]).
pub fn run_task_on_plant(
    scene: &Scene,
    robot: Robot,
    plant: &mut dyn Plant,
    steps: &[TaskStep<'_, '_>],
    fallbacks: &[TaskStep<'_, '_>],
    options: &ExecOptions,
) -> Result<TaskRun, SessionError> {
    with_plant_rig(scene, robot, plant, |rig| task_on(rig, steps, fallbacks, options))
}

fn task_on(
    rig: &mut Rig<'_>,
    steps: &[TaskStep<'_, '_>],
    fallbacks: &[TaskStep<'_, '_>],
    options: &ExecOptions,
) -> Result<TaskRun, SessionError> {
    let mut reports: Vec<StepReport> = Vec::new();
    let run_step =
        |task_step: &TaskStep<'_, '_>, first: bool, fallback: bool, reports: &[StepReport], rig: &mut Rig<'_>| {
            let step = task_step.step;
            let mut overrides = step.overrides;
            if let Some(anchor) = &step.at {
                match anchor_offset(anchor, &task_step.bound, reports, rig.flange_to_tool()) {
                    Ok(offset) => {
                        for (total, extra) in overrides.goal_offset_m.iter_mut().zip(offset) {
                            *total += extra;
                        }
                    }
                    Err(message) => {
                        return Ok(StepReport {
                            step: step.name.clone(),
                            skill: step.skill.clone(),
                            fallback,
                            report: RunReport::not_started(message),
                            log: RunLog::default(),
                        })
                    }
                }
            }
            let step_options = ExecOptions {
                overrides,
                step_limits: step.limits.clone(),
                prepose: first && options.prepose,
                ..options.clone()
            };
            let mut log = RunLog::tapped(options.tap.as_ref(), Some(&step.name));
            let report = run_skill(&task_step.bound, rig, &step_options, options.log.then_some(&mut log))?;
            Ok::<_, ExecError>(StepReport {
                step: step.name.clone(),
                skill: step.skill.clone(),
                fallback,
                report,
                log,
            })
        };
    for (index, task_step) in steps.iter().enumerate() {
        let report = run_step(task_step, index == 0, false, &reports, rig)?;
        let failed = report.report.outcome == skill_ir::Outcome::Failure;
        reports.push(report);
        if failed {
            // A step that ended in a reflex failed like any other: its `on failure` step runs,
            // from where the damped stop left the arm, under a supervisor armed afresh (it was
            // skipped silently before, which hid the fallback the task declares).
            if let skill_ir::OnFailure::Fallback(fallback) = &task_step.step.on_failure {
                if let Some(fallback) = fallbacks.get(*fallback as usize) {
                    let report = run_step(fallback, false, true, &reports, rig)?;
                    reports.push(report);
                }
            }
            return Ok(TaskRun {
                steps: reports,
                outcome: skill_ir::Outcome::Failure,
            });
        }
    }
    Ok(TaskRun {
        steps: reports,
        outcome: skill_ir::Outcome::Success,
    })
}

/// The goal offset `at: STEP.STATE` gives a step: from where the goal of its first state's motion
/// puts the tool point to where the tool point was when the earlier step first entered that state
/// ([`offset_to_place`]). An error message
/// when that step did not run or never entered the state, or the skill starts without a motion.
fn anchor_offset(
    anchor: &skill_ir::Anchor,
    bound: &BoundSkill<'_>,
    earlier: &[StepReport],
    flange_to_tool: &nalgebra::Isometry3<f64>,
) -> Result<[f64; 3], String> {
    let Some(found) = earlier
        .iter()
        .rev()
        .find(|report| report.step == anchor.step && !report.fallback)
    else {
        return Err(format!(
            "it starts at `{}.{}`, but step `{}` did not run before it",
            anchor.step, anchor.state, anchor.step
        ));
    };
    let Some(visit) = found.report.visits.iter().find(|visit| visit.state == anchor.state) else {
        return Err(format!(
            "it starts at `{}.{}`, but step `{}` never entered state `{}`",
            anchor.step, anchor.state, anchor.step, anchor.state
        ));
    };
    let initial = &bound.skill.states[bound.skill.initial.index()];
    let offset = match &initial.kind {
        skill_ir::StateKind::Active(active) => active
            .motion
            .and_then(|id| offset_to_place(bound.motions[id.index()], visit.enter_position_m, flange_to_tool)),
        skill_ir::StateKind::Terminal { .. } => None,
    };
    offset.ok_or_else(|| {
        format!(
            "it starts at `{}.{}`, but its first state `{}` runs no motion to place there",
            anchor.step, anchor.state, initial.name
        )
    })
}

//! One simulated run from files' worth of inputs: a scene, a bound skill (or a replay), options.
//! Used by `skillc run` and `skillc eval`.

use super::{run_replay, run_skill, BoundSkill, ExecError, ExecOptions, Rig, RunLog, RunReport};
use crate::control::{ControllerGains, HybridController};
use crate::plant::Plant;
use crate::robot::RobotError;
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
    let mut plant = RapierPlant::from_scene(scene)?;
    let spec = scene.spec();
    let robot = plant.robot().clone();
    let q0 = plant.observe().q;
    let controller = HybridController::new(robot, &spec.robot.sensor, q0.as_slice(), ControllerGains::default())?;
    let mut rig = Rig::new(&mut plant, controller, &spec.robot.sensor)?;
    let mut log = RunLog::default();
    let log_ref = if options.log { Some(&mut log) } else { None };
    let report = match mode {
        Mode::Skill(bound) => run_skill(bound, &mut rig, options, log_ref)?,
        Mode::Replay(learned) => run_replay(learned, &mut rig, options, log_ref)?,
    };
    Ok((report, log))
}

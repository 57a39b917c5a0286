//! The skill engine and its controller: the hybrid position/force control law, the safety
//! supervisor, and the state machine that runs a learned skill against any `Plant`. Links neither
//! the simulator nor the learner.
//!
//! The skill runtime (docs/method.md §7): binds a compiled skill and its learned features to a
//! robot and a plant, and runs the state machine at 1 kHz through the hybrid controller.
//!
//! Each tick: read the plant, compute the tool pose and the applied wrench, evaluate the current
//! state's guards in order and take the first that holds (running the entry actions of the
//! state entered: restart its motion from the current pose, shift a goal, reset the force
//! integral, tare the sensor); the entered state's guards are evaluated at the same instant, so
//! a chain of transitions takes no time. Then step the DMPs, build the command (pose, twist, wrench, compliant
//! frame, selection, stiffness, gains), run the controller, apply the torques, step the plant.
//!
//! Learned motions describe the flange (the demonstration records the flange); the controller
//! controls the tool point, so desired poses go through the robot's fixed flange-to-tool
//! transform. Compliant frames keep their learned orientation; their origin is put at the tool
//! point every tick (the contact is at the tool), except for constraints about a point or an
//! axis (`fixed_point`, `axial_rotation`) and literal frames, whose origin means something.
//!
//! The parts: [`bind`] (names become ids, once), `rig` (plant and controller, one tick, the
//! pre-positioning move), `motion` (starting DMPs), `machine` (the state machine), `run`
//! ([`run_skill`], [`run_replay`]), [`log`](RunLog) (the tick record), and, in `skill-runtime`, `session`
//! (a run or a task in a scene's simulation).
#![warn(missing_docs)]
pub mod control;
pub mod safety;

use skill_model::{dmp, skill};
use skill_robot::{self as robot, plant};

mod bind;
mod limits;
mod log;
mod machine;
mod motion;
mod rig;
mod run;

pub use bind::{bind, BindError, BoundSkill};
pub use limits::{apply_limits, learned_peak_force, learned_workspace, limits_for};
pub use log::{
    csv as logs_csv, CsvLog, JointValues, LogBatch, LogTap, PartSample, RunLog, TapEvent, Tick, MAX_INLINE_DOF,
    PART_MOVE_M, PART_PERIOD_TICKS,
};
pub use motion::offset_to_place;
pub use rig::Rig;
pub use run::{
    replay_state, run_replay, run_skill, ExecError, ExecOptions, RunReport, Visit, CONTACT_WITNESS, LOST_CONTACT,
    PLANT_LINK,
};

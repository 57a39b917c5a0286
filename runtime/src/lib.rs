//! The skillc runtime: learning from a demonstration, the robot model, the hybrid controller and
//! the simulation, under one roof. Each room is a crate of its own (`skill-robot`, `skill-model`,
//! `skill-learn`, `skill-sim`, `skill-exec`) so that a controller process links neither the
//! simulator nor the learner and a plant process links no learner; this crate re-exports them at
//! their old paths and adds what needs two rooms at once: a simulated run ([`exec::simulate`]).
#![warn(missing_docs)]
pub use skill_exec::{control, safety};
pub use skill_learn::{demo, demogen, rng, skill};
pub use skill_model::dmp;
pub use skill_robot::plant;
pub use {skill_learn as learn, skill_robot as robot, skill_sim as sim};

/// The skill engine ([`skill_exec`]) and simulated runs of it ([`simulate`](crate::exec::simulate),
/// [`simulate_task`](crate::exec::simulate_task)).
pub mod exec {
    pub use skill_exec::*;

    mod session;
    pub use session::{
        run_on_plant, run_task_on_plant, scene_controller, scene_robot, simulate, simulate_task, Mode, SessionError,
        StepReport, TaskRun, TaskStep,
    };
}

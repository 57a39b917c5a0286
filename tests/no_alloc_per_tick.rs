//! Allocations per tick of the closed loop: a counting global allocator (this test binary's
//! own) and a plant wrapper that notes the allocation count around every plant step, over a
//! whole `run_skill` of the slide skill (log on) on the rapier plant. Between two consecutive
//! steps lies one full tick: the step itself (rapier's pipeline, the contact and sensor read),
//! then sensing, the state machine, the controller, the supervisor and the log record.
//!
//! What is asserted, after a warm-up of [`WARM_UP`] ticks: a per-tick bound, not zero. Outside
//! the plant step no tick allocates ([`OUTSIDE_PLANT_PER_TICK`]), except at most one tick per
//! state entered (a state's entry restarts its DMPs and records the visit; at most
//! [`PER_ENTRY`]), so that part's total does not grow with the run; inside the step at most
//! [`RAPIER_PER_STEP`] on average, all of them rapier's own, which skillc cannot remove
//! without patching rapier. So the total grows linearly with the run (9 a tick); the test runs
//! the skill at half speed too (1.6 times as many ticks) to show the bounds hold for any
//! length. Sensing, the state machine, the controller, the supervisor, the log, the sensor
//! and skillc's plant code allocate nothing per tick (the log is reserved for the longest run
//! before it starts).

use std::alloc::System;
use std::path::PathBuf;

use skill_runtime::exec::{bind, run_skill, scene_controller, ExecOptions, Rig, RunLog};
use skill_runtime::plant::{Observation, Plant, PlantError};
use skill_runtime::sim::RapierPlant;
use skill_runtime::skill::LearnOptions;
use stats_alloc::{StatsAlloc, INSTRUMENTED_SYSTEM};

// The system allocator, counting (the workspace forbids unsafe code, so the counting wrapper
// comes from `stats_alloc`).
#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Allocations so far (reallocations count as allocations).
fn allocations() -> u64 {
    let stats = GLOBAL.stats();
    (stats.allocations + stats.reallocations) as u64
}

/// Ticks after the rig starts before counting: rapier's first contacts size its buffers.
const WARM_UP: usize = 200;
/// Allocations allowed on a tick that enters a state (DMP restart, the visit record).
const PER_ENTRY: u64 = 64;
/// Allocations skillc's own code makes on a steady tick, outside the plant step.
const OUTSIDE_PLANT_PER_TICK: u64 = 0;
/// Allocations inside one plant step, all rapier 0.36's own: its staged solver's multibody
/// set-up (the mass matrix's LU and quadform temporaries, 7) and the modified-body list that
/// `RigidBodySet::get_mut` pushes to and the pipeline takes every step (2). skillc's part of the
/// step (torques, contact wrench, sensor, the finiteness check) allocates nothing. That is
/// the mean over the steps; a step where a contact pair starts allocates its manifolds too (up
/// to [`RAPIER_PER_STEP_MAX`] measured 16).
const RAPIER_PER_STEP: f64 = 9.0;
/// The same in a debug build (`cargo test` without `--release`): rapier 0.36 allocates more
/// there (measured 11.21 a step on the slide).
const RAPIER_PER_STEP_DEBUG: f64 = 11.5;
/// Allocations inside the plant step that starts a contact.
const RAPIER_PER_STEP_MAX: u64 = 32;

/// The rapier plant, noting the allocation count before every step into a reserved Vec.
struct Noting {
    inner: RapierPlant,
    counts: Vec<u64>,
    /// Allocations inside each plant step (rapier's pipeline, the contact and sensor read).
    in_step: Vec<u64>,
}

impl Plant for Noting {
    fn dof(&self) -> usize {
        self.inner.dof()
    }
    fn time(&self) -> f64 {
        self.inner.time()
    }
    fn observe_into(&self, out: &mut Observation) {
        self.inner.observe_into(out);
    }
    fn apply(&mut self, torques: &[f64]) -> Result<(), PlantError> {
        self.inner.apply(torques)
    }
    fn step(&mut self, dt: f64) -> Result<(), PlantError> {
        let before = allocations();
        let stepped = self.inner.step(dt);
        if self.counts.len() < self.counts.capacity() {
            self.counts.push(before);
            self.in_step.push(allocations() - before);
        }
        stepped
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Allocations per tick of a run.
struct Ticks {
    /// Outside the plant step: sensing, the state machine, the controller, the supervisor, the log.
    outside: Vec<u64>,
    /// Inside the plant step.
    inside: Vec<u64>,
    /// States entered.
    entries: usize,
}

/// Runs the slide at `speed` and counts its allocations tick by tick.
fn slide_ticks(speed: f64) -> Ticks {
    let Ok((_, skill)) = skill_kit::load::load_skill(&root().join("stdlib-skills/slide.skill"), None) else {
        panic!("slide compiles")
    };
    let Ok(learned) = skill_kit::load::learn_from_files(
        &skill,
        &root().join("examples/demos/slide.csv"),
        &LearnOptions::default(),
    ) else {
        panic!("slide learns")
    };
    let bound = bind(&skill, &learned).expect("binds");
    let Ok(scene) = skill_kit::load::load_scene(&root().join("examples/scenes/table.toml"), &[]) else {
        panic!("scene")
    };
    let plant = RapierPlant::from_scene(&scene).expect("plant");
    let controller = scene_controller(&scene, &plant).expect("controller");
    let mut plant = Noting {
        inner: plant,
        counts: Vec::with_capacity(200_000),
        in_step: Vec::with_capacity(200_000),
    };
    let options = ExecOptions {
        overrides: skill_ir::Overrides {
            speed_factor: speed,
            ..skill_ir::Overrides::default()
        },
        ..ExecOptions::default()
    };
    let mut log = RunLog::default();
    let report = {
        let mut rig = Rig::new(&mut plant, controller, &scene.spec().robot.sensor).expect("rig");
        run_skill(&bound, &mut rig, &options, Some(&mut log)).expect("runs")
    };
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    assert_eq!(log.ticks.len(), plant.counts.len(), "one log record per plant step");
    // Between two steps' starts: the step itself, then the rest of the tick.
    let outside = plant
        .counts
        .windows(2)
        .zip(&plant.in_step)
        .map(|(w, inside)| w[1] - w[0] - inside)
        .collect();
    Ticks {
        outside,
        inside: plant.in_step,
        entries: report.visits.len(),
    }
}

fn check(speed: f64) -> usize {
    let run = slide_ticks(speed);
    let (outside, inside) = (&run.outside[WARM_UP..], &run.inside[WARM_UP..]);
    let allocating: Vec<(usize, u64)> = outside
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > OUTSIDE_PLANT_PER_TICK)
        .map(|(i, n)| (i + WARM_UP, *n))
        .collect();
    let shown = &allocating[..allocating.len().min(12)];
    let (outside_total, inside_total) = (outside.iter().sum::<u64>(), inside.iter().sum::<u64>());
    let inside_max = inside.iter().copied().max().unwrap_or(0);
    eprintln!(
        "speed {speed}: {} ticks counted; outside the plant step {outside_total} allocations \
         ({:.2} a tick), {} ticks above {OUTSIDE_PLANT_PER_TICK} (first: {shown:?}); inside the \
         plant step {inside_total} ({:.2} a tick, at most {inside_max}); {} states entered",
        outside.len(),
        outside_total as f64 / outside.len() as f64,
        allocating.len(),
        inside_total as f64 / inside.len() as f64,
        run.entries
    );
    assert!(
        allocating.len() <= run.entries && allocating.iter().all(|(_, n)| *n <= PER_ENTRY),
        "{} ticks allocate more than {OUTSIDE_PLANT_PER_TICK} outside the plant step (tick, \
         allocations; first 12): {shown:?}; states entered: {}",
        allocating.len(),
        run.entries
    );
    // Outside the plant step the whole run's count is bounded by the states entered, whatever
    // its length (measured 44 at both speeds).
    assert!(
        outside_total <= run.entries as u64 * PER_ENTRY,
        "{outside_total} allocations outside the plant step over {} ticks",
        outside.len()
    );
    let inside_mean = inside_total as f64 / inside.len() as f64;
    assert!(
        inside_mean
            <= if cfg!(debug_assertions) {
                RAPIER_PER_STEP_DEBUG
            } else {
                RAPIER_PER_STEP + 0.05
            }
            && inside_max <= RAPIER_PER_STEP_MAX,
        "the plant steps allocated {inside_mean:.2} times a step, at most {inside_max} (rapier's own: \
         {RAPIER_PER_STEP}, at most {RAPIER_PER_STEP_MAX})"
    );
    outside.len()
}

#[test]
fn the_closed_loop_allocates_a_bounded_amount_per_tick() {
    let ticks = check(1.0);
    let slower = check(0.5);
    assert!(
        slower > ticks * 3 / 2,
        "half speed runs longer: {slower} vs {ticks} ticks"
    );
}

//! Benchmark: the whole closed loop (state machine + controller + rapier + sensor + safety
//! supervisor + log) running the slide skill as demonstrated; reports simulated steps per wall
//! second. The scene, the rapier plant and the controller are built outside the timed part
//! (criterion's batched setup); one iteration is the rig's set-up (a few µs) and `run_skill`,
//! pre-positioning included, with the log on as `skillc run` has it. Beside it, the same run
//! with every supervisor check that can be switched off set to `inf`: the supervisor's cost,
//! measured in the same sitting.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use skill_runtime::control::HybridController;
use skill_runtime::exec::{
    bind, run_skill, scene_controller, simulate, BoundSkill, ExecOptions, Mode, Rig, RunLog, RunReport,
};
use skill_runtime::sim::{RapierPlant, Scene};
use skill_runtime::skill::LearnOptions;
use std::path::PathBuf;

/// The plant and controller of a run, built as `simulate` builds them (outside the timed part).
fn plant_and_controller(scene: &Scene) -> (RapierPlant, Option<HybridController>, RunLog) {
    let plant = RapierPlant::from_scene(scene).expect("plant");
    let controller = scene_controller(scene, &plant).expect("controller");
    (plant, Some(controller), RunLog::default())
}

/// The timed part: the rig and the run.
fn run(
    scene: &Scene,
    bound: &BoundSkill<'_>,
    options: &ExecOptions,
    (plant, controller, log): &mut (RapierPlant, Option<HybridController>, RunLog),
) -> RunReport {
    let mut rig = Rig::new(
        plant,
        controller.take().expect("a fresh controller"),
        &scene.spec().robot.sensor,
    )
    .expect("rig");
    run_skill(bound, &mut rig, options, Some(log)).expect("runs")
}

fn slide_closed_loop(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let Ok((_, skill)) = skill_kit::load::load_skill(&root.join("stdlib-skills/slide.skill"), None) else {
        panic!("slide compiles")
    };
    let Ok(learned) =
        skill_kit::load::learn_from_files(&skill, &root.join("examples/demos/slide.csv"), &LearnOptions::default())
    else {
        panic!("slide learns")
    };
    let Ok(scene) = skill_kit::load::load_scene(&root.join("examples/scenes/table.toml"), &[]) else {
        panic!("scene")
    };
    let bound = bind(&skill, &learned).expect("binds");
    let options = ExecOptions::default();
    let (report, _) = simulate(&scene, Mode::Skill(&bound), &options).expect("runs");
    let steps = (report.duration_s / options.dt_s).round() as u64;
    let mut group = c.benchmark_group("closed loop");
    group.sample_size(10);
    group.throughput(Throughput::Elements(steps));
    group.bench_function("slide as demonstrated (1 kHz steps)", |b| {
        b.iter_batched_ref(
            || plant_and_controller(&scene),
            |setup| run(&scene, &bound, &options, setup),
            BatchSize::PerIteration,
        )
    });
    let unchecked = ExecOptions {
        limits: skill_runtime::safety::LIMIT_NAMES
            .iter()
            .map(|spec| (spec.name.to_string(), f64::INFINITY))
            .collect(),
        ..options.clone()
    };
    group.bench_function("slide as demonstrated, supervisor limits off (1 kHz steps)", |b| {
        b.iter_batched_ref(
            || plant_and_controller(&scene),
            |setup| run(&scene, &bound, &unchecked, setup),
            BatchSize::PerIteration,
        )
    });
    group.finish();
}

criterion_group!(benches, slide_closed_loop);
criterion_main!(benches);

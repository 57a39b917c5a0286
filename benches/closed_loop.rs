//! Benchmark: the whole closed loop (state machine + controller + rapier + sensor + safety
//! supervisor) running the slide skill as demonstrated; reports simulated steps per wall second
//! (target ≥ 15 000). Beside it, the same run with every supervisor check that can be switched
//! off set to `inf`: the supervisor's cost, measured in the same sitting.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use skill_runtime::exec::{bind, simulate, ExecOptions, Mode};
use skill_runtime::skill::LearnOptions;
use std::path::PathBuf;

fn slide_closed_loop(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let Ok((_, skill)) = skillc::load::load_skill(&root.join("stdlib-skills/slide.skill"), None) else {
        panic!("slide compiles")
    };
    let Ok(learned) =
        skillc::load::learn_from_files(&skill, &root.join("examples/demos/slide.csv"), &LearnOptions::default())
    else {
        panic!("slide learns")
    };
    let Ok(scene) = skillc::load::load_scene(&root.join("examples/scenes/table.toml"), &[]) else {
        panic!("scene")
    };
    let bound = bind(&skill, &learned).expect("binds");
    let options = ExecOptions {
        log: false,
        ..ExecOptions::default()
    };
    let (report, _) = simulate(&scene, Mode::Skill(&bound), &options).expect("runs");
    let steps = (report.duration_s / options.dt_s).round() as u64;
    let mut group = c.benchmark_group("closed loop");
    group.sample_size(10);
    group.throughput(Throughput::Elements(steps));
    group.bench_function("slide as demonstrated (1 kHz steps)", |b| {
        b.iter(|| simulate(&scene, Mode::Skill(&bound), &options).expect("runs"))
    });
    let unchecked = ExecOptions {
        limits: skill_runtime::safety::LIMIT_NAMES
            .iter()
            .map(|spec| (spec.name.to_string(), f64::INFINITY))
            .collect(),
        ..options.clone()
    };
    group.bench_function("slide as demonstrated, supervisor limits off (1 kHz steps)", |b| {
        b.iter(|| simulate(&scene, Mode::Skill(&bound), &unchecked).expect("runs"))
    });
    group.finish();
}

criterion_group!(benches, slide_closed_loop);
criterion_main!(benches);

//! Benchmarks for issue 3: model FK + tool Jacobian + gravity, and rapier steps pressing on a table.

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Matrix6xX, Vector6};
use skill_runtime::plant::{Observation, Plant};
use skill_runtime::robot::{Robot, LWR4_URDF};
use skill_runtime::sim::{RapierPlant, Scene};

fn model(c: &mut Criterion) {
    let robot = Robot::from_urdf_str(LWR4_URDF, None).expect("bundled urdf");
    let mut data = robot.data();
    let mut jacobian = Matrix6xX::zeros(7);
    let mut gravity = [0.0; 7];
    let q = [0.3, 0.6, -0.2, -1.4, 0.1, 0.9, 0.2];
    c.bench_function("lwr4 fk + tool jacobian + gravity", |b| {
        b.iter(|| {
            robot.forward_kinematics(&mut data, black_box(&q));
            robot.tool_jacobian(&data, &mut jacobian);
            robot.gravity_torques(&mut data, &mut gravity);
            black_box((&jacobian, &gravity, robot.tool_in_base(&data)));
        })
    });
}

fn sim(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes/table.toml");
    let scene = Scene::from_file(&path).expect("example scene");
    let mut plant = RapierPlant::from_scene(&scene).expect("scene builds");
    let robot = plant.robot().clone();
    let mut data = robot.data();
    let mut jacobian = Matrix6xX::zeros(7);
    let mut gravity = [0.0; 7];
    let mut tau = [0.0; 7];
    let mut obs = Observation::zeros(7);
    let damping = [8.0, 8.0, 4.0, 4.0, 1.0, 0.5, 0.1];
    let wrench = Vector6::new(0.0, 0.0, -10.0, 0.0, 0.0, 0.0);
    let mut tick = |plant: &mut RapierPlant| {
        plant.observe_into(&mut obs);
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.tool_jacobian(&data, &mut jacobian);
        robot.gravity_torques(&mut data, &mut gravity);
        let push = jacobian.transpose() * wrench;
        for idx in 0..7 {
            tau[idx] = gravity[idx] + push[idx] - damping[idx] * obs.qd[idx];
        }
        plant.apply(&tau).expect("7 torques");
        plant.step(1e-3).expect("finite");
    };
    // Get into steady contact first.
    for _ in 0..500 {
        tick(&mut plant);
    }
    c.bench_function("rapier step pressing on table (controller + sensor)", |b| {
        b.iter(|| tick(&mut plant))
    });
}

criterion_group!(benches, model, sim);
criterion_main!(benches);

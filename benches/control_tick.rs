//! Benchmark: one hybrid-controller tick on the LWR-IV (model + adjoints + law) for a slide
//! command, at the next of 1024 observations (joint positions within ±0.2 rad of a pressing
//! configuration, velocities and wrench varied by a fixed-seed generator), so that the tick is
//! timed over many states, not one.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector6};
use skill_runtime::control::{Command, ControllerGains, HybridController};
use skill_runtime::plant::Observation;
use skill_runtime::rng::SplitMix64;
use skill_runtime::robot::{Robot, LWR4_FLANGE, LWR4_TOOL, LWR4_URDF};
use std::hint::black_box;

fn controller_tick(c: &mut Criterion) {
    let robot = Robot::from_urdf_str(LWR4_URDF, Some(LWR4_TOOL)).expect("bundled URDF");
    let q0 = [0.0, -0.5, 0.0, 1.5, 0.0, -1.14, 0.0];
    let mut controller =
        HybridController::new(robot, LWR4_FLANGE, &q0, ControllerGains::default()).expect("controller");
    let mut rng = SplitMix64::new(0x5eed);
    let mut uniform = move || rng.range(-1.0, 1.0);
    let base_q = [0.01, -0.49, 0.02, 1.51, -0.01, -1.13, 0.02];
    let observations: Vec<Observation> = (0..1024)
        .map(|_| {
            let mut obs = Observation::zeros(7);
            for (joint, q) in base_q.iter().enumerate() {
                obs.q[joint] = q + 0.2 * uniform();
                obs.qd[joint] = 0.05 * uniform();
            }
            obs.wrench_base = Vector6::new(
                0.5 * uniform(),
                0.5 * uniform(),
                9.8 + uniform(),
                0.02 * uniform(),
                0.02 * uniform(),
                0.0,
            );
            obs
        })
        .collect();
    controller.observe(&observations[0]);
    let tool = controller.state().tool;
    // A slide command: force along a tilted surface frame's z, position elsewhere.
    let cmd = Command {
        pose: tool,
        twist: Vector6::new(0.05, 0.02, 0.0, 0.0, 0.0, 0.0),
        wrench: Vector6::new(0.0, 0.0, -10.0, 0.0, 0.0, 0.0),
        force_twist: Vector6::zeros(),
        frame: Isometry3::from_parts(
            Translation3::from(tool.translation.vector),
            UnitQuaternion::from_euler_angles(3.1, 0.05, 0.0),
        ),
        position: [true, true, false, true, true, true],
        stiffness: [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0],
        kp: 0.5,
        ki: 10.0,
        integral_limit: Some(10.0),
    };
    let mut next = 0;
    c.bench_function("controller tick (observe + torques, 1024 states)", |b| {
        b.iter(|| {
            let obs = &observations[next % observations.len()];
            next += 1;
            controller.observe(black_box(obs));
            let torques = controller.torques(black_box(obs), black_box(&cmd), 0.001);
            black_box(torques[0])
        })
    });
}

criterion_group!(benches, controller_tick);
criterion_main!(benches);

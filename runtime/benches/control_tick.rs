//! Benchmark: one hybrid-controller tick on the LWR-IV (model + adjoints + law), target < 3 µs.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector6};
use skill_runtime::control::{Command, ControllerGains, HybridController};
use skill_runtime::plant::Observation;
use skill_runtime::robot::{Robot, LWR4_FLANGE, LWR4_TOOL, LWR4_URDF};
use std::hint::black_box;

fn controller_tick(c: &mut Criterion) {
    let robot = Robot::from_urdf_str(LWR4_URDF, Some(LWR4_TOOL)).expect("bundled URDF");
    let q0 = [0.0, -0.5, 0.0, 1.5, 0.0, -1.14, 0.0];
    let mut controller =
        HybridController::new(robot, LWR4_FLANGE, &q0, ControllerGains::default()).expect("controller");
    let mut obs = Observation::zeros(7);
    obs.q.copy_from_slice(&[0.01, -0.49, 0.02, 1.51, -0.01, -1.13, 0.02]);
    obs.qd.copy_from_slice(&[0.01, 0.02, -0.01, 0.03, 0.0, 0.01, 0.02]);
    obs.wrench_base = Vector6::new(0.3, -0.2, 9.8, 0.01, 0.02, 0.0);
    controller.observe(&obs);
    let tool = controller.state().tool;
    // A slide command: force along a tilted surface frame's z, position elsewhere.
    let cmd = Command {
        pose: tool,
        twist: Vector6::new(0.05, 0.02, 0.0, 0.0, 0.0, 0.0),
        wrench: Vector6::new(0.0, 0.0, -10.0, 0.0, 0.0, 0.0),
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
    c.bench_function("controller tick (observe + torques)", |b| {
        b.iter(|| {
            controller.observe(black_box(&obs));
            let torques = controller.torques(black_box(&obs), black_box(&cmd), 0.001);
            black_box(torques[0])
        })
    });
}

criterion_group!(benches, controller_tick);
criterion_main!(benches);

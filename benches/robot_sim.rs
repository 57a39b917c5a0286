//! Benchmarks of the robot model and the plant: FK + tool Jacobian + gravity over 1024 random
//! configurations (one per iteration), and one tick of the plant pressing on a table under the
//! real `HybridController` (observe, controller, apply, rapier step with contacts and sensor),
//! with every link's colliders and with the tool's alone (what the arm's colliders cost).

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Isometry3, Matrix6xX, Translation3, UnitQuaternion, Vector6};
use skill_runtime::control::{Command, ControllerGains, HybridController};
use skill_runtime::plant::{Observation, Plant};
use skill_runtime::rng::SplitMix64;
use skill_runtime::robot::{Robot, LWR4_URDF};
use skill_runtime::sim::{RapierOptions, RapierPlant, Scene};

/// 1024 joint configurations drawn uniformly within ±2 rad (±1.9 rad for the wrist) from a
/// fixed-seed LCG, so that the model tick is timed over many configurations, not one.
fn random_configurations() -> Vec<[f64; 7]> {
    let mut rng = SplitMix64::new(0x5eed);
    let mut uniform = move || rng.range(-1.0, 1.0);
    let limits = [2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 1.9];
    (0..1024).map(|_| limits.map(|limit| limit * uniform())).collect()
}

fn model(c: &mut Criterion) {
    let robot = Robot::from_urdf_str(LWR4_URDF, None).expect("bundled urdf");
    let mut data = robot.data();
    let mut jacobian = Matrix6xX::zeros(7);
    let mut gravity = [0.0; 7];
    let configurations = random_configurations();
    let mut next = 0;
    c.bench_function("lwr4 fk + tool jacobian + gravity (random q)", |b| {
        b.iter(|| {
            let q = &configurations[next % configurations.len()];
            next += 1;
            robot.forward_kinematics(&mut data, black_box(q));
            robot.tool_jacobian(&data, &mut jacobian);
            robot.gravity_torques(&mut data, &mut gravity);
            black_box((&jacobian, &gravity, robot.tool_in_base(&data)));
        })
    });
}

/// The bundled URDF without the collision shapes of the links before the flange: the arm as it
/// was simulated before its links collided with the scene (only the tool does).
fn tool_colliders_only() -> String {
    let split = LWR4_URDF
        .find("<link name=\"lwr_flange\">")
        .expect("the LWR's flange link");
    let (arm, tool) = LWR4_URDF.split_at(split);
    let mut stripped = String::with_capacity(LWR4_URDF.len());
    let mut rest = arm;
    while let Some(start) = rest.find("<collision>") {
        stripped.push_str(&rest[..start]);
        let end = rest[start..].find("</collision>").expect("closed collision") + start;
        rest = &rest[end + "</collision>".len()..];
    }
    stripped.push_str(rest);
    stripped.push_str(tool);
    stripped
}

fn sim(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/table.toml");
    let scene = Scene::from_file(&path).expect("example scene");
    let tool_only = Robot::from_urdf_str(&tool_colliders_only(), Some("probe_tip")).expect("stripped urdf");
    let plants = [
        (
            "plant tick pressing on table (HybridController + rapier step + sensor)",
            RapierPlant::from_scene(&scene).expect("scene builds"),
        ),
        (
            "plant tick pressing on table, tool colliders only",
            RapierPlant::new(tool_only, &scene, RapierOptions::default()).expect("scene builds"),
        ),
    ];
    for (name, mut plant) in plants {
        let q0 = plant.observe().q;
        let mut controller = HybridController::new(
            plant.robot().clone(),
            &scene.spec().robot.sensor,
            q0.as_slice(),
            ControllerGains::default(),
        )
        .expect("controller");
        let mut obs = Observation::zeros(7);
        plant.observe_into(&mut obs);
        controller.observe(&obs);
        let start = controller.state().tool;
        // Pressing down with 10 N along the base z, position control on the other axes, the
        // tool held where it started (over the table): the slide's command without the motion.
        let mut cmd = Command::hold(start, [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0]);
        cmd.position = [true, true, false, true, true, true];
        cmd.wrench = Vector6::new(0.0, 0.0, -10.0, 0.0, 0.0, 0.0);
        cmd.kp = 0.5;
        cmd.ki = 10.0;
        cmd.integral_limit = Some(10.0);
        let mut tick = |plant: &mut RapierPlant| {
            plant.observe_into(&mut obs);
            controller.observe(&obs);
            cmd.frame = Isometry3::from_parts(
                Translation3::from(controller.state().tool.translation.vector),
                UnitQuaternion::identity(),
            );
            let torques = controller.torques(&obs, &cmd, 1e-3);
            plant.apply(torques).expect("7 torques");
            plant.step(1e-3).expect("finite");
        };
        // Get into steady contact first (the tool starts above the table and moves down under
        // force control at the controller's speed limit).
        for _ in 0..3000 {
            tick(&mut plant);
        }
        let state = plant.observe();
        let force = state.wrench_base.fixed_rows::<3>(0).norm();
        assert!(force > 5.0, "{name}: pressing on the table, {force:.1} N");
        eprintln!(
            "{name}: tool force {force:.1} N, arm contact {:.1} N",
            state.arm_contact_n
        );
        c.bench_function(name, |b| b.iter(|| tick(&mut plant)));
    }
}

criterion_group!(benches, model, sim);
criterion_main!(benches);

//! The hybrid controller on the simulated LWR-IV: holding a pose, pressing on the table.

use nalgebra::{Isometry3, UnitQuaternion, Vector6};
use skill_runtime::control::{Command, ControllerGains, HybridController};
use skill_runtime::plant::Plant;
use skill_runtime::sim::{RapierPlant, Scene};

fn scene(name: &str) -> Scene {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/scenes")
        .join(name);
    Scene::from_file(&path).expect("example scene loads")
}

fn setup(scene: &Scene) -> (RapierPlant, HybridController) {
    let plant = RapierPlant::from_scene(scene).expect("scene builds");
    let q0 = plant.observe().q;
    let controller = HybridController::new(
        plant.robot().clone(),
        "lwr_flange",
        q0.as_slice(),
        ControllerGains::default(),
    )
    .expect("controller");
    (plant, controller)
}

#[test]
fn holding_the_start_pose_keeps_the_tool_still() {
    let mut scene = scene("table.toml");
    scene.set("table.z", "-1").expect("move the table away");
    let (mut plant, mut controller) = setup(&scene);
    let mut obs = plant.observe();
    controller.observe(&obs);
    let start = controller.state().tool;
    let frame = Isometry3::from_parts(start.translation, UnitQuaternion::identity());
    let mut worst: f64 = 0.0;
    for step in 0..2000 {
        plant.observe_into(&mut obs);
        controller.observe(&obs);
        let mut cmd = Command::hold(start, [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0]);
        cmd.frame = Isometry3::from_parts(controller.state().tool.translation, UnitQuaternion::identity());
        let _ = frame;
        let torques = controller.torques(&obs, &cmd, 0.001).to_vec();
        if step % 200 == 0 {
            eprintln!("step {step}: q = {:?}\n  tau = {:?}", obs.q.as_slice(), torques);
        }
        plant.apply(&torques).expect("apply");
        plant.step(0.001).expect("step");
        let drift = (controller.state().tool.translation.vector - start.translation.vector).norm();
        worst = worst.max(drift);
    }
    assert!(worst < 1e-3, "the tool drifted {worst} m");
    let _ = Vector6::<f64>::zeros();
}

#[test]
fn sliding_over_the_drum_follows_its_curvature() {
    // Contact recycling froze the drum's contact normal: the probe rode a tangent plane up to
    // 5 mm off the surface while still pushing. Slide 20° along the drum, target 5 mm inside it.
    let scene = scene("cylinder.toml");
    let (mut plant, mut controller) = setup(&scene);
    let (axis_x, axis_z, radius) = (0.5466, 0.15, 0.16);
    let mut obs = plant.observe();
    controller.observe(&obs);
    let rotation = controller.state().tool.rotation;
    let mut worst_gap: f64 = 0.0;
    // Warm-started friction made the contact force alternate 0 / 25 N every step while sliding.
    let mut worst_jump: f64 = 0.0;
    let mut last_force: Option<f64> = None;
    for step in 0..4000 {
        plant.observe_into(&mut obs);
        controller.observe(&obs);
        let (r, angle) = match step {
            0..2000 => (0.2, -30.0_f64),
            2000..2500 => (0.155, -30.0),
            _ => (0.155, -30.0 + (step - 2500) as f64 * 0.0133),
        };
        let (s, c) = angle.to_radians().sin_cos();
        let target = nalgebra::Translation3::new(axis_x + r * s, 0.0, axis_z + r * c);
        let mut cmd = Command::hold(
            Isometry3::from_parts(target, rotation),
            [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0],
        );
        cmd.frame = Isometry3::from_parts(controller.state().tool.translation, UnitQuaternion::identity());
        let torques = controller.torques(&obs, &cmd, 0.001).to_vec();
        plant.apply(&torques).expect("apply");
        plant.step(0.001).expect("step");
        if step >= 2600 {
            let p = controller.state().tool.translation.vector;
            let gap = (p.x - axis_x).hypot(p.z - axis_z) - radius;
            worst_gap = worst_gap.max(gap.abs());
            let force = plant.ideal_wrench_base().fixed_rows::<3>(0).norm();
            if let Some(last) = last_force {
                worst_jump = worst_jump.max((force - last).abs());
            }
            last_force = Some(force);
            assert!(
                controller.state().applied.fixed_rows::<3>(0).norm() > 2.0,
                "lost contact at step {step}"
            );
        }
    }
    // The bug this guards against left a 5 mm gap. The contact is compliant (the scene's default
    // 5e4 N/m stands for the arm's joint elasticity), so a ~10-20 N push sinks a few tenths of a mm.
    assert!(
        worst_gap < 1e-3,
        "the tool centre left the drum's offset surface by {worst_gap} m"
    );
    assert!(worst_jump < 2.0, "the contact force jumped {worst_jump} N in one step");
}

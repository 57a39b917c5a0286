//! The hybrid controller on the simulated LWR-IV: holding a pose, pressing on the table.

use nalgebra::{Isometry3, UnitQuaternion, Vector6};
use skill_runtime::control::{Command, ControllerGains, HybridController};
use skill_runtime::plant::Plant;
use skill_runtime::sim::{RapierPlant, Scene};

fn scene(name: &str) -> Scene {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes").join(name);
    Scene::from_file(&path).expect("example scene loads")
}

fn setup(scene: &Scene) -> (RapierPlant, HybridController) {
    let plant = RapierPlant::from_scene(scene).expect("scene builds");
    let q0 = plant.observe().q;
    let controller =
        HybridController::new(plant.robot().clone(), "lwr_flange", q0.as_slice(), ControllerGains::default()).expect("controller");
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


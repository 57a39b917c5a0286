//! The reflex's damped stop (`Robot::damped_stop_torques`) brings a moving arm to rest under
//! rapier, the wrist included: every joint's speed decays, none ever grows past where it started,
//! and the arm stands still within a few of the stop's time constants. A fixed damping gain per
//! unit of effort limit failed this: the wrist's explicit damping was unstable at 1 kHz and a
//! stop begun with the wrist turning at 0.1 rad/s spun it up to 28 rad/s.

use std::path::PathBuf;

use skill_runtime::plant::Plant;
use skill_runtime::robot::STOP_TIME_CONSTANT_S;
use skill_runtime::sim::{RapierPlant, Scene};

const DT: f64 = 1e-3;

fn plant() -> RapierPlant {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes/table.toml");
    let scene = Scene::from_file(&path).expect("example scene loads");
    RapierPlant::from_scene(&scene).expect("scene builds")
}

/// Spins the arm up for 100 ms with gravity compensation plus `push` N m on each joint, then
/// runs the damped stop for 300 ms; the joint speeds at the stop's start and every tick after.
fn stop_after(push: [f64; 7]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut plant = plant();
    let robot = plant.robot().clone();
    let mut data = robot.data();
    let mut obs = plant.observe();
    let mut tau = vec![0.0; 7];
    for _ in 0..100 {
        plant.observe_into(&mut obs);
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.gravity_torques(&mut data, &mut tau);
        for (t, p) in tau.iter_mut().zip(push) {
            *t += p;
        }
        plant.apply(&tau).expect("7 torques");
        plant.step(DT).expect("finite state");
    }
    plant.observe_into(&mut obs);
    let start = obs.qd.as_slice().to_vec();
    let mut speeds = Vec::new();
    for _ in 0..300 {
        plant.observe_into(&mut obs);
        robot.damped_stop_torques(&mut data, obs.q.as_slice(), obs.qd.as_slice(), &mut tau);
        plant.apply(&tau).expect("7 torques");
        plant.step(DT).expect("finite state");
        plant.observe_into(&mut obs);
        speeds.push(obs.qd.as_slice().to_vec());
    }
    (start, speeds)
}

#[test]
fn the_damped_stop_brings_every_joint_to_rest_the_wrist_included() {
    // The wrist alone (the joints the old gain made unstable), and the whole arm.
    for (name, push) in [
        ("wrist", [0.0, 0.0, 0.0, 0.0, 0.05, 0.03, 0.005]),
        ("whole arm", [8.0, -6.0, 4.0, 4.0, 0.05, 0.03, 0.005]),
    ] {
        let (start, speeds) = stop_after(push);
        let fastest = start.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(fastest > 0.3, "{name}: the arm was spun up to only {fastest:.3} rad/s");
        let peak = speeds.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(
            peak <= 1.05 * fastest,
            "{name}: a joint reached {peak:.3} rad/s during a stop begun at {fastest:.3} rad/s"
        );
        // Five time constants in: at most a twentieth of where it began (e⁻⁵ < 1 %, with
        // torque limits and the model's Coriolis terms leaving room).
        let settled = (5.0 * STOP_TIME_CONSTANT_S / DT).ceil() as usize;
        let left = speeds[settled..].iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(
            left <= 0.05 * fastest,
            "{name}: still {left:.4} rad/s after {settled} ms (from {fastest:.3} rad/s)"
        );
        eprintln!("{name}: from {fastest:.3} rad/s, peak {peak:.3}, {left:.5} rad/s after {settled} ms");
    }
}

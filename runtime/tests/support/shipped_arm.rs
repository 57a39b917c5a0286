//! Checks every shipped arm but the LWR-IV gets without any peer library (robot_iiwa14.rs,
//! robot_fr3.rs): the tool Jacobian against central differences of the forward kinematics, the
//! gravity torques against the derivative of the potential energy of the URDF's link masses, and
//! its scenes (`examples/scenes/NAME/`) against the LWR-IV's. Included by path, not as `support`.

// Each test crate that includes this module uses a part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use nalgebra::{Matrix6xX, Point3, Vector3};
use skill_runtime::robot::{BuiltinRobot, Robot, LWR4};
use skill_runtime::sim::{RapierPlant, Scene};

/// The shipped scenes, each with a copy per shipped arm.
pub(crate) const SCENES: [&str; 4] = ["table", "button", "cylinder", "workcell"];

/// The workspace root.
pub(crate) fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A tiny deterministic generator (splitmix64) so the tests need no extra crate.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    /// A number drawn uniformly from `[lo, hi)`.
    pub(crate) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// `count` random configurations inside the joint limits (the same ones for the same robot).
pub(crate) fn configurations(robot: &Robot, count: usize) -> Vec<Vec<f64>> {
    let mut rng = Rng(13);
    let limits: Vec<(f64, f64)> = robot.position_limits().collect();
    (0..count)
        .map(|_| limits.iter().map(|&(lo, hi)| rng.uniform(lo, hi)).collect())
        .collect()
}

/// Where `link`'s origin is at `q` (base frame).
pub(crate) fn link_position(robot: &Robot, link: &str, q: &[f64]) -> Vector3<f64> {
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, q);
    let link = robot.require_link(link).expect("link");
    robot.link_in_base(&data, link).translation.vector
}

/// The largest difference between the tool Jacobian and central differences (h = 1e-6) of the
/// forward kinematics at 50 random configurations.
pub(crate) fn worst_jacobian_difference(robot: &Robot) -> f64 {
    let h = 1e-6;
    let dof = robot.dof();
    let mut worst: f64 = 0.0;
    for q in configurations(robot, 50) {
        let (_, jacobian, _) = robot.evaluate(&q);
        let mut numeric = Matrix6xX::zeros(dof);
        for j in 0..dof {
            let (mut plus, mut minus) = (q.clone(), q.clone());
            plus[j] += h;
            minus[j] -= h;
            let (a, _, _) = robot.evaluate(&plus);
            let (b, _, _) = robot.evaluate(&minus);
            let linear = (a.translation.vector - b.translation.vector) / (2.0 * h);
            // The rotation from minus to plus over 2h, as an angular velocity in base axes.
            let angular = (a.rotation * b.rotation.inverse()).scaled_axis() / (2.0 * h);
            for r in 0..3 {
                numeric[(r, j)] = linear[r];
                numeric[(r + 3, j)] = angular[r];
            }
        }
        worst = worst.max((jacobian - numeric).amax());
    }
    worst
}

/// The mass of every link that moves (the fixed base excluded) \[kg\].
pub(crate) fn moving_mass(robot: &Robot) -> f64 {
    robot
        .links()
        .iter()
        .filter(|link| link.body.is_some())
        .map(|link| link.inertial.mass)
        .sum()
}

/// The largest difference \[N m\] between g(q) and ∂V/∂q (central differences, h = 1e-6) with
/// V = Σ m_i g z_i over every moving link with its URDF mass and centre of mass, at 50 random
/// configurations.
pub(crate) fn worst_gravity_difference(robot: &Robot) -> f64 {
    let potential = |q: &[f64]| -> f64 {
        let mut data = robot.data();
        robot.forward_kinematics(&mut data, q);
        robot
            .links()
            .iter()
            .enumerate()
            .filter(|(_, link)| link.body.is_some())
            .map(|(i, link)| {
                let com = robot.link_in_base(&data, i) * Point3::from(link.inertial.com);
                link.inertial.mass * 9.81 * com.z
            })
            .sum()
    };
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for q in configurations(robot, 50) {
        let (_, _, gravity) = robot.evaluate(&q);
        for j in 0..robot.dof() {
            let (mut plus, mut minus) = (q.clone(), q.clone());
            plus[j] += h;
            minus[j] -= h;
            let numeric = (potential(&plus) - potential(&minus)) / (2.0 * h);
            worst = worst.max((gravity[j] - numeric).abs());
        }
    }
    worst
}

/// Checks that `examples/scenes/{folder}/*.toml` are the LWR-IV's scenes with only `[robot]`
/// changed, naming `arm`'s sensor, and that `arm`'s tool starts where the LWR-IV's `q0` puts its
/// tool (within 1 µm and 1e-5 rad). Returns each scene's name and the arm's start configuration.
pub(crate) fn scenes_match_the_lwr_scenes(arm: BuiltinRobot, folder: &str) -> Vec<(&'static str, Vec<f64>)> {
    let root = root();
    let lwr = LWR4.load().expect("lwr4");
    let robot = arm.load().expect("shipped urdf");
    let read = |path: &Path| -> toml::Table {
        let mut table: toml::Table = std::fs::read_to_string(path)
            .expect("scene file")
            .parse()
            .expect("toml");
        table.remove("robot");
        table
    };
    SCENES
        .iter()
        .map(|&name| {
            let lwr_path = root.join(format!("examples/scenes/{name}.toml"));
            let arm_path = root.join(format!("examples/scenes/{folder}/{name}.toml"));
            assert_eq!(read(&arm_path), read(&lwr_path), "{name}: more than [robot] differs");
            let lwr_scene = Scene::from_file(&lwr_path).expect("lwr scene");
            let arm_scene = Scene::from_file(&arm_path).expect("arm scene");
            assert_eq!(arm_scene.spec().robot.sensor, arm.sensor);
            let (lwr_tool, _, _) = lwr.evaluate(&lwr_scene.start_configuration(&lwr).expect("q0"));
            let q = arm_scene.start_configuration(&robot).expect("reachable");
            let (arm_tool, _, _) = robot.evaluate(&q);
            let miss = (arm_tool.translation.vector - lwr_tool.translation.vector).norm();
            let angle = arm_tool.rotation.angle_to(&lwr_tool.rotation);
            assert!(miss < 1e-6 && angle < 1e-5, "{name}: {miss} m, {angle} rad");
            (name, q)
        })
        .collect()
}

/// Checks that the arm starts more than 5 cm clear of every object in each of
/// `examples/scenes/{folder}/*.toml`: a run cannot begin in an arm-contact reflex.
pub(crate) fn starts_clear_of_the_objects(folder: &str) {
    for name in SCENES {
        let path = root().join(format!("examples/scenes/{folder}/{name}.toml"));
        let scene = Scene::from_file(&path).expect("scene");
        let plant = RapierPlant::from_scene(&scene).expect("the arm starts outside every object");
        let (clearance, link, object) = plant.arm_start_clearance().expect("objects");
        assert!(
            clearance > 0.05,
            "{name}: `{link}` starts {clearance} m from `{object}`"
        );
    }
}

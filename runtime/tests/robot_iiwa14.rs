//! The shipped KUKA LBR iiwa 14 (`examples/robots/iiwa14.urdf`) without any peer library: its
//! published link lengths at two configurations, the tool Jacobian against central differences
//! of the forward kinematics, and the gravity torques against the derivative of the potential
//! energy of the URDF's link masses, at random configurations inside the joint limits. (The
//! side-by-side check with pinocchio is `tools/check/pinocchio_robot.py`; it needs Python.)

use nalgebra::{Matrix6xX, Vector3};
use skill_runtime::robot::{Robot, IIWA14};

/// A tiny deterministic generator (splitmix64) so the test needs no extra crate.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
}

fn iiwa() -> Robot {
    IIWA14.load().expect("the shipped iiwa14 urdf loads")
}

/// Random configurations inside the joint limits.
fn configurations(robot: &Robot, count: usize) -> Vec<Vec<f64>> {
    let mut rng = Rng(13);
    let limits: Vec<(f64, f64)> = robot.position_limits().collect();
    (0..count)
        .map(|_| limits.iter().map(|&(lo, hi)| rng.uniform(lo, hi)).collect())
        .collect()
}

fn flange(robot: &Robot, q: &[f64]) -> Vector3<f64> {
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, q);
    let link = robot.require_link(IIWA14.sensor).expect("flange");
    robot.link_in_base(&data, link).translation.vector
}

/// KUKA's dimensions of the iiwa 14 R820: A2 0.36 m above the base, A4 0.42 m above A2, A6 0.40 m
/// above A4, the flange 0.126 m beyond A6; the probe tip 0.11 m beyond the flange.
#[test]
fn the_flange_is_where_kukas_link_lengths_put_it() {
    let robot = iiwa();
    let straight = flange(&robot, &[0.0; 7]);
    assert!((straight - Vector3::new(0.0, 0.0, 1.306)).norm() < 1e-9, "{straight:?}");
    // A2 at 90°: everything after the shoulder lies along the base x axis at shoulder height.
    // (1e-9 m: the frames' rpy of ±π/2 and π are rounded in the file.)
    let level = flange(&robot, &[0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert!((level - Vector3::new(0.946, 0.0, 0.36)).norm() < 1e-9, "{level:?}");
    let (tool, _, _) = robot.evaluate(&[0.0; 7]);
    assert!((tool.translation.vector.z - 1.416).abs() < 1e-9);
}

#[test]
fn the_tool_jacobian_matches_central_differences_of_the_forward_kinematics() {
    let robot = iiwa();
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for q in configurations(&robot, 50) {
        let (_, jacobian, _) = robot.evaluate(&q);
        let mut numeric = Matrix6xX::zeros(7);
        for j in 0..7 {
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
    assert!(worst < 1e-8, "largest Jacobian difference {worst:e}");
}

/// g(q) = ∂V/∂q with V = Σ m_i g z_i over every link of the chain with its URDF mass and centre
/// of mass (the probe included, the fixed base excluded: it does not move).
#[test]
fn gravity_torques_are_the_derivative_of_the_potential_energy() {
    let robot = iiwa();
    let potential = |q: &[f64]| -> f64 {
        let mut data = robot.data();
        robot.forward_kinematics(&mut data, q);
        robot
            .links()
            .iter()
            .enumerate()
            .filter(|(_, link)| link.body.is_some())
            .map(|(i, link)| {
                let com = robot.link_in_base(&data, i) * nalgebra::Point3::from(link.inertial.com);
                link.inertial.mass * 9.81 * com.z
            })
            .sum()
    };
    let moving: f64 = robot
        .links()
        .iter()
        .filter(|link| link.body.is_some())
        .map(|link| link.inertial.mass)
        .sum();
    // Drake's link masses 5.76 + 6.35 + 3.5 × 3 + 1.8 + 1.2 and the 0.2 kg probe.
    assert!((moving - 25.81).abs() < 1e-9, "moving mass {moving} kg");
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for q in configurations(&robot, 50) {
        let (_, _, gravity) = robot.evaluate(&q);
        for j in 0..7 {
            let (mut plus, mut minus) = (q.clone(), q.clone());
            plus[j] += h;
            minus[j] -= h;
            let numeric = (potential(&plus) - potential(&minus)) / (2.0 * h);
            worst = worst.max((gravity[j] - numeric).abs());
        }
    }
    assert!(worst < 1e-6, "largest gravity torque difference {worst:e} N m");
}

/// `examples/scenes/iiwa14/*.toml` are the LWR-IV's scenes with only `[robot]` changed, and the
/// iiwa's tool starts where the LWR-IV's `q0` puts its tool (within 1 µm and 1e-5 rad).
#[test]
fn the_iiwa_scenes_are_the_lwr_scenes_with_the_tool_starting_at_the_same_pose() {
    use skill_runtime::robot::LWR4;
    use skill_runtime::sim::Scene;
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let lwr = LWR4.load().expect("lwr4");
    let iiwa = iiwa();
    for name in ["table", "button", "cylinder", "workcell"] {
        let read = |path: &std::path::Path| -> toml::Table {
            let mut table: toml::Table = std::fs::read_to_string(path)
                .expect("scene file")
                .parse()
                .expect("toml");
            table.remove("robot");
            table
        };
        let lwr_path = root.join(format!("examples/scenes/{name}.toml"));
        let iiwa_path = root.join(format!("examples/scenes/iiwa14/{name}.toml"));
        assert_eq!(read(&iiwa_path), read(&lwr_path), "{name}: more than [robot] differs");
        let lwr_scene = Scene::from_file(&lwr_path).expect("lwr scene");
        let iiwa_scene = Scene::from_file(&iiwa_path).expect("iiwa scene");
        assert_eq!(iiwa_scene.spec().robot.sensor, IIWA14.sensor);
        let (lwr_tool, _, _) = lwr.evaluate(&lwr_scene.start_configuration(&lwr).expect("q0"));
        let q = iiwa_scene.start_configuration(&iiwa).expect("reachable");
        let (iiwa_tool, _, _) = iiwa.evaluate(&q);
        let miss = (iiwa_tool.translation.vector - lwr_tool.translation.vector).norm();
        let angle = iiwa_tool.rotation.angle_to(&lwr_tool.rotation);
        assert!(miss < 1e-6 && angle < 1e-5, "{name}: {miss} m, {angle} rad");
        // Elbow up: joint 4 (the elbow) bends the way the iiwa's elbow-up seed does.
        assert!(q[3] < -1.0, "{name}: {q:?}");
    }
}

/// The iiwa's links (Drake's cylinders, our wrist primitives) start clear of every object in its
/// scenes: a run cannot begin in an arm-contact reflex.
#[test]
fn the_iiwa_starts_clear_of_the_objects_in_its_scenes() {
    use skill_runtime::sim::{RapierPlant, Scene};
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    for name in ["table", "button", "cylinder", "workcell"] {
        let scene = Scene::from_file(&root.join(format!("examples/scenes/iiwa14/{name}.toml"))).expect("scene");
        let plant = RapierPlant::from_scene(&scene).expect("the arm starts outside every object");
        let (clearance, link, object) = plant.arm_start_clearance().expect("objects");
        assert!(
            clearance > 0.05,
            "{name}: `{link}` starts {clearance} m from `{object}`"
        );
    }
}

//! The shipped Franka Research 3 (`examples/robots/fr3.urdf`) without any peer library: the
//! flange where Franka's published Denavit-Hartenberg parameters put it, the tool Jacobian against
//! central differences of the forward kinematics, the gravity torques against the derivative of
//! the potential energy of the URDF's link masses, and its scenes. (The side-by-side check with
//! pinocchio is `tools/check/pinocchio_robot.py`; it needs Python.)

#[path = "support/shipped_arm.rs"]
mod shipped_arm;

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use skill_runtime::robot::{Robot, FR3};

fn fr3() -> Robot {
    FR3.load().expect("the shipped fr3 urdf loads")
}

/// Franka's modified (Craig) Denavit-Hartenberg parameters of the FR3 (and the FER), as Franka's
/// robot documentation tables them: (a m, d m, α rad) for joints 1-7, then the flange.
const DH: [(f64, f64, f64); 8] = [
    (0.0, 0.333, 0.0),
    (0.0, 0.0, -FRAC_PI_2),
    (0.0, 0.316, FRAC_PI_2),
    (0.0825, 0.0, FRAC_PI_2),
    (-0.0825, 0.384, -FRAC_PI_2),
    (0.0, 0.0, FRAC_PI_2),
    (0.088, 0.0, FRAC_PI_2),
    (0.0, 0.107, 0.0),
];

/// The flange's pose by the DH table: each frame is Rot_x(α) Trans_x(a) Rot_z(θ) Trans_z(d) from
/// the one before (θ = 0 for the flange).
fn flange_by_dh(q: &[f64]) -> Isometry3<f64> {
    let mut pose = Isometry3::identity();
    for (i, &(a, d, alpha)) in DH.iter().enumerate() {
        let theta = q.get(i).copied().unwrap_or(0.0);
        pose = pose
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), alpha)
            * Translation3::new(a, 0.0, 0.0)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta)
            * Translation3::new(0.0, 0.0, d);
    }
    pose
}

/// The pose of `link` at `q` (base frame).
fn pose(robot: &Robot, link: &str, q: &[f64]) -> Isometry3<f64> {
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, q);
    let link = robot.require_link(link).expect("link");
    robot.link_in_base(&data, link)
}

/// The flange (franka_description's link8).
fn flange(robot: &Robot, q: &[f64]) -> Isometry3<f64> {
    pose(robot, "fr3_flange", q)
}

/// At q = 0 the flange is 0.088 m in front of the base axis, 0.333 + 0.316 + 0.384 − 0.107 m up,
/// pointing down; the probe tip 0.11 m below it. At 50 random configurations the flange is where
/// the DH table puts it (1e-12 m, 1e-12 rad).
#[test]
fn the_flange_is_where_frankas_dh_parameters_put_it() {
    let robot = fr3();
    let zero = flange(&robot, &[0.0; 7]);
    assert!(
        (zero.translation.vector - Vector3::new(0.088, 0.0, 0.926)).norm() < 1e-12,
        "{zero:?}"
    );
    assert!((zero.rotation * Vector3::z() + Vector3::z()).norm() < 1e-12);
    let (tool, _, _) = robot.evaluate(&[0.0; 7]);
    assert!((tool.translation.vector - Vector3::new(0.088, 0.0, 0.816)).norm() < 1e-12);
    let mut worst: (f64, f64) = (0.0, 0.0);
    for q in shipped_arm::configurations(&robot, 50) {
        let (ours, dh) = (flange(&robot, &q), flange_by_dh(&q));
        worst.0 = worst.0.max((ours.translation.vector - dh.translation.vector).norm());
        worst.1 = worst.1.max(ours.rotation.angle_to(&dh.rotation));
    }
    assert!(worst.0 < 1e-12 && worst.1 < 1e-12, "{worst:?}");
}

/// The joint ranges are franka_description's (since 1.1.0), joint 4 never straight, joint 6
/// never below 0.54 rad; the wrist sensor (and the probe on it) sits on the flange face turned by
/// π about its axis, the probe tip 0.11 m beyond.
#[test]
fn the_joint_ranges_and_the_sensor_mount_are_the_generators() {
    let robot = fr3();
    let limits: Vec<(f64, f64)> = robot.position_limits().collect();
    assert_eq!(limits[3], (-3.0481, -0.1458));
    assert_eq!(limits[5], (0.54092, 4.5205));
    assert_eq!(limits[6], (-3.0196, 3.0196));
    let q = [0.3, -0.4, 0.2, -2.0, 0.1, 1.9, 0.5];
    let (tool, _, _) = robot.evaluate(&q);
    let sensor = pose(&robot, FR3.sensor, &q);
    let turn = flange(&robot, &q).inverse() * sensor;
    assert!(turn.translation.vector.norm() < 1e-12, "{turn:?}");
    assert!((turn.rotation.angle() - PI).abs() < 1e-12);
    assert!((turn.rotation * Vector3::z() - Vector3::z()).norm() < 1e-12);
    let tip = sensor.inverse() * tool;
    assert!((tip.translation.vector - Vector3::new(0.0, 0.0, 0.11)).norm() < 1e-12);
    assert!(tip.rotation.angle() < 1e-12);
}

#[test]
fn the_tool_jacobian_matches_central_differences_of_the_forward_kinematics() {
    let worst = shipped_arm::worst_jacobian_difference(&fr3());
    assert!(worst < 1e-8, "largest Jacobian difference {worst:e}");
}

/// g(q) = ∂V/∂q with V = Σ m_i g z_i over every link of the chain with its URDF mass and centre
/// of mass (the probe included, the fixed base excluded: it does not move).
#[test]
fn gravity_torques_are_the_derivative_of_the_potential_energy() {
    let robot = fr3();
    let moving = shipped_arm::moving_mass(&robot);
    // franka_description's link masses 2.9275 + 2.9355 + 2.2449 + 2.6156 + 2.3271 + 1.8170 +
    // 0.6271 kg and the 0.2 kg probe.
    assert!((moving - 15.694_801_026_2).abs() < 1e-9, "moving mass {moving} kg");
    let worst = shipped_arm::worst_gravity_difference(&robot);
    assert!(worst < 1e-6, "largest gravity torque difference {worst:e} N m");
}

/// `examples/scenes/fr3/*.toml` are the LWR-IV's scenes with only `[robot]` changed, the FR3's
/// tool starts where the LWR-IV's `q0` puts its tool, and every joint starts at least 0.5 rad
/// inside its range (the elbow, joint 4, nearest: about 1.05 rad from its upper end).
#[test]
fn the_fr3_scenes_are_the_lwr_scenes_with_the_tool_starting_at_the_same_pose() {
    let robot = fr3();
    for (name, q) in shipped_arm::scenes_match_the_lwr_scenes(FR3, "fr3") {
        for (j, (value, (lo, hi))) in q.iter().zip(robot.position_limits()).enumerate() {
            let margin = (value - lo).min(hi - value);
            assert!(
                margin > 0.5,
                "{name}: joint {} at {value} rad, {margin} rad inside",
                j + 1
            );
        }
    }
}

/// The FR3's links (franka_description's self-collision capsules) start clear of every object in
/// its scenes: a run cannot begin in an arm-contact reflex.
#[test]
fn the_fr3_starts_clear_of_the_objects_in_its_scenes() {
    shipped_arm::starts_clear_of_the_objects("fr3");
}

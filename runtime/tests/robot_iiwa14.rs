//! The shipped KUKA LBR iiwa 14 (`examples/robots/iiwa14.urdf`) without any peer library: its
//! published link lengths at two configurations, the tool Jacobian against central differences
//! of the forward kinematics, and the gravity torques against the derivative of the potential
//! energy of the URDF's link masses, at random configurations inside the joint limits. (The
//! side-by-side check with pinocchio is `tools/check/pinocchio_robot.py`; it needs Python.)

#[path = "support/shipped_arm.rs"]
mod shipped_arm;

use nalgebra::Vector3;
use skill_runtime::robot::{Robot, IIWA14};

fn iiwa() -> Robot {
    IIWA14.load().expect("the shipped iiwa14 urdf loads")
}

fn flange(robot: &Robot, q: &[f64]) -> Vector3<f64> {
    shipped_arm::link_position(robot, IIWA14.sensor, q)
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
    let worst = shipped_arm::worst_jacobian_difference(&iiwa());
    assert!(worst < 1e-8, "largest Jacobian difference {worst:e}");
}

/// g(q) = ∂V/∂q with V = Σ m_i g z_i over every link of the chain with its URDF mass and centre
/// of mass (the probe included, the fixed base excluded: it does not move).
#[test]
fn gravity_torques_are_the_derivative_of_the_potential_energy() {
    let robot = iiwa();
    let moving = shipped_arm::moving_mass(&robot);
    // Drake's link masses 5.76 + 6.35 + 3.5 × 3 + 1.8 + 1.2 and the 0.2 kg probe.
    assert!((moving - 25.81).abs() < 1e-9, "moving mass {moving} kg");
    let worst = shipped_arm::worst_gravity_difference(&robot);
    assert!(worst < 1e-6, "largest gravity torque difference {worst:e} N m");
}

/// `examples/scenes/iiwa14/*.toml` are the LWR-IV's scenes with only `[robot]` changed, and the
/// iiwa's tool starts where the LWR-IV's `q0` puts its tool (within 1 µm and 1e-5 rad).
#[test]
fn the_iiwa_scenes_are_the_lwr_scenes_with_the_tool_starting_at_the_same_pose() {
    for (name, q) in shipped_arm::scenes_match_the_lwr_scenes(IIWA14, "iiwa14") {
        // Elbow up: joint 4 (the elbow) bends the way the iiwa's elbow-up seed does.
        assert!(q[3] < -1.0, "{name}: {q:?}");
    }
}

/// The iiwa's links (Drake's cylinders, our wrist primitives) start clear of every object in its
/// scenes: a run cannot begin in an arm-contact reflex.
#[test]
fn the_iiwa_starts_clear_of_the_objects_in_its_scenes() {
    shipped_arm::starts_clear_of_the_objects("iiwa14");
}

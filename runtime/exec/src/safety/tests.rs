//! Unit tests of the supervisor: every reflex kind fires on a state built to cross it, and only then.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};

use super::*;
use crate::robot::{Robot, LWR4_URDF};

struct Case {
    robot: Robot,
    obs: Observation,
    sensed: ControlState,
    cmd: Command,
    torques: Vec<f64>,
}

/// A quiet tick: the arm at rest mid-range, the tool where it is commanded, no contact.
fn quiet() -> Case {
    let robot = Robot::from_urdf_str(LWR4_URDF, None).expect("bundled urdf");
    let mut obs = Observation::zeros(robot.dof());
    obs.q.copy_from_slice(&[0.0, 0.5, 0.0, -1.2, 0.0, 0.6, 0.0]);
    let tool = Isometry3::from_parts(Translation3::new(0.5, 0.0, 0.4), UnitQuaternion::identity());
    let sensed = ControlState {
        tool,
        twist: Vector6::zeros(),
        applied: Vector6::zeros(),
    };
    let cmd = Command::hold(tool, [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0]);
    let torques = vec![1.0; robot.dof()];
    Case {
        robot,
        obs,
        sensed,
        cmd,
        torques,
    }
}

fn limits() -> Limits {
    let workspace = Workspace::around([[0.5, 0.0, 0.4]].iter(), 0.3);
    Limits::for_skill(10.0, workspace)
}

fn check(case: &Case, supervisor: &mut Supervisor) -> Result<(), Violation> {
    supervisor.check(1.0, 0.001, &case.obs, &case.sensed, &case.cmd, &case.torques)
}

fn quantity_of(case: &Case) -> Option<Quantity> {
    let mut supervisor = Supervisor::new(&case.robot, limits());
    check(case, &mut supervisor).err().map(|v| v.quantity)
}

#[test]
fn a_quiet_tick_passes_and_is_counted() {
    let case = quiet();
    let mut supervisor = Supervisor::new(&case.robot, limits());
    check(&case, &mut supervisor).expect("nothing crossed");
    let stats = supervisor.stats();
    assert_eq!(stats.peak_force_n, 0.0);
    // Joint 4 at -1.2 rad is 0.894 rad from its -2.094 rad limit, the closest of all.
    assert!((stats.min_joint_margin_rad - (2.094_395_102_39 - 1.2)).abs() < 1e-9);
}

#[test]
fn non_finite_numbers_anywhere_are_a_reflex() {
    let mut case = quiet();
    case.torques[3] = f64::NAN;
    assert_eq!(quantity_of(&case), Some(Quantity::NonFinite));
    let mut case = quiet();
    case.cmd.pose.translation.vector.x = f64::INFINITY;
    assert_eq!(quantity_of(&case), Some(Quantity::NonFinite));
    let mut case = quiet();
    case.obs.wrench_base[2] = f64::NAN;
    assert_eq!(quantity_of(&case), Some(Quantity::NonFinite));
    let mut case = quiet();
    case.cmd.stiffness[0] = f64::NAN;
    assert_eq!(quantity_of(&case), Some(Quantity::NonFinite));
}

#[test]
fn contact_force_and_moment_above_their_limits_are_reflexes() {
    // Learned peak 10 N: the force limit is max(30, 40) = 40 N.
    let mut case = quiet();
    case.sensed.applied[2] = 39.0;
    assert_eq!(quantity_of(&case), None);
    case.sensed.applied[0] = 10.0;
    assert_eq!(quantity_of(&case), Some(Quantity::ContactForce));
    let mut case = quiet();
    case.sensed.applied[4] = 11.0;
    assert_eq!(quantity_of(&case), Some(Quantity::ContactMoment));
}

#[test]
fn tool_speeds_above_their_limits_are_reflexes() {
    let mut case = quiet();
    case.sensed.twist[0] = 0.2;
    assert_eq!(quantity_of(&case), None);
    case.sensed.twist[1] = 0.2;
    assert_eq!(quantity_of(&case), Some(Quantity::ToolSpeed));
    let mut case = quiet();
    case.sensed.twist[5] = 2.5;
    assert_eq!(quantity_of(&case), Some(Quantity::ToolAngularSpeed));
}

#[test]
fn joints_near_a_limit_or_too_fast_are_reflexes() {
    let mut case = quiet();
    case.obs.q[1] = 2.094 - 0.01;
    let mut supervisor = Supervisor::new(&case.robot, limits());
    let violation = check(&case, &mut supervisor).expect_err("1° margin crossed");
    assert_eq!(violation.quantity, Quantity::JointMargin);
    assert_eq!(violation.joint, Some(1));
    assert!(violation.to_string().contains("below the limit"), "{violation}");
    let mut case = quiet();
    case.obs.qd[6] = 3.3;
    assert_eq!(quantity_of(&case), Some(Quantity::JointSpeed));
}

#[test]
fn torque_saturation_fires_only_after_its_window() {
    let mut case = quiet();
    case.torques[6] = 38.0;
    let mut supervisor = Supervisor::new(&case.robot, limits());
    for _ in 0..100 {
        check(&case, &mut supervisor).expect("within the 100 ms window");
    }
    let violation = check(&case, &mut supervisor).expect_err("past the window");
    assert_eq!(violation.quantity, Quantity::TorqueSaturation);
    assert_eq!(violation.joint, Some(6));
    assert!(violation.detail.starts_with("joint `"), "{}", violation.detail);
    // Leaving saturation resets the window.
    let mut supervisor = Supervisor::new(&case.robot, limits());
    for tick in 0..300 {
        case.torques[6] = if tick % 50 == 49 { 0.0 } else { 38.0 };
        check(&case, &mut supervisor).expect("never held 100 ms");
    }
    assert!(supervisor.stats().torque_limit_s > 0.29);
}

#[test]
fn tracking_error_counts_only_position_controlled_axes() {
    let mut case = quiet();
    case.cmd.pose.translation.vector.z -= 0.08;
    assert_eq!(quantity_of(&case), Some(Quantity::TrackingError));
    // The same error along a force-controlled z is the force loop's business, not a reflex.
    case.cmd.position[2] = false;
    assert_eq!(quantity_of(&case), None);
    let mut case = quiet();
    case.cmd.pose.rotation = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.5);
    assert_eq!(quantity_of(&case), Some(Quantity::TrackingAngle));
}

#[test]
fn leaving_the_workspace_is_a_reflex() {
    let mut case = quiet();
    let far = Isometry3::from_parts(Translation3::new(0.5, 0.0, 0.05), UnitQuaternion::identity());
    case.sensed.tool = far;
    case.cmd.pose = far;
    let mut supervisor = Supervisor::new(&case.robot, limits());
    let violation = check(&case, &mut supervisor).expect_err("5 cm below the box");
    assert_eq!(violation.quantity, Quantity::Workspace);
    assert!((violation.measured - 0.05).abs() < 1e-9);
}

#[test]
fn the_stop_holds_gravity_and_damps_motion() {
    let case = quiet();
    let mut supervisor = Supervisor::new(&case.robot, limits());
    let mut at_rest = vec![0.0; 7];
    supervisor.stop_torques(&case.obs, &mut at_rest);
    let mut data = case.robot.data();
    case.robot.forward_kinematics(&mut data, case.obs.q.as_slice());
    let mut gravity = vec![0.0; 7];
    case.robot.gravity_torques(&mut data, &mut gravity);
    for (stop, g) in at_rest.iter().zip(&gravity) {
        assert!((stop - g).abs() < 1e-12);
    }
    let mut moving = case.obs.clone();
    moving.qd[0] = 0.5;
    let mut braking = vec![0.0; 7];
    supervisor.stop_torques(&moving, &mut braking);
    assert!(braking[0] < gravity[0], "damping opposes the motion");
    let mut broken = case.obs.clone();
    broken.q[2] = f64::NAN;
    supervisor.stop_torques(&broken, &mut braking);
    assert!(braking.iter().all(|tau| *tau == 0.0));
}

#[test]
fn arm_contact_above_its_limit_is_a_reflex_that_names_the_link() {
    let mut case = quiet();
    let link = case.robot.link_index("lwr_3_link").expect("an LWR link");
    // Below the limit (a graze): nothing.
    case.obs.arm_contact_n = 0.8 * ARM_CONTACT_N;
    case.obs.arm_contact_link = Some(link);
    assert_eq!(quantity_of(&case), None);
    // Above it, and above the tool's force limit too: the arm contact is named first.
    case.obs.arm_contact_n = 2.0 * ARM_CONTACT_N;
    case.sensed.applied[2] = 100.0;
    let mut supervisor = Supervisor::new(&case.robot, limits());
    let violation = check(&case, &mut supervisor).expect_err("a link touches the scene");
    assert_eq!(violation.quantity, Quantity::ArmContact);
    assert_eq!(violation.limit, ARM_CONTACT_N);
    let text = violation.to_string();
    assert!(text.contains("link `lwr_3_link`"), "{text}");
    // The limit has a name, and switching it off lets the tick pass the arm check.
    let mut loose = limits();
    loose.set("arm_contact", f64::INFINITY).expect("a named limit");
    case.sensed.applied[2] = 0.0;
    let mut supervisor = Supervisor::new(&case.robot, loose);
    check(&case, &mut supervisor).expect("arm contact switched off");
    // A non-finite contact force is caught as such.
    case.obs.arm_contact_n = f64::NAN;
    assert_eq!(quantity_of(&case), Some(Quantity::NonFinite));
}

//! Acceptance tests of the robot model (issue 3 §2): DH agreement, Jacobian, mass matrix, Newton-Euler.

use nalgebra::{DMatrix, DVector, Matrix4, Matrix6xX, Vector3};
use skill_runtime::robot::{Robot, RobotData, LWR4_FLANGE, LWR4_TOOL, LWR4_URDF};

/// A tiny deterministic generator (splitmix64) so the tests need no extra crate.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    fn vector(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
}

fn lwr4() -> Robot {
    Robot::from_urdf_str(LWR4_URDF, None).expect("the bundled urdf loads")
}

/// Standard DH of the LWR IV (SOURCES.md): T_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i), a_i = 0.
fn dh_flange(q: &[f64]) -> Matrix4<f64> {
    use std::f64::consts::FRAC_PI_2;
    let alpha = [FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, 0.0];
    let d = [0.3105, 0.0, 0.4, 0.0, 0.39, 0.0, 0.078];
    let mut t = Matrix4::identity();
    for i in 0..7 {
        let (st, ct) = q[i].sin_cos();
        let (sa, ca) = alpha[i].sin_cos();
        #[rustfmt::skip]
        let link = Matrix4::new(
            ct, -st * ca, st * sa, 0.0,
            st, ct * ca, -ct * sa, 0.0,
            0.0, sa, ca, d[i],
            0.0, 0.0, 0.0, 1.0,
        );
        t *= link;
    }
    t
}

#[test]
fn lwr4_loads_as_seven_joint_chain() {
    let robot = lwr4();
    assert_eq!(robot.dof(), 7);
    assert_eq!(robot.name(), "kuka_lwr4");
    assert_eq!(robot.links()[robot.tool_link()].name, LWR4_TOOL);
    let names: Vec<&str> = robot.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "lwr_a1_joint",
            "lwr_a2_joint",
            "lwr_e1_joint",
            "lwr_a3_joint",
            "lwr_a4_joint",
            "lwr_a5_joint",
            "lwr_a6_joint"
        ]
    );
    // 5 x 2.35 + 1.1 + 0.25 kg of arm plus the 0.2 kg probe.
    assert!((robot.moving_mass() - 13.3).abs() < 1e-12);
    assert!((robot.joints()[1].effort - 176.0).abs() < 1e-12);
    assert!((robot.joints()[6].upper - 170f64.to_radians()).abs() < 1e-9);
}

#[test]
fn flange_pose_equals_lwr4_dh_model() {
    let robot = lwr4();
    let flange = robot.link_index(LWR4_FLANGE).expect("flange link");
    let mut data = robot.data();
    let mut rng = Rng(1);
    let mut worst = 0.0f64;
    for _ in 0..500 {
        let q = rng.vector(7, -2.9, 2.9);
        robot.forward_kinematics(&mut data, &q);
        let urdf = robot.link_in_base_matrix(&data, flange).to_homogeneous();
        worst = worst.max((urdf - dh_flange(&q)).abs().max());
    }
    assert!(worst < 1e-9, "max |T_urdf - T_dh| = {worst:e}");
}

#[test]
fn tool_tip_sits_on_flange_z_axis() {
    let robot = lwr4();
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, &[0.0; 7]);
    let tool = robot.tool_in_base(&data);
    // 0.3105 + 0.4 + 0.39 + 0.078 m to the flange, then 0.11 m to the tip centre.
    assert!((tool.translation.vector - Vector3::new(0.0, 0.0, 1.2885)).norm() < 1e-12);
}

#[test]
fn jacobian_matches_finite_differences() {
    let robot = lwr4();
    let mut data = robot.data();
    let mut jacobian = Matrix6xX::zeros(7);
    let mut rng = Rng(2);
    let h = 1e-6;
    for _ in 0..50 {
        let q = rng.vector(7, -2.0, 2.0);
        robot.forward_kinematics(&mut data, &q);
        robot.tool_jacobian(&data, &mut jacobian);
        for j in 0..7 {
            let mut plus = q.clone();
            let mut minus = q.clone();
            plus[j] += h;
            minus[j] -= h;
            robot.forward_kinematics(&mut data, &plus);
            let pose_plus = robot.tool_in_base(&data);
            robot.forward_kinematics(&mut data, &minus);
            let pose_minus = robot.tool_in_base(&data);
            let linear = (pose_plus.translation.vector - pose_minus.translation.vector) / (2.0 * h);
            let delta = pose_plus.rotation * pose_minus.rotation.inverse();
            let angular = delta.scaled_axis() / (2.0 * h);
            let column = jacobian.column(j);
            for row in 0..3 {
                assert!((column[row] - linear[row]).abs() < 1e-7, "v row {row} joint {j}");
                assert!((column[row + 3] - angular[row]).abs() < 1e-7, "w row {row} joint {j}");
            }
        }
    }
}

fn mass_matrix_at(robot: &Robot, data: &mut RobotData, q: &[f64]) -> DMatrix<f64> {
    let mut mass = DMatrix::zeros(7, 7);
    robot.forward_kinematics(data, q);
    robot.mass_matrix(data, &mut mass);
    mass
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_matches_kinetic_energy() {
    let robot = lwr4();
    let mut data = robot.data();
    let mut rng = Rng(3);
    let mut jacobian = Matrix6xX::zeros(7);
    for _ in 0..50 {
        let q = rng.vector(7, -2.0, 2.0);
        let qd = DVector::from_vec(rng.vector(7, -1.0, 1.0));
        let mass = mass_matrix_at(&robot, &mut data, &q);
        assert!((&mass - mass.transpose()).abs().max() < 1e-14);
        let eigen = mass.clone().symmetric_eigen();
        assert!(eigen.eigenvalues.min() > 1e-5, "eigenvalues {}", eigen.eigenvalues);
        // Independent check: kinetic energy from every link's centre-of-mass velocity.
        let mut energy = 0.0;
        for (link_idx, link) in robot.links().iter().enumerate() {
            if link.inertial.mass == 0.0 || link.body.is_none() {
                continue;
            }
            robot.link_jacobian(&data, link_idx, &link.inertial.com, &mut jacobian);
            let twist = &jacobian * &qd;
            let v = twist.fixed_rows::<3>(0);
            let w = twist.fixed_rows::<3>(3);
            let rot = robot.link_in_base_matrix(&data, link_idx).rotation;
            let inertia_base = rot.matrix() * link.inertial.inertia * rot.matrix().transpose();
            energy += 0.5 * link.inertial.mass * v.norm_squared() + 0.5 * w.dot(&(inertia_base * w));
        }
        let from_matrix = 0.5 * qd.dot(&(&mass * &qd));
        assert!((energy - from_matrix).abs() < 1e-12, "{energy} vs {from_matrix}");
    }
}

#[test]
fn newton_euler_equals_lagrangian_terms() {
    let robot = lwr4();
    let mut data = robot.data();
    let mut rng = Rng(4);
    let h = 1e-6;
    for _ in 0..20 {
        let q = rng.vector(7, -2.0, 2.0);
        let qd = DVector::from_vec(rng.vector(7, -1.5, 1.5));
        let qdd = DVector::from_vec(rng.vector(7, -3.0, 3.0));
        let mass = mass_matrix_at(&robot, &mut data, &q);
        let mut tau = vec![0.0; 7];
        let mut gravity = vec![0.0; 7];
        let mut coriolis = vec![0.0; 7];
        robot.inverse_dynamics(&mut data, qd.as_slice(), qdd.as_slice(), &mut tau);
        robot.gravity_torques(&mut data, &mut gravity);
        robot.coriolis_torques(&mut data, qd.as_slice(), &mut coriolis);
        let sum = &mass * &qdd + DVector::from_vec(coriolis.clone()) + DVector::from_vec(gravity.clone());
        assert!((DVector::from_vec(tau) - sum).abs().max() < 1e-10);
        // Independent Coriolis check: C(q, q̇) q̇ = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q, Ṁ by finite differences.
        let mut mass_dot = DMatrix::zeros(7, 7);
        let mut energy_gradient = DVector::zeros(7);
        for k in 0..7 {
            let mut plus = q.clone();
            let mut minus = q.clone();
            plus[k] += h;
            minus[k] -= h;
            let d_mass =
                (mass_matrix_at(&robot, &mut data, &plus) - mass_matrix_at(&robot, &mut data, &minus)) / (2.0 * h);
            mass_dot += &d_mass * qd[k];
            energy_gradient[k] = 0.5 * qd.dot(&(&d_mass * &qd));
        }
        let lagrange = &mass_dot * &qd - energy_gradient;
        let error = (lagrange - DVector::from_vec(coriolis)).abs().max();
        assert!(error < 1e-6, "coriolis mismatch {error:e}");
        // Independent gravity check: g = −Σ J_com,iᵀ m_i g0.
        robot.forward_kinematics(&mut data, &q);
        let mut jacobian = Matrix6xX::zeros(7);
        let mut potential = DVector::zeros(7);
        for (link_idx, link) in robot.links().iter().enumerate() {
            if link.inertial.mass == 0.0 || link.body.is_none() {
                continue;
            }
            robot.link_jacobian(&data, link_idx, &link.inertial.com, &mut jacobian);
            let force = -robot.gravity() * link.inertial.mass;
            potential += jacobian.fixed_rows::<3>(0).transpose() * force;
        }
        assert!((potential - DVector::from_vec(gravity)).abs().max() < 1e-10);
    }
}

#[test]
fn horizontal_arm_gravity_torque_at_a2() {
    let robot = lwr4();
    let (_, _, gravity) = robot.evaluate(&[0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // Reference without the probe: -48.1 N m (SOURCES.md); the 0.2 kg probe, its centre of mass
    // 0.4 + 0.39 + 0.078 + 0.05 m from A2, adds 0.2 * 9.81 * 0.918 N m. Axis A2 is -y, so the sign flips.
    let expected = -48.1 - 0.2 * 9.81 * 0.918;
    assert!((gravity[1] - expected).abs() < 0.05, "g2 = {}", gravity[1]);
    // The shoulder and wrist rotations carry no gravity load in this pose.
    assert!(gravity[0].abs() < 1e-12 && gravity[2].abs() < 1e-9);
}

/// The composite-rigid-body mass matrix against Newton-Euler, column by column:
/// `M e_j = ID(q, 0, e_j) − g(q)`, on random configurations of the LWR-IV and of the iiwa.
#[test]
fn mass_matrix_columns_match_newton_euler() {
    let iiwa = skill_runtime::robot::IIWA14.load().expect("the shipped iiwa loads");
    for robot in [lwr4(), iiwa] {
        let n = robot.dof();
        let mut data = robot.data();
        let mut rng = Rng(17);
        let mut mass = DMatrix::zeros(n, n);
        let (mut gravity, mut column, zeros) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for _ in 0..50 {
            let q = rng.vector(n, -2.5, 2.5);
            robot.forward_kinematics(&mut data, &q);
            robot.mass_matrix(&mut data, &mut mass);
            robot.gravity_torques(&mut data, &mut gravity);
            for j in 0..n {
                let mut unit = vec![0.0; n];
                unit[j] = 1.0;
                robot.inverse_dynamics(&mut data, &zeros, &unit, &mut column);
                for i in 0..n {
                    let expected = column[i] - gravity[i];
                    assert!(
                        (mass[(i, j)] - expected).abs() < 1e-12 * (1.0 + expected.abs()),
                        "M[{i}][{j}] = {} against {expected} at {q:?}",
                        mass[(i, j)]
                    );
                }
            }
        }
    }
}

#[test]
fn gravity_torques_match_newton_euler() {
    let iiwa = skill_runtime::robot::IIWA14.load().expect("the shipped iiwa loads");
    let slider = Robot::from_urdf_str(SLIDER_URDF, None).expect("valid urdf");
    let mut tilted = lwr4();
    tilted.set_gravity(Vector3::new(1.2, -0.7, -9.7));
    for robot in [lwr4(), iiwa, slider, tilted] {
        let n = robot.dof();
        let mut data = robot.data();
        let mut rng = Rng(29);
        let (mut gravity, mut reference, zeros) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for _ in 0..50 {
            let q = rng.vector(n, -2.5, 2.5);
            robot.forward_kinematics(&mut data, &q);
            robot.gravity_torques(&mut data, &mut gravity);
            robot.inverse_dynamics(&mut data, &zeros, &zeros, &mut reference);
            for i in 0..n {
                assert!(
                    (gravity[i] - reference[i]).abs() < 1e-12 * (1.0 + reference[i].abs()),
                    "g[{i}] = {} against Newton-Euler {} at {q:?}",
                    gravity[i],
                    reference[i]
                );
            }
        }
    }
}

/// A prismatic joint carrying a revolute one.
const SLIDER_URDF: &str = r#"<robot name="slider">
      <link name="base"/>
      <link name="carriage"><inertial><origin xyz="0.1 0 0"/><mass value="2"/>
        <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
      <link name="arm"><inertial><origin xyz="0 0 0.2"/><mass value="1"/>
        <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
      <joint name="slide" type="prismatic"><parent link="base"/><child link="carriage"/>
        <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="100" velocity="1"/></joint>
      <joint name="turn" type="revolute"><parent link="carriage"/><child link="arm"/>
        <origin xyz="0.2 0 0"/><axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
    </robot>"#;

#[test]
fn prismatic_joint_dynamics_are_consistent() {
    let robot = Robot::from_urdf_str(SLIDER_URDF, None).expect("valid urdf");
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, &[0.3, 0.0]);
    let mut gravity = [0.0; 2];
    robot.gravity_torques(&mut data, &mut gravity);
    // The slide carries both masses against gravity; the arm hangs straight up, no torque.
    assert!((gravity[0] - 3.0 * 9.81).abs() < 1e-12);
    assert!(gravity[1].abs() < 1e-12);
    let mut jacobian = Matrix6xX::zeros(2);
    robot.tool_jacobian(&data, &mut jacobian);
    assert!((jacobian[(2, 0)] - 1.0).abs() < 1e-15 && (jacobian[(3, 1)] - 1.0).abs() < 1e-15);
    let mut mass = DMatrix::zeros(2, 2);
    robot.mass_matrix(&mut data, &mut mass);
    assert!((mass[(0, 0)] - 3.0).abs() < 1e-12);
    // Arm about its joint: 0.01 + 1 * 0.2² kg m².
    assert!((mass[(1, 1)] - 0.05).abs() < 1e-12);
}

#[test]
fn inspection_has_the_cli_json_keys() {
    let robot = lwr4();
    let q = [0.0, std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0];
    let inspection = robot.inspect(Some(&q)).expect("7 finite values");
    let json = serde_json::to_value(&inspection).expect("serialisable");
    let object = json.as_object().expect("one object");
    let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "dof",
            "gravity_torque",
            "jacobian",
            "joints",
            "notes",
            "q",
            "robot",
            "tool_link",
            "tool_position",
            "tool_quaternion_wxyz"
        ]
    );
    assert_eq!(json["jacobian"].as_array().map(Vec::len), Some(6));
    assert_eq!(json["jacobian"][0].as_array().map(Vec::len), Some(7));
    let joint_keys: Vec<&str> = json["joints"][0]
        .as_object()
        .expect("joint")
        .keys()
        .map(String::as_str)
        .collect();
    assert_eq!(joint_keys.len(), 6);
    for key in ["name", "axis", "lower", "upper", "velocity", "effort"] {
        assert!(joint_keys.contains(&key), "missing joint key {key}");
    }
    assert!(inspection.to_text().contains("lwr_a2_joint"));
    assert!(matches!(
        robot.inspect(Some(&[0.0; 3])),
        Err(skill_runtime::robot::RobotError::WrongDof { .. })
    ));
}

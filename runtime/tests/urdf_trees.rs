//! URDFs as vendors ship them: a gripper with two fingers off the arm's chain, an inertial fixed
//! base, missing limits, and files that are not URDF (xacro), each with its stated outcome.

use skill_runtime::robot::{Robot, DEFAULT_EFFORT, DEFAULT_VELOCITY};

fn inertial(mass: f64, z: f64) -> String {
    format!(
        r#"<inertial><origin xyz="0 0 {z}"/><mass value="{mass}"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>"#
    )
}

fn revolute(name: &str, parent: &str, child: &str, z: f64, axis: &str) -> String {
    format!(
        r#"<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/><origin xyz="0 0 {z}"/><axis xyz="{axis}"/><limit lower="-2" upper="2" effort="50" velocity="2"/></joint>"#
    )
}

/// A three-joint arm ending in `hand`, then `tip` (the tool) on a fixed joint, and — when
/// `fingers` — two prismatic fingers of `finger_mass` at ±4 cm and a fixed grasp frame.
fn arm(fingers: bool, finger_mass: f64) -> String {
    let mut urdf = String::from(r#"<robot name="arm">"#);
    urdf += &format!(
        r#"<link name="base">{}</link>"#,
        inertial(0.0, 0.0).replace(r#"ixx="0.01""#, r#"ixx="0.5""#)
    );
    for (link, mass) in [("l1", 3.0), ("l2", 2.0), ("hand", 1.0)] {
        urdf += &format!(r#"<link name="{link}">{}</link>"#, inertial(mass, 0.1));
    }
    urdf += r#"<link name="tip"/>"#;
    urdf += &revolute("j1", "base", "l1", 0.3, "0 0 1");
    urdf += &revolute("j2", "l1", "l2", 0.2, "0 1 0");
    urdf += &revolute("j3", "l2", "hand", 0.4, "0 1 0");
    urdf +=
        r#"<joint name="tool" type="fixed"><parent link="hand"/><child link="tip"/><origin xyz="0 0 0.1"/></joint>"#;
    if fingers {
        for (name, side) in [("left", 1.0), ("right", -1.0)] {
            urdf += &format!(
                r#"<link name="{name}_finger"><inertial><origin xyz="0 {y} 0.05"/><mass value="{finger_mass}"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>"#,
                y = 0.04 * side
            );
            urdf += &format!(
                r#"<joint name="{name}_joint" type="prismatic"><parent link="hand"/><child link="{name}_finger"/><axis xyz="0 {side} 0"/><limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint>"#
            );
        }
        urdf += r#"<link name="grasp"/><joint name="grasp_joint" type="fixed"><parent link="hand"/><child link="grasp"/><origin xyz="0 0 0.12"/></joint>"#;
    }
    urdf + "</robot>"
}

/// The same arm without fingers, their combined mass carried by a fixed link at their midpoint.
fn arm_with_lumped_fingers(finger_mass: f64) -> String {
    let mut urdf = arm(false, 0.0);
    urdf.truncate(urdf.len() - "</robot>".len());
    urdf += &format!(
        r#"<link name="fingers"><inertial><origin xyz="0 0 0.05"/><mass value="{}"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>"#,
        2.0 * finger_mass
    );
    urdf += r#"<joint name="fingers_joint" type="fixed"><parent link="hand"/><child link="fingers"/></joint>"#;
    urdf + "</robot>"
}

fn gravity_and_tool(robot: &Robot, q: &[f64]) -> (Vec<f64>, nalgebra::Isometry3<f64>) {
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, q);
    let mut gravity = vec![0.0; robot.dof()];
    robot.gravity_torques(&mut data, &mut gravity);
    (gravity, robot.tool_in_base(&data))
}

#[test]
fn a_gripper_with_two_fingers_loads_the_arm_chain_and_lumps_the_fingers() {
    let tree = Robot::from_urdf_str(&arm(true, 0.1), Some("tip")).expect("the tree loads with a tool on the arm");
    assert_eq!(tree.dof(), 3, "the fingers are held, not joints of the model");
    let notes = tree.notes().join("\n");
    assert!(notes.contains("branch at link `hand`"), "{notes}");
    assert!(
        notes.contains("`left_joint` at 0 m") && notes.contains("`right_joint` at 0 m"),
        "{notes}"
    );
    assert!(notes.contains("link `base` is fixed to the base"), "{notes}");
    // The fingers' links are known (for collisions and frames), on the hand's body.
    let left = tree.link_index("left_finger").expect("branch links are kept");
    assert_eq!(tree.links()[left].body, Some(2));

    // Gravity depends on mass and centre of mass only: the tree equals a chain carrying both
    // fingers' mass at their midpoint; the tool pose does not depend on the branch at all.
    let chain = Robot::from_urdf_str(&arm_with_lumped_fingers(0.1), Some("tip")).expect("chain loads");
    for q in [[0.0, 0.0, 0.0], [0.3, -0.7, 1.1], [-1.2, 0.4, -0.9]] {
        let (g_tree, tool_tree) = gravity_and_tool(&tree, &q);
        let (g_chain, tool_chain) = gravity_and_tool(&chain, &q);
        for (a, b) in g_tree.iter().zip(&g_chain) {
            assert!((a - b).abs() < 1e-12, "gravity {g_tree:?} vs {g_chain:?}");
        }
        assert!((tool_tree.translation.vector - tool_chain.translation.vector).norm() < 1e-12);
    }
    assert!((tree.moving_mass() - (6.0 + 0.2)).abs() < 1e-12);
}

#[test]
fn a_tree_without_a_named_tool_asks_for_one() {
    let err = Robot::from_urdf_str(&arm(true, 0.1), None).expect_err("two fingers end equally long chains");
    let message = err.to_string();
    assert!(
        message.contains("several ends (`left_finger`, `right_finger`)"),
        "{message}"
    );
    assert!(message.contains("name the tool link"), "{message}");
}

#[test]
fn an_inertial_fixed_base_is_a_note_not_an_error() {
    // `base` has zero mass and a non-zero inertia (as a widely used simulator's iiwa file does).
    let robot = Robot::from_urdf_str(&arm(false, 0.0), None).expect("a fixed base's inertia is ignored");
    assert_eq!(robot.links()[robot.tool_link()].name, "tip");
    let notes = robot.notes().join("\n");
    assert!(
        notes.contains("link `base` is fixed to the base, so its inertial values are ignored"),
        "{notes}"
    );
    // The same values as the only link a joint moves are an error: the joint moves no mass.
    let moving = arm(false, 0.0).replace(
        &inertial(2.0, 0.1),
        &inertial(0.0, 0.1).replace(r#"ixx="0.01""#, r#"ixx="0.5""#),
    );
    let err = Robot::from_urdf_str(&moving, None).expect_err("a moving body needs mass");
    assert!(err.to_string().contains("joint `j2` moves no mass"), "{err}");
}

#[test]
fn missing_limits_get_the_stated_defaults_with_a_warning() {
    let urdf = arm(false, 0.0).replace(
        r#"<limit lower="-2" upper="2" effort="50" velocity="2"/></joint><joint name="j3""#,
        r#"</joint><joint name="j3""#,
    );
    let robot = Robot::from_urdf_str(&urdf, None).expect("missing limits are defaulted");
    let j2 = &robot.joints()[1];
    assert_eq!(j2.effort, DEFAULT_EFFORT);
    assert_eq!(j2.velocity, DEFAULT_VELOCITY);
    assert!((j2.upper - std::f64::consts::PI).abs() < 1e-12);
    let warnings: Vec<&String> = robot.notes().iter().filter(|n| n.starts_with("warning:")).collect();
    assert_eq!(warnings.len(), 3, "{warnings:?}");
}

#[test]
fn a_xacro_file_is_refused_with_how_to_expand_it() {
    let dir = std::env::temp_dir().join(format!("skillc-xacro-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("arm.urdf.xacro");
    let text = arm(false, 0.0).replace(r#"<origin xyz="0 0 0.4"/>"#, r#"<origin xyz="0 0 ${l/2}"/>"#);
    std::fs::write(&path, text).expect("write");
    let err = Robot::from_urdf_file(&path, None).expect_err("xacro must be expanded first");
    let message = err.to_string();
    assert!(message.contains("arm.urdf.xacro` is a xacro file"), "{message}");
    assert!(
        message.contains("xacro ") && message.contains("> robot.urdf"),
        "{message}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The joint-space mass matrix at `q`.
fn mass_matrix(robot: &Robot, q: &[f64]) -> nalgebra::DMatrix<f64> {
    let mut data = robot.data();
    robot.forward_kinematics(&mut data, q);
    let mut m = nalgebra::DMatrix::zeros(robot.dof(), robot.dof());
    robot.mass_matrix(&mut data, &mut m);
    m
}

#[test]
fn an_expanded_urdf_that_still_declares_the_xacro_namespace_loads() {
    let text = arm(false, 0.0).replace(
        r#"<robot name="arm">"#,
        r#"<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">"#,
    );
    let robot = Robot::from_urdf_str(&text, Some("tip")).expect("no xacro element or expression remains");
    assert_eq!(robot.dof(), 3);
    // An element or expression that remains is still refused.
    let macro_left = text.replace(
        r#"<link name="tip"/>"#,
        r#"<link name="tip"/><xacro:include filename="x.xacro"/>"#,
    );
    let err = Robot::from_urdf_str(&macro_left, Some("tip")).expect_err("a xacro element remains");
    assert!(err.to_string().contains("xacro file"), "{err}");
}

#[test]
fn a_massless_link_with_inertia_on_a_fixed_joint_is_lumped_with_a_note() {
    // As Franka's panda_link8: zero mass, a non-zero tensor, hung on the hand by a fixed joint.
    let tensor = r#"<inertia ixx="0.002" ixy="0.0005" ixz="0" iyy="0.003" iyz="0" izz="0.001"/>"#;
    let mut with_link8 = arm(false, 0.0);
    with_link8.truncate(with_link8.len() - "</robot>".len());
    with_link8 += &format!(
        r#"<link name="link8"><inertial><origin xyz="0 0 0.05"/><mass value="0"/>{tensor}</inertial></link><joint name="j8" type="fixed"><parent link="hand"/><child link="link8"/><origin xyz="0 0 0.1"/></joint></robot>"#
    );
    let robot = Robot::from_urdf_str(&with_link8, Some("tip")).expect("loads, as pinocchio loads it");
    let notes = robot.notes().join("\n");
    assert!(
        notes.contains("link `link8` has zero mass but an inertia tensor"),
        "{notes}"
    );
    // Ground truth: the same tensor added to the hand's own inertia (about its centre of mass;
    // with no mass there is no parallel-axis term, so where it hangs does not matter).
    let hand = r#"<link name="hand"><inertial><origin xyz="0 0 0.1"/><mass value="1"/><inertia ixx="0.012" ixy="0.0005" ixz="0" iyy="0.013" iyz="0" izz="0.011"/></inertial></link>"#;
    let start = arm(false, 0.0).find(r#"<link name="hand">"#).expect("hand");
    let plain = arm(false, 0.0);
    let end = start + plain[start..].find("</link>").expect("end") + "</link>".len();
    let merged = format!("{}{hand}{}", &plain[..start], &plain[end..]);
    let reference = Robot::from_urdf_str(&merged, Some("tip")).expect("reference");
    let without = Robot::from_urdf_str(&plain, Some("tip")).expect("without the link");
    for q in [[0.0, 0.0, 0.0], [0.3, -0.7, 1.1], [-1.2, 0.4, -0.9]] {
        let (a, b) = (mass_matrix(&robot, &q), mass_matrix(&reference, &q));
        assert!((&a - &b).abs().max() < 1e-12, "{a} vs {b}");
        assert!((&a - mass_matrix(&without, &q)).abs().max() > 1e-4, "the tensor counts");
    }
    // A tensor no body can have stays an error.
    let bad = with_link8.replace(r#"ixx="0.002""#, r#"ixx="-0.002""#);
    let err = Robot::from_urdf_str(&bad, Some("tip")).expect_err("not positive semi-definite");
    assert!(err.to_string().contains("not positive semi-definite"), "{err}");
}

#[test]
fn an_overflowing_number_is_refused_by_line_and_attribute_and_inf_is_not() {
    let text = arm(false, 0.0).replacen(r#"effort="50""#, "\neffort=\"1e309\"", 1);
    let err = Robot::from_urdf_str(&text, Some("tip")).expect_err("1e309 overflows");
    assert_eq!(
        err.to_string(),
        "`<string>`, line 2: `1e309` in `effort` of `<limit>` is too large for a number (it would overflow to infinity); write a finite value, or `inf` where no limit is meant"
    );
    let origin = arm(false, 0.0).replacen(r#"<origin xyz="0 0 0.3"/>"#, r#"<origin xyz="0 -1e400 0.3"/>"#, 1);
    let err = Robot::from_urdf_str(&origin, Some("tip")).expect_err("-1e400 overflows");
    assert!(err.to_string().contains("`-1e400` in `xyz` of `<origin>`"), "{err}");
    let inf = arm(false, 0.0).replacen(r#"effort="50""#, r#"effort="inf""#, 1);
    let robot = Robot::from_urdf_str(&inf, Some("tip")).expect("the word inf is the user's choice");
    assert!(robot.joints()[0].effort.is_infinite());
}

//! A scene's `robot.tool_start`: the tool's start pose instead of joint angles, solved by
//! inverse kinematics (seeded from `q0` when given), refused with the key when out of reach, and
//! changed by `--set` overrides like any other key.

mod support;

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use skill_runtime::plant::Plant;
use skill_runtime::robot::{Robot, LWR4_ELBOW_UP, LWR4_TOOL, LWR4_URDF};
use skill_runtime::sim::{RapierPlant, Scene, SceneError, SimError};
use support::root;

const PI: f64 = std::f64::consts::PI;

/// A scene with `robot_lines` under `[robot]` (after the URDF and the tool) and a table far below.
fn scene_with(robot_lines: &str) -> Scene {
    let text = format!(
        "[robot]\nurdf = \"examples/robots/lwr4.urdf\"\ntool = \"probe_tip\"\n{robot_lines}\n\n\
         [objects.floor]\nkind = \"box\"\nxyz = [0.5, 0.0, -0.5]\nsize = [1.0, 1.0, 0.1]\n"
    );
    Scene::from_toml(&text, "start.toml", &root()).expect("the scene reads")
}

fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

/// How far the simulated tool starts from `target` \[m, rad\].
fn start_miss(plant: &RapierPlant, target: &Isometry3<f64>) -> (f64, f64) {
    let tool = plant.robot().link_index(LWR4_TOOL).expect("the probe tip");
    let at = plant.link_pose(tool).expect("a simulated link");
    (
        (at.translation.vector - target.translation.vector).norm(),
        at.rotation.angle_to(&target.rotation),
    )
}

fn assert_starts_at(plant: &RapierPlant, target: &Isometry3<f64>) {
    let (miss_m, miss_rad) = start_miss(plant, target);
    assert!(
        miss_m < 1e-3 && miss_rad < 0.1f64.to_radians(),
        "tool starts {:.3} mm, {:.4}° from where the scene asks",
        miss_m * 1e3,
        miss_rad.to_degrees()
    );
}

#[test]
fn a_tool_start_puts_the_tool_where_asked() {
    // Beside and above the shipped start, tilted 0.2 rad and turned a quarter turn about the probe.
    let (xyz, rpy) = ([0.45, 0.2, 0.42], [PI, 0.2, PI / 2.0]);
    let scene = scene_with(&format!("tool_start = {{ xyz = {xyz:?}, rpy = {rpy:?} }}"));
    let plant = RapierPlant::from_scene(&scene).expect("a reachable start builds");
    let target = pose(xyz, rpy);
    assert_starts_at(&plant, &target);
    // The simulation starts at the configuration the scene reports, and by the default seed it
    // is elbow up (A4 bent the way the shipped start bends it).
    let robot = plant.robot().clone();
    let q = scene.start_configuration(&robot).expect("reachable");
    let observed = plant.observe().q;
    for (a, b) in q.iter().zip(observed.iter()) {
        assert!((a - b).abs() < 1e-9, "{q:?} vs {observed:?}");
    }
    assert!(q[3] > 0.5, "elbow up: A4 = {} rad", q[3]);
}

#[test]
fn q0_beside_a_tool_start_seeds_its_inverse_kinematics() {
    let robot = Robot::from_urdf_str(LWR4_URDF, Some(LWR4_TOOL)).expect("bundled urdf");
    // The same tool pose from two elbow configurations of the redundant arm: each seed keeps
    // its own, so the seed is what decides.
    let (target, _, _) = robot.evaluate(&LWR4_ELBOW_UP);
    let (roll, pitch, yaw) = target.rotation.euler_angles();
    let p = target.translation.vector;
    let line = format!(
        "tool_start = {{ xyz = [{}, {}, {}], rpy = [{roll}, {pitch}, {yaw}] }}",
        p.x, p.y, p.z
    );
    let mut swung = LWR4_ELBOW_UP;
    swung[0] = 0.4;
    swung[2] = -0.4;
    let seeded = scene_with(&format!("{line}\nq0 = {swung:?}"));
    let unseeded = scene_with(&line);
    let q_seeded = seeded.start_configuration(&robot).expect("reachable");
    let q_default = unseeded.start_configuration(&robot).expect("reachable");
    assert!(
        (q_seeded[2] - q_default[2]).abs() > 0.1,
        "the elbow follows the seed: A3 {} vs {}",
        q_seeded[2],
        q_default[2]
    );
    for scene in [seeded, unseeded] {
        let plant = RapierPlant::from_scene(&scene).expect("builds");
        assert_starts_at(&plant, &target);
    }
    // A seed of the wrong length is named as the seed.
    let err = scene_with(&format!("{line}\nq0 = [0.0, 0.0]"))
        .start_configuration(&robot)
        .expect_err("a 2-joint seed");
    assert!(err.to_string().contains("`robot.q0`"), "{err}");
}

#[test]
fn an_unreachable_tool_start_is_refused_naming_the_file_and_the_key() {
    let scene = scene_with(&format!(
        "tool_start = {{ xyz = [1.2, 0.0, 0.3], rpy = [{PI}, 0.0, 0.0] }}"
    ));
    let err = RapierPlant::from_scene(&scene).expect_err("1.2 m is beyond the LWR-IV's reach");
    assert!(
        matches!(err, SimError::Scene(SceneError::Invalid { ref key, .. }) if key == "robot.tool_start"),
        "{err:?}"
    );
    let message = err.to_string();
    assert!(
        message.contains("scene `start.toml`")
            && message.contains("`robot.tool_start`")
            && message.contains("out of reach"),
        "{message}"
    );
    // Non-finite numbers never reach the solver.
    let err = Scene::from_toml(
        "[robot]\nurdf = \"x.urdf\"\ntool_start = { xyz = [nan, 0.0, 0.3], rpy = [0.0, 0.0, 0.0] }\n",
        "nan.toml",
        &root(),
    )
    .expect_err("nan");
    assert!(err.to_string().contains("`robot.tool_start`"), "{err}");
}

#[test]
fn overrides_reach_into_the_tool_start() {
    let (xyz, rpy) = ([0.5, 0.0, 0.4], [PI, 0.0, PI]);
    let mut scene = scene_with(&format!("tool_start = {{ xyz = {xyz:?}, rpy = {rpy:?} }}"));
    scene
        .set("robot.tool_start.xyz", "[0.45, -0.1, 0.35]")
        .expect("a nested key");
    scene.set("robot.tool_start.z", "0.38").expect("`z` stands for `xyz.2`");
    scene
        .set("robot.tool_start.pitch", "0.1")
        .expect("`pitch` stands for `rpy.1`");
    let start = scene.spec().robot.tool_start.expect("still set");
    assert_eq!(start.xyz, [0.45, -0.1, 0.38]);
    assert_eq!(start.rpy, [PI, 0.1, PI]);
    let plant = RapierPlant::from_scene(&scene).expect("reachable");
    assert_starts_at(&plant, &pose(start.xyz, start.rpy));

    // A scene given by q0 takes a whole tool start as an inline table; half of one is refused.
    let mut table = Scene::from_file(&root().join("examples/scenes/table.toml")).expect("the table scene");
    let err = table
        .clone()
        .set("robot.tool_start.xyz", "[0.5, 0.0, 0.4]")
        .expect_err("no rpy");
    assert!(err.to_string().contains("rpy"), "{err}");
    table
        .set(
            "robot.tool_start",
            "{ xyz = [0.5466, 0.0, 0.33], rpy = [3.141592653589793, 0, 3.141592653589793] }",
        )
        .expect("an inline table");
    let plant = RapierPlant::from_scene(&table).expect("2 cm above the table");
    assert_starts_at(&plant, &pose([0.5466, 0.0, 0.33], [PI, 0.0, PI]));
}

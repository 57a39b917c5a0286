//! The arm's links collide with the scene, and their contact is a reflex: a shelf under the
//! forearm stops the standard touch (written out as IR in `support/`) with the `arm_contact`
//! reflex naming the link, before the tool reaches the table; the shipped scenes start, and hold
//! still, without any link touching anything; a link that starts inside an object is refused.

mod support;

use skill_ir as ir;
use skill_runtime::exec::{bind, simulate, ExecOptions, Mode, RunReport};
use skill_runtime::plant::{Observation, Plant};
use skill_runtime::robot::RobotData;
use skill_runtime::safety::{Quantity, ARM_CONTACT_N};
use skill_runtime::sim::{RapierPlant, Scene, SimError};
use support::{learn, root, Touch};

/// The table scene with the tool starting where the touch demonstration starts (the flange at
/// z = 0.480 m, the probe tip 6 cm above the table), and a shelf 8 cm deep whose top is 2.5 cm
/// under the forearm there: the touch's approach lowers the forearm onto it before the tip
/// reaches the table.
const SHELF_SCENE: &str = r#"
[robot]
urdf = "examples/robots/lwr4.urdf"
tool = "probe_tip"
sensor = "lwr_flange"
tool_start = { xyz = [0.5466, 0.0, 0.3702], rpy = [3.141592653589793, 0.0, 3.141592653589793] }

[sensor]
noise_force_n = 0.0
noise_torque_nm = 0.0

[objects.table]
kind = "box"
xyz = [0.55, 0.0, 0.275]
size = [0.6, 0.8, 0.05]

[objects.shelf]
kind = "box"
xyz = [0.44, 0.0, 0.48]    # top at z = 0.49 m, x from 0.40 to 0.48 m
size = [0.08, 0.2, 0.02]
"#;

fn shelf_scene() -> Scene {
    Scene::from_toml(SHELF_SCENE, "shelf.toml", &root()).expect("the shelf scene reads")
}

fn touch_in(scene: &Scene, options: &ExecOptions) -> RunReport {
    let skill = support::touch(Touch::default());
    let learned = learn(&skill);
    let bound = bind(&skill, &learned).expect("binds");
    simulate(scene, Mode::Skill(&bound), options).expect("runs").0
}

#[test]
fn a_forearm_lowered_onto_a_shelf_is_an_arm_contact_reflex_that_names_the_link() {
    let scene = shelf_scene();
    let plant = RapierPlant::from_scene(&scene).expect("the arm starts clear of the shelf");
    let (clearance, link, object) = plant.arm_start_clearance().expect("objects");
    assert!(
        clearance > 0.01,
        "{link} starts {clearance} m from {object}: the test needs a clear start"
    );

    let report = touch_in(&scene, &ExecOptions::default());
    eprintln!("{}", report.message);
    assert_eq!(report.outcome, ir::Outcome::Failure, "{}", report.message);
    let violation = report.reflex.as_ref().expect("a reflex stopped the run");
    assert_eq!(violation.quantity, Quantity::ArmContact, "{}", report.message);
    assert_eq!(violation.limit, ARM_CONTACT_N);
    assert!(violation.measured > ARM_CONTACT_N);
    // The forearm (the link after A5) is what reaches the shelf first.
    assert_eq!(violation.detail, "link `lwr_5_link`", "{}", report.message);
    assert!(
        report.message.contains("in state `approach`")
            && report
                .message
                .contains("arm contact with the scene (link `lwr_5_link`)")
            && report.message.contains("--limit arm_contact="),
        "{}",
        report.message
    );
    // The probe never reached the table 6 cm below its start.
    assert!(
        report.safety.peak_force_n < 2.0,
        "the tool pushed {} N",
        report.safety.peak_force_n
    );
}

#[test]
fn without_the_shelf_the_same_touch_succeeds() {
    let mut scene = shelf_scene();
    scene.set("shelf.z", "-1").expect("the shelf moves out of the way");
    let report = touch_in(&scene, &ExecOptions::default());
    assert_eq!(report.outcome, ir::Outcome::Success, "{}", report.message);
    assert!(report.reflex.is_none());
}

/// Gravity compensation with joint damping for `ticks` ms; the largest arm contact force seen.
fn hold_still(plant: &mut RapierPlant, ticks: usize) -> (f64, Option<usize>) {
    let robot = plant.robot().clone();
    let mut data: RobotData = robot.data();
    let mut tau = vec![0.0; robot.dof()];
    let mut obs = Observation::zeros(robot.dof());
    let mut worst = (0.0, None);
    for _ in 0..ticks {
        plant.observe_into(&mut obs);
        robot.forward_kinematics(&mut data, obs.q.as_slice());
        robot.gravity_torques(&mut data, &mut tau);
        for (idx, torque) in tau.iter_mut().enumerate() {
            *torque -= 2.0 * obs.qd[idx];
        }
        plant.apply(&tau).expect("7 torques");
        plant.step(1e-3).expect("finite");
        plant.observe_into(&mut obs);
        if obs.arm_contact_n > worst.0 {
            worst = (obs.arm_contact_n, obs.arm_contact_link);
        }
    }
    worst
}

#[test]
fn the_shipped_scenes_start_and_hold_with_no_link_touching_anything() {
    let dir = root().join("examples/scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("the scenes folder")
        .map(|entry| entry.expect("an entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 4, "{files:?}");
    for file in &files {
        let scene = Scene::from_file(file).expect("a shipped scene reads");
        let mut plant = RapierPlant::from_scene(&scene).expect("a shipped scene builds");
        let (clearance, link, object) = plant.arm_start_clearance().expect("every scene has objects");
        eprintln!(
            "{}: `{link}` starts {:.1} mm from `{object}`",
            file.display(),
            clearance * 1e3
        );
        // The closest link is the flange's (`lwr_7_link`), 96 mm above the surface under the probe.
        assert!(
            clearance > 0.05,
            "{}: `{link}` starts {:.1} mm from `{object}`",
            file.display(),
            clearance * 1e3
        );
        let (force, link) = hold_still(&mut plant, 300);
        assert_eq!(force, 0.0, "{}: {force} N on link {link:?}", file.display());
    }
}

#[test]
fn a_link_that_starts_inside_an_object_is_refused_with_the_link_and_the_object() {
    // The shelf raised into the forearm.
    let mut scene = shelf_scene();
    scene.set("shelf.z", "0.53").expect("valid z");
    let err = RapierPlant::from_scene(&scene).expect_err("the forearm starts inside the shelf");
    assert!(matches!(err, SimError::ArmStartsInside { .. }), "{err}");
    let message = err.to_string();
    assert!(
        message.contains("scene `shelf.toml`")
            && message.contains("inside object `shelf`")
            && message.contains("arm link `lwr_"),
        "{message}"
    );
}

//! Acceptance of the standard skills in simulation (issue 5): each skill, learned from its
//! shipped demonstration, reproduced in the demonstrated and in changed scenes, against the
//! replay baseline. Fixed seeds; the runs are deterministic.

use std::path::PathBuf;

use skill_eval::metrics::{measure, ContactPlan, Metrics};
use skill_runtime::exec::{bind, simulate, ExecOptions, Mode, RunLog, RunReport};
use skill_runtime::skill::{LearnOptions, Learned};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn learned(skill: &str) -> (skill_ir::Skill, Learned) {
    let file = root().join(format!("stdlib-skills/{skill}.skill"));
    let demo = root().join(format!("examples/demos/{skill}.csv"));
    let Ok((_, ir)) = skill_kit::load::load_skill(&file, None) else {
        panic!("{skill} compiles")
    };
    let Ok(learned) = skill_kit::load::learn_from_files(&ir, &demo, &LearnOptions::default()) else {
        panic!("{skill} learns from its demonstration")
    };
    (ir, learned)
}

fn run(
    skill: &skill_ir::Skill,
    learned: &Learned,
    scene: &str,
    sets: &[&str],
    replay: bool,
) -> (RunReport, RunLog, Metrics) {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let Ok(scene) = skill_kit::load::load_scene(&root().join("examples/scenes").join(scene), &sets) else {
        panic!("scene loads")
    };
    let bound = bind(skill, learned).expect("binds");
    let mode = if replay {
        Mode::Replay(learned)
    } else {
        Mode::Skill(&bound)
    };
    let (report, log) = simulate(&scene, mode, &ExecOptions::default()).expect("runs");
    let plan = ContactPlan::of(&bound);
    let frame_z = |t: f64| {
        learned
            .frames
            .values()
            .next()
            .map_or(nalgebra::Vector3::z(), |f| f.at(t).rotation * nalgebra::Vector3::z())
    };
    let metrics = measure(&log, &plan, replay, &frame_z);
    (report, log, metrics)
}

/// The shipped scenes' start with the tool 5 cm higher (found by inverse kinematics): scenes whose
/// objects move towards the robot must not start with the tool inside them.
const Q0_HIGHER: &str = "robot.q0=[0.0, -0.454318493, 0.0, 1.431100155, 0.0, -1.256174005, 0.0]";

/// The eval's peak bound: twice the demonstration's largest force plus 5 N.
fn peak_bound(skill: &str) -> f64 {
    let demo = root().join(format!("examples/demos/{skill}.csv"));
    let loaded = skill_runtime::demo::read_csv(&demo, &Default::default()).expect("demo reads");
    2.0 * loaded.demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max) + 5.0
}

fn assert_sane(log: &RunLog) {
    let robot = skill_runtime::robot::Robot::from_urdf_str(skill_runtime::robot::LWR4_URDF, None).expect("urdf");
    for tick in &log.ticks {
        for (tau, joint) in tick.torques.iter().zip(robot.joints()) {
            assert!(
                tau.is_finite() && tau.abs() <= joint.effort + 1e-9,
                "torque {tau} at t = {}",
                tick.t_s
            );
        }
        assert!(
            tick.measured.iter().chain(&tick.wrench_base).all(|v| v.is_finite()),
            "non-finite state at t = {}",
            tick.t_s
        );
    }
}

#[test]
fn slide_holds_the_learned_force_on_lowered_tables_where_replay_loses_contact() {
    let (skill, learned) = learned("slide");
    for (set, lowered) in [
        ("table.z=0.275", false),
        ("table.z=0.225", true),
        ("table.z=0.195", true),
        ("table.z=0.175", true),
    ] {
        let (report, log, metrics) = run(&skill, &learned, "table.toml", &[set], false);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{set}: {}", report.message);
        let rms = metrics.force_rms_rel.expect("a contact phase");
        let share = metrics.contact_share.expect("a contact phase");
        eprintln!(
            "slide {set}: force RMS {:.1} %, contact {:.1} %, peak {:.1} N",
            rms * 100.0,
            share * 100.0,
            metrics.peak_force_n
        );
        assert!(rms <= 0.10, "{set}: force RMS {rms}");
        assert!(share >= 0.95, "{set}: contact share {share}");
        assert!(
            metrics.peak_force_n <= peak_bound("slide"),
            "{set}: peak {}",
            metrics.peak_force_n
        );
        assert_sane(&log);
        if lowered {
            let (_, _, replay) = run(&skill, &learned, "table.toml", &[set], true);
            let share = replay.contact_share.expect("a contact phase");
            assert!(share < 0.05, "{set}: replay stays in contact {share}");
        }
    }
}

#[test]
fn touch_ends_at_the_learned_contact_force_in_cases_one_to_three() {
    let (skill, learned) = learned("touch");
    let learned_force = learned.forces["touch_force"].value_n().expect("a constant force");
    let bound = peak_bound("touch");
    for (case, sets) in [
        ("III nearer", &["table.z=0.305", Q0_HIGHER][..]),
        ("I as demonstrated", &["table.z=0.275"][..]),
        ("II farther", &["table.z=0.245"][..]),
    ] {
        let (report, log, metrics) = run(&skill, &learned, "table.toml", sets, false);
        assert!(
            metrics.peak_force_n <= bound,
            "case {case}: peak {} N over {bound} N",
            metrics.peak_force_n
        );
        assert_eq!(
            report.outcome,
            skill_ir::Outcome::Success,
            "case {case}: {}",
            report.message
        );
        let stop = metrics.stop_force_n.expect("a contact phase");
        eprintln!(
            "touch case {case}: stop {stop:.2} N of {learned_force:.2} N, peak at impact {:.1} N",
            metrics.peak_force_n
        );
        assert!(
            ((stop - learned_force) / learned_force).abs() <= 0.20,
            "case {case}: stopped at {stop} N"
        );
        assert_sane(&log);
    }
}

#[test]
fn press_tracks_the_learned_profile_with_the_button_nearer_and_farther() {
    let (skill, learned) = learned("press");
    let bound = peak_bound("press");
    for (name, sets) in [
        ("nearer", &["button.z=0.31", "base.z=0.22", Q0_HIGHER][..]),
        ("farther", &["button.z=0.27", "base.z=0.18"][..]),
    ] {
        let (report, log, metrics) = run(&skill, &learned, "button.toml", sets, false);
        assert!(
            metrics.peak_force_n <= bound,
            "{name}: peak {} N over {bound} N",
            metrics.peak_force_n
        );
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{name}: {}", report.message);
        let rms = metrics.force_rms_rel.expect("a contact phase");
        eprintln!(
            "press {name}: force RMS {:.1} % of the peak, peak {:.1} N",
            rms * 100.0,
            metrics.peak_force_n
        );
        // 15 %, as the eval's press criterion: the force loop crosses the button's travel at the
        // force-axis speed limit (examples/eval/default.toml says why).
        assert!(rms <= 0.15, "{name}: force RMS {rms}");
        assert_sane(&log);
    }
}

#[test]
fn contour_tracks_the_learned_magnitude_on_a_moved_drum() {
    let (skill, learned) = learned("contour");
    for (name, set) in [("2 cm farther", "drum.z=0.13"), ("2 cm sideways", "drum.x=0.5666")] {
        let (report, log, metrics) = run(&skill, &learned, "cylinder.toml", &[set], false);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{name}: {}", report.message);
        let rms = metrics.force_rms_rel.expect("a contact phase");
        let share = metrics.contact_share.expect("a contact phase");
        eprintln!(
            "contour {name}: force RMS {:.1} %, contact {:.1} %",
            rms * 100.0,
            share * 100.0
        );
        assert!(rms <= 0.15, "{name}: force RMS {rms}");
        assert!(share >= 0.95, "{name}: contact share {share}");
        assert_sane(&log);
    }
}

/// The compliant frame of the contour's `follow` follows the drum's own normal (issue 26, item 2):
/// on the drum moved 2 cm sideways, the learned frames hold the demonstrated drum's normals,
/// 5-32° off the moved drum's under the same path; the followed frame lies within 5° of the
/// analytic normal (the direction from the tool point to the drum's axis) wherever the tool
/// slides (over 20 mm/s) and pushes (over 2 N), once the estimate has settled (0.3 s in).
#[test]
fn the_contours_frame_follows_the_moved_drums_normal() {
    let (skill, learned) = learned("contour");
    // The drum's axis runs along the base y through (x, z) = (0.5666, 0.15).
    let (axis_x, axis_z) = (0.5666, 0.15);
    let (report, log, _) = run(&skill, &learned, "cylinder.toml", &["drum.x=0.5666"], false);
    let Ok(scene) = skill_kit::load::load_scene(&root().join("examples/scenes/cylinder.toml"), &[]) else {
        panic!("scene loads")
    };
    let stiffness = scene.spec().sim.contact_stiffness;
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    let follow = log.states.iter().position(|s| s == "follow").expect("a follow state") as u32;
    let entered = log.ticks.iter().find(|t| t.state == follow).expect("follow runs").t_s;
    let mut worst = 0.0_f64;
    let mut checked = 0;
    for pair in log.ticks.windows(2) {
        let (before, tick) = (&pair[0], &pair[1]);
        let p = nalgebra::Vector3::new(tick.measured[0], tick.measured[1], tick.measured[2]);
        let q = nalgebra::Vector3::new(before.measured[0], before.measured[1], before.measured[2]);
        let speed = (p - q).norm() / (tick.t_s - before.t_s);
        let force = nalgebra::Vector3::from_column_slice(&tick.wrench_base[..3]);
        let z = nalgebra::Vector3::from_column_slice(&tick.frame_z());
        if tick.state != follow || tick.t_s < entered + 0.3 || speed < 0.02 || force.dot(&z) < 2.0 {
            continue;
        }
        let normal = nalgebra::Vector3::new(axis_x - p.x, 0.0, axis_z - p.z).normalize();
        // The tool touches the drum: its tip (a sphere of 10 mm radius) on the surface, within a
        // millimetre and what the contact compliance explains.
        let gap = ((p.x - axis_x).hypot(p.z - axis_z) - 0.15 - 0.01).abs();
        assert!(
            gap < 1e-3 + force.norm() / stiffness,
            "tip {gap} m off the drum at t = {}",
            tick.t_s
        );
        worst = worst.max(z.angle(&normal).to_degrees());
        checked += 1;
    }
    eprintln!("contour on the drum 2 cm sideways: frame within {worst:.2}° of the normal over {checked} ticks");
    assert!(checked > 1000, "only {checked} ticks slid in contact");
    assert!(worst < 5.0, "the frame lay {worst:.2}° off the drum's normal");
}

#[test]
fn two_runs_are_bit_identical() {
    let (skill, learned) = learned("slide");
    let (_, first, _) = run(&skill, &learned, "table.toml", &["table.z=0.225"], false);
    let (_, second, _) = run(&skill, &learned, "table.toml", &["table.z=0.225"], false);
    assert_eq!(first.ticks.len(), second.ticks.len());
    for (a, b) in first.ticks.iter().zip(&second.ticks) {
        let bits = |t: &skill_runtime::exec::Tick| -> Vec<u64> {
            t.measured
                .iter()
                .chain(&t.wrench_base)
                .chain(&t.torques)
                .map(|v| v.to_bits())
                .collect()
        };
        assert_eq!(bits(a), bits(b), "runs differ at t = {}", a.t_s);
    }
}

#[test]
fn the_example_task_runs_end_to_end() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args([
            "run",
            "examples/tasks/inspect_and_press.skill",
            "--scene",
            "examples/scenes/workcell.toml",
        ])
        .current_dir(root())
        .output()
        .expect("skillc runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for step in [
        "step `find` (touch)",
        "step `wipe` (slide)",
        "step `push` (press)",
        "task succeeded",
    ] {
        assert!(stdout.contains(step), "missing `{step}` in\n{stdout}");
    }
}

#[test]
fn a_crossed_limit_is_a_reflex_that_names_the_state_line_quantity_and_values() {
    let (skill, learned) = learned("press");
    let Ok(scene) = skill_kit::load::load_scene(&root().join("examples/scenes/button.toml"), &[]) else {
        panic!("scene loads")
    };
    let bound = bind(&skill, &learned).expect("binds");
    let options = ExecOptions {
        limits: vec![("force".to_string(), 4.0)],
        ..ExecOptions::default()
    };
    let (report, log) = simulate(&scene, Mode::Skill(&bound), &options).expect("runs");
    assert_eq!(report.outcome, skill_ir::Outcome::Failure);
    let violation = report.reflex.as_ref().expect("a reflex stopped the run");
    assert_eq!(violation.quantity, skill_runtime::safety::Quantity::ContactForce);
    assert!(violation.measured > 4.0 && violation.limit == 4.0);
    for needle in [
        "reflex stop in state `press`",
        "press.skill:",
        "contact force",
        "above the limit 4.0000 N",
        "--limit force=",
    ] {
        assert!(report.message.contains(needle), "`{}` lacks `{needle}`", report.message);
    }
    // The arm was stopped: the log ends with the reflex hold, the last ticks nearly at rest.
    let reflex = log.states.iter().position(|s| s == "reflex").expect("a reflex state") as u32;
    let tail: Vec<_> = log.ticks.iter().filter(|t| t.state == reflex).collect();
    assert!(tail.len() >= 290, "{} reflex ticks", tail.len());
    let last = tail[tail.len() - 1];
    let before = tail[tail.len() - 11];
    let moved = (0..3)
        .map(|i| (last.measured[i] - before.measured[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(moved < 0.002, "still moving {moved} m in 10 ms after the stop");
    assert!(report.safety.peak_force_n > 4.0);
}

#[test]
fn a_tool_starting_inside_an_object_is_refused_with_the_object_named() {
    let (skill, learned) = learned("touch");
    let Ok(scene) = skill_kit::load::load_scene(
        &root().join("examples/scenes/table.toml"),
        // The top 2.9 cm above the tip's lowest point (the scene starts the tip 6.1 cm above it).
        &["table.z=0.355".to_string()],
    ) else {
        panic!("scene loads")
    };
    let bound = bind(&skill, &learned).expect("binds");
    let err = simulate(&scene, Mode::Skill(&bound), &ExecOptions::default()).expect_err("starts inside the table");
    let message = err.to_string();
    assert!(message.contains("inside object `table`"), "{message}");
}

/// The turning points of the measured tool x in state `state` (a reversal counts once the tool
/// has come back 2 cm), as times \[s\].
fn reversals(log: &RunLog, state: &str) -> Vec<f64> {
    let index = log.states.iter().position(|s| s == state).expect("the state ran") as u32;
    let (t, x): (Vec<f64>, Vec<f64>) = log
        .ticks
        .iter()
        .filter(|tick| tick.state == index)
        .map(|tick| (tick.t_s, tick.measured[0]))
        .unzip();
    skill_runtime::learn::strokes::turning_points(&x, 0.02)
        .into_iter()
        .map(|k| t[k])
        .collect()
}

#[test]
fn wipe_learns_its_four_strokes_and_reproduces_them_or_as_many_as_asked() {
    let (mut skill, learned) = learned("wipe");
    let strokes = &learned.motions["strokes"];
    assert_eq!(strokes.strokes.len(), 4, "the demonstration wipes four strokes");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root().join("examples/demos/wipe.truth.json")).expect("truth"))
            .expect("truth parses");
    let turns: Vec<f64> = truth["turns_s"]
        .as_array()
        .expect("turns")
        .iter()
        .map(|v| v.as_f64().expect("a time"))
        .collect();
    let found = &learned.quality.motions["strokes"].strokes_s;
    for (stroke, turn) in found.windows(2).zip(&turns) {
        // A stroke ends where the next begins; a minimum-jerk stroke is flat at its ends, so
        // the turning sample may sit a little along the flat part.
        assert_eq!(stroke[0][1], stroke[1][0]);
        assert!(
            (stroke[0][1] - turn).abs() < 0.06,
            "turn at {} s, truth {turn} s",
            stroke[0][1]
        );
    }
    let bound = peak_bound("wipe");
    for (set, runs) in [
        ("table.z=0.275", None),
        ("table.z=0.225", None),
        ("table.z=0.245", Some(7)),
    ] {
        for state in &mut skill.states {
            if let skill_ir::StateKind::Active(active) = &mut state.kind {
                if state.name == "wipe" {
                    active.repeat = runs;
                }
            }
        }
        let (report, log, metrics) = run(&skill, &learned, "table.toml", &[set], false);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{set}: {}", report.message);
        let rms = metrics.force_rms_rel.expect("a contact phase");
        eprintln!(
            "wipe {set}, runs {runs:?}: force RMS {:.1} %, peak {:.1} N, reversals {:?}",
            rms * 100.0,
            metrics.peak_force_n,
            reversals(&log, "wipe")
        );
        assert!(rms <= 0.10, "{set}: force RMS {rms}");
        assert!(metrics.peak_force_n <= bound, "{set}: peak {}", metrics.peak_force_n);
        let expected = runs.map_or(4, |n| n as usize) - 1;
        assert_eq!(reversals(&log, "wipe").len(), expected, "{set}: runs {runs:?}");
        assert_sane(&log);
    }
}

/// The contour's arc as one position-controlled motion run twice in free air, its compliant
/// frame the contour's per-sample frame.
const CONTOUR_TWICE: &str = r#"skill contour_twice {
    learn {
        segments = cluster(linkage: ward, connectivity: 10, cut: count(3), min_length: 200 ms, features: [force_magnitude])
        frame normal = force_aligned(segment 2)
        motion follow = dmp(segment 2, basis: 80)
    }

    state follow {
        move follow from current
        repeat 2
        control position all in normal
        on motion_done -> done
        on timeout 60 s -> lost
    }

    terminal done: success
    terminal lost: failure "the motion did not finish"
}
"#;

#[test]
fn a_repeated_motion_replays_its_per_sample_frames_with_each_run() {
    let dir = std::env::temp_dir().join(format!("skillc-contour-twice-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("folder");
    let file = dir.join("contour_twice.skill");
    std::fs::write(&file, CONTOUR_TWICE).expect("written");
    let Ok((_, skill)) = skill_kit::load::load_skill(&file, None) else {
        panic!("compiles")
    };
    let demo = root().join("examples/demos/contour.csv");
    let learned = skill_kit::load::learn_from_files(&skill, &demo, &LearnOptions::default()).expect("learns");
    // The table far below: the arc runs in the air.
    let (report, log, _) = run(&skill, &learned, "table.toml", &["table.z=-0.5"], false);
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    let frame = &learned.frames["normal"];
    let duration = learned.segments[1].end_s - learned.segments[1].start_s;
    let z_at = |t: f64| frame.at(t).rotation * nalgebra::Vector3::z();
    assert!(
        z_at(0.05).angle(&z_at(duration)).to_degrees() > 10.0,
        "the frame turns along the arc"
    );
    let follow = log
        .states
        .iter()
        .position(|name| name == "follow")
        .expect("a follow state") as u32;
    let ticks: Vec<_> = log.ticks.iter().filter(|tick| tick.state == follow).collect();
    let entered = ticks.first().expect("the state ran").t_s;
    let logged_z = |t: f64| {
        let tick = ticks
            .iter()
            .min_by(|a, b| (a.t_s - t).abs().total_cmp(&(b.t_s - t).abs()))
            .expect("ticks");
        nalgebra::Vector3::from(tick.frame_z())
    };
    for since in [0.05, duration / 3.0, 0.6 * duration] {
        let expected = z_at(since);
        for (run, start) in [(1, entered), (2, entered + duration)] {
            let error = logged_z(start + since).angle(&expected).to_degrees();
            assert!(error < 1.0, "run {run}, {since:.2} s in: the frame is {error:.2}° off");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! Acceptance of the standard skills in simulation (issue 5): each skill, learned from its
//! shipped demonstration, reproduced in the demonstrated and in changed scenes, against the
//! replay baseline. Fixed seeds; the runs are deterministic.

use std::path::PathBuf;

use skill_runtime::exec::{bind, simulate, ExecOptions, Mode, RunLog, RunReport};
use skill_runtime::skill::{LearnOptions, Learned};
use skillc::eval::metrics::{measure, ContactPlan, Metrics};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn learned(skill: &str) -> (skill_ir::Skill, Learned) {
    let file = root().join(format!("stdlib-skills/{skill}.skill"));
    let demo = root().join(format!("examples/demos/{skill}.csv"));
    let Ok((_, ir)) = skillc::load::load_skill(&file, None) else {
        panic!("{skill} compiles")
    };
    let Ok(learned) = skillc::load::learn_from_files(&ir, &demo, &LearnOptions::default()) else {
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
    let Ok(scene) = skillc::load::load_scene(&root().join("examples/scenes").join(scene), &sets) else {
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
    for (case, set) in [
        ("III nearer", "table.z=0.305"),
        ("I as demonstrated", "table.z=0.275"),
        ("II farther", "table.z=0.245"),
    ] {
        let (report, log, metrics) = run(&skill, &learned, "table.toml", &[set], false);
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
    for (name, sets) in [
        ("nearer", ["button.z=0.31", "base.z=0.22"]),
        ("farther", ["button.z=0.27", "base.z=0.18"]),
    ] {
        let (report, log, metrics) = run(&skill, &learned, "button.toml", &sets, false);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{name}: {}", report.message);
        let rms = metrics.force_rms_rel.expect("a contact phase");
        eprintln!(
            "press {name}: force RMS {:.1} % of the peak, peak {:.1} N",
            rms * 100.0,
            metrics.peak_force_n
        );
        assert!(rms <= 0.10, "{name}: force RMS {rms}");
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

//! `skillc eval --robot NAME` from a folder outside the repository: the touch trials run on the
//! KUKA LBR iiwa 14 from the built-in defaults (its URDF written to the cache with the rest),
//! each trial's overrides name the iiwa; an unknown robot is a usage error naming the shipped ones;
//! `skillc robot iiwa14` inspects the shipped robot by name.

use std::path::PathBuf;
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-eval-robot-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn eval_runs_the_touch_trials_on_the_iiwa_from_any_folder() {
    let dir = temp_dir("iiwa");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args([
            "eval",
            "--robot",
            "iiwa14",
            "--skill",
            "touch",
            "--no-replay",
            "--out",
            "report",
        ])
        .current_dir(&dir)
        .env("XDG_CACHE_HOME", dir.join("cache"))
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("robot: iiwa14 (KUKA LBR iiwa 14 R820"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report/summary.json")).expect("summary"))
            .expect("json");
    let trials = summary["trials"].as_array().expect("trials");
    assert_eq!(trials.len(), 5);
    for trial in trials {
        assert_eq!(trial["success"], true, "{trial}");
        let sets: Vec<&str> = trial["set"]
            .as_array()
            .expect("set")
            .iter()
            .filter_map(|v| v.as_str())
            .collect();
        assert!(
            sets.iter()
                .any(|s| s.starts_with("robot.urdf=") && s.ends_with("iiwa14.urdf\"")),
            "{sets:?}"
        );
        assert!(sets.contains(&"robot.sensor=iiwa_flange"), "{sets:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_robot_is_a_usage_error_naming_the_shipped_ones() {
    let dir = temp_dir("unknown");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(["eval", "--robot", "ur5", "--skill", "touch", "--out", "report"])
        .current_dir(&dir)
        .env("XDG_CACHE_HOME", dir.join("cache"))
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("unknown robot `ur5` for --robot (shipped: lwr4, iiwa14, fr3)"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `skillc robot NAME` inspects a shipped robot from any folder, with its probe tip as the tool.
#[test]
fn robot_inspects_a_shipped_robot_by_name() {
    let dir = temp_dir("inspect");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(["robot", "iiwa14", "--json"])
        .current_dir(&dir)
        .output()
        .expect("skillc runs");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let inspection: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(inspection["robot"], "kuka_iiwa14");
    assert_eq!(inspection["tool_link"], "probe_tip");
    // Stretched straight up: the tip 1.416 m above the base (0.36 + 0.42 + 0.40 + 0.126 + 0.11).
    let z = inspection["tool_position"][2].as_f64().expect("z");
    assert!((z - 1.416).abs() < 1e-9, "{z}");
    let _ = std::fs::remove_dir_all(&dir);
}

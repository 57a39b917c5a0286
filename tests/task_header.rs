//! A failed task's header counts the task's steps, not the reports that ran (issue 25, item 3):
//! `inspect_and_press` stopped by a reflex in its first step says `1 of 3 step(s) ran`.

use std::process::Command;

#[test]
fn a_failed_task_counts_its_steps() {
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .current_dir(root)
        .args([
            "run",
            "examples/tasks/inspect_and_press.skill",
            "--scene",
            "examples/scenes/workcell.toml",
            "--limit",
            "force=3",
        ])
        .output()
        .expect("skillc runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("TASK FAILED"), "{text}");
    assert!(text.contains("task `inspect_and_press`: 1 of 3 step(s) ran"), "{text}");
}

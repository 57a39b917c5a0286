//! `skillc eval` on `[[task]]` entries: the example task find_wipe_hold judged step by step in two
//! scenes; a trial that fails names the step and why (a criterion, a terminal, the steps not
//! run, an `at:` anchor the earlier step never entered); a `[[task]]` entry that names a skill
//! file, a missing file, a step whose demonstration is missing or criteria for a step the task
//! lacks is an error row naming the file and field.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> &'static str {
    env!("CARGO_MANIFEST_DIR")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-eval-tasks-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Runs `skillc eval --trials TRIALS --out DIR/report` with `trials` written to DIR/trials.toml.
fn eval(dir: &Path, trials: &str) -> (Output, serde_json::Value) {
    let file = dir.join("trials.toml");
    std::fs::write(&file, trials).expect("write trials");
    let out_dir = dir.join("report");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args([
            "eval",
            "--trials",
            file.to_str().expect("utf-8"),
            "--out",
            out_dir.to_str().expect("utf-8"),
        ])
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs");
    let summary = std::fs::read(out_dir.join("summary.json"))
        .ok()
        .and_then(|bytes| serde_json::from_slice(&bytes).ok())
        .unwrap_or(serde_json::Value::Null);
    (out, summary)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The example task's `[[task]]` entry with `extra` lines and `variants`.
fn example(extra: &str, variants: &str) -> String {
    let root = root();
    format!(
        r#"
[[task]]
file = "{root}/examples/tasks/find_wipe_hold.skill"
scene = "{root}/examples/scenes/table.toml"
{extra}
variants = [{variants}]
"#
    )
}

#[test]
fn a_task_passes_in_two_scenes_with_every_step_judged() {
    let dir = temp_dir("pass");
    // The guarded move is judged by the `[[skill]]` entry's criteria (its stop force); the wipe
    // and the press-and-hold, which have none here, by their kind (force RMS, contact share).
    let root = root();
    let trials = format!(
        r#"
[[skill]]
file = "{root}/stdlib-skills/guarded_move.skill"
demo = "{root}/examples/demos/guarded_move.csv"
scene = "{root}/examples/scenes/table.toml"
criteria = {{ stop_force_rel = 0.20, contact_share = 0.95 }}
variants = [{{ name = "as demonstrated", set = [] }}]
{}"#,
        example(
            "",
            r#"{ name = "as demonstrated", set = [] }, { name = "table 5 cm lower", set = ["table.z=0.225"] }"#
        )
    );
    let (out, summary) = eval(&dir, &trials);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}\n{}", text(&out.stderr));
    assert!(
        stdout.contains("1/1 skill trials pass, 2/2 task trials pass (tasks have no replay baseline)"),
        "{stdout}"
    );
    for step in [
        "step find (guarded_move)",
        "step clean (wipe)",
        "step hold (press_hold)",
    ] {
        assert_eq!(stdout.matches(step).count(), 2, "`{step}` once per variant:\n{stdout}");
    }
    assert!(stdout.contains("peak bound"), "{stdout}");
    let trials = summary["trials"].as_array().expect("trials");
    let tasks: Vec<&serde_json::Value> = trials.iter().filter(|t| t["mode"] == "task").collect();
    assert_eq!(tasks.len(), 2, "no replay rows for tasks: {trials:?}");
    for task in &tasks {
        assert_eq!(task["skill"], "find_wipe_hold");
        assert_eq!(task["success"], true, "{task}");
        let steps = task["steps"].as_array().expect("steps");
        assert_eq!(steps.len(), 3);
        let from: Vec<&str> = steps
            .iter()
            .map(|s| s["criteria_from"].as_str().expect("from"))
            .collect();
        assert_eq!(from, ["skill", "kind", "kind"]);
        for step in steps {
            let peak = step["peak_force_n"].as_f64().expect("peak");
            let bound = step["peak_bound_n"].as_f64().expect("bound");
            assert!(peak > 1.0 && peak < bound, "{step}");
        }
        assert!(steps[0]["criteria"]["stop_force_rel"].as_f64().is_some());
        assert!(steps[1]["criteria"]["force_rms_rel"].as_f64().is_some());
    }
    assert_eq!(summary["tasks"][0]["name"], "find_wipe_hold");
    assert!(dir.join("report/plots/find_wipe_hold.clean_force.svg").is_file());
    let html = std::fs::read_to_string(dir.join("report/index.html")).expect("html");
    assert!(html.contains("task find_wipe_hold") && html.contains("no replay baseline"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failing_task_trial_names_the_step_and_the_reason() {
    let dir = temp_dir("fail");
    // A force RMS no wipe meets, and a table 25 cm down that the guarded move never finds.
    let trials = example(
        "criteria = { clean = { force_rms_rel = 0.001, contact_share = 0.95 } }",
        r#"{ name = "as demonstrated", set = [] }, { name = "table out of reach", set = ["table.z=0.025"] }"#,
    );
    let (out, summary) = eval(&dir, &trials);
    let stdout = text(&out.stdout);
    let stderr = text(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(1),
        "a failing task trial fails the eval: {stdout}"
    );
    assert!(
        stdout.contains("0/0 skill trials pass, 0/2 task trials pass"),
        "{stdout}"
    );
    assert!(stderr.contains("2 of 2 task trials failed"), "{stderr}");
    assert!(
        stderr.contains("find_wipe_hold / as demonstrated: step clean: criterion:force_rms"),
        "{stderr}"
    );
    assert!(
        stderr.contains("find_wipe_hold / table out of reach: step find: terminal:missed"),
        "{stderr}"
    );
    // The criterion's message says what was measured against what.
    assert!(stderr.contains("of the learned force, above 0.1 %"), "{stderr}");
    let trials = summary["trials"].as_array().expect("trials");
    let missed = trials
        .iter()
        .find(|t| t["variant"] == "table out of reach")
        .expect("row");
    let reasons: Vec<&str> = missed["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .map(|s| s["reason"].as_str().unwrap_or("-"))
        .collect();
    assert_eq!(reasons, ["terminal:missed", "not_run", "not_run"]);
    // The step that passed shows no reason; the failing one its criterion.
    let demonstrated = trials.iter().find(|t| t["variant"] == "as demonstrated").expect("row");
    assert!(demonstrated["steps"][0]["reason"].is_null(), "{demonstrated}");
    assert_eq!(demonstrated["steps"][1]["reason"], "criterion:force_rms");
    assert_eq!(demonstrated["steps"][1]["criteria_from"], "task");
    // A step whose anchor (`at: find.detour`) the earlier step never entered: the touch reaches
    // its force and never takes the detour it would take on a timeout.
    let touch = std::fs::read_to_string(Path::new(root()).join("stdlib-skills/touch.skill")).expect("touch");
    let detour = touch
        .replace("skill touch {", "skill touch_detour {")
        .replace("on timeout 2 s -> retract", "on timeout 2 s -> detour")
        .replace(
            "    terminal done: success",
            "    state detour {\n        move retreat relative\n        control position all in contact\n        \
             stiffness x y z: 2000 N/m, rx ry rz: 150 Nm/rad\n        on motion_done -> done\n    }\n\n    terminal done: success",
        );
    assert!(detour.contains("-> detour") && detour.contains("state detour"));
    std::fs::write(dir.join("touch_detour.skill"), detour).expect("write skill");
    let demo = format!("{}/examples/demos/touch.csv", root());
    std::fs::write(
        dir.join("anchored.skill"),
        format!(
            "import \"touch_detour.skill\"\n\ntask anchored {{\n    step find = touch_detour(demo: \"{demo}\")\n    \
             step again = touch_detour(demo: \"{demo}\", at: find.detour)\n}}\n"
        ),
    )
    .expect("write task");
    let trials = format!(
        "[[task]]\nfile = \"anchored.skill\"\nscene = \"{}/examples/scenes/table.toml\"\nvariants = [{{ name = \"as demonstrated\", set = [] }}]\n",
        root()
    );
    let (out, summary) = eval(&dir, &trials);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("anchored / as demonstrated: step again: anchor"),
        "{stderr}"
    );
    assert!(stderr.contains("step `find` never entered state `detour`"), "{stderr}");
    let steps = summary["trials"][0]["steps"].as_array().expect("steps");
    assert_eq!(steps[0]["success"], true, "{}", steps[0]);
    assert_eq!(steps[1]["reason"], "anchor");
    // Criteria from the skill's kind: the touch stops once its force is reached.
    assert_eq!(steps[0]["criteria_from"], "kind");
    assert!(
        steps[0]["criteria"]["stop_force_rel"].as_f64().is_some(),
        "{}",
        steps[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_task_entries_are_error_rows_naming_the_file_and_field() {
    let dir = temp_dir("bad");
    let root = root();
    // A task whose step learns from a demonstration that does not exist.
    let task = dir.join("missing_demo.skill");
    std::fs::write(
        &task,
        format!(
            "import \"{root}/stdlib-skills/touch.skill\"\n\ntask poke {{\n    step find = touch(demo: \"nosuch.csv\")\n}}\n"
        ),
    )
    .expect("write task");
    let entry = |file: &str, extra: &str| {
        format!(
            "[[task]]\nfile = \"{file}\"\nscene = \"{root}/examples/scenes/table.toml\"\n{extra}\nvariants = [{{ name = \"as demonstrated\", set = [] }}]\n"
        )
    };
    let trials = [
        entry(&format!("{root}/stdlib-skills/touch.skill"), ""),
        entry(&format!("{root}/examples/tasks/nosuch.skill"), ""),
        entry(task.to_str().expect("utf-8"), ""),
        entry(
            &format!("{root}/examples/tasks/find_wipe_hold.skill"),
            "criteria = { wipe = { force_rms_rel = 0.1 } }",
        ),
    ]
    .join("\n");
    let (out, summary) = eval(&dir, &trials);
    let stdout = text(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}\n{}", text(&out.stderr));
    assert!(stdout.contains("0/4 task trials pass"), "{stdout}");
    let rows = summary["trials"].as_array().expect("trials");
    assert_eq!(rows.len(), 4);
    let message = |index: usize| {
        assert_eq!(rows[index]["error"], true, "{}", rows[index]);
        rows[index]["message"].as_str().expect("message").to_string()
    };
    let skill = message(0);
    assert!(
        skill.contains("`[[task]]` file") && skill.contains("touch.skill") && skill.contains("defines no task"),
        "{skill}"
    );
    let missing = message(1);
    assert!(
        missing.contains("nosuch.skill") && missing.contains("cannot read"),
        "{missing}"
    );
    let demo = message(2);
    assert!(
        demo.contains("missing_demo.skill") && demo.contains("step `find`") && demo.contains("nosuch.csv"),
        "{demo}"
    );
    let criteria = message(3);
    assert!(
        criteria.contains("`criteria` names step `wipe`") && criteria.contains("find, clean, hold"),
        "{criteria}"
    );
    // An unknown key is a trials-file error, as in a `[[skill]]` entry.
    let (out, _) = eval(&dir, &example("speed = 2", r#"{ name = "x", set = [] }"#));
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("speed"), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

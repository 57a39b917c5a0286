//! Skill parameters in simulation (issue 12): a hold time declared `param hold = 1 s` holds the
//! default, the value `--param` sets (with the file learned for the default), and each task
//! step's own; bad settings are refused naming the setting.

use std::path::PathBuf;
use std::process::Command;

use skill_runtime::exec::{bind, simulate, simulate_task, ExecOptions, Mode, RunReport, TaskStep};
use skill_runtime::skill::{ir_hash, LearnOptions, Learned};

const FILE: &str = "tests/data/touch_hold.skill";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn skill(params: &[&str]) -> skill_ir::Skill {
    let params: Vec<String> = params.iter().map(|p| p.to_string()).collect();
    match skill_kit::load::load_skill_with(&root().join(FILE), None, &params) {
        Ok((_, skill)) => skill,
        Err(_) => panic!("{FILE} compiles with {params:?}"),
    }
}

fn learn(skill: &skill_ir::Skill) -> Learned {
    let demo = root().join("examples/demos/touch.csv");
    let Ok(learned) = skill_kit::load::learn_from_files(skill, &demo, &LearnOptions::default()) else {
        panic!("learns from {}", demo.display())
    };
    learned
}

fn scene() -> skill_runtime::sim::Scene {
    let Ok(scene) = skill_kit::load::load_scene(&root().join("examples/scenes/table.toml"), &[]) else {
        panic!("scene loads")
    };
    scene
}

/// How long the run stayed in `hold_force`.
fn held_s(report: &RunReport) -> f64 {
    let visit = report
        .visits
        .iter()
        .find(|visit| visit.state == "hold_force")
        .unwrap_or_else(|| panic!("hold_force is visited: {}", report.message));
    visit.exit_s - visit.enter_s
}

#[test]
fn the_hold_lasts_the_default_then_what_the_command_line_sets_with_the_same_learned_file() {
    let plain = skill(&[]);
    assert_eq!(plain.params.len(), 2);
    assert_eq!(plain.params[0].name, "hold");
    assert_eq!(plain.params[0].value_si, 1.0);
    let learned = learn(&plain);
    let run = |skill: &skill_ir::Skill| {
        let bound = bind(skill, &learned).expect("the learned file binds");
        simulate(&scene(), Mode::Skill(&bound), &ExecOptions::default())
            .expect("runs")
            .0
    };
    let report = run(&plain);
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    let default_hold = held_s(&report);
    eprintln!("default: held {default_hold:.3} s");
    assert!((default_hold - 1.0).abs() < 0.005, "held {default_hold} s");

    // `--param hold=2.5s`: only the state machine changes, so the default's learned file binds.
    let longer = skill(&["hold=2.5s"]);
    assert_eq!(ir_hash(&longer), ir_hash(&plain));
    assert_eq!(longer.params[0].value_si, 2.5);
    assert_eq!(longer.params[0].set_by, skill_ir::ParamSource::CommandLine);
    let report = run(&longer);
    assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
    let held = held_s(&report);
    eprintln!("--param hold=2.5s: held {held:.3} s");
    assert!((held - 2.5).abs() < 0.005, "held {held} s");
}

#[test]
fn each_task_step_runs_the_skill_with_its_own_values() {
    let compilation = skill_kit::frontend::compile_path(&root().join(FILE)).expect("reads");
    let program = compilation.program.expect("compiles");
    let task = &program.tasks[0];
    assert!(task.steps[0].specialised.is_none(), "the first step sets nothing");
    let long = task.steps[1].skill_in(&program).expect("the step's skill");
    assert_eq!(long.params[0].value_si, 3.0);
    assert_eq!(long.params[0].set_by, skill_ir::ParamSource::Step("long".into()));

    let skills: Vec<&skill_ir::Skill> = task
        .steps
        .iter()
        .map(|s| s.skill_in(&program).expect("skill"))
        .collect();
    let learned: Vec<Learned> = skills.iter().map(|s| learn(s)).collect();
    let steps: Vec<TaskStep<'_, '_>> = task
        .steps
        .iter()
        .zip(&skills)
        .zip(&learned)
        .map(|((step, skill), learned)| TaskStep {
            step,
            bound: bind(skill, learned).expect("binds"),
        })
        .collect();
    let run = simulate_task(&scene(), &steps, &[], &ExecOptions::default()).expect("runs");
    assert_eq!(run.outcome, skill_ir::Outcome::Success);
    let holds: Vec<f64> = run.steps.iter().map(|step| held_s(&step.report)).collect();
    eprintln!("task: held {holds:?} s");
    assert!((holds[0] - 1.0).abs() < 0.005, "{holds:?}");
    assert!((holds[1] - 3.0).abs() < 0.005, "{holds:?}");
}

#[test]
fn bad_settings_are_refused_naming_the_setting() {
    let skillc = env!("CARGO_BIN_EXE_skillc");
    let check = |param: &str| {
        let output = Command::new(skillc)
            .current_dir(root())
            .args([
                "run",
                FILE,
                "--skill",
                "touch_hold",
                "--scene",
                "examples/scenes/table.toml",
            ])
            .args(["--demo", "examples/demos/touch.csv", "--param", param])
            .output()
            .expect("skillc runs");
        let text = String::from_utf8_lossy(&output.stderr).into_owned() + &String::from_utf8_lossy(&output.stdout);
        (output.status.code(), text)
    };
    let (code, text) = check("hols=3s");
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("no skill in") && text.contains("`hols`"), "{text}");
    assert!(text.contains("did you mean `hold`?"), "{text}");
    let (code, text) = check("pause=3s");
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("parameters declared: `hold`, `meet_speed`"), "{text}");
    let (code, text) = check("hold=3N");
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("parameter `hold` of `touch_hold` is a duration, this value is a force"),
        "{text}"
    );
    // Where it is names the setting: one of several `--param`s.
    assert!(text.contains("--param hold:1:"), "{text}");
    let (code, text) = check("hold");
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("cannot read `--param hold`"), "{text}");
    let (code, text) = check("hold=1e400s");
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("not finite"), "{text}");
}

#[test]
fn a_count_set_in_exponent_form_is_a_whole_number() {
    let file = root().join("compiler/tests/corpus/ok/params.skill");
    let compiled = |value: &str| skill_kit::load::load_program_with(&file, &[format!("presses={value}")]);
    for (value, repeat) in [("1e3", 1000), ("3.0", 3), ("2", 2)] {
        let Ok(program) = compiled(value) else {
            panic!("presses={value} compiles")
        };
        fn repeats(value: &serde_json::Value, out: &mut Vec<u64>) {
            match value {
                serde_json::Value::Object(map) => {
                    out.extend(map.get("repeat").and_then(serde_json::Value::as_u64));
                    map.values().for_each(|v| repeats(v, out));
                }
                serde_json::Value::Array(items) => items.iter().for_each(|v| repeats(v, out)),
                _ => {}
            }
        }
        let mut found = Vec::new();
        repeats(&serde_json::to_value(&program).expect("json"), &mut found);
        assert!(found.contains(&repeat), "presses={value}: repeats {found:?}");
    }
    for value in ["2.5", "-1", "1e4"] {
        let Err(skill_kit::load::Failure::Input(message)) = compiled(value) else {
            panic!("presses={value} is refused")
        };
        assert!(
            message.contains("whole number") || message.contains("between 1 and"),
            "presses={value}: {message}"
        );
    }
}

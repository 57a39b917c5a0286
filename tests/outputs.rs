//! Outputs that never replace an input the command found itself (imports, task steps'
//! demonstrations, the scene's robot), interrupts that leave no temporaries and the previous
//! report whole, and the numbers a user gives that would size work or switch a check off.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A copy of the repository's skills and examples, so that nothing here can touch the real ones.
fn workspace(name: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("skillc-outputs-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for folder in [
        "stdlib-skills",
        "examples/demos",
        "examples/scenes",
        "examples/robots",
        "examples/tasks",
        "examples/eval",
    ] {
        copy_dir(&root.join(folder), &dir.join(folder));
    }
    dir
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("dir");
    for entry in std::fs::read_dir(from).expect("list") {
        let path = entry.expect("entry").path();
        let target = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_dir(&path, &target);
        } else {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}

fn skillc(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Hidden temporaries (`.NAME.tmp-…`, `.NAME.old-…`) anywhere below `dir`.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(folder) = stack.pop() {
        for entry in std::fs::read_dir(&folder).expect("list").filter_map(Result::ok) {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') && (name.contains(".tmp-") || name.contains(".old-")) {
                found.push(path.clone());
            }
            if path.is_dir() {
                stack.push(path);
            }
        }
    }
    found
}

#[test]
fn an_output_is_never_an_input_the_command_found_itself() {
    let dir = workspace("found");
    let read = |path: &str| std::fs::read(dir.join(path)).expect("input");
    let cases: [(&[&str], &str); 5] = [
        // A task step's demonstration, refused before anything is learned.
        (
            &[
                "run",
                "examples/tasks/inspect_and_press.skill",
                "--scene",
                "examples/scenes/workcell.toml",
                "-o",
                "examples/demos/touch.csv",
            ],
            "examples/demos/touch.csv",
        ),
        // An imported skill.
        (
            &[
                "compile",
                "examples/tasks/inspect_and_press.skill",
                "-o",
                "stdlib-skills/touch.skill",
            ],
            "stdlib-skills/touch.skill",
        ),
        // The scene's robot.
        (
            &[
                "run",
                "stdlib-skills/touch.skill",
                "--demo",
                "examples/demos/touch.csv",
                "--scene",
                "examples/scenes/table.toml",
                "-o",
                "examples/robots/lwr4.urdf",
            ],
            "examples/robots/lwr4.urdf",
        ),
        // The scene itself, by another spelling.
        (
            &[
                "run",
                "stdlib-skills/touch.skill",
                "--demo",
                "examples/demos/touch.csv",
                "--scene",
                "examples/scenes/table.toml",
                "-o",
                "examples/scenes/../scenes/table.toml",
            ],
            "examples/scenes/table.toml",
        ),
        // The trials file of an eval, as its report folder's neighbour: `--out` a file.
        (
            &[
                "learn",
                "examples/tasks/inspect_and_press.skill",
                "examples/demos/touch.csv",
                "--skill",
                "touch",
                "-o",
                "stdlib-skills/press.skill",
            ],
            "stdlib-skills/press.skill",
        ),
    ];
    for (args, input) in cases {
        let before = read(input);
        let started = Instant::now();
        let out = skillc(&dir, args);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {message}");
        assert!(
            message.contains("is also an input")
                && message.contains(Path::new(input).file_name().unwrap().to_str().unwrap()),
            "{args:?}: {message}"
        );
        assert_eq!(read(input), before, "{input} unchanged");
        // Refused up front, not after a run: well under what the run itself takes.
        assert!(started.elapsed() < Duration::from_secs(120), "{args:?}");
    }
    #[cfg(unix)]
    {
        // Through a symlink to the demonstration a task step reads.
        std::os::unix::fs::symlink("examples/demos/slide.csv", dir.join("alias.csv")).expect("link");
        let before = read("examples/demos/slide.csv");
        let out = skillc(
            &dir,
            &[
                "run",
                "examples/tasks/inspect_and_press.skill",
                "--scene",
                "examples/scenes/workcell.toml",
                "-o",
                "alias.csv",
            ],
        );
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(stderr(&out).contains("slide.csv"), "{}", stderr(&out));
        assert_eq!(read("examples/demos/slide.csv"), before);
    }
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[cfg(unix)]
#[test]
fn an_interrupted_eval_leaves_the_previous_report_or_none_and_no_temporary() {
    let dir = workspace("interrupt");
    let eval = ["eval", "--skill", "touch", "--no-replay", "--out", "report"];
    let first = skillc(&dir, &eval);
    assert_eq!(first.status.code(), Some(0), "{}", stderr(&first));
    let report = dir.join("report");
    let summary = std::fs::read_to_string(report.join("summary.json")).expect("first report");
    // Interrupts at staggered moments: while learning, running, writing plots, or after.
    let mut interrupted = 0;
    for (step, signal, code) in [
        (0, "-INT", 130),
        (1, "-TERM", 143),
        (2, "-INT", 130),
        (3, "-TERM", 143),
        (5, "-INT", 130),
        (8, "-TERM", 143),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_skillc"))
            .args(eval)
            .current_dir(&dir)
            .env("NO_COLOR", "1")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("skillc starts");
        std::thread::sleep(Duration::from_millis(150 * step + 50));
        let _ = Command::new("kill").args([signal, &child.id().to_string()]).status();
        let status = child.wait().expect("ends");
        match status.code() {
            Some(0) => {}
            Some(found) => {
                assert_eq!(found, code, "{signal} gives 128 + its number");
                interrupted += 1;
            }
            None => panic!("killed by {signal} without its handler: {status:?}"),
        }
        assert!(temporaries(&dir).is_empty(), "after {signal}: {:?}", temporaries(&dir));
        // The report is whole: the previous one or a new one, never a mix.
        let now = std::fs::read_to_string(report.join("summary.json")).expect("a report is there");
        let value: serde_json::Value = serde_json::from_str(&now).expect("whole JSON");
        assert!(value["trials"].as_array().is_some_and(|t| !t.is_empty()));
        assert!(report.join("index.html").is_file(), "index.html beside summary.json");
        assert!(
            report.join("plots").read_dir().expect("plots").next().is_some(),
            "plots not empty"
        );
        let _ = &summary;
    }
    assert!(interrupted > 0, "at least one interrupt landed before the eval ended");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn numbers_that_would_size_work_or_switch_a_check_off_are_bounded() {
    let dir = workspace("numbers");
    // --threads 100000 runs, lowered and said.
    let out = skillc(
        &dir,
        &[
            "eval",
            "--skill",
            "touch",
            "--no-replay",
            "--threads",
            "100000",
            "--out",
            "r",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).contains("--threads 100000: running"), "{}", stderr(&out));
    // An overflowing limit is not a switch.
    let out = skillc(
        &dir,
        &[
            "run",
            "stdlib-skills/touch.skill",
            "--demo",
            "examples/demos/touch.csv",
            "--scene",
            "examples/scenes/table.toml",
            "--limit",
            "force=1e400",
        ],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("too large for a number"), "{}", stderr(&out));
    // A trials file's negative or NaN criterion.
    for bad in ["-0.2", "nan"] {
        let trials = std::fs::read_to_string(dir.join("examples/eval/default.toml")).expect("trials");
        let edited = trials.replacen(
            "criteria = { stop_force_rel = 0.20 }",
            &format!("criteria = {{ stop_force_rel = {bad} }}"),
            1,
        );
        assert_ne!(edited, trials, "the default trials judge a stop force");
        std::fs::write(dir.join("examples/eval/bad.toml"), edited).expect("write");
        let out = skillc(&dir, &["eval", "--trials", "examples/eval/bad.toml", "--out", "r2"]);
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(
            stderr(&out).contains("criteria.stop_force_rel") && stderr(&out).contains("must be a number from 0"),
            "{}",
            stderr(&out)
        );
    }
    // A URDF whose effort overflows.
    let urdf = std::fs::read_to_string(dir.join("examples/robots/lwr4.urdf")).expect("urdf");
    let at = urdf.find("effort=\"").expect("an effort");
    let end = at + 8 + urdf[at + 8..].find('"').expect("end");
    let edited = format!("{}effort=\"1e309{}", &urdf[..at], &urdf[end..]);
    std::fs::write(dir.join("huge.urdf"), edited).expect("write");
    let out = skillc(&dir, &["robot", "huge.urdf"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("`1e309` in `effort` of `<limit>` is too large"),
        "{}",
        stderr(&out)
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn the_report_opens_on_whether_it_worked() {
    let dir = workspace("report");
    let out = skillc(&dir, &["eval", "--skill", "touch", "--out", "report"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let html = std::fs::read_to_string(dir.join("report/index.html")).expect("index.html");
    let summary = html.find("<section id=summary>").expect("a summary section");
    let verdict = html.find("skill and task trials pass").expect("the verdict");
    let table = html.find("<table id=trials>").expect("the full table");
    let image = html.find("<img").expect("plots");
    assert!(
        summary < verdict && verdict < table && table < image,
        "summary, then table, then plots"
    );
    // The touch's line counts its skill trials (replays are not judged) and links its plots.
    let trials = std::fs::read_to_string(dir.join("report/summary.json")).expect("summary");
    let value: serde_json::Value = serde_json::from_str(&trials).expect("json");
    let skill_trials = value["trials"]
        .as_array()
        .expect("trials")
        .iter()
        .filter(|t| t["mode"] == "skill")
        .count();
    assert!(skill_trials > 0);
    assert!(
        html.contains(&format!("<td>{skill_trials} / {skill_trials}</td>")),
        "passed / run for touch"
    );
    assert!(html.contains("<a href=\"#trial-touch\">plots</a>") && html.contains("<h2 id=\"trial-touch\">"));
    // A failed trial is listed first with its reason: loosen nothing, tighten the force limit.
    let out = skillc(
        &dir,
        &[
            "eval",
            "--skill",
            "touch",
            "--no-replay",
            "--limit",
            "force=1",
            "--out",
            "tight",
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let html = std::fs::read_to_string(dir.join("tight/index.html")).expect("index.html");
    let failures = html.find("<h2>Failed trials</h2>").expect("failures listed");
    assert!(failures < html.find("<table id=trials>").expect("table"));
    assert!(html[failures..].contains("reflex:contact_force"), "the reason");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_run_log_into_a_folder_that_does_not_exist_is_refused_before_the_run() {
    let dir = workspace("no-folder");
    for (args, what) in [
        (
            vec![
                "run",
                "stdlib-skills/touch.skill",
                "--demo",
                "examples/demos/touch.csv",
                "--scene",
                "examples/scenes/table.toml",
            ],
            "a skill",
        ),
        (
            vec![
                "run",
                "examples/tasks/inspect_and_press.skill",
                "--scene",
                "examples/scenes/workcell.toml",
            ],
            "a task",
        ),
    ] {
        for log in ["missing/log.csv", "missing/log.mcap"] {
            let mut args = args.clone();
            args.extend(["-o", log]);
            let out = skillc(&dir, &args);
            assert_eq!(out.status.code(), Some(2), "{what}, {log}: {}", stderr(&out));
            assert!(
                stderr(&out).contains("the folder `missing` does not exist"),
                "{what}, {log}: {}",
                stderr(&out)
            );
            // Nothing ran: no summary of a run, no verdict.
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(!stdout.contains("simulated") && !stdout.contains("success"), "{stdout}");
            assert!(!dir.join("missing").exists());
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

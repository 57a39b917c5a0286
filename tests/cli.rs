//! The `skillc` binary as a user runs it: exit codes, output formats, files written or not.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn skillc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn check_exits_zero_on_the_standard_library() {
    let out = skillc(&[
        "check",
        "stdlib-skills/touch.skill",
        "stdlib-skills/press.skill",
        "stdlib-skills/slide.skill",
        "stdlib-skills/contour.skill",
        "stdlib-skills/wipe.skill",
        "stdlib-skills/press_hold.skill",
        "stdlib-skills/guarded_move.skill",
        "stdlib-skills/double_tap.skill",
        "stdlib-skills/slide_then_press.skill",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no problems"));
}

#[test]
fn check_counts_the_warnings_allowed_on_purpose_and_denies_none_of_them() {
    let out = skillc(&[
        "check",
        "--deny-warnings",
        "compiler/tests/corpus/ok/allowed_lint.skill",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("checked 1 file: no problems (1 warning allowed)"),
        "{stderr}"
    );
}

#[test]
fn check_exits_one_on_errors_and_two_on_a_missing_file() {
    let out = skillc(&["check", "compiler/tests/corpus/err/check/unknown_name.skill"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("skill::check::unknown_name"), "{stderr}");
    assert!(stderr.contains("did you mean `path`?"), "{stderr}");
    assert!(!stderr.contains("\u{1b}["), "no colour when not on a terminal");

    let out = skillc(&["check", "no/such/file.skill"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no/such/file.skill"),
        "the missing file is named"
    );
}

#[test]
fn warnings_pass_unless_denied() {
    let file = "compiler/tests/corpus/err/lint/unused.skill";
    assert_eq!(skillc(&["check", file]).status.code(), Some(0));
    assert_eq!(skillc(&["check", "--deny-warnings", file]).status.code(), Some(1));
}

#[test]
fn check_json_prints_one_object_per_diagnostic() {
    let out = skillc(&[
        "check",
        "--format",
        "json",
        "compiler/tests/corpus/err/check/many_problems.skill",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let objects: Vec<serde_json::Value> = stdout
        .lines()
        .map(|line| serde_json::from_str(line).expect("each line is JSON"))
        .collect();
    assert!(objects.len() >= 8);
    for object in &objects {
        for key in [
            "file",
            "line",
            "column",
            "end_line",
            "end_column",
            "severity",
            "code",
            "message",
            "help",
        ] {
            assert!(object.get(key).is_some(), "missing `{key}` in {object}");
        }
        assert_eq!(object["file"], "compiler/tests/corpus/err/check/many_problems.skill");
    }
    let first = &objects[0];
    assert_eq!(first["code"], "skill::check::expect_mismatch");
    assert_eq!(first["line"], 4);
}

#[test]
fn compile_writes_the_ir_or_nothing() {
    let dir = temp_dir("compile");
    let good = dir.join("press.ir.json");
    let out = skillc(&[
        "compile",
        "stdlib-skills/press.skill",
        "-o",
        good.to_str().expect("utf8 path"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let ir: skill_ir::Program = serde_json::from_slice(&std::fs::read(&good).expect("written")).expect("valid IR");
    assert_eq!(ir.skills[0].name, "press");

    let bad = dir.join("bad.ir.json");
    let out = skillc(&[
        "compile",
        "compiler/tests/corpus/err/check/dead_end.skill",
        "-o",
        bad.to_str().expect("utf8 path"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!bad.exists(), "nothing is written when the file has errors");
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing written"));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn graph_draws_guards_on_edges() {
    let out = skillc(&["graph", "stdlib-skills/touch.skill"]);
    assert_eq!(out.status.code(), Some(0));
    let dot = String::from_utf8_lossy(&out.stdout);
    assert!(dot.starts_with("digraph"));
    assert!(
        dot.contains("\"touch.approach\" -> \"touch.settle\" [label=\"force(contact.z) >= touch\"]"),
        "{dot}"
    );
    let out = skillc(&["graph", "--format", "mermaid", "stdlib-skills/press.skill"]);
    let mermaid = String::from_utf8_lossy(&out.stdout);
    assert!(mermaid.starts_with("stateDiagram-v2"));
    assert!(
        mermaid.contains("press__press --> press__retract : motion_done"),
        "{mermaid}"
    );
}

#[test]
fn fmt_rewrites_in_place_and_check_only_reports() {
    let dir = temp_dir("fmt");
    let file = dir.join("messy.skill");
    let messy = "skill s{learn{motion p=dmp(segment 1)}\nstate a{move p\non motion_done->d}\nterminal d:success}\n";
    std::fs::write(&file, messy).expect("write");
    let path = file.to_str().expect("utf8 path");

    let out = skillc(&["fmt", "--check", path]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(&file).expect("read"),
        messy,
        "--check changes nothing"
    );

    let out = skillc(&["fmt", path]);
    assert_eq!(out.status.code(), Some(0));
    let formatted = std::fs::read_to_string(&file).expect("read");
    assert!(
        formatted.contains("    state a {\n        move p from current\n"),
        "{formatted}"
    );
    assert_eq!(
        skillc(&["fmt", "--check", path]).status.code(),
        Some(0),
        "formatted files pass --check"
    );

    std::fs::write(&file, "skill {").expect("write");
    let out = skillc(&["fmt", path]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(&file).expect("read"),
        "skill {",
        "files that do not parse are left alone"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn stdlib_files_are_formatted() {
    let files: Vec<String> = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("stdlib-skills"))
        .expect("stdlib dir")
        .filter_map(Result::ok)
        .map(|e| format!("stdlib-skills/{}", e.file_name().to_string_lossy()))
        .collect();
    let mut args = vec!["fmt", "--check"];
    args.extend(files.iter().map(String::as_str));
    let out = skillc(&args);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
}

#[test]
fn robot_json_has_exactly_the_documented_keys() {
    let out = skillc(&[
        "robot",
        "examples/robots/lwr4.urdf",
        "--tool",
        "probe_tip",
        "--q",
        "0,-0.5,0,1.5,0,-1.14,0",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let value: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let mut keys: Vec<&str> = value.as_object().expect("object").keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "dof",
            "gravity_torque",
            "jacobian",
            "joints",
            "notes",
            "q",
            "robot",
            "tool_link",
            "tool_position",
            "tool_quaternion_wxyz"
        ]
    );
    assert_eq!(value["dof"], 7);
    assert_eq!(value["jacobian"].as_array().expect("rows").len(), 6);
    let out = skillc(&["robot", "examples/robots/lwr4.urdf", "--q", "0,1"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "a wrong-length configuration is a usage error"
    );
    assert!(!String::from_utf8_lossy(&out.stderr).is_empty());
}

#[test]
fn learn_writes_a_learned_file_with_the_documented_keys_and_rollout_previews_it() {
    let dir = temp_dir("learn");
    let learned = dir.join("slide.learned.json");
    let plots = dir.join("plots");
    let out = skillc(&[
        "learn",
        "stdlib-skills/slide.skill",
        "examples/demos/slide.csv",
        "-o",
        learned.to_str().expect("utf8"),
        "--plot",
        plots.to_str().expect("utf8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("segments:") && stdout.contains("planar"), "{stdout}");
    let value: serde_json::Value = serde_json::from_slice(&std::fs::read(&learned).expect("written")).expect("JSON");
    for key in ["segments", "frames", "forces", "quality", "ir_hash"] {
        assert!(value.get(key).is_some(), "missing `{key}`");
    }
    assert_eq!(value["segments"].as_array().expect("list").len(), 3);
    assert_eq!(value["frames"]["surface"]["kind"], "planar");
    assert_eq!(value["forces"]["push"]["kind"], "constant");
    let force = value["forces"]["push"]["value_n"].as_f64().expect("a number");
    assert!(
        (force - 10.0).abs() < 0.3,
        "learned {force} N, the demonstration pressed 10 N"
    );
    assert!(plots.join("slide_trajectory.svg").exists() && plots.join("slide_learned_force.svg").exists());

    let out = skillc(&["rollout", learned.to_str().expect("utf8"), "--goal-offset", "0,0,-0.05"]);
    assert_eq!(out.status.code(), Some(0));
    let csv = String::from_utf8_lossy(&out.stdout);
    assert!(csv.starts_with("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n"));
    assert!(csv.lines().count() > 8000, "the three motions at 1 kHz");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn learn_refuses_a_demonstration_without_contact_and_writes_nothing() {
    let dir = temp_dir("nocontact");
    let demo = dir.join("free.csv");
    let mut text = String::from("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
    for k in 0..2000 {
        let t = k as f64 * 0.001;
        text.push_str(&format!("{t},{},0,0.4,1,0,0,0,0.01,0,0.02,0,0,0\n", 0.5 + 0.05 * t));
    }
    std::fs::write(&demo, text).expect("write");
    let learned = dir.join("touch.learned.json");
    let out = skillc(&[
        "learn",
        "stdlib-skills/touch.skill",
        demo.to_str().expect("utf8"),
        "-o",
        learned.to_str().expect("utf8"),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no contact"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!learned.exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn eval_results_do_not_depend_on_the_thread_count_and_a_broken_trial_is_reported() {
    let dir = temp_dir("eval");
    let trials = dir.join("trials.toml");
    let root = env!("CARGO_MANIFEST_DIR");
    std::fs::write(
        &trials,
        format!(
            r#"
[[skill]]
file = "{root}/stdlib-skills/touch.skill"
demo = "{root}/examples/demos/touch.csv"
scene = "{root}/examples/scenes/table.toml"
criteria = {{ stop_force_rel = 0.20 }}
variants = [
    {{ name = "as demonstrated", set = [] }},
    {{ name = "farther", set = ["table.z=0.245"] }},
    {{ name = "broken", set = ["table.nonsense=1"] }},
]

[[skill]]
file = "{root}/stdlib-skills/press.skill"
demo = "{root}/examples/demos/missing.csv"
scene = "{root}/examples/scenes/button.toml"
variants = [{{ name = "as demonstrated", set = [] }}]
"#
        ),
    )
    .expect("write trials");
    let summaries: Vec<serde_json::Value> = ["1", "2"]
        .iter()
        .map(|threads| {
            let out_dir = dir.join(format!("report{threads}"));
            let out = skillc(&[
                "eval",
                "--trials",
                trials.to_str().expect("utf8"),
                "--threads",
                threads,
                "--out",
                out_dir.to_str().expect("utf8"),
            ]);
            assert_eq!(out.status.code(), Some(1), "a broken trial makes the exit code 1");
            assert!(out_dir.join("index.html").exists());
            serde_json::from_slice(&std::fs::read(out_dir.join("summary.json")).expect("summary")).expect("JSON")
        })
        .collect();
    let trials_of = |summary: &serde_json::Value| summary["trials"].clone();
    assert_eq!(
        trials_of(&summaries[0]),
        trials_of(&summaries[1]),
        "results differ with the thread count"
    );
    let rows = summaries[0]["trials"].as_array().expect("trials");
    assert_eq!(
        rows.len(),
        8,
        "3 touch variants and 1 press variant, each with its replay"
    );
    for row in rows {
        for key in [
            "skill",
            "variant",
            "mode",
            "success",
            "force_rms_rel",
            "contact_share",
            "peak_force_n",
            "duration_s",
        ] {
            assert!(row.get(key).is_some(), "missing `{key}` in {row}");
        }
    }
    let touch_ok = rows
        .iter()
        .filter(|r| r["skill"] == "touch" && r["mode"] == "skill" && r["success"] == true)
        .count();
    assert_eq!(touch_ok, 2, "the two good touch variants succeed: {rows:?}");
    let broken = rows.iter().find(|r| r["variant"] == "broken").expect("broken row");
    assert_eq!(broken["error"], true);
    assert!(
        broken["message"].as_str().expect("message").contains("nonsense"),
        "{broken}"
    );
    let press = rows.iter().find(|r| r["skill"] == "press").expect("press row");
    assert!(
        press["message"].as_str().expect("message").contains("missing.csv"),
        "{press}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn the_shipped_demonstrations_are_what_the_generator_makes() {
    let out = skillc(&["demos", "--check", "--out", "examples/demos"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stdout));
}

#[test]
fn eval_real_learns_from_a_folder_of_demonstrations_and_scores_the_segmentation() {
    // A folder shaped like the LASA data: one demonstration that stores the force the robot
    // applies, one whose force never changes, and a labels file.
    let dir = temp_dir("real");
    let data = dir.join("csv");
    std::fs::create_dir_all(&data).expect("dir");
    let demo =
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/demos/slide.csv"))
            .expect("shipped slide demo");
    let mut applied = String::new();
    let mut frozen = String::new();
    for (index, line) in demo.lines().enumerate() {
        if index == 0 {
            applied.push_str(line);
            frozen.push_str(line);
        } else {
            let mut fields: Vec<String> = line.split(',').map(str::to_string).collect();
            for field in &mut fields[8..14] {
                let value: f64 = field.parse().expect("number");
                *field = format!("{}", -value);
            }
            applied.push_str(&fields.join(","));
            for field in &mut fields[8..14] {
                *field = "1.5".to_string();
            }
            frozen.push_str(&fields.join(","));
        }
        applied.push('\n');
        frozen.push('\n');
    }
    std::fs::write(data.join("wipe_01.csv"), applied).expect("write");
    std::fs::write(data.join("wipe_02.csv"), frozen).expect("write");
    // Ground truth of the shipped slide: contact at 2.005 s, lift-off at 6.832 s (1 kHz).
    std::fs::write(
        data.join("segment_labels.csv"),
        "file,first_sample,last_sample,label\nwipe_01.csv,1,2005,1\nwipe_01.csv,2006,6832,2\nwipe_01.csv,6833,8850,3\n",
    )
    .expect("write");
    let out_dir = dir.join("report");
    let out = skillc(&[
        "eval",
        "--skill",
        "touch",
        "--no-replay",
        "--real",
        data.to_str().expect("utf8"),
        "--out",
        out_dir.to_str().expect("utf8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("summary.json")).expect("summary")).expect("JSON");
    let real = summary["real"].as_array().expect("real results");
    assert_eq!(real.len(), 2);
    let frozen = real.iter().find(|r| r["file"] == "wipe_02.csv").expect("frozen row");
    assert!(frozen["skipped"].as_str().expect("skipped").contains("frozen"));
    let wipe = real.iter().find(|r| r["file"] == "wipe_01.csv").expect("wipe row");
    // The learner read the negated file as the force the robot applies and says so.
    let wrench = wipe["wrench"].as_str().expect("wrench report");
    assert!(wrench.contains("sign") && wrench.contains("applies"), "{wrench}");
    let errors: Vec<f64> = wipe["boundary_errors_s"]
        .as_array()
        .expect("errors")
        .iter()
        .filter_map(|e| e.as_f64())
        .collect();
    assert_eq!(errors.len(), 2);
    assert!(errors.iter().all(|e| *e < 0.2), "boundary errors {errors:?}");
    let force = wipe["force_n"].as_f64().expect("force");
    assert!((force - 10.0).abs() < 0.5, "learned {force} N");
    // The wipe template reads the slide's one pass as one stroke.
    assert_eq!(wipe["strokes"], 1, "{wipe}");
    assert!(
        wipe["reproduction"]
            .as_str()
            .expect("reproduction")
            .starts_with("Success"),
        "{wipe}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn completions_man_page_and_help_texts() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let out = skillc(&["completions", shell]);
        assert_eq!(out.status.code(), Some(0), "{shell}");
        assert!(String::from_utf8_lossy(&out.stdout).contains("skillc"), "{shell}");
    }
    let out = skillc(&["man"]);
    assert_eq!(out.status.code(), Some(0));
    let page = String::from_utf8_lossy(&out.stdout);
    assert!(page.contains(".TH skillc 1"), "{page}");
    let dir = temp_dir("man");
    let out = skillc(&["--quiet", "man", "--out", dir.to_str().expect("utf8")]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stderr.is_empty(), "quiet");
    for page in ["skillc.1", "skillc-learn.1", "skillc-run.1", "skillc-eval.1"] {
        assert!(dir.join(page).exists(), "{page}");
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
    for verb in [
        "check", "compile", "graph", "fmt", "learn", "rollout", "run", "eval", "robot", "demos", "dump",
    ] {
        let out = skillc(&[verb, "--help"]);
        assert_eq!(out.status.code(), Some(0), "{verb}");
        let help = String::from_utf8_lossy(&out.stdout);
        assert!(
            !help.contains("\\["),
            "`skillc {verb} --help` shows an escaped bracket:\n{help}"
        );
        assert!(
            help.contains("--quiet") && help.contains("--verbose"),
            "global flags in {verb}"
        );
    }
}

#[test]
fn learn_reads_other_separators_and_column_names() {
    let dir = temp_dir("dialect");
    let demo = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/demos/touch.csv"))
        .expect("shipped demo");
    let mut lines = demo.lines();
    let header = lines
        .next()
        .expect("header")
        .replace("t,px,py,pz", "time,x_pos,y_pos,z_pos");
    let mut text = format!("\u{feff}{}\r\n", header.replace(',', "\t"));
    for line in lines {
        let quoted: Vec<String> = line.split(',').map(|f| format!("\"{f}\"")).collect();
        text.push_str(&quoted.join("\t"));
        text.push_str("\r\n");
    }
    let demo_path = dir.join("touch.tsv");
    std::fs::write(&demo_path, text).expect("write");
    let learned = dir.join("touch.learned.json");
    let args = [
        "learn",
        "stdlib-skills/touch.skill",
        demo_path.to_str().expect("utf8"),
        "-o",
        learned.to_str().expect("utf8"),
    ];
    let out = skillc(&args);
    assert_eq!(out.status.code(), Some(1), "x_pos is not a known spelling");
    assert!(String::from_utf8_lossy(&out.stderr).contains("lacks column(s) `px`, `py`, `pz`"));
    let mut mapped = args.to_vec();
    mapped.extend(["--columns", "px=x_pos,py=y_pos,z_pos=pz", "--delimiter", "tab"]);
    let out = skillc(&mapped);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(learned.exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// The trials of a summary.json, each without its wall-time-free fields compared as JSON.
fn sweep_trials(path: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(path).expect("summary written");
    let summary: serde_json::Value = serde_json::from_str(&text).expect("json");
    assert_eq!(summary["kind"], "sweep");
    let mut trials = summary["trials"].as_array().expect("trials").clone();
    trials.sort_by_key(|t| t["draw"]["index"].as_u64());
    trials
}

#[test]
fn a_sweep_split_into_shares_and_merged_equals_the_whole_sweep() {
    let dir = temp_dir("sweep");
    let run = |out: &str, extra: &[&str]| {
        let out_dir = dir.join(out);
        let mut args = vec![
            "eval",
            "--skill",
            "touch",
            "--sweep",
            "3",
            "--seed",
            "5",
            "--min-success",
            "0",
            "--out",
            out_dir.to_str().expect("utf-8"),
        ];
        args.extend_from_slice(extra);
        let result = skillc(&args);
        assert_eq!(
            result.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&result.stderr)
        );
        out_dir.join("summary.json")
    };
    let whole = run("whole", &[]);
    let first = run("first", &["--partition", "1/2"]);
    let second = run("second", &["--partition", "2/2"]);
    assert_eq!(sweep_trials(&first).len(), 2);
    assert_eq!(sweep_trials(&second).len(), 1);
    let merged_dir = dir.join("merged");
    let merged = skillc(&[
        "eval",
        "merge",
        "--min-success",
        "0",
        "--out",
        merged_dir.to_str().expect("utf-8"),
        first.to_str().expect("utf-8"),
        second.to_str().expect("utf-8"),
    ]);
    assert_eq!(
        merged.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    assert_eq!(sweep_trials(&merged_dir.join("summary.json")), sweep_trials(&whole));
    // Each trial carries its draw and the overrides that repeat it.
    for trial in sweep_trials(&whole) {
        assert!(trial["draw"]["height_m"].as_f64().expect("height").abs() <= 0.10);
        assert!(trial["set"].as_array().is_some_and(|s| !s.is_empty()));
    }
    assert!(merged_dir.join("plots/sweep.svg").exists());

    // Overlapping shares and a file that is not a sweep summary are refused.
    let overlap = skillc(&[
        "eval",
        "merge",
        "--out",
        merged_dir.to_str().expect("utf-8"),
        first.to_str().expect("utf-8"),
        first.to_str().expect("utf-8"),
    ]);
    assert_eq!(
        overlap.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&overlap.stderr)
    );
    assert!(
        String::from_utf8_lossy(&overlap.stderr).contains("is share 1/2 again"),
        "{}",
        String::from_utf8_lossy(&overlap.stderr)
    );
    // The folders `--out` named merge like their summaries.
    let folders = skillc(&[
        "eval",
        "merge",
        "--min-success",
        "0",
        "--out",
        dir.join("merged-folders").to_str().expect("utf-8"),
        dir.join("first").to_str().expect("utf-8"),
        dir.join("second").to_str().expect("utf-8"),
    ]);
    assert_eq!(
        folders.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&folders.stderr)
    );
    assert_eq!(
        sweep_trials(&dir.join("merged-folders/summary.json")),
        sweep_trials(&whole)
    );
    // Shares that do not belong together, edited or truncated shares, and missing shares.
    let merge_of = |parts: &[&Path]| {
        let mut args = vec![
            "eval".to_string(),
            "merge".into(),
            "--min-success".into(),
            "0".into(),
            "--out".into(),
            dir.join("refused").to_string_lossy().into_owned(),
        ];
        args.extend(parts.iter().map(|p| p.to_string_lossy().into_owned()));
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = skillc(&refs);
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let edited = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut value: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&second).expect("second")).expect("json");
        edit(&mut value);
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_string(&value).expect("json")).expect("write");
        path
    };
    let other_settings = run("other", &["--partition", "2/2", "--limit", "force=60"]);
    let (code, err) = merge_of(&[&first, &other_settings]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("comes from another sweep") && err.contains("other trials, files or settings"),
        "{err}"
    );
    let three = edited("three.json", &|v| v["identity"]["shares"] = 3.into());
    let (code, err) = merge_of(&[&first, &three]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("is not one of the 3 shares") || err.contains("another sweep"),
        "{err}"
    );
    let seven = edited("seven.json", &|v| v["partitions"] = serde_json::json!(["7/2"]));
    let (code, err) = merge_of(&[&first, &seven]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("K must lie in 1..=M"), "{err}");
    let empty = edited("empty.json", &|v| v["trials"] = serde_json::json!([]));
    let (code, err) = merge_of(&[&first, &empty]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("lacks draw #") && err.contains("did not finish"), "{err}");
    let moved = edited("moved.json", &|v| v["partitions"] = serde_json::json!(["1/2"]));
    let (code, err) = merge_of(&[&moved]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("which its share 1/2 does not run"), "{err}");
    let (code, err) = merge_of(&[&first]);
    assert_eq!(code, Some(1), "a lone share of two fails: {err}");
    assert!(err.contains("lacks share 2/2"), "{err}");
    assert!(
        dir.join("refused/summary.json").is_file(),
        "the partial report is written"
    );
    let not_sweep = skillc(&[
        "eval",
        "merge",
        "--out",
        merged_dir.to_str().expect("utf-8"),
        "examples/eval/default.toml",
    ]);
    assert_ne!(not_sweep.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&not_sweep.stderr).contains("not a sweep summary"));
    // A bad partition or draw count is a usage error.
    for bad in [["--sweep", "0"], ["--partition", "3/2"]] {
        let mut args = vec!["eval", "--skill", "touch", "--sweep", "2"];
        args.extend_from_slice(&bad);
        assert_eq!(skillc(&args).status.code(), Some(2), "{bad:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn eval_runs_on_its_built_in_defaults_from_any_folder() {
    let dir = temp_dir("anywhere");
    let cache = dir.join("cache");
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(["eval", "--skill", "touch", "--no-replay", "--out", "report"])
        .current_dir(&dir)
        .env("XDG_CACHE_HOME", &cache)
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("report/summary.json").is_file());
    let defaults = cache.join(format!("skillc/{}/defaults", env!("CARGO_PKG_VERSION")));
    for file in [
        "stdlib-skills/touch.skill",
        "examples/demos/touch.csv",
        "examples/robots/lwr4.urdf",
    ] {
        assert!(defaults.join(file).is_file(), "{file}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `rollout --template` writes the learned force profile on its segment (as the wrench on the
/// tool, as demonstrations store it), holds the pose through a segment without a motion, keeps
/// time increasing, and what it writes learns the same segments and force again; without the
/// template the force columns are 0 and a note says why.
#[test]
fn rollout_with_its_template_writes_the_learned_forces_on_their_segments() {
    let dir = temp_dir("rollout-forces");
    let learned = dir.join("press.learned.json");
    let learned = learned.to_str().expect("utf8");
    let out = skillc(&[
        "-q",
        "learn",
        "stdlib-skills/press.skill",
        "examples/demos/press.csv",
        "-o",
        learned,
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let value: serde_json::Value = serde_json::from_slice(&std::fs::read(learned).expect("learned")).expect("JSON");
    let segment = |k: usize, key: &str| value["segments"][k][key].as_f64().expect("segment time");
    let (press_start, press_end) = (segment(1, "start_s"), segment(1, "end_s"));

    let out = skillc(&["rollout", learned]);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("--template"),
        "the zeros are explained"
    );
    let out = skillc(&["rollout", learned, "--template", "stdlib-skills/press.skill"]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let csv = String::from_utf8_lossy(&out.stdout).into_owned();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').map(|f| f.parse().expect("number")).collect())
        .collect();
    let mut last_t = f64::NEG_INFINITY;
    let mut peak_fz: f64 = 0.0;
    for row in &rows {
        assert!(row[0] > last_t, "time increases: {} after {last_t}", row[0]);
        last_t = row[0];
        let pushing = row[10].abs() > 1e-9;
        if pushing {
            assert!(
                row[0] >= press_start - 0.01 && row[0] <= press_end + 0.01,
                "a force at {} s, outside the press segment {press_start}..{press_end} s",
                row[0]
            );
        }
        peak_fz = peak_fz.max(row[10]);
    }
    assert!(
        (last_t - segment(2, "end_s")).abs() < 0.02,
        "the rollout lasts as the demonstration: {last_t} s"
    );
    // The button pushes back up on the tool: +z, about as hard as the demonstration pressed.
    assert!((5.0..15.0).contains(&peak_fz), "peak fz {peak_fz} N");
    let rollout = dir.join("press.rollout.csv");
    std::fs::write(&rollout, &csv).expect("write");
    let again = dir.join("again.json");
    let out = skillc(&[
        "-q",
        "learn",
        "stdlib-skills/press.skill",
        rollout.to_str().expect("utf8"),
        "-o",
        again.to_str().expect("utf8"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let again: serde_json::Value = serde_json::from_slice(&std::fs::read(&again).expect("learned")).expect("JSON");
    let again_start = again["segments"][1]["start_s"].as_f64().expect("segment");
    assert!(
        (again_start - press_start).abs() < 0.05,
        "{again_start} against {press_start}"
    );
    // A template the file was not learned for is refused by name.
    let out = skillc(&["rollout", learned, "--template", "stdlib-skills/touch.skill"]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

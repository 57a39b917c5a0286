//! Every verb of `skillc` over a corpus of malformed and adversarial inputs (`tests/adversarial/`
//! plus learned files and demonstrations derived from the shipped ones here): no panic (exit
//! 101), no hang (each run is killed after 300 s and fails the test), the documented exit code
//! (1 for problems in the input, 2 for usage and IO) with a message, and no output that replaces
//! an input, a symlink or a non-regular file.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A run that takes longer than this hangs: a limit to catch hangs, not slowness, with a wide
/// margin for a debug build on a loaded 2-core machine (a run here takes seconds).
const LIMIT: Duration = Duration::from_secs(300);

/// Where standard output goes.
#[derive(Clone, Copy, PartialEq)]
enum Stdout {
    /// Captured.
    Pipe,
    /// A pipe whose reader has gone (`skillc ... | head -0`).
    Closed,
    /// `/dev/full`: every write fails with "no space left".
    Full,
}

struct Ran {
    code: i32,
    stdout: String,
    stderr: String,
}

/// Runs `skillc args` in `dir`, killing it after [`LIMIT`].
fn run_in(dir: &Path, args: &[&str], stdout: Stdout) -> Ran {
    let out_dir = dir.join(format!(".out-{}", std::process::id()));
    std::fs::create_dir_all(&out_dir).expect("output dir");
    let stderr_path = out_dir.join("stderr");
    let stdout_path = out_dir.join("stdout");
    let mut command = Command::new(env!("CARGO_BIN_EXE_skillc"));
    command
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::null())
        .stderr(std::fs::File::create(&stderr_path).expect("stderr file"));
    match stdout {
        Stdout::Pipe => command.stdout(std::fs::File::create(&stdout_path).expect("stdout file")),
        Stdout::Closed => command.stdout(Stdio::piped()),
        Stdout::Full => command.stdout(
            std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .expect("/dev/full"),
        ),
    };
    let mut child = command.spawn().expect("skillc starts");
    if stdout == Stdout::Closed {
        drop(child.stdout.take());
    }
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("`skillc {}` did not finish within {LIMIT:?}", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let ran = Ran {
        code: status.code().unwrap_or(-1),
        stdout: std::fs::read_to_string(&stdout_path).unwrap_or_default(),
        stderr: std::fs::read_to_string(&stderr_path).unwrap_or_default(),
    };
    let _ = std::fs::remove_dir_all(&out_dir);
    assert_ne!(ran.code, 101, "`skillc {}` panicked:\n{}", args.join(" "), ran.stderr);
    assert_ne!(ran.code, -1, "`skillc {}` was killed by a signal", args.join(" "));
    ran
}

/// Runs and checks the exit code, and that a failure says something.
fn expect(dir: &Path, args: &[&str], stdout: Stdout, code: i32) -> Ran {
    let ran = run_in(dir, args, stdout);
    assert_eq!(
        ran.code,
        code,
        "`skillc {}` exited {}, expected {code}; stderr:\n{}",
        args.join(" "),
        ran.code,
        ran.stderr
    );
    if code != 0 && stdout != Stdout::Closed {
        assert!(
            ran.stderr.contains("error"),
            "`skillc {}` failed without a message",
            args.join(" ")
        );
    }
    ran
}

/// A fresh working folder with the corpus, the standard skills and the examples.
fn workspace(name: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("skillc-adversarial-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("in")).expect("dir");
    for entry in std::fs::read_dir(root.join("tests/adversarial")).expect("corpus") {
        let path = entry.expect("entry").path();
        std::fs::copy(&path, dir.join("in").join(path.file_name().expect("name"))).expect("copy");
    }
    for (from, to) in [
        ("stdlib-skills/touch.skill", "in/touch.skill"),
        ("stdlib-skills/press.skill", "in/press.skill"),
        ("examples/demos/touch.csv", "in/touch.csv"),
        ("examples/scenes/table.toml", "in/table.toml"),
        ("examples/robots/lwr4.urdf", "in/lwr4.urdf"),
    ] {
        std::fs::copy(root.join(from), dir.join(to)).expect("copy");
    }
    // The scene refers to the robot beside it.
    let scene = std::fs::read_to_string(dir.join("in/table.toml")).expect("scene");
    std::fs::write(dir.join("in/table.toml"), scene.replace("../robots/", "")).expect("scene");
    dir
}

/// Every input file's bytes, to check nothing was touched.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    for entry in std::fs::read_dir(dir.join("in")).expect("inputs") {
        let path = entry.expect("entry").path();
        let meta = std::fs::symlink_metadata(&path).expect("meta");
        if meta.is_file() {
            files.insert(path.clone(), std::fs::read(&path).expect("read"));
        }
    }
    files
}

fn assert_unchanged(before: &BTreeMap<PathBuf, Vec<u8>>, dir: &Path) {
    let after = snapshot(dir);
    for (path, bytes) in before {
        assert!(after.get(path) == Some(bytes), "input `{}` was changed", path.display());
    }
}

/// Learns touch from the shipped demonstration into `in/touch.learned.json`.
fn learned(dir: &Path) -> serde_json::Value {
    expect(
        dir,
        &[
            "-q",
            "learn",
            "in/touch.skill",
            "in/touch.csv",
            "-o",
            "in/touch.learned.json",
        ],
        Stdout::Pipe,
        0,
    );
    serde_json::from_slice(&std::fs::read(dir.join("in/touch.learned.json")).expect("learned")).expect("JSON")
}

#[test]
fn malformed_demonstrations_and_templates_are_refused_and_nothing_is_written() {
    let dir = workspace("demos");
    // Derived from the shipped demonstration: positions of 1e300 m, steps of 1e-300 s, a
    // demonstration timed in microseconds.
    let demo = std::fs::read_to_string(dir.join("in/touch.csv")).expect("demo");
    let derive = |name: &str, change: &dyn Fn(usize, &mut Vec<String>)| {
        let mut text = String::new();
        for (index, line) in demo.lines().enumerate() {
            let mut fields: Vec<String> = line.split(',').map(str::to_string).collect();
            if index > 0 && !line.starts_with('#') {
                change(index, &mut fields);
            }
            text.push_str(&fields.join(","));
            text.push('\n');
        }
        std::fs::write(dir.join("in").join(name), text).expect("write");
    };
    derive("touch_1e300.csv", &|_, f| {
        for field in &mut f[1..4] {
            *field = format!("{:e}", field.parse::<f64>().expect("number") * 1e300 + 1e300);
        }
    });
    derive("touch_1e-300.csv", &|i, f| f[0] = format!("{:e}", i as f64 * 1e-300));
    derive("touch_us.csv", &|_, f| {
        f[0] = format!("{}", f[0].parse::<f64>().expect("number") * 1e6)
    });
    let before = snapshot(&dir);
    let mut demos: Vec<String> = std::fs::read_dir(dir.join("in"))
        .expect("inputs")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".csv") && name != "touch.csv" && name != "semicolons.csv")
        .collect();
    demos.sort();
    assert!(demos.len() >= 15, "the corpus: {demos:?}");
    for demo in &demos {
        let path = format!("in/{demo}");
        let ran = expect(
            &dir,
            &["learn", "in/touch.skill", &path, "-o", "out.json"],
            Stdout::Pipe,
            1,
        );
        assert!(
            ran.stderr.contains(demo.as_str()) || ran.stderr.contains("touch"),
            "the message names the file or the skill: {}",
            ran.stderr
        );
        assert!(!dir.join("out.json").exists(), "nothing written for {demo}");
    }
    let ran = expect(
        &dir,
        &["learn", "in/touch.skill", "in/touch_1e300.csv", "-o", "out.json"],
        Stdout::Pipe,
        1,
    );
    assert!(!ran.stderr.contains("null"), "{}", ran.stderr);
    // Missing or unreadable files are IO errors, whatever they are.
    expect(
        &dir,
        &["learn", "in/touch.skill", "in/nosuch.csv", "-o", "out.json"],
        Stdout::Pipe,
        2,
    );
    expect(
        &dir,
        &["learn", "in/nosuch.skill", "in/touch.csv", "-o", "out.json"],
        Stdout::Pipe,
        2,
    );
    expect(
        &dir,
        &["learn", "in/touch.skill", "in", "-o", "out.json"],
        Stdout::Pipe,
        2,
    );
    // Templates and flags that would size absurd work.
    let ran = expect(
        &dir,
        &["learn", "in/resample_10000_khz.skill", "in/touch.csv", "-o", "out.json"],
        Stdout::Pipe,
        1,
    );
    assert!(ran.stderr.contains("resample"), "{}", ran.stderr);
    let ran = expect(
        &dir,
        &["learn", "in/expect_100000.skill", "in/touch.csv", "-o", "out.json"],
        Stdout::Pipe,
        1,
    );
    assert!(
        ran.stderr.contains("expect 100000"),
        "blames the template: {}",
        ran.stderr
    );
    for flag in [
        ["--resample", "1.9e7"],
        ["--resample", "0"],
        ["--lowpass", "inf"],
        ["--lowpass", "-3"],
        ["--delimiter", "ab"],
        ["--columns", "t"],
        ["--columns", "nothing=here"],
    ] {
        let mut args = vec!["learn", "in/touch.skill", "in/touch.csv", "-o", "out.json"];
        args.extend(flag);
        expect(&dir, &args, Stdout::Pipe, 2);
    }
    assert!(!dir.join("out.json").exists());
    // The separator is detected: a semicolon file learns.
    expect(
        &dir,
        &["-q", "learn", "in/touch.skill", "in/semicolons.csv", "-o", "out.json"],
        Stdout::Pipe,
        0,
    );
    assert_unchanged(&before, &dir);
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn malformed_learned_files_are_refused_by_rollout_and_run() {
    let dir = workspace("learned");
    let good = learned(&dir);
    type Change = fn(&mut serde_json::Value);
    let cases: [(&str, Change); 11] = [
        ("version_99", |v| v["learned_version"] = 99.into()),
        ("version_text", |v| v["learned_version"] = "one".into()),
        ("no_version", |v| {
            v.as_object_mut().expect("object").remove("learned_version");
        }),
        ("empty_basis", |v| {
            let p = first_position(v);
            p["basis"]["centers"] = serde_json::json!([]);
            p["basis"]["widths"] = serde_json::json!([]);
            p["weights"] = serde_json::json!([[], [], []]);
        }),
        ("tau_1e12", |v| first_position(v)["tau_s"] = 1e12.into()),
        ("tau_negative", |v| first_position(v)["tau_s"] = (-1.0).into()),
        ("tau_zero", |v| first_position(v)["tau_s"] = 0.0.into()),
        ("weight_1e300", |v| first_position(v)["weights"][0][3] = 1e300.into()),
        ("null_goal", |v| first_position(v)["goal"][0] = serde_json::Value::Null),
        ("basis_2_5m", |v| {
            let p = first_position(v);
            let n = 2_500_000;
            p["basis"]["centers"] = serde_json::json!(vec![0.5; n]);
            p["basis"]["widths"] = serde_json::json!(vec![1.0; n]);
            p["weights"] = serde_json::json!(vec![vec![0.0; n]; 3]);
            p["config"]["n_basis"] = n.into();
        }),
        ("quaternion_norm_2", |v| {
            let motions = v["motions"].as_object_mut().expect("motions");
            let first = motions.values_mut().next().expect("a motion");
            first["orientation"]["goal"] = serde_json::json!([0.0, 0.0, 0.0, 2.0]);
        }),
    ];
    for (name, change) in cases {
        let mut value = good.clone();
        change(&mut value);
        std::fs::write(dir.join(format!("in/{name}.json")), value.to_string()).expect("write");
    }
    std::fs::write(dir.join("in/not_json.json"), "{ learned").expect("write");
    std::fs::write(dir.join("in/empty.json"), "").expect("write");
    let before = snapshot(&dir);
    for name in cases.iter().map(|c| c.0).chain(["not_json", "empty"]) {
        let file = format!("in/{name}.json");
        let ran = expect(&dir, &["rollout", &file, "-o", "out.csv"], Stdout::Pipe, 1);
        assert!(ran.stderr.contains(&file), "names the file: {}", ran.stderr);
        if name.starts_with("version") {
            assert!(ran.stderr.contains("learn it again"), "{}", ran.stderr);
        }
        assert!(!dir.join("out.csv").exists());
        expect(
            &dir,
            &["run", "in/touch.skill", "--learned", &file, "--scene", "in/table.toml"],
            Stdout::Pipe,
            1,
        );
    }
    expect(&dir, &["rollout", "in/nosuch.json"], Stdout::Pipe, 2);
    expect(&dir, &["rollout", "in"], Stdout::Pipe, 2);
    for flags in [
        ["--dt", "1e-9"],
        ["--dt", "0"],
        ["--dt", "nan"],
        ["--goal-offset", "1e308,0,0"],
        ["--goal-offset", "nan,0,0"],
        ["--goal-offset", "0,0"],
    ] {
        let mut args = vec!["rollout", "in/touch.learned.json"];
        args.extend(flags);
        expect(&dir, &args, Stdout::Pipe, 2);
    }
    assert_unchanged(&before, &dir);
    std::fs::remove_dir_all(&dir).expect("clean up");
}

fn strokes(v: &mut serde_json::Value) -> &mut Vec<serde_json::Value> {
    v["motions"]["strokes"]["strokes"].as_array_mut().expect("strokes")
}

fn first_position(v: &mut serde_json::Value) -> &mut serde_json::Value {
    let motions = v["motions"].as_object_mut().expect("motions");
    &mut motions.values_mut().next().expect("a motion")["position"]
}

#[test]
fn closed_and_full_standard_output_never_panic() {
    let dir = workspace("stdout");
    learned(&dir);
    let verbs: [&[&str]; 9] = [
        &["rollout", "in/touch.learned.json"],
        &["dump", "--stage", "ast", "in/press.skill"],
        &["dump", "--stage", "ir", "in/press.skill"],
        &["compile", "in/press.skill"],
        &["graph", "in/press.skill"],
        &["robot", "in/lwr4.urdf"],
        &["completions", "bash"],
        &["man"],
        &["learn", "in/touch.skill", "in/touch.csv", "-o", "out.json"],
    ];
    for args in verbs {
        expect(&dir, args, Stdout::Closed, 0);
        let ran = run_in(&dir, args, Stdout::Full);
        if args[0] == "learn" {
            // The learned file is written; the summary cannot be.
            assert_eq!(ran.code, 2, "{}", ran.stderr);
        } else {
            assert_eq!(ran.code, 2, "`{}` to /dev/full: {}", args.join(" "), ran.stderr);
        }
        assert!(ran.stderr.contains("standard output"), "{}", ran.stderr);
    }
    let ran = expect(
        &dir,
        &["check", "--format", "json", "in/expect_100000.skill", "in/nosuch.skill"],
        Stdout::Pipe,
        2,
    );
    assert!(!ran.stdout.is_empty() || ran.stderr.contains("nosuch"));
    // Diagnostics on a full stdout are not lost silently.
    std::fs::write(
        dir.join("in/bad.skill"),
        "skill bad { state a { on timeout 1 s -> nowhere } }\n",
    )
    .expect("write");
    let ran = expect(&dir, &["check", "--format", "json", "in/bad.skill"], Stdout::Full, 2);
    assert!(ran.stderr.contains("standard output"), "{}", ran.stderr);
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn check_does_not_claim_to_have_checked_what_it_could_not_read() {
    let dir = workspace("check");
    let ran = expect(&dir, &["check", "in/nosuch.skill"], Stdout::Pipe, 2);
    assert!(!ran.stderr.contains("checked 1 file"), "{}", ran.stderr);
    assert!(ran.stderr.contains("in/nosuch.skill"), "{}", ran.stderr);
    let ran = expect(&dir, &["check", "in/touch.skill", "in/nosuch.skill"], Stdout::Pipe, 2);
    assert!(
        ran.stderr.contains("checked 1 file") && ran.stderr.contains("1 file could not be read"),
        "{}",
        ran.stderr
    );
    let ran = expect(&dir, &["--quiet", "check", "in/touch.skill"], Stdout::Pipe, 0);
    assert!(ran.stderr.is_empty(), "quiet: {}", ran.stderr);
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn outputs_never_replace_inputs_symlinks_or_devices() {
    let dir = workspace("outputs");
    learned(&dir);
    let before = snapshot(&dir);
    for args in [
        &["compile", "in/press.skill", "-o", "in/press.skill"][..],
        &["compile", "in/press.skill", "-o", "in/./press.skill"],
        &["graph", "in/press.skill", "-o", "in/press.skill"],
        &["learn", "in/touch.skill", "in/touch.csv", "-o", "in/touch.csv"],
        &["learn", "in/touch.skill", "in/touch.csv", "-o", "in/touch.skill"],
        &["rollout", "in/touch.learned.json", "-o", "in/touch.learned.json"],
        &["compile", "in/press.skill", "-o", "in"],
    ] {
        let ran = expect(&dir, args, Stdout::Pipe, 2);
        assert!(ran.stderr.contains("in"), "{}", ran.stderr);
    }
    assert_unchanged(&before, &dir);
    // /dev/null stays a device.
    expect(&dir, &["compile", "in/press.skill", "-o", "/dev/null"], Stdout::Pipe, 0);
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let meta = std::fs::metadata("/dev/null").expect("/dev/null");
        assert!(meta.file_type().is_char_device());
        // A symlinked output is written through; a symlinked skill is formatted behind its link.
        std::os::unix::fs::symlink("ir.json", dir.join("link.json")).expect("link");
        expect(&dir, &["compile", "in/press.skill", "-o", "link.json"], Stdout::Pipe, 0);
        assert!(std::fs::symlink_metadata(dir.join("link.json"))
            .expect("link")
            .file_type()
            .is_symlink());
        assert!(std::fs::read_to_string(dir.join("ir.json"))
            .expect("target")
            .contains("\"skills\""));
        std::fs::write(
            dir.join("ugly.skill"),
            "skill   ugly {\nstate a { on timeout 1 s -> done }\nterminal done: success\n}\n",
        )
        .expect("write");
        std::os::unix::fs::symlink("ugly.skill", dir.join("pretty.skill")).expect("link");
        expect(&dir, &["fmt", "pretty.skill"], Stdout::Pipe, 0);
        assert!(std::fs::symlink_metadata(dir.join("pretty.skill"))
            .expect("link")
            .file_type()
            .is_symlink());
        assert!(std::fs::read_to_string(dir.join("ugly.skill"))
            .expect("target")
            .starts_with("skill ugly {"));
        // A FIFO is refused rather than waited on.
        if Command::new("mkfifo")
            .arg(dir.join("fifo"))
            .status()
            .is_ok_and(|s| s.success())
        {
            expect(&dir, &["compile", "in/press.skill", "-o", "fifo"], Stdout::Pipe, 2);
            assert!(std::fs::symlink_metadata(dir.join("fifo"))
                .expect("fifo")
                .file_type()
                .is_fifo());
        }
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn robot_and_demos_report_bad_inputs_with_the_right_code() {
    let dir = workspace("robot");
    expect(&dir, &["robot", "in/garbage.urdf"], Stdout::Pipe, 1);
    expect(&dir, &["robot", "in/nosuch.urdf"], Stdout::Pipe, 2);
    expect(
        &dir,
        &["robot", "in/lwr4.urdf", "--q", "nan,0,0,0,0,0,0"],
        Stdout::Pipe,
        2,
    );
    expect(&dir, &["robot", "in/lwr4.urdf", "--tool", "nosuch"], Stdout::Pipe, 1);
    // `demos --out` naming a file is an IO error; the file stays.
    let before = snapshot(&dir);
    expect(&dir, &["demos", "--out", "in/touch.csv"], Stdout::Pipe, 2);
    assert_unchanged(&before, &dir);
    let ran = run_in(&dir, &["demos", "--check", "--out", "in"], Stdout::Pipe);
    assert_eq!(ran.code, 1, "{}", ran.stdout);
    assert!(ran.stdout.contains("cannot be read"), "{}", ran.stdout);
    expect(
        &dir,
        &["--quiet", "--verbose", "check", "in/touch.skill"],
        Stdout::Pipe,
        2,
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `skillc run` bounds `--speed`/`--force-scale`, refuses `-o` naming an input, and scenes
/// refuse absurd sizes.
#[test]
fn run_bounds_its_factors_and_never_overwrites_the_scene() {
    let dir = workspace("run");
    learned(&dir);
    let before = snapshot(&dir);
    let base = [
        "run",
        "in/touch.skill",
        "--learned",
        "in/touch.learned.json",
        "--scene",
        "in/table.toml",
    ];
    for flags in [
        ["--speed", "1e-12"],
        ["--speed", "1e300"],
        ["--speed", "inf"],
        ["--force-scale", "1e300"],
        ["-o", "in/table.toml"],
        ["-o", "in/touch.learned.json"],
    ] {
        let mut args = base.to_vec();
        args.extend(flags);
        expect(&dir, &args, Stdout::Pipe, 2);
    }
    expect(
        &dir,
        &[
            "run",
            "in/touch.skill",
            "--learned",
            "in/touch.learned.json",
            "--scene",
            "in/huge_box.toml",
        ],
        Stdout::Pipe,
        1,
    );
    expect(
        &dir,
        &[
            "run",
            "in/touch.skill",
            "--learned",
            "in/touch.learned.json",
            "--scene",
            "in/nosuch.toml",
        ],
        Stdout::Pipe,
        2,
    );
    assert_unchanged(&before, &dir);
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn scenes_that_cannot_be_read_are_io_errors_named_once() {
    let dir = workspace("scenes");
    learned(&dir);
    let ran = expect(
        &dir,
        &[
            "run",
            "in/touch.skill",
            "--learned",
            "in/touch.learned.json",
            "--scene",
            "in/nosuch.toml",
        ],
        Stdout::Pipe,
        2,
    );
    assert_eq!(ran.stderr.matches("os error").count(), 1, "{}", ran.stderr);
    expect(
        &dir,
        &[
            "run",
            "in/touch.skill",
            "--learned",
            "in/touch.learned.json",
            "--scene",
            "in/garbage.toml",
        ],
        Stdout::Pipe,
        1,
    );
    expect(
        &dir,
        &[
            "run",
            "in/touch.skill",
            "--demo",
            "in/nosuch.csv",
            "--scene",
            "in/table.toml",
        ],
        Stdout::Pipe,
        2,
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// Files that still print with `print!`/`println!` (their owner routes them through
/// `skill_kit::out::print`); the backstop in `main` keeps them from panicking meanwhile.
const PRINTING: [&str; 0] = [];

/// Whether `line` calls `mac` itself (not `eprintln!` for `println!`).
fn calls(line: &str, mac: &str) -> bool {
    line.match_indices(mac)
        .any(|(at, _)| !line[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
}

#[test]
fn primary_output_goes_through_one_writer() {
    fn walk(dir: &Path, files: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("src").filter_map(Result::ok) {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, files);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    walk(&root.join("src"), &mut files);
    for path in files {
        let name = path
            .strip_prefix(root)
            .expect("inside")
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(&path).expect("read");
        let prints = text
            .lines()
            .map(str::trim_start)
            .filter(|line| !line.starts_with("//"))
            .any(|line| ["println!(", "print!("].iter().any(|m| calls(line, m)));
        if PRINTING.contains(&name.as_str()) {
            continue;
        }
        assert!(
            !prints,
            "`{name}` prints with print!/println!, which panic on a closed or full stdout: use skill_kit::out::print"
        );
    }
}

/// Copies the standard wipe and its demonstration into the workspace.
fn with_wipe(dir: &Path) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (from, to) in [
        ("stdlib-skills/wipe.skill", "in/wipe.skill"),
        ("examples/demos/wipe.csv", "in/wipe.csv"),
    ] {
        std::fs::copy(root.join(from), dir.join(to)).expect("copy");
    }
}

/// `repeat`, `strokes(...)` and the displacement and magnitude guards with absurd values: the
/// template is refused by name and line, or learns what it says; a learned strokes motion with
/// too many strokes, an empty basis or an absurd duration is refused by rollout and run.
#[test]
fn repetition_and_strokes_with_absurd_values_are_refused_or_learn() {
    let dir = workspace("strokes");
    with_wipe(&dir);
    let before = snapshot(&dir);
    for (skill, needle) in [
        ("repeat_zero", "repeat count"),
        ("repeat_huge", "repeat count"),
        ("strokes_segment_99", "segment 99"),
        ("strokes_min_length_0", "stroke length"),
        ("strokes_basis_huge", "basis functions"),
        ("cluster_min_length_1e300", "min_length"),
    ] {
        let file = format!("in/{skill}.skill");
        let ran = expect(
            &dir,
            &["learn", &file, "in/wipe.csv", "-o", "out.json"],
            Stdout::Pipe,
            1,
        );
        assert!(
            ran.stderr.contains(needle) && (ran.stderr.contains(skill) || ran.stderr.contains("skill `wipe`")),
            "{skill}: {}",
            ran.stderr
        );
        assert!(!ran.stderr.contains("18446744073709551"), "{skill}: {}", ran.stderr);
        assert!(!dir.join("out.json").exists(), "{skill}: nothing is written");
        expect(
            &dir,
            &["check", &file],
            Stdout::Pipe,
            u8::from(skill != "cluster_min_length_1e300").into(),
        );
    }
    // One stroke no shorter than 1e300 s is the whole segment; guards that cannot fire compile.
    for skill in ["strokes_min_length_1e300", "guards_1e300"] {
        let file = format!("in/{skill}.skill");
        let out = format!("{skill}.json");
        expect(
            &dir,
            &["-q", "learn", &file, "in/wipe.csv", "-o", &out],
            Stdout::Pipe,
            0,
        );
    }
    let learned: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("strokes_min_length_1e300.json")).expect("learned"))
            .expect("JSON");
    assert_eq!(
        learned["motions"]["strokes"]["strokes"].as_array().map(Vec::len),
        Some(1)
    );

    // Learned strokes: too many, an empty basis, an absurd duration.
    expect(
        &dir,
        &[
            "-q",
            "learn",
            "in/wipe.skill",
            "in/wipe.csv",
            "-o",
            "in/wipe.learned.json",
        ],
        Stdout::Pipe,
        0,
    );
    let good: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("in/wipe.learned.json")).expect("learned")).expect("JSON");
    type Change = fn(&mut Vec<serde_json::Value>);
    let cases: [(&str, Change, &str); 3] = [
        (
            "strokes_10001",
            |s| {
                // Small strokes (two basis functions), so that the file stays small.
                let mut small = s[0].clone();
                for part in ["position", "orientation"] {
                    small[part]["basis"]["centers"] = serde_json::json!([0.9, 0.1]);
                    small[part]["basis"]["widths"] = serde_json::json!([1.0, 1.0]);
                    small[part]["weights"] = serde_json::json!([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]);
                    small[part]["config"]["n_basis"] = 2.into();
                }
                *s = vec![small; 10_001];
            },
            "strokes",
        ),
        (
            "stroke_empty_basis",
            |s| {
                let p = &mut s[1]["position"];
                p["basis"]["centers"] = serde_json::json!([]);
                p["basis"]["widths"] = serde_json::json!([]);
                p["weights"] = serde_json::json!([[], [], []]);
            },
            "basis",
        ),
        ("stroke_tau_1e12", |s| s[2]["position"]["tau_s"] = 1e12.into(), "tau_s"),
    ];
    for (name, change, needle) in cases {
        let mut value = good.clone();
        change(strokes(&mut value));
        let file = format!("in/{name}.json");
        std::fs::write(dir.join(&file), value.to_string()).expect("write");
        let ran = expect(&dir, &["rollout", &file, "-o", "out.csv"], Stdout::Pipe, 1);
        assert!(
            ran.stderr.contains(&file) && ran.stderr.contains(needle),
            "{name}: {}",
            ran.stderr
        );
        expect(
            &dir,
            &["run", "in/wipe.skill", "--learned", &file, "--scene", "in/table.toml"],
            Stdout::Pipe,
            1,
        );
        assert!(!dir.join("out.csv").exists());
    }
    assert_unchanged(&before, &dir);
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// A force of 1e300 N is refused by sample and column, not reported as an infinite peak.
#[test]
fn a_force_beyond_any_sensor_is_named_by_sample_and_column() {
    let dir = workspace("force");
    let demo = std::fs::read_to_string(dir.join("in/touch.csv")).expect("demo");
    let mut text = String::new();
    let mut data_rows = 0;
    for line in demo.lines() {
        if line.starts_with('#') || line.starts_with('t') {
            text.push_str(line);
        } else {
            data_rows += 1;
            let mut fields: Vec<&str> = line.split(',').collect();
            if data_rows == 3000 {
                fields[10] = "1e300";
            }
            text.push_str(&fields.join(","));
        }
        text.push('\n');
    }
    std::fs::write(dir.join("in/force_1e300.csv"), text).expect("write");
    let ran = expect(
        &dir,
        &["learn", "in/touch.skill", "in/force_1e300.csv", "-o", "out.json"],
        Stdout::Pipe,
        1,
    );
    assert!(
        ran.stderr.contains("in/force_1e300.csv") && ran.stderr.contains("sample 3000") && ran.stderr.contains("fz"),
        "{}",
        ran.stderr
    );
    assert!(!ran.stderr.contains("inf N"), "{}", ran.stderr);
    assert!(!dir.join("out.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `eval --real` on a folder without demonstrations and `eval --skill` naming no skill are usage
/// errors found before any trial runs, naming the folder or the name; `--quiet` silences `run`
/// and `eval` but for errors, a failed run among them.
#[test]
fn eval_refuses_what_it_cannot_run_and_quiet_reaches_run_and_eval() {
    let dir = workspace("eval");
    std::fs::create_dir_all(dir.join("empty")).expect("dir");
    std::fs::write(dir.join("empty/segment_labels.csv"), "file,start,end,label\n").expect("labels");
    let ran = expect(&dir, &["eval", "--real", "empty", "--out", "report"], Stdout::Pipe, 2);
    assert!(
        ran.stderr.contains("`empty`") && ran.stderr.contains("no demonstration"),
        "{}",
        ran.stderr
    );
    expect(&dir, &["eval", "--real", "nosuch", "--out", "report"], Stdout::Pipe, 2);
    let ran = expect(&dir, &["eval", "--skill", "nosuch", "--out", "report"], Stdout::Pipe, 2);
    assert!(
        ran.stderr.contains("`nosuch`") && ran.stderr.contains("touch"),
        "{}",
        ran.stderr
    );
    assert!(!dir.join("report").exists());

    learned(&dir);
    let run = [
        "run",
        "in/touch.skill",
        "--learned",
        "in/touch.learned.json",
        "--scene",
        "in/table.toml",
    ];
    let ran = expect(&dir, &[&["-q"][..], &run].concat(), Stdout::Pipe, 0);
    assert!(
        ran.stdout.is_empty() && ran.stderr.is_empty(),
        "{}{}",
        ran.stdout,
        ran.stderr
    );
    // The table 30 cm lower is never reached: the failure is the one thing said.
    let ran = expect(
        &dir,
        &[&["-q"][..], &run, &["--set", "table.z=0.0"]].concat(),
        Stdout::Pipe,
        1,
    );
    assert!(
        ran.stdout.is_empty() && ran.stderr.contains("ended in failure"),
        "{}",
        ran.stderr
    );
    let ran = expect(&dir, &[&["-v"][..], &run].concat(), Stdout::Pipe, 0);
    assert!(
        ran.stderr.contains("wall clock") && ran.stdout.contains("success"),
        "{}",
        ran.stderr
    );
    let ran = expect(
        &dir,
        &["-q", "eval", "--skill", "touch", "--no-replay", "--out", "report"],
        Stdout::Pipe,
        0,
    );
    assert!(
        ran.stdout.is_empty() && ran.stderr.is_empty(),
        "{}{}",
        ran.stdout,
        ran.stderr
    );
    assert!(dir.join("report/summary.json").is_file());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

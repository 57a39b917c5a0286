//! `skillc plant` and `skillc run --plant` as two processes over loopback TCP: in lockstep the
//! run's log is the in-process run's log byte for byte, for a skill and for a task (a task's MCAP
//! with the button's cap moving on `/scene`), and so are its contact witness's lines; in realtime
//! the run prints the loop's line and its scheduling, and under SCHED_FIFO at most 1 % of the
//! ticks are late; the plant stops cleanly on SIGTERM and reports what it served; an endpoint that
//! is not `tcp/HOST:PORT` as Zenoh reads it is a usage error naming its flag, for both commands.
#![cfg(feature = "zenoh")]

use std::io::Read;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// `skillc run` of the standard touch on the table, learned from its demonstration.
const TOUCH: [&str; 6] = [
    "run",
    "stdlib-skills/touch.skill",
    "--demo",
    "examples/demos/touch.csv",
    "--scene",
    "examples/scenes/table.toml",
];

fn skillc() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_skillc"));
    command.current_dir(env!("CARGO_MANIFEST_DIR"));
    command
}

fn endpoint() -> String {
    let port = TcpListener::bind("127.0.0.1:0")
        .and_then(|listener| listener.local_addr())
        .expect("a free port")
        .port();
    format!("tcp/127.0.0.1:{port}")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-split-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// A running `skillc plant`, killed if the test fails before it stops it.
struct Plant(Option<Child>);

impl Plant {
    fn start(scene: &str, endpoint: &str) -> Plant {
        let child = skillc()
            .args(["plant", "--scene", scene, "--listen", endpoint])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("starts skillc plant");
        Plant(Some(child))
    }

    /// SIGTERM, then what it printed; it must exit by itself within 5 s.
    fn stop(mut self) -> Output {
        let mut child = self.0.take().expect("running");
        let status = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .expect("kill");
        assert!(status.success());
        let began = Instant::now();
        while child.try_wait().expect("wait").is_none() {
            assert!(
                began.elapsed() < Duration::from_secs(5),
                "the plant did not stop on SIGTERM"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        child.wait_with_output().expect("output")
    }
}

impl Drop for Plant {
    fn drop(&mut self) {
        if let Some(child) = &mut self.0 {
            let _ = child.kill();
            let mut text = String::new();
            if let Some(err) = child.stderr.as_mut() {
                let _ = err.read_to_string(&mut text);
            }
            let _ = child.wait();
            eprintln!("plant's stderr: {text}");
        }
    }
}

fn run(args: &[&str]) -> Output {
    let output = skillc().args(args).output().expect("runs skillc");
    assert!(
        output.status.code().is_some_and(|code| code <= 1),
        "skillc {args:?}: {}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn same_file(a: &Path, b: &Path) {
    let (left, right) = (std::fs::read(a).expect("log"), std::fs::read(b).expect("log"));
    assert!(!left.is_empty());
    if left != right {
        let (l, r) = (String::from_utf8_lossy(&left), String::from_utf8_lossy(&right));
        let first = l.lines().zip(r.lines()).position(|(x, y)| x != y);
        panic!(
            "{} and {} differ ({} and {} lines), first at line {first:?}",
            a.display(),
            b.display(),
            l.lines().count(),
            r.lines().count()
        );
    }
}

#[test]
fn lockstep_logs_equal_the_in_process_logs_for_a_skill_and_a_task() {
    let dir = scratch("lockstep");
    // The task presses the work cell's button: its MCAP log's `/scene` moves the cap as the
    // plant's states report it, so the bag equals the in-process one only if the cap's depth
    // crossed the link too.
    let task_log = if cfg!(feature = "mcap") { "mcap" } else { "csv" };
    let cases: [(&str, Vec<&str>, &str); 2] = [
        (
            "examples/scenes/table.toml",
            [TOUCH.as_slice(), &["--set", "table.z+=-0.02"]].concat(),
            "csv",
        ),
        (
            "examples/scenes/workcell.toml",
            vec![
                "run",
                "examples/tasks/inspect_and_press.skill",
                "--scene",
                "examples/scenes/workcell.toml",
            ],
            task_log,
        ),
    ];
    for (index, (scene, args, log)) in cases.iter().enumerate() {
        let here = dir.join(format!("{index}-here.{log}"));
        let there = dir.join(format!("{index}-there.{log}"));
        let mut local = args.clone();
        local.extend(["-o", here.to_str().expect("utf-8")]);
        let local_out = run(&local);

        let endpoint = endpoint();
        // The plant takes the run's scene changes too.
        let sets: Vec<&str> = args.windows(2).filter(|w| w[0] == "--set").map(|w| w[1]).collect();
        let mut plant_args = vec!["plant", "--scene", scene, "--listen", &endpoint];
        for set in &sets {
            plant_args.extend(["--set", set]);
        }
        let plant = Plant(Some(
            skillc()
                .args(&plant_args)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("plant"),
        ));
        let mut remote = args.clone();
        remote.extend(["--plant", &endpoint, "--lockstep", "-o", there.to_str().expect("utf-8")]);
        let remote_out = run(&remote);
        same_file(&here, &there);
        assert_eq!(local_out.status.code(), remote_out.status.code(), "same verdict");
        // The plant's contact witness reaches the run's report: the same lines, step for step,
        // as the in-process simulation's (one per task step).
        let witness = |out: &Output| -> Vec<String> {
            String::from_utf8_lossy(&out.stdout)
                .lines()
                .filter(|line| line.contains("contact witness"))
                .map(str::to_owned)
                .collect()
        };
        let (local_witness, remote_witness) = (witness(&local_out), witness(&remote_out));
        assert!(
            !local_witness.is_empty(),
            "{}",
            String::from_utf8_lossy(&local_out.stdout)
        );
        assert_eq!(local_witness, remote_witness);
        let served = plant.stop();
        assert_eq!(
            served.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&served.stderr)
        );
        let text = String::from_utf8_lossy(&served.stdout);
        let ticks = logged_ticks(&local_out);
        assert!(
            text.contains(&format!("plant: stopped after {ticks} ticks")) && text.contains("1 session(s)"),
            "{text}"
        );
        // The plant's own witness line counts every step it served, the runs' share included.
        assert!(
            text.contains(&format!("contact witness: {ticks} steps checked")),
            "{text}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The ticks a run's `wrote `…` (N ticks)` line names.
fn logged_ticks(out: &Output) -> u64 {
    let text = String::from_utf8_lossy(&out.stdout);
    text.lines()
        .find_map(|line| {
            let (_, rest) = line.strip_prefix("wrote `")?.rsplit_once("` (")?;
            rest.strip_suffix(" ticks)")?.parse().ok()
        })
        .unwrap_or_else(|| panic!("no `wrote` line in {text}"))
}

#[test]
fn realtime_prints_the_loop_and_ends_in_a_verdict() {
    let endpoint = endpoint();
    let plant = Plant::start("examples/scenes/table.toml", &endpoint);
    let began = Instant::now();
    let mut args = TOUCH.to_vec();
    args.extend(["--plant", &endpoint, "--realtime"]);
    let output = run(&args);
    let wall = began.elapsed().as_secs_f64();
    let text = String::from_utf8_lossy(&output.stdout);
    let line = text
        .lines()
        .find(|line| line.trim_start().starts_with("loop: "))
        .unwrap_or_else(|| {
            panic!(
                "no loop line (exit {:?}) in {text}\nstderr: {}",
                output.status.code(),
                String::from_utf8_lossy(&output.stderr)
            )
        });
    let words: Vec<&str> = line.split_whitespace().collect();
    let ticks: u64 = words[1].parse().expect("ticks");
    let late: u64 = words[3].parse().expect("late");
    eprintln!("{line} ({wall:.2} s wall)");
    // The plant's 1 ms clock sets the pace: the run takes at least its ticks' time.
    assert!(wall >= ticks as f64 * 1e-3, "{ticks} ticks in {wall} s");
    assert!(ticks > 200 && late < ticks, "{line}");
    // Under SCHED_FIFO (root, CAP_SYS_NICE or an rtprio limit) the loop keeps its ticks: on the
    // 2-core VM this was built on, 0.03-0.10 % of them were late, about one a second, where
    // `cyclictest` at the same priority shows the machine itself waking a thread 0.3-3.3 ms late
    // about twice a second. At normal priority 0.3-0.9 % were late; that is only printed.
    let scheduling = text
        .lines()
        .find(|line| line.trim_start().starts_with("scheduling: "))
        .unwrap_or_else(|| panic!("no scheduling line in {text}"));
    if scheduling.contains("SCHED_FIFO priority") {
        assert!(
            late * 100 <= ticks,
            "more than 1 % of the ticks late under SCHED_FIFO: {line}"
        );
    } else {
        eprintln!("{scheduling}: late commands not bounded");
    }
    // The plant's contact witness reaches the run across the link.
    assert!(text.contains("contact witness: "), "{text}");
    // On a quiet machine the touch succeeds; on the 2-core VM this was built on, stalls of
    // several ms leave the plant holding the torques that long, and at normal priority in about
    // one run of four the wrist's speed tripped the supervisor. Either way the run ends in a
    // verdict, never a hang or an error.
    assert!(
        text.contains("success: reached `done`") || text.contains("FAILURE: reflex stop"),
        "{text}"
    );
    let served = plant.stop();
    assert_eq!(served.status.code(), Some(0));
}

#[test]
fn without_a_plant_the_run_says_what_to_start() {
    let endpoint = endpoint();
    let output = skillc()
        .args(TOUCH)
        .args(["--plant", &endpoint])
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no plant answered") && err.contains("skillc plant --scene"),
        "{err}"
    );
    let bad = skillc()
        .args([
            "plant",
            "--scene",
            "examples/scenes/table.toml",
            "--listen",
            "udp/1.2.3.4:5",
        ])
        .output()
        .expect("runs");
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("tcp/HOST:PORT"));
}

#[test]
fn bad_endpoints_are_usage_errors_that_name_their_flag() {
    for bad in [
        r#"tcp/127.0.0.1:7447","tcp/0.0.0.0:7448"#,
        "tcp/host",
        "udp/127.0.0.1:7447",
        r#"tcp/127.0.0.1:7447""#,
        r#"tcp/127.0.0.1":7447"#,
        "tcp/127.0.0.1:7447#iface=lo",
    ] {
        let plant = skillc()
            .args(["plant", "--scene", "examples/scenes/table.toml", "--listen", bad])
            .output()
            .expect("runs");
        let mut args = TOUCH.to_vec();
        args.extend(["--plant", bad]);
        let run = skillc().args(&args).output().expect("runs");
        for (output, flag) in [(plant, "--listen"), (run, "--plant")] {
            let err = String::from_utf8_lossy(&output.stderr);
            assert_eq!(output.status.code(), Some(2), "{flag} {bad}: {err}");
            assert!(
                err.contains(flag) && err.contains("tcp/HOST:PORT"),
                "{flag} {bad}: {err}"
            );
            // A usage error, not Zenoh's configuration parser.
            assert!(!err.contains("json"), "{flag} {bad}: {err}");
        }
    }
}

#[test]
fn a_plant_that_falls_silent_ends_the_run_in_a_named_failure_with_its_log() {
    let dir = scratch("silent");
    let learned = dir.join("touch.learned.json");
    let learn = skillc()
        .args([
            "learn",
            "stdlib-skills/touch.skill",
            "examples/demos/touch.csv",
            "-q",
            "-o",
        ])
        .arg(&learned)
        .status()
        .expect("learns");
    assert!(learn.success());
    let endpoint = endpoint();
    let mut plant = Plant::start("examples/scenes/table.toml", &endpoint);
    let log = dir.join("log.csv");
    // A slow touch (a quarter of the demonstrated speed): tens of thousands of lockstep ticks,
    // seconds of them after the plant is killed below.
    let run = skillc()
        .args([
            "run",
            "stdlib-skills/touch.skill",
            "--scene",
            "examples/scenes/table.toml",
            "--speed",
            "0.25",
        ])
        .arg("--learned")
        .arg(&learned)
        .args(["--plant", &endpoint, "--lockstep", "-o"])
        .arg(&log)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    std::thread::sleep(Duration::from_secs(2));
    // Killed, not stopped: no goodbye, the link just falls silent.
    if let Some(child) = plant.0.as_mut() {
        child.kill().expect("kills the plant");
        let _ = child.wait();
    }
    plant.0 = None;
    let began = Instant::now();
    let output = run.wait_with_output().expect("the run ends");
    let text = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        began.elapsed() < Duration::from_secs(30),
        "the run ended {:.1} s after the plant was killed",
        began.elapsed().as_secs_f64()
    );
    assert_eq!(
        output.status.code(),
        Some(1),
        "a failure, not an error: {text}\n{stderr}"
    );
    assert!(
        text.contains("FAILURE") && text.contains("plant_link: the link to the plant failed in state"),
        "{text}\n{stderr}"
    );
    let rows = std::fs::read_to_string(&log)
        .expect("the log up to the loss")
        .lines()
        .count();
    assert!(rows > 500, "{rows} rows");
    let _ = std::fs::remove_dir_all(&dir);
}

//! Benchmark: the plant and the run in two processes over loopback (issue 28), beside the same
//! run in one process. For the standard slide learned from its demonstration, each round times
//! `skillc run` in one process, the same run `--plant … --lockstep` against a fresh `skillc plant`
//! (the cost of a tick's round trip, per tick), and `--realtime` (the loop line's late commands,
//! round trip and jitter), with the CPU each process used (from `/usr/bin/time` where it is
//! installed). Rounds interleave the cases so the host's load moves them alike; medians and ranges
//! are printed. Run with `cargo bench --bench split [-- ROUNDS]` (default 4: about a minute of
//! realtime slide).

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn skillc(timed: bool) -> Command {
    if timed && Path::new("/usr/bin/time").exists() {
        let mut command = Command::new("/usr/bin/time");
        command.args(["-f", "cpu %U %S"]).arg(env!("CARGO_BIN_EXE_skillc"));
        command
    } else {
        Command::new(env!("CARGO_BIN_EXE_skillc"))
    }
}

fn endpoint() -> String {
    let port = TcpListener::bind("127.0.0.1:0")
        .and_then(|listener| listener.local_addr())
        .expect("a free port")
        .port();
    format!("tcp/127.0.0.1:{port}")
}

/// User + system CPU seconds from `/usr/bin/time`'s last `cpu U S` line, if any.
fn cpu(stderr: &str) -> Option<f64> {
    let line = stderr.lines().rev().find(|line| line.starts_with("cpu "))?;
    let mut words = line.split_whitespace().skip(1);
    Some(words.next()?.parse::<f64>().ok()? + words.next()?.parse::<f64>().ok()?)
}

struct Timed {
    wall_s: f64,
    cpu_s: Option<f64>,
    stdout: String,
}

fn run(root: &Path, args: &[String]) -> Timed {
    let started = Instant::now();
    let out = skillc(true).args(args).current_dir(root).output().expect("skillc runs");
    let wall_s = started.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.code().is_some_and(|code| code <= 1),
        "`skillc {}` failed: {stderr}",
        args.join(" ")
    );
    Timed {
        wall_s,
        cpu_s: cpu(&stderr),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
    }
}

fn start_plant(root: &Path, endpoint: &str) -> Child {
    let child = skillc(true)
        .args([
            "plant",
            "--scene",
            "examples/scenes/table.toml",
            "--listen",
            endpoint,
            "-q",
        ])
        .current_dir(root)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("skillc plant");
    std::thread::sleep(Duration::from_millis(300));
    child
}

/// SIGTERM to the plant (the child of `/usr/bin/time` when that measures it: time itself would
/// die of the signal and leave the plant running); the plant's CPU seconds.
fn stop_plant(child: Child) -> Option<f64> {
    let pid = child.id().to_string();
    let signalled = if Path::new("/usr/bin/time").exists() {
        Command::new("pkill").args(["-TERM", "-P", &pid]).status()
    } else {
        Command::new("kill").args(["-TERM", &pid]).status()
    };
    assert!(signalled.expect("kill").success());
    let out = child.wait_with_output().expect("the plant exits");
    cpu(&String::from_utf8_lossy(&out.stderr))
}

fn median(values: &[f64]) -> f64 {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted.sort_by(f64::total_cmp);
    sorted[sorted.len() / 2]
}

fn range(values: &[f64]) -> (f64, f64) {
    values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(*v), hi.max(*v))
    })
}

fn main() {
    let rounds: usize = std::env::args().skip(1).find_map(|arg| arg.parse().ok()).unwrap_or(4);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("skillc-bench-split-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("bench folder");
    let learned = dir.join("slide.learned.json");
    let learn = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args([
            "learn",
            "stdlib-skills/slide.skill",
            "examples/demos/slide.csv",
            "-q",
            "-o",
        ])
        .arg(&learned)
        .current_dir(&root)
        .status()
        .expect("skillc learns");
    assert!(learn.success());
    let base: Vec<String> = [
        "run",
        "stdlib-skills/slide.skill",
        "--scene",
        "examples/scenes/table.toml",
        "--learned",
        &learned.display().to_string(),
    ]
    .map(String::from)
    .to_vec();
    let with = |extra: &[&str]| {
        let mut args = base.clone();
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let ticks = {
        let log = dir.join("ticks.csv");
        run(&root, &with(&["-q", "-o", &log.display().to_string()]));
        (std::fs::read_to_string(&log).expect("log").lines().count() - 1) as f64
    };
    let (mut here, mut lockstep, mut realtime) = (Vec::new(), Vec::new(), Vec::new());
    let (mut here_cpu, mut lock_cpu, mut lock_plant_cpu) = (Vec::new(), Vec::new(), Vec::new());
    let (mut real_cpu, mut real_plant_cpu, mut lines) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds {
        let local = run(&root, &with(&["-q"]));
        here.push(local.wall_s);
        here_cpu.push(local.cpu_s.unwrap_or(f64::NAN));

        let at = endpoint();
        let plant = start_plant(&root, &at);
        let remote = run(&root, &with(&["-q", "--plant", &at, "--lockstep"]));
        lockstep.push(remote.wall_s);
        lock_cpu.push(remote.cpu_s.unwrap_or(f64::NAN));
        lock_plant_cpu.push(stop_plant(plant).unwrap_or(f64::NAN));

        let at = endpoint();
        let plant = start_plant(&root, &at);
        let remote = run(&root, &with(&["--plant", &at, "--realtime"]));
        realtime.push(remote.wall_s);
        real_cpu.push(remote.cpu_s.unwrap_or(f64::NAN));
        real_plant_cpu.push(stop_plant(plant).unwrap_or(f64::NAN));
        let line = remote
            .stdout
            .lines()
            .find(|line| line.trim_start().starts_with("loop: "))
            .unwrap_or("no loop line")
            .trim()
            .to_owned();
        let verdict = if remote.stdout.contains("success: reached") {
            "success"
        } else {
            "failure"
        };
        lines.push(format!("{line} [{verdict}]"));
    }
    println!("slide, {ticks} ticks; {rounds} rounds interleaved; median wall (range), CPU s (user + system)");
    for (name, walls, cpus, plant_cpus) in [
        ("in one process", &here, &here_cpu, None),
        ("--plant --lockstep", &lockstep, &lock_cpu, Some(&lock_plant_cpu)),
        ("--plant --realtime", &realtime, &real_cpu, Some(&real_plant_cpu)),
    ] {
        let (low, high) = range(walls);
        let mid = median(walls);
        let plant = plant_cpus
            .map(|cpus| format!(", plant {:.2} s CPU", median(cpus)))
            .unwrap_or_default();
        println!(
            "  {name:<20} {mid:>7.3} s ({low:.3}-{high:.3}), {:>6.1} µs a tick; run {:.2} s CPU{plant}",
            mid / ticks * 1e6,
            median(cpus)
        );
    }
    println!(
        "  lockstep costs {:.1} µs a tick more than one process",
        (median(&lockstep) - median(&here)) / ticks * 1e6
    );
    for line in lines {
        println!("  realtime: {line}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

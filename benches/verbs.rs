//! Benchmark: every verb a user runs, timed as the whole `skillc` process on generated files
//! of realistic size (issue 27): `learn` at 10 000, 50 000 and 600 000 samples (a minute and
//! the 600 s maximum at 1 kHz; Ward with ±5 connectivity), `run` of the slide without a log,
//! with a CSV log and with an MCAP log, the default `eval` and a sweep of 200 draws.
//!
//! A bench binary, not criterion: one `eval` takes tens of seconds, and what a user feels is
//! the wall time of the process, so each case runs `ROUNDS` times (default 3, first argument or
//! `SKILLC_BENCH_ROUNDS`), the cases interleaved round by round so that the host's load moves
//! them alike, and the median wall time is printed with the range, the peak resident memory
//! (from `/usr/bin/time` where it is installed) and, for `learn`, the growth exponent between
//! sizes. Run with `cargo bench --bench verbs [-- ROUNDS] [-- quick]`; `quick` leaves out the
//! eval and the sweep.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// A slide-like demonstration at 1 kHz: an approach (at most 5 s), a stroke in 12 N contact,
/// a retreat (at most 5 s); 0.1 mm and 0.3 N of noise from a fixed-seed generator.
fn write_demo(path: &Path, samples: usize) {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let approach = (samples * 3 / 10).min(5000);
    let retreat = (samples / 5).min(5000);
    let stroke = samples - approach - retreat;
    let wave = if samples <= 100_000 { 0.05 } else { 0.0 };
    let mut text = String::with_capacity(samples * 100);
    text.push_str("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
    for i in 0..samples {
        let (pos, force) = if i < approach {
            let u = i as f64 / approach as f64;
            ([0.5, 0.0, 0.3 - 0.2 * u], [0.0; 3])
        } else if i < approach + stroke {
            let u = (i - approach) as f64 / stroke as f64;
            ([0.5 + 0.15 * u, wave * (5.0 * u).sin(), 0.1], [1.0, 0.5, -12.0])
        } else {
            let u = (i - approach - stroke) as f64 / retreat as f64;
            ([0.65, wave * 5f64.sin(), 0.1 + 0.2 * u], [0.0; 3])
        };
        let p: Vec<f64> = pos.iter().map(|v| v + 2e-4 * noise()).collect();
        let f: Vec<f64> = force.iter().map(|v| v + 0.6 * noise()).collect();
        text.push_str(&format!(
            "{:.3},{:.6},{:.6},{:.6},0,1,0,0,{:.4},{:.4},{:.4},0,0,0\n",
            i as f64 / 1000.0,
            p[0],
            p[1],
            p[2],
            f[0],
            f[1],
            f[2]
        ));
    }
    std::fs::write(path, text).expect("demonstration written");
}

/// One case: its name and the arguments of `skillc`.
struct Case {
    name: String,
    args: Vec<String>,
    /// Samples of the demonstration, for the growth exponent of `learn`.
    samples: Option<usize>,
    /// Ticks of the run, for the time per tick.
    ticks: Option<f64>,
}

/// The wall time of one run of `skillc args` in `dir` [s], and its peak memory [KB] when
/// `/usr/bin/time` is there to say.
fn time_once(dir: &Path, args: &[String]) -> (f64, Option<u64>) {
    let gnu_time = Path::new("/usr/bin/time").exists();
    let mut command = if gnu_time {
        let mut c = Command::new("/usr/bin/time");
        c.args(["-f", "%M"]).arg(env!("CARGO_BIN_EXE_skillc"));
        c
    } else {
        Command::new(env!("CARGO_BIN_EXE_skillc"))
    };
    command.args(args).current_dir(dir).stdout(Stdio::null());
    let started = Instant::now();
    let out = command.stderr(Stdio::piped()).output().expect("skillc runs");
    let seconds = started.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "`skillc {}` failed: {stderr}",
        args.join(" ")
    );
    let memory = gnu_time
        .then(|| stderr.lines().last().and_then(|l| l.trim().parse().ok()))
        .flatten();
    (seconds, memory)
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "quick");
    let rounds: usize = args
        .iter()
        .find_map(|a| a.parse().ok())
        .or_else(|| std::env::var("SKILLC_BENCH_ROUNDS").ok()?.parse().ok())
        .unwrap_or(3);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("skillc-bench-verbs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("bench folder");
    let slide = std::fs::read_to_string(root.join("stdlib-skills/slide.skill")).expect("slide");
    // scikit-learn's kneighbors_graph(t, 10) neighbourhood: ±5 samples.
    std::fs::write(
        dir.join("slide5.skill"),
        slide.replace("connectivity: 10", "connectivity: 5"),
    )
    .expect("template");
    let mut cases = Vec::new();
    for samples in [10_000, 50_000, 600_000] {
        let demo = format!("demo_{samples}.csv");
        write_demo(&dir.join(&demo), samples);
        cases.push(Case {
            name: format!("learn slide (Ward ±5), {samples} samples"),
            args: ["learn", "slide5.skill", &demo, "-o", "learned.json", "-q"]
                .map(String::from)
                .to_vec(),
            samples: Some(samples),
            ticks: None,
        });
    }
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
    let ticks = {
        let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
            .args([
                "run",
                "stdlib-skills/slide.skill",
                "--scene",
                "examples/scenes/table.toml",
                "-q",
                "--learned",
            ])
            .arg(&learned)
            .arg("-o")
            .arg(dir.join("ticks.csv"))
            .current_dir(&root)
            .status()
            .expect("skillc runs");
        assert!(out.success());
        let rows = std::fs::read_to_string(dir.join("ticks.csv"))
            .expect("log")
            .lines()
            .count();
        (rows - 1) as f64
    };
    let run = |output: Option<&str>| {
        let mut args: Vec<String> = [
            "run",
            &format!("{}/stdlib-skills/slide.skill", root.display()),
            "--scene",
            &format!("{}/examples/scenes/table.toml", root.display()),
            "--learned",
            &learned.display().to_string(),
            "-q",
        ]
        .map(String::from)
        .to_vec();
        if let Some(output) = output {
            args.extend(["-o".to_string(), output.to_string()]);
        }
        args
    };
    // The logs go to the bench folder (the run cases run from the repository root).
    let (csv_log, mcap_log) = (dir.join("log.csv"), dir.join("log.mcap"));
    for (name, output) in [
        ("run slide, no log", None),
        ("run slide, CSV log", Some(csv_log.display().to_string())),
        ("run slide, MCAP log", Some(mcap_log.display().to_string())),
    ] {
        cases.push(Case {
            name: name.to_string(),
            args: run(output.as_deref()),
            samples: None,
            ticks: Some(ticks),
        });
    }
    if !quick {
        let out = dir.join("report").display().to_string();
        cases.push(Case {
            name: "eval (default trials)".into(),
            args: ["eval", "-q", "--out", &out].map(String::from).to_vec(),
            samples: None,
            ticks: None,
        });
        let out = dir.join("sweep").display().to_string();
        cases.push(Case {
            name: "eval --sweep 200 (touch)".into(),
            args: [
                "eval",
                "-q",
                "--skill",
                "touch",
                "--sweep",
                "200",
                "--min-success",
                "0",
                "--out",
                &out,
            ]
            .map(String::from)
            .to_vec(),
            samples: None,
            ticks: None,
        });
    }
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
    let mut memory: Vec<Option<u64>> = vec![None; cases.len()];
    for _ in 0..rounds {
        for (index, case) in cases.iter().enumerate() {
            // The learn cases run in the bench folder, the rest from the repository root.
            let at = if case.samples.is_some() { &dir } else { &root };
            let (seconds, kb) = time_once(at, &case.args);
            times[index].push(seconds);
            memory[index] = memory[index].max(kb);
        }
    }
    println!("skillc as a process, {rounds} rounds, interleaved; median wall time (range), peak memory");
    let mut learn_points = Vec::new();
    for (index, case) in cases.iter().enumerate() {
        let (low, high) = times[index]
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), t| (lo.min(*t), hi.max(*t)));
        let mid = median(&mut times[index]);
        let per_tick = case
            .ticks
            .map(|n| format!(", {:.1} µs a tick over {n} ticks", mid / n * 1e6))
            .unwrap_or_default();
        let mem = memory[index]
            .map(|kb| format!(", {:.0} MB", kb as f64 / 1024.0))
            .unwrap_or_default();
        println!("  {:<44} {:>9.3} s ({low:.3}-{high:.3}){mem}{per_tick}", case.name, mid);
        if let Some(samples) = case.samples {
            learn_points.push((samples as f64, mid));
        }
    }
    for pair in learn_points.windows(2) {
        let [(n0, t0), (n1, t1)] = [pair[0], pair[1]];
        println!(
            "  learn grows as n^{:.2} from {n0} to {n1} samples",
            (t1 / t0).ln() / (n1 / n0).ln()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

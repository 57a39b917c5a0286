//! The press follows its force profile through the button's travel (issue 25, item 6): on the
//! shipped button, as demonstrated and 2 cm lower, the force along the contact normal tracks the
//! desired force with at most 5 % RMS of its peak after the first 200 ms (the eval's measure),
//! and the desired force never pulls. While the cap travels the force keeps up with the
//! profile: the rate feed-forward (`skill_exec::control::travel`) leaves a mean lag under 0.3 N
//! going down and 0.12 N coming back up (0.40-0.43 N and 0.17-0.21 N without it).

use std::process::Command;

/// One tick of the press state: time, measured and desired force along the compliant z \[N\],
/// and the tool point's depth along it \[m\].
struct PressTick {
    t: f64,
    measured: f64,
    desired: f64,
    depth: f64,
}

/// The press state's ticks of a logged run.
fn press_ticks(sets: &[&str], log: &std::path::Path) -> Vec<PressTick> {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut args = vec![
        "run",
        "stdlib-skills/press.skill",
        "--demo",
        "examples/demos/press.csv",
        "--scene",
        "examples/scenes/button.toml",
        "--no-prepose",
        "-q",
        "-o",
    ];
    let log_arg = log.to_str().expect("a UTF-8 temporary path");
    args.push(log_arg);
    for set in sets {
        args.extend(["--set", set]);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .current_dir(root)
        .args(&args)
        .output()
        .expect("skillc runs");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{sets:?}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(log).expect("the log was written");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("column {name}"))
    };
    let (t, state, measured, desired) = (column("t"), column("state"), column("cf_fz"), column("cf_fz_d"));
    let tool = [column("x"), column("y"), column("z")];
    let frame_z = [column("cf_zx"), column("cf_zy"), column("cf_zz")];
    lines
        .map(|line| line.split(',').collect::<Vec<_>>())
        .filter(|fields| fields[state] == "press")
        .map(|fields| {
            let number = |i: usize| fields[i].parse::<f64>().expect("a number");
            PressTick {
                t: number(t),
                measured: number(measured),
                desired: number(desired),
                depth: (0..3).map(|i| number(tool[i]) * number(frame_z[i])).sum(),
            }
        })
        .collect()
}

#[test]
fn the_press_tracks_its_profile_within_five_percent() {
    let dir = std::env::temp_dir().join(format!("skillc-press-tracking-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    for (name, sets) in [("as demonstrated", &[][..]), ("2 cm lower", &["objects.z-=0.02"][..])] {
        let ticks = press_ticks(sets, &dir.join("press.csv"));
        assert!(ticks.len() > 1000, "{name}: {} press ticks", ticks.len());
        let t0 = ticks[0].t;
        let judged: Vec<_> = ticks.iter().filter(|tick| tick.t - t0 >= 0.2).collect();
        let peak = judged.iter().map(|tick| tick.desired.abs()).fold(0.0, f64::max);
        let rms = (judged
            .iter()
            .map(|tick| (tick.desired - tick.measured).powi(2))
            .sum::<f64>()
            / judged.len() as f64)
            .sqrt();
        assert!(peak > 8.0, "{name}: the profile peaks at {peak:.2} N");
        assert!(
            rms / peak <= 0.05,
            "{name}: force RMS {:.2} % of the {peak:.2} N peak",
            100.0 * rms / peak
        );
        let lowest = ticks.iter().map(|tick| tick.desired).fold(f64::INFINITY, f64::min);
        assert!(lowest >= -1e-6, "{name}: the desired force pulled ({lowest:.3} N)");
    }
    std::fs::remove_dir_all(&dir).expect("the temporary folder is removed");
}

#[test]
fn the_force_keeps_up_with_the_profile_while_the_cap_travels() {
    let dir = std::env::temp_dir().join(format!("skillc-press-travel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    for (name, sets) in [("as demonstrated", &[][..]), ("2 cm lower", &["objects.z-=0.02"][..])] {
        let ticks = press_ticks(sets, &dir.join("press.csv"));
        let t0 = ticks[0].t;
        // The lag (desired − measured) on the ticks where the tool moves faster than 2 mm/s
        // along the compliant z, the cap travelling down (deeper) or up.
        let (mut down, mut up) = (Vec::new(), Vec::new());
        for pair in ticks.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            if b.t - t0 < 0.2 {
                continue;
            }
            let speed = (b.depth - a.depth) / (b.t - a.t);
            let lag = b.desired - b.measured;
            if speed > 2e-3 {
                down.push(lag);
            } else if speed < -2e-3 {
                up.push(lag);
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        // The cap's 8 mm at about 12 mm/s each way: some 700 ms of ticks.
        assert!(
            down.len() > 500 && up.len() > 500,
            "{name}: {} ticks down, {} up",
            down.len(),
            up.len()
        );
        let (lag_down, lag_up) = (mean(&down), mean(&up));
        eprintln!("{name}: mean lag {lag_down:+.3} N going down, {lag_up:+.3} N coming up");
        assert!(
            lag_down.abs() < 0.3,
            "{name}: the force lags {lag_down:.3} N going down"
        );
        assert!(lag_up.abs() < 0.12, "{name}: the force lags {lag_up:.3} N coming up");
    }
    std::fs::remove_dir_all(&dir).expect("the temporary folder is removed");
}

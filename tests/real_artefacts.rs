//! Learning from a recording with what real ones carry (docs/method.md §1, "In-air load"): the
//! shipped slide demonstration recorded three times over, end to end, with a load on the sensor
//! in the air that drifts from 1 N to 4.5 N (a hand's grip), a 10 Hz tremor of 0.3 N, and a
//! stretch where the sensor froze in the air. Each contact must be found as its own phase within
//! 0.3 s of the truth, and the slide learned from each must press within 15 % of the 10 N it was
//! demonstrated with. Without the in-air load removed the air between the passes reads as
//! contact and the passes run together.

use std::path::Path;
use std::process::Command;

/// The shipped slide's rows as numbers, and its truth: the slide's start and end \[s\], its force \[N\].
fn slide() -> (Vec<Vec<f64>>, (f64, f64), f64) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("examples/demos/slide.csv")).expect("slide.csv");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|line| line.split(',').map(|x| x.parse().expect("number")).collect())
        .collect();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("examples/demos/slide.truth.json")).expect("truth"))
            .expect("json");
    let slide = &truth["segments"][1];
    let span = (
        slide["start_s"].as_f64().expect("start"),
        slide["end_s"].as_f64().expect("end"),
    );
    (rows, span, truth["force_n"].as_f64().expect("force"))
}

#[test]
fn three_passes_with_a_drifting_hand_load_are_three_phases_at_the_demonstrated_force() {
    let (rows, (on, off), force_n) = slide();
    let period = rows[rows.len() - 1][0] + 0.001;
    let total = 3.0 * period;
    let mut csv = String::from("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
    let mut frozen: Option<[f64; 3]> = None;
    for pass in 0..3 {
        for row in &rows {
            let t = row[0] + f64::from(pass) * period;
            // The hand's load: 1 N at the start, 4.5 N at the end, in the sensor's axes.
            let load = 1.0 + 3.5 * t / total;
            let tremor = 0.3 * (2.0 * std::f64::consts::PI * 10.0 * t).sin();
            let mut f = [
                row[8] + 0.3 * load + tremor,
                row[9] - 0.4 * load,
                row[10] + 0.866 * load,
            ];
            // The sensor froze for 0.4 s in the air after the first pass.
            let in_freeze = t > period - 0.9 && t < period - 0.5;
            if in_freeze {
                f = *frozen.get_or_insert(f);
            }
            let fields: Vec<String> = [t, row[1], row[2], row[3], row[4], row[5], row[6], row[7]]
                .iter()
                .chain(f.iter())
                .chain(row[11..14].iter())
                .map(|x| format!("{x:.6}"))
                .collect();
            csv.push_str(&fields.join(","));
            csv.push('\n');
        }
    }
    let dir = std::env::temp_dir().join(format!("skillc-real-artefacts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("three_passes.csv");
    std::fs::write(&file, csv).expect("write");
    let skillc = env!("CARGO_BIN_EXE_skillc");

    let out = Command::new(skillc)
        .args(["identify", &file.display().to_string(), "--format", "json"])
        .output()
        .expect("identify");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let phases: Vec<(f64, f64)> = report["phases"]
        .as_array()
        .expect("phases")
        .iter()
        .map(|p| (p["start_s"].as_f64().expect("start"), p["end_s"].as_f64().expect("end")))
        .collect();
    assert_eq!(phases.len(), 3, "{phases:?}");
    for (pass, &(start, end)) in phases.iter().enumerate() {
        let shift = pass as f64 * period;
        assert!(
            (start - (on + shift)).abs() <= 0.3,
            "pass {pass}: starts {start:.2} for {:.2}",
            on + shift
        );
        assert!(
            (end - (off + shift)).abs() <= 0.3,
            "pass {pass}: ends {end:.2} for {:.2}",
            off + shift
        );
    }

    let template = Path::new(env!("CARGO_MANIFEST_DIR")).join("stdlib-skills/slide.skill");
    for phase in 1..=3 {
        let learned = dir.join(format!("pass{phase}.json"));
        let out = Command::new(skillc)
            .args([
                "learn",
                &template.display().to_string(),
                &file.display().to_string(),
                "--phase",
                &phase.to_string(),
                "-o",
                &learned.display().to_string(),
            ])
            .output()
            .expect("learn");
        let said = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "phase {phase}: {said}");
        assert!(
            said.contains("while the tool is in the air"),
            "the load is named: {said}"
        );
        let file: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&learned).expect("learned")).expect("json");
        let constant = file["forces"]
            .as_object()
            .expect("forces")
            .values()
            .find_map(|f| f["value_n"].as_f64())
            .expect("a constant force");
        assert!(
            (constant - force_n).abs() <= 0.15 * force_n,
            "phase {phase}: learned {constant:.2} N for {force_n} N"
        );
    }
}

/// A force profile whose fit misses the demonstration by more than 15 % of its level says so
/// with the figures (the shipped press: its onset rises faster than the profile's fit follows);
/// one that fits (the shipped contour) says nothing.
#[test]
fn a_force_profile_fitted_far_from_its_level_is_a_warning_with_the_figures() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("skillc-fit-warning-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    for (skill, warned) in [("press", true), ("contour", false)] {
        let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
            .args([
                "learn",
                &root.join(format!("stdlib-skills/{skill}.skill")).display().to_string(),
                &root.join(format!("examples/demos/{skill}.csv")).display().to_string(),
                "-o",
                &dir.join(format!("{skill}.json")).display().to_string(),
            ])
            .output()
            .expect("learn");
        assert!(out.status.success(), "{skill}");
        let said = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        let line = said.lines().find(|line| line.contains("force profile"));
        assert_eq!(line.is_some(), warned, "{skill}: {said}");
        if let Some(line) = line {
            assert!(
                line.contains("N RMS error") && line.contains("% of its level"),
                "{line}"
            );
        }
    }
}

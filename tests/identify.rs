//! `skillc identify` (issue 26, item 4): every shipped demonstration is identified as its own
//! skill (through the CLI, text and JSON), and at least 95 of 100 generated variants (other
//! rates, position noise, durations, tilts, wipes of several passes, wipes over a curved part)
//! are; the confusion table is printed.

use std::path::PathBuf;
use std::process::Command;

use skill_runtime::demo::{Demo, WrenchOptions};
use skill_runtime::demogen::{generate_varied, StdSkill, Variation};
use skillc::identify_cmd::{identify, TEMPLATES};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn every_shipped_demonstration_is_its_own_skill() {
    for skill in StdSkill::ALL {
        let demo = root().join(format!("examples/demos/{}.csv", skill.name()));
        let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
            .arg("identify")
            .arg(&demo)
            .args(["--format", "json"])
            .output()
            .expect("skillc runs");
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
        let json: serde_json::Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
        let ranking = json["ranking"].as_array().expect("a ranking");
        assert_eq!(ranking[0]["skill"], skill.name(), "{}: {json}", skill.name());
        assert!(ranking[0]["evidence"].as_array().is_some_and(|e| !e.is_empty()));
        assert!(json["phases"].as_array().is_some_and(|p| !p.is_empty()));
        let text = Command::new(env!("CARGO_BIN_EXE_skillc"))
            .arg("identify")
            .arg(&demo)
            .output()
            .expect("skillc runs");
        let text = String::from_utf8_lossy(&text.stdout);
        assert!(
            text.contains(&format!("skillc learn stdlib-skills/{}.skill", skill.name())),
            "{text}"
        );
    }
}

#[test]
fn a_demonstration_without_contact_is_refused() {
    let dir = std::env::temp_dir().join(format!("skillc-identify-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let shipped = std::fs::read_to_string(root().join("examples/demos/touch.csv")).expect("shipped demo");
    // The first second of the touch: the free approach only.
    let free: Vec<&str> = shipped.lines().take(1001).collect();
    let path = dir.join("free.csv");
    std::fs::write(&path, free.join("\n") + "\n").expect("write");
    let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("identify")
        .arg(&path)
        .output()
        .expect("skillc runs");
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("free.csv") && stderr.contains("no contact phase"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_missing_file_is_refused_naming_it() {
    let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(["identify", "no/such/demo.csv"])
        .output()
        .expect("skillc runs");
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("no/such/demo.csv"));
}

fn demo_of(samples: &[skill_runtime::demogen::Sample], name: String) -> Demo {
    Demo {
        source: name,
        t_s: samples.iter().map(|s| s.t_s).collect(),
        position_m: samples.iter().map(|s| s.position_m).collect(),
        orientation: samples.iter().map(|s| s.orientation).collect(),
        force_n: samples.iter().map(|s| s.force_n).collect(),
        torque_nm: samples.iter().map(|s| s.torque_nm).collect(),
    }
}

#[test]
fn generated_variants_are_identified_95_times_in_100() {
    let rates = [1000.0, 500.0, 250.0, 100.0];
    let noises = [0.0, 0.0001, 0.0002];
    let scales = [0.8, 1.0, 1.25];
    let tilts = [0.0, 0.1, -0.15, 0.2];
    let mut confusion = vec![vec![0usize; TEMPLATES.len()]; StdSkill::ALL.len()];
    let mut misses = Vec::new();
    let mut curved = 0;
    for index in 0..100usize {
        let skill = StdSkill::ALL[index % StdSkill::ALL.len()];
        let variation = Variation {
            passes: if skill == StdSkill::Wipe {
                1 + (index / 9) % 3
            } else {
                1
            },
            position_noise_m: noises[index % noises.len()],
            rate_hz: rates[(index / 3) % rates.len()],
            time_scale: scales[(index / 5) % scales.len()],
            tilt_rad: tilts[(index / 7) % tilts.len()],
            // One wipe in three is a single pass over a curved part (a fender), ±20-60°.
            curve_deg: if skill == StdSkill::Wipe && (index / 9) % 3 == 0 {
                [20.0, 35.0, 45.0, 60.0][(index / 27) % 4]
            } else {
                0.0
            },
        };
        curved += usize::from(variation.curve_deg > 0.0);
        let generated = generate_varied(skill, 1000 + index as u64, &variation);
        let name = format!("{}#{index}", skill.name());
        let demo = demo_of(&generated.samples, name.clone());
        let id = identify(&demo, &WrenchOptions::default(), &name).expect("identifies");
        let best = &id.ranking[0].skill;
        let row = StdSkill::ALL.iter().position(|s| *s == skill).expect("a skill");
        let column = TEMPLATES.iter().position(|t| t == best).expect("a template");
        confusion[row][column] += 1;
        if best != skill.name() {
            misses.push(format!("{name} {variation:?} -> {best}: {:?}", id.measures));
        }
    }
    let mut table = format!("{:<17}", "shown \\ found");
    for template in TEMPLATES {
        table.push_str(&format!(" {:>6}", &template[..template.len().min(6)]));
    }
    for (row, skill) in StdSkill::ALL.iter().enumerate() {
        table.push_str(&format!("\n{:<17}", skill.name()));
        for count in &confusion[row] {
            table.push_str(&format!(" {count:>6}"));
        }
    }
    let right: usize = StdSkill::ALL
        .iter()
        .enumerate()
        .map(|(row, skill)| confusion[row][TEMPLATES.iter().position(|t| *t == skill.name()).expect("known")])
        .sum();
    eprintln!("{table}\n{right} of 100 right\n{}", misses.join("\n"));
    assert_eq!(curved, 4, "four of the wipes are fender wipes over ±20, 35, 45 and 60°");
    assert!(right >= 95, "{right} of 100 right:\n{table}\n{}", misses.join("\n"));
}

//! `skillc identify --template FILE` (issue 47, item 5): a template's checks come from its
//! structure, derived from its IR, so every shipped template derives the profile `identify`
//! writes out for it, and a user's template that is structurally a slide is judged as the slide
//! is; and a demonstration no template fits is answered "none fits" with the reasons.

use std::path::PathBuf;
use std::process::Command;

use skillc::identify_cmd::{Profile, TEMPLATES};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn every_shipped_template_derives_its_written_profile() {
    for name in TEMPLATES {
        let path = root().join(format!("stdlib-skills/{name}.skill"));
        let (_, skill) = skill_kit::load::load_skill(&path, None).unwrap_or_else(|_| panic!("{name} compiles"));
        let derived = Profile::from_skill(&skill);
        assert_eq!(Some(derived), Profile::standard(name), "{name}");
    }
}

#[test]
fn a_users_slide_is_ranked_beside_the_standard_slide() {
    let dir = std::env::temp_dir().join(format!("skillc-identify-template-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let slide = std::fs::read_to_string(root().join("stdlib-skills/slide.skill")).expect("slide");
    let mine = dir.join("my_glide.skill");
    std::fs::write(&mine, slide.replace("skill slide {", "skill my_glide {")).expect("write");
    let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("identify")
        .arg(root().join("examples/demos/slide.csv"))
        .arg("--template")
        .arg(&mine)
        .args(["--format", "json"])
        .output()
        .expect("skillc runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
    let ranking = json["ranking"].as_array().expect("a ranking");
    assert_eq!(ranking.len(), TEMPLATES.len() + 1);
    let find = |name: &str| ranking.iter().find(|f| f["skill"] == name).expect("ranked").clone();
    let (standard, user) = (find("slide"), find("my_glide"));
    assert_eq!(standard["score"], user["score"], "{json}");
    assert_eq!(standard["profile"], user["profile"]);
    assert_eq!(user["fits"], true);
    assert!(user["file"].as_str().is_some_and(|f| f.ends_with("my_glide.skill")));
    // The standard template ranks first among equals.
    assert_eq!(ranking[0]["skill"], "slide");
    assert!(ranking[0]["evidence"]
        .as_array()
        .is_some_and(|e| e.iter().any(|c| c["defining"] == true)));
    // A user's press judged on the same demonstration does not fit: the tool travels.
    let press = std::fs::read_to_string(root().join("stdlib-skills/press.skill")).expect("press");
    let mine_press = dir.join("my_push.skill");
    std::fs::write(&mine_press, press.replace("skill press {", "skill my_push {")).expect("write");
    let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("identify")
        .arg(root().join("examples/demos/slide.csv"))
        .arg("--template")
        .arg(&mine)
        .arg("--template")
        .arg(&mine_press)
        .output()
        .expect("skillc runs");
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.lines()
            .any(|l| l.contains("my_push") && l.contains("does not fit: travel in contact")),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_template_that_does_not_compile_is_refused_naming_it() {
    let dir = std::env::temp_dir().join(format!("skillc-identify-broken-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let broken = dir.join("broken.skill");
    std::fs::write(&broken, "skill broken {").expect("write");
    let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("identify")
        .arg(root().join("examples/demos/slide.csv"))
        .arg("--template")
        .arg(&broken)
        .output()
        .expect("skillc runs");
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("broken.skill"));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn none_fits_when_no_template_does() {
    // A contact that travels 1-2 cm: too far for a press, too short for a slide.
    let shipped = std::fs::read_to_string(root().join("examples/demos/press.csv")).expect("shipped demo");
    let mut lines = shipped.lines();
    let header = lines.next().expect("a header");
    let columns: Vec<&str> = header.split(',').collect();
    let (t, x) = (
        columns.iter().position(|c| *c == "t").unwrap_or(0),
        columns
            .iter()
            .position(|c| *c == "px" || *c == "x")
            .expect("an x column"),
    );
    let mut out = vec![header.to_string()];
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
        let time: f64 = cells[t].parse().expect("a time");
        // Creep 2 cm along x between 2.3 and 5.2 s (the press), evenly.
        let u = ((time - 2.3) / 2.9).clamp(0.0, 1.0);
        let value: f64 = cells[x].parse().expect("a number");
        cells[x] = format!("{}", value + 0.02 * u);
        out.push(cells.join(","));
    }
    let dir = std::env::temp_dir().join(format!("skillc-identify-none-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("creep.csv");
    std::fs::write(&path, out.join("\n") + "\n").expect("write");
    let output = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .arg("identify")
        .arg(&path)
        .args(["--format", "json"])
        .output()
        .expect("skillc runs");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
    let none = json["none_fits"]
        .as_str()
        .unwrap_or_else(|| panic!("none fits: {json:#}"));
    assert!(none.contains("press: travel in contact"), "{none}");
    assert_eq!(json["command"], "");
    assert!(json["ranking"]
        .as_array()
        .is_some_and(|r| r.iter().all(|f| f["fits"] == false)));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

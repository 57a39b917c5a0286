//! A slide that runs off its surface fails as lost contact (issue 25, item 3): the standard
//! slide on a table cut short, whose end the probe's path crosses 4 cm before the stroke ends,
//! fails with `lost_contact`, the time, the state and its `.skill` line and where the tool was;
//! the same table ending within the last few millimetres of the stroke, and the shipped table,
//! are slides that succeed.

use std::process::{Command, Output};

/// `skillc run` of the standard slide on table.toml with `sets`.
fn slide(sets: &[&str]) -> Output {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut args = vec![
        "run",
        "stdlib-skills/slide.skill",
        "--demo",
        "examples/demos/slide.csv",
        "--scene",
        "examples/scenes/table.toml",
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    Command::new(env!("CARGO_BIN_EXE_skillc"))
        .current_dir(root)
        .args(&args)
        .output()
        .expect("skillc runs")
}

/// The number after `label` in `text` (`(0.584, 0.045, 0.309) m` gives its first).
fn number_after(text: &str, label: &str) -> f64 {
    let at = text.find(label).unwrap_or_else(|| panic!("`{label}` in {text}")) + label.len();
    let digits: String = text[at..]
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-')
        .collect();
    digits
        .parse()
        .unwrap_or_else(|_| panic!("a number after `{label}` in {text}"))
}

#[test]
fn a_slide_off_the_table_fails_as_lost_contact() {
    // The table's far end at x = 0.43 + 0.15 = 0.580 m; the slide runs to x ≈ 0.62 m.
    let out = slide(&["table.size=[0.3,0.8,0.05]", "table.x=0.43"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    let line = text
        .lines()
        .find(|line| line.starts_with("FAILURE: lost_contact"))
        .unwrap_or_else(|| panic!("a lost_contact failure in {text}"));
    assert!(line.contains("in state `slide` (stdlib-skills/slide.skill:"), "{line}");
    // Lost where the probe's tip (5 mm radius) leaves the edge, not 1-2 cm beyond it.
    let x = number_after(line, "the tool at (");
    assert!((0.578..0.592).contains(&x), "lost at x = {x} m: {line}");
    let left_mm = number_after(line, " m with ");
    assert!(left_mm > 20.0, "{left_mm} mm of the stroke left: {line}");
    let t = number_after(line, "lost at t = ");
    assert!(t > 5.0 && t < 12.0, "{line}");
    // The run stops within the watch's time of the loss: no leave, no `done`.
    assert!(!text.contains("reached `done`"), "{text}");
}

#[test]
fn a_slide_whose_table_ends_with_its_stroke_and_the_standard_slide_succeed() {
    // The table's end at x = 0.617 m, within the stroke's last few millimetres.
    for sets in [&["table.size=[0.3,0.8,0.05]", "table.x=0.467"][..], &[][..]] {
        let out = slide(sets);
        let text = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(0), "{sets:?}: {text}");
        assert!(text.contains("success: reached `done`"), "{sets:?}: {text}");
        assert!(!text.contains("lost_contact"), "{sets:?}: {text}");
    }
}

//! `.skill` text as editors and unkind users write it, through the `skillc` binary: a byte order
//! mark is accepted, invisible and lookalike characters are named with their code point, deep
//! nesting is a located error (never a stack overflow) for every verb that parses, a missing
//! name says so, and a silent order-dependent mistake is reported with its exit code.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-text-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    dir
}

fn skillc(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs")
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

const SKILL: &str = "skill s {\n    learn {\n        motion path = dmp(segment 1)\n    }\n\n    state go {\n        move path from current\n        on motion_done -> done\n    }\n\n    terminal done: success\n}\n";

#[test]
fn a_byte_order_mark_is_accepted_and_strange_characters_are_named() {
    let dir = dir("chars");
    std::fs::write(dir.join("bom.skill"), format!("\u{feff}{SKILL}")).expect("write");
    let out = skillc(&dir, &["check", "bom.skill"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    // Formatting leaves a formatted file alone and keeps the mark when it reformats.
    let out = skillc(&dir, &["fmt", "--check", "bom.skill"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    std::fs::write(
        dir.join("bom.skill"),
        format!("\u{feff}{}", SKILL.replace("    state go", "  state   go")),
    )
    .expect("write");
    let out = skillc(&dir, &["fmt", "bom.skill"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert_eq!(
        std::fs::read_to_string(dir.join("bom.skill")).expect("read"),
        format!("\u{feff}{SKILL}")
    );
    for (character, named) in [
        ('\u{a0}', "U+00A0 NO-BREAK SPACE"),
        ('\u{200b}', "U+200B ZERO WIDTH SPACE"),
        ('\u{430}', "U+0430 CYRILLIC SMALL LETTER A"),
        ('\u{ff11}', "U+FF11 FULLWIDTH DIGIT ONE"),
        ('\0', "U+0000 NUL"),
    ] {
        let file = SKILL.replacen("state go", &format!("state g{character}o"), 1);
        std::fs::write(dir.join("odd.skill"), file).expect("write");
        let out = skillc(&dir, &["check", "odd.skill"]);
        assert_eq!(out.status.code(), Some(1), "{named}: {}", text(&out));
        assert!(text(&out).contains(named), "{named}: {}", text(&out));
        // Located at the character: line 6.
        assert!(text(&out).contains("odd.skill:6:"), "{named}: {}", text(&out));
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn deep_nesting_is_a_located_error_for_every_verb_that_parses() {
    let dir = dir("deep");
    let nots = "not ".repeat(5000);
    let file = SKILL.replacen("on motion_done", &format!("on {nots}motion_done"), 1);
    std::fs::write(dir.join("deep.skill"), &file).expect("write");
    for verb in [
        &["check", "deep.skill"][..],
        &["fmt", "--check", "deep.skill"],
        &["compile", "deep.skill"],
        &["dump", "--stage", "ast", "deep.skill"],
    ] {
        let started = Instant::now();
        let out = skillc(&dir, verb);
        assert_eq!(out.status.code(), Some(1), "{verb:?}: {}", text(&out));
        assert!(text(&out).contains("nested more than"), "{verb:?}: {}", text(&out));
        // A hang guard, not a speed test: the refusal takes milliseconds.
        assert!(started.elapsed() < Duration::from_secs(120), "{verb:?}");
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn missing_names_and_order_dependent_mistakes_are_reported() {
    let dir = dir("order");
    let capture = SKILL.replacen("        on motion_done", "        capture\n        on motion_done", 1);
    std::fs::write(dir.join("capture.skill"), capture).expect("write");
    let out = skillc(&dir, &["check", "capture.skill"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    assert!(text(&out).contains("`capture` needs a name"), "{}", text(&out));
    // A zero timeout in a state that moves: a warning, an error under --deny-warnings.
    let zero = SKILL.replacen(
        "        on motion_done -> done\n",
        "        on motion_done -> done\n        on timeout 0 s -> done\n",
        1,
    );
    std::fs::write(dir.join("zero.skill"), zero).expect("write");
    let out = skillc(&dir, &["check", "zero.skill"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(text(&out).contains("ends as soon as it is entered"), "{}", text(&out));
    let out = skillc(&dir, &["check", "--deny-warnings", "zero.skill"]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

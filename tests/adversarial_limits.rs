//! The cases of issue 50 outside the language server, each input generated here: a header of
//! 200 000 columns, bidirectional controls in a comment, imports and files that are devices or
//! FIFOs, `--phase` and `--domain` values out of range, and `learn --plot` that cannot write a
//! plot. Each must end at once with the documented exit code (1 for a problem in an input, 2 for
//! usage and IO), a message naming the file or flag, and nothing new left behind.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Far more than any of these needs (each answers in well under a second in a release build):
/// a bound that catches hangs, not slowness, on a loaded 2-core machine in a debug build.
const LIMIT: Duration = Duration::from_secs(60);

/// Runs `skillc args` in `dir` with no standard input; the exit code, standard output and error.
fn skillc(dir: &Path, args: &[&str]) -> (i32, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("skillc starts");
    let started = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if started.elapsed() > LIMIT {
            let _ = child.kill();
            panic!("skillc {args:?} did not end within {LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("output");
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

fn workspace(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-limits-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("workspace");
    dir
}

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path).display().to_string()
}

#[test]
fn a_header_of_two_hundred_thousand_columns_is_refused_at_once_naming_the_file_and_the_limit() {
    let dir = workspace("wide");
    let mut text = String::from("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz");
    for column in 0..200_000 {
        text.push_str(&format!(",extra{column}"));
    }
    text.push('\n');
    for row in 0..5 {
        text.push_str(&format!("{}", f64::from(row) * 0.01));
        text.push_str(",0,0,0,1,0,0,0,0,0,0,0,0,0");
        text.push_str(&",0".repeat(200_000));
        text.push('\n');
    }
    std::fs::write(dir.join("wide.csv"), &text).expect("write");
    assert!(text.lines().next().expect("header").len() > 2_000_000);
    for args in [
        vec!["identify", "wide.csv"],
        vec![
            "learn",
            &repo("stdlib-skills/slide.skill"),
            "wide.csv",
            "-o",
            "learned.json",
        ],
    ] {
        let started = Instant::now();
        let (code, out) = skillc(&dir, &args);
        assert_eq!(code, 1, "{args:?}: {out}");
        assert!(
            out.contains("wide.csv") && out.contains("200014 columns") && out.contains("1024"),
            "{out}"
        );
        assert!(started.elapsed() < LIMIT, "{:?}", started.elapsed());
    }
    assert!(!dir.join("learned.json").exists());
}

#[test]
fn bidirectional_controls_in_comments_and_strings_are_errors() {
    let dir = workspace("bidi");
    let touch = std::fs::read_to_string(repo("stdlib-skills/touch.skill")).expect("touch");
    for (name, control) in [("rlo", '\u{202E}'), ("lri", '\u{2066}'), ("pdf", '\u{202C}')] {
        let file = format!("{name}.skill");
        std::fs::write(dir.join(&file), format!("// reads {control} differently\n{touch}")).expect("write");
        let (code, out) = skillc(&dir, &["check", &file]);
        assert_eq!(code, 1, "{out}");
        assert!(out.contains(&format!("U+{:04X}", u32::from(control))), "{out}");
        assert!(out.contains("changes the order in which the text is shown"), "{out}");
    }
    // The same file without the control checks clean: the control is what is refused.
    std::fs::write(dir.join("clean.skill"), format!("// reads the same\n{touch}")).expect("write");
    assert_eq!(skillc(&dir, &["check", "clean.skill"]).0, 0);
}

#[test]
fn imports_and_files_that_are_devices_or_fifos_are_refused_without_reading_them() {
    let dir = workspace("devices");
    let touch = std::fs::read_to_string(repo("stdlib-skills/touch.skill")).expect("touch");
    for device in ["/dev/zero", "/dev/stdin"] {
        std::fs::write(dir.join("imports.skill"), format!("import \"{device}\"\n{touch}")).expect("write");
        let (code, out) = skillc(&dir, &["check", "imports.skill"]);
        assert_eq!(code, 1, "{device}: {out}");
        assert!(out.contains(&format!("cannot import `{device}`")), "{out}");
        assert!(out.contains("not a regular file"), "{out}");
    }
    let (code, out) = skillc(&dir, &["check", "/dev/zero"]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("/dev/zero") && out.contains("a device"), "{out}");
    if Command::new("mkfifo")
        .arg(dir.join("pipe"))
        .status()
        .is_ok_and(|status| status.success())
    {
        std::fs::write(dir.join("fifo.skill"), format!("import \"pipe\"\n{touch}")).expect("write");
        let (code, out) = skillc(&dir, &["check", "fifo.skill"]);
        assert_eq!(code, 1, "{out}");
        assert!(out.contains("cannot import `pipe`: a FIFO"), "{out}");
        let (code, out) = skillc(&dir, &["check", "pipe"]);
        assert_eq!(code, 2, "{out}");
        assert!(out.contains("a FIFO"), "{out}");
    } else {
        eprintln!("mkfifo is missing: the FIFO cases are skipped");
    }
    // An import of more than 8 MiB is refused by its size.
    let big = format!("// {}\n", "x".repeat(9 << 20));
    std::fs::write(dir.join("big.skill"), big).expect("write");
    std::fs::write(dir.join("imports.skill"), format!("import \"big.skill\"\n{touch}")).expect("write");
    let (code, out) = skillc(&dir, &["check", "imports.skill"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("larger than 8 MiB"), "{out}");
}

#[test]
fn phase_and_domain_out_of_range_name_the_flag_and_exit_2() {
    let dir = workspace("flags");
    let (skill, demo) = (repo("stdlib-skills/slide.skill"), repo("examples/demos/slide.csv"));
    for (value, why) in [("0", "count from 1"), ("-1", "count from 1"), ("x", "whole number")] {
        let (code, out) = skillc(&dir, &["learn", &skill, &demo, "--phase", value, "-o", "l.json"]);
        assert_eq!(code, 2, "--phase {value}: {out}");
        assert!(
            out.contains(&format!("'{value}' for '--phase")) && out.contains(why),
            "{out}"
        );
    }
    let scene = repo("examples/scenes/table.toml");
    let (code, out) = skillc(
        &dir,
        &[
            "plant",
            "--scene",
            &scene,
            "--listen",
            "tcp/127.0.0.1:1",
            "--domain",
            "-1",
        ],
    );
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("'-1' for '--domain"), "{out}");
    assert!(!dir.join("l.json").exists());
}

#[test]
fn learn_with_plots_that_cannot_be_written_leaves_nothing_new() {
    let dir = workspace("plots");
    let (skill, demo) = (repo("stdlib-skills/slide.skill"), repo("examples/demos/slide.csv"));
    // The second plot's name is taken by a folder: the first plot can be written, the second not.
    std::fs::create_dir_all(dir.join("plots/slide_learned_force.svg")).expect("blocker");
    let (code, out) = skillc(&dir, &["learn", &skill, &demo, "-o", "learned.json", "--plot", "plots"]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("slide_learned_force.svg"), "{out}");
    assert!(!dir.join("learned.json").exists(), "the learned file was left behind");
    assert!(
        !dir.join("plots/slide_trajectory.svg").exists(),
        "a plot was left behind"
    );
    let left: Vec<_> = std::fs::read_dir(dir.join("plots")).expect("plots").collect();
    assert_eq!(left.len(), 1, "only the blocker remains: {left:?}");
    // Without the blocker the same command writes all three.
    std::fs::remove_dir_all(dir.join("plots")).expect("unblock");
    let (code, out) = skillc(&dir, &["learn", &skill, &demo, "-o", "learned.json", "--plot", "plots"]);
    assert_eq!(code, 0, "{out}");
    for file in [
        "learned.json",
        "plots/slide_trajectory.svg",
        "plots/slide_learned_force.svg",
    ] {
        assert!(dir.join(file).is_file(), "{file}: {out}");
    }
    let svg = std::fs::read_to_string(dir.join("plots/slide_trajectory.svg")).expect("svg");
    assert!(svg.trim_end().ends_with("</svg>"), "a whole SVG");
}

#[test]
fn trials_files_that_are_no_text_or_run_nothing_are_input_errors() {
    let dir = workspace("trials");
    std::fs::write(dir.join("bag.toml"), b"\x89MCAP0\r\n\x01\x02").expect("write");
    std::fs::write(dir.join("latin1.toml"), b"[[skill]]\nfile = \"caf\xe9.skill\"\n").expect("write");
    for (file, why) in [("bag.toml", "is an MCAP file"), ("latin1.toml", "is not UTF-8")] {
        let (code, out) = skillc(&dir, &["eval", "--trials", file, "--out", "report"]);
        assert_eq!(code, 1, "{file}: {out}");
        assert!(out.contains(file) && out.contains(why), "{out}");
    }
    let skill = repo("stdlib-skills/touch.skill");
    let demo = repo("examples/demos/touch.csv");
    let scene = repo("examples/scenes/table.toml");
    let empty = format!("[[skill]]\nfile = \"{skill}\"\ndemo = \"{demo}\"\nscene = \"{scene}\"\nvariants = []\n");
    std::fs::write(dir.join("empty.toml"), empty).expect("write");
    let (code, out) = skillc(&dir, &["eval", "--trials", "empty.toml", "--out", "report"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("empty.toml") && out.contains("has no variants"), "{out}");
    assert!(!dir.join("report").exists());
}

#[test]
fn a_share_of_a_sweep_with_no_draws_says_so() {
    let dir = workspace("share");
    let (code, out) = skillc(
        &dir,
        &[
            "eval",
            "--skill",
            "touch",
            "--sweep",
            "2",
            "--partition",
            "3/3",
            "--out",
            "share3",
        ],
    );
    assert_eq!(code, 0, "{out}");
    assert!(
        out.contains("warning: share 3/3 holds none of the sweep's 2 draws"),
        "{out}"
    );
}

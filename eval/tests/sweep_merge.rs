//! A sweep run as M shares (`--partition K/M`) and joined by `skillc eval merge` writes the
//! `summary.json` one process writes, byte for byte but for the keys that name its shares and
//! time it; its trials in the trials file's order, not sorted by skill.
//!
//! In-process, through `skill_eval::run` as `skillc eval` calls it; a test binary of its own,
//! since the inputs a process has read are part of a sweep's identity.

use std::path::{Path, PathBuf};

use clap::Parser;
use skill_kit::out::Verbosity;

/// `skillc eval ...` as the real command line parses it.
#[derive(Parser)]
#[command(name = "skillc")]
enum Cli {
    Eval(skill_eval::EvalArgs),
}

fn eval(args: &[&str]) {
    let Cli::Eval(args) = Cli::try_parse_from(std::iter::once("skillc").chain(["eval"]).chain(args.iter().copied()))
        .unwrap_or_else(|err| panic!("{err}"));
    assert_eq!(skill_eval::run(&args, Verbosity::Quiet), 0, "skillc eval {args:?}");
}

/// The keys stripped before comparing: the wall time, which differs from run to run, and what
/// names the shares (`partitions`: `1/1` against `1/3 2/3 3/3`; `identity.shares`: 1 against 3).
const DIFFER_BY_DESIGN: [&str; 3] = ["\"elapsed_s\": ", "\"partitions\": [", "\"shares\": "];

/// `summary.json`'s text without the lines of [`DIFFER_BY_DESIGN`] (`to_string_pretty` puts a
/// key and its number on one line and each entry of `partitions` on a line of its own).
fn stripped(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
    let mut out = String::new();
    let mut in_partitions = false;
    for line in text.lines() {
        let key = line.trim_start();
        if in_partitions {
            in_partitions = !key.starts_with(']');
            continue;
        }
        if key.starts_with(DIFFER_BY_DESIGN[1]) {
            in_partitions = !key.ends_with("],") && !key.ends_with(']');
            continue;
        }
        if DIFFER_BY_DESIGN.iter().any(|prefix| key.starts_with(prefix)) {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

#[test]
fn three_shares_merged_write_the_summary_one_process_writes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let trials = root.join("examples/eval/default.toml");
    let dir = std::env::temp_dir().join(format!("skill-eval-sweep-merge-{}", std::process::id()));
    let out = |name: &str| -> PathBuf { dir.join(name) };
    let path = |p: &Path| p.to_str().expect("utf-8").to_string();
    // Two skills whose file order (touch before press) is not their alphabetical order, two
    // draws each: four draws over three shares (2, 1 and 1 draws, both skills split).
    let sweep = |name: &str, partition: Option<&str>| {
        let (trials, out) = (path(&trials), path(&out(name)));
        let mut args = vec![
            "--trials",
            &trials,
            "--skill",
            "press",
            "--skill",
            "touch",
            "--sweep",
            "2",
            "--seed",
            "5",
            "--min-success",
            "0",
            "--no-replay",
            "--threads",
            "2",
            "--out",
            &out,
        ];
        if let Some(partition) = partition {
            args.extend(["--partition", partition]);
        }
        eval(&args);
    };
    sweep("whole", None);
    for k in 1..=3 {
        sweep(&format!("share{k}"), Some(&format!("{k}/3")));
    }
    // The shares given out of order, as a Slurm array's outputs may be listed.
    let shares: Vec<String> = [3, 1, 2].iter().map(|k| path(&out(&format!("share{k}")))).collect();
    let merged = path(&out("merged"));
    let mut args = vec!["merge", "--min-success", "0", "--out", &merged];
    args.extend(shares.iter().map(String::as_str));
    eval(&args);

    let whole = stripped(&out("whole").join("summary.json"));
    let joined = stripped(&out("merged").join("summary.json"));
    let raw = std::fs::read_to_string(out("whole").join("summary.json")).expect("summary written");
    let order: Vec<(String, u64)> = serde_json::from_str::<serde_json::Value>(&raw).expect("json")["trials"]
        .as_array()
        .expect("trials")
        .iter()
        .map(|t| {
            (
                t["skill"].as_str().expect("skill").to_string(),
                t["draw"]["index"].as_u64().expect("index"),
            )
        })
        .collect();
    let expected: Vec<(String, u64)> = [("touch", 0), ("touch", 1), ("press", 0), ("press", 1)]
        .iter()
        .map(|(skill, index)| (skill.to_string(), *index))
        .collect();
    assert_eq!(order, expected, "one process runs the trials file's order");
    for (line, (a, b)) in whole.lines().zip(joined.lines()).enumerate() {
        assert_eq!(a, b, "line {} of the stripped summary.json differs", line + 1);
    }
    assert_eq!(whole, joined);
    // The plot of the draws too.
    let svg = |name: &str| std::fs::read(out(name).join("plots/sweep.svg")).expect("plot written");
    assert_eq!(svg("whole"), svg("merged"));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

//! ROS 2 bags (MCAP) through every verb that reads or writes them, adversarially: bags without
//! poses or with one, `-o` naming a folder, a full device, a symlink or the input bag, and flags
//! of the other kind of demonstration file. Each gives its documented exit code with a message
//! naming what is wrong, writes nothing, and replaces no input, symlink or device.
#![cfg(feature = "mcap")]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use skill_runtime::demo::{parse_csv, ReadOptions};
use skillc::ros::msgs::{MsgType, PoseStamped, WrenchStamped};
use skillc::ros::write_demo;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-adv-mcap-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn skillc(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_skillc"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .output()
        .expect("skillc runs");
    assert_ne!(out.status.code(), Some(101), "`skillc {}` panicked", args.join(" "));
    out
}

/// Runs and checks the exit code and that the message holds every needle.
fn expect(dir: &Path, args: &[&str], code: i32, needles: &[&str]) -> String {
    let out = skillc(dir, args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "`skillc {}`: {stderr}", args.join(" "));
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "`skillc {}`: `{needle}` not in {stderr}",
            args.join(" ")
        );
    }
    stderr
}

/// A bag with `poses` PoseStamped messages on `/pose` and 50 WrenchStamped ones on `/wrench`.
fn bag(poses: usize) -> Vec<u8> {
    let mut writer = mcap::Writer::new(std::io::Cursor::new(Vec::new())).expect("writer");
    let mut channels = Vec::new();
    for (topic, ty) in [("/pose", MsgType::PoseStamped), ("/wrench", MsgType::WrenchStamped)] {
        let schema = writer
            .add_schema(ty.schema_name(), "ros2msg", ty.definition().as_bytes())
            .expect("schema");
        channels.push(
            writer
                .add_channel(schema, topic, "cdr", &BTreeMap::new())
                .expect("channel"),
        );
    }
    let stamp = |k: usize| skillc::ros::msgs::Time::from_seconds(k as f64 * 1e-3);
    let payloads: [Vec<Vec<u8>>; 2] = [
        (0..poses)
            .map(|k| {
                let mut pose = PoseStamped {
                    position: [0.5, 0.0, 0.3],
                    orientation_xyzw: [0.0, 1.0, 0.0, 0.0],
                    ..PoseStamped::default()
                };
                pose.header.stamp = stamp(k);
                pose.encode()
            })
            .collect(),
        (0..50)
            .map(|k| {
                let mut wrench = WrenchStamped::default();
                wrench.header.stamp = stamp(k);
                wrench.encode()
            })
            .collect(),
    ];
    for (channel, messages) in channels.iter().zip(&payloads) {
        for (k, data) in messages.iter().enumerate() {
            let time = 1_000_000 * k as u64;
            let header = mcap::records::MessageHeader {
                channel_id: *channel,
                sequence: k as u32,
                log_time: time,
                publish_time: time,
            };
            writer.write_to_known_channel(&header, data).expect("message");
        }
    }
    writer.finish().expect("finish");
    writer.into_inner().into_inner()
}

#[test]
fn bags_without_poses_and_outputs_that_are_not_files_are_refused() {
    let dir = temp_dir("bags");
    for (from, to) in [
        ("stdlib-skills/touch.skill", "touch.skill"),
        ("examples/scenes/table.toml", "table.toml"),
    ] {
        std::fs::copy(root().join(from), dir.join(to)).expect("copy");
    }
    let scene = std::fs::read_to_string(dir.join("table.toml")).expect("scene");
    let robot = root().join("examples/robots/").display().to_string();
    std::fs::write(dir.join("table.toml"), scene.replace("../robots/", &robot)).expect("scene");
    // The shipped touch demonstration as a bag.
    let csv = std::fs::read_to_string(root().join("examples/demos/touch.csv")).expect("demo");
    let loaded = parse_csv("touch.csv", &csv, &ReadOptions::default()).expect("parses");
    std::fs::write(
        dir.join("touch.mcap"),
        write_demo(&loaded.demo, loaded.wrench.frame).expect("bag"),
    )
    .expect("write");
    std::fs::write(dir.join("no_poses.mcap"), bag(0)).expect("write");
    std::fs::write(dir.join("one_pose.mcap"), bag(1)).expect("write");
    let input = std::fs::read(dir.join("touch.mcap")).expect("bag");

    // Bags with no pose or a single one: input problems, for learn and for run --demo.
    for name in ["no_poses.mcap", "one_pose.mcap"] {
        expect(&dir, &["learn", "touch.skill", name, "-o", "out.json"], 1, &[name]);
        expect(
            &dir,
            &["run", "touch.skill", "--demo", name, "--scene", "table.toml"],
            1,
            &[name],
        );
    }
    expect(
        &dir,
        &["learn", "touch.skill", "no_poses.mcap", "-o", "out.json"],
        1,
        &["PoseStamped"],
    );
    assert!(!dir.join("out.json").exists());

    // -o naming the input bag, in learn and run.
    expect(
        &dir,
        &["learn", "touch.skill", "touch.mcap", "-o", "touch.mcap"],
        2,
        &["touch.mcap"],
    );
    let run = ["run", "touch.skill", "--demo", "touch.mcap", "--scene", "table.toml"];
    expect(&dir, &[&run[..], &["-o", "touch.mcap"]].concat(), 2, &["touch.mcap"]);
    assert_eq!(
        std::fs::read(dir.join("touch.mcap")).expect("bag"),
        input,
        "the input bag is untouched"
    );

    // -o naming a folder, or a full device directly or through a symlink.
    std::fs::create_dir(dir.join("folder.mcap")).expect("dir");
    expect(&dir, &[&run[..], &["-o", "folder.mcap"]].concat(), 2, &["folder.mcap"]);
    assert!(dir.join("folder.mcap").is_dir());
    #[cfg(unix)]
    if Path::new("/dev/full").exists() {
        expect(&dir, &[&run[..], &["-o", "/dev/full"]].concat(), 2, &["/dev/full"]);
        std::os::unix::fs::symlink("/dev/full", dir.join("full.mcap")).expect("link");
        expect(&dir, &[&run[..], &["-o", "full.mcap"]].concat(), 2, &["full.mcap"]);
        assert!(std::fs::symlink_metadata(dir.join("full.mcap"))
            .expect("link")
            .file_type()
            .is_symlink());
    }

    // A symlinked log is written behind its link.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("log.mcap", dir.join("link.mcap")).expect("link");
        expect(&dir, &[&run[..], &["-o", "link.mcap"]].concat(), 0, &[]);
        assert!(std::fs::symlink_metadata(dir.join("link.mcap"))
            .expect("link")
            .file_type()
            .is_symlink());
        assert!(std::fs::read(dir.join("log.mcap"))
            .expect("log")
            .starts_with(mcap::MAGIC));
        // The log has two PoseStamped topics: run --demo names the one to learn from, as learn does.
        expect(
            &dir,
            &["run", "touch.skill", "--demo", "log.mcap", "--scene", "table.toml"],
            1,
            &["--pose-topic", "/tool_pose", "/desired_pose"],
        );
    }

    // Flags for the other kind of file are refused, not ignored.
    expect(
        &dir,
        &[
            "learn",
            "touch.skill",
            "touch.mcap",
            "-o",
            "out.json",
            "--delimiter",
            ";",
        ],
        2,
        &["--delimiter", "touch.mcap"],
    );
    expect(
        &dir,
        &[
            "learn",
            "touch.skill",
            "touch.mcap",
            "-o",
            "out.json",
            "--columns",
            "t=time",
        ],
        2,
        &["--columns"],
    );
    std::fs::copy(root().join("examples/demos/touch.csv"), dir.join("touch.csv")).expect("copy");
    expect(
        &dir,
        &[
            "learn",
            "touch.skill",
            "touch.csv",
            "-o",
            "out.json",
            "--pose-topic",
            "/pose",
        ],
        2,
        &["--pose-topic", "touch.csv"],
    );
    expect(
        &dir,
        &[
            "run",
            "touch.skill",
            "--demo",
            "touch.csv",
            "--scene",
            "table.toml",
            "--wrench-topic",
            "/w",
        ],
        2,
        &["--wrench-topic"],
    );
    expect(
        &dir,
        &[
            "learn",
            "touch.skill",
            "touch.mcap",
            "-o",
            "out.json",
            "--pose-topic",
            "/pose",
            "--tf-parent",
            "base",
        ],
        2,
        &["--tf-parent"],
    );
    assert!(!dir.join("out.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

//! ROS 2 bags (MCAP) through every verb that reads or writes them, adversarially: bags without
//! poses or with one, `-o` naming a folder, a full device, a symlink or the input bag, and flags
//! of the other kind of demonstration file; chunks whose CRC no longer matches (a pose moved
//! 2 mm), sizes of 2^40 bytes, PoseStamped bytes under a WrenchStamped schema, a schema text of
//! another type, leftover bytes, zero-length `frame_id`s (read as empty), rosbag2 folders
//! (learned as their `.mcap` is, split in two or not; without metadata, with a missing file,
//! stored as SQLite) and files whose content is the other kind. Each gives its documented exit
//! code with a message (its first line checked) naming what is wrong, writes nothing, and
//! replaces no input, symlink or device. Every bag is generated here.
#![cfg(feature = "mcap")]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use skill_ros::bag::write_demo;
use skill_ros::msgs::{MsgType, PoseStamped, WrenchStamped};
use skill_runtime::demo::{parse_csv, ReadOptions};

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
    let stamp = |k: usize| skill_ros::msgs::Time::from_seconds(k as f64 * 1e-3);
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

/// The first line of a message, checked to start with `start` and, with the rest, to hold every
/// needle; the exit code checked too.
fn expect_first(dir: &Path, args: &[&str], code: i32, start: &str, needles: &[&str]) -> String {
    let stderr = expect(dir, args, code, needles);
    let first = stderr.lines().next().unwrap_or_default().to_owned();
    assert!(
        first.starts_with(start),
        "`skillc {}`: first line `{first}` does not start `{start}`",
        args.join(" ")
    );
    first
}

/// The shipped touch demonstration, and the folder a test works in with `touch.skill` in it.
fn touch_setup(name: &str) -> (PathBuf, skill_runtime::demo::Demo) {
    let dir = temp_dir(name);
    std::fs::copy(root().join("stdlib-skills/touch.skill"), dir.join("touch.skill")).expect("copy");
    let csv = std::fs::read_to_string(root().join("examples/demos/touch.csv")).expect("demo");
    let loaded = parse_csv("touch.csv", &csv, &ReadOptions::default()).expect("parses");
    (dir, loaded.demo)
}

/// One message: its channel (an index into the channels given to [`write_bag`]), log time and bytes.
type Message = (usize, u64, Vec<u8>);

/// An MCAP file written with `options`: `channels` are (topic, schema name, schema text).
fn write_bag(options: mcap::WriteOptions, channels: &[(&str, &str, String)], messages: &[Message]) -> Vec<u8> {
    let mut writer = options.create(std::io::Cursor::new(Vec::new())).expect("writer");
    let mut ids = Vec::new();
    for (topic, schema, text) in channels {
        let schema = writer.add_schema(schema, "ros2msg", text.as_bytes()).expect("schema");
        ids.push(
            writer
                .add_channel(schema, topic, "cdr", &BTreeMap::new())
                .expect("channel"),
        );
    }
    for (k, (channel, time, data)) in messages.iter().enumerate() {
        let header = mcap::records::MessageHeader {
            channel_id: ids[*channel],
            sequence: k as u32,
            log_time: *time,
            publish_time: *time,
        };
        writer.write_to_known_channel(&header, data).expect("message");
    }
    writer.finish().expect("finish");
    writer.into_inner().into_inner()
}

/// The channels a demonstration is written on: `/tool_pose` (0) and `/wrench` (1), as `write_demo` does.
fn demo_channels() -> Vec<(&'static str, &'static str, String)> {
    [
        ("/tool_pose", MsgType::PoseStamped),
        ("/wrench", MsgType::WrenchStamped),
    ]
    .into_iter()
    .map(|(topic, ty)| (topic, ty.schema_name(), ty.definition()))
    .collect()
}

/// A demonstration's pose and wrench messages, as `write_demo` encodes them (pose in `base`, the
/// wrench naming no frame), alternating pose and wrench.
fn demo_messages(demo: &skill_runtime::demo::Demo) -> Vec<Message> {
    let mut out = Vec::new();
    for k in 0..demo.len() {
        let stamp = skill_ros::msgs::Time::from_seconds(demo.t_s[k]);
        let time = stamp.nanos() as u64;
        let (p, q) = (demo.position_m[k], demo.orientation[k].quaternion());
        let mut pose = PoseStamped {
            position: [p.x, p.y, p.z],
            orientation_xyzw: [q.i, q.j, q.k, q.w],
            ..PoseStamped::default()
        };
        pose.header.stamp = stamp;
        pose.header.frame_id = "base".into();
        let (f, m) = (demo.force_n[k], demo.torque_nm[k]);
        let mut wrench = WrenchStamped {
            force: [f.x, f.y, f.z],
            torque: [m.x, m.y, m.z],
            ..WrenchStamped::default()
        };
        wrench.header.stamp = stamp;
        out.push((0, time, pose.encode()));
        out.push((1, time, wrench.encode()));
    }
    out
}

/// Where the chunk records of an MCAP file start.
fn chunk_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut at = 8;
    let mut out = Vec::new();
    while at + 9 <= bytes.len() {
        let opcode = bytes[at];
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().expect("8 bytes")) as usize;
        match opcode {
            0x06 => out.push(at),
            0x02 => break,
            _ => {}
        }
        at += 9 + len;
    }
    out
}

/// Where `needle` is in `haystack` (once).
fn find(haystack: &[u8], needle: &[u8]) -> usize {
    let hits: Vec<usize> = haystack
        .windows(needle.len())
        .enumerate()
        .filter(|(_, window)| *window == needle)
        .map(|(at, _)| at)
        .collect();
    assert_eq!(hits.len(), 1, "the bytes are in the file once");
    hits[0]
}

fn learn_args<'a>(demo: &'a str, out: &'a str) -> Vec<&'a str> {
    vec!["learn", "touch.skill", demo, "-o", out]
}

#[test]
fn a_pose_moved_inside_a_chunk_whose_crc_no_longer_matches_is_refused() {
    let (dir, demo) = touch_setup("crc");
    let messages = demo_messages(&demo);
    let plain = || mcap::WriteOptions::new().compression(None).chunk_size(Some(16 << 10));
    let bytes = write_bag(plain(), &demo_channels(), &messages);
    assert!(chunk_offsets(&bytes).len() > 10, "several chunks");
    std::fs::write(dir.join("good.mcap"), &bytes).expect("write");
    expect(&dir, &learn_args("good.mcap", "good.json"), 0, &[]);

    // Pose 2000 (message 3999 of the file) 2 mm higher: its chunk's CRC no longer matches.
    let mut moved = bytes.clone();
    let at = find(&moved, &messages[3998].2) + 44;
    let z = f64::from_le_bytes(moved[at..at + 8].try_into().expect("z"));
    moved[at..at + 8].copy_from_slice(&(z + 0.002).to_le_bytes());
    std::fs::write(dir.join("moved.mcap"), &moved).expect("write");
    let first = expect_first(
        &dir,
        &learn_args("moved.mcap", "moved.json"),
        1,
        "error: `moved.mcap`: a chunk's stored CRC ",
        &[
            "does not match its contents",
            "the chunk after message",
            "copy or export it again",
        ],
    );
    assert!(first.contains("counting from 1"), "{first}");
    assert!(!dir.join("moved.json").exists());

    // The same in a zstd chunk: the stored CRC changed (the compressed bytes would not decompress).
    let zstd = write_bag(
        mcap::WriteOptions::new().chunk_size(Some(16 << 10)),
        &demo_channels(),
        &messages,
    );
    let mut bad_crc = zstd.clone();
    let chunk = chunk_offsets(&zstd)[3];
    bad_crc[chunk + 9 + 24] ^= 0x01;
    std::fs::write(dir.join("zstd_crc.mcap"), &bad_crc).expect("write");
    expect_first(
        &dir,
        &learn_args("zstd_crc.mcap", "zstd.json"),
        1,
        "error: `zstd_crc.mcap`: a chunk's stored CRC ",
        &["the chunk after message"],
    );

    // Without chunk CRCs, the data section's CRC still covers the chunk.
    let no_chunk_crc = write_bag(plain().calculate_chunk_crcs(false), &demo_channels(), &messages);
    let mut moved = no_chunk_crc.clone();
    let at = find(&moved, &messages[3998].2) + 44;
    moved[at..at + 8].copy_from_slice(&(z + 0.002).to_le_bytes());
    std::fs::write(dir.join("data_crc.mcap"), &moved).expect("write");
    expect_first(
        &dir,
        &learn_args("data_crc.mcap", "data.json"),
        1,
        "error: `data_crc.mcap`: the data section's stored CRC ",
        &["does not match"],
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn sizes_larger_than_the_file_or_the_chunk_bound_are_refused_before_reading() {
    let (dir, demo) = touch_setup("sizes");
    let messages = demo_messages(&demo);
    let options = || mcap::WriteOptions::new().chunk_size(Some(16 << 10));
    let zstd = write_bag(options(), &demo_channels(), &messages);
    let plain = write_bag(options().compression(None), &demo_channels(), &messages);
    let tera = (1u64 << 40).to_le_bytes();
    // A chunk declaring 2^40 bytes uncompressed: zstd (the reader would size its buffer by it)
    // and uncompressed (the size disagrees with the records it holds).
    for (name, bytes, needle) in [
        (
            "tera_zstd.mcap",
            &zstd,
            "a chunk declares 1099511627776 bytes uncompressed, more than the 256 MiB",
        ),
        (
            "tera_plain.mcap",
            &plain,
            "a chunk is not compressed and declares 1099511627776 bytes uncompressed, but holds",
        ),
    ] {
        let mut bytes = bytes.clone();
        let chunk = chunk_offsets(&bytes)[2];
        bytes[chunk + 9 + 16..chunk + 9 + 24].copy_from_slice(&tera);
        std::fs::write(dir.join(name), &bytes).expect("write");
        let first = expect_first(
            &dir,
            &learn_args(name, "out.json"),
            1,
            &format!("error: `{name}`, byte {chunk}: {needle}"),
            &[],
        );
        assert!(first.ends_with("the file is corrupt; export it again"), "{first}");
    }
    // A chunk record declaring 2^40 bytes, far beyond the file's end.
    let mut bytes = zstd.clone();
    let chunk = chunk_offsets(&bytes)[1];
    bytes[chunk + 1..chunk + 9].copy_from_slice(&tera);
    std::fs::write(dir.join("tera_record.mcap"), &bytes).expect("write");
    expect_first(
        &dir,
        &learn_args("tera_record.mcap", "out.json"),
        1,
        &format!(
            "error: `tera_record.mcap`, byte {chunk}: a record (opcode 0x06) declares 1099511627776 bytes, and only "
        ),
        &["mcap recover"],
    );
    // A chunk whose compressed size is beyond its record.
    let mut bytes = zstd.clone();
    let chunk = chunk_offsets(&bytes)[0];
    let name_len = u32::from_le_bytes(bytes[chunk + 9 + 28..chunk + 9 + 32].try_into().expect("4")) as usize;
    let size_at = chunk + 9 + 32 + name_len;
    bytes[size_at..size_at + 8].copy_from_slice(&tera);
    std::fs::write(dir.join("tera_compressed.mcap"), &bytes).expect("write");
    expect_first(
        &dir,
        &learn_args("tera_compressed.mcap", "out.json"),
        1,
        &format!("error: `tera_compressed.mcap`, byte {chunk}: a chunk declares 1099511627776 bytes of records"),
        &[],
    );
    // Cut short: the footer never comes.
    std::fs::write(dir.join("cut.mcap"), &zstd[..zstd.len() * 2 / 3]).expect("write");
    expect_first(
        &dir,
        &learn_args("cut.mcap", "out.json"),
        1,
        "error: `cut.mcap`, byte ",
        &["cut short", "mcap recover"],
    );
    assert!(!dir.join("out.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn messages_that_are_not_their_schemas_type_or_not_read_exactly_are_refused() {
    let (dir, demo) = touch_setup("types");
    let messages = demo_messages(&demo);
    // PoseStamped bytes on the WrenchStamped channel: the poses, also on /wrench.
    let poses_on_wrench: Vec<Message> = messages
        .iter()
        .enumerate()
        .map(|(k, (channel, time, data))| match channel {
            0 => (0, *time, data.clone()),
            _ => (1, *time, messages[k - 1].2.clone()),
        })
        .collect();
    let options = mcap::WriteOptions::new;
    std::fs::write(
        dir.join("pose_on_wrench.mcap"),
        write_bag(options(), &demo_channels(), &poses_on_wrench),
    )
    .expect("write");
    expect_first(
        &dir,
        &learn_args("pose_on_wrench.mcap", "out.json"),
        1,
        "error: `pose_on_wrench.mcap`, topic `/wrench`, message 1 (counting from 1): not a geometry_msgs/msg/WrenchStamped in CDR: at byte 76: 8 byte(s) are left over after the last field (`wrench.torque.z`)",
        &["read exactly as a geometry_msgs/msg/PoseStamped", "re-record it with its real type"],
    );

    // /wrench registered as PoseStamped, named with --wrench-topic.
    let mut channels = demo_channels();
    channels.push((
        "/wrench_raw",
        MsgType::PoseStamped.schema_name(),
        MsgType::PoseStamped.definition(),
    ));
    let mut with_pose_topic = messages.clone();
    with_pose_topic.push((2, 0, messages[0].2.clone()));
    std::fs::write(
        dir.join("named.mcap"),
        write_bag(options(), &channels, &with_pose_topic),
    )
    .expect("write");
    let mut args = learn_args("named.mcap", "out.json");
    args.extend(["--pose-topic", "/tool_pose", "--wrench-topic", "/wrench_raw"]);
    expect_first(
        &dir,
        &args,
        1,
        "error: `named.mcap`: --wrench-topic `/wrench_raw` has schema `geometry_msgs/msg/PoseStamped`, not the expected `geometry_msgs/msg/WrenchStamped`",
        &["`/wrench`"],
    );

    // A schema named WrenchStamped whose text is PoseStamped's.
    let mut channels = demo_channels();
    channels[1].2 = MsgType::PoseStamped.definition();
    std::fs::write(dir.join("schema_text.mcap"), write_bag(options(), &channels, &messages)).expect("write");
    expect_first(
        &dir,
        &learn_args("schema_text.mcap", "out.json"),
        1,
        "error: `schema_text.mcap`: topic `/wrench`: its schema is named `geometry_msgs/msg/WrenchStamped` but defines the fields `header`, `pose`, and a geometry_msgs/msg/WrenchStamped has `header`, `wrench`",
        &[],
    );

    // Leftover bytes: four after wrench 700 (past any end padding); up to three are padding.
    let mut leftover = messages.clone();
    leftover[1399].2.extend_from_slice(&[0; 4]);
    std::fs::write(
        dir.join("leftover.mcap"),
        write_bag(options(), &demo_channels(), &leftover),
    )
    .expect("write");
    expect_first(
        &dir,
        &learn_args("leftover.mcap", "out.json"),
        1,
        "error: `leftover.mcap`, topic `/wrench`, message 700 (counting from 1): not a geometry_msgs/msg/WrenchStamped in CDR: at byte 68: 4 byte(s) are left over",
        &[],
    );
    assert!(!dir.join("out.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// `bytes`, a CDR message whose header `frame_id` is empty (length 1 and a NUL, at byte 12), with
/// that string written as length 0 instead, as some writers do: its NUL becomes padding.
fn zero_length_frame_id(mut bytes: Vec<u8>) -> Vec<u8> {
    assert_eq!(&bytes[12..17], &[1, 0, 0, 0, 0], "an empty frame_id");
    bytes[12] = 0;
    bytes
}

#[test]
fn zero_length_frame_ids_read_as_empty_without_misaligning_later_fields() {
    let (dir, demo) = touch_setup("frame_id");
    let messages = demo_messages(&demo);
    std::fs::write(
        dir.join("nul.mcap"),
        write_bag(mcap::WriteOptions::new(), &demo_channels(), &messages),
    )
    .expect("write");
    // Every wrench's empty frame_id as length 0, and the poses' too (their frame `base` dropped).
    let zero: Vec<Message> = messages
        .iter()
        .map(|(channel, time, data)| {
            let data = match channel {
                0 => {
                    let mut pose = PoseStamped::decode(data).expect("pose");
                    pose.header.frame_id.clear();
                    zero_length_frame_id(pose.encode())
                }
                _ => zero_length_frame_id(data.clone()),
            };
            (*channel, *time, data)
        })
        .collect();
    std::fs::write(
        dir.join("zero.mcap"),
        write_bag(mcap::WriteOptions::new(), &demo_channels(), &zero),
    )
    .expect("write");
    let read = |name: &str| skill_ros::bag::read_demo(&dir.join(name), &Default::default()).expect("reads");
    let (nul, zero) = (read("nul.mcap"), read("zero.mcap"));
    assert_eq!(zero.loaded.demo.len(), demo.len());
    assert_eq!(zero.loaded.demo.position_m, nul.loaded.demo.position_m);
    assert_eq!(zero.loaded.demo.position_m, demo.position_m);
    assert_eq!(zero.loaded.demo.force_n, demo.force_n);
    assert_eq!(zero.loaded.demo.torque_nm, demo.torque_nm);
    assert_eq!(zero.loaded.demo.t_s, nul.loaded.demo.t_s);
    expect(&dir, &learn_args("zero.mcap", "zero.json"), 0, &[]);
    assert!(dir.join("zero.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// A rosbag2 `metadata.yaml` as `ros2 bag record -s mcap` writes it, listing `files`.
fn metadata_yaml(files: &[&str], storage: &str) -> String {
    let mut text = format!(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: {storage}\n  duration:\n    nanoseconds: 5119000000\n  starting_time:\n    nanoseconds_since_epoch: 0\n  message_count: 10240\n  topics_with_message_count:\n    - topic_metadata:\n        name: /wrench\n        type: geometry_msgs/msg/WrenchStamped\n        serialization_format: cdr\n        offered_qos_profiles: \"- history: 3\\n  depth: 0\\n  reliability: 1\"\n      message_count: 5120\n  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n"
    );
    for file in files {
        text.push_str(&format!("    - {file}\n"));
    }
    text.push_str("  files:\n");
    for file in files {
        text.push_str(&format!("    - path: {file}\n      message_count: 5120\n"));
    }
    text
}

/// A learned file's text with the demonstration's path replaced, for comparing two sources.
fn learned_text(path: &Path, source: &str) -> String {
    std::fs::read_to_string(path).expect("learned").replace(source, "DEMO")
}

#[test]
fn a_rosbag2_folder_learns_what_its_mcap_file_learns() {
    let (dir, demo) = touch_setup("rosbag2");
    let messages = demo_messages(&demo);
    let bytes = write_bag(mcap::WriteOptions::new(), &demo_channels(), &messages);
    std::fs::write(dir.join("touch.mcap"), &bytes).expect("write");
    expect(&dir, &learn_args("touch.mcap", "file.json"), 0, &[]);

    // One file, as recorded.
    std::fs::create_dir(dir.join("bag")).expect("dir");
    std::fs::write(dir.join("bag/bag_0.mcap"), &bytes).expect("write");
    std::fs::write(dir.join("bag/metadata.yaml"), metadata_yaml(&["bag_0.mcap"], "mcap")).expect("write");
    expect(&dir, &learn_args("bag", "folder.json"), 0, &[]);
    assert_eq!(
        learned_text(&dir.join("folder.json"), "bag"),
        learned_text(&dir.join("file.json"), "touch.mcap")
    );

    // Split in two files (by size, as `ros2 bag record -b` does), read in the listed order.
    std::fs::create_dir(dir.join("split")).expect("dir");
    let half = messages.len() / 2;
    let channels = demo_channels();
    std::fs::write(
        dir.join("split/split_1.mcap"),
        write_bag(mcap::WriteOptions::new(), &channels, &messages[half..]),
    )
    .expect("write");
    std::fs::write(
        dir.join("split/split_0.mcap"),
        write_bag(mcap::WriteOptions::new(), &channels, &messages[..half]),
    )
    .expect("write");
    std::fs::write(
        dir.join("split/metadata.yaml"),
        metadata_yaml(&["split_0.mcap", "split_1.mcap"], "mcap"),
    )
    .expect("write");
    let mut args = learn_args("split", "split.json");
    args.extend(["--pose-topic", "/tool_pose"]);
    expect(&dir, &args, 0, &[]);
    assert_eq!(
        learned_text(&dir.join("split.json"), "split"),
        learned_text(&dir.join("file.json"), "touch.mcap")
    );
    // A message's number counts on across the files: wrench 3000 is in the second.
    let mut bad = messages[half..].to_vec();
    bad[5999 - half].2.truncate(30);
    std::fs::write(
        dir.join("split/split_1.mcap"),
        write_bag(mcap::WriteOptions::new(), &channels, &bad),
    )
    .expect("write");
    let bad_file = Path::new("split").join("split_1.mcap").display().to_string();
    expect_first(
        &dir,
        &learn_args("split", "out.json"),
        1,
        &format!("error: `{bad_file}`, topic `/wrench`, message 3000 (counting from 1): not a geometry_msgs/msg/WrenchStamped in CDR"),
        &[],
    );

    // Folders that are not readable bags; one without metadata.yaml is a path given wrongly
    // (usage, exit 2, as any folder where a file is expected).
    std::fs::create_dir(dir.join("no_metadata")).expect("dir");
    std::fs::write(dir.join("no_metadata/take.mcap"), &bytes).expect("write");
    expect_first(
        &dir,
        &learn_args("no_metadata", "out.json"),
        2,
        "error: `no_metadata` is a folder without `metadata.yaml`, so not a rosbag2 bag: pass the bag file `no_metadata/take.mcap` itself",
        &[],
    );
    std::fs::create_dir(dir.join("missing")).expect("dir");
    std::fs::write(
        dir.join("missing/metadata.yaml"),
        metadata_yaml(&["missing_0.mcap"], "mcap"),
    )
    .expect("write");
    expect_first(
        &dir,
        &learn_args("missing", "out.json"),
        1,
        "error: `missing` lists `missing_0.mcap` in its `metadata.yaml` (`relative_file_paths`), which is not a file in the folder",
        &[],
    );
    std::fs::create_dir(dir.join("sqlite")).expect("dir");
    std::fs::write(
        dir.join("sqlite/metadata.yaml"),
        metadata_yaml(&["sqlite_0.db3"], "sqlite3"),
    )
    .expect("write");
    expect_first(
        &dir,
        &learn_args("sqlite", "out.json"),
        1,
        "error: `sqlite` is a rosbag2 bag stored as `sqlite3` (`storage_identifier` in its `metadata.yaml`), and skillc reads only `mcap`",
        &["convert"],
    );
    // Topic flags are for a bag folder as for a bag file; CSV flags are not.
    let mut args = learn_args("bag", "out.json");
    args.extend(["--delimiter", ";"]);
    expect(&dir, &args, 2, &["--delimiter", "ROS 2 bag"]);
    assert!(!dir.join("out.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_file_whose_content_is_the_other_kind_is_named_for_what_it_is() {
    let (dir, demo) = touch_setup("misnamed");
    let bag = write_demo(&demo, None).expect("bag");
    std::fs::write(dir.join("bag.csv"), &bag).expect("write");
    expect_first(
        &dir,
        &learn_args("bag.csv", "out.json"),
        1,
        "error: `bag.csv` is an MCAP file (a ROS 2 bag), not CSV: rename it to `bag.mcap`",
        &[],
    );
    let scene = std::fs::read_to_string(root().join("examples/scenes/table.toml")).expect("scene");
    let robot = root().join("examples/robots/").display().to_string();
    std::fs::write(dir.join("table.toml"), scene.replace("../robots/", &robot)).expect("scene");
    let run = ["run", "touch.skill", "--demo", "bag.csv", "--scene", "table.toml"];
    expect_first(
        &dir,
        &run,
        1,
        "error: `bag.csv` is an MCAP file (a ROS 2 bag), not CSV",
        &[],
    );
    std::fs::copy(root().join("examples/demos/touch.csv"), dir.join("text.mcap")).expect("copy");
    expect_first(
        &dir,
        &learn_args("text.mcap", "out.json"),
        1,
        "error: `text.mcap` is text (it starts `t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz`), not MCAP: if it is a CSV demonstration, rename it to `text.csv`",
        &[],
    );
    let mut sqlite = b"SQLite format 3\0".to_vec();
    sqlite.extend_from_slice(&[0; 100]);
    std::fs::write(dir.join("old.mcap"), &sqlite).expect("write");
    expect_first(
        &dir,
        &learn_args("old.mcap", "out.json"),
        1,
        "error: `old.mcap` is an SQLite database (a rosbag2 bag in the older `sqlite3` storage, `.db3`), not MCAP: convert it",
        &[],
    );
    std::fs::write(dir.join("old.csv"), &sqlite).expect("write");
    expect_first(
        &dir,
        &learn_args("old.csv", "out.json"),
        1,
        "error: `old.csv` is an SQLite database",
        &["mcap convert"],
    );
    let mut ros1 = b"#ROSBAG V2.0\n".to_vec();
    ros1.extend_from_slice(&[0xff; 64]);
    std::fs::write(dir.join("ros1.mcap"), &ros1).expect("write");
    expect_first(
        &dir,
        &learn_args("ros1.mcap", "out.json"),
        1,
        "error: `ros1.mcap` is a ROS 1 bag, not MCAP",
        &[],
    );
    std::fs::write(dir.join("empty.mcap"), b"").expect("write");
    expect_first(
        &dir,
        &learn_args("empty.mcap", "out.json"),
        1,
        "error: `empty.mcap` is empty, not MCAP",
        &[],
    );
    assert!(!dir.join("out.json").exists());
    std::fs::remove_dir_all(&dir).expect("clean up");
}

//! ROS 2 interop through MCAP: a demonstration written as a bag by skillc and read back learns
//! what its CSV learns; `skillc run -o log.mcap` writes one message per tick on each topic; a
//! bag written by another tool (Foxglove's Python `mcap-ros2-support`, tests/data/README.md) is
//! read with the right values; malformed bags are refused with the file, topic and message named.
#![cfg(feature = "mcap")]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use skill_kit::load::{learn_from_files, load_skill};
use skill_ros::bag::{read_demo, write_demo, BagOptions, RunLogTopics};
use skill_ros::msgs::{decode_string, JointState, MsgType, PoseStamped, WrenchStamped};
use skill_runtime::demo::{parse_csv, ReadOptions, WrenchFrame};
use skill_runtime::demogen::{generate, to_csv, StdSkill};
use skill_runtime::skill::LearnOptions;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("skillc-mcap-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
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

/// Every message of an MCAP file: topic → (schema name, schema encoding, message encoding, payloads).
type Topics = BTreeMap<String, (String, String, String, Vec<Vec<u8>>)>;

fn messages(path: &Path) -> Topics {
    let bytes = std::fs::read(path).expect("read bag");
    let mut topics = Topics::new();
    for message in mcap::MessageStream::new(&bytes).expect("MCAP") {
        let message = message.expect("message");
        let schema = message.channel.schema.as_ref().expect("a schema");
        let entry = topics.entry(message.channel.topic.clone()).or_insert_with(|| {
            (
                schema.name.clone(),
                schema.encoding.clone(),
                message.channel.message_encoding.clone(),
                Vec::new(),
            )
        });
        entry.3.push(message.data.into_owned());
    }
    topics
}

/// Every number in two JSON values agrees within `tol` (absolute and relative); other values are equal.
fn assert_close(a: &serde_json::Value, b: &serde_json::Value, tol: f64, at: &str) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().expect("f64"), y.as_f64().expect("f64"));
            assert!((x - y).abs() <= tol * (1.0 + x.abs().max(y.abs())), "{at}: {x} != {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            for (index, (x, y)) in x.iter().zip(y).enumerate() {
                assert_close(x, y, tol, &format!("{at}[{index}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>(), "{at}: keys");
            for (key, value) in x {
                assert_close(value, &y[key], tol, &format!("{at}.{key}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

#[test]
fn a_demonstration_written_as_mcap_learns_what_its_csv_learns() {
    let dir = temp_dir("roundtrip");
    let demonstration = generate(StdSkill::Press, StdSkill::Press.default_seed());
    let csv_path = dir.join("press.csv");
    let csv = to_csv(&demonstration);
    std::fs::write(&csv_path, &csv).expect("csv");
    let loaded = parse_csv("press.csv", &csv, &ReadOptions::default()).expect("csv parses");
    let bag_path = dir.join("press.mcap");
    let bytes = write_demo(&loaded.demo, loaded.wrench.frame).expect("encode");
    std::fs::write(&bag_path, &bytes).expect("bag");

    // Read back: the same samples (times to the nanosecond the stamps hold).
    let read = read_demo(&bag_path, &BagOptions::default()).expect("our bag reads");
    let demo = &read.loaded.demo;
    assert_eq!(demo.len(), loaded.demo.len());
    for k in 0..demo.len() {
        assert!((demo.t_s[k] - loaded.demo.t_s[k]).abs() < 1e-9, "time {k}");
        assert_eq!(demo.position_m[k], loaded.demo.position_m[k], "position {k}");
        assert_eq!(demo.force_n[k], loaded.demo.force_n[k], "force {k}");
        assert_eq!(demo.torque_nm[k], loaded.demo.torque_nm[k], "torque {k}");
        assert!(
            demo.orientation[k].angle_to(&loaded.demo.orientation[k]) < 1e-12,
            "orientation {k}"
        );
    }
    assert_eq!(read.pose_source, "topic `/tool_pose`");
    assert_eq!(read.wrench_topic, "/wrench");

    // Learned from either file: the same segments, frames, motions and forces.
    let (_, skill) = load_skill(&root().join("stdlib-skills/press.skill"), None).expect("press compiles");
    let from_csv = learn_from_files(&skill, &csv_path, &LearnOptions::default()).expect("learns from CSV");
    let from_bag = learn_from_files(&skill, &bag_path, &LearnOptions::default()).expect("learns from MCAP");
    assert_eq!(from_csv.segments.len(), 3);
    let mut csv_json = serde_json::to_value(&from_csv).expect("json");
    let mut bag_json = serde_json::to_value(&from_bag).expect("json");
    // The bag's one extra note: its wrench names no frame (the CSV declares none either).
    assert_eq!(from_bag.demo.warnings.len(), from_csv.demo.warnings.len() + 1);
    assert!(
        from_bag.demo.warnings[0].contains("names no header frame"),
        "{:?}",
        from_bag.demo.warnings
    );
    for json in [&mut csv_json, &mut bag_json] {
        json["demo"]["source"] = serde_json::Value::Null;
        json["demo"]["warnings"] = serde_json::Value::Null;
    }
    assert_close(&csv_json, &bag_json, 1e-6, "learned");
    for (a, b) in from_csv.segments.iter().zip(&from_bag.segments) {
        assert_eq!((a.start_index, a.end_index), (b.start_index, b.end_index));
    }
    std::fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn run_writes_its_log_as_mcap_with_one_message_per_tick() {
    let dir = temp_dir("runlog");
    let log = dir.join("press.log.mcap");
    let out = skillc(
        root(),
        &[
            "run",
            "stdlib-skills/press.skill",
            "--demo",
            "examples/demos/press.csv",
            "--scene",
            "examples/scenes/button.toml",
            "-o",
            log.to_str().expect("utf-8 path"),
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let ticks: usize = stdout
        .lines()
        .find_map(|line| line.strip_suffix(" ticks)")?.rsplit('(').next()?.parse().ok())
        .expect("the summary counts the ticks");
    let topics = messages(&log);
    let expected = [
        (RunLogTopics::JOINT_STATES, MsgType::JointState),
        (RunLogTopics::TOOL_POSE, MsgType::PoseStamped),
        (RunLogTopics::DESIRED_POSE, MsgType::PoseStamped),
        (RunLogTopics::WRENCH, MsgType::WrenchStamped),
        (RunLogTopics::STATE, MsgType::String),
        (RunLogTopics::TF, MsgType::TfMessage),
        (RunLogTopics::TF_STATIC, MsgType::TfMessage),
        (RunLogTopics::ROBOT_DESCRIPTION, MsgType::String),
        (RunLogTopics::SCENE, MsgType::MarkerArray),
        (RunLogTopics::CONTACT_FORCE, MsgType::MarkerArray),
    ];
    assert_eq!(topics.len(), expected.len());
    for (topic, ty) in expected {
        let (schema, schema_encoding, encoding, payloads) = &topics[topic];
        assert_eq!(schema, ty.schema_name(), "{topic}");
        assert_eq!(schema_encoding, "ros2msg", "{topic}");
        assert_eq!(encoding, "cdr", "{topic}");
        match topic {
            RunLogTopics::TF | RunLogTopics::CONTACT_FORCE => {
                assert_eq!(
                    payloads.len(),
                    ticks.div_ceil(skill_ros::bag::TF_PERIOD_TICKS),
                    "{topic}"
                )
            }
            RunLogTopics::TF_STATIC | RunLogTopics::ROBOT_DESCRIPTION => assert_eq!(payloads.len(), 1, "{topic}"),
            // Once at the start, then again whenever the button's cap moved (at most at /tf's rate).
            RunLogTopics::SCENE => assert!(
                (1..=ticks.div_ceil(skill_ros::bag::TF_PERIOD_TICKS)).contains(&payloads.len()),
                "{topic}: {} messages",
                payloads.len()
            ),
            _ if ty != MsgType::String => assert_eq!(payloads.len(), ticks, "{topic}: one message per tick"),
            _ => {}
        }
    }
    let joints = JointState::decode(&topics[RunLogTopics::JOINT_STATES].3[0]).expect("JointState");
    assert_eq!(joints.name.len(), 7);
    assert_eq!(
        (joints.position.len(), joints.velocity.len(), joints.effort.len()),
        (7, 7, 7)
    );
    assert!(
        joints.name.iter().all(|name| !name.starts_with("joint_")),
        "the URDF's names: {:?}",
        joints.name
    );
    let states: Vec<String> = topics[RunLogTopics::STATE]
        .3
        .iter()
        .map(|bytes| decode_string(bytes).expect("String"))
        .collect();
    assert_eq!(states.first().map(String::as_str), Some("prepose"));
    assert!(states.iter().any(|s| s == "press"), "{states:?}");
    let pose = PoseStamped::decode(&topics[RunLogTopics::TOOL_POSE].3[1]).expect("PoseStamped");
    assert_eq!(pose.header.frame_id, "base");
    assert!(pose.header.stamp.nanos() > 0);
    // The log reads back as a demonstration: the tool pose and the sensor's wrench, every tick.
    let read = read_demo(
        &log,
        &BagOptions {
            pose_topic: Some(RunLogTopics::TOOL_POSE.into()),
            ..BagOptions::default()
        },
    )
    .expect("the log reads as a demonstration");
    assert_eq!(read.loaded.demo.len(), ticks);
    assert_eq!(read.loaded.wrench.frame, Some(WrenchFrame::Base));
    // Without --pose-topic the two PoseStamped topics are named as candidates.
    let err = read_demo(&log, &BagOptions::default()).expect_err("two pose topics");
    let message = err.to_string();
    assert!(
        message.contains("/tool_pose") && message.contains("/desired_pose") && message.contains("--pose-topic"),
        "{message}"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// tests/data/press_ros2.mcap, written by tools/check/mcap_ros2_press.py (Python `mcap` 1.6.0,
/// `mcap-ros2-support` 0.6.0, zstd chunks): pose at 250 Hz, wrench at 500 Hz stamped 1 ms after.
fn other_tools_bag() -> PathBuf {
    root().join("tests/data/press_ros2.mcap")
}

#[test]
fn a_bag_written_by_another_tool_reads_with_the_wrench_interpolated_onto_the_pose() {
    let path = other_tools_bag();
    let read = read_demo(&path, &BagOptions::default()).expect("the other tool's bag reads");
    let demo = &read.loaded.demo;
    assert_eq!(read.pose_source, "topic `/ee_pose`");
    assert_eq!(read.wrench_topic, "/ft_sensor");
    // Poses at 0, 4, ..., 3200 ms; the wrench spans 1 .. 3199 ms, so the first and last pose
    // are left out (and said so).
    assert_eq!(demo.len(), 799);
    assert!(
        read.notes.iter().any(|n| n.contains("2 pose sample(s)")),
        "{:?}",
        read.notes
    );
    assert_eq!(
        read.loaded.wrench.frame,
        Some(WrenchFrame::Base),
        "frame_id base_link is the pose's frame"
    );
    for (k, t) in demo.t_s.iter().enumerate() {
        assert!((t - k as f64 * 0.004).abs() < 1e-9, "time {k}: {t}");
    }
    assert!(demo.position_m.iter().all(|p| p.x == 0.5 && p.y == 0.0));
    assert!((demo.position_m[0].z - 0.35).abs() < 1e-5);
    let lowest = demo.position_m.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    assert!((lowest - 0.31).abs() < 1e-12, "pressed 4 cm down: {lowest}");
    let q = demo.orientation[0];
    assert_eq!((q.w, q.i, q.j, q.k), (0.0, 0.0, 1.0, 0.0));

    // The force at each pose time is the mean of the wrench samples 1 ms either side.
    let raw: Vec<WrenchStamped> = messages(&path)["/ft_sensor"]
        .3
        .iter()
        .map(|bytes| WrenchStamped::decode(bytes).expect("WrenchStamped"))
        .collect();
    assert_eq!(raw.len(), 1600);
    assert_eq!(raw[0].header.frame_id, "base_link");
    for k in 0..demo.len() {
        // Pose k + 1 is at 4 (k + 1) ms; wrench j at 1 + 2 j ms.
        let below = &raw[2 * (k + 1) - 1];
        let above = &raw[2 * (k + 1)];
        let expected = 0.5 * (below.force[2] + above.force[2]);
        assert!(
            (demo.force_n[k].z - expected).abs() < 1e-12,
            "force {k}: {} != {expected}",
            demo.force_n[k].z
        );
    }
    let peak = demo.force_n.iter().map(|f| f.z).fold(0.0, f64::max);
    assert!((9.8..10.3).contains(&peak), "peak {peak}");

    // The same pose from TF, named by its frames; a frame that is not there lists those that are.
    let tf = read_demo(
        &path,
        &BagOptions {
            tf_parent: Some("base_link".into()),
            tf_child: Some("tool0".into()),
            ..BagOptions::default()
        },
    )
    .expect("the TF edge reads");
    assert_eq!(tf.loaded.demo.position_m, demo.position_m);
    assert_eq!(tf.loaded.demo.force_n, demo.force_n);
    assert!(
        tf.pose_source.starts_with("TF `base_link` → `tool0`"),
        "{}",
        tf.pose_source
    );
    assert_eq!(tf.loaded.wrench.frame, Some(WrenchFrame::Base));
    let err = read_demo(
        &path,
        &BagOptions {
            tf_child: Some("flange".into()),
            ..BagOptions::default()
        },
    )
    .expect_err("no such frame");
    let message = err.to_string();
    assert!(
        message.contains("`base_link` → `tool0`") && message.contains("`world` → `base_link`"),
        "{message}"
    );
}

#[test]
fn learn_reads_another_tools_bag_from_the_command_line() {
    let dir = temp_dir("learn");
    let out_path = dir.join("press.learned.json");
    let out = skillc(
        root(),
        &[
            "learn",
            "stdlib-skills/press.skill",
            other_tools_bag().to_str().expect("utf-8 path"),
            "-o",
            out_path.to_str().expect("utf-8 path"),
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("pose from topic `/ee_pose`, wrench from topic `/ft_sensor`"),
        "{stdout}"
    );
    let learned: serde_json::Value = serde_json::from_slice(&std::fs::read(&out_path).expect("written")).expect("JSON");
    assert_eq!(learned["segments"].as_array().map(Vec::len), Some(3));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// A bag of one PoseStamped and one WrenchStamped topic whose messages `poses` and `wrenches` give.
fn bag(poses: &[Vec<u8>], wrenches: &[Vec<u8>]) -> Vec<u8> {
    let mut writer = mcap::Writer::new(std::io::Cursor::new(Vec::new())).expect("writer");
    let mut ids = Vec::new();
    for (topic, ty) in [("/pose", MsgType::PoseStamped), ("/wrench", MsgType::WrenchStamped)] {
        let schema = writer
            .add_schema(ty.schema_name(), "ros2msg", ty.definition().as_bytes())
            .expect("schema");
        ids.push(
            writer
                .add_channel(schema, topic, "cdr", &BTreeMap::new())
                .expect("channel"),
        );
    }
    for (channel, payloads) in ids.iter().zip([poses, wrenches]) {
        for (k, data) in payloads.iter().enumerate() {
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

fn pose_message(k: usize) -> PoseStamped {
    let mut pose = PoseStamped {
        position: [0.5, 0.0, 0.3 - 1e-4 * k as f64],
        orientation_xyzw: [0.0, 1.0, 0.0, 0.0],
        ..PoseStamped::default()
    };
    pose.header.stamp = skill_ros::msgs::Time::from_seconds(k as f64 * 1e-3);
    pose.header.frame_id = "base".into();
    pose
}

fn wrench_message(k: usize) -> WrenchStamped {
    let mut wrench = WrenchStamped {
        force: [0.0, 0.0, k as f64 * 0.01],
        ..WrenchStamped::default()
    };
    wrench.header.stamp = skill_ros::msgs::Time::from_seconds(k as f64 * 1e-3);
    wrench
}

#[test]
fn malformed_bags_are_refused_naming_file_topic_and_message() {
    let dir = temp_dir("malformed");
    let good_poses: Vec<Vec<u8>> = (0..50).map(|k| pose_message(k).encode()).collect();
    let good_wrenches: Vec<Vec<u8>> = (0..50).map(|k| wrench_message(k).encode()).collect();
    // Message 3 of /pose has a frame_id claiming 4 GB.
    let mut huge_string = good_poses.clone();
    huge_string[2][12..16].copy_from_slice(&0xffff_fff0u32.to_le_bytes());
    // Message 5 of /wrench is cut short.
    let mut short = good_wrenches.clone();
    short[4].truncate(20);
    // Message 7 of /pose is NaN.
    let mut nan = good_poses.clone();
    let mut pose = pose_message(6);
    pose.position[2] = f64::NAN;
    nan[6] = pose.encode();
    // Message 2 of /pose has an XCDR2 header.
    let mut xcdr2 = good_poses.clone();
    xcdr2[1][1] = 0x07;
    let other_tool = std::fs::read(other_tools_bag()).expect("bag");
    let mut huge_record = mcap::MAGIC.to_vec();
    huge_record.push(0x01);
    huge_record.extend_from_slice(&(1u64 << 62).to_le_bytes());
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        ("empty.mcap", Vec::new(), &["empty.mcap"]),
        ("garbage.mcap", b"t,px,py\n1,2,3\n".to_vec(), &["garbage.mcap", "MCAP"]),
        (
            "truncated.mcap",
            other_tool[..other_tool.len() / 2].to_vec(),
            &["truncated.mcap"],
        ),
        ("huge_record.mcap", huge_record, &["huge_record.mcap"]),
        (
            "huge_string.mcap",
            bag(&huge_string, &good_wrenches),
            &["huge_string.mcap", "`/pose`", "message 3", "frame_id"],
        ),
        (
            "short.mcap",
            bag(&good_poses, &short),
            &["short.mcap", "`/wrench`", "message 5"],
        ),
        (
            "nan.mcap",
            bag(&nan, &good_wrenches),
            &["nan.mcap", "`/pose`", "message 7", "pose.position.z"],
        ),
        (
            "xcdr2.mcap",
            bag(&xcdr2, &good_wrenches),
            &["xcdr2.mcap", "message 2", "XCDR2"],
        ),
        (
            "no_wrench.mcap",
            bag(&good_poses, &[]),
            &["no_wrench.mcap", "WrenchStamped"],
        ),
    ];
    for (name, bytes, needles) in &cases {
        std::fs::write(dir.join(name), bytes).expect("write case");
        let out = skillc(
            &dir,
            &[
                "learn",
                &root().join("stdlib-skills/touch.skill").display().to_string(),
                name,
                "-o",
                "out.json",
            ],
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        for needle in *needles {
            assert!(stderr.contains(needle), "{name}: `{needle}` not in {stderr}");
        }
        assert!(!dir.join("out.json").exists(), "{name}: nothing is written");
    }
    // The good bag learns, and a missing one is an IO error.
    std::fs::write(dir.join("good.mcap"), bag(&good_poses, &good_wrenches)).expect("write");
    let read = read_demo(&dir.join("good.mcap"), &BagOptions::default()).expect("good bag");
    assert_eq!(read.loaded.demo.len(), 50);
    assert_eq!(
        read.loaded.wrench.frame, None,
        "an empty wrench frame is left to detection"
    );
    let out = skillc(
        &dir,
        &[
            "learn",
            &root().join("stdlib-skills/touch.skill").display().to_string(),
            "nosuch.mcap",
            "-o",
            "out.json",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// The MCAP log of `skillc run` of standard skill `skill`, learned from its shipped
/// demonstration, in `examples/scenes/<scene>.toml`, written into `dir`; the run must succeed.
fn run_logged_as_mcap(dir: &Path, skill: &str, scene: &str) -> Vec<u8> {
    let log = dir.join(format!("{skill}.log.mcap"));
    let out = skillc(
        root(),
        &[
            "run",
            &format!("stdlib-skills/{skill}.skill"),
            "--demo",
            &format!("examples/demos/{skill}.csv"),
            "--scene",
            &format!("examples/scenes/{scene}.toml"),
            "-o",
            log.to_str().expect("utf-8 path"),
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::read(&log).expect("read bag")
}

/// `/tf` read back with the `mcap` crate's reader (not skillc's bag reader): its tool link's
/// transform at each stamp equals `/tool_pose` at that stamp within 1e-9; `/robot_description`
/// is the file's first message and carries the scene's URDF; `/scene` draws the table where the
/// scene file puts it; `/contact_force`'s measured arrow is `/wrench`'s force from `/tool_pose`,
/// and its desired arrow stands where the touch presses; the latched topics are marked as
/// rosbag2 marks them.
#[test]
fn a_run_log_carries_transforms_and_the_robot_for_a_3d_view() {
    use skill_ros::bag::{FORCE_ARROW_MIN_N, FORCE_ARROW_M_PER_N};
    use skill_ros::msgs::{decode_markers, decode_tf, marker_action, marker_type, Marker};
    let dir = temp_dir("tf");
    let bytes = run_logged_as_mcap(&dir, "touch", "table");
    let mut first_topic = None;
    let mut poses = BTreeMap::new();
    let mut transforms = Vec::new();
    let mut description = None;
    let mut scene_markers: Option<Vec<Marker>> = None;
    let mut wrenches = BTreeMap::new();
    let mut arrows = Vec::new();
    for message in mcap::MessageStream::new(&bytes).expect("MCAP") {
        let message = message.expect("message");
        first_topic.get_or_insert_with(|| message.channel.topic.clone());
        let latched = message
            .channel
            .metadata
            .get("offered_qos_profiles")
            .is_some_and(|qos| qos.contains("durability: 1"));
        match message.channel.topic.as_str() {
            RunLogTopics::TOOL_POSE => {
                let pose = PoseStamped::decode(&message.data).expect("pose");
                poses.insert(message.log_time, pose);
            }
            RunLogTopics::TF => {
                assert!(!latched, "/tf is not latched");
                transforms.push((message.log_time, decode_tf(&message.data).expect("TFMessage")));
            }
            RunLogTopics::TF_STATIC => assert!(latched, "/tf_static is latched"),
            RunLogTopics::SCENE => {
                assert!(latched, "/scene is latched");
                assert!(scene_markers.is_none(), "/scene is written once");
                scene_markers = Some(decode_markers(&message.data).expect("MarkerArray"));
            }
            RunLogTopics::WRENCH => {
                wrenches.insert(message.log_time, WrenchStamped::decode(&message.data).expect("wrench"));
            }
            RunLogTopics::CONTACT_FORCE => {
                assert!(!latched, "/contact_force is not latched");
                arrows.push((message.log_time, decode_markers(&message.data).expect("MarkerArray")));
            }
            RunLogTopics::ROBOT_DESCRIPTION => {
                assert!(latched, "/robot_description is latched");
                description = Some(decode_string(&message.data).expect("String"));
            }
            _ => {}
        }
    }
    assert_eq!(first_topic.as_deref(), Some(RunLogTopics::ROBOT_DESCRIPTION));
    let urdf = std::fs::read_to_string(root().join("examples/robots/lwr4.urdf")).expect("urdf");
    assert_eq!(description.as_deref(), Some(urdf.as_str()));
    let scene = std::fs::read_to_string(root().join("examples/scenes/table.toml")).expect("scene");
    let tool = scene
        .lines()
        .find_map(|line| line.trim().strip_prefix("tool = \""))
        .and_then(|rest| rest.strip_suffix('"'))
        .unwrap_or("probe_tip")
        .to_string();
    assert!(transforms.len() > 100, "{} /tf messages", transforms.len());
    let mut worst = 0.0f64;
    for (stamp, message) in &transforms {
        let frame = message
            .iter()
            .find(|t| t.child_frame_id == tool)
            .unwrap_or_else(|| panic!("/tf has the tool link `{tool}`"));
        assert_eq!(frame.header.frame_id, "base");
        let pose = &poses[stamp];
        for axis in 0..3 {
            worst = worst.max((frame.translation[axis] - pose.position[axis]).abs());
        }
        // Quaternions q and -q are the same rotation.
        let dot: f64 = (0..4).map(|i| frame.rotation_xyzw[i] * pose.orientation_xyzw[i]).sum();
        worst = worst.max(1.0 - dot.abs());
    }
    assert!(worst < 1e-9, "/tf's tool frame is /tool_pose within {worst:e}");

    // The scene: the table box (examples/scenes/table.toml) and its label above its top.
    let scene = scene_markers.expect("/scene is written");
    assert_eq!(scene.len(), 2, "{scene:?}");
    let table = &scene[0];
    assert_eq!((table.ns.as_str(), table.shape), ("scene", marker_type::CUBE));
    assert_eq!(table.header.frame_id, "base");
    assert_eq!(table.position, [0.55, 0.0, 0.275]);
    assert_eq!(table.scale, [0.6, 0.8, 0.05]);
    assert_eq!(table.orientation_xyzw, [0.0, 0.0, 0.0, 1.0]);
    let label = &scene[1];
    assert_eq!(
        (label.shape, label.text.as_str()),
        (marker_type::TEXT_VIEW_FACING, "table")
    );
    assert!(label.position[2] > 0.3, "the label stands above the table top");

    // The force arrows, at the /tf rate: the measured one is /wrench's force drawn from the tool
    // point, and is there exactly when the force is.
    assert_eq!(arrows.len(), transforms.len());
    let (mut drawn, mut pressing) = (0, 0);
    for (stamp, markers) in &arrows {
        assert_eq!(markers.len(), 2);
        let (measured, desired) = (&markers[0], &markers[1]);
        let force = wrenches[stamp].force;
        let norm = force.iter().map(|f| f * f).sum::<f64>().sqrt();
        if norm < FORCE_ARROW_MIN_N {
            assert_eq!(measured.action, marker_action::DELETE);
        } else {
            drawn += 1;
            assert_eq!(
                (measured.action, measured.shape),
                (marker_action::ADD, marker_type::ARROW)
            );
            let tool = poses[stamp].position;
            assert_eq!(measured.points[0], tool);
            for axis in 0..3 {
                let length = measured.points[1][axis] - tool[axis];
                assert!((length - FORCE_ARROW_M_PER_N * force[axis]).abs() < 1e-12);
            }
        }
        if desired.action == marker_action::ADD {
            // The touch presses down on the table: the force that meets it back points up.
            let up = desired.points[1][2] - desired.points[0][2];
            assert!(up > 0.0, "the desired arrow points up at {stamp}: {up}");
            pressing += 1;
        }
    }
    assert!(
        drawn > 10 && pressing > 10,
        "{drawn} measured and {pressing} desired arrows drawn"
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// A tick of a 7-joint arm at `t_s` in state `state`, its numbers varying with `t_s`.
fn tick_at(t_s: f64, state: u32) -> skill_runtime::exec::Tick {
    let q: Vec<f64> = (0..7).map(|j| 0.1 * j as f64 + t_s).collect();
    skill_runtime::exec::Tick {
        t_s,
        state,
        desired: [0.5 + t_s, 0.1, 0.2, 0.0, 1.0, 0.0, 0.0],
        measured: [0.5 + 0.9 * t_s, 0.1, 0.2, 0.0, 1.0, 0.0, 0.0],
        wrench_base: [0.0, 0.0, -10.0 * t_s, 0.0, 0.0, 0.0],
        wrench_cf: [0.0; 6],
        desired_cf: [0.0, 0.0, 5.0, 0.0, 0.0, 0.0],
        frame: [0.0, 1.0, 0.0, 0.0],
        selection: 0b11_1011,
        torques: skill_runtime::exec::JointValues::from_slices(&[&q]),
        joint_state: skill_runtime::exec::JointValues::from_slices(&[&q, &[0.01; 7]]),
    }
}

#[test]
fn a_run_log_written_in_batches_is_the_log_written_whole() {
    // Two logs, the second's clock starting again (a task's next step), states changing
    // between and inside the batches a tap sends.
    let mut first = skill_runtime::exec::RunLog::default();
    let mut second = skill_runtime::exec::RunLog::default();
    for (log, ticks) in [(&mut first, 95), (&mut second, 41)] {
        let [a, b] = [log.state_index("approach"), log.state_index("press")];
        for k in 0..ticks {
            let state = if k % 30 < 13 { a } else { b };
            log.ticks.push(tick_at(k as f64 * 1e-3, state));
        }
        // The button's cap goes down and comes back every tenth tick, and a part the scene
        // does not have is skipped.
        log.part_names = vec!["button".to_owned(), "no_such_part".to_owned()];
        for (n, tick) in (0..ticks).step_by(10).enumerate() {
            for part in 0..2 {
                let offset_m = 1e-3 * (n % 4) as f64;
                log.parts.push(skill_runtime::exec::PartSample { tick, part, offset_m });
            }
        }
    }
    let scene = skill_kit::load::load_scene(&root().join("examples/scenes/button.toml"), &[]).expect("scene");
    let objects = &scene.spec().objects;
    let names: Vec<String> = (1..=7).map(|j| format!("j{j}")).collect();
    let logs = [(None, &first), (Some("press"), &second)];
    let whole = skill_ros::bag::write_run_log(&logs, &names, None, objects).expect("written whole");
    for batch in [1, 7, 30, 1000] {
        let mut writer = skill_ros::bag::RunLogWriter::new(&names, None, objects);
        for (step, log) in &logs {
            writer.start_log(step.map(str::to_owned));
            for (chunk, ticks) in log.ticks.chunks(batch).enumerate() {
                let range = chunk * batch..chunk * batch + ticks.len();
                let parts: Vec<_> = log.parts.iter().filter(|p| range.contains(&p.tick)).copied().collect();
                let batch = skill_runtime::exec::LogBatch {
                    ticks,
                    parts: &parts,
                    ..log.batch()
                };
                writer.push(batch).expect("a batch");
            }
        }
        let batched = writer.finish().expect("written in batches");
        assert!(batched == whole, "batches of {batch}: the bytes differ");
    }
    let topics = {
        let dir = temp_dir("batches");
        let path = dir.join("log.mcap");
        std::fs::write(&path, &whole).expect("written");
        messages(&path)
    };
    assert_eq!(topics[RunLogTopics::JOINT_STATES].3.len(), 95 + 41);
    let states: Vec<String> = topics[RunLogTopics::STATE]
        .3
        .iter()
        .map(|data| decode_string(data).expect("a string"))
        .collect();
    assert_eq!(states[..2], ["approach", "press"]);
    assert_eq!(states.last().map(String::as_str), Some("press/approach"));
}

#[test]
fn a_log_written_while_the_run_goes_on_is_the_log_written_after_it() {
    let (_, skill) = load_skill(&root().join("stdlib-skills/press.skill"), None).expect("press");
    let learned = learn_from_files(
        &skill,
        &root().join("examples/demos/press.csv"),
        &LearnOptions::default(),
    )
    .expect("learns");
    let scene = skill_kit::load::load_scene(&root().join("examples/scenes/button.toml"), &[]).expect("scene");
    let bound = skill_runtime::exec::bind(&skill, &learned).expect("binds");
    let dir = temp_dir("live");
    for ext in ["csv", "mcap"] {
        let live_path = dir.join(format!("live.{ext}"));
        let live = skillc::run_log::LiveLog::start(&live_path, &scene).expect("writer starts");
        let options = skill_runtime::exec::ExecOptions {
            tap: Some(live.tap()),
            ..Default::default()
        };
        let (report, log) =
            skill_runtime::exec::simulate(&scene, skill_runtime::exec::Mode::Skill(&bound), &options).expect("runs");
        drop(options);
        assert_eq!(report.outcome, skill_ir::Outcome::Success, "{}", report.message);
        assert!(
            log.ticks.len() > 3000,
            "a run of several batches: {} ticks",
            log.ticks.len()
        );
        assert!(log.parts.len() > 100, "the cap moved: {} part samples", log.parts.len());
        live.finish(&live_path).expect("written live");
        let after_path = dir.join(format!("after.{ext}"));
        skillc::run_log::write_after(&after_path, &[(None, &log)], &scene).expect("written after");
        let (live, after) = (
            std::fs::read(&live_path).expect("live"),
            std::fs::read(&after_path).expect("after"),
        );
        assert!(
            live == after,
            "{ext}: the live log differs from the log written after the run"
        );
        assert!(live.len() > 100_000, "{ext}: {} bytes", live.len());
    }
}

/// A press of the button scene: `/scene` is written again whenever the cap moves, whole each
/// time (a latched topic's last message is what a late viewer draws), and the cap it draws
/// goes down under the probe and comes back up. The second witness is the probe itself: at the
/// cap's deepest the probe's tip sphere (`/tool_pose` its centre) stands on the cap's drawn top,
/// and `/wrench` pushes the tool up by more than the spring's preload.
#[test]
fn a_pressed_buttons_cap_moves_on_scene_under_the_probe() {
    use skill_ros::msgs::{decode_markers, marker_type, Marker};
    let dir = temp_dir("cap");
    let bytes = run_logged_as_mcap(&dir, "press", "button");
    let mut scenes: Vec<(u64, Vec<Marker>)> = Vec::new();
    let mut poses = BTreeMap::new();
    let mut wrenches = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("MCAP") {
        let message = message.expect("message");
        match message.channel.topic.as_str() {
            RunLogTopics::SCENE => scenes.push((message.log_time, decode_markers(&message.data).expect("MarkerArray"))),
            RunLogTopics::TOOL_POSE => {
                poses.insert(message.log_time, PoseStamped::decode(&message.data).expect("pose"));
            }
            RunLogTopics::WRENCH => {
                wrenches.insert(message.log_time, WrenchStamped::decode(&message.data).expect("wrench"));
            }
            _ => {}
        }
    }
    // examples/scenes/button.toml: the base box, then the button's cap (20 mm tall, its centre
    // at z = 0.29 m at rest, 8 mm of travel), each with its label.
    let (rest_z, half_height, travel) = (0.29, 0.01, 0.008);
    let cap_z = |markers: &[Marker]| {
        assert_eq!(markers.len(), 4, "the whole scene each time: {markers:?}");
        let cap = &markers[2];
        assert_eq!((cap.ns.as_str(), cap.shape), ("scene", marker_type::CYLINDER));
        assert_eq!(cap.position[..2], [0.5466, 0.0]);
        assert_eq!(markers[0].position, [0.55, 0.0, 0.2], "the base box never moves");
        cap.position[2]
    };
    assert!(scenes.len() > 10, "{} /scene messages", scenes.len());
    assert!((cap_z(&scenes[0].1) - rest_z).abs() < 1e-12, "at rest at the start");
    let (deepest_at, deepest_z) = scenes
        .iter()
        .map(|(stamp, markers)| (*stamp, cap_z(markers)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("messages");
    let depth = rest_z - deepest_z;
    assert!(depth > 1e-3 && depth < travel + 1e-3, "the cap went {depth} m down");
    // The tool point is the centre of the probe's 10 mm tip sphere (examples/robots/lwr4.urdf).
    let tip = poses[&deepest_at].position[2];
    let top = deepest_z + half_height;
    assert!(
        (tip - 0.01 - top).abs() < 1.5e-3,
        "the probe's tip sphere (centre {tip} m) stands on the cap's top at {top} m"
    );
    let push = wrenches[&deepest_at].force[2];
    assert!(
        push > 2.0,
        "the cap pushes the probe up with {push} N, more than its preload"
    );
    let last = cap_z(&scenes.last().expect("messages").1);
    assert!(
        rest_z - last < 5e-4,
        "the cap is back up at the end: {} m in",
        rest_z - last
    );
    std::fs::remove_dir_all(&dir).expect("clean up");
}

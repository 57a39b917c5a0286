//! Reading a demonstration out of a ROS 2 bag (an MCAP file, or a rosbag2 folder of them): the
//! tool pose from a `geometry_msgs/PoseStamped` topic or from TF (`tf2_msgs/TFMessage`, one
//! parent → child transform), the wrench from a `geometry_msgs/WrenchStamped` topic, resampled
//! onto the pose's times by linear interpolation.
//!
//! Topics are chosen by the caller ([`BagOptions`]) or found by type: the one topic of the type,
//! else an error listing the candidates. Times are the header stamps, or the log times for a
//! stream whose stamps are all zero, counted from the first pose sample. Each file's records
//! are walked first ([`records::check_records`]: sizes against bytes), then it is streamed with its
//! CRCs checked, a chunk's before any of its messages is used (memory grows with the kept
//! samples and the largest chunk, each bounded). A channel's schema must be the type its name
//! says, and every message must decode to its last byte (CDR's end padding aside). A malformed
//! file or message is an error naming the file, the topic and the message's index on its topic
//! (counted from 1, on across a folder's files).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use mcap::sans_io::LinearReaderOptions;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use skill_learn::demo::{orientation_warnings, Demo, Loaded, Normalised, WrenchDeclaration, WrenchFrame};

use super::msgs::{decode_tf, definition_fields, MsgType, PoseStamped, WrenchStamped};
use super::{records, BagError, BagOptions};

/// Largest MCAP record (a chunk, compressed or not) read into memory \[bytes\].
pub const MAX_RECORD_BYTES: usize = 256 << 20;
/// Most samples kept from one pose or wrench stream (the demonstration's bound after resampling).
pub const MAX_SAMPLES: usize = 2_000_000;
/// Most transforms kept from all TF topics together.
pub const MAX_TRANSFORMS: usize = 8_000_000;

/// A demonstration read from a bag, with what was read and what the reader noticed.
#[derive(Debug, Clone)]
pub struct BagDemo {
    /// The demonstration, its warnings and the wrench's declared frame.
    pub loaded: Loaded,
    /// Where the pose came from: ``topic `/pose` `` or ``TF `base` → `tool` ``.
    pub pose_source: String,
    /// The wrench topic.
    pub wrench_topic: String,
    /// Things the reader did or noticed (left-out samples, clocks, the wrench's frame).
    pub notes: Vec<String>,
}

/// One stamped sample: the header stamp, the log time (both ns), the message's index on its
/// topic (from 1), and six or seven values.
#[derive(Debug, Clone, Copy)]
struct Sample<const N: usize> {
    stamp_ns: i64,
    log_ns: u64,
    index: u64,
    values: [f64; N],
}

/// What was kept of one channel of a type skillc reads.
#[derive(Debug, Default)]
struct Stream<const N: usize> {
    topic: String,
    samples: Vec<Sample<N>>,
    /// The first header frame_id, and whether later messages named another.
    frame_id: Option<String>,
    frame_changes: bool,
    /// The first message that could not be used (reported only if this stream is chosen).
    problem: Option<Problem>,
}

impl<const N: usize> Stream<N> {
    fn new(topic: &str) -> Self {
        Stream {
            topic: topic.to_owned(),
            samples: Vec::new(),
            frame_id: None,
            frame_changes: false,
            problem: None,
        }
    }

    fn frame(&mut self, frame_id: &str) {
        match &self.frame_id {
            None => self.frame_id = Some(frame_id.to_owned()),
            Some(first) if first != frame_id => self.frame_changes = true,
            Some(_) => {}
        }
    }
}

/// A message that could not be used: the file it is in (one of a rosbag2 folder's), its topic,
/// its index on the topic (from 1; 0 for the channel's schema, before any message) and why.
#[derive(Debug, Clone)]
struct Problem {
    file: String,
    topic: String,
    index: u64,
    reason: String,
}

impl Problem {
    fn error(&self) -> BagError {
        if self.index == 0 {
            return BagError::Topics {
                file: self.file.clone(),
                reason: format!("topic `{}`: {}", self.topic, self.reason),
            };
        }
        message_error(&self.file, &format!("topic `{}`", self.topic), self.index, &self.reason)
    }
}

/// A topic of the bag, whatever its type: its schema's name (empty without one) and the
/// messages seen on it so far.
#[derive(Debug)]
struct TopicInfo {
    topic: String,
    schema: String,
    count: u64,
}

/// What a channel of one file is read as: its type if skillc reads it, the stream it feeds
/// (an index into `poses` or `wrenches`) and its topic (an index into `topics`).
#[derive(Debug, Clone, Copy)]
struct ChannelSlot {
    kind: Option<MsgType>,
    slot: usize,
    topic: usize,
}

/// A TF edge's samples and the topics they came from.
#[derive(Debug, Default)]
struct TfEdge {
    samples: Vec<Sample<7>>,
    topics: Vec<String>,
}

/// Everything read from the file, before topics are chosen.
#[derive(Debug, Default)]
struct Contents {
    poses: Vec<Stream<7>>,
    wrenches: Vec<Stream<6>>,
    /// `(parent, child)` → samples.
    tf: BTreeMap<(String, String), TfEdge>,
    tf_topics: Vec<String>,
    tf_problem: Option<Problem>,
    n_transforms: usize,
    /// Topics of a known type whose messages are not CDR, with their encoding.
    not_cdr: Vec<(String, String)>,
    /// Every topic, in the order first seen, and where each is in `topics`.
    topics: Vec<TopicInfo>,
    topic_slots: BTreeMap<String, usize>,
    /// Messages read from all files.
    n_messages: u64,
}

impl Contents {
    /// Registers a channel of the file `file` the first time one of its messages is read.
    fn register(&mut self, file: &str, channel: &mcap::Channel<'_>) -> ChannelSlot {
        let topic = channel.topic.as_str();
        let schema_name = channel
            .schema
            .as_ref()
            .map(|schema| schema.name.clone())
            .unwrap_or_default();
        let topic_slot = match self.topic_slots.get(topic) {
            Some(&slot) => slot,
            None => {
                self.topics.push(TopicInfo {
                    topic: topic.to_owned(),
                    schema: schema_name.clone(),
                    count: 0,
                });
                self.topic_slots.insert(topic.to_owned(), self.topics.len() - 1);
                self.topics.len() - 1
            }
        };
        let kind = MsgType::from_schema_name(&schema_name)
            .filter(|kind| matches!(kind, MsgType::PoseStamped | MsgType::WrenchStamped | MsgType::TfMessage));
        let Some(kind) = kind else {
            return ChannelSlot {
                kind: None,
                slot: 0,
                topic: topic_slot,
            };
        };
        if channel.message_encoding != "cdr" {
            if !self.not_cdr.iter().any(|(t, _)| t == topic) {
                self.not_cdr.push((topic.to_owned(), channel.message_encoding.clone()));
            }
            return ChannelSlot {
                kind: None,
                slot: 0,
                topic: topic_slot,
            };
        }
        // A schema whose definition is not the type its name says.
        let schema_problem = channel.schema.as_ref().and_then(|schema| {
            if schema.encoding != "ros2msg" {
                return None;
            }
            let text = String::from_utf8_lossy(&schema.data);
            let fields = definition_fields(&text);
            let expected = kind.field_names();
            if fields.is_empty() {
                return None;
            }
            (fields != expected).then(|| Problem {
                file: file.to_owned(),
                topic: topic.to_owned(),
                index: 0,
                reason: format!(
                    "its schema is named `{schema_name}` but defines the fields `{}`, and a {} has `{}`: the schema is not the type its name says; re-record the topic with its real type",
                    fields.join("`, `"),
                    kind.schema_name(),
                    expected.join("`, `")
                ),
            })
        });
        let slot = match kind {
            MsgType::PoseStamped => stream_slot(&mut self.poses, topic, schema_problem),
            MsgType::WrenchStamped => stream_slot(&mut self.wrenches, topic, schema_problem),
            _ => {
                if !self.tf_topics.iter().any(|t| t == topic) {
                    self.tf_topics.push(topic.to_owned());
                }
                if self.tf_problem.is_none() {
                    self.tf_problem = schema_problem;
                }
                0
            }
        };
        ChannelSlot {
            kind: Some(kind),
            slot,
            topic: topic_slot,
        }
    }

    /// The topics of the bag that are not of `kind`, with their schemas: `` `/a` (`pkg/msg/T`) ``.
    fn other_topics(&self, kind: MsgType) -> String {
        let others: Vec<String> = self
            .topics
            .iter()
            .filter(|info| MsgType::from_schema_name(&info.schema) != Some(kind))
            .take(12)
            .map(|info| format!("`{}` ({})", info.topic, schema_label(&info.schema)))
            .collect();
        if others.is_empty() {
            "none".into()
        } else {
            others.join(", ")
        }
    }

    /// The schema of `topic`, if the bag has that topic.
    fn schema_of(&self, topic: &str) -> Option<&str> {
        self.topic_slots
            .get(topic)
            .map(|&slot| self.topics[slot].schema.as_str())
    }
}

/// The stream of `topic` in `streams` (made if new), with a schema problem recorded on it.
fn stream_slot<const N: usize>(streams: &mut Vec<Stream<N>>, topic: &str, schema_problem: Option<Problem>) -> usize {
    let slot = match streams.iter().position(|stream| stream.topic == topic) {
        Some(slot) => slot,
        None => {
            streams.push(Stream::new(topic));
            streams.len() - 1
        }
    };
    if streams[slot].problem.is_none() {
        streams[slot].problem = schema_problem;
    }
    slot
}

/// A schema name for a message: `` `pkg/msg/T` `` or `no schema`.
fn schema_label(schema: &str) -> String {
    if schema.is_empty() {
        "no schema".into()
    } else {
        format!("`{schema}`")
    }
}

/// Reads the demonstration in the bag at `path`: an MCAP file or a rosbag2 folder.
pub fn read_demo(path: &Path, options: &BagOptions) -> Result<BagDemo, BagError> {
    let file = path.display().to_string();
    let contents = scan_bag(path, &file)?;
    let mut notes = Vec::new();
    let (pose_source, parent_frame, child_frame, poses) = choose_pose(&file, &contents, options)?;
    let wrench = choose_wrench(&file, &contents, options)?;
    let wrench_topic = wrench.topic.clone();
    let wrench_place = format!("topic `{wrench_topic}`");
    let pose_fields = if child_frame.is_some() { TF_FIELDS } else { POSE_FIELDS };

    let pose_times = times(&poses, &pose_source, &mut notes);
    let wrench_times = times(&wrench.samples, &wrench_place, &mut notes);
    let pose_order = sorted(&file, &pose_source, &pose_times, &poses)?;
    let wrench_order = sorted(&file, &wrench_place, &wrench_times, &wrench.samples)?;
    if pose_times.uses_log_time != wrench_times.uses_log_time {
        notes.push(format!(
            "the pose ({pose_source}) is timed by its {} and the wrench (`{wrench_topic}`) by its {}: check that both clocks agree",
            pose_times.name(),
            wrench_times.name()
        ));
    }

    // The wrench on the pose's times: linear interpolation inside the wrench's time span; pose
    // samples outside it are left out.
    let wrench_t: Vec<i64> = wrench_order.iter().map(|&i| wrench_times.ns[i]).collect();
    let (first_w, last_w) = (wrench_t[0], wrench_t[wrench_t.len() - 1]);
    let kept: Vec<usize> = pose_order
        .iter()
        .copied()
        .filter(|&i| (first_w..=last_w).contains(&pose_times.ns[i]))
        .collect();
    let left_out = pose_order.len() - kept.len();
    if kept.len() < 2 {
        return Err(BagError::Topics {
            file,
            reason: format!(
                "the pose ({pose_source}) and the wrench (`{wrench_topic}`) overlap in {} sample(s) of time: they do not cover the same period (are both timed by the same clock?)",
                kept.len()
            ),
        });
    }
    if left_out > 0 {
        notes.push(format!(
            "{left_out} pose sample(s) outside the wrench's time span were left out (the wrench is interpolated, not extrapolated)"
        ));
    }
    let pose_rate = rate_hz(&pose_times.ns, &pose_order);
    let wrench_rate = rate_hz(&wrench_times.ns, &wrench_order);
    if wrench_rate > 2.0 * pose_rate {
        notes.push(format!(
            "the wrench ({wrench_rate:.0} Hz) is sampled faster than the pose ({pose_rate:.0} Hz); it is interpolated at the pose's times, so force detail between pose samples is lost"
        ));
    }

    let t0 = pose_times.ns[kept[0]];
    let mut demo = Demo {
        source: file.clone(),
        t_s: Vec::with_capacity(kept.len()),
        position_m: Vec::with_capacity(kept.len()),
        orientation: Vec::with_capacity(kept.len()),
        force_n: Vec::with_capacity(kept.len()),
        torque_nm: Vec::with_capacity(kept.len()),
    };
    let mut normalised = Normalised::default();
    let mut cursor = 0usize;
    for &i in &kept {
        let sample = &poses[i];
        let t_ns = pose_times.ns[i];
        check_finite(&file, &pose_source, sample.index, &sample.values, &pose_fields)?;
        let [x, y, z, qx, qy, qz, qw] = sample.values;
        let raw = Quaternion::new(qw, qx, qy, qz);
        let norm = raw.norm();
        if norm < 1e-9 {
            return Err(message_error(
                &file,
                &pose_source,
                sample.index,
                "the orientation quaternion has zero norm",
            ));
        }
        normalised.note(norm, sample.index as usize);
        // The wrench samples around t: wrench_t[cursor] <= t < wrench_t[cursor + 1] (or t is the last).
        while cursor + 1 < wrench_t.len() && wrench_t[cursor + 1] <= t_ns {
            cursor += 1;
        }
        let below = &wrench.samples[wrench_order[cursor]];
        check_finite(&file, &wrench_place, below.index, &below.values, &WRENCH_FIELDS)?;
        let values = if wrench_t[cursor] == t_ns || cursor + 1 == wrench_t.len() {
            below.values
        } else {
            let above = &wrench.samples[wrench_order[cursor + 1]];
            check_finite(&file, &wrench_place, above.index, &above.values, &WRENCH_FIELDS)?;
            let share = (t_ns - wrench_t[cursor]) as f64 / (wrench_t[cursor + 1] - wrench_t[cursor]) as f64;
            std::array::from_fn(|k| below.values[k] + share * (above.values[k] - below.values[k]))
        };
        demo.t_s.push((t_ns - t0) as f64 * 1e-9);
        demo.position_m.push(Vector3::new(x, y, z));
        demo.orientation.push(UnitQuaternion::from_quaternion(raw));
        demo.force_n.push(Vector3::new(values[0], values[1], values[2]));
        demo.torque_nm.push(Vector3::new(values[3], values[4], values[5]));
    }

    let warnings = orientation_warnings(&file, &mut demo.orientation, &normalised, |k| {
        poses[kept[k]].index as usize
    });

    let wrench_frame_id = wrench.frame_id.clone().unwrap_or_default();
    let frame = if !wrench_frame_id.is_empty() && wrench_frame_id == parent_frame {
        Some(WrenchFrame::Base)
    } else if !wrench_frame_id.is_empty() && Some(wrench_frame_id.as_str()) == child_frame.as_deref() {
        Some(WrenchFrame::Sensor)
    } else if wrench_frame_id.is_empty() {
        notes.push(format!(
            "`{wrench_topic}` names no header frame: the wrench's axes (base or sensor) are detected when learning (declare them with --wrench-frame)"
        ));
        None
    } else {
        notes.push(format!(
            "the wrench's frame `{wrench_frame_id}` is neither the pose's base frame `{parent_frame}`{}: its axes (base or sensor) are detected when learning (declare them with --wrench-frame)",
            child_frame.as_deref().map(|c| format!(" nor the tool frame `{c}`")).unwrap_or_default()
        ));
        None
    };
    if wrench.frame_changes {
        notes.push(format!(
            "`{wrench_topic}` names more than one header frame; the first, `{wrench_frame_id}`, was taken"
        ));
    }
    Ok(BagDemo {
        loaded: Loaded {
            demo,
            warnings,
            wrench: WrenchDeclaration {
                frame,
                ..WrenchDeclaration::default()
            },
        },
        pose_source,
        wrench_topic,
        notes,
    })
}

const POSE_FIELDS: [&str; 7] = [
    "pose.position.x",
    "pose.position.y",
    "pose.position.z",
    "pose.orientation.x",
    "pose.orientation.y",
    "pose.orientation.z",
    "pose.orientation.w",
];
const TF_FIELDS: [&str; 7] = [
    "transform.translation.x",
    "transform.translation.y",
    "transform.translation.z",
    "transform.rotation.x",
    "transform.rotation.y",
    "transform.rotation.z",
    "transform.rotation.w",
];
const WRENCH_FIELDS: [&str; 6] = [
    "wrench.force.x",
    "wrench.force.y",
    "wrench.force.z",
    "wrench.torque.x",
    "wrench.torque.y",
    "wrench.torque.z",
];

fn message_error(file: &str, place: &str, index: u64, reason: &str) -> BagError {
    BagError::Message {
        file: file.to_owned(),
        place: place.to_owned(),
        index,
        reason: reason.to_owned(),
    }
}

fn check_finite(file: &str, source: &str, index: u64, values: &[f64], names: &[&str]) -> Result<(), BagError> {
    match values.iter().zip(names).find(|(value, _)| !value.is_finite()) {
        Some((value, name)) => Err(message_error(file, source, index, &format!("`{name}` is {value}"))),
        None => Ok(()),
    }
}

/// A stream's times in ns: its header stamps, or its log times when every stamp is zero.
struct Times {
    ns: Vec<i64>,
    uses_log_time: bool,
}

impl Times {
    fn name(&self) -> &'static str {
        if self.uses_log_time {
            "log times (its header stamps are zero)"
        } else {
            "header stamps"
        }
    }
}

fn times<const N: usize>(samples: &[Sample<N>], source: &str, notes: &mut Vec<String>) -> Times {
    let uses_log_time = samples.iter().all(|s| s.stamp_ns == 0);
    if uses_log_time {
        notes.push(format!("{source} has zero header stamps: its log times were used"));
    }
    Times {
        ns: samples
            .iter()
            .map(|s| {
                if uses_log_time {
                    i64::try_from(s.log_ns).unwrap_or(i64::MAX)
                } else {
                    s.stamp_ns
                }
            })
            .collect(),
        uses_log_time,
    }
}

/// The samples' order by time; two samples at one time are an error.
fn sorted<const N: usize>(
    file: &str,
    source: &str,
    times: &Times,
    samples: &[Sample<N>],
) -> Result<Vec<usize>, BagError> {
    let mut order: Vec<usize> = (0..samples.len()).collect();
    order.sort_by_key(|&i| times.ns[i]);
    for pair in order.windows(2) {
        if times.ns[pair[0]] == times.ns[pair[1]] {
            return Err(message_error(
                file,
                source,
                samples[pair[1]].index,
                &format!(
                    "its time {} ns is that of message {} too: samples must have distinct times",
                    times.ns[pair[1]], samples[pair[0]].index
                ),
            ));
        }
    }
    Ok(order)
}

fn rate_hz(ns: &[i64], order: &[usize]) -> f64 {
    match (order.first(), order.last()) {
        (Some(&a), Some(&b)) if ns[b] > ns[a] => (order.len() - 1) as f64 / ((ns[b] - ns[a]) as f64 * 1e-9),
        _ => 0.0,
    }
}

/// Reads every file of the bag at `path` (an MCAP file or a rosbag2 folder) into one
/// [`Contents`]: messages on a topic are counted on across files.
fn scan_bag(path: &Path, file: &str) -> Result<Contents, BagError> {
    let mut contents = Contents::default();
    for part in records::bag_files(path)? {
        scan(&part, &part.display().to_string(), &mut contents)?;
    }
    if contents.n_messages == 0 {
        return Err(BagError::Topics {
            file: file.to_owned(),
            reason: "the bag holds no messages: was it recorded with the topics subscribed?".into(),
        });
    }
    Ok(contents)
}

/// Checks the MCAP file at `path` ([`records::check_records`]), then streams it once with every CRC
/// it stores checked (a chunk's before any of its messages is read), decoding every message of
/// the three types skillc reads into `contents`.
fn scan(path: &Path, file: &str, contents: &mut Contents) -> Result<(), BagError> {
    records::check_records(path, file, MAX_RECORD_BYTES as u64)?;
    let handle = File::open(path).map_err(|source| BagError::Io {
        file: file.to_owned(),
        source,
    })?;
    let reader = mcap::io::MessageReader::new_with_options(
        BufReader::new(handle),
        LinearReaderOptions::default()
            .with_record_length_limit(MAX_RECORD_BYTES)
            .with_prevalidate_chunk_crcs(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true),
    );
    // Channel id → what its messages are read as (ids are per file).
    let mut channels: BTreeMap<u16, ChannelSlot> = BTreeMap::new();
    // The last message read: its topic and index on it.
    let mut last: Option<(usize, u64)> = None;
    for (n_before, message) in (0u64..).zip(reader) {
        let message = message.map_err(|source| mcap_error(file, source, n_before, last, contents))?;
        contents.n_messages += 1;
        let channel = &message.channel;
        let ChannelSlot { kind, slot, topic } = match channels.get(&channel.id) {
            Some(entry) => *entry,
            None => {
                let entry = contents.register(file, channel);
                channels.insert(channel.id, entry);
                entry
            }
        };
        contents.topics[topic].count += 1;
        let index = contents.topics[topic].count;
        last = Some((topic, index));
        let topic = channel.topic.as_str();
        let log_ns = message.log_time;
        let bad = |reason: String| Problem {
            file: file.to_owned(),
            topic: topic.to_owned(),
            index,
            reason,
        };
        match kind {
            Some(MsgType::PoseStamped) => {
                let stream = &mut contents.poses[slot];
                if stream.problem.is_some() {
                    continue;
                }
                match PoseStamped::decode(&message.data) {
                    Ok(pose) if stream.samples.len() < MAX_SAMPLES => {
                        stream.frame(&pose.header.frame_id);
                        let [x, y, z] = pose.position;
                        let [qx, qy, qz, qw] = pose.orientation_xyzw;
                        stream.samples.push(Sample {
                            stamp_ns: pose.header.stamp.nanos(),
                            log_ns,
                            index,
                            values: [x, y, z, qx, qy, qz, qw],
                        });
                    }
                    Ok(_) => stream.problem = Some(bad(format!("more than {MAX_SAMPLES} poses; cut the bag shorter"))),
                    Err(err) => stream.problem = Some(bad(not_decoded(MsgType::PoseStamped, &err, &message.data))),
                }
            }
            Some(MsgType::WrenchStamped) => {
                let stream = &mut contents.wrenches[slot];
                if stream.problem.is_some() {
                    continue;
                }
                match WrenchStamped::decode(&message.data) {
                    Ok(wrench) if stream.samples.len() < MAX_SAMPLES => {
                        stream.frame(&wrench.header.frame_id);
                        let [fx, fy, fz] = wrench.force;
                        let [mx, my, mz] = wrench.torque;
                        stream.samples.push(Sample {
                            stamp_ns: wrench.header.stamp.nanos(),
                            log_ns,
                            index,
                            values: [fx, fy, fz, mx, my, mz],
                        });
                    }
                    Ok(_) => {
                        stream.problem = Some(bad(format!("more than {MAX_SAMPLES} wrenches; cut the bag shorter")))
                    }
                    Err(err) => stream.problem = Some(bad(not_decoded(MsgType::WrenchStamped, &err, &message.data))),
                }
            }
            Some(MsgType::TfMessage) => {
                if contents.tf_problem.is_some() {
                    continue;
                }
                match decode_tf(&message.data) {
                    Ok(transforms) if contents.n_transforms + transforms.len() <= MAX_TRANSFORMS => {
                        contents.n_transforms += transforms.len();
                        for transform in transforms {
                            let edge = contents
                                .tf
                                .entry((transform.header.frame_id.clone(), transform.child_frame_id.clone()))
                                .or_default();
                            if !edge.topics.iter().any(|t| t == topic) {
                                edge.topics.push(topic.to_owned());
                            }
                            let [x, y, z] = transform.translation;
                            let [qx, qy, qz, qw] = transform.rotation_xyzw;
                            edge.samples.push(Sample {
                                stamp_ns: transform.header.stamp.nanos(),
                                log_ns,
                                index,
                                values: [x, y, z, qx, qy, qz, qw],
                            });
                        }
                    }
                    Ok(_) => {
                        contents.tf_problem = Some(bad(format!(
                            "more than {MAX_TRANSFORMS} transforms; cut the bag shorter"
                        )))
                    }
                    Err(err) => contents.tf_problem = Some(bad(not_decoded(MsgType::TfMessage, &err, &message.data))),
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Why a message of `kind` could not be decoded, and what its bytes are if they decode exactly
/// as another type skillc reads (a PoseStamped recorded under a WrenchStamped schema).
fn not_decoded(kind: MsgType, err: &super::cdr::CdrError, data: &[u8]) -> String {
    let is = [
        (MsgType::PoseStamped, PoseStamped::decode(data).is_ok()),
        (MsgType::WrenchStamped, WrenchStamped::decode(data).is_ok()),
        (MsgType::TfMessage, decode_tf(data).is_ok()),
    ]
    .into_iter()
    .find(|(other, decodes)| *other != kind && *decodes);
    let what = match is {
        Some((other, _)) => format!(
            "its bytes read exactly as a {}, so the topic carries another type than its schema names: re-record it with its real type",
            other.schema_name()
        ),
        None => "the message is corrupt or of another type".to_owned(),
    };
    format!("not a {} in CDR: {err}; {what}", kind.schema_name())
}

/// The `mcap` crate's error for the file `file` after `n_in_file` of its messages, the last on
/// `last`: a CRC that does not match is said as such, with where.
fn mcap_error(
    file: &str,
    source: mcap::McapError,
    n_in_file: u64,
    last: Option<(usize, u64)>,
    contents: &Contents,
) -> BagError {
    let crc = |section: &'static str, saved: u32, calculated: u32, place: String| BagError::Crc {
        file: file.to_owned(),
        section,
        saved,
        calculated,
        place,
    };
    match source {
        mcap::McapError::BadChunkCrc { saved, calculated } => {
            let place = match last {
                None => ", the file's first chunk of messages".to_owned(),
                Some((topic, index)) => format!(
                    ", the chunk after message {n_in_file} of the file (`{}` message {index}, counting from 1)",
                    contents.topics[topic].topic
                ),
            };
            crc("a chunk", saved, calculated, place)
        }
        mcap::McapError::BadDataCrc { saved, calculated } => crc("the data section", saved, calculated, String::new()),
        mcap::McapError::BadSummaryCrc { saved, calculated } => {
            crc("the summary section", saved, calculated, String::new())
        }
        source => BagError::Mcap {
            file: file.to_owned(),
            messages: n_in_file,
            source,
        },
    }
}

fn list<const N: usize>(streams: &[Stream<N>]) -> String {
    streams
        .iter()
        .map(|s| format!("`{}` ({} messages)", s.topic, s.samples.len()))
        .collect::<Vec<_>>()
        .join(", ")
}

fn not_cdr_note(contents: &Contents) -> String {
    if contents.not_cdr.is_empty() {
        return String::new();
    }
    let topics: Vec<String> = contents
        .not_cdr
        .iter()
        .map(|(topic, encoding)| format!("`{topic}` ({encoding})"))
        .collect();
    format!("; topics not in CDR were skipped: {}", topics.join(", "))
}

/// Why `--pose-topic NAME` (`flag`) cannot be the `kind` stream: the topic's schema is another
/// type (named with the expected one), it is not CDR, or the bag has no such topic.
fn wrong_topic(contents: &Contents, flag: &str, name: &str, kind: MsgType, candidates: &str) -> String {
    let expected = kind.schema_name();
    let candidates = if candidates.is_empty() { "none" } else { candidates };
    if let Some((_, encoding)) = contents.not_cdr.iter().find(|(topic, _)| topic == name) {
        return format!(
            "{flag} `{name}` holds `{encoding}` messages, not CDR: skillc reads ROS 2's CDR only; the bag's {expected} topics in CDR: {candidates}"
        );
    }
    match contents.schema_of(name) {
        Some(schema) => format!(
            "{flag} `{name}` has schema {}, not the expected `{expected}`: choose a topic of that type (the bag's: {candidates})",
            schema_label(schema)
        ),
        None => format!(
            "{flag} `{name}` is not a topic of the bag; its {expected} topics: {candidates}; its other topics: {}",
            contents.other_topics(kind)
        ),
    }
}

type PoseChoice = (String, String, Option<String>, Vec<Sample<7>>);

/// The pose samples: from `--pose-topic`, from TF when `--tf-parent`/`--tf-child` is given, else
/// the one PoseStamped topic, else the one moving TF edge. Returns the source's name, the parent
/// frame, the child frame (TF only) and the samples.
fn choose_pose(file: &str, contents: &Contents, options: &BagOptions) -> Result<PoseChoice, BagError> {
    let topics_error = |reason: String| BagError::Topics {
        file: file.to_owned(),
        reason,
    };
    let use_tf = options.tf_parent.is_some() || options.tf_child.is_some();
    let stream = match &options.pose_topic {
        Some(name) => match contents.poses.iter().find(|s| &s.topic == name) {
            Some(stream) => Some(stream),
            None if contents.tf_topics.contains(name) => None,
            None => {
                return Err(topics_error(wrong_topic(
                    contents,
                    "--pose-topic",
                    name,
                    MsgType::PoseStamped,
                    &list(&contents.poses),
                )))
            }
        },
        None if use_tf => None,
        None => match contents.poses.as_slice() {
            [only] => Some(only),
            [] => None,
            many => {
                return Err(topics_error(format!(
                    "{} geometry_msgs/msg/PoseStamped topics: {}; choose one with --pose-topic",
                    many.len(),
                    list(many)
                )))
            }
        },
    };
    if let Some(stream) = stream {
        if let Some(problem) = &stream.problem {
            return Err(problem.error());
        }
        if stream.samples.len() < 2 {
            return Err(topics_error(format!(
                "pose topic `{}` has {} message(s), at least 2 are needed",
                stream.topic,
                stream.samples.len()
            )));
        }
        return Ok((
            format!("topic `{}`", stream.topic),
            stream.frame_id.clone().unwrap_or_default(),
            None,
            stream.samples.clone(),
        ));
    }
    // TF.
    if let Some(problem) = &contents.tf_problem {
        return Err(problem.error());
    }
    let edges: Vec<(&(String, String), &TfEdge)> = contents
        .tf
        .iter()
        .filter(|((parent, child), _)| {
            options.tf_parent.as_ref().is_none_or(|p| p == parent)
                && options.tf_child.as_ref().is_none_or(|c| c == child)
        })
        .filter(|(_, edge)| options.pose_topic.as_ref().is_none_or(|t| edge.topics.contains(t)))
        .collect();
    let describe = |edges: &[(&(String, String), &TfEdge)]| {
        edges
            .iter()
            .map(|((parent, child), edge)| format!("`{parent}` → `{child}` ({} samples)", edge.samples.len()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let moving: Vec<_> = edges
        .iter()
        .copied()
        .filter(|(_, edge)| edge.samples.len() >= 2)
        .collect();
    let chosen = match (moving.as_slice(), use_tf) {
        ([one], _) => *one,
        ([], _) if contents.tf.is_empty() && contents.poses.is_empty() => {
            return Err(topics_error(format!(
                "no tool pose: the file has no geometry_msgs/msg/PoseStamped topic and no tf2_msgs/msg/TFMessage topic{}",
                not_cdr_note(contents)
            )))
        }
        ([], _) => {
            let all: Vec<_> = contents.tf.iter().collect();
            return Err(topics_error(format!(
                "no TF transform{}{} with at least 2 samples; the file's transforms: {}",
                options.tf_parent.as_ref().map(|p| format!(" from `{p}`")).unwrap_or_default(),
                options.tf_child.as_ref().map(|c| format!(" to `{c}`")).unwrap_or_default(),
                if all.is_empty() { "none".to_owned() } else { describe(&all) }
            )))
        }
        (many, _) => {
            return Err(topics_error(format!(
                "{} TF transforms could be the tool's pose: {}; choose one with --tf-parent and --tf-child (only a direct transform is read, not a chain)",
                many.len(),
                describe(many)
            )))
        }
    };
    let ((parent, child), edge) = chosen;
    Ok((
        format!("TF `{parent}` → `{child}` on `{}`", edge.topics.join("`, `")),
        parent.clone(),
        Some(child.clone()),
        edge.samples.clone(),
    ))
}

/// The wrench stream: `--wrench-topic`, else the one WrenchStamped topic.
fn choose_wrench<'c>(file: &str, contents: &'c Contents, options: &BagOptions) -> Result<&'c Stream<6>, BagError> {
    let topics_error = |reason: String| BagError::Topics {
        file: file.to_owned(),
        reason,
    };
    let stream = match &options.wrench_topic {
        Some(name) => contents.wrenches.iter().find(|s| &s.topic == name).ok_or_else(|| {
            topics_error(wrong_topic(
                contents,
                "--wrench-topic",
                name,
                MsgType::WrenchStamped,
                &list(&contents.wrenches),
            ))
        })?,
        None => match contents.wrenches.as_slice() {
            [only] => only,
            [] => {
                return Err(topics_error(format!(
                    "no wrench: the file has no geometry_msgs/msg/WrenchStamped topic; its other topics: {}{}",
                    contents.other_topics(MsgType::WrenchStamped),
                    not_cdr_note(contents)
                )))
            }
            many => {
                return Err(topics_error(format!(
                    "{} geometry_msgs/msg/WrenchStamped topics: {}; choose one with --wrench-topic",
                    many.len(),
                    list(many)
                )))
            }
        },
    };
    if let Some(problem) = &stream.problem {
        return Err(problem.error());
    }
    if stream.samples.is_empty() {
        return Err(topics_error(format!("wrench topic `{}` has no messages", stream.topic)));
    }
    Ok(stream)
}

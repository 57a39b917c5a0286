//! ROS 2 interop through MCAP files (the format of ROS 2 bags): reading a demonstration from a
//! bag ([`read_demo`]) and writing a run log or a demonstration as one ([`write_run_log`],
//! [`write_demo`]), with the CDR encoding of the few message types involved written here
//! ([`cdr`], [`msgs`]). The MCAP parts need the `mcap` cargo feature (on by default); the
//! CDR parts do not.
//!
//! Messages are CDR (`message_encoding` `cdr`); schemas are `ros2msg` definitions, so Foxglove
//! and `ros2 bag play` open what is written here.

use std::path::Path;

#[cfg(feature = "mcap")]
mod records;
#[cfg(feature = "mcap")]
use crate::{cdr, msgs};
#[cfg(feature = "mcap")]
mod read;
#[cfg(feature = "mcap")]
mod write;

#[cfg(feature = "mcap")]
pub use read::{read_demo, BagDemo, MAX_RECORD_BYTES, MAX_SAMPLES, MAX_TRANSFORMS};
#[cfg(feature = "mcap")]
pub use write::{
    write_demo, write_run_log, RobotDescription, RunLogTopics, RunLogWriter, DEMO_POSE_TOPIC, DEMO_WRENCH_TOPIC,
    FORCE_ARROW_MIN_N, FORCE_ARROW_M_PER_N, TF_PERIOD_TICKS,
};

/// Which topics of a bag to read a demonstration from; `None` finds them by type.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BagOptions {
    /// The `geometry_msgs/PoseStamped` topic with the tool (flange) pose in the base frame.
    pub pose_topic: Option<String>,
    /// The `geometry_msgs/WrenchStamped` topic.
    pub wrench_topic: Option<String>,
    /// TF: the base frame (the transform's `header.frame_id`).
    pub tf_parent: Option<String>,
    /// TF: the tool frame (the transform's `child_frame_id`).
    pub tf_child: Option<String>,
}

/// Whether `path` names a ROS 2 bag: an MCAP file (its extension is `.mcap`, any case) or a
/// rosbag2 folder (a folder with a `metadata.yaml`). What a file holds is not looked at here:
/// [`misnamed_csv`] and the bag reader compare it with the name.
pub fn is_mcap(path: &Path) -> bool {
    path.extension().is_some_and(|ext| ext.eq_ignore_ascii_case("mcap"))
        || (path.is_dir() && path.join("metadata.yaml").is_file())
}

/// The 8 bytes an MCAP file starts and ends with: `0x89`, `MCAP`, the format version `0`, CR LF.
pub const MCAP_MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// What a file's first bytes say it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Content {
    /// An MCAP file (it starts with [`MCAP_MAGIC`]).
    Mcap,
    /// Nothing.
    Empty,
    /// UTF-8 text; its first line (at most 40 characters).
    Text(String),
    /// An SQLite database: rosbag2's older storage (`.db3`).
    Sqlite,
    /// A ROS 1 bag (`#ROSBAG V2.0`).
    Ros1Bag,
    /// A compressed file: the compressor's name (`zstd`, `gzip`, `lz4`, `zip`).
    Compressed(&'static str),
    /// Anything else: its first bytes (at most 8).
    Binary(Vec<u8>),
}

impl Content {
    /// What the content is, for a message: `text (it starts `t,x,y`)`.
    pub fn describe(&self) -> String {
        match self {
            Content::Mcap => "an MCAP file (a ROS 2 bag)".into(),
            Content::Empty => "empty".into(),
            Content::Text(line) => format!("text (it starts `{line}`)"),
            Content::Sqlite => "an SQLite database (a rosbag2 bag in the older `sqlite3` storage, `.db3`)".into(),
            Content::Ros1Bag => "a ROS 1 bag".into(),
            Content::Compressed(how) => format!("{how}-compressed"),
            Content::Binary(start) => {
                let hex: Vec<String> = start.iter().map(|b| format!("{b:02x}")).collect();
                format!("binary data of no format skillc knows (it starts `{}`)", hex.join(" "))
            }
        }
    }
}

/// Reads the first bytes of the file at `path` and says what they are.
pub fn sniff(path: &Path) -> std::io::Result<Content> {
    use std::io::Read as _;
    let mut head = Vec::with_capacity(512);
    std::fs::File::open(path)?.take(512).read_to_end(&mut head)?;
    Ok(sniff_bytes(&head))
}

/// What the first bytes of a file (up to 512 of them) say it is.
pub fn sniff_bytes(head: &[u8]) -> Content {
    const SIGNATURES: [(&[u8], Content); 7] = [
        (MCAP_MAGIC, Content::Mcap),
        (b"SQLite format 3\0", Content::Sqlite),
        (b"#ROSBAG V", Content::Ros1Bag),
        (&[0x28, 0xb5, 0x2f, 0xfd], Content::Compressed("zstd")),
        (&[0x1f, 0x8b], Content::Compressed("gzip")),
        (&[0x04, 0x22, 0x4d, 0x18], Content::Compressed("lz4")),
        (b"PK\x03\x04", Content::Compressed("zip")),
    ];
    if head.is_empty() {
        return Content::Empty;
    }
    if let Some((_, content)) = SIGNATURES.iter().find(|(magic, _)| head.starts_with(magic)) {
        return content.clone();
    }
    // Text: UTF-8 (but for a character the 512 bytes cut) without control characters.
    let text = match std::str::from_utf8(head) {
        Ok(text) => text,
        Err(err) if head.len() - err.valid_up_to() < 4 && err.error_len().is_none() => {
            std::str::from_utf8(&head[..err.valid_up_to()]).unwrap_or_default()
        }
        Err(_) => "",
    };
    let is_text = !text.is_empty() && !text.chars().any(|c| c.is_control() && !matches!(c, '\t' | '\r' | '\n'));
    if is_text {
        let line = text.trim_start_matches('\u{feff}').lines().next().unwrap_or_default();
        return Content::Text(line.chars().take(40).collect());
    }
    Content::Binary(head.iter().take(8).copied().collect())
}

/// Refuses a demonstration read as CSV (it is not named `.mcap`) whose content is a bag: an MCAP
/// file, a ROS 1 bag or an SQLite rosbag2 file, naming what it is and what to do. `None` for
/// anything else, the CSV reader's to judge (and for a file that cannot be read: the CSV
/// reader says why).
pub fn misnamed_csv(path: &Path) -> Option<String> {
    let file = path.display();
    let content = sniff(path).ok()?;
    let what = content.describe();
    match content {
        Content::Mcap => Some(format!(
            "`{file}` is {what}, not CSV: rename it to `{}` (skillc reads a bag by its `.mcap` extension)",
            path.with_extension("mcap").display()
        )),
        Content::Sqlite | Content::Ros1Bag => Some(format!(
            "`{file}` is {what}, not CSV: convert it to MCAP (`mcap convert {file} {}`) and learn from that",
            path.with_extension("mcap").display()
        )),
        _ => None,
    }
}

/// Problems reading or writing an MCAP file. Messages are counted from 1 on their topic.
#[cfg(feature = "mcap")]
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BagError {
    /// The file could not be opened or read.
    #[error("cannot read `{file}`: {source}")]
    Io {
        /// Path of the file.
        file: String,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file's content is not MCAP: `reason` says what it is and what to do.
    #[error("`{file}` {reason}")]
    NotMcap {
        /// Path of the file.
        file: String,
        /// ``is text, not MCAP …``.
        reason: String,
    },
    /// A record's declared size does not fit the file, found before anything was allocated.
    #[error("`{file}`, byte {offset}: {reason}")]
    Corrupt {
        /// Path of the file.
        file: String,
        /// Where the record starts in the file.
        offset: u64,
        /// What is wrong and what to do.
        reason: String,
    },
    /// A CRC the file stores does not match the bytes it covers.
    #[error("`{file}`: {section}'s stored CRC {saved:08x} does not match its contents (CRC {calculated:08x}){place}: the file is corrupt, so none of it is used; copy or export it again")]
    Crc {
        /// Path of the file.
        file: String,
        /// `a chunk`, `the data section`, `the summary section`.
        section: &'static str,
        /// The CRC the file stores.
        saved: u32,
        /// The CRC of the bytes.
        calculated: u32,
        /// Where: ``, the chunk after message 24 of the file (`/wrench` message 12, counting from 1)``.
        place: String,
    },
    /// A folder given as a demonstration that is no rosbag2 bag at all (no `metadata.yaml`):
    /// a path given wrongly, as any folder where a file is expected.
    #[error("`{dir}` is a folder without `metadata.yaml`, so not a rosbag2 bag{hint}")]
    NotABag {
        /// Path of the folder.
        dir: String,
        /// What to pass instead: ``: pass the bag file `x/take.mcap` itself``.
        hint: String,
    },
    /// A rosbag2 folder skillc cannot read.
    #[error("`{dir}` {reason}")]
    Folder {
        /// Path of the folder.
        dir: String,
        /// What is wrong and what to do: ``is a rosbag2 bag stored as `sqlite3` …``.
        reason: String,
    },
    /// The file is not MCAP, or its records are corrupt (after `messages` good messages).
    #[error("`{file}` is not a readable MCAP file (after {messages} message(s)): {source}: it is corrupt; export it again, or recover what it holds with `mcap recover`")]
    Mcap {
        /// Path of the file.
        file: String,
        /// Messages read before the problem.
        messages: u64,
        /// What the `mcap` crate found.
        #[source]
        source: mcap::McapError,
    },
    /// One message cannot be used.
    #[error("`{file}`, {place}, message {index} (counting from 1): {reason}")]
    Message {
        /// Path of the file.
        file: String,
        /// ``topic `/pose` `` or ``TF `base` → `tool` on `/tf` ``.
        place: String,
        /// The message's index on its topic, from 1.
        index: u64,
        /// What is wrong.
        reason: String,
    },
    /// The topics needed are absent or ambiguous; the message lists the candidates.
    #[error("`{file}`: {reason}")]
    Topics {
        /// Path of the file.
        file: String,
        /// What is missing or ambiguous, and the candidates.
        reason: String,
    },
    /// Writing MCAP failed (in memory; the file is written afterwards).
    #[error("cannot encode MCAP: {0}")]
    Write(#[source] mcap::McapError),
}

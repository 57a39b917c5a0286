//! ROS 2 interop through MCAP files (the format of ROS 2 bags): reading a demonstration from a
//! bag ([`read_demo`]) and writing a run log or a demonstration as one ([`write_run_log`],
//! [`write_demo`]), with the CDR encoding of the few message types involved written here
//! ([`cdr`], [`msgs`]). The MCAP parts need the `mcap` cargo feature (on by default); the
//! CDR parts do not.
//!
//! Messages are CDR (`message_encoding` `cdr`); schemas are `ros2msg` definitions, so Foxglove
//! and `ros2 bag play` open what is written here.

pub mod cdr;
pub mod msgs;
#[cfg(feature = "mcap")]
mod read;
#[cfg(feature = "mcap")]
mod write;

#[cfg(feature = "mcap")]
pub use read::{read_demo, BagDemo, MAX_RECORD_BYTES, MAX_SAMPLES, MAX_TRANSFORMS};
#[cfg(feature = "mcap")]
pub use write::{write_demo, write_run_log, RunLogTopics, DEMO_POSE_TOPIC, DEMO_WRENCH_TOPIC};

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

/// Whether `path` names an MCAP file (its extension is `.mcap`, any case).
pub fn is_mcap(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|ext| ext.eq_ignore_ascii_case("mcap"))
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
    /// The file is not MCAP, or its records are corrupt (after `messages` good messages).
    #[error("`{file}` is not a readable MCAP file (after {messages} message(s)): {source}")]
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
    #[error("`{file}`, {place}, message {index}: {reason}")]
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

//! The plant and the run in separate processes or machines, over Zenoh on the wire format of ROS 2's
//! `rmw_zenoh`: [`serve()`] serves a [`Plant`](skill_robot::plant::Plant) (the simulated arm) and
//! [`RemotePlant`] is a `Plant` whose arm is on the other side, so the skill engine and its
//! controller run unchanged against either.
//!
//! Topics (ROS 2 names and types; the key expressions, attachments and liveliness tokens as
//! `rmw_zenoh` forms them, [`skill_ros::rmw`]):
//!
//! | topic | type | from → to |
//! |---|---|---|
//! | `/joint_states` | `sensor_msgs/msg/JointState` | plant → anyone: URDF joint names, position, velocity, effort = applied torque |
//! | `/wrench` | `geometry_msgs/msg/WrenchStamped` | plant → anyone: the wrist sensor's wrench in its frame |
//! | `/joint_effort_commands` | `std_msgs/msg/Float64MultiArray` | controller → plant: joint torques, URDF order |
//! | `/skillc/state` | `std_msgs/msg/Float64MultiArray` | plant → run: the whole observation with its tick ([`wire::State`]) |
//!
//! and two queries: `<domain>/skillc/plant/start`, with which a run starts its session (it says
//! `lockstep` or `realtime` and the plant answers with its state), and
//! `<domain>/skillc/plant/witness`, which the plant answers with what its contact witness found
//! since the last time it was asked (a [`ContactAudit`](skill_robot::plant::ContactAudit) as JSON,
//! `null` for a plant without one).
#![warn(missing_docs)]

pub mod node;
pub mod remote;
pub mod serve;
pub mod wire;

pub use remote::{LinkMode, LoopStats, RemoteOptions, RemotePlant};
pub use serve::{serve, ServeOptions, ServeSummary};

/// Joint states, for ROS 2 tools.
pub const JOINT_STATES: &str = "/joint_states";
/// The wrist sensor's wrench, for ROS 2 tools.
pub const WRENCH: &str = "/wrench";
/// Torque commands.
pub const COMMANDS: &str = "/joint_effort_commands";
/// The plant's whole state each tick, for the run.
pub const STATE: &str = "/skillc/state";

/// The key expression of the start query on `domain`.
pub fn start_key(domain: u32) -> String {
    format!("{domain}/skillc/plant/start")
}

/// The key expression of the witness query on `domain`.
pub fn witness_key(domain: u32) -> String {
    format!("{domain}/skillc/plant/witness")
}

/// Why the link between the plant and the run failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TransportError {
    /// An endpoint that is not `tcp/HOST:PORT`.
    #[error("endpoint `{endpoint}`: {reason}")]
    Endpoint {
        /// As given.
        endpoint: String,
        /// What is wrong with it.
        reason: String,
    },
    /// Zenoh refused something.
    #[error("{what}: {reason}")]
    Zenoh {
        /// What was being done.
        what: String,
        /// Zenoh's words.
        reason: String,
    },
    /// No plant answered.
    #[error(
        "no plant answered at `{endpoint}` (domain {domain}) within {waited_s} s: start one there with `skillc plant \
         --scene SCENE --listen {endpoint}`"
    )]
    NoPlant {
        /// Where the run looked.
        endpoint: String,
        /// The ROS domain.
        domain: u32,
        /// How long it waited.
        waited_s: f64,
    },
    /// The plant's messages do not fit the run's robot.
    #[error("the plant at `{endpoint}` {reason}")]
    Mismatch {
        /// Where it is.
        endpoint: String,
        /// What does not fit.
        reason: String,
    },
    /// The plant failed while serving.
    #[error(transparent)]
    Plant(#[from] skill_robot::plant::PlantError),
}

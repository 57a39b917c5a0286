//! The `skillc` command line as a library: argument types, the commands' file IO and rendering,
//! and exit codes. What the commands share with the eval harness is in `skill-kit`; the eval
//! harness (`skill-eval`), the language server (`skill-language-server`) and ROS 2 bags
//! (`skill_ros::bag`) are crates of their own.
//!
//! `main.rs` only parses arguments and calls [`run`]; tests drive the same functions.

pub mod cli;
pub mod identify_cmd;
pub mod learn_cmd;
pub mod link;
pub mod robot_cmd;
pub mod run_cmd;
pub mod run_log;

pub use cli::{run, Cli};

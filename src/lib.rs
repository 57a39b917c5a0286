//! The `skillc` command-line tool as a library: argument types, file IO, rendering and exit codes.
//!
//! `main.rs` only parses arguments and calls [`run`]; tests drive the same functions.

pub mod atomic;
pub mod cli;
pub mod defaults;
pub mod eval;
pub mod frontend;
pub mod identify_cmd;
pub mod learn_cmd;
pub mod limits;
pub mod link;
pub mod load;
pub mod lsp;
pub mod out;
pub mod plot;
pub mod profile;
pub mod render;
pub mod robot_cmd;
pub mod ros;
pub mod run_cmd;
pub mod run_log;
pub mod scene_view;

pub use cli::{run, Cli};

//! The `skillc` command-line tool.
fn main() {}

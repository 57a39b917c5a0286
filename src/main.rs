//! The `skillc` binary: parses the command line and hands over to [`skillc::run`].

use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = skillc::Cli::parse();
    skillc::run(cli)
}

//! The `skillc` binary: parses the command line and hands over to [`skillc::run`].

use clap::Parser;

fn main() -> std::process::ExitCode {
    skillc::out::install_print_panic_backstop();
    let cli = skillc::Cli::parse();
    skillc::run(cli)
}

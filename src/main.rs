//! The `skillc` binary: parses the command line and hands over to [`skillc::run`].

use clap::Parser;

fn main() -> std::process::ExitCode {
    skill_kit::out::install_print_panic_backstop();
    // Temporaries are removed on SIGINT/SIGTERM/SIGHUP (exit 130/143/129); without the handler
    // a signal would leave them behind, so not having it is worth a word, not a refusal to run.
    if let Err(err) = skill_kit::atomic::install_signal_cleanup() {
        eprintln!("warning: cannot handle signals ({err}); an interrupt may leave temporary files");
    }
    let cli = skillc::Cli::parse();
    skillc::run(cli)
}

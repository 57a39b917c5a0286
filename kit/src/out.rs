//! Standard output for every command: one writer that treats a closed pipe as a quiet end
//! (exit 0, what `skillc rollout L.json | head` users expect) and any other write error (a full
//! disk, `> /dev/full`) as an IO error (exit 2) with a message, never a panic as `print!` would.

use std::io::Write;

use crate::load::Failure;

/// Writes `text` to standard output and flushes it.
///
/// `Err(Failure::Closed)` when the reader went away (report it: exit 0, no message);
/// `Err(Failure::Usage)` for any other write error.
pub fn print(text: &str) -> Result<(), Failure> {
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(failure)
}

/// The failure for a write error on standard output.
pub fn failure(err: std::io::Error) -> Failure {
    if err.kind() == std::io::ErrorKind::BrokenPipe {
        Failure::Closed
    } else {
        Failure::Usage(format!("cannot write to standard output: {err}"))
    }
}

/// Writes `text` to standard output, for commands that return an exit code: `Err(code)` when
/// it could not (0 for a closed pipe, 2 otherwise, with the message printed).
pub fn print_or_code(text: &str) -> Result<(), u8> {
    print(text).map_err(Failure::report)
}

/// A backstop for code that still prints with `print!`/`println!`/`eprintln!` (which panic when
/// the stream is closed or full): a panic whose message says printing to stdout failed ends the
/// process with exit 0 (closed pipe) or 2 (other error, with a message) instead of 101; one
/// that says printing to stderr failed ends it with 2. Installed once by `main`; other panics
/// keep the default report.
pub fn install_print_panic_backstop() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(reason) = message.strip_prefix("failed printing to stdout: ") {
            if reason.contains("Broken pipe") || reason.contains("os error 32") {
                std::process::exit(0);
            }
            eprintln!("error: cannot write to standard output: {reason}");
            std::process::exit(2);
        }
        if message.starts_with("failed printing to stderr") {
            // Nowhere to say anything: the exit code tells.
            std::process::exit(2);
        }
        default(info);
    }));
}

/// How much a command says on standard error besides errors and diagnostics (`--quiet`,
/// `--verbose`). Standard output (the data a command produces) is the same at every level.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Verbosity {
    /// Errors and diagnostics only: no summaries, no "wrote" lines.
    Quiet,
    /// The default.
    #[default]
    Normal,
    /// Also what was read and written, and timings.
    Verbose,
}

impl Verbosity {
    /// From the global flags (clap makes them exclusive).
    pub fn from_flags(quiet: bool, verbose: bool) -> Self {
        match (quiet, verbose) {
            (true, _) => Verbosity::Quiet,
            (false, true) => Verbosity::Verbose,
            (false, false) => Verbosity::Normal,
        }
    }

    /// `--quiet` was given.
    pub fn quiet(self) -> bool {
        self == Verbosity::Quiet
    }

    /// `--verbose` was given.
    pub fn verbose(self) -> bool {
        self == Verbosity::Verbose
    }

    /// Prints `message` to standard error unless quiet.
    pub fn note(self, message: impl std::fmt::Display) {
        if !self.quiet() {
            eprintln!("{message}");
        }
    }

    /// Prints `message` to standard error when verbose.
    pub fn detail(self, message: impl std::fmt::Display) {
        if self.verbose() {
            eprintln!("{message}");
        }
    }
}

//! The command line: clap definitions and one function per subcommand, each returning an exit code.
//!
//! Exit codes: 0 success (warnings allowed), 1 problems found in the input (diagnostics,
//! unformatted files, a failed skill), 2 usage or IO errors.

use clap::{CommandFactory, Parser, Subcommand, ValueEnum};
use skill_compiler::graph::GraphFormat;
use skill_kit::load::Failure;
use skill_kit::out::{self, Verbosity};
use skill_kit::{atomic, frontend, render};
use std::fmt::Write as _;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// skillc: teach a robot a contact skill from one demonstration.
#[derive(Debug, Parser)]
#[command(name = "skillc", version, about, long_about = None, after_help = EXAMPLES)]
pub struct Cli {
    /// Print only errors and diagnostics: no summaries, no "wrote" lines.
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    pub quiet: bool,
    /// Also print what was read and written, and timings.
    #[arg(short, long, global = true)]
    pub verbose: bool,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

const EXAMPLES: &str = "Examples:
  skillc check stdlib-skills/*.skill
  skillc compile stdlib-skills/press.skill -o press.ir.json
  skillc graph stdlib-skills/touch.skill --format mermaid
  skillc fmt --check stdlib-skills/*.skill";

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check `.skill` files and report every problem.
    #[command(after_help = "Examples:
  skillc check press.skill
  skillc check --format json stdlib-skills/*.skill
  skillc check --deny-warnings my.skill")]
    Check {
        /// The files to check.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// `human` for people, `json` for one JSON object per diagnostic and line.
        #[arg(long, value_enum, default_value_t = Format::Human)]
        format: Format,
        /// Treat warnings as errors.
        #[arg(long)]
        deny_warnings: bool,
    },
    /// Compile a `.skill` file to its IR (JSON).
    #[command(after_help = "Examples:
  skillc compile stdlib-skills/slide.skill
  skillc compile examples/tasks/inspect_and_press.skill -o task.ir.json")]
    Compile {
        /// The file to compile.
        file: PathBuf,
        /// Write the IR here (atomically) instead of to standard output.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Draw the state machines of a `.skill` file.
    #[command(after_help = "Examples:
  skillc graph stdlib-skills/touch.skill | dot -Tsvg > touch.svg
  skillc graph stdlib-skills/press.skill --format mermaid")]
    Graph {
        /// The file to draw.
        file: PathBuf,
        /// The output language.
        #[arg(long, value_enum, default_value_t = GraphKind::Dot)]
        format: GraphKind,
        /// Write here (atomically) instead of to standard output.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Rewrite `.skill` files in the canonical layout.
    #[command(after_help = "Examples:
  skillc fmt my.skill
  skillc fmt --check stdlib-skills/*.skill")]
    Fmt {
        /// The files to format in place.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Only report files that are not formatted; change nothing.
        #[arg(long)]
        check: bool,
    },
    /// Learn a skill template's features from one demonstration.
    #[command(after_help = "Examples:
  skillc learn stdlib-skills/press.skill examples/demos/press.csv -o press.learned.json
  skillc learn my.skill demo.csv -o my.learned.json --skill wipe --lowpass 20
  skillc learn stdlib-skills/press.skill press.mcap -o press.learned.json --pose-topic /tool_pose --wrench-topic /wrench
  skillc learn stdlib-skills/press.skill bag.mcap -o press.learned.json --tf-parent base --tf-child tool0")]
    Learn(crate::learn_cmd::LearnArgs),
    /// Which standard templates a demonstration fits, ranked, with the evidence for each.
    #[command(after_help = "Examples:
  skillc identify examples/demos/wipe.csv
  skillc identify demo.csv --format json")]
    Identify(crate::identify_cmd::IdentifyArgs),
    /// The kinematic rollout of a learned file's motions, in the demonstration's CSV columns.
    #[command(after_help = "Examples:
  skillc rollout press.learned.json -o press.rollout.csv
  skillc rollout slide.learned.json --goal-offset 0,0,-0.05")]
    Rollout(crate::learn_cmd::RolloutArgs),
    /// Reproduce a skill in simulation, in the demonstrated scene or a changed one.
    #[command(after_help = "Examples:
  skillc run stdlib-skills/slide.skill --demo examples/demos/slide.csv --scene examples/scenes/table.toml --set table.z=0.195
  skillc run stdlib-skills/press.skill --learned press.learned.json --scene examples/scenes/button.toml -o press.log.csv
  skillc run stdlib-skills/press.skill --learned press.learned.json --scene examples/scenes/button.toml -o press.log.mcap
  skillc run stdlib-skills/slide.skill --learned slide.learned.json --scene examples/scenes/table.toml --replay")]
    Run(crate::run_cmd::RunArgs),
    /// Serve the simulated arm of a scene to runs and ROS 2 tools in other processes, over Zenoh
    /// (docs/split.md).
    #[command(after_help = "Examples:
  skillc plant --scene examples/scenes/table.toml --listen tcp/127.0.0.1:7447
  skillc run stdlib-skills/slide.skill --demo examples/demos/slide.csv --scene examples/scenes/table.toml --plant tcp/127.0.0.1:7447 --lockstep
  skillc plant --scene examples/scenes/button.toml --set button.x=0.52 --listen tcp/0.0.0.0:7447 --domain 3")]
    Plant(crate::link::PlantArgs),
    /// Run the thesis's experiments: learn each skill, reproduce it in changed scenes beside the
    /// replay baseline, and write a report with tables and plots.
    #[command(after_help = "Examples:
  skillc eval                                  # the standard skills, demonstrations and scenes
  skillc eval --skill slide --out slide-report
  skillc eval --robot iiwa14                   # the same skills and scenes on the KUKA LBR iiwa 14
  skillc eval --trials my-trials.toml --threads 1")]
    Eval(skill_eval::EvalArgs),
    /// Inspect a robot description: its chain, and the tool pose, Jacobian and gravity torques at a configuration.
    #[command(after_help = "Examples:
  skillc robot examples/robots/lwr4.urdf
  skillc robot iiwa14 --q 0,0.5,0,-1.5,0,1.14,0    # a shipped robot by name (lwr4, iiwa14)
  skillc robot examples/robots/lwr4.urdf --tool probe_tip --q 0,-0.5,0,1.5,0,-1.14,0 --json")]
    Robot(crate::robot_cmd::RobotArgs),
    /// Write the shipped synthetic demonstrations (and their ground truth) of the standard skills.
    #[command(after_help = "Examples:
  skillc demos                      # rewrite examples/demos/
  skillc demos --check              # fail if the shipped files differ from the generator")]
    Demos {
        /// Where to write `<skill>.csv` and `<skill>.truth.json`.
        #[arg(long, default_value = "examples/demos")]
        out: PathBuf,
        /// Only compare with what is there; write nothing.
        #[arg(long)]
        check: bool,
    },
    /// Print an intermediate stage (the output format may change between versions).
    Dump {
        /// The stage to print.
        #[arg(long, value_enum, default_value_t = Stage::Ir)]
        stage: Stage,
        /// The file.
        file: PathBuf,
    },
    /// Print a shell completion script.
    #[command(after_help = "Examples:
  skillc completions bash > ~/.local/share/bash-completion/completions/skillc
  skillc completions zsh > ~/.zfunc/_skillc
  skillc completions fish > ~/.config/fish/completions/skillc.fish")]
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff), or write one page per command into a folder.
    #[command(after_help = "Examples:
  skillc man | man -l -
  skillc man --out ~/.local/share/man/man1")]
    Man {
        /// Write `skillc.1` and `skillc-<command>.1` here instead of printing `skillc.1`.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Run the language server on standard input and output, for editors (docs/editors.md).
    #[command(after_help = "Examples:
  skillc lsp                        # started by the editor, which talks to it over stdio")]
    Lsp,
}

/// Diagnostic output formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Rendered for people.
    Human,
    /// One JSON object per diagnostic and line.
    Json,
}

/// Graph output languages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GraphKind {
    /// Graphviz dot.
    Dot,
    /// Mermaid.
    Mermaid,
}

/// Stages `dump` can print.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Stage {
    /// The syntax tree.
    Ast,
    /// The IR.
    Ir,
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> ExitCode {
    let verbosity = Verbosity::from_flags(cli.quiet, cli.verbose);
    let code = match cli.command {
        Command::Check {
            files,
            format,
            deny_warnings,
        } => check(&files, format, deny_warnings, verbosity),
        Command::Compile { file, output } => compile(&file, output.as_deref()),
        Command::Graph { file, format, output } => graph(&file, format, output.as_deref()),
        Command::Fmt { files, check } => fmt(&files, check, verbosity),
        Command::Dump { stage, file } => dump(&file, stage),
        Command::Demos { out, check } => demos(&out, check, verbosity),
        Command::Learn(args) => crate::learn_cmd::run(&args, verbosity),
        Command::Identify(args) => crate::identify_cmd::run(&args, verbosity),
        Command::Rollout(args) => crate::learn_cmd::rollout(&args, verbosity),
        Command::Run(args) => crate::run_cmd::run(&args, verbosity),
        Command::Plant(args) => crate::link::plant(&args, verbosity),
        Command::Eval(args) => skill_eval::run(&args, verbosity),
        Command::Robot(args) => crate::robot_cmd::run(&args),
        Command::Completions { shell } => completions(shell),
        Command::Man { out } => man(out.as_deref(), verbosity),
        Command::Lsp => skill_language_server::run_stdio(),
    };
    ExitCode::from(code)
}

/// The command line's definition, for completions and the manual.
fn command() -> clap::Command {
    Cli::command()
}

fn completions(shell: clap_complete::Shell) -> u8 {
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut command(), "skillc", &mut script);
    print_or_code(&String::from_utf8_lossy(&script))
}

fn man_page(cmd: clap::Command) -> Result<Vec<u8>, std::io::Error> {
    let mut page = Vec::new();
    clap_mangen::Man::new(cmd).render(&mut page)?;
    Ok(page)
}

fn man(out: Option<&Path>, verbosity: Verbosity) -> u8 {
    let mut cmd = command();
    cmd.build();
    let Some(dir) = out else {
        return match man_page(cmd) {
            Ok(page) => print_or_code(&String::from_utf8_lossy(&page)),
            Err(err) => usage_error(format!("cannot render the manual: {err}")),
        };
    };
    if let Err(err) = std::fs::create_dir_all(dir) {
        return usage_error(format!("cannot create `{}`: {err}", dir.display()));
    }
    let mut pages = vec![("skillc.1".to_string(), cmd.clone())];
    for sub in cmd.get_subcommands().filter(|sub| sub.get_name() != "help") {
        // `build` named them `skillc-<command>` for display, which the page title uses.
        pages.push((
            format!("skillc-{}.1", sub.get_name()),
            sub.clone().version(env!("CARGO_PKG_VERSION")),
        ));
    }
    for (file, page) in pages {
        let path = dir.join(file);
        let written = man_page(page).and_then(|bytes| atomic::write(&path, &bytes));
        if let Err(err) = written {
            return usage_error(format!("cannot write `{}`: {err}", path.display()));
        }
        verbosity.detail(format_args!("wrote `{}`", path.display()));
    }
    verbosity.note(format_args!("wrote the manual pages into `{}`", dir.display()));
    0
}

/// Prints `text` to standard output; the exit code to return when that failed (0 for a closed
/// pipe, 2 otherwise), or 0.
fn print_or_code(text: &str) -> u8 {
    out::print_or_code(text).err().unwrap_or(0)
}

fn usage_error(message: impl std::fmt::Display) -> u8 {
    eprintln!("error: {message}");
    2
}

fn terminal_width() -> usize {
    std::env::var("COLUMNS")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(100)
}

/// Prints the diagnostics of a compilation to standard error.
fn print_diags(compilation: &skill_compiler::Compilation) {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let mut stderr = std::io::stderr().lock();
    // Standard error that is closed or full has nowhere to report to: the exit code tells.
    for diag in &compilation.diags {
        let _ = write!(stderr, "{}", render::human(diag, compilation, color, terminal_width()));
    }
}

fn check(files: &[PathBuf], format: Format, deny_warnings: bool, verbosity: Verbosity) -> u8 {
    let mut unreadable = 0;
    let (mut errors, mut warnings, mut allowed) = (0, 0, 0);
    for path in files {
        let compilation = match frontend::compile_path(path) {
            Ok(compilation) => compilation,
            Err(err) => {
                eprintln!("error: {err}");
                unreadable += 1;
                continue;
            }
        };
        let (e, w) = render::counts(&compilation.diags);
        errors += e;
        warnings += w;
        allowed += compilation.allowed;
        match format {
            Format::Human => print_diags(&compilation),
            Format::Json => {
                let mut lines = String::new();
                for diag in &compilation.diags {
                    let _ = writeln!(lines, "{}", render::json(diag, &compilation));
                }
                if let Err(failure) = out::print(&lines) {
                    return failure.report();
                }
            }
        }
        verbosity.detail(format_args!(
            "checked `{}`: {e} error(s), {w} warning(s)",
            path.display()
        ));
    }
    let checked = files.len() - unreadable;
    if format == Format::Human && !verbosity.quiet() && checked > 0 {
        let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
        let mut line = if errors + warnings == 0 {
            format!("checked {}: no problems", plural(checked, "file"))
        } else {
            format!(
                "checked {}: {}, {}",
                plural(checked, "file"),
                plural(errors, "error"),
                plural(warnings, "warning")
            )
        };
        if allowed > 0 {
            let _ = write!(line, " ({} allowed)", plural(allowed, "warning"));
        }
        if unreadable > 0 {
            let _ = write!(line, "; {} could not be read", plural(unreadable, "file"));
        }
        eprintln!("{line}");
    }
    if unreadable > 0 {
        2
    } else if errors > 0 || (deny_warnings && warnings > 0) {
        1
    } else {
        0
    }
}

/// Compiles a file for a command that needs its IR; prints diagnostics and returns the exit
/// code to use when there is no program.
fn compile_or_report(path: &Path) -> Result<skill_compiler::Compilation, u8> {
    let compilation = frontend::compile_path(path).map_err(usage_error)?;
    print_diags(&compilation);
    if compilation.program.is_none() {
        let (errors, _) = render::counts(&compilation.diags);
        eprintln!(
            "error: `{}` has {errors} error{}; nothing written",
            path.display(),
            if errors == 1 { "" } else { "s" }
        );
        return Err(1);
    }
    Ok(compilation)
}

fn emit(output: Option<&Path>, text: &str) -> u8 {
    match output {
        Some(path) => match atomic::write(path, text.as_bytes()) {
            Ok(()) => 0,
            Err(err) => usage_error(format!("cannot write `{}`: {err}", path.display())),
        },
        None => print_or_code(text),
    }
}

/// Refuses `-o` naming the input (or any file the input imports is left to the user).
fn refuse_input(output: Option<&Path>, input: &Path) -> Result<(), u8> {
    match output {
        Some(out) => atomic::refuse_inputs(out, "-o", &[input]).map_err(usage_error),
        None => Ok(()),
    }
}

fn compile(path: &Path, output: Option<&Path>) -> u8 {
    if let Err(code) = refuse_input(output, path) {
        return code;
    }
    let compilation = match compile_or_report(path) {
        Ok(compilation) => compilation,
        Err(code) => return code,
    };
    let program = compilation
        .program
        .as_ref()
        .expect("compile_or_report returns programs");
    match serde_json::to_string_pretty(program) {
        Ok(mut json) => {
            json.push('\n');
            emit(output, &json)
        }
        Err(err) => usage_error(format!("cannot serialise the IR: {err}")),
    }
}

fn graph(path: &Path, format: GraphKind, output: Option<&Path>) -> u8 {
    if let Err(code) = refuse_input(output, path) {
        return code;
    }
    let compilation = match compile_or_report(path) {
        Ok(compilation) => compilation,
        Err(code) => return code,
    };
    let program = compilation
        .program
        .as_ref()
        .expect("compile_or_report returns programs");
    let format = match format {
        GraphKind::Dot => GraphFormat::Dot,
        GraphKind::Mermaid => GraphFormat::Mermaid,
    };
    emit(output, &skill_compiler::graph::render(program, format))
}

fn fmt(files: &[PathBuf], check_only: bool, verbosity: Verbosity) -> u8 {
    let mut status = 0;
    for path in files {
        let name = path.to_string_lossy().replace('\\', "/");
        let bytes = match std::fs::read(path) {
            Ok(bytes) => bytes,
            Err(err) => {
                eprintln!("error: cannot read `{name}`: {err}");
                status = 2;
                continue;
            }
        };
        // The compiler reads past a byte order mark; the file keeps the one its editor wrote.
        let mark = if bytes.starts_with("\u{feff}".as_bytes()) {
            "\u{feff}"
        } else {
            ""
        };
        let source = match frontend::decode(&name, bytes) {
            Ok(source) => source,
            Err(invalid) => {
                let (source, diag) = *invalid;
                let compilation = skill_compiler::Compilation {
                    files: vec![source],
                    diags: vec![diag],
                    ast: Default::default(),
                    program: None,
                    allowed: 0,
                };
                print_diags(&compilation);
                status = status.max(1);
                continue;
            }
        };
        let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
        if !diags.is_empty() {
            let compilation = skill_compiler::Compilation {
                files: vec![source],
                diags,
                ast,
                program: None,
                allowed: 0,
            };
            print_diags(&compilation);
            eprintln!("error: `{name}` does not parse; not formatted");
            status = status.max(1);
            continue;
        }
        let formatted = format!("{mark}{}", skill_compiler::fmt::format(&source, &ast));
        if formatted.strip_prefix(mark) == Some(&*source.text) {
            verbosity.detail(format_args!("`{name}` is formatted"));
            continue;
        }
        let line = if check_only {
            status = status.max(1);
            format!("would reformat `{name}`\n")
        } else if let Err(err) = atomic::write(path, formatted.as_bytes()) {
            eprintln!("error: cannot write `{name}`: {err}");
            status = 2;
            continue;
        } else if verbosity.quiet() {
            continue;
        } else {
            format!("formatted `{name}`\n")
        };
        if let Err(failure) = out::print(&line) {
            return match failure {
                Failure::Closed => status,
                other => other.report(),
            };
        }
    }
    status
}

fn dump(path: &Path, stage: Stage) -> u8 {
    match stage {
        Stage::Ast => {
            let compilation = match frontend::compile_path(path) {
                Ok(compilation) => compilation,
                Err(err) => return usage_error(err),
            };
            print_diags(&compilation);
            match out::print_or_code(&format!("{:#?}\n", compilation.ast)) {
                Ok(()) => u8::from(compilation.has_errors()),
                Err(code) => code,
            }
        }
        Stage::Ir => compile(path, None),
    }
}

fn demos(out: &Path, check_only: bool, verbosity: Verbosity) -> u8 {
    use skill_runtime::demogen::{generate, to_csv, StdSkill};
    if !check_only {
        if let Err(err) = std::fs::create_dir_all(out) {
            return usage_error(format!("cannot create `{}`: {err}", out.display()));
        }
    }
    let mut status = 0;
    for skill in StdSkill::ALL {
        let demo = generate(skill, skill.default_seed());
        let truth = match serde_json::to_string_pretty(&demo.truth) {
            Ok(json) => json + "\n",
            Err(err) => return usage_error(format!("cannot serialise the ground truth: {err}")),
        };
        for (path, text) in [
            (out.join(format!("{}.csv", skill.name())), to_csv(&demo)),
            (out.join(format!("{}.truth.json", skill.name())), truth),
        ] {
            let line = if check_only {
                match std::fs::read_to_string(&path) {
                    Ok(existing) if existing == text => continue,
                    Ok(_) => {
                        status = 1;
                        format!("`{}` differs from the generator\n", path.display())
                    }
                    Err(err) => {
                        status = 1;
                        format!("`{}` cannot be read: {err}\n", path.display())
                    }
                }
            } else if let Err(err) = atomic::write(&path, text.as_bytes()) {
                return usage_error(format!("cannot write `{}`: {err}", path.display()));
            } else if verbosity.quiet() {
                continue;
            } else {
                format!("wrote `{}` ({} samples)\n", path.display(), demo.samples.len())
            };
            if let Err(code) = out::print_or_code(&line) {
                return code.max(status);
            }
        }
    }
    status
}

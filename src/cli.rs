//! The command line: clap definitions and one function per subcommand, each returning an exit code.
//!
//! Exit codes: 0 success (warnings allowed), 1 problems found in the input (diagnostics,
//! unformatted files, a failed skill), 2 usage or IO errors.

use crate::{atomic, frontend, render};
use clap::{Parser, Subcommand, ValueEnum};
use skill_compiler::graph::GraphFormat;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// skillc: teach a robot a contact skill from one demonstration.
#[derive(Debug, Parser)]
#[command(name = "skillc", version, about, long_about = None, after_help = EXAMPLES)]
pub struct Cli {
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
  skillc learn my.skill demo.csv -o my.learned.json --skill wipe --lowpass 20")]
    Learn(crate::learn_cmd::LearnArgs),
    /// The kinematic rollout of a learned file's motions, in the demonstration's CSV columns.
    #[command(after_help = "Examples:
  skillc rollout press.learned.json -o press.rollout.csv
  skillc rollout slide.learned.json --goal-offset 0,0,-0.05")]
    Rollout(crate::learn_cmd::RolloutArgs),
    /// Reproduce a skill in simulation, in the demonstrated scene or a changed one.
    #[command(after_help = "Examples:
  skillc run stdlib-skills/slide.skill --demo examples/demos/slide.csv --scene examples/scenes/table.toml --set table.z=0.195
  skillc run stdlib-skills/press.skill --learned press.learned.json --scene examples/scenes/button.toml -o press.log.csv
  skillc run stdlib-skills/slide.skill --learned slide.learned.json --scene examples/scenes/table.toml --replay")]
    Run(crate::run_cmd::RunArgs),
    /// Run the thesis's experiments: learn each skill, reproduce it in changed scenes beside the
    /// replay baseline, and write a report with tables and plots.
    #[command(after_help = "Examples:
  skillc eval                                  # the standard skills, demonstrations and scenes
  skillc eval --skill slide --out slide-report
  skillc eval --trials my-trials.toml --threads 1")]
    Eval(crate::eval::EvalArgs),
    /// Inspect a robot description: its chain, and the tool pose, Jacobian and gravity torques at a configuration.
    #[command(after_help = "Examples:
  skillc robot examples/robots/lwr4.urdf
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
    let code = match cli.command {
        Command::Check {
            files,
            format,
            deny_warnings,
        } => check(&files, format, deny_warnings),
        Command::Compile { file, output } => compile(&file, output.as_deref()),
        Command::Graph { file, format, output } => graph(&file, format, output.as_deref()),
        Command::Fmt { files, check } => fmt(&files, check),
        Command::Dump { stage, file } => dump(&file, stage),
        Command::Demos { out, check } => demos(&out, check),
        Command::Learn(args) => crate::learn_cmd::run(&args),
        Command::Rollout(args) => crate::learn_cmd::rollout(&args),
        Command::Run(args) => crate::run_cmd::run(&args),
        Command::Eval(args) => crate::eval::run(&args),
        Command::Robot(args) => match crate::robot_cmd::run(&args) {
            Ok(()) => 0,
            Err(err) => usage_error(err),
        },
    };
    ExitCode::from(code)
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
    for diag in &compilation.diags {
        let _ = write!(stderr, "{}", render::human(diag, compilation, color, terminal_width()));
    }
}

fn check(files: &[PathBuf], format: Format, deny_warnings: bool) -> u8 {
    let mut io_error = false;
    let (mut errors, mut warnings) = (0, 0);
    let mut stdout = std::io::stdout().lock();
    for path in files {
        let compilation = match frontend::compile_path(path) {
            Ok(compilation) => compilation,
            Err(err) => {
                eprintln!("error: {err}");
                io_error = true;
                continue;
            }
        };
        let (e, w) = render::counts(&compilation.diags);
        errors += e;
        warnings += w;
        match format {
            Format::Human => print_diags(&compilation),
            Format::Json => {
                for diag in &compilation.diags {
                    let _ = writeln!(stdout, "{}", render::json(diag, &compilation));
                }
            }
        }
    }
    if format == Format::Human {
        let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
        if errors + warnings == 0 && !io_error {
            eprintln!("checked {}: no problems", plural(files.len(), "file"));
        } else {
            eprintln!(
                "checked {}: {}, {}",
                plural(files.len(), "file"),
                plural(errors, "error"),
                plural(warnings, "warning")
            );
        }
    }
    if io_error {
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
        None => {
            let mut stdout = std::io::stdout().lock();
            match stdout.write_all(text.as_bytes()) {
                Ok(()) => 0,
                Err(err) if err.kind() == std::io::ErrorKind::BrokenPipe => 0,
                Err(err) => usage_error(format!("cannot write to standard output: {err}")),
            }
        }
    }
}

fn compile(path: &Path, output: Option<&Path>) -> u8 {
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

fn fmt(files: &[PathBuf], check_only: bool) -> u8 {
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
        let source = match frontend::decode(&name, bytes) {
            Ok(source) => source,
            Err(invalid) => {
                let (source, diag) = *invalid;
                let compilation = skill_compiler::Compilation {
                    files: vec![source],
                    diags: vec![diag],
                    ast: Default::default(),
                    program: None,
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
            };
            print_diags(&compilation);
            eprintln!("error: `{name}` does not parse; not formatted");
            status = status.max(1);
            continue;
        }
        let formatted = skill_compiler::fmt::format(&source, &ast);
        if formatted == *source.text {
            continue;
        }
        if check_only {
            println!("would reformat `{name}`");
            status = status.max(1);
        } else if let Err(err) = atomic::write(path, formatted.as_bytes()) {
            eprintln!("error: cannot write `{name}`: {err}");
            status = 2;
        } else {
            println!("formatted `{name}`");
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
            println!("{:#?}", compilation.ast);
            u8::from(compilation.has_errors())
        }
        Stage::Ir => compile(path, None),
    }
}

fn demos(out: &Path, check_only: bool) -> u8 {
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
            if check_only {
                match std::fs::read_to_string(&path) {
                    Ok(existing) if existing == text => {}
                    Ok(_) => {
                        println!("`{}` differs from the generator", path.display());
                        status = 1;
                    }
                    Err(err) => {
                        println!("`{}` cannot be read: {err}", path.display());
                        status = 1;
                    }
                }
            } else if let Err(err) = atomic::write(&path, text.as_bytes()) {
                return usage_error(format!("cannot write `{}`: {err}", path.display()));
            } else {
                println!("wrote `{}` ({} samples)", path.display(), demo.samples.len());
            }
        }
    }
    status
}

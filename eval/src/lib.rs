//! `skillc eval`: the thesis's experiments (chapter 5) as one command. Each skill is learned
//! once from its demonstration, then reproduced in every variant of its scene, side by side with
//! the replay baseline; trials run in parallel and the results are the same for any thread count.

pub mod metrics;
pub mod real;
mod report;
pub mod robot;
mod run;
mod spark;
pub mod sweep;
mod sweep_run;
pub mod tasks;
mod trials;
mod verdict;

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use skill_runtime::exec::RunLog;

use run::{bind_prepared, prepare, prepared_views, run_job, worker_threads, Bound, Job, Prepared, SkillView};
use skill_kit::load::{load_skill, Failure};
use skill_kit::out::Verbosity;
use skill_kit::plot;
use sweep_run::{merge, run_sweep, Runner};
use trials::{load_trials, parse_rate};
pub use trials::{Criteria, SkillTrials, TrialsFile, Variant, DEFAULT_PEAK_BOUND};
pub(crate) use verdict::run_reason;
use verdict::{pass_line, witness_line};

/// The default trials, shipped as `examples/eval/default.toml`.
pub const DEFAULT_TRIALS: &str = include_str!("../../examples/eval/default.toml");

/// Where the default trials file lives, relative to the repository root.
pub const DEFAULT_TRIALS_PATH: &str = "examples/eval/default.toml";

/// Arguments of `skillc eval`.
#[derive(Debug, Clone, clap::Args)]
pub struct EvalArgs {
    /// Where to write the report (index.html, summary.json, plots/).
    #[arg(long, default_value = "report")]
    pub out: PathBuf,
    /// A trials file for your own skills and scenes (TOML, like examples/eval/default.toml).
    #[arg(long)]
    pub trials: Option<PathBuf>,
    /// Only these skills (by name; repeatable).
    #[arg(long = "skill")]
    pub skills: Vec<String>,
    /// Worker threads (default: one per core). Results do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Skip the replay baseline.
    #[arg(long)]
    pub no_replay: bool,
    /// Also learn the wipe skill from every real demonstration in this folder (CSV files like
    /// ../shared/data/lasa_wiping_lwr4/csv/), compare with `segment_labels.csv` there, and
    /// reproduce each on a table at the learned plane.
    #[arg(long, value_name = "DIR")]
    pub real: Option<PathBuf>,
    /// Tighten or loosen a safety limit for every trial, e.g. `--limit force=60` (see `skillc run`).
    #[arg(long = "limit", value_name = "NAME=VALUE", value_parser = skill_kit::limits::parse_limit)]
    pub limits: Vec<(String, f64)>,
    /// Set a skill parameter, e.g. `--param hold=5s` (repeatable): in every skill of the trials
    /// that declares it, after the trials file's own `params`.
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Run every trial on this shipped robot instead of the scene's (`lwr4`, `iiwa14`, `fr3`): the
    /// skills learned from the same demonstrations, the robot's tool starting where the scene's
    /// robot starts its tool (inverse kinematics), objects and sensor as the scene has them.
    #[arg(long, value_name = "NAME", conflicts_with = "real")]
    pub robot: Option<String>,
    /// Instead of the listed variants, reproduce each skill in N scenes drawn at random within
    /// its `sweep` ranges (default: height ±10 cm, tilt ±10°, position ±3 cm, friction 0.2-1.0,
    /// sensor noise 1-3×); report success rates and failures by reason.
    #[arg(long, value_name = "N", value_parser = sweep::parse_draws)]
    pub sweep: Option<usize>,
    /// The sweep's seed: the same seed draws the same scenes.
    #[arg(long, default_value_t = 1, requires = "sweep")]
    pub seed: u64,
    /// Run only share K of M of the sweep's draws (for a Slurm array or a CI matrix); join the
    /// shares' summaries with `skillc eval merge`.
    #[arg(long, value_name = "K/M", value_parser = sweep::parse_partition, requires = "sweep")]
    pub partition: Option<sweep::Partition>,
    /// A sweep fails (exit 1) when a skill's success rate is below this.
    #[arg(long, default_value_t = 0.95, value_parser = parse_rate, requires = "sweep")]
    pub min_success: f64,
    #[command(subcommand)]
    pub command: Option<EvalCommand>,
}

/// Subcommands of `skillc eval`.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum EvalCommand {
    /// Join the `summary.json` of a sweep's shares (`--partition K/M`) into one report.
    Merge {
        /// Where to write the joined report.
        #[arg(long, default_value = "report")]
        out: PathBuf,
        /// A success rate below this fails the merge (exit 1).
        #[arg(long, default_value_t = 0.95, value_parser = parse_rate)]
        min_success: f64,
        /// The shares' `summary.json` files.
        #[arg(required = true)]
        summaries: Vec<PathBuf>,
    },
}

/// The version of `summary.json`'s layout; bumped on every change to its keys.
pub const SUMMARY_VERSION: u32 = 4;

/// One trial's result (an entry of `summary.json`'s `trials`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrialResult {
    /// The skill's name.
    pub skill: String,
    /// The variant.
    pub variant: String,
    /// `skill` or `replay`.
    pub mode: String,
    /// Whether it met every criterion (and, for the skill, ended in a success state).
    pub success: bool,
    /// RMS force error in contact over the learned force.
    pub force_rms_rel: Option<f64>,
    /// Share of the contact phase in contact.
    pub contact_share: Option<f64>,
    /// Peak applied force \[N\].
    pub peak_force_n: f64,
    /// Final contact force \[N\] (touch).
    pub stop_force_n: Option<f64>,
    /// The learned contact force it is judged against \[N\].
    pub learned_force_n: Option<f64>,
    /// Position error at the goal \[m\].
    pub goal_error_m: f64,
    /// Simulated duration \[s\].
    pub duration_s: f64,
    /// How the run ended, or why it could not run.
    pub message: String,
    /// Why the trial failed, short and stable (`reflex:contact_force`, `criterion:force_rms`,
    /// `contact_witness`, `criterion:peak_force`, `lost_contact`, `failure_state`, `error`, ...); `None` when it succeeded.
    pub reason: Option<String>,
    /// The peak force the trial was allowed \[N\] (skill trials).
    pub peak_bound_n: Option<f64>,
    /// Largest tool speed \[m/s\].
    pub peak_tool_speed_mps: f64,
    /// Smallest distance of a joint from its limits \[rad\].
    pub min_joint_margin_rad: f64,
    /// Time any joint torque was at its effort limit \[s\].
    pub torque_limit_s: f64,
    /// Whether the trial could not run at all (bad input).
    pub error: bool,
    /// States visited with entry times, `state@t`.
    pub states: Vec<String>,
    /// The scene a sweep drew (sweeps only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub draw: Option<sweep::Draw>,
    /// The scene overrides of the trial (`skillc run --no-prepose --set ...` repeats it).
    #[serde(default)]
    pub set: Vec<String>,
    /// A task trial's steps, in order (then any fallback that ran); empty for skill trials.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub steps: Vec<tasks::StepResult>,
    /// What the simulation's contact witness found over every step of the run (a task's steps
    /// together); `None` when the trial did not run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<skill_runtime::plant::ContactAudit>,
}

/// What one trial produced, kept for plots.
pub struct Outcome {
    /// The result row.
    pub result: TrialResult,
    /// The tick log (empty when the trial failed to run, and for tasks).
    pub log: RunLog,
    /// A task trial's tick log per entry of its `steps`.
    pub step_logs: Vec<RunLog>,
    /// The scene's objects as the trial ran them (its variant's settings applied), for the
    /// report's 3-D picture; empty when the trial did not run.
    pub objects: std::collections::BTreeMap<String, skill_runtime::sim::ObjectSpec>,
}

impl Outcome {
    /// An error row: trial `name` / `variant` in `mode` (`skill`, `replay`, `task`) could not
    /// run, with scene overrides `set`.
    pub(crate) fn error(name: &str, variant: &str, mode: &str, set: Vec<String>, message: String) -> Self {
        Outcome {
            result: TrialResult {
                skill: name.to_string(),
                variant: variant.to_string(),
                mode: mode.to_string(),
                success: false,
                force_rms_rel: None,
                contact_share: None,
                peak_force_n: 0.0,
                stop_force_n: None,
                learned_force_n: None,
                goal_error_m: 0.0,
                duration_s: 0.0,
                message,
                reason: Some("error".to_string()),
                peak_bound_n: None,
                peak_tool_speed_mps: 0.0,
                min_joint_margin_rad: 0.0,
                torque_limit_s: 0.0,
                error: true,
                states: Vec::new(),
                draw: None,
                set,
                steps: Vec::new(),
                contact: None,
            },
            log: RunLog::default(),
            step_logs: Vec::new(),
            objects: Default::default(),
        }
    }

    /// The trial as the plots draw it.
    pub fn trial(&self) -> plot::Trial<'_> {
        plot::Trial {
            variant: &self.result.variant,
            replay: self.result.mode == "replay",
            error: self.result.error,
            log: &self.log,
        }
    }
}

/// Runs `skillc eval`. `--quiet` prints no tables, progress or report path, only errors and
/// the trials that failed; `--verbose` adds the time of each stage.
pub fn run(args: &EvalArgs, verbosity: Verbosity) -> u8 {
    let result = match &args.command {
        Some(EvalCommand::Merge {
            out,
            min_success,
            summaries,
        }) => merge(out, *min_success, summaries, verbosity),
        None => evaluate(args, verbosity),
    };
    match result {
        Ok(code) => code,
        Err(failure) => failure.report(),
    }
}

/// Prints `text` to standard output unless `--quiet`.
fn say(verbosity: Verbosity, text: &str) -> Result<(), Failure> {
    if verbosity.quiet() {
        Ok(())
    } else {
        skill_kit::out::print(text)
    }
}

/// The demonstrations `eval --real DIR` would learn from: the folder's `*.csv` files but the
/// labels and index; none is a usage error found before any trial runs.
fn check_real_dir(dir: &Path) -> Result<(), Failure> {
    let entries = std::fs::read_dir(dir)
        .map_err(|err| Failure::Usage(format!("--real: cannot read the folder `{}`: {err}", dir.display())))?;
    let demos = entries
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "csv"))
        .filter(|path| {
            !matches!(
                path.file_name().and_then(|name| name.to_str()),
                Some("segment_labels.csv" | "index.csv")
            )
        })
        .count();
    if demos == 0 {
        return Err(Failure::Usage(format!(
            "--real: `{}` holds no demonstration (`*.csv` besides segment_labels.csv and index.csv)",
            dir.display()
        )));
    }
    Ok(())
}

fn evaluate(args: &EvalArgs, verbosity: Verbosity) -> Result<u8, Failure> {
    let started = Instant::now();
    if let Some(dir) = &args.real {
        check_real_dir(dir)?;
    }
    let (trials, base_dir) = load_trials(args)?;
    // `--skill NAME` selects skill and task entries alike, by name (an entry's `name`, else its
    // file's stem).
    let mut names: Vec<String> = trials.skills.iter().map(skill_stem).collect();
    names.extend(trials.tasks.iter().map(tasks::stem));
    if let Some(unknown) = args.skills.iter().find(|name| !names.contains(name)) {
        return Err(Failure::Usage(format!(
            "--skill `{unknown}`: the trials have no such skill or task; they have {}",
            names.join(", ")
        )));
    }
    // A task step without criteria of its own is judged by its skill's `[[skill]]` entry's,
    // whether or not `--skill` selects that entry.
    let mut skill_criteria = std::collections::BTreeMap::new();
    for spec in &trials.skills {
        skill_criteria.entry(skill_stem(spec)).or_insert(spec.criteria);
    }
    let selected: Vec<SkillTrials> = trials
        .skills
        .into_iter()
        .filter(|spec| args.skills.is_empty() || args.skills.contains(&skill_stem(spec)))
        .collect();
    let selected_tasks: Vec<tasks::TaskTrials> = trials
        .tasks
        .into_iter()
        .filter(|spec| args.skills.is_empty() || args.skills.contains(&tasks::stem(spec)))
        .collect();
    if selected.is_empty() && (selected_tasks.is_empty() || args.sweep.is_some()) {
        return Err(Failure::Usage(if args.sweep.is_some() {
            "the trials file lists no skill (a sweep runs skills only)".into()
        } else {
            "the trials file lists no skill or task".into()
        }));
    }
    let trials_count = match args.sweep {
        Some(draws) => selected.len().saturating_mul(draws),
        None => {
            let skills: usize = selected.iter().map(|spec| spec.variants.len() * 2).sum();
            skills + selected_tasks.iter().map(|spec| spec.variants.len()).sum::<usize>()
        }
    };
    let threads = worker_threads(args.threads, trials_count, verbosity);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|err| Failure::Usage(format!("cannot start worker threads: {err}")))?;

    let progress = if verbosity.quiet() {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(0)
    };
    progress.set_style(
        indicatif::ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    progress.set_message("learning");
    let swap = match &args.robot {
        Some(name) => Some(std::sync::Arc::new(robot::Swap::new(
            name,
            &skill_kit::defaults::root().map_err(Failure::Usage)?,
        )?)),
        None => None,
    };
    let mut prepared: Vec<Prepared> = pool.install(|| {
        selected
            .into_par_iter()
            .map(|spec| prepare(spec, &base_dir, &args.params))
            .collect()
    });
    // Sweeps draw scenes for skills only: tasks are not prepared.
    let task_specs = if args.sweep.is_some() {
        if !selected_tasks.is_empty() {
            say(
                verbosity,
                &format!(
                    "--sweep: {} skipped (a sweep runs skills only)\n",
                    match selected_tasks.len() {
                        1 => "the task entry is".to_string(),
                        n => format!("the {n} task entries are"),
                    }
                ),
            )?;
        }
        Vec::new()
    } else {
        selected_tasks
    };
    let mut prepared_tasks: Vec<tasks::PreparedTask> = pool.install(|| {
        task_specs
            .into_par_iter()
            .map(|spec| tasks::prepare(spec, &base_dir, &args.params, &skill_criteria))
            .collect()
    });
    if let Some(unused) = args.params.iter().find(|setting| {
        let name = setting.split('=').next().unwrap_or_default().trim();
        !prepared.iter().any(|prep| {
            prep.program_skill
                .as_ref()
                .is_ok_and(|(skill, _)| skill.params.iter().any(|p| p.name == name))
        }) && !prepared_tasks.iter().any(|prep| prep.declares(name))
    }) {
        return Err(Failure::Usage(format!(
            "--param `{unused}`: no skill of these trials declares that parameter"
        )));
    }
    for prep in &mut prepared {
        prep.swap.clone_from(&swap);
    }
    for prep in &mut prepared_tasks {
        prep.swap.clone_from(&swap);
    }
    let bound: Vec<Bound<'_>> = prepared.iter().map(bind_prepared).collect();
    verbosity.detail(format_args!(
        "learned {} skill(s) and {} task(s) in {:.1} s",
        prepared.len(),
        prepared_tasks.len(),
        started.elapsed().as_secs_f64()
    ));
    if let Some(draws) = args.sweep {
        let runner = Runner {
            pool: &pool,
            progress: &progress,
            started,
            verbosity,
        };
        return run_sweep(args, draws, &prepared, &bound, runner);
    }
    let mut jobs = Vec::new();
    for (skill, prep) in prepared.iter().enumerate() {
        for variant in 0..prep.spec.variants.len() {
            jobs.push(Job::Skill {
                skill,
                variant,
                replay: false,
            });
            if !args.no_replay {
                jobs.push(Job::Skill {
                    skill,
                    variant,
                    replay: true,
                });
            }
        }
    }
    // Tasks have no replay baseline: one trial per variant.
    for (task, prep) in prepared_tasks.iter().enumerate() {
        jobs.extend((0..prep.spec.variants.len()).map(|variant| Job::Task { task, variant }));
    }
    progress.set_length(jobs.len() as u64);
    progress.set_message("trials");
    let outcomes: Vec<Outcome> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let outcome = match *job {
                    Job::Skill { skill, variant, replay } => {
                        let prep = &prepared[skill];
                        run_job(prep, &bound[skill], &prep.spec.variants[variant], replay, &args.limits)
                    }
                    Job::Task { task, variant } => {
                        let prep = &prepared_tasks[task];
                        tasks::run_trial(prep, &prep.spec.variants[variant], &args.limits)
                    }
                };
                progress.inc(1);
                outcome
            })
            .collect()
    });
    progress.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();

    let table = report::table(&outcomes);
    if let Some(swap) = &swap {
        say(
            verbosity,
            &format!(
                "robot: {} ({}), its tool starting where each scene's robot starts its tool\n",
                swap.robot.name, swap.robot.title
            ),
        )?;
    }
    say(
        verbosity,
        &format!(
            "{table}{} trials in {elapsed:.1} s\n{}\n{}\n",
            outcomes.len(),
            pass_line(&outcomes),
            witness_line(&outcomes)
        ),
    )?;
    let real = match &args.real {
        Some(dir) => {
            let root = skill_kit::defaults::root().map_err(Failure::Usage)?;
            let (_, wipe) = load_skill(&root.join("stdlib-skills/wipe.skill"), None)?;
            let table = root.join("examples/scenes/table.toml");
            let results = pool
                .install(|| real::evaluate(dir, &wipe, &table))
                .map_err(Failure::Usage)?;
            say(verbosity, &report::real_table(&results))?;
            results
        }
        None => Vec::new(),
    };
    let written = report::write(
        &args.out,
        &prepared_views(&prepared, &bound),
        &tasks::views(&prepared_tasks),
        &outcomes,
        elapsed,
        &table,
        &real,
    )
    .map_err(|err| Failure::Usage(format!("cannot write the report to `{}`: {err}", args.out.display())))?;
    say(verbosity, &format!("report: {}\n", written.display()))?;
    // A gate for CI: any skill or task trial that failed its criteria (or could not run) fails
    // the eval.
    let mut any_failed = false;
    for mode in ["skill", "task"] {
        let failed: Vec<&TrialResult> = outcomes
            .iter()
            .map(|o| &o.result)
            .filter(|r| r.mode == mode && (r.error || !r.success))
            .collect();
        if failed.is_empty() {
            continue;
        }
        any_failed = true;
        eprintln!(
            "{} of {} {mode} trials failed:",
            failed.len(),
            outcomes.iter().filter(|o| o.result.mode == mode).count()
        );
        for r in &failed {
            eprintln!(
                "  {} / {}: {} ({})",
                r.skill,
                r.variant,
                r.reason.as_deref().unwrap_or("error"),
                r.message
            );
        }
    }
    Ok(u8::from(any_failed))
}

/// The name `--skill` selects a skill's trials by: its `name`, else its file's stem.
fn skill_stem(spec: &SkillTrials) -> String {
    spec.name.clone().unwrap_or_else(|| {
        spec.file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    })
}

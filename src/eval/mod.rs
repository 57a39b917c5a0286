//! `skillc eval`: the thesis's experiments (chapter 5) as one command. Each skill is learned
//! once from its demonstration, then reproduced in every variant of its scene, side by side with
//! the replay baseline; trials run in parallel and the results are the same for any thread count.

pub mod metrics;
pub mod real;
mod report;
pub mod robot;
mod spark;
pub mod sweep;
pub mod tasks;
mod trials;

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use skill_runtime::exec::{bind, simulate, BoundSkill, ExecOptions, Mode, RunLog};
use skill_runtime::skill::{LearnOptions, Learned};

use crate::load::{error_chain, learn_from_files, load_scene, load_skill, load_skill_with, Failure};
use crate::out::Verbosity;
use crate::plot;
use crate::profile::DesiredProfile;
use metrics::{ContactPlan, Metrics};
use trials::{load_trials, parse_rate};
pub use trials::{Criteria, SkillTrials, TrialsFile, Variant, DEFAULT_PEAK_BOUND};

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
    #[arg(long = "limit", value_name = "NAME=VALUE", value_parser = crate::run_cmd::parse_limit)]
    pub limits: Vec<(String, f64)>,
    /// Set a skill parameter, e.g. `--param hold=5s` (repeatable): in every skill of the trials
    /// that declares it, after the trials file's own `params`.
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Run every trial on this shipped robot instead of the scene's (`lwr4`, `iiwa14`): the
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

/// A learned skill ready for trials (it binds), or why it is not.
struct Prepared {
    name: String,
    program_skill: Result<(skill_ir::Skill, Learned), String>,
    /// The demonstration's largest force magnitude \[N\].
    demo_peak_n: f64,
    spec: SkillTrials,
    base_dir: PathBuf,
    /// The robot `--robot` puts into every scene.
    swap: Option<std::sync::Arc<robot::Swap>>,
    /// The command line's `--param` settings.
    command_line: Vec<String>,
}

/// One trial to run.
enum Job {
    /// A skill's variant, or its replay.
    Skill { skill: usize, variant: usize, replay: bool },
    /// A task's variant.
    Task { task: usize, variant: usize },
}

/// One draw of a sweep to run.
struct DrawJob {
    skill: usize,
    index: usize,
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

/// Worker threads per core at most: trials are CPU-bound, so more only adds memory and
/// switching.
const THREADS_PER_CORE: usize = 4;

/// The worker threads an eval runs: `--threads` (default one per core), at most
/// [`THREADS_PER_CORE`] per core and at most one per trial, saying so when it lowers the
/// request (`--threads 100000` asked for thousands of threads and did not finish).
fn worker_threads(requested: Option<usize>, trials: usize, verbosity: Verbosity) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let wanted = requested.filter(|n| *n > 0).unwrap_or(cores);
    let (per_core, trials) = (cores * THREADS_PER_CORE, trials.max(1));
    let most = per_core.min(trials);
    if wanted > most && requested.is_some() {
        verbosity.note(format_args!(
            "--threads {wanted}: running {most} worker threads ({}; trials are CPU-bound)",
            if trials < per_core {
                format!("one per trial, {trials} trials")
            } else {
                format!("at most {THREADS_PER_CORE} per core, {cores} cores")
            }
        ));
    }
    wanted.min(most)
}

/// Compiles a trial's skill with the trials file's `params` and those of the command line
/// that the skill declares (the command line's apply to every skill declaring them).
fn skill_with_params(
    file: &Path,
    name: Option<&str>,
    own: &[String],
    command_line: &[String],
) -> Result<skill_ir::Skill, Failure> {
    if command_line.is_empty() {
        return load_skill_with(file, name, own).map(|(_, skill)| skill);
    }
    let (_, plain) = load_skill_with(file, name, own)?;
    let mut params = own.to_vec();
    params.extend(
        command_line
            .iter()
            .filter(|setting| {
                let setting_name = setting.split('=').next().unwrap_or_default().trim();
                plain.params.iter().any(|p| p.name == setting_name)
            })
            .cloned(),
    );
    load_skill_with(file, name, &params).map(|(_, skill)| skill)
}

fn prepare(spec: SkillTrials, base_dir: &Path, command_line: &[String]) -> Prepared {
    let file = base_dir.join(&spec.file);
    let demo = base_dir.join(&spec.demo);
    let fallback_name = spec.name.clone().unwrap_or_else(|| {
        spec.file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "?".to_string())
    });
    let loaded = skill_with_params(&file, spec.name.as_deref(), &spec.params, command_line).and_then(|skill| {
        let learned = learn_from_files(&skill, &demo, &LearnOptions::default())?;
        Ok((skill, learned))
    });
    let (name, program_skill) = match loaded {
        Ok((skill, learned)) => {
            let binds = bind(&skill, &learned).map(|_| ()).map_err(|err| err.to_string());
            (skill.name.clone(), binds.map(|()| (skill, learned)))
        }
        Err(Failure::Input(message) | Failure::Usage(message)) => (fallback_name, Err(message)),
        Err(Failure::Closed) => (fallback_name, Err("standard output closed".to_string())),
    };
    let demo_peak_n = crate::load::read_demo(&demo, &Default::default(), &Default::default())
        .map(|(loaded, _, _)| loaded.demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max))
        .unwrap_or(0.0);
    Prepared {
        name,
        program_skill,
        demo_peak_n,
        spec,
        base_dir: base_dir.to_path_buf(),
        swap: None,
        command_line: command_line.to_vec(),
    }
}

/// A prepared skill bound to what it learned, with its contact phase; or why it cannot run.
type Bound<'a> = Result<(BoundSkill<'a>, ContactPlan), String>;

fn bind_prepared(prepared: &Prepared) -> Bound<'_> {
    match &prepared.program_skill {
        Ok((skill, learned)) => match bind(skill, learned) {
            Ok(bound) => {
                let plan = ContactPlan::of(&bound);
                Ok((bound, plan))
            }
            Err(err) => Err(err.to_string()),
        },
        Err(message) => Err(message.clone()),
    }
}

fn run_job(
    prepared: &Prepared,
    bound: &Bound<'_>,
    variant: &Variant,
    replay: bool,
    limits: &[(String, f64)],
) -> Outcome {
    let mode_name = if replay { "replay" } else { "skill" };
    let failed =
        |message: String| Outcome::error(&prepared.name, &variant.name, mode_name, variant.set.clone(), message);
    let (specialised, variant_bound);
    let (bound, plan) = match bound {
        Ok(parts) if variant.params.is_empty() => (&parts.0, &parts.1),
        Ok(_) => {
            // The variant sets parameters: compile the skill with them and bind the features
            // learned once.
            let Ok((_, learned)) = &prepared.program_skill else {
                return failed("the skill did not learn".to_string());
            };
            let mut params = prepared.spec.params.clone();
            params.extend(variant.params.iter().cloned());
            let file = prepared.base_dir.join(&prepared.spec.file);
            specialised = match skill_with_params(&file, prepared.spec.name.as_deref(), &params, &prepared.command_line)
            {
                Ok(skill) => skill,
                Err(Failure::Input(message) | Failure::Usage(message)) => return failed(message),
                Err(Failure::Closed) => return failed("standard output closed".to_string()),
            };
            variant_bound = match bind(&specialised, learned) {
                Ok(bound) => {
                    let plan = ContactPlan::of(&bound);
                    (bound, plan)
                }
                Err(err) => return failed(err.to_string()),
            };
            (&variant_bound.0, &variant_bound.1)
        }
        Err(message) => return failed(message.clone()),
    };
    let scene_path = prepared.base_dir.join(&prepared.spec.scene);
    let mut sets = variant.set.clone();
    if let Some(swap) = &prepared.swap {
        match swap.sets(&scene_path, &sets) {
            Ok(extra) => sets.extend(extra),
            Err(message) => return failed(message),
        }
    }
    let scene = match load_scene(&scene_path, &sets) {
        Ok(scene) => scene,
        Err(Failure::Input(message) | Failure::Usage(message)) => return failed(message),
        Err(Failure::Closed) => return failed("standard output closed".to_string()),
    };
    let mode = if replay {
        Mode::Replay(bound.learned)
    } else {
        Mode::Skill(bound)
    };
    // Trials start where the scene puts the arm (`robot.q0`: the demonstration's start in the
    // shipped scenes, higher where the objects moved up) and the skill's first motion runs from
    // there: moving to the demonstrated start first would drive into objects that moved up.
    let options = ExecOptions {
        limits: limits.to_vec(),
        prepose: false,
        ..ExecOptions::default()
    };
    let (report, log) = match simulate(&scene, mode, &options) {
        Ok(done) => done,
        Err(err) => return failed(error_chain(&err)),
    };
    let frame_z = |t: f64| replay_frame_z(bound, plan, t);
    let metrics: Metrics = metrics::measure(&log, plan, replay, &frame_z);
    let learned_force = plan.force.as_ref().map(|force| DesiredProfile::new(force, 0.01).peak());
    let criteria = prepared.spec.criteria;
    let peak_bound = (!replay).then(|| criteria.peak_bound(prepared.demo_peak_n));
    // The first reason a trial fails, in order of gravity. Replays are the baseline: they are
    // never a success, and their reason says why they would have failed.
    let reason = run_reason(&report).or_else(|| {
        if report.outcome != skill_ir::Outcome::Success {
            Some("failure_state".to_string())
        } else {
            let demo_peak = (!replay).then_some(prepared.demo_peak_n);
            criteria
                .missed(&metrics, learned_force, demo_peak)
                .map(|(reason, _)| reason)
        }
    });
    let success = !replay && reason.is_none();
    let safety = &report.safety;
    Outcome {
        result: TrialResult {
            skill: prepared.name.clone(),
            variant: variant.name.clone(),
            mode: mode_name.to_string(),
            success,
            force_rms_rel: metrics.force_rms_rel,
            contact_share: metrics.contact_share,
            peak_force_n: metrics.peak_force_n,
            stop_force_n: metrics.stop_force_n,
            learned_force_n: learned_force,
            goal_error_m: metrics.goal_error_m,
            duration_s: report.duration_s,
            message: report.message.clone(),
            reason,
            peak_bound_n: peak_bound,
            contact: report.contact.clone(),
            peak_tool_speed_mps: safety.peak_tool_speed_mps,
            min_joint_margin_rad: safety.min_joint_margin_rad,
            torque_limit_s: safety.torque_limit_s,
            error: false,
            states: report
                .visits
                .iter()
                .map(|v| format!("{}@{:.2}", v.state, v.enter_s))
                .collect(),
            draw: None,
            set: sets,
            steps: Vec::new(),
        },
        log,
        step_logs: Vec::new(),
        objects: scene.spec().objects.clone(),
    }
}

/// The compliant z of the contact state for replay ticks, `t` seconds into the contact phase.
fn replay_frame_z(bound: &BoundSkill<'_>, plan: &ContactPlan, t: f64) -> nalgebra::Vector3<f64> {
    match plan.frame {
        Some(skill_ir::FrameRef::Learned(id)) => bound.frame(id).at(t).rotation * nalgebra::Vector3::z(),
        _ => nalgebra::Vector3::z(),
    }
}

/// What a sweep runs with: the worker threads, the progress bar, the start and how much to say.
struct Runner<'a> {
    pool: &'a rayon::ThreadPool,
    progress: &'a indicatif::ProgressBar,
    started: Instant,
    verbosity: Verbosity,
}

/// Prints `text` to standard output unless `--quiet`.
fn say(verbosity: Verbosity, text: &str) -> Result<(), Failure> {
    if verbosity.quiet() {
        Ok(())
    } else {
        crate::out::print(text)
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
            &crate::defaults::root().map_err(Failure::Usage)?,
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
            let root = crate::defaults::root().map_err(Failure::Usage)?;
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

/// What the contact witness found over every trial: steps checked, steps in contact, steps
/// that broke its rules, and the deepest the tool went into an object (with the trial).
fn witness_line(outcomes: &[Outcome]) -> String {
    let mut all = skill_runtime::plant::ContactAudit::default();
    let mut deepest: Option<(f64, &TrialResult)> = None;
    let mut trials = 0;
    for result in outcomes.iter().map(|o| &o.result) {
        let Some(audit) = &result.contact else { continue };
        trials += 1;
        if deepest.is_none_or(|(depth, _)| audit.max_depth_m > depth) {
            deepest = Some((audit.max_depth_m, result));
        }
        all.merge(audit.clone());
    }
    let broken = outcomes
        .iter()
        .filter(|o| o.result.contact.as_ref().is_some_and(|audit| audit.violated()))
        .count();
    let mut line = format!(
        "contact witness: {} steps of {trials} trials checked against the shapes, {} in contact; {} with force away from \
         every object, {} deeper than the compliance explains ({broken} trials)",
        all.ticks, all.touching_ticks, all.far_ticks, all.deep_ticks
    );
    if let Some((depth, result)) = deepest.filter(|(depth, _)| *depth > 0.0) {
        line.push_str(&format!(
            "; deepest {:.2} mm ({} {}, {})",
            depth * 1e3,
            result.skill,
            result.variant,
            result.mode
        ));
    }
    line
}

/// The first reason a run itself gives for failing, in order of gravity, before any criterion
/// is looked at: contacts that are not where the shapes are (every other figure of the run is
/// suspect then), a reflex, a contact lost mid-stroke.
pub(crate) fn run_reason(report: &skill_runtime::exec::RunReport) -> Option<String> {
    if report.contact.as_ref().is_some_and(|audit| audit.violated()) {
        Some(skill_runtime::exec::CONTACT_WITNESS.to_string())
    } else if let Some(violation) = &report.reflex {
        Some(format!("reflex:{}", violation.quantity.name()))
    } else if report.lost_contact() {
        Some(skill_runtime::exec::LOST_CONTACT.to_string())
    } else {
        None
    }
}

/// `N/M skill trials pass`, and `K/L task trials pass` when there are task trials.
fn pass_line(outcomes: &[Outcome]) -> String {
    let count = |mode: &str| {
        let of_mode: Vec<&TrialResult> = outcomes.iter().map(|o| &o.result).filter(|r| r.mode == mode).collect();
        (of_mode.iter().filter(|r| r.success && !r.error).count(), of_mode.len())
    };
    let (skills_ok, skills) = count("skill");
    let mut line = format!("{skills_ok}/{skills} skill trials pass");
    let (tasks_ok, tasks) = count("task");
    if tasks > 0 {
        line.push_str(&format!(
            ", {tasks_ok}/{tasks} task trials pass (tasks have no replay baseline)"
        ));
    }
    line
}

/// What the report needs of each prepared skill.
struct SkillView<'a> {
    /// The skill's name.
    name: &'a str,
    /// The skill bound to what it learned, if learning worked.
    bound: Option<&'a BoundSkill<'a>>,
    /// Why learning failed.
    error: Option<&'a str>,
    /// The demonstration path.
    demo: PathBuf,
    /// Criteria.
    criteria: Criteria,
}

impl SkillView<'_> {
    /// The skill as the plots see it.
    fn subject(&self) -> plot::Subject<'_> {
        plot::Subject {
            name: self.name,
            demo: &self.demo,
            bound: self.bound,
        }
    }
}

fn prepared_views<'a>(prepared: &'a [Prepared], bound: &'a [Bound<'a>]) -> Vec<SkillView<'a>> {
    prepared
        .iter()
        .zip(bound)
        .map(|(p, bound)| SkillView {
            name: &p.name,
            bound: bound.as_ref().ok().map(|(bound, _)| bound),
            error: p.program_skill.as_ref().err().map(String::as_str),
            demo: p.base_dir.join(&p.spec.demo),
            criteria: p.spec.criteria,
        })
        .collect()
}

/// What a sweep needs of each skill's scene: the scene as written and its robot.
type SweepBase = Result<(skill_runtime::sim::Scene, skill_runtime::robot::Robot), String>;

fn sweep_base(prepared: &Prepared) -> SweepBase {
    prepared.spec.sweep.validate(&prepared.name)?;
    let scene = load_scene(&prepared.base_dir.join(&prepared.spec.scene), &[]).map_err(|failure| match failure {
        Failure::Input(message) | Failure::Usage(message) => message,
        Failure::Closed => "standard output closed".to_string(),
    })?;
    let robot = skill_runtime::robot::Robot::from_urdf_file(&scene.urdf_path(), scene.spec().robot.tool.as_deref())
        .map_err(|err| error_chain(&err))?;
    Ok((scene, robot))
}

/// One draw of a sweep: the scene drawn, the start raised out of the objects, the skill run.
fn run_draw(prepared: &Prepared, bound: &Bound<'_>, base: &SweepBase, index: usize, args: &EvalArgs) -> Outcome {
    let ranges = &prepared.spec.sweep;
    let mut draw = sweep::draw(ranges, args.seed, &prepared.name, index);
    let sets = base
        .as_ref()
        .map_err(Clone::clone)
        .and_then(|(scene, robot)| sweep::scene_sets(scene, robot, &mut draw, args.seed));
    let variant = Variant {
        name: format!("draw #{index}"),
        set: sets.as_ref().cloned().unwrap_or_default(),
        params: Vec::new(),
    };
    let mut outcome = match (&sets, bound) {
        (Err(message), _) => run_job(prepared, &Err(message.clone()), &variant, false, &args.limits),
        _ => run_job(prepared, bound, &variant, false, &args.limits),
    };
    outcome.result.draw = Some(draw);
    // A sweep keeps its results, not its tick logs (hundreds of runs of ~10^4 ticks each).
    outcome.log = RunLog::default();
    outcome
}

fn run_sweep(
    args: &EvalArgs,
    draws: usize,
    prepared: &[Prepared],
    bound: &[Bound<'_>],
    runner: Runner<'_>,
) -> Result<u8, Failure> {
    let Runner {
        pool,
        progress,
        started,
        verbosity,
    } = runner;
    let partition = args.partition.unwrap_or(sweep::Partition::ALL);
    let bases: Vec<SweepBase> = prepared.iter().map(sweep_base).collect();
    let jobs: Vec<DrawJob> = (0..prepared.len())
        .flat_map(|skill| (0..draws).map(move |index| DrawJob { skill, index }))
        .enumerate()
        .filter(|(global, _)| partition.runs(*global))
        .map(|(_, job)| job)
        .collect();
    progress.set_length(jobs.len() as u64);
    progress.set_message("sweep");
    let outcomes: Vec<Outcome> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let outcome = run_draw(
                    &prepared[job.skill],
                    &bound[job.skill],
                    &bases[job.skill],
                    job.index,
                    args,
                );
                progress.inc(1);
                outcome
            })
            .collect()
    });
    progress.finish_and_clear();
    let summary = sweep::SweepSummary {
        format_version: SUMMARY_VERSION,
        kind: "sweep".to_string(),
        seed: args.seed,
        per_skill: draws,
        partitions: vec![partition.to_string()],
        ranges: prepared.iter().map(|p| (p.name.clone(), p.spec.sweep)).collect(),
        identity: Some(sweep::SweepIdentity {
            skillc_version: env!("CARGO_PKG_VERSION").to_string(),
            inputs: sweep_fingerprint(args),
            skills: prepared.iter().map(|p| p.name.clone()).collect(),
            shares: partition.m,
        }),
        elapsed_s: started.elapsed().as_secs_f64(),
        trials: outcomes.into_iter().map(|o| o.result).collect(),
    };
    finish_sweep(&args.out, &summary, args.min_success, verbosity)
}

/// The fingerprint of a sweep's inputs: every file it read and the settings that change a draw.
fn sweep_fingerprint(args: &EvalArgs) -> String {
    let settings = format!(
        "params {:?}\nlimits {:?}\nrobot {:?}\nskills {:?}\nfiles {}",
        args.params,
        args.limits,
        args.robot,
        args.skills,
        crate::atomic::inputs_fingerprint()
    );
    crate::defaults::fnv(settings.as_bytes())
}

/// Prints and writes a sweep's (or merged sweeps') report; exit 1 when a skill's success rate is
/// below `min_success`.
fn finish_sweep(
    out: &Path,
    summary: &sweep::SweepSummary,
    min_success: f64,
    verbosity: Verbosity,
) -> Result<u8, Failure> {
    let text = sweep::table(summary);
    say(
        verbosity,
        &format!("{text}{} trials in {:.1} s\n", summary.trials.len(), summary.elapsed_s),
    )?;
    let written = sweep::write(out, summary, &text)
        .map_err(|err| Failure::Usage(format!("cannot write the report to `{}`: {err}", out.display())))?;
    say(verbosity, &format!("report: {}\n", written.display()))?;
    let low: Vec<(String, f64)> = sweep::rates(&summary.trials)
        .into_iter()
        .filter(|(_, rate)| *rate < min_success)
        .collect();
    for (skill, rate) in &low {
        eprintln!(
            "skill `{skill}` succeeded in {:.1} % of its draws, below the required {:.1} %",
            rate * 100.0,
            min_success * 100.0
        );
    }
    Ok(u8::from(!low.is_empty()))
}

/// `skillc eval merge`: each argument a share's `summary.json` or the folder its `--out` named.
/// Shares that do not belong together are refused; missing shares fail the merge (exit 1)
/// after its report is written.
fn merge(out: &Path, min_success: f64, summaries: &[PathBuf], verbosity: Verbosity) -> Result<u8, Failure> {
    let mut parts = Vec::new();
    for given in summaries {
        let path = if given.is_dir() {
            given.join("summary.json")
        } else {
            given.clone()
        };
        let text = std::fs::read_to_string(&path).map_err(|err| {
            Failure::Usage(format!(
                "cannot read `{}`: {err}{}",
                path.display(),
                if given.is_dir() {
                    " (is the folder a sweep's --out?)"
                } else {
                    ""
                }
            ))
        })?;
        crate::atomic::note_input(&path);
        let part: sweep::SweepSummary = serde_json::from_str(&text).map_err(|err| {
            Failure::Input(format!(
                "`{}` is not a sweep summary of this skillc (written by `skillc eval --sweep`): {err}",
                path.display()
            ))
        })?;
        parts.push((path.display().to_string(), part));
    }
    // The summaries are noted inputs: an `--out` that is one of them is refused here.
    crate::atomic::refuse_inputs(&out.join("summary.json"), "--out", &[]).map_err(Failure::Usage)?;
    let merged = sweep::merge(parts).map_err(Failure::Input)?;
    let code = finish_sweep(out, &merged.summary, min_success, verbosity)?;
    if !merged.missing.is_empty() {
        eprintln!(
            "error: the merge lacks share{} {} of the sweep: its report covers only the shares given",
            if merged.missing.len() == 1 { "" } else { "s" },
            merged.missing.join(", ")
        );
        return Ok(1);
    }
    Ok(code)
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

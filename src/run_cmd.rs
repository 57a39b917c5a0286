//! `skillc run`: reproduce a skill (or a task) in simulation and summarise what happened.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use skill_runtime::exec::{
    bind, run_on_plant, run_task_on_plant, simulate, simulate_task, BoundSkill, ExecOptions, Mode, RunLog, RunReport,
    SessionError, TaskStep,
};
use skill_runtime::skill::{LearnOptions, Learned};

use crate::link::scene_with_robot;
use crate::run_log::{self, LiveLog};
use skill_kit::atomic;
use skill_kit::load::{error_chain, learn_from_files, learn_from_source, load_skill_with, read_learned, Failure};
use skill_kit::out::Verbosity;
use skill_kit::plot::{self, Plot, Subject, Trial};
use skill_runtime::demo::Dialect;

/// Arguments of `skillc run`.
#[derive(Debug, Clone, clap::Args)]
pub struct RunArgs {
    /// The `.skill` file with the skill (or task) to run.
    pub file: PathBuf,
    /// The skill to run, when the file defines several.
    #[arg(long, conflicts_with = "task")]
    pub skill: Option<String>,
    /// The task to run (default: the file's first task, when it has tasks and no --skill is given).
    #[arg(long)]
    pub task: Option<String>,
    /// The learned file (from `skillc learn`); tasks name their own inputs.
    #[arg(long, conflicts_with = "demo")]
    pub learned: Option<PathBuf>,
    /// Learn from this demonstration first instead of reading a learned file (CSV, or MCAP with
    /// its pose and wrench topics found by type).
    #[arg(long)]
    pub demo: Option<PathBuf>,
    /// With --demo as a ROS 2 bag (MCAP): the `geometry_msgs/PoseStamped` topic with the flange
    /// pose (default: the file's only one, else TF).
    #[arg(long, value_name = "TOPIC", requires = "demo", conflicts_with_all = ["tf_parent", "tf_child"])]
    pub pose_topic: Option<String>,
    /// With --demo as a ROS 2 bag: the `geometry_msgs/WrenchStamped` topic (default: the only one).
    #[arg(long, value_name = "TOPIC", requires = "demo")]
    pub wrench_topic: Option<String>,
    /// With --demo as a ROS 2 bag: read the pose from TF, the transform from this base frame.
    #[arg(long, value_name = "FRAME", requires = "demo")]
    pub tf_parent: Option<String>,
    /// With --demo as a ROS 2 bag: read the pose from TF, the transform to this tool frame.
    #[arg(long, value_name = "FRAME", requires = "demo")]
    pub tf_child: Option<String>,
    /// The scene (TOML).
    #[arg(long)]
    pub scene: PathBuf,
    /// Change a scene value, e.g. `--set table.z=0.195` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Set a skill parameter, e.g. `--param hold=5s` (repeatable): in every skill of the file
    /// that declares it; a task step's own values come after it.
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Write every control tick to this file: CSV, or a ROS 2 bag when it ends in `.mcap`
    /// (/joint_states, /tool_pose, /desired_pose, /wrench, /skill_state; see the README).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also draw the run into this folder (SVG): tool path against the demonstration, force
    /// along the compliant z, world-frame forces, state timeline. Needs `--demo`.
    #[arg(long, value_name = "DIR", requires = "demo")]
    pub plot: Option<PathBuf>,
    /// Run the baseline instead: the learned motions replayed under pure impedance control.
    #[arg(long)]
    pub replay: bool,
    /// Start from where the scene puts the arm instead of first moving (guarded) to the
    /// demonstrated start: what `skillc eval` does, so its trials and sweep draws repeat exactly.
    #[arg(long)]
    pub no_prepose: bool,
    /// Multiply every desired force and force threshold.
    #[arg(long, default_value_t = 1.0, value_parser = skill_kit::limits::factor)]
    pub force_scale: f64,
    /// Multiply the motion speed.
    #[arg(long, default_value_t = 1.0, value_parser = skill_kit::limits::factor)]
    pub speed: f64,
    /// Tighten or loosen a safety limit, in SI units, e.g. `--limit force=60` (N),
    /// `--limit speed=0.1` (m/s); `inf` switches a check off. Names: force, moment, speed,
    /// angular_speed, joint_margin, joint_speed, saturation, tracking, tracking_angle, arm_contact (repeatable).
    #[arg(long = "limit", value_name = "NAME=VALUE", value_parser = skill_kit::limits::parse_limit)]
    pub limits: Vec<(String, f64)>,
    /// Run on this shipped robot (`lwr4`, `iiwa14`) instead of the scene's, its tool starting
    /// where the scene's robot starts its tool.
    #[arg(long, value_name = "NAME")]
    pub robot: Option<String>,
    /// The plant in another process (`skillc plant`).
    #[command(flatten)]
    pub link: crate::link::LinkArgs,
}

/// Runs on the plant `--plant` names (`remote`, given the scene's robot model), or simulates
/// here (`here`); the link's line when the run printed one.
fn on_plant_or_here<T>(
    scene: &skill_runtime::sim::Scene,
    link: &crate::link::LinkArgs,
    remote: impl FnOnce(skill_runtime::robot::Robot, &mut dyn skill_runtime::plant::Plant) -> Result<T, SessionError>,
    here: impl FnOnce() -> Result<T, SessionError>,
) -> Result<(T, Option<String>), Failure> {
    let Some(endpoint) = &link.plant else {
        return Ok((here().map_err(|err| Failure::Input(error_chain(&err)))?, None));
    };
    #[cfg(feature = "zenoh")]
    return crate::link::run_remote(scene, link, endpoint, remote);
    #[cfg(not(feature = "zenoh"))]
    {
        let _ = (scene, endpoint, remote);
        Err(crate::link::without_zenoh())
    }
}

/// The writer of a run's `-o` log while the run goes on; `None` without `-o`, and in
/// `--realtime` against a plant, where a second busy thread on the run's side could make its
/// commands late (that log is written after the run).
fn live_log(args: &RunArgs, scene: &skill_runtime::sim::Scene) -> Result<Option<LiveLog>, Failure> {
    match &args.output {
        Some(path) if !args.link.realtime => LiveLog::start(path, scene).map(Some),
        _ => Ok(None),
    }
}

/// Runs `skillc run`. `--quiet` prints nothing but errors (a run that ends in failure is one);
/// `--verbose` adds the wall-clock time.
pub fn run(args: &RunArgs, verbosity: Verbosity) -> u8 {
    let started = std::time::Instant::now();
    match run_inner(args) {
        Ok((report, text)) => {
            verbosity.detail(format_args!(
                "ran in {:.2} s (wall clock)",
                started.elapsed().as_secs_f64()
            ));
            let failed = report.outcome == skill_ir::Outcome::Failure;
            if verbosity.quiet() {
                if failed {
                    eprintln!("error: `{}` ended in failure: {}", args.file.display(), report.message);
                }
            } else if let Err(code) = skill_kit::out::print_or_code(&text) {
                return code;
            }
            u8::from(failed)
        }
        Err(failure) => failure.report(),
    }
}

/// The bag topics the flags name (`--pose-topic` ...), refused for a CSV demonstration.
fn bag_options(args: &RunArgs) -> Result<skill_ros::bag::BagOptions, Failure> {
    let bag = skill_ros::bag::BagOptions {
        pose_topic: args.pose_topic.clone(),
        wrench_topic: args.wrench_topic.clone(),
        tf_parent: args.tf_parent.clone(),
        tf_child: args.tf_child.clone(),
    };
    let is_bag = args.demo.as_deref().is_some_and(skill_ros::bag::is_mcap);
    if bag != skill_ros::bag::BagOptions::default() && !is_bag {
        return Err(Failure::Usage(
            "--pose-topic, --wrench-topic, --tf-parent and --tf-child are for a --demo that is a ROS 2 bag (`.mcap`)"
                .into(),
        ));
    }
    Ok(bag)
}

fn run_inner(args: &RunArgs) -> Result<(RunReport, String), Failure> {
    if let Some(out) = &args.output {
        let mut inputs: Vec<&std::path::Path> = vec![&args.file, &args.scene];
        inputs.extend(args.learned.as_deref());
        inputs.extend(args.demo.as_deref());
        atomic::refuse_inputs(out, "-o", &inputs).map_err(Failure::Usage)?;
    }
    if args.skill.is_none() {
        let compilation = skill_kit::frontend::compile_path_with(&args.file, &args.params)
            .map_err(|err| Failure::Usage(err.to_string()))?;
        if let Some(program) = &compilation.program {
            let task = match &args.task {
                Some(name) => Some(
                    program
                        .task(name)
                        .ok_or_else(|| Failure::Usage(format!("`{}` has no task `{name}`", args.file.display())))?,
                ),
                None => program.tasks.first(),
            };
            if let Some(task) = task {
                return run_task(args, program, task);
            }
        }
    }
    let (_, skill) = load_skill_with(&args.file, args.skill.as_deref(), &args.params)?;
    let learned = match (&args.learned, &args.demo) {
        (Some(path), _) => read_learned(path)?,
        (None, Some(demo)) => {
            learn_from_source(
                &skill,
                demo,
                &Dialect::default(),
                &bag_options(args)?,
                &LearnOptions::default(),
                false,
            )?
            .0
        }
        (None, None) => {
            return Err(Failure::Usage(
                "give the learned file (--learned L.json) or a demonstration (--demo D.csv)".into(),
            ))
        }
    };
    let scene = scene_with_robot(&args.scene, &args.sets, args.robot.as_deref())?;
    refuse_noted_output(args)?;
    let live = live_log(args, &scene)?;
    let options = ExecOptions {
        overrides: skill_ir::Overrides {
            force_scale: args.force_scale,
            speed_factor: args.speed,
            goal_offset_m: [0.0; 3],
        },
        limits: args.limits.clone(),
        prepose: !args.no_prepose,
        tap: live.as_ref().map(LiveLog::tap),
        ..ExecOptions::default()
    };
    let bound = bind(&skill, &learned).map_err(|err| Failure::Input(err.to_string()))?;
    let mode = if args.replay {
        Mode::Replay(&learned)
    } else {
        Mode::Skill(&bound)
    };
    let ((report, log), link_line) = on_plant_or_here(
        &scene,
        &args.link,
        |robot, plant| run_on_plant(&scene, robot, plant, mode, &options),
        || simulate(&scene, mode, &options),
    )?;
    if let Some(path) = &args.output {
        match live {
            Some(live) => live.finish(path)?,
            None => run_log::write_after(path, &[(None, &log)], &scene)?,
        }
    }
    let mut text = summary(&skill.name, args.replay, &report, &log);
    if let Some(line) = link_line {
        let _ = writeln!(text, "  {line}");
    }
    if let Some(path) = &args.output {
        let _ = writeln!(text, "wrote `{}` ({} ticks)", path.display(), log.ticks.len());
    }
    if let (Some(dir), Some(demo)) = (&args.plot, &args.demo) {
        plot_run(dir, demo, &bound, args.replay, &log, &mut text)?;
    }
    Ok((report, text))
}

/// Draws the eval's plots for one run.
fn plot_run(
    dir: &Path,
    demo: &Path,
    bound: &BoundSkill<'_>,
    replay: bool,
    log: &RunLog,
    text: &mut String,
) -> Result<(), Failure> {
    std::fs::create_dir_all(dir).map_err(|err| Failure::Usage(format!("cannot create `{}`: {err}", dir.display())))?;
    let name = &bound.skill.name;
    let subject = Subject {
        name,
        demo,
        bound: Some(bound),
    };
    let trial = Trial {
        variant: "this run",
        replay,
        error: false,
        log,
    };
    for kind in [Plot::Trajectory, Plot::Force, Plot::WorldForce, Plot::Timeline] {
        let path = dir.join(format!("{name}_{}.svg", kind.name()));
        plot::draw(kind, &path, &subject, &[trial])
            .map_err(|err| Failure::Usage(format!("cannot plot `{}`: {err}", kind.name())))?;
        let _ = writeln!(text, "wrote `{}`", path.display());
    }
    Ok(())
}

/// Per-state contact statistics of a run: applied force along the compliant frame's z.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateStats {
    /// Ticks in the state.
    pub ticks: usize,
    /// Mean applied force along the compliant z \[N\].
    pub mean_n: f64,
    /// Largest applied force along the compliant z \[N\].
    pub max_n: f64,
    /// RMS of (desired − applied) along z on force-controlled ticks \[N\], if any.
    pub rms_error_n: Option<f64>,
    /// Mean desired force along z on force-controlled ticks \[N\], if any.
    pub mean_desired_n: Option<f64>,
}

/// Statistics per state index of the log.
pub fn state_stats(log: &RunLog) -> Vec<StateStats> {
    let mut sums = vec![(0usize, 0.0, f64::NEG_INFINITY, 0usize, 0.0, 0.0); log.states.len()];
    for tick in &log.ticks {
        let entry = &mut sums[tick.state as usize];
        let fz = tick.wrench_cf[2];
        entry.0 += 1;
        entry.1 += fz;
        entry.2 = entry.2.max(fz);
        if tick.selection & (1 << 2) == 0 {
            entry.3 += 1;
            entry.4 += (tick.desired_cf[2] - fz).powi(2);
            entry.5 += tick.desired_cf[2];
        }
    }
    sums.into_iter()
        .map(|(ticks, sum, max, force_ticks, sq, desired)| StateStats {
            ticks,
            mean_n: if ticks > 0 { sum / ticks as f64 } else { 0.0 },
            max_n: if ticks > 0 { max } else { 0.0 },
            rms_error_n: (force_ticks > 0).then(|| (sq / force_ticks as f64).sqrt()),
            mean_desired_n: (force_ticks > 0).then(|| desired / force_ticks as f64),
        })
        .collect()
}

/// The human summary of a run.
pub fn summary(skill: &str, replay: bool, report: &RunReport, log: &RunLog) -> String {
    let heading = format!("{} `{skill}`", if replay { "replay of" } else { "skill" });
    summary_under(&heading, report, log)
}

/// The human summary of a run under `heading` (what ran).
fn summary_under(heading: &str, report: &RunReport, log: &RunLog) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{heading}: {:.2} s simulated", report.duration_s);
    let stats = state_stats(log);
    let _ = writeln!(
        out,
        "  {:<18} {:>8} {:>8}   {:>8} {:>8} {:>9}",
        "state", "enter s", "exit s", "F̄z N", "max Fz N", "Fz err N"
    );
    for visit in &report.visits {
        let index = log.states.iter().position(|s| *s == visit.state);
        let stat = index.and_then(|i| stats.get(i)).cloned().unwrap_or_default();
        let error = match (stat.rms_error_n, stat.mean_desired_n) {
            (Some(rms), Some(desired)) => format!("{rms:.2} of {desired:.1}"),
            _ => "-".to_string(),
        };
        let _ = writeln!(
            out,
            "  {:<18} {:>8.3} {:>8.3}   {:>8.2} {:>8.2} {:>9}",
            visit.state, visit.enter_s, visit.exit_s, stat.mean_n, stat.max_n, error
        );
    }
    let safety = &report.safety;
    let _ = writeln!(
        out,
        "  safety: peak force {:.1} N, peak tool speed {:.3} m/s, smallest joint margin {:.3} rad, {:.3} s at a torque limit",
        safety.peak_force_n, safety.peak_tool_speed_mps, safety.min_joint_margin_rad, safety.torque_limit_s
    );
    if let Some(audit) = &report.contact {
        let _ = writeln!(out, "  {}", audit.summary());
    }
    let status = match report.outcome {
        skill_ir::Outcome::Success => "success",
        skill_ir::Outcome::Failure => "FAILURE",
    };
    let _ = writeln!(out, "{status}: {}", report.message);
    out
}

/// Refuses `-o` when it is a file read so far (imports, the scene's robot, ...) or lies in a folder
/// that does not exist, before the run.
fn refuse_noted_output(args: &RunArgs) -> Result<(), Failure> {
    let Some(out) = &args.output else { return Ok(()) };
    atomic::refuse_inputs(out, "-o", &[]).map_err(Failure::Usage)?;
    // Said before the run, not after it: a run may take minutes.
    match out.parent().filter(|dir| !dir.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => Err(Failure::Usage(format!(
            "cannot write `{}`: the folder `{}` does not exist; create it or choose another -o",
            out.display(),
            dir.display()
        ))),
        _ => Ok(()),
    }
}

/// Learns (or reads) what a task step needs.
fn step_learned(program: &skill_ir::Program, step: &skill_ir::Step) -> Result<(skill_ir::Skill, Learned), Failure> {
    let skill = step
        .skill_in(program)
        .cloned()
        .ok_or_else(|| Failure::Input(format!("step `{}` runs unknown skill `{}`", step.name, step.skill)))?;
    let learned = match &step.input {
        skill_ir::StepInput::Demo(path) => {
            learn_from_files(&skill, Path::new(path), &skill_kit::load::step_learn_options(step)).map_err(
                |failure| match failure {
                    Failure::Input(message) => Failure::Input(format!("step `{}`: {message}", step.name)),
                    other => other,
                },
            )?
        }
        skill_ir::StepInput::Learned(path) => read_learned(Path::new(path))?,
    };
    Ok((skill, learned))
}

/// `step `last` learned contact phase 3 of 3 (14.20-20.40 s, median 6.6 N), as its `phase:` says`,
/// for a step that learned from one phase of its demonstration.
fn step_phase_line(step: &skill_ir::Step, learned: &Learned) -> Option<String> {
    let phases = learned.quality.phases.as_ref()?;
    let phase = phases.learned?;
    let [on, off] = *phases.phases_s.get(phase.checked_sub(1)?)?;
    let median = phases.median_n.get(phase - 1).copied().unwrap_or(f64::NAN);
    let why = if step.phase.is_some() {
        "as its `phase:` says"
    } else {
        "the longest; `phase: N` picks another"
    };
    Some(format!(
        "step `{}` learned contact phase {phase} of {} ({on:.2}-{off:.2} s, median {median:.1} N), {why}",
        step.name,
        phases.phases_s.len()
    ))
}

fn bind_all<'b, 'a>(
    steps: &'b [skill_ir::Step],
    prepared: &'a [(skill_ir::Skill, Learned)],
) -> Result<Vec<TaskStep<'b, 'a>>, Failure> {
    steps
        .iter()
        .zip(prepared)
        .map(|(step, (skill, learned))| {
            bind(skill, learned)
                .map(|bound| TaskStep { step, bound })
                .map_err(|err| Failure::Input(format!("step `{}`: {err}", step.name)))
        })
        .collect()
}

fn run_task(
    args: &RunArgs,
    program: &skill_ir::Program,
    task: &skill_ir::Task,
) -> Result<(RunReport, String), Failure> {
    let scene = scene_with_robot(&args.scene, &args.sets, args.robot.as_deref())?;
    // The steps' demonstrations and learned files are inputs too: refuse an output that is one
    // of them before learning anything.
    for step in task.steps.iter().chain(&task.fallbacks) {
        match &step.input {
            skill_ir::StepInput::Demo(path) | skill_ir::StepInput::Learned(path) => atomic::note_input(Path::new(path)),
        }
    }
    refuse_noted_output(args)?;
    let prepared: Vec<(skill_ir::Skill, Learned)> = task
        .steps
        .iter()
        .map(|step| step_learned(program, step))
        .collect::<Result<_, _>>()?;
    let prepared_fallbacks: Vec<(skill_ir::Skill, Learned)> = task
        .fallbacks
        .iter()
        .map(|step| step_learned(program, step))
        .collect::<Result<_, _>>()?;
    let steps = bind_all(&task.steps, &prepared)?;
    let fallbacks = bind_all(&task.fallbacks, &prepared_fallbacks)?;
    let live = live_log(args, &scene)?;
    let options = ExecOptions {
        limits: args.limits.clone(),
        prepose: !args.no_prepose,
        tap: live.as_ref().map(LiveLog::tap),
        ..ExecOptions::default()
    };
    let (run, link_line) = on_plant_or_here(
        &scene,
        &args.link,
        |robot, plant| run_task_on_plant(&scene, robot, plant, &steps, &fallbacks, &options),
        || simulate_task(&scene, &steps, &fallbacks, &options),
    )?;
    if let Some(path) = &args.output {
        let logs: Vec<(Option<&str>, &RunLog)> = run
            .steps
            .iter()
            .map(|step| (Some(step.step.as_str()), &step.log))
            .collect();
        match live {
            Some(live) => live.finish(path)?,
            None => run_log::write_after(path, &logs, &scene)?,
        }
    }
    let mut text = String::new();
    // The header counts the task's own steps (run.steps also holds a fallback that ran).
    let ran = run.steps.iter().filter(|step| !step.fallback).count();
    let fallbacks: Vec<String> = run
        .steps
        .iter()
        .filter(|step| step.fallback)
        .map(|step| format!(", fallback `{}` ran", step.step))
        .collect();
    let _ = writeln!(
        text,
        "task `{}`: {ran} of {} step(s) ran{}",
        task.name,
        task.steps.len(),
        fallbacks.concat()
    );
    // A step that learned from one contact phase of its recording says which (issue 26: mixing
    // or picking phases is never silent).
    for (step, (_, learned)) in task
        .steps
        .iter()
        .zip(&prepared)
        .chain(task.fallbacks.iter().zip(&prepared_fallbacks))
    {
        if let Some(line) = step_phase_line(step, learned) {
            let _ = writeln!(text, "  {line}");
        }
    }
    for step in &run.steps {
        let title = format!(
            "{}step `{}` ({})",
            if step.fallback { "fallback " } else { "" },
            step.step,
            step.skill
        );
        text.push_str(&summary_under(&title, &step.report, &step.log));
    }
    let outcome = run.outcome;
    let status = match outcome {
        skill_ir::Outcome::Success => "task succeeded",
        skill_ir::Outcome::Failure => "TASK FAILED",
    };
    let _ = writeln!(text, "{status}");
    if let Some(line) = link_line {
        let _ = writeln!(text, "  {line}");
    }
    if let Some(path) = &args.output {
        let _ = writeln!(text, "wrote `{}` ({} ticks)", path.display(), run.ticks());
    }
    let last = run
        .steps
        .last()
        .map_or_else(|| RunReport::not_started(String::new()), |step| step.report.clone());
    Ok((RunReport { outcome, ..last }, text))
}

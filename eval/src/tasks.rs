//! `[[task]]` trials of `skillc eval`: each step of a task learned once from its `demo:`, the
//! task run in every variant of its scene through the closed loop `skillc run` runs tasks with
//! (`simulate_task`, each step starting where the last ended), and judged step by step with the
//! skill trials' criteria and peak-force bound. Tasks have no replay baseline.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use skill_runtime::exec::{bind, simulate_task, BoundSkill, ExecOptions, RunLog, StepReport, TaskStep};
use skill_runtime::skill::Learned;

use super::metrics::{self, ContactPlan};
use super::{robot, Criteria, Outcome, TrialResult, Variant};
use skill_kit::load::{error_chain, learn_from_files, load_program_with, load_scene, Failure};
use skill_kit::profile::DesiredProfile;

/// The trials of one task (a `[[task]]` entry of a trials file).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskTrials {
    /// The `.skill` file with the task; its steps' `demo:` paths are relative to it.
    pub file: PathBuf,
    /// The task's name, when the file defines several (default: its first task).
    #[serde(default)]
    pub name: Option<String>,
    /// The scene.
    pub scene: PathBuf,
    /// Success thresholds per step name; a step not named is judged by the criteria of the
    /// trials file's `[[skill]]` entry for its skill, else by its skill's kind
    /// ([`derived_criteria`]).
    #[serde(default)]
    pub criteria: BTreeMap<String, Criteria>,
    /// Skill parameters, as `--param` takes them: for every skill of the task's file that
    /// declares them, before a step's own settings.
    #[serde(default)]
    pub params: Vec<String>,
    /// The scene variants.
    pub variants: Vec<Variant>,
}

/// How one step of a task trial went (an entry of a task trial's `steps` in `summary.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StepResult {
    /// The step's name.
    pub step: String,
    /// The skill it runs.
    pub skill: String,
    /// Whether it is a fallback (run after a failing step; never judged).
    pub fallback: bool,
    /// Whether it ran (the steps after a failing one do not).
    pub ran: bool,
    /// Whether it reached a success terminal without a reflex and met every criterion.
    pub success: bool,
    /// The criteria it was judged by.
    pub criteria: Criteria,
    /// Where they came from: `task` (the entry's own), `skill` (the `[[skill]]` entry of its
    /// skill), `kind` (derived from the skill).
    pub criteria_from: String,
    /// RMS force error in contact over the learned force.
    pub force_rms_rel: Option<f64>,
    /// Share of the contact phase in contact.
    pub contact_share: Option<f64>,
    /// Peak applied force during the step \[N\].
    pub peak_force_n: f64,
    /// The peak force the step was allowed \[N\]: a × its demonstration's peak + b.
    pub peak_bound_n: Option<f64>,
    /// Final contact force \[N\].
    pub stop_force_n: Option<f64>,
    /// The learned contact force it is judged against \[N\].
    pub learned_force_n: Option<f64>,
    /// Simulated duration of the step \[s\].
    pub duration_s: f64,
    /// How the step ended.
    pub message: String,
    /// Why it failed (`contact_witness`, `reflex:...`, `lost_contact`, `terminal:NAME`, `anchor`, `criterion:...`, `not_run`);
    /// `None` when it succeeded.
    pub reason: Option<String>,
    /// States visited with entry times, `state@t`.
    pub states: Vec<String>,
}

/// What one step learned, once per eval run.
struct StepLearned {
    learned: Learned,
    /// The demonstration (resolved against the task file).
    demo: PathBuf,
    /// The demonstration's largest force magnitude \[N\].
    demo_peak_n: f64,
}

/// A task learned and ready for trials.
pub(super) struct Ready {
    program: skill_ir::Program,
    task: usize,
    steps: Vec<StepLearned>,
    fallbacks: Vec<StepLearned>,
    /// Each step's criteria and where they came from.
    criteria: Vec<(Criteria, &'static str)>,
}

/// A task entry prepared for its trials: learned, or why it cannot run.
pub(super) struct PreparedTask {
    /// The task's name (its entry's name or file stem when it did not compile).
    pub name: String,
    pub spec: TaskTrials,
    base_dir: PathBuf,
    pub ready: Result<Ready, String>,
    /// The robot `--robot` puts into every scene.
    pub swap: Option<std::sync::Arc<robot::Swap>>,
    /// The command line's `--param` settings.
    command_line: Vec<String>,
}

impl PreparedTask {
    /// The parameters some skill of the task's file declares.
    pub(super) fn declares(&self, name: &str) -> bool {
        self.ready.as_ref().is_ok_and(|ready| {
            ready
                .program
                .skills
                .iter()
                .any(|skill| skill.params.iter().any(|p| p.name == name))
        })
    }
}

/// The name `--skill` selects a task entry by: its `name`, else its file's stem.
pub(super) fn stem(spec: &TaskTrials) -> String {
    spec.name.clone().unwrap_or_else(|| {
        spec.file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    })
}

fn message_of(failure: Failure) -> String {
    match failure {
        Failure::Input(message) | Failure::Usage(message) => message,
        Failure::Closed => "standard output closed".to_string(),
    }
}

/// Compiles the task's file with the entry's `params`, then those of the command line that a
/// skill of the file declares, and finds the task.
fn compile(
    spec: &TaskTrials,
    file: &Path,
    own: &[String],
    command_line: &[String],
) -> Result<(skill_ir::Program, usize), String> {
    let field = |message: String| format!("`[[task]]` file `{}`: {message}", spec.file.display());
    let mut program = load_program_with(file, own).map_err(|failure| field(message_of(failure)))?;
    if !command_line.is_empty() {
        let mut params = own.to_vec();
        params.extend(
            command_line
                .iter()
                .filter(|setting| {
                    let name = setting.split('=').next().unwrap_or_default().trim();
                    program
                        .skills
                        .iter()
                        .any(|skill| skill.params.iter().any(|p| p.name == name))
                })
                .cloned(),
        );
        program = load_program_with(file, &params).map_err(|failure| field(message_of(failure)))?;
    }
    let index = match &spec.name {
        Some(name) => program
            .tasks
            .iter()
            .position(|task| task.name == *name)
            .ok_or_else(|| {
                let names: Vec<&str> = program.tasks.iter().map(|t| t.name.as_str()).collect();
                field(format!(
                    "has no task `{name}`{}",
                    if names.is_empty() {
                        String::new()
                    } else {
                        format!("; it has {}", names.join(", "))
                    }
                ))
            })?,
        None if program.tasks.is_empty() => {
            let skills: Vec<&str> = program.skills.iter().map(|s| s.name.as_str()).collect();
            return Err(field(format!(
                "defines no task (it defines the skill(s) {}: list a skill under `[[skill]]`)",
                skills.join(", ")
            )));
        }
        None => 0,
    };
    Ok((program, index))
}

/// Learns one step (or fallback) from its demonstration.
fn learn_step(program: &skill_ir::Program, step: &skill_ir::Step, spec: &TaskTrials) -> Result<StepLearned, String> {
    let field = |message: String| {
        format!(
            "`[[task]]` file `{}`, step `{}`: {message}",
            spec.file.display(),
            step.name
        )
    };
    let skill = step
        .skill_in(program)
        .ok_or_else(|| field(format!("runs unknown skill `{}`", step.skill)))?;
    let demo = match &step.input {
        skill_ir::StepInput::Demo(path) => PathBuf::from(path),
        skill_ir::StepInput::Learned(path) => {
            return Err(field(format!(
                "reads the learned file `{path}`; eval learns each step from its demonstration \
                 (`demo:`), whose peak force bounds the step's"
            )))
        }
    };
    let learned =
        learn_from_files(skill, &demo, &skill_kit::load::step_learn_options(step)).map_err(|f| field(message_of(f)))?;
    // The peak the step is judged against is its demonstration's, within the contact phase it
    // learned from when it learned from one (the other phases are other steps' work).
    let phase_s = learned
        .quality
        .phases
        .as_ref()
        .and_then(|phases| phases.phases_s.get(phases.learned?.checked_sub(1)?).copied());
    let demo_peak_n = skill_kit::load::read_demo(&demo, &Default::default(), &Default::default())
        .map(|(loaded, _, _)| {
            let demo = &loaded.demo;
            demo.force_n
                .iter()
                .zip(&demo.t_s)
                .filter(|(_, t)| phase_s.is_none_or(|[on, off]| (on..=off).contains(*t)))
                .map(|(f, _)| f.norm())
                .fold(0.0, f64::max)
        })
        .map_err(|f| field(message_of(f)))?;
    Ok(StepLearned {
        learned,
        demo,
        demo_peak_n,
    })
}

/// The criteria a step of a task is judged by when the task's entry does not name it: those of
/// a skill that stops once its contact force is reached (a touch, a guarded move: every contact
/// state is left on `force_reached` for a state outside the contact phase) are the touch's,
/// the stop force within 20 %; those of other skills with a contact force the slide's, force
/// RMS within 10 % and 95 % of the contact phase in contact; a skill without one has none (it
/// is still judged by its terminal, reflexes and the peak bound).
pub fn derived_criteria(bound: &BoundSkill<'_>) -> Criteria {
    let plan = ContactPlan::of(bound);
    if plan.force.is_none() {
        return Criteria::default();
    }
    let skill = bound.skill;
    let in_contact = |id: skill_ir::StateId| plan.skill_states.contains(&skill.states[id.index()].name);
    let stops_on_force = plan.skill_states.iter().all(|name| {
        let Some(from) = skill.states.iter().position(|s| s.name == *name) else {
            return false;
        };
        skill.transitions.iter().any(|t| {
            t.from.index() == from
                && mentions_force_reached(&t.guard)
                && matches!(&t.action, skill_ir::TransitionAction::Goto { target } if !in_contact(*target))
        })
    });
    if stops_on_force {
        Criteria {
            stop_force_rel: Some(0.20),
            ..Criteria::default()
        }
    } else {
        Criteria {
            force_rms_rel: Some(0.10),
            contact_share: Some(0.95),
            ..Criteria::default()
        }
    }
}

fn mentions_force_reached(guard: &skill_ir::Guard) -> bool {
    match guard {
        skill_ir::Guard::ForceReached { .. } => true,
        skill_ir::Guard::And { all } => all.iter().any(mentions_force_reached),
        skill_ir::Guard::Held { guard, .. } => mentions_force_reached(guard),
        _ => false,
    }
}

/// Compiles and learns a task entry: every step and fallback from its demonstration (a skill
/// and demonstration used by several steps learned once), each step's criteria chosen.
/// `skill_criteria` are the `[[skill]]` entries' criteria by skill name.
pub(super) fn prepare(
    spec: TaskTrials,
    base_dir: &Path,
    command_line: &[String],
    skill_criteria: &BTreeMap<String, Criteria>,
) -> PreparedTask {
    let file = base_dir.join(&spec.file);
    let ready = compile(&spec, &file, &spec.params, command_line).and_then(|(program, index)| {
        let task = &program.tasks[index];
        if let Some(unknown) = spec.criteria.keys().find(|name| !task.steps.iter().any(|s| s.name == **name)) {
            let names: Vec<&str> = task.steps.iter().map(|s| s.name.as_str()).collect();
            return Err(format!(
                "`[[task]]` file `{}`: `criteria` names step `{unknown}`, which task `{}` does not have; its steps are {}",
                spec.file.display(),
                task.name,
                names.join(", ")
            ));
        }
        let learn_all = |steps: &[skill_ir::Step]| -> Result<Vec<StepLearned>, String> {
            steps.par_iter().map(|step| learn_step(&program, step, &spec)).collect()
        };
        let steps = learn_all(&task.steps)?;
        let fallbacks = learn_all(&task.fallbacks)?;
        let mut criteria = Vec::new();
        for (step, learned) in task.steps.iter().zip(&steps) {
            let chosen = if let Some(own) = spec.criteria.get(&step.name) {
                (*own, "task")
            } else if let Some(entry) = skill_criteria.get(&step.skill) {
                (*entry, "skill")
            } else {
                let skill = step.skill_in(&program).ok_or_else(|| format!("step `{}`: no skill", step.name))?;
                let bound = bind(skill, &learned.learned).map_err(|err| format!("step `{}`: {err}", step.name))?;
                (derived_criteria(&bound), "kind")
            };
            criteria.push(chosen);
        }
        Ok(Ready {
            program,
            task: index,
            steps,
            fallbacks,
            criteria,
        })
    });
    let name = ready
        .as_ref()
        .map(|ready| ready.program.tasks[ready.task].name.clone())
        .unwrap_or_else(|_| stem(&spec));
    PreparedTask {
        name,
        spec,
        base_dir: base_dir.to_path_buf(),
        ready,
        swap: None,
        command_line: command_line.to_vec(),
    }
}

/// An error row: the trial could not run.
fn failed(prepared: &PreparedTask, variant: &Variant, sets: Vec<String>, message: String) -> Outcome {
    Outcome::error(&prepared.name, &variant.name, "task", sets, message)
}

/// Binds every step of `steps` to what it learned.
fn bind_steps<'a>(
    program: &'a skill_ir::Program,
    steps: &'a [skill_ir::Step],
    learned: &'a [StepLearned],
) -> Result<Vec<TaskStep<'a, 'a>>, String> {
    steps
        .iter()
        .zip(learned)
        .map(|(step, learned)| {
            let skill = step
                .skill_in(program)
                .ok_or_else(|| format!("step `{}` runs unknown skill `{}`", step.name, step.skill))?;
            bind(skill, &learned.learned)
                .map(|bound| TaskStep { step, bound })
                .map_err(|err| format!("step `{}`: {err}", step.name))
        })
        .collect()
}

/// Runs one variant of a task and judges it.
pub(super) fn run_trial(prepared: &PreparedTask, variant: &Variant, limits: &[(String, f64)]) -> Outcome {
    let ready = match &prepared.ready {
        Ok(ready) => ready,
        Err(message) => return failed(prepared, variant, variant.set.clone(), message.clone()),
    };
    // A variant that sets parameters compiles the task's file again with them; the steps run
    // with the features learned once (parameters change nothing learned).
    let recompiled;
    let program = if variant.params.is_empty() {
        &ready.program
    } else {
        let mut params = prepared.spec.params.clone();
        params.extend(variant.params.iter().cloned());
        let file = prepared.base_dir.join(&prepared.spec.file);
        recompiled = match compile(&prepared.spec, &file, &params, &prepared.command_line) {
            Ok((program, _)) => program,
            Err(message) => return failed(prepared, variant, variant.set.clone(), message),
        };
        &recompiled
    };
    let Some(task) = program.tasks.get(ready.task) else {
        return failed(prepared, variant, variant.set.clone(), "the task vanished".to_string());
    };
    let (steps, fallbacks) = match (
        bind_steps(program, &task.steps, &ready.steps),
        bind_steps(program, &task.fallbacks, &ready.fallbacks),
    ) {
        (Ok(steps), Ok(fallbacks)) => (steps, fallbacks),
        (Err(message), _) | (_, Err(message)) => return failed(prepared, variant, variant.set.clone(), message),
    };
    let scene_path = prepared.base_dir.join(&prepared.spec.scene);
    let mut sets = variant.set.clone();
    if let Some(swap) = &prepared.swap {
        match swap.sets(&scene_path, &sets) {
            Ok(extra) => sets.extend(extra),
            Err(message) => return failed(prepared, variant, sets, message),
        }
    }
    let scene = match load_scene(&scene_path, &sets) {
        Ok(scene) => scene,
        Err(failure) => return failed(prepared, variant, sets, message_of(failure)),
    };
    // As skill trials: from where the scene puts the arm, no pre-positioning.
    let options = ExecOptions {
        limits: limits.to_vec(),
        prepose: false,
        ..ExecOptions::default()
    };
    let run = match simulate_task(&scene, &steps, &fallbacks, &options) {
        Ok(run) => run,
        Err(err) => return failed(prepared, variant, sets, error_chain(&err)),
    };
    let mut outcome = judge(prepared, ready, &steps, run.steps, variant, sets);
    outcome.objects = scene.spec().objects.clone();
    outcome
}

/// Judges every step of a task's run, in order; the task succeeds when every step does.
fn judge(
    prepared: &PreparedTask,
    ready: &Ready,
    steps: &[TaskStep<'_, '_>],
    reports: Vec<StepReport>,
    variant: &Variant,
    sets: Vec<String>,
) -> Outcome {
    let mut results = Vec::new();
    let mut logs = Vec::new();
    let mut duration_s = 0.0;
    let (mut peak_speed, mut min_margin, mut torque_s) = (0.0_f64, f64::INFINITY, 0.0);
    let mut states = Vec::new();
    let mut goal_error_m = 0.0;
    for report in &reports {
        duration_s += report.report.duration_s;
        let safety = &report.report.safety;
        if !report.report.visits.is_empty() {
            peak_speed = peak_speed.max(safety.peak_tool_speed_mps);
            min_margin = min_margin.min(safety.min_joint_margin_rad);
            torque_s += safety.torque_limit_s;
        }
        states.extend(
            report
                .report
                .visits
                .iter()
                .map(|v| format!("{}/{}@{:.2}", report.step, v.state, v.enter_s)),
        );
    }
    for (index, task_step) in steps.iter().enumerate() {
        let (criteria, from) = ready.criteria[index];
        let Some(report) = reports.iter().find(|r| r.step == task_step.step.name && !r.fallback) else {
            results.push(StepResult {
                step: task_step.step.name.clone(),
                skill: task_step.step.skill.clone(),
                fallback: false,
                ran: false,
                success: false,
                criteria,
                criteria_from: from.to_string(),
                force_rms_rel: None,
                contact_share: None,
                peak_force_n: 0.0,
                peak_bound_n: None,
                stop_force_n: None,
                learned_force_n: None,
                duration_s: 0.0,
                message: "not run: an earlier step failed".to_string(),
                reason: Some("not_run".to_string()),
                states: Vec::new(),
            });
            logs.push(RunLog::default());
            continue;
        };
        let (result, goal_error) = judge_step(task_step, report, &ready.steps[index], criteria, from);
        goal_error_m = goal_error;
        results.push(result);
        logs.push(report.log.clone());
    }
    // Fallbacks are listed as they ran; the task has already failed.
    for report in reports.iter().filter(|r| r.fallback) {
        results.push(StepResult {
            step: report.step.clone(),
            skill: report.skill.clone(),
            fallback: true,
            ran: true,
            success: report.report.outcome == skill_ir::Outcome::Success,
            criteria: Criteria::default(),
            criteria_from: "fallback".to_string(),
            force_rms_rel: None,
            contact_share: None,
            peak_force_n: report.report.safety.peak_force_n,
            peak_bound_n: None,
            stop_force_n: None,
            learned_force_n: None,
            duration_s: report.report.duration_s,
            message: report.report.message.clone(),
            reason: None,
            states: report
                .report
                .visits
                .iter()
                .map(|v| format!("{}@{:.2}", v.state, v.enter_s))
                .collect(),
        });
        logs.push(report.log.clone());
    }
    let failing = results.iter().find(|r| !r.fallback && r.reason.is_some());
    let reason = failing.map(|r| format!("step {}: {}", r.step, r.reason.as_deref().unwrap_or("?")));
    let message = match failing {
        Some(r) => format!("step `{}` ({}): {}", r.step, r.skill, r.message),
        None => format!("all {} steps succeeded", results.len()),
    };
    let peak_force_n = results.iter().map(|r| r.peak_force_n).fold(0.0, f64::max);
    let contact = reports
        .iter()
        .filter_map(|report| report.report.contact.clone())
        .reduce(|mut all, step| {
            all.merge(step);
            all
        });
    Outcome {
        result: TrialResult {
            skill: prepared.name.clone(),
            variant: variant.name.clone(),
            mode: "task".to_string(),
            success: reason.is_none(),
            force_rms_rel: None,
            contact_share: None,
            peak_force_n,
            stop_force_n: None,
            learned_force_n: None,
            goal_error_m,
            duration_s,
            message,
            reason,
            peak_bound_n: None,
            peak_tool_speed_mps: peak_speed,
            min_joint_margin_rad: if min_margin.is_finite() { min_margin } else { 0.0 },
            torque_limit_s: torque_s,
            error: false,
            states,
            draw: None,
            set: sets,
            steps: results,
            contact,
        },
        log: RunLog::default(),
        step_logs: logs,
        objects: Default::default(),
    }
}

/// Judges one step that ran, as a skill trial is judged; also returns its goal error \[m\].
fn judge_step(
    task_step: &TaskStep<'_, '_>,
    report: &StepReport,
    learned: &StepLearned,
    criteria: Criteria,
    from: &str,
) -> (StepResult, f64) {
    let bound = &task_step.bound;
    let plan = ContactPlan::of(bound);
    let measured = metrics::measure(&report.log, &plan, false, &|_| Vector3::z());
    let learned_force = plan.force.as_ref().map(|force| DesiredProfile::new(force, 0.01).peak());
    let peak_bound = criteria.peak_bound(learned.demo_peak_n);
    let run = &report.report;
    // The first reason the step fails, in the skill trials' order, with what was measured.
    let (reason, detail) = if let Some(reason) = super::run_reason(run) {
        (Some(reason), None)
    } else if run.visits.is_empty() && task_step.step.at.is_some() {
        // `at: STEP.STATE` not found: the step failed before it moved (the message says which).
        (Some("anchor".to_string()), None)
    } else if run.outcome != skill_ir::Outcome::Success {
        (
            Some(format!("terminal:{}", run.terminal.as_deref().unwrap_or("none"))),
            None,
        )
    } else {
        criteria
            .missed(&measured, learned_force, Some(learned.demo_peak_n))
            .map_or((None, None), |(reason, detail)| (Some(reason), Some(detail)))
    };
    let message = match detail {
        Some(detail) => format!("{}; {detail}", run.message),
        None => run.message.clone(),
    };
    let result = StepResult {
        step: task_step.step.name.clone(),
        skill: task_step.step.skill.clone(),
        fallback: false,
        ran: true,
        success: reason.is_none(),
        criteria,
        criteria_from: from.to_string(),
        force_rms_rel: measured.force_rms_rel,
        contact_share: measured.contact_share,
        peak_force_n: measured.peak_force_n,
        peak_bound_n: Some(peak_bound),
        stop_force_n: measured.stop_force_n,
        learned_force_n: learned_force,
        duration_s: run.duration_s,
        message,
        reason,
        states: run
            .visits
            .iter()
            .map(|v| format!("{}@{:.2}", v.state, v.enter_s))
            .collect(),
    };
    (result, measured.goal_error_m)
}

/// What the report shows of a task: its name, error, and per step the bound skill, its
/// demonstration and criteria (for the plots).
pub(super) struct TaskView<'a> {
    pub name: &'a str,
    pub error: Option<&'a str>,
    pub steps: Vec<StepView<'a>>,
}

/// One step of a [`TaskView`].
pub(super) struct StepView<'a> {
    pub step: &'a str,
    /// The plot's name: `task.step`.
    pub title: String,
    pub bound: Option<BoundSkill<'a>>,
    pub demo: &'a Path,
    pub criteria: Criteria,
}

/// The report's view of each prepared task.
pub(super) fn views(prepared: &[PreparedTask]) -> Vec<TaskView<'_>> {
    prepared
        .iter()
        .map(|prep| match &prep.ready {
            Err(message) => TaskView {
                name: &prep.name,
                error: Some(message),
                steps: Vec::new(),
            },
            Ok(ready) => {
                let task = &ready.program.tasks[ready.task];
                TaskView {
                    name: &prep.name,
                    error: None,
                    steps: task
                        .steps
                        .iter()
                        .zip(&ready.steps)
                        .zip(&ready.criteria)
                        .map(|((step, learned), (criteria, _))| StepView {
                            step: &step.name,
                            title: format!("{}.{}", prep.name, step.name),
                            bound: step
                                .skill_in(&ready.program)
                                .and_then(|skill| bind(skill, &learned.learned).ok()),
                            demo: &learned.demo,
                            criteria: *criteria,
                        })
                        .collect(),
                }
            }
        })
        .collect()
}

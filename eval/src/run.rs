//! Running the eval's trials: each skill learned once and bound (`Prepared`, `Bound`), one
//! trial (a variant, or its replay) run and judged against its criteria (`run_job`), and the
//! worker threads they run on.

use super::metrics::{ContactPlan, Metrics};
use super::trials::{Criteria, SkillTrials, Variant};
use super::verdict::run_reason;
use super::{metrics, robot, Outcome, TrialResult};
use skill_kit::load::{error_chain, learn_from_files, load_scene, load_skill_with, Failure};
use skill_kit::out::Verbosity;
use skill_kit::plot;
use skill_kit::profile::DesiredProfile;
use skill_runtime::exec::{bind, simulate, BoundSkill, ExecOptions, Mode};
use skill_runtime::skill::{LearnOptions, Learned};
use std::path::{Path, PathBuf};

/// A learned skill ready for trials (it binds), or why it is not.
pub(super) struct Prepared {
    pub(super) name: String,
    pub(super) program_skill: Result<(skill_ir::Skill, Learned), String>,
    /// The demonstration's largest force magnitude \[N\].
    pub(super) demo_peak_n: f64,
    pub(super) spec: SkillTrials,
    pub(super) base_dir: PathBuf,
    /// The robot `--robot` puts into every scene.
    pub(super) swap: Option<std::sync::Arc<robot::Swap>>,
    /// The command line's `--param` settings.
    pub(super) command_line: Vec<String>,
}

/// One trial to run.
pub(super) enum Job {
    /// A skill's variant, or its replay.
    Skill { skill: usize, variant: usize, replay: bool },
    /// A task's variant.
    Task { task: usize, variant: usize },
}

/// Worker threads per core at most: trials are CPU-bound, so more only adds memory and
/// switching.
pub(super) const THREADS_PER_CORE: usize = 4;

/// The worker threads an eval runs: `--threads` (default one per core), at most
/// [`THREADS_PER_CORE`] per core and at most one per trial, saying so when it lowers the
/// request (`--threads 100000` asked for thousands of threads and did not finish).
pub(super) fn worker_threads(requested: Option<usize>, trials: usize, verbosity: Verbosity) -> usize {
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
pub(super) fn skill_with_params(
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

pub(super) fn prepare(spec: SkillTrials, base_dir: &Path, command_line: &[String]) -> Prepared {
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
    let demo_peak_n = skill_kit::load::read_demo(&demo, &Default::default(), &Default::default())
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
pub(super) type Bound<'a> = Result<(BoundSkill<'a>, ContactPlan), String>;

pub(super) fn bind_prepared(prepared: &Prepared) -> Bound<'_> {
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

pub(super) fn run_job(
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
pub(super) fn replay_frame_z(bound: &BoundSkill<'_>, plan: &ContactPlan, t: f64) -> nalgebra::Vector3<f64> {
    match plan.frame {
        Some(skill_ir::FrameRef::Learned(id)) => bound.frame(id).at(t).rotation * nalgebra::Vector3::z(),
        _ => nalgebra::Vector3::z(),
    }
}

/// What the report needs of each prepared skill.
pub(super) struct SkillView<'a> {
    /// The skill's name.
    pub(super) name: &'a str,
    /// The skill bound to what it learned, if learning worked.
    pub(super) bound: Option<&'a BoundSkill<'a>>,
    /// Why learning failed.
    pub(super) error: Option<&'a str>,
    /// The demonstration path.
    pub(super) demo: PathBuf,
    /// Criteria.
    pub(super) criteria: Criteria,
}

impl SkillView<'_> {
    /// The skill as the plots see it.
    pub(super) fn subject(&self) -> plot::Subject<'_> {
        plot::Subject {
            name: self.name,
            demo: &self.demo,
            bound: self.bound,
        }
    }
}

pub(super) fn prepared_views<'a>(prepared: &'a [Prepared], bound: &'a [Bound<'a>]) -> Vec<SkillView<'a>> {
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

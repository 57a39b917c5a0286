//! Driving `skillc eval --sweep`: random draws of each skill's scene run on the worker
//! threads, a share of them (`--part`) written as its own summary, and shares merged
//! (`--merge`); the draws themselves are `sweep.rs`'s.

use super::run::{run_job, Bound, Prepared};
use super::trials::Variant;
use super::{say, sweep, EvalArgs, Outcome, SUMMARY_VERSION};
use rayon::prelude::*;
use skill_kit::load::{error_chain, load_scene, Failure};
use skill_kit::out::Verbosity;
use skill_runtime::exec::RunLog;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One draw of a sweep to run.
pub(super) struct DrawJob {
    pub(super) skill: usize,
    pub(super) index: usize,
}

/// What a sweep runs with: the worker threads, the progress bar, the start and how much to say.
pub(super) struct Runner<'a> {
    pub(super) pool: &'a rayon::ThreadPool,
    pub(super) progress: &'a indicatif::ProgressBar,
    pub(super) started: Instant,
    pub(super) verbosity: Verbosity,
}

/// What a sweep needs of each skill's scene: the scene as written and its robot.
pub(super) type SweepBase = Result<(skill_runtime::sim::Scene, skill_runtime::robot::Robot), String>;

pub(super) fn sweep_base(prepared: &Prepared) -> SweepBase {
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
pub(super) fn run_draw(
    prepared: &Prepared,
    bound: &Bound<'_>,
    base: &SweepBase,
    index: usize,
    args: &EvalArgs,
) -> Outcome {
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

pub(super) fn run_sweep(
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
    if jobs.is_empty() {
        eprintln!(
            "warning: share {partition} holds none of the sweep's {} draws ({} skill(s) × {draws}): more shares than \
             draws; its summary has no trials (merging it with the other shares still gives the whole sweep)",
            prepared.len() * draws,
            prepared.len()
        );
    }
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
pub(super) fn sweep_fingerprint(args: &EvalArgs) -> String {
    let settings = format!(
        "params {:?}\nlimits {:?}\nrobot {:?}\nskills {:?}\nfiles {}",
        args.params,
        args.limits,
        args.robot,
        args.skills,
        skill_kit::atomic::inputs_fingerprint()
    );
    skill_kit::atomic::fnv(settings.as_bytes())
}

/// Prints and writes a sweep's (or merged sweeps') report; exit 1 when a skill's success rate is
/// below `min_success`.
pub(super) fn finish_sweep(
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
pub(super) fn merge(out: &Path, min_success: f64, summaries: &[PathBuf], verbosity: Verbosity) -> Result<u8, Failure> {
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
        skill_kit::atomic::note_input(&path);
        let part: sweep::SweepSummary = serde_json::from_str(&text).map_err(|err| {
            Failure::Input(format!(
                "`{}` is not a sweep summary of this skillc (written by `skillc eval --sweep`): {err}",
                path.display()
            ))
        })?;
        parts.push((path.display().to_string(), part));
    }
    // The summaries are noted inputs: an `--out` that is one of them is refused here.
    skill_kit::atomic::refuse_inputs(&out.join("summary.json"), "--out", &[]).map_err(Failure::Usage)?;
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

//! The trials file of `skillc eval`: its types (skills, tasks, criteria, variants), the
//! validation of its criteria, and where it is read from (`--trials`, or the shipped default).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::metrics::Metrics;
use super::{sweep, tasks, EvalArgs, DEFAULT_TRIALS, DEFAULT_TRIALS_PATH};
use skill_kit::load::Failure;

pub(super) fn parse_rate(text: &str) -> Result<f64, String> {
    skill_kit::limits::check(
        "the success rate",
        text.trim().parse().map_err(|_| format!("`{text}` is not a number"))?,
        (0.0, 1.0),
        "",
    )
}

/// A trials file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrialsFile {
    /// One entry per skill.
    #[serde(rename = "skill", default)]
    pub skills: Vec<SkillTrials>,
    /// One entry per task.
    #[serde(rename = "task", default)]
    pub tasks: Vec<tasks::TaskTrials>,
}

/// The trials of one skill.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkillTrials {
    /// The `.skill` file.
    pub file: PathBuf,
    /// The skill's name, when the file defines several.
    #[serde(default)]
    pub name: Option<String>,
    /// The demonstration to learn from.
    pub demo: PathBuf,
    /// The scene.
    pub scene: PathBuf,
    /// Success thresholds.
    #[serde(default)]
    pub criteria: Criteria,
    /// The scene variants.
    pub variants: Vec<Variant>,
    /// The ranges `--sweep` draws this skill's scenes from.
    #[serde(default)]
    pub sweep: sweep::SweepRanges,
    /// Values for the skill's parameters, as `--param` takes them (`["hold=4s"]`); the command
    /// line's `--param` settings come after them.
    #[serde(default)]
    pub params: Vec<String>,
}

/// Success thresholds of a trial.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Criteria {
    /// Largest relative RMS force error in contact.
    pub force_rms_rel: Option<f64>,
    /// Smallest share of the contact phase in contact.
    pub contact_share: Option<f64>,
    /// Largest relative error of the final contact force (touch).
    pub stop_force_rel: Option<f64>,
    /// Largest peak contact force as `[a, b]`: at most `a × the demonstration's peak + b N`
    /// (default `[2, 5]`, for every skill trial).
    #[serde(default)]
    pub peak_force: Option<[f64; 2]>,
}

/// The default [`Criteria::peak_force`]: twice the demonstrated peak plus 5 N.
pub const DEFAULT_PEAK_BOUND: [f64; 2] = [2.0, 5.0];

impl Criteria {
    /// Refuses a criterion no trial could be judged by: a negative, NaN or infinite bound
    /// (`stop_force_rel = -0.2` would fail every trial), a share outside 0 to 1. The message
    /// names the field.
    pub fn validate(&self) -> Result<(), String> {
        let bounded = |field: &str, value: Option<f64>, most: f64| match value {
            Some(v) if !(v.is_finite() && (0.0..=most).contains(&v)) => {
                Err(format!("`criteria.{field} = {v}` must be a number from 0 to {most}"))
            }
            _ => Ok(()),
        };
        bounded("force_rms_rel", self.force_rms_rel, 100.0)?;
        bounded("contact_share", self.contact_share, 1.0)?;
        bounded("stop_force_rel", self.stop_force_rel, 100.0)?;
        if let Some([scale, offset]) = self.peak_force {
            if !(scale.is_finite() && scale >= 0.0 && offset.is_finite() && offset >= 0.0) {
                return Err(format!(
                    "`criteria.peak_force = [{scale}, {offset}]` must be two finite numbers of at least 0 (a × the demonstration's peak + b N)"
                ));
            }
        }
        Ok(())
    }

    /// The peak force a run may reach \[N\]: `a × demo_peak_n + b` from [`Criteria::peak_force`].
    pub fn peak_bound(&self, demo_peak_n: f64) -> f64 {
        let [scale, offset] = self.peak_force.unwrap_or(DEFAULT_PEAK_BOUND);
        scale * demo_peak_n + offset
    }

    /// The first criterion a run that reached its success state misses, in the trials' order
    /// (peak force, force RMS, contact share, stop force): its reason (`criterion:...`) and
    /// what was measured against what. `demo_peak_n` is the demonstration's peak force, `None`
    /// for a run the peak bound does not apply to (a replay); `learned_force` the learned
    /// contact force the stop force is judged against.
    pub fn missed(
        &self,
        measured: &Metrics,
        learned_force: Option<f64>,
        demo_peak_n: Option<f64>,
    ) -> Option<(String, String)> {
        let percent = |value: Option<f64>| value.map_or("none".to_string(), |v| format!("{:.1} %", v * 100.0));
        if let Some(demo_peak) = demo_peak_n {
            let bound = self.peak_bound(demo_peak);
            if measured.peak_force_n > bound {
                let [scale, offset] = self.peak_force.unwrap_or(DEFAULT_PEAK_BOUND);
                return Some((
                    "criterion:peak_force".to_string(),
                    format!(
                        "peak force {:.1} N above the bound {bound:.1} N ({scale} × the demonstration's {demo_peak:.1} N + {offset} N)",
                        measured.peak_force_n
                    ),
                ));
            }
        }
        if let Some(max) = self
            .force_rms_rel
            .filter(|max| !measured.force_rms_rel.is_some_and(|v| v <= *max))
        {
            return Some((
                "criterion:force_rms".to_string(),
                format!(
                    "force RMS {} of the learned force, above {:.1} %",
                    percent(measured.force_rms_rel),
                    max * 100.0
                ),
            ));
        }
        if let Some(min) = self
            .contact_share
            .filter(|min| !measured.contact_share.is_some_and(|v| v >= *min))
        {
            return Some((
                "criterion:contact_share".to_string(),
                format!(
                    "in contact for {} of the contact phase, below {:.1} %",
                    percent(measured.contact_share),
                    min * 100.0
                ),
            ));
        }
        if let (Some(max), Some(learned)) = (self.stop_force_rel, learned_force) {
            let met = measured
                .stop_force_n
                .is_some_and(|f| learned > 0.0 && ((f - learned) / learned).abs() <= max);
            if !met {
                return Some((
                    "criterion:stop_force".to_string(),
                    format!(
                        "stop force {} against the learned {learned:.2} N, beyond ±{:.1} %",
                        measured
                            .stop_force_n
                            .map_or("none".to_string(), |f| format!("{f:.2} N")),
                        max * 100.0
                    ),
                ));
            }
        }
        None
    }
}

/// A scene variant.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// Its name in the report.
    pub name: String,
    /// Scene overrides, `KEY=VALUE`.
    #[serde(default)]
    pub set: Vec<String>,
    /// Skill parameters for this variant, as `--param` takes them (`["hold=4s"]`), after the
    /// skill's own `params`: the skill is compiled again with them and runs with the features
    /// learned once (parameters change nothing learned).
    #[serde(default)]
    pub params: Vec<String>,
}

pub(super) fn load_trials(args: &EvalArgs) -> Result<(TrialsFile, PathBuf), Failure> {
    let (text, name, base_dir) = match &args.trials {
        Some(path) => {
            let bytes = std::fs::read(path)
                .map_err(|err| Failure::Usage(format!("cannot read `{}`: {err}", path.display())))?;
            // A file that can be read but is no TOML text is a problem in an input (exit 1).
            if bytes.starts_with(b"\x89MCAP") {
                return Err(Failure::Input(format!(
                    "`{}` is an MCAP file (a ROS 2 bag), not a trials file: give a TOML file like examples/eval/default.toml",
                    path.display()
                )));
            }
            let text = String::from_utf8(bytes).map_err(|err| {
                Failure::Input(format!(
                    "`{}` is not UTF-8 text (byte {} is not), so it is no trials file: give a TOML file like examples/eval/default.toml",
                    path.display(),
                    err.utf8_error().valid_up_to()
                ))
            })?;
            skill_kit::atomic::note_input(path);
            let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
            (text, path.display().to_string(), base)
        }
        None => {
            // The root's copy (the repository's, edits included, or the built-in one written
            // to the cache), the built-in text if it cannot be read.
            let root = skill_kit::defaults::root().map_err(Failure::Usage)?;
            let path = root.join(DEFAULT_TRIALS_PATH);
            let text = std::fs::read_to_string(&path).unwrap_or_else(|_| DEFAULT_TRIALS.to_string());
            skill_kit::atomic::note_input(&path);
            (text, DEFAULT_TRIALS_PATH.to_string(), root.join("examples/eval"))
        }
    };
    let trials: TrialsFile =
        toml::from_str(&text).map_err(|err| Failure::Input(format!("`{name}`: {}", err.to_string().trim())))?;
    for (index, spec) in trials.skills.iter().enumerate() {
        if spec.variants.is_empty() && args.sweep.is_none() {
            return Err(Failure::Input(format!(
                "`{name}`: `[[skill]]` entry {} (`{}`) has no variants, so it would run no trial: give at least one \
                 `[[skill.variants]]` (`name = \"as demonstrated\"` with no `set` runs the scene as written)",
                index + 1,
                spec.file.display()
            )));
        }
        spec.criteria.validate().map_err(|err| {
            Failure::Input(format!(
                "`{name}`: `[[skill]]` entry {} (`{}`): {err}",
                index + 1,
                spec.file.display()
            ))
        })?;
    }
    for (index, spec) in trials.tasks.iter().enumerate() {
        if spec.variants.is_empty() && args.sweep.is_none() {
            return Err(Failure::Input(format!(
                "`{name}`: `[[task]]` entry {} (`{}`) has no variants, so it would run no trial: give at least one \
                 `[[task.variants]]`",
                index + 1,
                spec.file.display()
            )));
        }
        for (step, criteria) in &spec.criteria {
            criteria.validate().map_err(|err| {
                Failure::Input(format!(
                    "`{name}`: `[[task]]` entry {} (`{}`), step `{step}`: {err}",
                    index + 1,
                    spec.file.display()
                ))
            })?;
        }
    }
    Ok((trials, base_dir))
}

//! `skillc identify DEMO`: which templates a demonstration fits, ranked, with the evidence for
//! each (docs/method.md §3, "Which skill a demonstration shows").
//!
//! The demonstration is read and its wrench settled as `learn` does, the force it shows in the
//! air removed and its contact phases found (`identify/measure.rs`), and a few measurements
//! taken on them: how many phases, how long each lasts, how far the tool travels in the plane of
//! contact, how often that travel reverses, how far the contact force's direction turns, how
//! much of the phase the force holds its level, whether the force rises at the end (a slide that
//! ends in a press) and whether the recording ends in contact.
//!
//! Each template is described by its structure (`identify/profile.rs`: written out for the
//! standard templates, derived from the IR for a user's `--template FILE`), and the structure
//! gives its checks (`identify/checks.rs`): defining checks, which must all hold for the
//! template to fit (a press does not travel, a slide travels while in contact, a touch stops at
//! first contact), and supporting checks. Templates that fit rank above those that do not, and
//! among themselves by the share of supporting checks they pass; ties go to the earlier in
//! [`TEMPLATES`] (the more specific first), then to the user's templates. When no template
//! fits, the answer is "none fits" with each template's reason.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;
use skill_runtime::demo::{prepare, Demo, Dialect, PreprocessConfig, WrenchOptions};

use skill_kit::load::{load_skill, read_demo, Failure};
use skill_kit::out::{self, Verbosity};

mod checks;
mod measure;
mod profile;

pub use checks::Evidence;
pub use measure::Measures;
pub use profile::{Contacts, ForceShape, InContact, Profile, Surface};

/// Arguments of `skillc identify`.
#[derive(Debug, Clone, clap::Args)]
pub struct IdentifyArgs {
    /// The demonstration (CSV or a ROS 2 bag, as `skillc learn` reads them).
    pub demo: PathBuf,
    /// `text` (default) or `json`: `{"ranking": [{"skill", "score", "fits", "reason",
    /// "evidence": [{"check", "passed", "defining"}]}], "phases", "measures", "command", "none_fits"}`.
    #[arg(long, default_value = "text", value_parser = ["text", "json"])]
    pub format: String,
    /// A template of your own to rank beside the standard ones (a `.skill` file with one
    /// skill); repeat for several. Its checks are derived from its structure.
    #[arg(long = "template", value_name = "FILE")]
    pub templates: Vec<PathBuf>,
}

/// The fewest samples a demonstration is identified from (a contact phase needs 80 ms).
const MIN_SAMPLES: usize = 20;

/// The standard templates `identify` knows, the more specific first (ties go to the earlier).
pub const TEMPLATES: [&str; 9] = [
    "double_tap",
    "slide_then_press",
    "wipe",
    "contour",
    "guarded_move",
    "press_hold",
    "touch",
    "press",
    "slide",
];

/// A template to rank: a standard one or a user's.
#[derive(Debug, Clone)]
pub struct Template {
    /// Its name.
    pub name: String,
    /// The `.skill` file of a user's template (`None`: standard).
    pub file: Option<PathBuf>,
    /// What it expects.
    pub profile: Profile,
}

impl Template {
    /// The standard template `name`.
    pub fn standard(name: &str) -> Option<Template> {
        Profile::standard(name).map(|profile| Template {
            name: name.to_string(),
            file: None,
            profile,
        })
    }

    /// A user's template: the only skill of a `.skill` file, its profile derived from its IR.
    pub fn from_file(path: &Path) -> Result<Template, Failure> {
        let (_, skill) = load_skill(path, None)?;
        Ok(Template {
            name: skill.name.clone(),
            file: Some(path.to_path_buf()),
            profile: Profile::from_skill(&skill),
        })
    }
}

/// A template's fit.
#[derive(Debug, Clone, Serialize)]
pub struct Fit {
    /// The template.
    pub skill: String,
    /// Above 0.5 when it fits: 0.5 plus half the share of its supporting checks that hold;
    /// under 0.5 when it does not.
    pub score: f64,
    /// All its defining checks hold.
    pub fits: bool,
    /// Why it does not fit: its defining checks that fail (`None` when it fits).
    pub reason: Option<String>,
    /// The `.skill` file of a user's template (absent for a standard one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// What it expects, structurally.
    pub profile: Profile,
    /// Each check, defining ones first.
    pub evidence: Vec<Evidence>,
}

/// A contact phase as `identify` reports it.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseOut {
    /// Onset \[s\].
    pub start_s: f64,
    /// Release \[s\].
    pub end_s: f64,
    /// Median force \[N\].
    pub median_n: f64,
}

/// The answer: ranking, phases, the measures and the command that learns the best.
#[derive(Debug, Clone, Serialize)]
pub struct Identification {
    /// Best first.
    pub ranking: Vec<Fit>,
    /// The contact phases.
    pub phases: Vec<PhaseOut>,
    /// What the ranking is based on.
    pub measures: Measures,
    /// `skillc learn stdlib-skills/BEST.skill DEMO -o BEST.learned.json` (empty when none fits).
    pub command: String,
    /// `None` when a template fits; otherwise why none does, template by template.
    pub none_fits: Option<String>,
}

impl Identification {
    /// The template ranked first if it fits.
    pub fn best(&self) -> Option<&str> {
        self.ranking.first().filter(|f| f.fits).map(|f| f.skill.as_str())
    }
}

/// The standard templates, in [`TEMPLATES`] order.
pub fn standard_templates() -> Vec<Template> {
    TEMPLATES.iter().filter_map(|name| Template::standard(name)).collect()
}

/// Identifies the standard skill a demonstration (read, not yet prepared) shows.
pub fn identify(demo: &Demo, wrench: &WrenchOptions, demo_name: &str) -> Result<Identification, String> {
    identify_with(demo, wrench, demo_name, &standard_templates())
}

/// Ranks `templates` (ties in their order) against a demonstration (read, not yet prepared).
pub fn identify_with(
    demo: &Demo,
    wrench: &WrenchOptions,
    demo_name: &str,
    templates: &[Template],
) -> Result<Identification, String> {
    if demo.len() < MIN_SAMPLES {
        return Err(format!(
            "{} sample(s); identifying a skill needs at least {MIN_SAMPLES}",
            demo.len()
        ));
    }
    let prepared = prepare(demo, &PreprocessConfig::default(), wrench).map_err(|err| err.to_string())?;
    let measured = measure::measure_demo(&prepared.demo)?;
    let measures = measured.measures;
    let mut ranking: Vec<Fit> = templates
        .iter()
        .map(|template| {
            let evidence = checks::checks(&template.profile, &measures);
            let (fits, score) = checks::score(&evidence);
            let failed: Vec<&str> = evidence
                .iter()
                .filter(|e| e.defining && !e.passed)
                .map(|e| e.check.as_str())
                .collect();
            Fit {
                skill: template.name.clone(),
                score,
                fits,
                reason: (!fits).then(|| failed.join("; ")),
                file: template.file.as_ref().map(|f| f.display().to_string()),
                profile: template.profile,
                evidence,
            }
        })
        .collect();
    // A stable sort keeps the earlier template first among equals.
    ranking.sort_by(|a, b| b.score.total_cmp(&a.score));
    let (command, none_fits) = match ranking.first() {
        Some(best) if best.fits => {
            let file = best
                .file
                .clone()
                .unwrap_or_else(|| format!("stdlib-skills/{}.skill", best.skill));
            (
                format!("skillc learn {file} {demo_name} -o {}.learned.json", best.skill),
                None,
            )
        }
        _ => {
            let reasons: Vec<String> = ranking
                .iter()
                .map(|fit| format!("{}: {}", fit.skill, fit.reason.as_deref().unwrap_or("")))
                .collect();
            (String::new(), Some(reasons.join("; ")))
        }
    };
    let demo = &measured.demo;
    Ok(Identification {
        command,
        none_fits,
        phases: measured
            .phases
            .iter()
            .map(|p| PhaseOut {
                start_s: demo.t_s[p.onset],
                end_s: demo.t_s[p.release.min(demo.len()) - 1],
                median_n: p.median_n,
            })
            .collect(),
        measures,
        ranking,
    })
}

/// The identification as text.
fn text(id: &Identification, demo: &Path) -> String {
    let mut out = String::new();
    let list: Vec<String> = id
        .phases
        .iter()
        .map(|p| format!("{:.2}-{:.2} s ({:.1} N)", p.start_s, p.end_s, p.median_n))
        .collect();
    let _ = writeln!(
        out,
        "`{}`: {} contact phase(s){}{}",
        demo.display(),
        id.phases.len(),
        if list.is_empty() { "" } else { ": " },
        list.join(", ")
    );
    if id.measures.air_force_n > 0.5 {
        let _ = writeln!(
            out,
            "    (a force of up to {:.1} N in the air, away from the contact, taken as the sensor's and removed)",
            id.measures.air_force_n
        );
    }
    for (rank, fit) in id.ranking.iter().enumerate() {
        let name = match &fit.file {
            Some(file) => format!("{} ({file})", fit.skill),
            None => fit.skill.clone(),
        };
        let verdict = match &fit.reason {
            Some(reason) => format!("  does not fit: {reason}"),
            None => String::new(),
        };
        let _ = writeln!(out, "{:>2}. {:<17} {:.2}{verdict}", rank + 1, name, fit.score);
        for evidence in &fit.evidence {
            let mark = match (evidence.passed, evidence.defining) {
                (true, true) => "+!",
                (false, true) => "-!",
                (true, false) => "+ ",
                (false, false) => "- ",
            };
            let _ = writeln!(out, "      {mark} {}", evidence.check);
        }
    }
    let _ = writeln!(
        out,
        "(! marks a defining check: a template fits only if all of them hold)"
    );
    match &id.none_fits {
        Some(reasons) => {
            let _ = writeln!(out, "none fits: {reasons}");
        }
        None => {
            let _ = writeln!(out, "learn it with: {}", id.command);
        }
    }
    out
}

/// Runs `skillc identify`.
pub fn run(args: &IdentifyArgs, _verbosity: Verbosity) -> u8 {
    let result = (|| -> Result<(), Failure> {
        let mut templates = standard_templates();
        for path in &args.templates {
            templates.push(Template::from_file(path)?);
        }
        let (loaded, _, _) = read_demo(&args.demo, &Dialect::default(), &skill_ros::bag::BagOptions::default())?;
        let wrench = WrenchOptions {
            declared: loaded.wrench,
            keep_bias: false,
        };
        let name = args.demo.display().to_string();
        let id = identify_with(&loaded.demo, &wrench, &name, &templates)
            .map_err(|err| Failure::Input(format!("cannot identify `{name}`: {err}")))?;
        if args.format == "json" {
            let json = serde_json::to_string_pretty(&id).map_err(|err| Failure::Usage(err.to_string()))?;
            out::print(&(json + "\n"))
        } else {
            out::print(&text(&id, &args.demo))
        }
    })();
    match result {
        Ok(()) => 0,
        Err(failure) => failure.report(),
    }
}

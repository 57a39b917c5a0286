//! `skillc identify DEMO`: which standard templates a demonstration fits, ranked, with the
//! evidence for each (docs/method.md §3, "Which skill a demonstration shows").
//!
//! The demonstration is read and its wrench settled as `learn` does, its contact phases found
//! (`skill_runtime::learn::phases`), and a few measurements taken on them: how many phases,
//! how long each lasts, how far the tool travels while in contact (the extent along its main
//! direction), how often that travel reverses, how far the contact force's direction turns,
//! how much of the phase the force holds its level, whether the force rises at the end
//! (a slide that ends in a press) and whether the recording ends in contact. Each template
//! states what it expects of those measurements; its score is the share of its checks the
//! demonstration passes, and the ranking is by score, ties in the order of
//! [`TEMPLATES`] (the more specific first).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use skill_runtime::demo::{prepare, Demo, Dialect, PreprocessConfig, WrenchOptions};
use skill_runtime::learn::phases::{contact_phases, ContactPhase};

use skill_kit::load::{read_demo, Failure};
use skill_kit::out::{self, Verbosity};

/// Arguments of `skillc identify`.
#[derive(Debug, Clone, clap::Args)]
pub struct IdentifyArgs {
    /// The demonstration (CSV or a ROS 2 bag, as `skillc learn` reads them).
    pub demo: PathBuf,
    /// `text` (default) or `json`: `{"ranking": [{"skill", "score", "evidence"}], "phases": [...]}`.
    #[arg(long, default_value = "text", value_parser = ["text", "json"])]
    pub format: String,
}

/// The fewest samples a demonstration is identified from (a contact phase needs 80 ms).
const MIN_SAMPLES: usize = 20;
/// Travel in contact beyond this is sliding \[m\].
const SLIDING_M: f64 = 0.03;
/// Travel in contact under this is staying put \[m\].
const STILL_M: f64 = 0.01;
/// A contact force that turns more than this follows a curved surface \[°\].
const CURVED_DEG: f64 = 15.0;
/// A contact that turns less than this is on a plane \[°\].
const FLAT_DEG: f64 = 12.0;
/// A touch lasts less than this \[s\].
const TOUCH_S: f64 = 0.6;
/// A tap lasts less than this \[s\].
const TAP_S: f64 = 1.5;
/// A hold holds its level over at least this share of the contact.
const HOLD_SHARE: f64 = 0.65;
/// ... within this share of its median.
const HOLD_BAND: f64 = 0.1;
/// A slide that ends in a press ends at least this many times its sliding force.
const FIRM_END_RATIO: f64 = 1.8;

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

/// What was measured on a demonstration.
#[derive(Debug, Clone, Serialize)]
pub struct Measures {
    /// Contact phases.
    pub phases: usize,
    /// The longest phase's duration \[s\].
    pub duration_s: f64,
    /// The longest phase's travel along its main direction \[m\].
    pub travel_m: f64,
    /// Reversals of that travel.
    pub reversals: usize,
    /// How far the contact force's direction turns from the phase's first quarter to its last \[°\].
    pub turn_deg: f64,
    /// The share of the phase the force stays within 10 % of its median.
    pub hold_share: f64,
    /// The force of the phase's last fifth over its first half's.
    pub end_ratio: f64,
    /// The recording ends in contact.
    pub ends_in_contact: bool,
    /// Per phase: duration \[s\] and travel \[m\].
    pub per_phase: Vec<[f64; 2]>,
    /// Distance between the first two phases' centres \[m\] (0 with fewer).
    pub apart_m: f64,
}

/// One check of a template against the measures.
#[derive(Debug, Clone, Serialize)]
pub struct Evidence {
    /// What is checked, with the value found.
    pub check: String,
    /// Whether it holds.
    pub passed: bool,
}

/// A template's fit.
#[derive(Debug, Clone, Serialize)]
pub struct Fit {
    /// The template.
    pub skill: String,
    /// The share of its checks that hold, 0 to 1.
    pub score: f64,
    /// Each check.
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
    /// `skillc learn stdlib-skills/BEST.skill DEMO -o BEST.learned.json`.
    pub command: String,
}

/// Identifies the skill a demonstration (read, not yet prepared) shows.
pub fn identify(demo: &Demo, wrench: &WrenchOptions, demo_name: &str) -> Result<Identification, String> {
    if demo.len() < MIN_SAMPLES {
        return Err(format!(
            "{} sample(s); identifying a skill needs at least {MIN_SAMPLES}",
            demo.len()
        ));
    }
    let prepared = prepare(demo, &PreprocessConfig::default(), wrench).map_err(|err| err.to_string())?;
    let demo = prepared.demo;
    let found = contact_phases(&demo);
    if found.phases.is_empty() {
        let peak = demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max);
        return Err(format!(
            "no contact phase (the debiased force peaks at {peak:.2} N, under the {:.2} N a contact needs): every standard template learns a contact",
            found.on_n
        ));
    }
    let measures = measure(&demo, &found.phases);
    let mut ranking: Vec<Fit> = TEMPLATES
        .iter()
        .map(|name| {
            let evidence = checks(name, &measures);
            let passed = evidence.iter().filter(|e| e.passed).count();
            Fit {
                skill: (*name).to_string(),
                score: passed as f64 / evidence.len() as f64,
                evidence,
            }
        })
        .collect();
    // A stable sort keeps the more specific template first among equals.
    ranking.sort_by(|a, b| b.score.total_cmp(&a.score));
    let best = &ranking[0].skill;
    Ok(Identification {
        command: format!("skillc learn stdlib-skills/{best}.skill {demo_name} -o {best}.learned.json"),
        phases: found
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

fn check(check: String, passed: bool) -> Evidence {
    Evidence { check, passed }
}

/// What template `name` expects of the measures.
fn checks(name: &str, m: &Measures) -> Vec<Evidence> {
    let phases = |want: usize| {
        check(
            format!("{} contact phase(s), expects {want}", m.phases),
            m.phases == want,
        )
    };
    let cm = m.travel_m * 100.0;
    let still = check(
        format!("travel in contact {cm:.1} cm, expects under 1 cm"),
        m.travel_m < STILL_M,
    );
    let slides = check(
        format!("travel in contact {cm:.1} cm, expects 3 cm or more"),
        m.travel_m >= SLIDING_M,
    );
    let flat = check(
        format!("force turns {:.0}°, expects under 12° (a plane)", m.turn_deg),
        m.turn_deg < FLAT_DEG,
    );
    let no_reversal = check(
        format!("{} stroke reversal(s), expects none", m.reversals),
        m.reversals == 0,
    );
    let not_at_end = check(
        format!(
            "ends {}in contact, expects a retreat",
            if m.ends_in_contact { "" } else { "not " }
        ),
        !m.ends_in_contact,
    );
    let plain_end = check(
        format!("end force {:.1}× the sliding force, expects under 1.8×", m.end_ratio),
        m.end_ratio < FIRM_END_RATIO,
    );
    let hold = m.hold_share * 100.0;
    match name {
        "touch" => vec![
            phases(1),
            check(
                format!("contact {:.2} s, expects under 0.6 s", m.duration_s),
                m.duration_s < TOUCH_S,
            ),
            still,
            not_at_end,
        ],
        "press" => vec![
            phases(1),
            check(
                format!("contact {:.2} s, expects 0.6 s or more", m.duration_s),
                m.duration_s >= TOUCH_S,
            ),
            still,
            check(
                format!("force at its level {hold:.0} % of the contact, expects a profile (under 65 %)"),
                m.hold_share < HOLD_SHARE,
            ),
            not_at_end,
        ],
        "press_hold" => vec![
            phases(1),
            check(
                format!("contact {:.2} s, expects 1.5 s or more", m.duration_s),
                m.duration_s >= TAP_S,
            ),
            still,
            check(
                format!("force at its level {hold:.0} % of the contact, expects 65 % or more"),
                m.hold_share >= HOLD_SHARE,
            ),
            not_at_end,
        ],
        "guarded_move" => vec![
            phases(1),
            check(
                format!(
                    "ends {}in contact, expects the recording to end in contact",
                    if m.ends_in_contact { "" } else { "not " }
                ),
                m.ends_in_contact,
            ),
            still,
        ],
        "double_tap" => {
            let short = m.per_phase.iter().all(|[d, _]| *d < TAP_S);
            let put = m.per_phase.iter().all(|[_, travel]| *travel < STILL_M);
            vec![
                phases(2),
                check(
                    format!("taps under {TAP_S} s each: {short}"),
                    short && !m.per_phase.is_empty(),
                ),
                check(
                    format!("each tap stays put (under 1 cm): {put}"),
                    put && !m.per_phase.is_empty(),
                ),
                check(
                    format!("taps {:.1} cm apart, expects 1 cm or more", m.apart_m * 100.0),
                    m.apart_m >= STILL_M,
                ),
                not_at_end,
            ]
        }
        "slide" => vec![phases(1), slides, no_reversal, flat, plain_end, not_at_end],
        "wipe" => vec![
            check(
                format!("{} contact phase(s), expects one or more", m.phases),
                m.phases >= 1,
            ),
            slides,
            check(
                format!("{} stroke reversal(s), expects 2 or more", m.reversals),
                m.reversals >= 2,
            ),
            flat,
            not_at_end,
        ],
        "contour" => vec![
            phases(1),
            slides,
            no_reversal,
            check(
                format!("force turns {:.0}°, expects 15° or more (a curved surface)", m.turn_deg),
                m.turn_deg >= CURVED_DEG,
            ),
            not_at_end,
        ],
        "slide_then_press" => vec![
            phases(1),
            slides,
            no_reversal,
            flat,
            check(
                format!("end force {:.1}× the sliding force, expects 1.8× or more", m.end_ratio),
                m.end_ratio >= FIRM_END_RATIO,
            ),
            not_at_end,
        ],
        _ => Vec::new(),
    }
}

/// The main direction of `points` and their extent along it.
fn extent(points: &[Vector3<f64>]) -> (Vector3<f64>, f64) {
    if points.len() < 2 {
        return (Vector3::x(), 0.0);
    }
    let centre: Vector3<f64> = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let covariance: Matrix3<f64> = points.iter().map(|p| (p - centre) * (p - centre).transpose()).sum();
    let eigen = covariance.symmetric_eigen();
    let index = eigen.eigenvalues.imax();
    let axis: Vector3<f64> = eigen.eigenvectors.column(index).into();
    let along: Vec<f64> = points.iter().map(|p| p.dot(&axis)).collect();
    let (lo, hi) = along.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(*v), hi.max(*v))
    });
    (axis, hi - lo)
}

/// Reversals of the travel along `axis`: extremes the path comes back from by a quarter of the range.
fn reversals(points: &[Vector3<f64>], axis: &Vector3<f64>, range: f64) -> usize {
    if range < STILL_M {
        return 0;
    }
    let band = 0.25 * range;
    let along: Vec<f64> = points.iter().map(|p| p.dot(axis)).collect();
    let (mut high, mut low) = (along[0], along[0]);
    let mut direction = 0i8;
    let mut count = 0;
    for &s in &along {
        high = high.max(s);
        low = low.min(s);
        if direction >= 0 && s < high - band {
            if direction > 0 {
                count += 1;
            }
            direction = -1;
            low = s;
        } else if direction <= 0 && s > low + band {
            if direction < 0 {
                count += 1;
            }
            direction = 1;
            high = s;
        }
    }
    count
}

fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn measure(demo: &Demo, phases: &[ContactPhase]) -> Measures {
    let n = demo.len();
    let per_phase: Vec<[f64; 2]> = phases
        .iter()
        .map(|p| [p.duration_s(demo), extent(&demo.position_m[p.on..p.off]).1])
        .collect();
    let longest = (0..phases.len()).max_by(|&a, &b| per_phase[a][0].total_cmp(&per_phase[b][0]));
    let centre = |p: &ContactPhase| demo.position_m[p.on..p.off].iter().sum::<Vector3<f64>>() / (p.off - p.on) as f64;
    let apart_m = if phases.len() >= 2 {
        (centre(&phases[0]) - centre(&phases[1])).norm()
    } else {
        0.0
    };
    let mut measures = Measures {
        phases: phases.len(),
        duration_s: 0.0,
        travel_m: 0.0,
        reversals: 0,
        turn_deg: 0.0,
        hold_share: 0.0,
        end_ratio: 1.0,
        ends_in_contact: phases.last().is_some_and(|p| p.off >= n.saturating_sub(1)),
        per_phase: per_phase.clone(),
        apart_m,
    };
    let Some(index) = longest else {
        return measures;
    };
    let phase = &phases[index];
    let core = phase.on..phase.off;
    let points = &demo.position_m[core.clone()];
    let (axis, travel) = extent(points);
    measures.duration_s = per_phase[index][0];
    measures.travel_m = travel;
    measures.reversals = reversals(points, &axis, travel);
    // The force without its friction: the component along the direction of travel removed
    // where the tool slides (faster than 5 mm/s over 50 ms), so the turn is the normal's.
    let rate = (n - 1) as f64 / demo.duration_s().max(1e-9);
    let half = ((0.025 * rate).round() as usize).max(1);
    let forces: Vec<Vector3<f64>> = core
        .clone()
        .map(|k| {
            let (a, b) = (k.saturating_sub(half), (k + half).min(n - 1));
            let dt = demo.t_s[b] - demo.t_s[a];
            let velocity = if dt > 0.0 {
                (demo.position_m[b] - demo.position_m[a]) / dt
            } else {
                Vector3::zeros()
            };
            let f = demo.force_n[k];
            match velocity.try_normalize(1e-12) {
                Some(direction) if velocity.norm() > 0.005 => f - direction * f.dot(&direction),
                _ => f,
            }
        })
        .collect();
    let forces = &forces[..];
    let quarter = (forces.len() / 4).max(1);
    let mean_direction = |fs: &[Vector3<f64>]| fs.iter().sum::<Vector3<f64>>().try_normalize(1e-12);
    if let (Some(first), Some(last)) = (
        mean_direction(&forces[..quarter]),
        mean_direction(&forces[forces.len() - quarter..]),
    ) {
        measures.turn_deg = first.dot(&last).clamp(-1.0, 1.0).acos().to_degrees();
    }
    let magnitude: Vec<f64> = demo.force_n[core.clone()].iter().map(|f| f.norm()).collect();
    let level = median(magnitude.clone());
    measures.hold_share = magnitude
        .iter()
        .filter(|f| (**f - level).abs() <= HOLD_BAND * level)
        .count() as f64
        / magnitude.len() as f64;
    // The end: the last fifth before the release ramp (the last 10 % of the phase) against the first half.
    let len = magnitude.len();
    let first_half = median(magnitude[..len / 2].to_vec());
    let end = median(magnitude[(len * 7 / 10)..(len * 9 / 10).max(len * 7 / 10 + 1)].to_vec());
    measures.end_ratio = if first_half > 0.0 { end / first_half } else { 1.0 };
    measures
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
    for (rank, fit) in id.ranking.iter().enumerate() {
        let _ = writeln!(out, "{:>2}. {:<17} {:.2}", rank + 1, fit.skill, fit.score);
        for evidence in &fit.evidence {
            let _ = writeln!(
                out,
                "      {} {}",
                if evidence.passed { "+" } else { "-" },
                evidence.check
            );
        }
    }
    let _ = writeln!(out, "learn it with: {}", id.command);
    out
}

/// Runs `skillc identify`.
pub fn run(args: &IdentifyArgs, _verbosity: Verbosity) -> u8 {
    let result = (|| -> Result<(), Failure> {
        let (loaded, _, _) = read_demo(&args.demo, &Dialect::default(), &skill_ros::bag::BagOptions::default())?;
        let wrench = WrenchOptions {
            declared: loaded.wrench,
            keep_bias: false,
        };
        let name = args.demo.display().to_string();
        let id = identify(&loaded.demo, &wrench, &name)
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

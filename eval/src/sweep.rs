//! `skillc eval --sweep N`: every skill reproduced in N scenes drawn at random within documented
//! ranges (surface height, tilt, position, friction, sensor noise), success rates and failures by
//! reason; `--partition K/M` runs one share of the draws and `skillc eval merge` joins the shares.
//!
//! A draw depends only on the seed, the skill's name and the draw's index, so the trials are the
//! same for any thread count and any partition.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Rotation3, Translation3, Unit, Vector3};
use serde::{Deserialize, Serialize};
use skill_runtime::rng::SplitMix64;
use skill_runtime::robot::Robot;
use skill_runtime::sim::{RapierPlant, Scene};

use super::TrialResult;
use skill_kit::atomic;

/// The ranges a sweep draws a skill's scene from: `sweep = { ... }` in a trials file, each key
/// optional.
///
/// Every object of the scene moves as one rigid group (a button stays on its base): it tilts
/// about a random horizontal axis through the tool's start, then moves along the base z (height)
/// and along the base x and y (position).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SweepRanges {
    /// The surface moves along the base z by up to ± this \[m\] (default 0.10).
    pub height_m: f64,
    /// It tilts by up to ± this \[deg\] about a horizontal axis of random direction (default 10).
    pub tilt_deg: f64,
    /// It moves along the base x and along the base y by up to ± this each \[m\] (default 0.03).
    pub shift_m: f64,
    /// Every object's friction coefficient, drawn from `[low, high]` (default `[0.2, 1.0]`).
    pub friction: [f64; 2],
    /// The scene's sensor noise times a factor drawn from `[low, high]` (default `[1, 3]`).
    pub noise_scale: [f64; 2],
}

impl Default for SweepRanges {
    fn default() -> Self {
        SweepRanges {
            height_m: 0.10,
            tilt_deg: 10.0,
            shift_m: 0.03,
            friction: [0.2, 1.0],
            noise_scale: [1.0, 3.0],
        }
    }
}

impl SweepRanges {
    /// Refuses ranges a sweep cannot draw from sensibly, naming the key.
    pub fn validate(&self, skill: &str) -> Result<(), String> {
        let bad = |key: &str, why: &str| Err(format!("skill `{skill}`: `sweep.{key}` {why}"));
        for (key, value, max) in [
            ("height_m", self.height_m, 0.5),
            ("tilt_deg", self.tilt_deg, 45.0),
            ("shift_m", self.shift_m, 0.5),
        ] {
            if !(value.is_finite() && (0.0..=max).contains(&value)) {
                return bad(key, &format!("is {value}; it must lie between 0 and {max}"));
            }
        }
        for (key, [low, high], max) in [
            ("friction", self.friction, 2.0),
            ("noise_scale", self.noise_scale, 100.0),
        ] {
            if !(low.is_finite() && high.is_finite() && 0.0 <= low && low <= high && high <= max) {
                return bad(
                    key,
                    &format!("is [{low}, {high}]; write [low, high] with 0 <= low <= high <= {max}"),
                );
            }
        }
        Ok(())
    }
}

/// One random scene of a sweep: what was drawn, and how far the start had to be raised.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Draw {
    /// The draw's index among the skill's draws (0-based).
    pub index: usize,
    /// Height change of the objects \[m\] (positive: nearer the tool, which starts above them).
    pub height_m: f64,
    /// Tilt \[deg\].
    pub tilt_deg: f64,
    /// Direction of the tilt's horizontal axis from the base x \[deg\].
    pub tilt_axis_deg: f64,
    /// Position change along the base x and y \[m\].
    pub shift_m: [f64; 2],
    /// Friction coefficient of every object.
    pub friction: f64,
    /// Sensor noise factor.
    pub noise_scale: f64,
    /// How far the tool's start was raised so that it starts outside every object \[m\].
    pub start_raised_m: f64,
}

/// The trials of a sweep as written to `summary.json` (and read back by `eval merge`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepSummary {
    /// [`super::SUMMARY_VERSION`].
    pub format_version: u32,
    /// Always `sweep` (a plain eval writes no `kind`).
    pub kind: String,
    /// The seed of every draw.
    pub seed: u64,
    /// Draws per skill.
    pub per_skill: usize,
    /// The shares merged into this summary, as `K/M` each.
    pub partitions: Vec<String>,
    /// The ranges of each skill.
    pub ranges: BTreeMap<String, SweepRanges>,
    /// What identifies the sweep a share belongs to; `None` in a summary of an older skillc,
    /// which `eval merge` refuses.
    #[serde(default)]
    pub identity: Option<SweepIdentity>,
    /// Wall time of the trials \[s\] (summed over merged shares).
    pub elapsed_s: f64,
    /// One entry per trial run.
    pub trials: Vec<TrialResult>,
}

/// What every share of one sweep has in common, recorded in each share's summary so that
/// `eval merge` joins only shares that belong together.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SweepIdentity {
    /// The skillc version that ran the share.
    pub skillc_version: String,
    /// A fingerprint of the trials file, every file the sweep read (skills, demonstrations,
    /// scenes, robots) and the settings that change a draw (`--param`, `--limit`, `--robot`).
    pub inputs: String,
    /// The skills in draw order: draw `i` of skill `s` has the global index `s × per_skill + i`.
    pub skills: Vec<String>,
    /// The number of shares the sweep was split into (M of `--partition K/M`).
    pub shares: usize,
}

/// Which share of the draws to run: `K/M` runs every draw whose global index `i` has
/// `i % M == K - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Partition {
    /// 1-based share.
    pub k: usize,
    /// Number of shares.
    pub m: usize,
}

impl Partition {
    /// All draws.
    pub const ALL: Partition = Partition { k: 1, m: 1 };

    /// Whether this share runs the draw with global index `index`.
    pub fn runs(&self, index: usize) -> bool {
        index % self.m == self.k - 1
    }
}

impl std::fmt::Display for Partition {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.k, self.m)
    }
}

/// Most shares a sweep may be split into.
pub const MAX_SHARES: usize = 10_000;

/// Clap parser for `--partition K/M`.
pub fn parse_partition(text: &str) -> Result<Partition, String> {
    let (k, m) = text
        .split_once('/')
        .ok_or_else(|| format!("`{text}`: write K/M, e.g. 2/4 for the second of four shares"))?;
    let number = |part: &str| {
        part.trim()
            .parse::<usize>()
            .map_err(|_| format!("`{text}`: `{part}` is not a whole number"))
    };
    let (k, m) = (number(k)?, number(m)?);
    if m == 0 || m > MAX_SHARES || k == 0 || k > m {
        return Err(format!("`{text}`: K must lie in 1..=M and M in 1..={MAX_SHARES}"));
    }
    Ok(Partition { k, m })
}

/// Most draws per skill.
pub const MAX_DRAWS: usize = 100_000;

/// Clap parser for `--sweep N`.
pub fn parse_draws(text: &str) -> Result<usize, String> {
    let n: usize = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    if n == 0 || n > MAX_DRAWS {
        return Err(format!(
            "the number of draws per skill must lie in 1..={MAX_DRAWS}, got {n}"
        ));
    }
    Ok(n)
}

/// The random generator of one draw: a function of the seed, the skill and the index only.
fn generator(seed: u64, skill: &str, index: usize) -> SplitMix64 {
    // FNV-1a of the name: stable across runs and platforms (std's hasher is not).
    let name = skill.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    let mut rng = SplitMix64::new(seed ^ name.rotate_left(17) ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    rng.next_u64();
    rng
}

/// Draws scene changes within `ranges` (the start is not raised yet).
pub fn draw(ranges: &SweepRanges, seed: u64, skill: &str, index: usize) -> Draw {
    let mut rng = generator(seed, skill, index);
    let symmetric = |rng: &mut SplitMix64, half: f64| rng.range(-half, half);
    Draw {
        index,
        height_m: symmetric(&mut rng, ranges.height_m),
        tilt_deg: symmetric(&mut rng, ranges.tilt_deg),
        tilt_axis_deg: rng.range(0.0, 360.0),
        shift_m: [symmetric(&mut rng, ranges.shift_m), symmetric(&mut rng, ranges.shift_m)],
        friction: rng.range(ranges.friction[0], ranges.friction[1]),
        noise_scale: rng.range(ranges.noise_scale[0], ranges.noise_scale[1]),
        start_raised_m: 0.0,
    }
}

/// How far above every object a sweep's tool starts at least \[m\] (the shipped scenes start it
/// about 6 cm above their surfaces, so only draws that raise the objects that far move it).
pub const START_CLEARANCE_M: f64 = 0.001;

/// The highest a sweep raises the tool's start \[m\].
const MAX_LIFT_M: f64 = 0.5;

/// The `--set` overrides that make `draw` of `scene` (objects moved and tilted, friction, sensor
/// noise and seed), and a start raised by inverse kinematics when the moved objects would hold
/// the tool inside them. `draw.start_raised_m` is filled in.
pub fn scene_sets(scene: &Scene, robot: &Robot, draw: &mut Draw, seed: u64) -> Result<Vec<String>, String> {
    let spec = scene.spec();
    let q0 = scene
        .start_configuration(robot)
        .map_err(|err| skill_kit::load::error_chain(&err))?;
    let (start, _, _) = robot.evaluate(&q0);
    let pivot = start.translation.vector;
    let axis_angle = draw.tilt_axis_deg.to_radians();
    let axis = Unit::new_normalize(Vector3::new(axis_angle.cos(), axis_angle.sin(), 0.0));
    let tilt = Rotation3::from_axis_angle(&axis, draw.tilt_deg.to_radians());
    let shift = Vector3::new(draw.shift_m[0], draw.shift_m[1], draw.height_m);
    let list = |v: [f64; 3]| format!("[{:.9}, {:.9}, {:.9}]", v[0], v[1], v[2]);
    let mut sets = Vec::new();
    for (name, object) in &spec.objects {
        let position = Vector3::from(object.xyz);
        let moved = pivot + tilt * (position - pivot) + shift;
        let rotation = tilt * Rotation3::from_euler_angles(object.rpy[0], object.rpy[1], object.rpy[2]);
        let (roll, pitch, yaw) = rotation.euler_angles();
        sets.push(format!("objects.{name}.xyz={}", list([moved.x, moved.y, moved.z])));
        sets.push(format!("objects.{name}.rpy={}", list([roll, pitch, yaw])));
        sets.push(format!("objects.{name}.friction={:.6}", draw.friction));
    }
    let sensor = &spec.sensor;
    sets.push(format!(
        "sensor.noise_force_n={:.9}",
        sensor.noise_force_n * draw.noise_scale
    ));
    sets.push(format!(
        "sensor.noise_torque_nm={:.9}",
        sensor.noise_torque_nm * draw.noise_scale
    ));
    sets.push(format!(
        "sensor.seed={}",
        seed.wrapping_add(draw.index as u64) % (1 << 53)
    ));

    let mut moved = scene.clone();
    apply(&mut moved, &sets)?;
    // Raise the start until the tool is outside every object: find how far the tool must go up,
    // put it there by inverse kinematics, and check with the arm where it then is (a little
    // more each time the orientation's residual left it short).
    let mut lift = 0.0;
    for margin in [0.0, 0.002, 0.005] {
        let needed = RapierPlant::scene_lift_to_clear(robot.clone(), &moved, START_CLEARANCE_M + margin, MAX_LIFT_M)
            .map_err(|err| skill_kit::load::error_chain(&err))?
            .ok_or_else(|| {
                format!("no start up to {MAX_LIFT_M} m above the tool's start is clear of the moved objects")
            })?;
        if needed <= 0.0 {
            break;
        }
        lift += needed;
        let target = Translation3::new(0.0, 0.0, lift) * start;
        // A scene that gives the tool's start pose gets a higher pose; one that gives joint
        // angles gets the joint angles of the higher pose.
        let (key, value) = if spec.robot.tool_start.is_some() {
            let p = target.translation.vector;
            ("robot.tool_start.xyz", format!("[{:.9}, {:.9}, {:.9}]", p.x, p.y, p.z))
        } else {
            let q = robot.inverse_kinematics(&target, &q0).map_err(|err| err.to_string())?;
            let text = q.iter().map(|v| format!("{v:.9}")).collect::<Vec<_>>().join(", ");
            ("robot.q0", format!("[{text}]"))
        };
        moved
            .set(key, &value)
            .map_err(|err| skill_kit::load::error_chain(&err))?;
        sets.retain(|set| !set.starts_with(&format!("{key}=")));
        sets.push(format!("{key}={value}"));
    }
    draw.start_raised_m = lift;
    Ok(sets)
}

fn apply(scene: &mut Scene, sets: &[String]) -> Result<(), String> {
    for set in sets {
        let (key, value) = set.split_once('=').ok_or_else(|| format!("bad override `{set}`"))?;
        scene
            .set(key, value)
            .map_err(|err| skill_kit::load::error_chain(&err))?;
    }
    Ok(())
}

/// Success rate and failures by reason, per skill, as a text table.
pub fn table(summary: &SweepSummary) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "sweep: seed {}, {} draws per skill, shares {}",
        summary.seed,
        summary.per_skill,
        summary.partitions.join(" ")
    );
    let _ = writeln!(
        out,
        "{:<10} {:>6} {:>9} {:>8} {:>8}  failures by reason",
        "skill", "trials", "success %", "peak N", "time s"
    );
    for (skill, trials) in by_skill(&summary.trials) {
        let ok = trials.iter().filter(|t| t.success).count();
        let peak = trials.iter().map(|t| t.peak_force_n).fold(0.0, f64::max);
        let mean_time = trials.iter().map(|t| t.duration_s).sum::<f64>() / trials.len().max(1) as f64;
        let mut reasons: BTreeMap<&str, usize> = BTreeMap::new();
        for t in trials.iter().filter(|t| !t.success) {
            *reasons.entry(t.reason.as_deref().unwrap_or("error")).or_default() += 1;
        }
        let reasons: Vec<String> = reasons.iter().map(|(r, n)| format!("{r} ×{n}")).collect();
        let _ = writeln!(
            out,
            "{:<10} {:>6} {:>9.1} {:>8.1} {:>8.2}  {}",
            skill,
            trials.len(),
            100.0 * ok as f64 / trials.len().max(1) as f64,
            peak,
            mean_time,
            reasons.join(", ")
        );
    }
    let failed: Vec<&TrialResult> = summary.trials.iter().filter(|t| !t.success).collect();
    if !failed.is_empty() {
        let _ = writeln!(
            out,
            "failed draws (height cm, tilt °, shift cm, friction, noise ×, start raised cm):"
        );
        for t in failed {
            let Some(d) = &t.draw else { continue };
            let _ = writeln!(
                out,
                "  {:<8} #{:<5} {:+6.1} {:+5.1} [{:+4.1}, {:+4.1}] {:.2} {:.1} {:4.1}  {}: {}",
                t.skill,
                d.index,
                d.height_m * 100.0,
                d.tilt_deg,
                d.shift_m[0] * 100.0,
                d.shift_m[1] * 100.0,
                d.friction,
                d.noise_scale,
                d.start_raised_m * 100.0,
                t.reason.as_deref().unwrap_or("error"),
                t.message
            );
        }
    }
    out
}

/// The trials grouped by skill, in the order skills first appear.
fn by_skill(trials: &[TrialResult]) -> Vec<(&str, Vec<&TrialResult>)> {
    let mut groups: Vec<(&str, Vec<&TrialResult>)> = Vec::new();
    for trial in trials {
        match groups.iter_mut().find(|(name, _)| *name == trial.skill) {
            Some((_, list)) => list.push(trial),
            None => groups.push((&trial.skill, vec![trial])),
        }
    }
    groups
}

/// The success rate of each skill.
pub fn rates(trials: &[TrialResult]) -> Vec<(String, f64)> {
    by_skill(trials)
        .into_iter()
        .map(|(name, list)| {
            let ok = list.iter().filter(|t| t.success).count();
            (name.to_string(), ok as f64 / list.len().max(1) as f64)
        })
        .collect()
}

/// Writes `summary.json`, `plots/sweep.svg` and `index.html` into the folder `out` as a unit
/// ([`atomic::write_dir`]); returns the HTML's path.
pub fn write(out: &Path, summary: &SweepSummary, text: &str) -> std::io::Result<PathBuf> {
    atomic::write_dir(out, |dir| fill(dir, summary, text))?;
    Ok(out.join("index.html"))
}

/// [`write`]'s files, written into `out`.
fn fill(out: &Path, summary: &SweepSummary, text: &str) -> std::io::Result<()> {
    std::fs::create_dir_all(out.join("plots"))?;
    let json = serde_json::to_string_pretty(summary).map_err(std::io::Error::other)? + "\n";
    atomic::write(&out.join("summary.json"), json.as_bytes())?;
    let points: Vec<skill_kit::plot::SweepPoint<'_>> = summary
        .trials
        .iter()
        .filter_map(|t| {
            t.draw.map(|d| skill_kit::plot::SweepPoint {
                skill: &t.skill,
                height_m: d.height_m,
                tilt_deg: d.tilt_deg,
                success: t.success,
            })
        })
        .collect();
    let plot = match skill_kit::plot::sweep(&out.join("plots").join("sweep.svg"), &points) {
        Ok(()) => "<figure><img src=\"plots/sweep.svg\" alt=\"sweep\"><figcaption>Each draw's height change and tilt; green: success, red: failure.</figcaption></figure>".to_string(),
        Err(err) => format!("<p>plot failed: {}</p>", escape(&err)),
    };
    let html = format!(
        "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>skillc eval --sweep</title></head><body style=\"font-family:sans-serif;margin:2em\">\n<h1>skillc eval --sweep</h1>\n<p>Ranges per skill: <code>{}</code></p>\n{plot}\n<pre>{}</pre>\n</body></html>\n",
        escape(&serde_json::to_string(&summary.ranges).unwrap_or_default()),
        escape(text)
    );
    atomic::write(&out.join("index.html"), html.as_bytes())
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Joins the summaries of a sweep's shares. They must come from the same sweep (its identity,
/// seed, draws per skill, ranges), each share once, each holding exactly the draws it runs.
pub fn merge(parts: Vec<(String, SweepSummary)>) -> Result<Merged, String> {
    let mut parts = parts.into_iter();
    let Some((first_name, mut merged)) = parts.next() else {
        return Err("give the summary.json of every share to merge".to_string());
    };
    let check = |name: &str, part: &SweepSummary| -> Result<Vec<Partition>, String> {
        if part.format_version != super::SUMMARY_VERSION || part.kind != "sweep" {
            return Err(format!(
                "`{name}` is not a sweep summary of this skillc (format {} `{}`, expected {} `sweep`)",
                part.format_version,
                part.kind,
                super::SUMMARY_VERSION
            ));
        }
        let Some(identity) = &part.identity else {
            return Err(format!(
                "`{name}` records no sweep identity (written by an older skillc): run its share again"
            ));
        };
        if part.partitions.is_empty() {
            return Err(format!("`{name}` names no share (`partitions` is empty)"));
        }
        let mut shares = Vec::new();
        for text in &part.partitions {
            let share = parse_partition(text).map_err(|err| format!("`{name}`: share {err}"))?;
            if share.m != identity.shares {
                return Err(format!(
                    "`{name}`: share `{text}` is not one of the {} shares its sweep was split into",
                    identity.shares
                ));
            }
            shares.push(share);
        }
        // Each trial must be a draw its shares run, and each share must hold all of its draws:
        // a hand-edited or truncated summary is refused, not merged.
        let expected = expected_draws(identity, part.per_skill, &shares);
        let mut found = std::collections::BTreeSet::new();
        for trial in &part.trials {
            let key = (trial.skill.clone(), trial.draw.map_or(usize::MAX, |d| d.index));
            if !expected.contains(&key) {
                return Err(format!(
                    "`{name}` holds draw #{} of `{}`, which its share{} {} does not run",
                    key.1,
                    key.0,
                    if shares.len() == 1 { "" } else { "s" },
                    part.partitions.join(", ")
                ));
            }
            if !found.insert(key.clone()) {
                return Err(format!("`{name}` holds draw #{} of `{}` twice", key.1, key.0));
            }
        }
        if let Some((skill, index)) = expected.difference(&found).next() {
            return Err(format!(
                "`{name}` lacks draw #{index} of `{skill}` of its share{} {} ({} of {} draws present): the share did not finish; run it again",
                if shares.len() == 1 { "" } else { "s" },
                part.partitions.join(", "),
                found.len(),
                expected.len()
            ));
        }
        Ok(shares)
    };
    let mut shares_seen: BTreeMap<usize, String> = BTreeMap::new();
    let mut note_shares = |name: &str, shares: Vec<Partition>| -> Result<(), String> {
        for share in shares {
            if let Some(earlier) = shares_seen.insert(share.k, name.to_string()) {
                return Err(format!(
                    "`{name}` is share {share} again (as `{earlier}`): give each share once"
                ));
            }
        }
        Ok(())
    };
    note_shares(&first_name, check(&first_name, &merged)?)?;
    // Shares of one split run disjoint draws, and each share holds exactly its own once
    // (`check`), so no draw can stand twice in the merge.
    for (name, part) in parts {
        let shares = check(&name, &part)?;
        if part.seed != merged.seed || part.per_skill != merged.per_skill || part.ranges != merged.ranges {
            return Err(format!(
                "`{name}` comes from another sweep (seed {}, {} draws, or other ranges) than `{first_name}` (seed {}, {} draws)",
                part.seed, part.per_skill, merged.seed, merged.per_skill
            ));
        }
        if let (Some(a), Some(b)) = (&part.identity, &merged.identity) {
            if a != b {
                let what = if a.skillc_version != b.skillc_version {
                    format!("skillc {} against {}", a.skillc_version, b.skillc_version)
                } else if a.inputs != b.inputs {
                    "other trials, files or settings (--param, --limit, --robot)".to_string()
                } else if a.skills != b.skills {
                    format!("the skills {} against {}", a.skills.join(", "), b.skills.join(", "))
                } else {
                    format!("{} shares against {}", a.shares, b.shares)
                };
                return Err(format!("`{name}` comes from another sweep than `{first_name}`: {what}"));
            }
        }
        note_shares(&name, shares)?;
        merged.partitions.extend(part.partitions);
        merged.elapsed_s += part.elapsed_s;
        merged.trials.extend(part.trials);
    }
    // The order one process gives: each trial at its global index in the draw sequence (the
    // skills in the trials file's order, each skill's draws in index order), not by skill name.
    // (`check` admitted only draws of the identity's skills, each with its draw.)
    if let Some(identity) = &merged.identity {
        merged.trials.sort_by_cached_key(|trial| {
            (
                identity.skills.iter().position(|skill| *skill == trial.skill),
                trial.draw.map(|d| d.index),
            )
        });
    }
    let total = merged.identity.as_ref().map_or(1, |identity| identity.shares);
    let missing: Vec<String> = (1..=total)
        .filter(|k| !shares_seen.contains_key(k))
        .map(|k| Partition { k, m: total }.to_string())
        .collect();
    merged.partitions = shares_seen
        .keys()
        .map(|&k| Partition { k, m: total }.to_string())
        .collect();
    Ok(Merged {
        summary: merged,
        missing,
    })
}

/// What `eval merge` joined: the summary of the shares given, and the shares missing (a merge
/// with missing shares writes its report and fails).
#[derive(Debug)]
pub struct Merged {
    /// The joined summary.
    pub summary: SweepSummary,
    /// The shares not given, as `K/M` each.
    pub missing: Vec<String>,
}

/// The draws (skill, index) that `shares` of a sweep run.
fn expected_draws(
    identity: &SweepIdentity,
    per_skill: usize,
    shares: &[Partition],
) -> std::collections::BTreeSet<(String, usize)> {
    let mut draws = std::collections::BTreeSet::new();
    for (position, skill) in identity.skills.iter().enumerate() {
        for index in 0..per_skill {
            let global = position * per_skill + index;
            if shares.iter().any(|share| share.runs(global)) {
                draws.insert((skill.clone(), index));
            }
        }
    }
    draws
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_stay_in_their_ranges_and_repeat_for_a_seed() {
        let ranges = SweepRanges::default();
        for index in 0..500 {
            let d = draw(&ranges, 7, "touch", index);
            assert!(d.height_m.abs() <= 0.10 && d.tilt_deg.abs() <= 10.0);
            assert!(d.shift_m.iter().all(|s| s.abs() <= 0.03));
            assert!((0.2..=1.0).contains(&d.friction) && (1.0..=3.0).contains(&d.noise_scale));
            assert_eq!(d, draw(&ranges, 7, "touch", index));
        }
        assert_ne!(draw(&ranges, 7, "touch", 0), draw(&ranges, 8, "touch", 0));
        assert_ne!(draw(&ranges, 7, "touch", 0), draw(&ranges, 7, "press", 0));
        // The draws cover the range, not one corner of it.
        let heights: Vec<f64> = (0..500).map(|i| draw(&ranges, 7, "touch", i).height_m).collect();
        assert!(heights.iter().any(|h| *h > 0.08) && heights.iter().any(|h| *h < -0.08));
    }

    #[test]
    fn partitions_split_the_draws_without_overlap_or_gap() {
        let shares: Vec<Partition> = (1..=3)
            .map(|k| parse_partition(&format!("{k}/3")).expect("valid"))
            .collect();
        for index in 0..100 {
            assert_eq!(shares.iter().filter(|p| p.runs(index)).count(), 1);
        }
        for bad in ["0/3", "4/3", "1/0", "x/2", "12", "1/100000"] {
            assert!(parse_partition(bad).is_err(), "{bad}");
        }
        assert!(parse_draws("0").is_err() && parse_draws("1000000").is_err() && parse_draws("-1").is_err());
    }

    /// A synthetic sweep of two skills (the trials file's order not alphabetical), its trials'
    /// numbers drawn at random with up to 17 significant digits (plus 0.1 + 0.2 and 1/3), as
    /// one process writes it and as M shares written, read back and merged.
    fn synthetic_sweep(shares: usize) -> (SweepSummary, Vec<SweepSummary>) {
        let skills = ["touch".to_string(), "press".to_string()];
        let per_skill = 4;
        let ranges = SweepRanges::default();
        let mut rng = SplitMix64::new(11);
        let mut trials = Vec::new();
        for skill in &skills {
            for index in 0..per_skill {
                let mut trial =
                    crate::Outcome::error(skill, &format!("draw #{index}"), "skill", Vec::new(), String::new()).result;
                let mut number = || rng.range(-1.0, 1.0) * 10f64.powi(rng.range(-6.0, 6.0) as i32);
                trial.force_rms_rel = Some(0.1 + 0.2);
                trial.contact_share = Some(1.0 / 3.0);
                trial.peak_force_n = number();
                trial.goal_error_m = number();
                trial.duration_s = number();
                trial.peak_tool_speed_mps = number();
                trial.min_joint_margin_rad = number();
                trial.torque_limit_s = number();
                let mut d = draw(&ranges, 3, skill, index);
                d.start_raised_m = number();
                trial.draw = Some(d);
                trials.push(trial);
            }
        }
        let summary = |partition: Partition, trials: Vec<TrialResult>| SweepSummary {
            format_version: crate::SUMMARY_VERSION,
            kind: "sweep".to_string(),
            seed: 3,
            per_skill,
            partitions: vec![partition.to_string()],
            ranges: skills.iter().map(|skill| (skill.clone(), ranges)).collect(),
            identity: Some(SweepIdentity {
                skillc_version: "test".to_string(),
                inputs: "inputs".to_string(),
                skills: skills.to_vec(),
                shares: partition.m,
            }),
            elapsed_s: 0.0,
            trials,
        };
        let whole = summary(Partition::ALL, trials.clone());
        // Each share as `eval --partition K/M` writes it (`fill`) and `eval merge` reads it,
        // given to the merge last share first.
        let parts = (1..=shares)
            .rev()
            .map(|k| {
                let partition = Partition { k, m: shares };
                let mine = trials
                    .iter()
                    .enumerate()
                    .filter(|(global, _)| partition.runs(*global))
                    .map(|(_, trial)| trial.clone())
                    .collect();
                let text = serde_json::to_string_pretty(&summary(partition, mine)).expect("serialises") + "\n";
                serde_json::from_str(&text).expect("reads back")
            })
            .collect();
        (whole, parts)
    }

    #[test]
    fn merged_shares_write_the_bytes_one_process_writes() {
        let (whole, parts) = synthetic_sweep(3);
        let named = parts
            .into_iter()
            .enumerate()
            .map(|(i, part)| (format!("share{i}"), part))
            .collect();
        let mut merged = merge(named).expect("the shares belong together");
        assert!(merged.missing.is_empty());
        assert_eq!(merged.summary.partitions, ["1/3", "2/3", "3/3"]);
        // What differs by design: the shares named and the number of shares (timing is 0 here).
        merged.summary.partitions = whole.partitions.clone();
        if let Some(identity) = &mut merged.summary.identity {
            identity.shares = 1;
        }
        let text = |summary: &SweepSummary| serde_json::to_string_pretty(summary).expect("serialises");
        let (one, joined) = (text(&whole), text(&merged.summary));
        // Line by line first, for a readable failure.
        for (a, b) in one.lines().zip(joined.lines()) {
            assert_eq!(a, b, "the merge changed a line of summary.json");
        }
        assert_eq!(one, joined);
        assert_eq!(table(&whole), table(&merged.summary));
    }

    #[test]
    fn bad_ranges_name_their_key() {
        let ranges = SweepRanges {
            friction: [0.8, 0.2],
            ..SweepRanges::default()
        };
        assert!(ranges.validate("press").unwrap_err().contains("sweep.friction"));
        let ranges = SweepRanges {
            height_m: f64::NAN,
            ..SweepRanges::default()
        };
        assert!(ranges.validate("press").unwrap_err().contains("sweep.height_m"));
    }
}

#[cfg(test)]
mod scene_tests {
    use std::path::Path;

    use skill_runtime::robot::Robot;
    use skill_runtime::sim::{RapierPlant, Scene};

    use super::*;

    /// Every shipped scene, its objects moved up into the tool's start: the draw raises the
    /// start until the tool is outside them, and the scene then builds.
    #[test]
    fn raised_objects_raise_the_start_out_of_them() {
        for file in [
            "examples/scenes/table.toml",
            "examples/scenes/button.toml",
            "examples/scenes/cylinder.toml",
        ] {
            let scene =
                Scene::from_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(file)).expect("shipped scene");
            let robot = Robot::from_urdf_file(&scene.urdf_path(), scene.spec().robot.tool.as_deref()).expect("urdf");
            let unmoved = RapierPlant::scene_start_clearance(robot.clone(), &scene)
                .expect("builds")
                .map_or(1.0, |(d, _)| d);
            for (height_m, tilt_deg) in [(0.066, 3.3), (0.10, -10.0), (0.0, 10.0), (-0.1, 0.0)] {
                let mut draw = Draw {
                    index: 0,
                    height_m,
                    tilt_deg,
                    tilt_axis_deg: 30.0,
                    shift_m: [0.01, -0.02],
                    friction: 0.5,
                    noise_scale: 2.0,
                    start_raised_m: 0.0,
                };
                let sets = scene_sets(&scene, &robot, &mut draw, 1).expect("a start above the objects");
                let mut moved = scene.clone();
                apply(&mut moved, &sets).expect("valid overrides");
                let clearance = RapierPlant::scene_start_clearance(robot.clone(), &moved)
                    .expect("builds")
                    .map_or(1.0, |(d, _)| d);
                assert!(
                    clearance >= START_CLEARANCE_M,
                    "{file} {height_m} m {tilt_deg}°: clearance {clearance} m after raising {} m",
                    draw.start_raised_m
                );
                // Under a table (wide enough that the shift keeps it under the tool) the start
                // rises by about what the table rises beyond its clearance in the scene as
                // written (the tilt moves the nearest point by under 2 cm). A shifted button or
                // drum may leave the tool's column, so there only the clearance is checked.
                let beyond = height_m - unmoved + START_CLEARANCE_M;
                if file.ends_with("table.toml") && beyond > 0.02 {
                    assert!(
                        draw.start_raised_m > beyond - 0.02,
                        "{file}: raised {} m for objects {height_m} m higher, {unmoved} m clear before",
                        draw.start_raised_m
                    );
                } else if height_m < 0.0 {
                    assert_eq!(draw.start_raised_m, 0.0);
                }
                RapierPlant::from_scene(&moved).expect("the tool starts outside every object");
            }
        }
    }
}

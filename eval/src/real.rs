//! `skillc eval --real DIR`: learn the wipe skill (approach, strokes in contact, retreat) from each
//! usable real demonstration in a folder
//! shaped like the LASA wiping data (`*.csv` with skillc's demonstration columns, optional
//! `segment_labels.csv`), compare the segmentation with the authors' labels, and reproduce
//! each on a table whose top is the learned plane.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use serde::Serialize;
use skill_runtime::demo::{frozen_force_share, read_csv, ReadOptions, FROZEN_FORCE_SHARE};
use skill_runtime::exec::{bind, simulate, ExecOptions, Mode};
use skill_runtime::skill::{learn_skill, LearnOptions, LearnedForce, LearnedFrame};

use super::metrics::{measure, ContactPlan};
use skill_kit::load::{error_chain, load_scene, Failure};

/// What happened with one real demonstration.
#[derive(Debug, Clone, Serialize)]
pub struct RealResult {
    /// The file.
    pub file: String,
    /// Samples.
    pub samples: usize,
    /// Why it was skipped or failed, if it was.
    pub skipped: Option<String>,
    /// Boundaries found \[s\].
    pub found_boundaries_s: Vec<f64>,
    /// Boundaries of the authors' labels \[s\], if a labels file lists the demonstration.
    pub label_boundaries_s: Vec<f64>,
    /// Per label boundary, the distance to the nearest found boundary \[s\].
    pub boundary_errors_s: Vec<f64>,
    /// The learned constant force \[N\].
    pub force_n: Option<f64>,
    /// The learned plane's normal (into the surface), base frame.
    pub plane_z: Option<[f64; 3]>,
    /// The reproduction on a table at the learned plane.
    pub reproduction: Option<String>,
    /// Its force RMS over the learned force, during contact.
    pub force_rms_rel: Option<f64>,
    /// Its share of the contact phase in contact.
    pub contact_share: Option<f64>,
    /// The strokes found in the contact phase (a strokes motion's count).
    pub strokes: Option<usize>,
    /// The reproduction's largest contact force and the eval's bound on it (twice the
    /// demonstration's largest force plus 5 N) \[N\].
    pub peak_force_n: Option<[f64; 2]>,
    /// How learning read the file's wrench: its frame, bias and sign.
    pub wrench: Option<String>,
    /// Whether the reproduction started from the file's joint angles.
    pub start_from_demo: bool,
    /// The contact phases found, onset and release \[s\] from the file's start.
    pub phases_s: Vec<[f64; 2]>,
    /// The phase learned (1-based) when the file was cut to one.
    pub phase_learned: Option<usize>,
    /// The median applied force along the learned plane's normal over the labelled wipe
    /// segment (label 2) that overlaps the learned contact most \[N\].
    pub labelled_median_n: Option<f64>,
    /// The learned force against it, `learned / median − 1`.
    pub force_error_rel: Option<f64>,
}

impl RealResult {
    /// `phases 1.93-8.05 s; learned phase -; force 20.1 N for a labelled median 21.0 N (-4.3 %)`.
    pub fn learning_line(&self) -> String {
        let phases: Vec<String> = self.phases_s.iter().map(|[a, b]| format!("{a:.2}-{b:.2}")).collect();
        let mut line = format!("{} contact phase(s) [{}] s", phases.len(), phases.join(", "));
        if let Some(phase) = self.phase_learned {
            let _ = write!(line, ", learned phase {phase}");
        }
        if let (Some(force), Some(median), Some(error)) = (self.force_n, self.labelled_median_n, self.force_error_rel) {
            let _ = write!(
                line,
                "; force {force:.2} N for a labelled median {median:.2} N ({:+.1} %)",
                error * 100.0
            );
        }
        line
    }
}

/// Rows of `segment_labels.csv` for `file`: first and last sample (0-based, inclusive) and label.
fn label_rows(dir: &Path, file: &str) -> Vec<(usize, usize, String)> {
    let Ok(text) = std::fs::read_to_string(dir.join("segment_labels.csv")) else {
        return Vec::new();
    };
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("file,"))
        .filter_map(|line| {
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if fields.len() != 4 || fields[0] != file {
                return None;
            }
            let first = fields[1].parse::<usize>().ok()?.checked_sub(1)?;
            let last = fields[2].parse::<usize>().ok()?.checked_sub(1)?;
            Some((first, last, fields[3].to_string()))
        })
        .collect()
}

fn label_boundaries(dir: &Path, file: &str) -> Option<Vec<usize>> {
    let text = std::fs::read_to_string(dir.join("segment_labels.csv")).ok()?;
    let mut starts: Vec<usize> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("file,"))
        .filter_map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            (fields.len() == 4 && fields[0].trim() == file)
                .then(|| fields[1].trim().parse::<usize>().ok())
                .flatten()
        })
        .collect();
    starts.sort_unstable();
    (!starts.is_empty()).then(|| starts.into_iter().skip(1).map(|s| s - 1).collect())
}

/// Evaluates every demonstration in `dir` with the wipe template `skill`.
pub fn evaluate(dir: &Path, skill: &skill_ir::Skill, table_scene: &Path) -> Result<Vec<RealResult>, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|err| format!("cannot read `{}`: {err}", dir.display()))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .filter(|p| {
            !matches!(
                p.file_name().and_then(|n| n.to_str()),
                Some("segment_labels.csv" | "index.csv")
            )
        })
        .collect();
    files.sort();
    use rayon::prelude::*;
    Ok(files
        .par_iter()
        .map(|path| one(dir, path, skill, table_scene))
        .collect())
}

fn one(dir: &Path, path: &Path, skill: &skill_ir::Skill, table_scene: &Path) -> RealResult {
    let file = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut result = RealResult {
        file: file.clone(),
        samples: 0,
        skipped: None,
        found_boundaries_s: Vec::new(),
        label_boundaries_s: Vec::new(),
        boundary_errors_s: Vec::new(),
        force_n: None,
        plane_z: None,
        reproduction: None,
        force_rms_rel: None,
        contact_share: None,
        strokes: None,
        peak_force_n: None,
        wrench: None,
        start_from_demo: false,
        phases_s: Vec::new(),
        phase_learned: None,
        labelled_median_n: None,
        force_error_rel: None,
    };
    let loaded = match read_csv(path, &ReadOptions { min_samples: 30 }) {
        Ok(loaded) => loaded,
        Err(err) => {
            result.skipped = Some(error_chain(&err));
            return result;
        }
    };
    let demo = loaded.demo;
    result.samples = demo.len();
    if frozen_force_share(&demo.force_n) > FROZEN_FORCE_SHARE {
        result.skipped = Some("the force signal is frozen (the sensor did not stream): skipped".to_string());
        return result;
    }
    // The learner settles the wrench's frame, bias and sign itself (docs/method.md §1).
    let warnings: Vec<String> = loaded.warnings.iter().map(ToString::to_string).collect();
    let learned = match learn_skill(skill, &demo, &warnings, &LearnOptions::default()) {
        Ok(learned) => learned,
        Err(err) => {
            result.skipped = Some(error_chain(&err));
            return result;
        }
    };
    result.wrench = learned.quality.wrench.as_ref().map(ToString::to_string);
    let t0 = demo.t_s[0];
    result.found_boundaries_s = learned.segments.iter().skip(1).map(|s| s.start_s - t0).collect();
    if let Some(labels) = label_boundaries(dir, &file) {
        result.label_boundaries_s = labels.iter().filter_map(|&k| demo.t_s.get(k)).map(|t| t - t0).collect();
        result.boundary_errors_s = result
            .label_boundaries_s
            .iter()
            .map(|l| {
                result
                    .found_boundaries_s
                    .iter()
                    .map(|f| (f - l).abs())
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
    }
    result.strokes = learned.motions.values().map(|m| m.strokes.len()).find(|&n| n > 0);
    result.force_n = learned.forces.values().find_map(|f| match f {
        LearnedForce::Constant { value_n, .. } => Some(*value_n),
        _ => None,
    });
    let Some(LearnedFrame::Constant(plane)) = learned.frames.values().next() else {
        result.reproduction = Some("no constant plane learned".to_string());
        return result;
    };
    let plane = plane.isometry();
    let z = plane.rotation * Vector3::z();
    result.plane_z = Some([z.x, z.y, z.z]);
    if let Some(phases) = &learned.quality.phases {
        result.phases_s = phases.phases_s.iter().map(|[a, b]| [a - t0, b - t0]).collect();
        result.phase_learned = phases.learned;
    }
    // The labelled median: the applied force along the learned normal, the wrench settled as
    // learning settles it, over the labelled wipe segment nearest the learned contact.
    if let (Some(contact), Ok(prepared)) = (
        learned.segments.get(1),
        skill_runtime::demo::prepare(
            &demo,
            &skill_runtime::demo::PreprocessConfig::default(),
            &skill_runtime::demo::WrenchOptions::default(),
        ),
    ) {
        let overlap = |first: usize, last: usize| {
            let (a, b) = (demo.t_s[first.min(demo.len() - 1)], demo.t_s[last.min(demo.len() - 1)]);
            (b.min(contact.end_s) - a.max(contact.start_s)).max(0.0)
        };
        let best = label_rows(dir, &file)
            .into_iter()
            .filter(|(_, _, label)| label == "2")
            .max_by(|a, b| overlap(a.0, a.1).total_cmp(&overlap(b.0, b.1)));
        if let Some((first, last, _)) = best {
            let last = last.min(prepared.demo.len() - 1);
            let mut along: Vec<f64> = (first..=last).map(|k| -prepared.demo.force_n[k].dot(&z)).collect();
            along.sort_by(f64::total_cmp);
            if let Some(&median) = along.get(along.len() / 2) {
                result.labelled_median_n = Some(median);
                result.force_error_rel = result.force_n.map(|f| f / median - 1.0);
            }
        }
    }

    // A table whose top is the learned plane, moved along the normal by the probe's length
    // (demonstrations record the flange; the probe tip touches the surface).
    let tool_offset = 0.11 + skill_runtime::demogen::TIP_RADIUS_M;
    let thickness = 0.05;
    let centre = plane.translation.vector + z * (tool_offset + thickness / 2.0);
    let top_down = UnitQuaternion::from_rotation_matrix(&Rotation3::face_towards(&z, &Vector3::x()));
    let (roll, pitch, yaw) =
        (top_down * UnitQuaternion::from_euler_angles(0.0, std::f64::consts::PI, 0.0)).euler_angles();
    let mut sets = vec![
        format!("table.xyz=[{}, {}, {}]", centre.x, centre.y, centre.z),
        format!("table.rpy=[{roll}, {pitch}, {yaw}]"),
        "table.size=[0.8, 0.8, 0.05]".to_string(),
    ];
    // Start the arm as the demonstrator held it (the file's joint angles), not in whatever
    // configuration the scene's q0 gives: the same flange pose has other elbow positions.
    if let Some(q) = start_joints(path) {
        let list: Vec<String> = q.iter().map(|v| format!("{v}")).collect();
        sets.push(format!("robot.q0=[{}]", list.join(", ")));
        result.start_from_demo = true;
    }
    let scene = match load_scene(table_scene, &sets) {
        Ok(scene) => scene,
        Err(Failure::Input(m) | Failure::Usage(m)) => {
            result.reproduction = Some(format!("cannot build the table scene: {m}"));
            return result;
        }
        Err(Failure::Closed) => return result,
    };
    let bound = match bind(skill, &learned) {
        Ok(bound) => bound,
        Err(err) => {
            result.reproduction = Some(err.to_string());
            return result;
        }
    };
    match simulate(&scene, Mode::Skill(&bound), &ExecOptions::default()) {
        Ok((report, log)) => {
            let plan = ContactPlan::of(&bound);
            let metrics = measure(&log, &plan, false, &|_| z);
            result.force_rms_rel = metrics.force_rms_rel;
            result.contact_share = metrics.contact_share;
            let demo_peak = demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max);
            result.peak_force_n = Some([metrics.peak_force_n, super::Criteria::default().peak_bound(demo_peak)]);
            result.reproduction = Some(format!("{:?}: {}", report.outcome, report.message));
        }
        Err(err) => result.reproduction = Some(error_chain(&err)),
    }
    result
}

/// The joint angles of a demonstration's first sample, when the file has the columns `q1` to
/// `q7` (as the LASA LWR-IV recordings do) and they are finite.
fn start_joints(path: &Path) -> Option<Vec<f64>> {
    let mut reader = csv::ReaderBuilder::new().flexible(true).from_path(path).ok()?;
    let headers = reader.headers().ok()?.clone();
    let columns: Vec<usize> = (1..=7)
        .map(|j| headers.iter().position(|h| h.trim() == format!("q{j}")))
        .collect::<Option<_>>()?;
    let first = reader.records().next()?.ok()?;
    let q: Vec<f64> = columns
        .iter()
        .map(|&c| first.get(c).and_then(|v| v.trim().parse::<f64>().ok()))
        .collect::<Option<_>>()?;
    q.iter().all(|v| v.is_finite()).then_some(q)
}

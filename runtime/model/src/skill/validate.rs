//! Checking a learned file before it is written and after it is read: the version, finite
//! numbers, consistent and non-empty arrays, unit quaternions, and bounds on everything that
//! sizes work or memory later (DMP durations, basis counts, per-sample frames), so that a
//! hand-edited or corrupt file is an error naming the value, never a panic, a hang or a
//! multi-gigabyte allocation in a rollout.

use nalgebra::UnitQuaternion;

use super::learned::{FramePose, Learned, LearnedForce, LearnedFrame, LEARNED_VERSION};
use crate::dmp::{Basis, Dmp, DmpConfig, QuatDmp};

/// Longest DMP duration accepted \[s\]: a rollout at 1 kHz is then at most 600 000 steps.
pub const MAX_TAU_S: f64 = 600.0;
/// Shortest DMP duration accepted \[s\].
pub const MIN_TAU_S: f64 = 1e-3;
/// Most basis functions per DMP (the learner's own limit).
pub const MAX_BASIS: usize = 10_000;
/// Largest magnitude of a position \[m\], force \[N\] or torque \[N m\] in a learned file.
pub const MAX_VALUE: f64 = 1e6;
/// Largest magnitude of a DMP weight (learned ones are below 1e5).
pub const MAX_WEIGHT: f64 = 1e9;
/// Most poses of a per-sample frame.
pub const MAX_FRAME_SAMPLES: usize = 1_000_000;
/// The most strokes a learned motion may hold: a demonstration of at most 600 s with strokes of
/// at least a few hundredths of a second.
pub const MAX_STROKES: usize = 10_000;
/// How far a quaternion's norm may be from 1.
const UNIT_TOLERANCE: f64 = 1e-3;

/// What is wrong with a learned file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum InvalidLearned {
    /// Written by another version of the format.
    #[error("learned-file version {found}, this skillc reads version {supported}: learn it again with this skillc")]
    Version {
        /// The file's `learned_version`.
        found: u64,
        /// [`LEARNED_VERSION`].
        supported: u32,
    },
    /// One value is out of range or inconsistent with the rest.
    #[error("`{field}` {reason}")]
    Value {
        /// Where in the file, e.g. `motions.approach.position.tau_s`.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
}

fn bad(field: impl Into<String>, reason: impl Into<String>) -> InvalidLearned {
    InvalidLearned::Value {
        field: field.into(),
        reason: reason.into(),
    }
}

fn finite(field: &str, value: f64, max: f64) -> Result<(), InvalidLearned> {
    if !value.is_finite() {
        return Err(bad(field, format!("is not a finite number ({value})")));
    }
    if value.abs() > max {
        return Err(bad(field, format!("is {value:e}, beyond ±{max:e}")));
    }
    Ok(())
}

fn all_finite(field: &str, values: &[f64], max: f64) -> Result<(), InvalidLearned> {
    for (index, value) in values.iter().enumerate() {
        finite(&format!("{field}[{index}]"), *value, max)?;
    }
    Ok(())
}

fn unit(field: &str, wxyz: [f64; 4]) -> Result<(), InvalidLearned> {
    all_finite(field, &wxyz, 2.0)?;
    let norm = wxyz.iter().map(|v| v * v).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > UNIT_TOLERANCE {
        return Err(bad(field, format!("is not a unit quaternion (norm {norm:.6})")));
    }
    Ok(())
}

fn unit_quaternion(field: &str, q: &UnitQuaternion<f64>) -> Result<(), InvalidLearned> {
    let q = q.quaternion();
    unit(field, [q.w, q.i, q.j, q.k])
}

impl Learned {
    /// Checks the file as the module docs say; `Ok` means a rollout, a binding and a run can
    /// use it without further checks of its numbers.
    pub fn validate(&self) -> Result<(), InvalidLearned> {
        if self.learned_version != LEARNED_VERSION {
            return Err(InvalidLearned::Version {
                found: u64::from(self.learned_version),
                supported: LEARNED_VERSION,
            });
        }
        finite("demo.duration_s", self.demo.duration_s, 1e9)?;
        finite("demo.rate_hz", self.demo.rate_hz, 1e9)?;
        for (index, segment) in self.segments.iter().enumerate() {
            let field = format!("segments[{index}]");
            finite(&format!("{field}.start_s"), segment.start_s, 1e9)?;
            finite(&format!("{field}.end_s"), segment.end_s, 1e9)?;
            if segment.end_s < segment.start_s || segment.end_index < segment.start_index {
                return Err(bad(field, "ends before it starts"));
            }
        }
        for (name, frame) in &self.frames {
            let field = format!("frames.{name}");
            match frame {
                LearnedFrame::Constant(pose) => pose_ok(&field, pose)?,
                LearnedFrame::Samples(poses) => {
                    if poses.is_empty() {
                        return Err(bad(field, "has no poses"));
                    }
                    if poses.len() > MAX_FRAME_SAMPLES {
                        return Err(bad(
                            field,
                            format!("has {} poses, at most {MAX_FRAME_SAMPLES}", poses.len()),
                        ));
                    }
                    for (index, pose) in poses.iter().enumerate() {
                        pose_ok(&format!("{field}[{index}]"), pose)?;
                    }
                }
            }
        }
        for (name, motion) in &self.motions {
            let field = format!("motions.{name}");
            if motion.segment >= self.segments.len().max(1) {
                return Err(bad(
                    format!("{field}.segment"),
                    format!("is {}, the file has {} segment(s)", motion.segment, self.segments.len()),
                ));
            }
            dmp_ok(&format!("{field}.position"), &motion.position, Some(3))?;
            quat_dmp_ok(&format!("{field}.orientation"), &motion.orientation)?;
            if motion.strokes.len() > MAX_STROKES {
                return Err(bad(
                    format!("{field}.strokes"),
                    format!("has {} strokes, more than {MAX_STROKES}", motion.strokes.len()),
                ));
            }
            for (index, stroke) in motion.strokes.iter().enumerate() {
                let field = format!("{field}.strokes[{index}]");
                if !stroke.strokes.is_empty() {
                    return Err(bad(
                        format!("{field}.strokes"),
                        "is not empty: a stroke is not cut into strokes again".to_string(),
                    ));
                }
                if stroke.segment != motion.segment {
                    return Err(bad(
                        format!("{field}.segment"),
                        format!(
                            "is {}, its motion's segment is {}: a stroke lies in its motion's segment",
                            stroke.segment, motion.segment
                        ),
                    ));
                }
                dmp_ok(&format!("{field}.position"), &stroke.position, Some(3))?;
                quat_dmp_ok(&format!("{field}.orientation"), &stroke.orientation)?;
            }
        }
        for (name, force) in &self.forces {
            let field = format!("forces.{name}");
            match force {
                LearnedForce::Constant {
                    value_n,
                    std_n,
                    region_s,
                } => {
                    finite(&format!("{field}.value_n"), *value_n, MAX_VALUE)?;
                    finite(&format!("{field}.std_n"), *std_n, MAX_VALUE)?;
                    all_finite(&format!("{field}.region_s"), region_s, 1e9)?;
                }
                LearnedForce::At { value_n }
                | LearnedForce::Literal { value_n }
                | LearnedForce::Tracked { value_n } => finite(&format!("{field}.value_n"), *value_n, MAX_VALUE)?,
                LearnedForce::Dmp { dmp } => dmp_ok(&format!("{field}.dmp"), dmp, Some(3))?,
                LearnedForce::Magnitude { dmp } => dmp_ok(&format!("{field}.dmp"), dmp, Some(1))?,
            }
        }
        for (name, threshold) in &self.thresholds {
            finite(&format!("thresholds.{name}.value"), threshold.value, MAX_VALUE)?;
        }
        for (name, quality) in &self.quality.motions {
            let field = format!("quality.motions.{name}");
            all_finite(&format!("{field}.position_rms_m"), &quality.position_rms_m, f64::MAX)?;
            finite(
                &format!("{field}.orientation_rms_rad"),
                quality.orientation_rms_rad,
                f64::MAX,
            )?;
        }
        for (name, rms) in &self.quality.forces_rms_n {
            finite(&format!("quality.forces_rms_n.{name}"), *rms, f64::MAX)?;
        }
        for (name, fits) in &self.quality.constraints {
            for (index, fit) in fits.iter().enumerate() {
                let field = format!("quality.constraints.{name}[{index}]");
                finite(&format!("{field}.residual_m"), fit.residual_m, f64::MAX)?;
                finite(&format!("{field}.residual_rad"), fit.residual_rad, f64::MAX)?;
                finite(&format!("{field}.force_agreement"), fit.force_agreement, f64::MAX)?;
            }
        }
        Ok(())
    }
}

fn pose_ok(field: &str, pose: &FramePose) -> Result<(), InvalidLearned> {
    all_finite(&format!("{field}.origin"), &pose.origin, MAX_VALUE)?;
    unit(&format!("{field}.quaternion_wxyz"), pose.quaternion_wxyz)?;
    if let Some(t_s) = pose.t_s {
        finite(&format!("{field}.t_s"), t_s, 1e9)?;
    }
    Ok(())
}

fn config_ok(field: &str, config: &DmpConfig, basis: &Basis, tau_s: f64) -> Result<(), InvalidLearned> {
    config
        .validate()
        .map_err(|err| bad(format!("{field}.config"), format!("is invalid: {err}")))?;
    let n = basis.centers.len();
    if !(2..=MAX_BASIS).contains(&n) {
        return Err(bad(
            format!("{field}.basis.centers"),
            format!("has {n} basis function(s), between 2 and {MAX_BASIS} are needed"),
        ));
    }
    if n != config.n_basis {
        return Err(bad(
            format!("{field}.basis.centers"),
            format!("has {n} entries, `config.n_basis` says {}", config.n_basis),
        ));
    }
    if basis.widths.len() != n {
        return Err(bad(
            format!("{field}.basis.widths"),
            format!("has {} entries, the basis has {n} centres", basis.widths.len()),
        ));
    }
    all_finite(&format!("{field}.basis.centers"), &basis.centers, 1.0 + 1e-9)?;
    all_finite(&format!("{field}.basis.widths"), &basis.widths, f64::MAX)?;
    if let Some(index) = basis.widths.iter().position(|w| *w <= 0.0) {
        return Err(bad(format!("{field}.basis.widths[{index}]"), "must be positive"));
    }
    finite(&format!("{field}.basis.alpha_s"), basis.alpha_s, 1e3)?;
    if !(MIN_TAU_S..=MAX_TAU_S).contains(&tau_s) {
        return Err(bad(
            format!("{field}.tau_s"),
            format!("is {tau_s} s, it must lie between {MIN_TAU_S} and {MAX_TAU_S} s"),
        ));
    }
    Ok(())
}

fn weights_ok(field: &str, weights: &[Vec<f64>], channels: usize, n: usize) -> Result<(), InvalidLearned> {
    if weights.len() != channels {
        return Err(bad(
            format!("{field}.weights"),
            format!("has {} channel(s), {channels} are needed", weights.len()),
        ));
    }
    for (channel, row) in weights.iter().enumerate() {
        let field = format!("{field}.weights[{channel}]");
        if row.len() != n {
            return Err(bad(field, format!("has {} weights, the basis has {n}", row.len())));
        }
        all_finite(&field, row, MAX_WEIGHT)?;
    }
    Ok(())
}

fn dmp_ok(field: &str, dmp: &Dmp, channels: Option<usize>) -> Result<(), InvalidLearned> {
    config_ok(field, &dmp.config, &dmp.basis, dmp.tau_s)?;
    let dims = dmp.start.len();
    if dims == 0 {
        return Err(bad(format!("{field}.start"), "is empty"));
    }
    if let Some(expected) = channels {
        if dims != expected {
            return Err(bad(
                format!("{field}.start"),
                format!("has {dims} channel(s), {expected} are needed"),
            ));
        }
    }
    if dmp.goal.len() != dims {
        return Err(bad(
            format!("{field}.goal"),
            format!("has {} channel(s), `start` has {dims}", dmp.goal.len()),
        ));
    }
    if !dmp.start_velocity.is_empty() && dmp.start_velocity.len() != dims {
        return Err(bad(
            format!("{field}.start_velocity"),
            format!("has {} channel(s), `start` has {dims}", dmp.start_velocity.len()),
        ));
    }
    all_finite(&format!("{field}.start"), &dmp.start, MAX_VALUE)?;
    all_finite(&format!("{field}.goal"), &dmp.goal, MAX_VALUE)?;
    all_finite(&format!("{field}.start_velocity"), &dmp.start_velocity, MAX_VALUE)?;
    weights_ok(field, &dmp.weights, dims, dmp.basis.centers.len())
}

fn quat_dmp_ok(field: &str, dmp: &QuatDmp) -> Result<(), InvalidLearned> {
    config_ok(field, &dmp.config, &dmp.basis, dmp.tau_s)?;
    unit_quaternion(&format!("{field}.start"), &dmp.start)?;
    unit_quaternion(&format!("{field}.goal"), &dmp.goal)?;
    weights_ok(field, &dmp.weights, 3, dmp.basis.centers.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skill::learned::{DemoInfo, LearnedMotion, LearnedSegment, Quality};
    use std::collections::BTreeMap;

    fn learned() -> Learned {
        let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.01).collect();
        let x: Vec<f64> = t.iter().map(|t| 0.1 * t).collect();
        let config = DmpConfig {
            n_basis: 10,
            ..DmpConfig::default()
        };
        let position = Dmp::fit(&config, &t, &[&x, &x, &x]).expect("fits");
        let q = vec![UnitQuaternion::identity(); t.len()];
        let orientation = QuatDmp::fit(&config, &t, &q).expect("fits");
        let mut motions = BTreeMap::new();
        motions.insert(
            "approach".to_string(),
            LearnedMotion {
                segment: 0,
                position,
                orientation,
                strokes: Vec::new(),
            },
        );
        Learned {
            learned_version: LEARNED_VERSION,
            skill: "touch".into(),
            ir_hash: "0".into(),
            demo: DemoInfo {
                source: "demo.csv".into(),
                samples: 200,
                duration_s: 1.99,
                rate_hz: 100.0,
                warnings: Vec::new(),
            },
            segments: vec![LearnedSegment {
                start_s: 0.0,
                end_s: 1.99,
                start_index: 0,
                end_index: 200,
            }],
            frames: BTreeMap::new(),
            motions,
            forces: BTreeMap::new(),
            thresholds: BTreeMap::new(),
            quality: Quality::default(),
        }
    }

    fn motion(learned: &mut Learned) -> &mut LearnedMotion {
        learned.motions.get_mut("approach").expect("the motion")
    }

    #[test]
    fn a_learned_file_passes() {
        learned().validate().expect("valid");
    }

    #[test]
    fn another_version_says_learn_again() {
        let mut file = learned();
        file.learned_version = 99;
        let err = file.validate().expect_err("version 99").to_string();
        assert!(err.contains("99") && err.contains("learn it again"), "{err}");
    }

    #[test]
    fn strokes_are_checked_like_motions_and_stay_in_their_segment() {
        let mut file = learned();
        let mut stroke = motion(&mut file).clone();
        stroke.strokes.clear();
        motion(&mut file).strokes = vec![stroke.clone(), stroke.clone()];
        file.validate().expect("two strokes in the motion's segment");
        motion(&mut file).strokes[1].segment = 1;
        let err = file.validate().expect_err("a stroke elsewhere").to_string();
        assert!(err.contains("motions.approach.strokes[1].segment"), "{err}");
        motion(&mut file).strokes[1].segment = 0;
        motion(&mut file).strokes[0].position.tau_s = 1e12;
        let err = file.validate().expect_err("a stroke of 1e12 s").to_string();
        assert!(err.contains("motions.approach.strokes[0].position.tau_s"), "{err}");
        motion(&mut file).strokes[0] = stroke.clone();
        motion(&mut file).strokes[0].strokes = vec![stroke];
        let err = file.validate().expect_err("strokes of a stroke").to_string();
        assert!(err.contains("motions.approach.strokes[0].strokes"), "{err}");
    }

    #[test]
    fn empty_bases_and_weights_are_refused() {
        let mut file = learned();
        let position = &mut motion(&mut file).position;
        position.basis.centers.clear();
        position.basis.widths.clear();
        position.weights = vec![Vec::new(); 3];
        let err = file.validate().expect_err("empty basis").to_string();
        assert!(err.contains("motions.approach.position.basis.centers"), "{err}");
    }

    #[test]
    fn durations_and_basis_counts_are_bounded() {
        for tau_s in [0.0, -1.0, 1e12, f64::NAN] {
            let mut file = learned();
            motion(&mut file).orientation.tau_s = tau_s;
            let err = file.validate().expect_err("tau out of range").to_string();
            assert!(err.contains("orientation.tau_s"), "{err}");
        }
        let mut file = learned();
        let position = &mut motion(&mut file).position;
        position.basis.centers = vec![0.5; 2_500_000];
        assert!(file.validate().is_err(), "2.5 M bases");
    }

    #[test]
    fn overflowing_values_and_non_unit_quaternions_are_named() {
        let mut file = learned();
        motion(&mut file).position.weights[1][3] = 1e300;
        let err = file.validate().expect_err("huge weight").to_string();
        assert!(err.contains("motions.approach.position.weights[1][3]"), "{err}");
        let mut file = learned();
        motion(&mut file).position.goal[2] = f64::INFINITY;
        assert!(file.validate().expect_err("inf goal").to_string().contains("goal[2]"));
        let mut file = learned();
        motion(&mut file).orientation.goal =
            UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(2.0, 0.0, 0.0, 0.0));
        let err = file.validate().expect_err("norm 2").to_string();
        assert!(err.contains("unit quaternion"), "{err}");
    }
}

//! Learning a plan's motions: a position DMP and a quaternion DMP per segment (and per stroke of
//! a `strokes` motion, cut by [`find_strokes`]), with their
//! reconstruction error and the plausibility checks of docs/method.md §2 (warn, or refuse).

use nalgebra::Vector3;
use skill_ir as ir;

use super::smoothing::{smooth_points, smoothing_window};
use super::{LearnError, Learner};
use crate::demo::Smoothing;
use crate::dmp::{Dmp, DmpConfig, QuatDmp};
use crate::skill::learned::{LearnedMotion, MotionQuality};
use crate::strokes::find_strokes;

/// Reconstruction error (3-D RMS) above which `learn` warns \[m\]. A 50-basis fit of a smooth
/// hand-guided segment reconstructs to a few hundredths of a millimetre; a millimetre means
/// the primitive misses features, which matters where the tool meets a surface.
const WARN_RMS_M: f64 = 1e-3;

/// Reconstruction error (3-D RMS) above which `learn` refuses \[m\]: the primitive no longer
/// describes the demonstration (the path goes centimetres elsewhere, where a surface may be).
const REFUSE_RMS_M: f64 = 1e-2;

/// The rollout's peak speed may exceed the demonstrated (smoothed) peak by this factor plus
/// [`SPEED_SLACK_MPS`] before `learn` warns: a faithful fit reproduces the speed within a few
/// per cent.
const WARN_SPEED_RATIO: f64 = 1.5;

/// ... and by this factor before it refuses: a primitive three times as fast as the person
/// moved the arm (noise fitted as motion, 0.8 m/s swings) is unsafe to run in contact.
const REFUSE_SPEED_RATIO: f64 = 3.0;

/// Slack for nearly still segments \[m/s\], where a ratio alone would flag millimetres per second.
const SPEED_SLACK_MPS: f64 = 0.02;

impl Learner<'_> {
    pub(super) fn motion(&mut self, decl: &ir::MotionDecl) -> Result<LearnedMotion, LearnError> {
        let seg = self.seg(decl.segment);
        let t = self.segment_times(seg, &decl.name, decl.segment.index())?;
        let demo = self.demo;
        let positions = &demo.position_m[seg.range()];
        let (mut motion, mut quality) = self.fit_motion(decl, &decl.name, seg.range())?;
        if let Some(spec) = decl.strokes {
            // The strokes are what runs: the motion's quality is theirs, the worst of each
            // figure (the whole segment's fit serves only to place the motion's start and end).
            quality.position_rms_m = [0.0; 3];
            quality.orientation_rms_rad = 0.0;
            quality.peak_speed_mps = 0.0;
            quality.demo_peak_speed_mps = 0.0;
            for stroke in find_strokes(&t, positions, spec.min_length_s) {
                let range = seg.start + stroke.start..seg.start + stroke.end;
                let name = format!("{} stroke {}", decl.name, motion.strokes.len() + 1);
                if range.len() < 5 {
                    return Err(LearnError::TooShort {
                        segment: decl.segment.index() + 1,
                        samples: range.len(),
                        name,
                    });
                }
                let (piece, part) = self.fit_motion(decl, &name, range.clone())?;
                self.check_plausible(&name, &part)?;
                quality.strokes_s.push([demo.t_s[range.start], demo.t_s[range.end - 1]]);
                for (whole, part) in quality.position_rms_m.iter_mut().zip(part.position_rms_m) {
                    *whole = whole.max(part);
                }
                quality.orientation_rms_rad = quality.orientation_rms_rad.max(part.orientation_rms_rad);
                quality.peak_speed_mps = quality.peak_speed_mps.max(part.peak_speed_mps);
                quality.demo_peak_speed_mps = quality.demo_peak_speed_mps.max(part.demo_peak_speed_mps);
                motion.strokes.push(piece);
            }
        } else {
            self.check_plausible(&decl.name, &quality)?;
        }
        self.quality.motions.insert(decl.name.clone(), quality);
        Ok(motion)
    }

    /// Fits the position and quaternion DMPs of `decl` to the samples `range` and measures the
    /// fit (reconstruction at the samples' own times, peak speeds).
    fn fit_motion(
        &self,
        decl: &ir::MotionDecl,
        name: &str,
        range: std::ops::Range<usize>,
    ) -> Result<(LearnedMotion, MotionQuality), LearnError> {
        let t = &self.demo.t_s[range.clone()];
        let config = DmpConfig {
            n_basis: decl.basis as usize,
            ..DmpConfig::default()
        };
        let wrap = |source| LearnError::Dmp {
            name: name.to_string(),
            source,
        };
        let positions = &self.demo.position_m[range.clone()];
        let orientations = &self.demo.orientation[range];
        let position = Dmp::fit_points(&config, t, positions).map_err(wrap)?;
        let orientation = QuatDmp::fit(&config, t, orientations).map_err(wrap)?;

        // Reconstruction: roll out at the demonstration's own sample times.
        let mut rollout = position.rollout();
        let mut q_rollout = orientation.rollout();
        let mut sum = [0.0; 3];
        let mut sum_rot = 0.0;
        let mut peak_speed: f64 = 0.0;
        let mut velocity = [0.0; 3];
        for (k, (p, q)) in positions.iter().zip(orientations).enumerate() {
            if k > 0 {
                let dt = t[k] - t[k - 1];
                rollout.step(&position, dt);
                q_rollout.step(&orientation, dt);
            }
            for (axis, slot) in sum.iter_mut().enumerate() {
                *slot += (rollout.position()[axis] - p[axis]).powi(2);
            }
            sum_rot += q_rollout.orientation().angle_to(q).powi(2);
            rollout.velocity_into(&mut velocity);
            peak_speed = peak_speed.max(Vector3::from(velocity).norm());
        }
        let count = positions.len() as f64;
        let quality = MotionQuality {
            position_rms_m: sum.map(|s| (s / count).sqrt()),
            orientation_rms_rad: (sum_rot / count).sqrt(),
            peak_speed_mps: peak_speed,
            demo_peak_speed_mps: peak_speed_of(t, positions),
            strokes_s: Vec::new(),
        };
        let motion = LearnedMotion {
            segment: decl.segment.index(),
            position,
            orientation,
            strokes: Vec::new(),
        };
        Ok((motion, quality))
    }

    /// Warns about, or refuses, a motion whose reconstruction or speed is implausible.
    fn check_plausible(&mut self, name: &str, quality: &MotionQuality) -> Result<(), LearnError> {
        let rms = quality.position_rms_m.iter().map(|v| v * v).sum::<f64>().sqrt();
        let (speed, demo_speed) = (quality.peak_speed_mps, quality.demo_peak_speed_mps);
        let refuse_speed = REFUSE_SPEED_RATIO * demo_speed + SPEED_SLACK_MPS;
        let warn_speed = WARN_SPEED_RATIO * demo_speed + SPEED_SLACK_MPS;
        let mut problems = Vec::new();
        if rms > WARN_RMS_M {
            problems.push(format!("reconstruction error {:.2} mm RMS", rms * 1e3));
        }
        if speed > warn_speed {
            problems.push(format!(
                "peak speed {:.0} mm/s where the demonstration peaks at {:.0} mm/s",
                speed * 1e3,
                demo_speed * 1e3
            ));
        }
        if problems.is_empty() {
            return Ok(());
        }
        let hint = match self.smoothing {
            Smoothing::Off | Smoothing::RateTooLow { .. } => {
                "the demonstration is not smoothed: set `lowpass` in the template or pass --lowpass 20 (or record at 100 Hz or more)"
            }
            _ => {
                "check the demonstration for jumps, lower the low-pass cut-off (e.g. --lowpass 10) or give the motion more basis functions (`basis:`)"
            }
        };
        if rms > REFUSE_RMS_M || speed > refuse_speed {
            return Err(LearnError::Implausible {
                name: name.to_string(),
                reason: format!(
                    "{} (the bounds are {:.0} mm RMS and {REFUSE_SPEED_RATIO} times the demonstrated peak speed)",
                    problems.join(", "),
                    REFUSE_RMS_M * 1e3
                ),
                hint: hint.to_string(),
            });
        }
        self.warnings
            .push(format!("motion `{name}`: {}; {hint}", problems.join(", ")));
        Ok(())
    }
}

/// The peak speed of `positions` sampled at `t` \[m/s\], from central differences of the
/// positions smoothed over 40 ms, so that noise does not count as speed.
fn peak_speed_of(t: &[f64], positions: &[Vector3<f64>]) -> f64 {
    let smoothed = smooth_points(positions, smoothing_window(t));
    (1..smoothed.len().saturating_sub(1))
        .map(|k| (smoothed[k + 1] - smoothed[k - 1]).norm() / (t[k + 1] - t[k - 1]))
        .fold(0.0, f64::max)
}

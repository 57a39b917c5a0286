//! The learning driver: runs a skill's IR learning plan on one demonstration (thesis 4.2.2).
//!
//! Segmentation first, then frames (so forces can be measured along them), motions, forces and
//! thresholds. A demonstration that does not fit the template (no contact in a force skill,
//! another number of segments than the template expects) is an error, not a file.

use nalgebra::{UnitQuaternion, Vector3};
use skill_ir as ir;
use std::collections::BTreeMap;

use super::learned::*;
use crate::demo::{preprocess, Demo, DemoError, FilterOrder, PreprocessConfig};
use crate::dmp::{fit_scalar, Dmp, DmpConfig, DmpError, QuatDmp};
use crate::learn::constraint::{
    fit_constraints, force_aligned_frame_at, force_aligned_frames, ConstraintConfig, ConstraintError, ConstraintKind,
    ForceFrameConfig,
};
use crate::learn::force::{constant_normal_force, ConstantForceConfig, ForceError};
use crate::learn::segment::{
    changepoint_demo, cluster_demo, split_at_force_peak, ChangepointConfig, ClusterConfig, Cut, Linkage, Segment,
    SegmentError, SegmentModel, Temporal, TouchConfig,
};

/// Options of `skillc learn` that override the template.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LearnOptions {
    /// Low-pass cut-off \[Hz\], replacing the template's `lowpass`.
    pub lowpass_hz: Option<f64>,
    /// Resampling rate \[Hz\], replacing the template's `resample`.
    pub resample_hz: Option<f64>,
}

/// Why a skill could not be learned from a demonstration.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LearnError {
    /// Reading or preprocessing the demonstration failed.
    #[error(transparent)]
    Demo(#[from] DemoError),
    /// The segmentation failed.
    #[error("segmentation of `{source_name}` failed")]
    Segment {
        /// The demonstration.
        source_name: String,
        /// Why.
        #[source]
        source: SegmentError,
    },
    /// The segmentation found another number of segments than the template needs.
    #[error("`{method}` found {found} segment(s) in `{source_name}`, the template needs {expected}")]
    SegmentCount {
        /// The method.
        method: &'static str,
        /// The demonstration.
        source_name: String,
        /// What was found.
        found: usize,
        /// What the template declares.
        expected: usize,
    },
    /// A segment is too short for what is learned on it.
    #[error("segment {segment} has {samples} sample(s), too few to learn `{name}`")]
    TooShort {
        /// 1-based segment.
        segment: usize,
        /// Its samples.
        samples: usize,
        /// The feature.
        name: String,
    },
    /// No contact force where the template needs one.
    #[error("no contact in `{source_name}` for `{name}`: the largest force is {peak_n:.2} N")]
    NoContact {
        /// The demonstration.
        source_name: String,
        /// The feature that needs contact.
        name: String,
        /// The largest force magnitude found \[N\].
        peak_n: f64,
    },
    /// Fitting a frame failed.
    #[error("cannot learn frame `{name}`")]
    Frame {
        /// The frame.
        name: String,
        /// Why.
        #[source]
        source: ConstraintError,
    },
    /// Fitting a DMP failed.
    #[error("cannot learn `{name}`")]
    Dmp {
        /// The motion or force.
        name: String,
        /// Why.
        #[source]
        source: DmpError,
    },
    /// Extracting a force failed.
    #[error("cannot learn force `{name}`")]
    Force {
        /// The force.
        name: String,
        /// Why.
        #[source]
        source: ForceError,
    },
}

/// Forces below this are not contact \[N\].
const CONTACT_N: f64 = 1.0;

/// Per-sample frames are stored every this many seconds.
const FRAME_SAMPLE_PERIOD_S: f64 = 0.01;

/// Learns `skill`'s features from `demo` (warnings are the reader's, kept in the file).
pub fn learn_skill(
    skill: &ir::Skill,
    demo: &Demo,
    warnings: &[String],
    options: &LearnOptions,
) -> Result<Learned, LearnError> {
    let plan = &skill.learn;
    let config = PreprocessConfig {
        resample_hz: options.resample_hz.or(plan.resample_hz),
        lowpass_cutoff_hz: options.lowpass_hz.or(plan.lowpass_hz),
        lowpass_order: FilterOrder::default(),
    };
    let demo = preprocess(demo, &config)?;
    let segments = segment(plan, &demo)?;
    let n = demo.len();
    let rate_hz = if demo.duration_s() > 0.0 {
        (n - 1) as f64 / demo.duration_s()
    } else {
        0.0
    };
    let mut learner = Learner {
        demo: &demo,
        segments: &segments,
        frames: Vec::new(),
        quality: Quality::default(),
    };

    let mut frames = BTreeMap::new();
    for decl in &plan.frames {
        let frame = learner.frame(decl)?;
        let segment_start_s = match &decl.source {
            ir::FrameSource::ForceAlignedSamples { segment } => demo.t_s[segments[segment.index()].start],
            _ => 0.0,
        };
        learner.frames.push((frame.clone(), segment_start_s));
        frames.insert(decl.name.clone(), frame);
    }
    let mut motions = BTreeMap::new();
    for decl in &plan.motions {
        motions.insert(decl.name.clone(), learner.motion(decl)?);
    }
    let mut forces = BTreeMap::new();
    for decl in &plan.forces {
        forces.insert(decl.name.clone(), learner.force(decl)?);
    }
    let mut thresholds = BTreeMap::new();
    for decl in &plan.thresholds {
        let value = match &decl.source {
            ir::ThresholdSource::Literal { value } => *value,
            ir::ThresholdSource::ForceAt { point, along, scale } => {
                let index = learner.point(*point);
                let value = learner.applied_along(index, *along);
                learner.require_contact(&decl.name, value)?;
                value * scale
            }
        };
        thresholds.insert(decl.name.clone(), LearnedThreshold { value });
    }

    let segments = segments
        .iter()
        .map(|seg| LearnedSegment {
            start_s: demo.t_s[seg.start],
            end_s: demo.t_s[seg.end - 1],
            start_index: seg.start,
            end_index: seg.end,
        })
        .collect();
    Ok(Learned {
        learned_version: LEARNED_VERSION,
        skill: skill.name.clone(),
        ir_hash: ir_hash(skill),
        demo: DemoInfo {
            source: demo.source.clone(),
            samples: n,
            duration_s: demo.duration_s(),
            rate_hz,
            warnings: warnings.to_vec(),
        },
        segments,
        frames,
        motions,
        forces,
        thresholds,
        quality: learner.quality,
    })
}

/// Cuts the demonstration as the plan says and checks the count.
fn segment(plan: &ir::LearnPlan, demo: &Demo) -> Result<Vec<Segment>, LearnError> {
    let expected = plan.segments as usize;
    let wrap = |source: SegmentError| LearnError::Segment {
        source_name: demo.source.clone(),
        source,
    };
    let rate_hz = if demo.duration_s() > 0.0 {
        (demo.len() - 1) as f64 / demo.duration_s()
    } else {
        1.0
    };
    let (method, segments): (&'static str, Vec<Segment>) = match &plan.segmentation {
        ir::Segmentation::None => (
            "none",
            vec![Segment {
                start: 0,
                end: demo.len(),
            }],
        ),
        ir::Segmentation::MaxForce => {
            let peak = demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max);
            if peak < CONTACT_N {
                return Err(LearnError::NoContact {
                    source_name: demo.source.clone(),
                    name: "segments = max_force".into(),
                    peak_n: peak,
                });
            }
            (
                "max_force",
                split_at_force_peak(&demo.force_n, &TouchConfig::default())
                    .map_err(wrap)?
                    .to_vec(),
            )
        }
        ir::Segmentation::Cluster {
            linkage,
            temporal,
            cut,
            min_length_s,
            features,
        } => {
            let config = ClusterConfig {
                linkage: match linkage {
                    ir::Linkage::Ward => Linkage::Ward,
                    ir::Linkage::Complete => Linkage::Complete,
                    ir::Linkage::Average => Linkage::Average,
                    ir::Linkage::Single => Linkage::Single,
                },
                temporal: match temporal {
                    ir::Temporal::Connectivity { k } => Temporal::Connectivity { k: *k as usize },
                    ir::Temporal::TimeFeature { weight } => Temporal::TimeFeature {
                        weight: *weight,
                        max_blocks: 2000,
                    },
                },
                cut: match cut {
                    ir::Cut::Count(segments) => Cut::Count {
                        segments: *segments as usize,
                    },
                    ir::Cut::Distance(threshold) => Cut::Distance { threshold: *threshold },
                },
                min_segment_samples: (min_length_s * rate_hz).round().max(1.0) as usize,
                features: feature_set(features),
            };
            ("cluster", cluster_demo(demo, &config).map_err(wrap)?)
        }
        ir::Segmentation::Changepoint {
            min_length_s,
            models,
            max_particles,
            features,
        } => {
            let config = ChangepointConfig {
                models: models
                    .iter()
                    .map(|m| match m {
                        ir::SegmentModel::Constant => SegmentModel::Constant,
                        ir::SegmentModel::Linear => SegmentModel::Linear,
                    })
                    .collect(),
                min_length_s: *min_length_s,
                max_particles: *max_particles as usize,
                expected_segments: Some(expected),
                features: feature_set(features),
                ..ChangepointConfig::default()
            };
            let found = changepoint_demo(demo, &config).map_err(wrap)?;
            ("changepoint", found.into_iter().map(|m| m.segment).collect())
        }
    };
    if segments.len() != expected {
        return Err(LearnError::SegmentCount {
            method,
            source_name: demo.source.clone(),
            found: segments.len(),
            expected,
        });
    }
    Ok(segments)
}

fn feature_set(features: &ir::SegmentFeatures) -> crate::learn::segment::FeatureSet {
    crate::learn::segment::FeatureSet {
        position: features.position,
        force: features.force,
        force_magnitude: features.force_magnitude,
    }
}

struct Learner<'a> {
    demo: &'a Demo,
    segments: &'a [Segment],
    /// Frames learned so far, by `FrameId`, with the start time of the segment per-sample
    /// frames are timed from (0 for constant frames).
    frames: Vec<(LearnedFrame, f64)>,
    quality: Quality,
}

impl Learner<'_> {
    fn seg(&self, segment: ir::SegmentIdx) -> Segment {
        self.segments[segment.index()]
    }

    fn point(&self, point: ir::Point) -> usize {
        match point {
            ir::Point::Start(segment) => self.seg(segment).start,
            ir::Point::End(segment) => self.seg(segment).end - 1,
            ir::Point::PeakForce => {
                self.demo
                    .force_n
                    .iter()
                    .enumerate()
                    .fold((0, f64::NEG_INFINITY), |best, (k, f)| {
                        if f.norm() > best.1 {
                            (k, f.norm())
                        } else {
                            best
                        }
                    })
                    .0
            }
        }
    }

    fn peak_n(&self) -> f64 {
        self.demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max)
    }

    fn require_contact(&self, name: &str, value: f64) -> Result<(), LearnError> {
        if value.abs() < CONTACT_N {
            return Err(LearnError::NoContact {
                source_name: self.demo.source.clone(),
                name: name.to_string(),
                peak_n: self.peak_n(),
            });
        }
        Ok(())
    }

    /// The unit axis of a frame at demonstration sample `index`.
    fn axis_at(&self, index: usize, along: ir::FrameAxis) -> Vector3<f64> {
        let unit = match along.axis {
            ir::Axis::X | ir::Axis::Rx => Vector3::x(),
            ir::Axis::Y | ir::Axis::Ry => Vector3::y(),
            ir::Axis::Z | ir::Axis::Rz => Vector3::z(),
        };
        let rotation = match along.frame {
            ir::FrameRef::Base => UnitQuaternion::identity(),
            ir::FrameRef::Tool => self.demo.orientation[index],
            ir::FrameRef::Learned(id) => {
                let (frame, segment_start_s) = &self.frames[id.index()];
                // Per-sample frames are timed from their segment's start; outside it the ends hold.
                frame.at(self.demo.t_s[index] - segment_start_s).rotation
            }
        };
        rotation * unit
    }

    /// The applied force (robot on environment) along a frame axis at sample `index` \[N\].
    fn applied_along(&self, index: usize, along: ir::FrameAxis) -> f64 {
        -self.demo.force_n[index].dot(&self.axis_at(index, along))
    }

    fn frame(&mut self, decl: &ir::FrameDecl) -> Result<LearnedFrame, LearnError> {
        let demo = self.demo;
        let wrap = |source| LearnError::Frame {
            name: decl.name.clone(),
            source,
        };
        Ok(match &decl.source {
            ir::FrameSource::Constraint { segment, candidates } => {
                let range = self.seg(*segment).range();
                let config = ConstraintConfig {
                    candidates: candidates.iter().map(|c| constraint_kind(*c)).collect(),
                    ..ConstraintConfig::default()
                };
                let report = fit_constraints(
                    &demo.position_m[range.clone()],
                    &demo.orientation[range.clone()],
                    &demo.force_n[range],
                    &config,
                )
                .map_err(wrap)?;
                let chosen = report.chosen();
                self.quality.constraints.insert(
                    decl.name.clone(),
                    report
                        .fits
                        .iter()
                        .enumerate()
                        .map(|(index, fit)| ConstraintQuality {
                            kind: kind_name(fit.kind).to_string(),
                            residual_m: fit.residual_m,
                            residual_rad: fit.residual_rad,
                            force_agreement: fit.force_agreement,
                            chosen: index == report.best,
                        })
                        .collect(),
                );
                let pose = nalgebra::Isometry3::from_parts(chosen.frame.origin_m.into(), chosen.frame.orientation);
                LearnedFrame::Constant(FramePose::from_isometry(kind_name(chosen.kind), &pose, None))
            }
            ir::FrameSource::ForceAlignedSamples { segment } => {
                let seg = self.seg(*segment);
                let range = seg.range();
                let normal_force = without_friction(
                    &demo.t_s[range.clone()],
                    &demo.position_m[range.clone()],
                    &demo.force_n[range.clone()],
                );
                let frames = force_aligned_frames(&normal_force, &demo.position_m[range], &ForceFrameConfig::default())
                    .map_err(wrap)?;
                let t0 = demo.t_s[seg.start];
                let mut poses = Vec::new();
                let mut next_t = 0.0;
                for (offset, frame) in frames.iter().enumerate() {
                    let t = demo.t_s[seg.start + offset] - t0;
                    if t + 1e-9 >= next_t || offset + 1 == frames.len() {
                        let pose = nalgebra::Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                        poses.push(FramePose::from_isometry("force_aligned", &pose, Some(t)));
                        next_t = t + FRAME_SAMPLE_PERIOD_S;
                    }
                }
                LearnedFrame::Samples(poses)
            }
            ir::FrameSource::ForceAlignedAt { point } => {
                let index = self.point(*point);
                let frame =
                    force_aligned_frame_at(&demo.force_n, &demo.position_m, index, &ForceFrameConfig::default())
                        .map_err(wrap)?;
                let pose = nalgebra::Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                LearnedFrame::Constant(FramePose::from_isometry("force_aligned", &pose, None))
            }
            ir::FrameSource::Fixed {
                origin_m,
                quaternion_wxyz,
            } => LearnedFrame::Constant(FramePose {
                kind: "fixed".into(),
                origin: *origin_m,
                quaternion_wxyz: *quaternion_wxyz,
                t_s: None,
            }),
        })
    }

    fn segment_times(&self, seg: Segment, name: &str, segment: usize) -> Result<Vec<f64>, LearnError> {
        if seg.len() < 5 {
            return Err(LearnError::TooShort {
                segment: segment + 1,
                samples: seg.len(),
                name: name.to_string(),
            });
        }
        Ok(self.demo.t_s[seg.range()].to_vec())
    }

    fn motion(&mut self, decl: &ir::MotionDecl) -> Result<LearnedMotion, LearnError> {
        let seg = self.seg(decl.segment);
        let t = self.segment_times(seg, &decl.name, decl.segment.index())?;
        let config = DmpConfig {
            n_basis: decl.basis as usize,
            ..DmpConfig::default()
        };
        let wrap = |source| LearnError::Dmp {
            name: decl.name.clone(),
            source,
        };
        let positions = &self.demo.position_m[seg.range()];
        let orientations = &self.demo.orientation[seg.range()];
        let position = Dmp::fit_points(&config, &t, positions).map_err(wrap)?;
        let orientation = QuatDmp::fit(&config, &t, orientations).map_err(wrap)?;

        // Reconstruction: roll out at the demonstration's own sample times.
        let mut rollout = position.rollout();
        let mut q_rollout = orientation.rollout();
        let mut sum = [0.0; 3];
        let mut sum_rot = 0.0;
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
        }
        let count = positions.len() as f64;
        self.quality.motions.insert(
            decl.name.clone(),
            MotionQuality {
                position_rms_m: sum.map(|s| (s / count).sqrt()),
                orientation_rms_rad: (sum_rot / count).sqrt(),
            },
        );
        Ok(LearnedMotion {
            segment: decl.segment.index(),
            position,
            orientation,
        })
    }

    fn force(&mut self, decl: &ir::ForceDecl) -> Result<LearnedForce, LearnError> {
        let wrap = |source| LearnError::Force {
            name: decl.name.clone(),
            source,
        };
        Ok(match &decl.source {
            ir::ForceSource::Literal { value_n } => LearnedForce::Literal { value_n: *value_n },
            ir::ForceSource::Tracked => LearnedForce::Tracked { value_n: 0.0 },
            ir::ForceSource::At { point, along } => {
                let index = self.point(*point);
                let value_n = self.applied_along(index, *along);
                self.require_contact(&decl.name, value_n)?;
                LearnedForce::At { value_n }
            }
            ir::ForceSource::Constant { segment, along } => {
                let seg = self.seg(*segment);
                let t = self.segment_times(seg, &decl.name, segment.index())?;
                let profile: Vec<f64> = seg.range().map(|k| self.applied_along(k, *along)).collect();
                let config = ConstantForceConfig {
                    contact_threshold_n: CONTACT_N,
                    ..ConstantForceConfig::default()
                };
                let found = constant_normal_force(&t, &profile, &config).map_err(|err| match err {
                    ForceError::NoContact { peak_n, .. } => LearnError::NoContact {
                        source_name: self.demo.source.clone(),
                        name: decl.name.clone(),
                        peak_n,
                    },
                    other => wrap(other),
                })?;
                LearnedForce::Constant {
                    value_n: found.value_n,
                    std_n: found.std_n,
                    region_s: match (found.regions.first(), found.regions.last()) {
                        (Some(first), Some(last)) => [t[first.start], t[last.end - 1]],
                        _ => [t[0], t[t.len() - 1]],
                    },
                }
            }
            ir::ForceSource::Dmp { segment, basis } => {
                let seg = self.seg(*segment);
                let t = self.segment_times(seg, &decl.name, segment.index())?;
                let raw: Vec<Vector3<f64>> = self.demo.force_n[seg.range()].iter().map(|f| -f).collect();
                let applied = smooth_points(&raw, smoothing_window(&t));
                let peak = applied.iter().map(|f| f.norm()).fold(0.0, f64::max);
                self.require_contact(&decl.name, peak)?;
                let config = force_dmp_config(*basis);
                let dmp = Dmp::fit_points(&config, &t, &applied).map_err(|source| LearnError::Dmp {
                    name: decl.name.clone(),
                    source,
                })?;
                let rms = force_rms(&dmp, &t, |k, channel| raw[k][channel]);
                self.quality.forces_rms_n.insert(decl.name.clone(), rms);
                LearnedForce::Dmp { dmp }
            }
            ir::ForceSource::Magnitude { segment, along, basis } => {
                let seg = self.seg(*segment);
                let t = self.segment_times(seg, &decl.name, segment.index())?;
                let raw: Vec<f64> = seg.range().map(|k| self.applied_along(k, *along)).collect();
                let profile = smooth(&raw, smoothing_window(&t));
                let peak = profile.iter().copied().fold(0.0, f64::max);
                self.require_contact(&decl.name, peak)?;
                let config = force_dmp_config(*basis);
                let dmp = fit_scalar(&config, &t, &profile).map_err(|source| LearnError::Dmp {
                    name: decl.name.clone(),
                    source,
                })?;
                let rms = force_rms(&dmp, &t, |k, _| raw[k]);
                self.quality.forces_rms_n.insert(decl.name.clone(), rms);
                LearnedForce::Magnitude { dmp }
            }
        })
    }
}

/// The measured forces without their component along the direction of motion.
///
/// While sliding, friction tilts the contact force against the motion by up to atan(µ) (17° at
/// µ = 0.3); a frame aligned with the raw force would put its z 17° off the surface normal, and
/// position control along its x would then push into and pull off the surface. Friction acts
/// along the sliding direction, so removing the force component along the (smoothed) velocity
/// leaves the normal force. Where the tool hardly moves (below 5 mm/s) the force is kept as is.
fn without_friction(t: &[f64], position: &[Vector3<f64>], force: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let n = position.len();
    let window = smoothing_window(t);
    let smoothed = smooth_points(position, window);
    (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            let dt = t[b] - t[a];
            let velocity = if dt > 0.0 {
                (smoothed[b] - smoothed[a]) / dt
            } else {
                Vector3::zeros()
            };
            let speed = velocity.norm();
            if speed < 0.005 {
                force[k]
            } else {
                let along = velocity / speed;
                force[k] - along * force[k].dot(&along)
            }
        })
        .collect()
}

/// Force profiles are smoothed over this window before a DMP is fitted to them: fitting
/// differentiates twice, and white sensor noise differentiated twice swamps the forcing term.
const FORCE_SMOOTHING_S: f64 = 0.04;

/// The moving-average window for samples at times `t` (odd, at least 1).
fn smoothing_window(t: &[f64]) -> usize {
    let duration = t.last().copied().unwrap_or(0.0) - t.first().copied().unwrap_or(0.0);
    let rate = if duration > 0.0 {
        (t.len() - 1) as f64 / duration
    } else {
        1.0
    };
    ((FORCE_SMOOTHING_S * rate).round() as usize) | 1
}

/// Two passes of a centred moving average of `window` samples (a triangular kernel); the
/// window shrinks at the ends so the ends are not pulled towards zero.
fn smooth(values: &[f64], window: usize) -> Vec<f64> {
    let pass = |input: &[f64]| -> Vec<f64> {
        let n = input.len();
        let half = window / 2;
        let mut prefix = Vec::with_capacity(n + 1);
        prefix.push(0.0);
        for v in input {
            prefix.push(prefix[prefix.len() - 1] + v);
        }
        (0..n)
            .map(|k| {
                let reach = half.min(k).min(n - 1 - k);
                let (a, b) = (k - reach, k + reach + 1);
                (prefix[b] - prefix[a]) / (b - a) as f64
            })
            .collect()
    };
    pass(&pass(values))
}

fn smooth_points(points: &[Vector3<f64>], window: usize) -> Vec<Vector3<f64>> {
    let channels: Vec<Vec<f64>> = (0..3)
        .map(|c| smooth(&points.iter().map(|p| p[c]).collect::<Vec<_>>(), window))
        .collect();
    (0..points.len())
        .map(|k| Vector3::new(channels[0][k], channels[1][k], channels[2][k]))
        .collect()
}

/// Force DMPs use the default (ridge) regression, which reproduces better than LWR.
fn force_dmp_config(basis: u32) -> DmpConfig {
    DmpConfig {
        n_basis: basis as usize,
        ..DmpConfig::default()
    }
}

/// RMS error of a force DMP's rollout at the demonstration's sample times \[N\].
fn force_rms(dmp: &Dmp, t: &[f64], demo: impl Fn(usize, usize) -> f64) -> f64 {
    let mut rollout = dmp.rollout();
    let mut sum = 0.0;
    let mut count = 0.0f64;
    for k in 0..t.len() {
        if k > 0 {
            rollout.step(dmp, t[k] - t[k - 1]);
        }
        let error: f64 = (0..dmp.n_dims())
            .map(|c| (rollout.position()[c] - demo(k, c)).powi(2))
            .sum();
        sum += error;
        count += 1.0;
    }
    (sum / count.max(1.0)).sqrt()
}

fn constraint_kind(model: ir::ConstraintModel) -> ConstraintKind {
    match model {
        ir::ConstraintModel::FixedPoint => ConstraintKind::FixedPoint,
        ir::ConstraintModel::PointOnPlane => ConstraintKind::PointOnPlane,
        ir::ConstraintModel::Planar => ConstraintKind::Planar,
        ir::ConstraintModel::ConcentricCylinder => ConstraintKind::ConcentricCylinder,
        ir::ConstraintModel::Prismatic => ConstraintKind::Prismatic,
        ir::ConstraintModel::AxialRotation => ConstraintKind::AxialRotation,
    }
}

/// The source-language name of a constraint model.
pub fn kind_name(kind: ConstraintKind) -> &'static str {
    match kind {
        ConstraintKind::FixedPoint => "fixed_point",
        ConstraintKind::PointOnPlane => "point_on_plane",
        ConstraintKind::Planar => "planar",
        ConstraintKind::ConcentricCylinder => "cylinder",
        ConstraintKind::Prismatic => "prismatic",
        ConstraintKind::AxialRotation => "axial_rotation",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothing_keeps_lines_and_removes_alternating_noise() {
        let line: Vec<f64> = (0..100).map(|k| 0.5 * k as f64).collect();
        let smoothed = smooth(&line, 9);
        for (a, b) in line.iter().zip(&smoothed) {
            assert!((a - b).abs() < 1e-9, "a line is kept exactly, ends included");
        }
        let noisy: Vec<f64> = (0..100).map(|k| if k % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let smoothed = smooth(&noisy, 9);
        assert!(smoothed[10..90].iter().all(|v| v.abs() < 0.05));
    }

    #[test]
    fn a_force_profile_that_starts_rising_is_reproduced() {
        // Touch-down: the force is already rising fast when the segment starts. A DMP that
        // starts at rest cannot follow (5 N RMS on this profile); one that starts with the
        // demonstrated velocity does.
        let t: Vec<f64> = (0..2320).map(|k| k as f64 * 0.001).collect();
        let mut rng = crate::rng::SplitMix64::new(1);
        let raw: Vec<f64> = t
            .iter()
            .map(|&t| 10.0 * (1.0 - (-t / 0.05).exp()) + 0.15 * rng.normal())
            .collect();
        let profile = smooth(&raw, smoothing_window(&t));
        let dmp = fit_scalar(&force_dmp_config(40), &t, &profile).expect("fits");
        let rms = force_rms(&dmp, &t, |k, _| raw[k]);
        assert!(rms < 0.5, "RMS {rms} N (5 % of the 10 N plateau)");
    }
}

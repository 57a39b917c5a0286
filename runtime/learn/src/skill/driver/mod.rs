//! The learning driver: runs a skill's IR learning plan on one demonstration (thesis 4.2.2).
//!
//! Segmentation first ([`crate::segment::segment_demo`], configured through
//! [`crate::ir_seam`]), its planar contacts' boundaries checked against the geometry
//! (`contact`), then frames (so forces can be measured along them), motions,
//! forces and thresholds. A demonstration that does not fit the template (no contact in a force
//! skill, another number of segments than the template expects) is an error, not a file.
//!
//! One file per job: `contact`, `frames`, `motions`, `forces` (with thresholds), the `smoothing` they
//! share, and the `error` type; this file holds the driver and the sample lookups all of them use.

mod contact;
mod error;
mod forces;
mod frames;
mod motions;
mod phases;
mod smoothing;

pub use self::error::LearnError;
pub use self::frames::DEFAULT_FRICTION_MU;

use nalgebra::{UnitQuaternion, Vector3};
use skill_ir as ir;
use std::collections::BTreeMap;

use super::learned::{ir_hash, DemoInfo, Learned, LearnedFrame, LearnedSegment, Quality, LEARNED_VERSION};
use crate::demo::{prepare, Demo, FilterOrder, PreprocessConfig, Smoothing, WrenchDeclaration, WrenchOptions};
use crate::segment::{segment_demo, Segment, SegmentError, Segmentation};

/// Options of `skillc learn` that override the template.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LearnOptions {
    /// Low-pass cut-off \[Hz\], replacing the template's `lowpass`; 0 switches off all
    /// smoothing, the default motion low-pass included (docs/method.md §1).
    pub lowpass_hz: Option<f64>,
    /// Resampling rate \[Hz\], replacing the template's `resample`.
    pub resample_hz: Option<f64>,
    /// The wrench's frame and sign, when known; what is not declared is detected
    /// (docs/method.md §1).
    pub wrench: WrenchDeclaration,
    /// Leave the sensor bias in instead of removing the mean of a still, contact-free period.
    pub keep_bias: bool,
    /// The friction coefficient µ that bounds how far the contact force may lean from a fitted
    /// plane's normal, `atan µ` (docs/method.md §4); [`DEFAULT_FRICTION_MU`] when `None`.
    pub friction_mu: Option<f64>,
    /// The contact phase to learn from (1-based, `--phase N`), when the demonstration has several
    /// (docs/method.md §3); `None`: all of it, or the longest phase when a segment would span
    /// several.
    pub phase: Option<usize>,
}

/// Forces below this are not contact \[N\].
const CONTACT_N: f64 = 1.0;

/// Learns `skill`'s features from `demo` (warnings are the reader's, kept in the file with the
/// ones preparing the demonstration and learning raise).
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
    let wrench = WrenchOptions {
        declared: options.wrench,
        keep_bias: options.keep_bias,
    };
    let prepared = prepare(demo, &config, &wrench)?;
    let mut warnings = warnings.to_vec();
    warnings.extend(prepared.warnings.iter().map(ToString::to_string));
    let chosen = phases::choose(plan, prepared.demo, options.phase, |demo| segment(plan, demo))?;
    let demo = chosen.demo;
    let mut segments = chosen.segments;
    let mut phase_report = chosen.report;
    warnings.extend(chosen.warning);
    let contacts = contact::refine_planar_contacts(plan, &demo, &mut segments, prepared.position_noise_m);
    phase_report.moved = phases::move_to_onsets(plan, &demo, &mut segments, &chosen.phases);
    let n = demo.len();
    let rate_hz = if demo.duration_s() > 0.0 {
        (n - 1) as f64 / demo.duration_s()
    } else {
        0.0
    };
    let mut learner = Learner {
        demo: &demo,
        segments: &segments,
        phases: &chosen.phases,
        frames: Vec::new(),
        quality: Quality {
            position_noise_m: prepared.position_noise_m,
            smoothing: prepared.smoothing.to_string(),
            wrench: Some(prepared.wrench.clone()),
            contacts,
            phases: Some(phase_report),
            ..Quality::default()
        },
        smoothing: prepared.smoothing,
        friction_mu: options.friction_mu.unwrap_or(DEFAULT_FRICTION_MU),
        warnings: Vec::new(),
    };

    let mut frames = BTreeMap::new();
    for decl in &plan.frames {
        let frame = learner.frame(decl)?;
        let segment_start_s = match &decl.source {
            ir::FrameSource::ForceAlignedSamples { segment } | ir::FrameSource::Constraint { segment, .. } => {
                demo.t_s[segments[segment.index()].start]
            }
            _ => 0.0,
        };
        learner.frames.push((frame.clone(), segment_start_s));
        frames.insert(decl.name.clone(), frame);
    }
    // The motions and the forces need only the segments and frames: the forces are learned
    // beside the motions, by a fork whose quality and warnings come back after the motions'.
    let (motions, forces) = std::thread::scope(|scope| {
        let mut fork = learner.fork();
        let forces = scope.spawn(move || {
            let forces: Result<BTreeMap<_, _>, LearnError> = plan
                .forces
                .iter()
                .map(|decl| Ok((decl.name.clone(), fork.force(decl)?)))
                .collect();
            forces.map(|forces| (forces, fork))
        });
        let motions: Result<BTreeMap<_, _>, LearnError> = plan
            .motions
            .iter()
            .map(|decl| Ok((decl.name.clone(), learner.motion(decl)?)))
            .collect();
        let forces = forces.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (motions, forces)
    });
    // A motion's error comes first, as when they were learned one after the other.
    let motions = motions?;
    let (forces, fork) = forces?;
    learner.absorb(fork);
    let mut thresholds = BTreeMap::new();
    for decl in &plan.thresholds {
        thresholds.insert(decl.name.clone(), learner.threshold(decl)?);
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
            warnings: warnings.into_iter().chain(learner.warnings).collect(),
        },
        segments,
        frames,
        motions,
        forces,
        thresholds,
        quality: learner.quality,
    })
}

/// An error and its sources on one line.
fn error_text(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(inner) = source {
        text.push_str(": ");
        text.push_str(&inner.to_string());
        source = inner.source();
    }
    text
}

/// Cuts the demonstration as the plan says and checks the count against the template.
fn segment(plan: &ir::LearnPlan, demo: &Demo) -> Result<Vec<Segment>, LearnError> {
    let rate_hz = if demo.duration_s() > 0.0 {
        (demo.len() - 1) as f64 / demo.duration_s()
    } else {
        1.0
    };
    let segmentation = Segmentation::from_plan(plan, rate_hz);
    if let Segmentation::MaxForce(_) = segmentation {
        // The template needs contact: say so in its terms before the split looks for a peak.
        let peak = demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max);
        if peak < CONTACT_N {
            return Err(LearnError::NoContact {
                source_name: demo.source.clone(),
                name: "segments = max_force".into(),
                peak_n: peak,
            });
        }
    }
    segment_demo(demo, &segmentation, Some(plan.segments as usize)).map_err(|source| match source {
        SegmentError::WrongCount { found, expected } => LearnError::SegmentCount {
            method: segmentation.method(),
            source_name: demo.source.clone(),
            found,
            expected,
        },
        source => LearnError::Segment {
            source_name: demo.source.clone(),
            source,
        },
    })
}

/// The state of one run of a plan: the demonstration, its segments and what is learned so far.
struct Learner<'a> {
    demo: &'a Demo,
    segments: &'a [Segment],
    /// The contact phases of `demo`.
    phases: &'a [crate::phases::ContactPhase],
    /// Frames learned so far, by `FrameId`, with the start time of the segment per-sample
    /// frames are timed from (0 for constant frames).
    frames: Vec<(LearnedFrame, f64)>,
    quality: Quality,
    /// How the demonstration was smoothed (the plausibility checks' advice depends on it).
    smoothing: Smoothing,
    /// The friction coefficient of the normal check (docs/method.md §4).
    friction_mu: f64,
    /// Warnings raised while learning.
    warnings: Vec<String>,
}

impl<'a> Learner<'a> {
    /// A learner for work beside this one: the same demonstration, segments and frames, with a
    /// quality and warnings of its own that [`Learner::absorb`] brings back. A fork learns
    /// motions and forces, whose figures are the only quality it keeps.
    fn fork(&self) -> Learner<'a> {
        Learner {
            demo: self.demo,
            segments: self.segments,
            phases: self.phases,
            frames: self.frames.clone(),
            quality: Quality::default(),
            smoothing: self.smoothing,
            friction_mu: self.friction_mu,
            warnings: Vec::new(),
        }
    }

    /// Takes in what `fork` learned after what this learner has.
    fn absorb(&mut self, mut fork: Learner<'_>) {
        self.quality.motions.append(&mut fork.quality.motions);
        self.quality.forces_rms_n.append(&mut fork.quality.forces_rms_n);
        debug_assert_eq!(
            fork.quality,
            Quality::default(),
            "a fork's quality is its motions' and forces' figures"
        );
        self.warnings.append(&mut fork.warnings);
    }
}

impl Learner<'_> {
    fn seg(&self, segment: ir::SegmentIdx) -> Segment {
        self.segments[segment.index()]
    }

    fn point(&self, point: ir::Point) -> usize {
        match point {
            ir::Point::Start(segment) => self.seg(segment).start,
            ir::Point::End(segment) => self.seg(segment).end - 1,
            ir::Point::PeakForce => self.peak_sample(0, self.demo.force_n.len()),
            ir::Point::PeakForceIn(segment) => {
                let segment = self.seg(segment);
                self.peak_sample(segment.start, segment.end)
            }
        }
    }

    /// The sample of largest force magnitude in `start..end` (the first of equals; `start` when
    /// the range is empty).
    fn peak_sample(&self, start: usize, end: usize) -> usize {
        let end = end.min(self.demo.force_n.len());
        (start..end)
            .fold((start, f64::NEG_INFINITY), |best, k| {
                let norm = self.demo.force_n[k].norm();
                if norm > best.1 {
                    (k, norm)
                } else {
                    best
                }
            })
            .0
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
}

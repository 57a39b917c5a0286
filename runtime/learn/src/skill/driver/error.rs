//! Why a skill could not be learned from a demonstration: the driver's one error type.

use crate::constraint::ConstraintError;
use crate::demo::DemoError;
use crate::dmp::DmpError;
use crate::force::ForceError;
use crate::segment::SegmentError;

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
    /// `--phase N` (or a task step's `phase: N`) names a contact phase the demonstration does not have.
    #[error("no contact phase {phase} to learn from (`--phase {phase}`, a step's `phase: {phase}`): `{source_name}` has {count} contact phase(s){list}")]
    NoSuchPhase {
        /// The demonstration.
        source_name: String,
        /// The phase asked for (1-based).
        phase: usize,
        /// How many there are.
        count: usize,
        /// `: 4.10-13.20 s, ...` (empty without phases).
        list: String,
    },
    /// A segment would hold several contact phases and no single phase could be learned instead.
    #[error(
        "segment {segment} of `{source_name}` would span {count} contact phases ({list}); \
         learning phase {longest}, the longest, alone failed too: {reason}; choose one with --phase N"
    )]
    PhasesMixed {
        /// The demonstration.
        source_name: String,
        /// The segment that spans them (1-based).
        segment: usize,
        /// How many phases there are.
        count: usize,
        /// The phases.
        list: String,
        /// The longest (1-based).
        longest: usize,
        /// Why learning it alone failed.
        reason: String,
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
    /// A segment too short for `constant(...)` to find a steady force in (a tap).
    #[error(
        "segment {segment} lasts {:.0} ms ({samples} samples), too short for `{name} = constant(segment {segment}, ...)`: \
         it looks for a steady force over at least half the segment and needs a segment of {:.0} ms and {required_samples} samples or more; \
         learn the force at one point instead, `force {name} = force_at(end(segment {segment}), along: ...)`",
        duration_s * 1e3,
        required_s * 1e3
    )]
    TooShortForConstant {
        /// 1-based segment.
        segment: usize,
        /// Its samples.
        samples: usize,
        /// Its duration \[s\].
        duration_s: f64,
        /// The shortest segment `constant(...)` learns from \[s\].
        required_s: f64,
        /// The fewest samples `constant(...)` learns from.
        required_samples: usize,
        /// The force.
        name: String,
    },
    /// A constant force far from what the demonstration pressed with: outside 0.5-2 times the
    /// median of the segment's contact samples.
    #[error(
        "`{name}` learned {learned_n:.2} N from a steady stretch of {from_s:.2}-{to_s:.2} s, but the demonstration \
         pressed with a median of {median_n:.2} N over its contact in that segment: the steady stretch is not the \
         contact (check the contact phases `skillc identify` finds, or pick one with `--phase N`)"
    )]
    ForceOffRecording {
        /// The force.
        name: String,
        /// What was learned \[N\].
        learned_n: f64,
        /// The median of the segment's contact samples \[N\].
        median_n: f64,
        /// The steady stretch it was learned from \[s\].
        from_s: f64,
        /// Its end \[s\].
        to_s: f64,
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
    /// A learned motion does not describe its demonstration: its reconstruction error or its
    /// speed is beyond the hard bounds of docs/method.md §2.
    #[error("refusing to learn motion `{name}`: {reason}; {hint}")]
    Implausible {
        /// The motion.
        name: String,
        /// What is wrong, with the figures.
        reason: String,
        /// What to try.
        hint: String,
    },
}

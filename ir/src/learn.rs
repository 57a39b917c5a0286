//! The learning plan: the frames, motions, forces and thresholds a skill learns from its
//! demonstration, and the points of the demonstration they are taken at.

use crate::{FrameAxis, SegmentIdx, Segmentation, SourceSpan};
use serde::{Deserialize, Serialize};

/// The learning plan: how to segment the demonstration and which features to extract.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnPlan {
    /// How to cut the demonstration into segments.
    pub segmentation: Segmentation,
    /// The number of segments the skill needs; learning fails when it finds another count.
    pub segments: u32,
    /// Low-pass cut-off applied to the demonstration before learning \[Hz\], if any.
    pub lowpass_hz: Option<f64>,
    /// Resampling rate applied before learning \[Hz\], if any.
    pub resample_hz: Option<f64>,
    /// Compliant frames to learn.
    pub frames: Vec<FrameDecl>,
    /// Motions (position + orientation DMPs) to learn.
    pub motions: Vec<MotionDecl>,
    /// Desired forces to learn.
    pub forces: Vec<ForceDecl>,
    /// Scalar thresholds to learn.
    pub thresholds: Vec<ThresholdDecl>,
}

/// A named compliant frame to learn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameDecl {
    /// Its name.
    pub name: String,
    /// How it is obtained.
    pub source: FrameSource,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// The six geometric constraint models (Subramani et al. 2018). What each leaves free and the
/// frame it gives are those of the runtime's fit (`skill_runtime::learn::constraint`,
/// docs/method.md §4); "into the surface" is along the mean applied force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstraintModel {
    /// A point of the tool stays at one point and the tool rotates freely (a ball joint);
    /// origin at the point, z along the mean applied force.
    FixedPoint,
    /// A point of the tool moves on a plane and the tool rotates freely; z is the plane's
    /// normal, into the surface.
    PointOnPlane,
    /// The tool slides on a plane and rotates only about its normal; z is the normal, into the
    /// surface, x the main direction of motion.
    Planar,
    /// The tool translates along an axis and rotates about it (a peg in a hole; `cylinder` in
    /// source); z along the axis in the direction of travel, x from the axis towards the tool.
    ConcentricCylinder,
    /// The tool translates along a line without rotating (a drawer); x along the line in the
    /// direction of travel, z along the applied force made perpendicular to the line.
    Prismatic,
    /// The tool rotates about a fixed axis (a hinge); z along the axis, x from the axis
    /// towards the tool.
    AxialRotation,
}

/// A point in the demonstration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "at", content = "segment", rename_all = "snake_case")]
pub enum Point {
    /// The first sample of a segment.
    Start(SegmentIdx),
    /// The last sample of a segment (for `max_force`, the end of segment 0 is the force peak).
    End(SegmentIdx),
    /// The sample of largest force magnitude.
    PeakForce,
    /// The sample of largest force magnitude within a segment (`peak_force(segment N)`).
    PeakForceIn(SegmentIdx),
}

/// How a frame is obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrameSource {
    /// Fit constraint models on a segment and keep the best scoring of `candidates`.
    Constraint {
        /// The segment fitted.
        segment: SegmentIdx,
        /// The models tried; one model means that model is imposed.
        candidates: Vec<ConstraintModel>,
    },
    /// z along the applied force at every sample of a segment (a moving frame).
    ForceAlignedSamples {
        /// The segment.
        segment: SegmentIdx,
    },
    /// z along the applied force at one point; origin at the tool position there.
    ForceAlignedAt {
        /// The point.
        point: Point,
    },
    /// A literal frame in the robot base frame.
    Fixed {
        /// Origin \[m\], base frame.
        origin_m: [f64; 3],
        /// Orientation as a unit quaternion `[w, x, y, z]`, base frame.
        quaternion_wxyz: [f64; 4],
    },
}

/// A named motion: a position DMP and a quaternion DMP of one segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotionDecl {
    /// Its name.
    pub name: String,
    /// The segment learned.
    pub segment: SegmentIdx,
    /// Gaussian basis functions per channel.
    pub basis: u32,
    /// `strokes(...)`: the segment is also cut into strokes at the reversals of its motion, and
    /// each stroke learned as a motion of its own (a wipe's back-and-forth, a circle's halves).
    /// Left out of the JSON when the motion is a plain `dmp`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strokes: Option<Strokes>,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// How a motion's segment is cut into strokes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Strokes {
    /// A stroke shorter than this is merged into its neighbour \[s\].
    pub min_length_s: f64,
}

/// A named desired force.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForceDecl {
    /// Its name.
    pub name: String,
    /// How it is obtained.
    pub source: ForceSource,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// How a desired force is obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ForceSource {
    /// Constant: the mean applied force along `along` over the lowest-variance in-contact
    /// region of a segment (thesis 4.2.2, slide).
    Constant {
        /// The segment.
        segment: SegmentIdx,
        /// The direction measured.
        along: FrameAxis,
    },
    /// The applied force along `along` at one point (touch).
    At {
        /// The point.
        point: Point,
        /// The direction measured.
        along: FrameAxis,
    },
    /// DMPs of the applied force vector of a segment, in the base frame (press).
    Dmp {
        /// The segment.
        segment: SegmentIdx,
        /// Basis functions per channel.
        basis: u32,
    },
    /// The magnitude of the applied force along a (usually moving) frame's axis over a
    /// segment, learned as a 1-D DMP (contour).
    Magnitude {
        /// The segment.
        segment: SegmentIdx,
        /// The direction measured.
        along: FrameAxis,
        /// Basis functions.
        basis: u32,
    },
    /// A literal force \[N\] along the z axis of the state's control frame.
    Literal {
        /// The force \[N\].
        value_n: f64,
    },
    /// No desired force: force-controlled axes regulate to zero (pure compliance) and the
    /// force is only watched by guards.
    Tracked,
}

/// A named scalar threshold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThresholdDecl {
    /// Its name.
    pub name: String,
    /// How it is obtained.
    pub source: ThresholdSource,
    /// Where it is declared.
    pub span: SourceSpan,
}

/// How a threshold is obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ThresholdSource {
    /// `scale` times the applied force along `along` at `point` \[N\].
    ForceAt {
        /// The point.
        point: Point,
        /// The direction measured.
        along: FrameAxis,
        /// Multiplier on the learned value.
        scale: f64,
    },
    /// A literal value \[N or Nm\].
    Literal {
        /// The value in SI units.
        value: f64,
    },
}

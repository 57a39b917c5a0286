//! The learned-file format written by `skillc learn`: versioned JSON tied to the IR it was learned
//! for by a hash, holding everything the runtime needs plus quality figures.
//!
//! Top-level keys other tools rely on: `segments` (`{start_s, end_s}`), `frames` (name → a
//! constant frame `{kind, origin, quaternion_wxyz}` or, per sample, the list of those; `kind` is
//! a [`FrameKind`]), `forces`
//! (name → `{kind, value_n}` for constants, a DMP otherwise), `quality`.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;

use crate::constraint::ConstraintKind;
use crate::dmp::{Dmp, QuatDmp};

/// The learned-file format version; bump on every change to the serialized form.
pub const LEARNED_VERSION: u32 = 1;

/// A 64-bit FNV-1a hash of what a skill learns (its name and its learning plan, as canonical
/// JSON without spans and docs), in hex: a learned file is only used with the plan it was
/// learned by. The states, transitions, limits and parameters are left out: they decide how the
/// learned features run, not what they are, and binding checks by name that every feature a
/// state uses is in the file; so a state, a limit or a parameter (`--param`, a task step's
/// value) may change without learning again.
pub fn ir_hash(skill: &skill_ir::Skill) -> String {
    let mut value = serde_json::json!({ "name": skill.name, "learn": skill.learn });
    strip_positions(&mut value);
    let text = value.to_string();
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in text.bytes() {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{hash:016x}")
}

fn strip_positions(value: &mut serde_json::Value) {
    match value {
        serde_json::Value::Object(map) => {
            map.remove("span");
            map.remove("doc");
            map.values_mut().for_each(strip_positions);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(strip_positions),
        _ => {}
    }
}

/// Everything learned from one demonstration for one skill.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Learned {
    /// Always [`LEARNED_VERSION`] when written by this version.
    pub learned_version: u32,
    /// The skill's name.
    pub skill: String,
    /// [`ir_hash`] of the skill it was learned for.
    pub ir_hash: String,
    /// Where the demonstration came from.
    pub demo: DemoInfo,
    /// The segments, in time order.
    pub segments: Vec<LearnedSegment>,
    /// Compliant frames by name.
    pub frames: BTreeMap<String, LearnedFrame>,
    /// Motions by name.
    pub motions: BTreeMap<String, LearnedMotion>,
    /// Desired forces by name.
    pub forces: BTreeMap<String, LearnedForce>,
    /// Thresholds by name \[N or N m\].
    pub thresholds: BTreeMap<String, LearnedThreshold>,
    /// How well the features reproduce the demonstration.
    pub quality: Quality,
}

/// The demonstration a file was learned from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DemoInfo {
    /// The file, as given.
    pub source: String,
    /// Number of samples used (after preprocessing).
    pub samples: usize,
    /// Duration \[s\].
    pub duration_s: f64,
    /// Mean sampling rate \[Hz\].
    pub rate_hz: f64,
    /// Warnings raised while reading it.
    pub warnings: Vec<String>,
}

/// One segment of the demonstration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LearnedSegment {
    /// Start time \[s\], demonstration clock.
    pub start_s: f64,
    /// End time \[s\] (time of the last sample).
    pub end_s: f64,
    /// First sample index.
    pub start_index: usize,
    /// One past the last sample index.
    pub end_index: usize,
}

/// How a learned frame was obtained. Serialised with the source language's names, which are
/// also the names [`FrameKind::name`] gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameKind {
    /// The constraint model `fixed_point`.
    FixedPoint,
    /// The constraint model `point_on_plane`.
    PointOnPlane,
    /// The constraint model `planar`.
    Planar,
    /// The constraint model `cylinder`. Written `cylinder`, as the source language names it
    /// (the IR's serde name `concentric_cylinder` is read too).
    #[serde(rename = "cylinder", alias = "concentric_cylinder")]
    ConcentricCylinder,
    /// The constraint model `prismatic`.
    Prismatic,
    /// The constraint model `axial_rotation`.
    AxialRotation,
    /// z along the applied force (`force_aligned`).
    ForceAligned,
    /// A literal frame (`fixed`).
    Fixed,
}

/// Where a learned frame's origin is when it is used as a control frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameOrigin {
    /// The learned origin: it is a point of the task (the fixed point, a point on the hinge
    /// axis, the literal frame's origin) that rotations and forces are about.
    Learned,
    /// The current tool point: only the frame's orientation was learned; its origin (a
    /// centroid, a point on a line or cylinder axis, a sample's position) means nothing later.
    AtTool,
}

impl FrameKind {
    /// The name written in learned files and printed.
    pub fn name(self) -> &'static str {
        match self {
            FrameKind::FixedPoint => "fixed_point",
            FrameKind::PointOnPlane => "point_on_plane",
            FrameKind::Planar => "planar",
            FrameKind::ConcentricCylinder => "cylinder",
            FrameKind::Prismatic => "prismatic",
            FrameKind::AxialRotation => "axial_rotation",
            FrameKind::ForceAligned => "force_aligned",
            FrameKind::Fixed => "fixed",
        }
    }

    /// Where a frame of this kind has its origin at run time.
    pub fn origin(self) -> FrameOrigin {
        match self {
            FrameKind::FixedPoint | FrameKind::AxialRotation | FrameKind::Fixed => FrameOrigin::Learned,
            FrameKind::PointOnPlane
            | FrameKind::Planar
            | FrameKind::ConcentricCylinder
            | FrameKind::Prismatic
            | FrameKind::ForceAligned => FrameOrigin::AtTool,
        }
    }
}

impl From<ConstraintKind> for FrameKind {
    fn from(kind: ConstraintKind) -> Self {
        match kind {
            ConstraintKind::FixedPoint => FrameKind::FixedPoint,
            ConstraintKind::PointOnPlane => FrameKind::PointOnPlane,
            ConstraintKind::Planar => FrameKind::Planar,
            ConstraintKind::ConcentricCylinder => FrameKind::ConcentricCylinder,
            ConstraintKind::Prismatic => FrameKind::Prismatic,
            ConstraintKind::AxialRotation => FrameKind::AxialRotation,
        }
    }
}

impl fmt::Display for FrameKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

/// A frame pose in the base frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FramePose {
    /// How it was obtained.
    pub kind: FrameKind,
    /// Origin \[m\].
    pub origin: [f64; 3],
    /// Orientation `[w, x, y, z]`.
    pub quaternion_wxyz: [f64; 4],
    /// Time from the start of the frame's segment \[s\], for per-sample frames.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_s: Option<f64>,
}

impl FramePose {
    /// The pose as an isometry.
    pub fn isometry(&self) -> Isometry3<f64> {
        let [w, x, y, z] = self.quaternion_wxyz;
        let rotation = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
        Isometry3::from_parts(Translation3::from(Vector3::from(self.origin)), rotation)
    }

    /// A frame pose from an isometry.
    pub fn from_isometry(kind: FrameKind, pose: &Isometry3<f64>, t_s: Option<f64>) -> Self {
        let q = pose.rotation.quaternion();
        FramePose {
            kind,
            origin: pose.translation.vector.into(),
            quaternion_wxyz: [q.w, q.i, q.j, q.k],
            t_s,
        }
    }
}

/// A learned frame: one pose, or one per sample of a segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum LearnedFrame {
    /// A constant frame.
    Constant(FramePose),
    /// A frame per sample (decimated), with `t_s` from the segment's start.
    Samples(Vec<FramePose>),
}

impl LearnedFrame {
    /// The frame at `t_s` from the start of its segment (constant frames ignore it); between
    /// samples the nearest earlier one is held.
    pub fn at(&self, t_s: f64) -> Isometry3<f64> {
        match self {
            LearnedFrame::Constant(pose) => pose.isometry(),
            LearnedFrame::Samples(poses) => {
                let index = poses.partition_point(|p| p.t_s.unwrap_or(0.0) <= t_s).saturating_sub(1);
                poses.get(index).map_or(Isometry3::identity(), FramePose::isometry)
            }
        }
    }

    /// The kind of the (first) pose; an empty list of samples (never written) counts as
    /// `force_aligned`, the only kind learned per sample.
    pub fn kind(&self) -> FrameKind {
        match self {
            LearnedFrame::Constant(pose) => pose.kind,
            LearnedFrame::Samples(poses) => poses.first().map_or(FrameKind::ForceAligned, |p| p.kind),
        }
    }
}

/// A learned motion: position and orientation DMPs of the flange over one segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnedMotion {
    /// The segment (0-based).
    pub segment: usize,
    /// Position DMP, 3 channels \[m\], base frame.
    pub position: Dmp,
    /// Orientation DMP, base frame.
    pub orientation: QuatDmp,
    /// A motion learned as `strokes(...)`: each stroke of the segment as a motion of its own, in
    /// time order (their own `strokes` empty). Empty for a plain `dmp` motion.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strokes: Vec<LearnedMotion>,
}

impl LearnedMotion {
    /// What the `index`-th run (0-based) of this motion runs in a state that repeats it: the
    /// motion itself, or for a strokes motion the `index`-th demonstrated stroke and, past the
    /// last, the last two strokes alternately (so a back-and-forth stays back and forth).
    pub fn piece(&self, index: usize) -> &LearnedMotion {
        let k = self.strokes.len();
        match k {
            0 => self,
            1 => &self.strokes[0],
            _ if index < k => &self.strokes[index],
            _ => &self.strokes[k - 2 + (index - k) % 2],
        }
    }

    /// How many runs a state without `repeat` makes: the demonstrated strokes, or one.
    pub fn default_runs(&self) -> usize {
        self.strokes.len().max(1)
    }
}

/// A learned desired force. Scalar forces act along the z axis of the state's control frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LearnedForce {
    /// Constant from the lowest-variance in-contact region.
    Constant {
        /// The force \[N\].
        value_n: f64,
        /// Its standard deviation over the region \[N\].
        std_n: f64,
        /// From the start of the first to the end of the last low-variance region averaged
        /// \[s\], demonstration time.
        region_s: [f64; 2],
    },
    /// The force at a point.
    At {
        /// The force \[N\].
        value_n: f64,
    },
    /// A literal.
    Literal {
        /// The force \[N\].
        value_n: f64,
    },
    /// No desired force (pure compliance on force axes).
    Tracked {
        /// Always 0.
        value_n: f64,
    },
    /// DMPs of the applied force vector \[N\], base frame.
    Dmp {
        /// 3 channels.
        dmp: Dmp,
    },
    /// A DMP of the force magnitude along a frame axis \[N\].
    Magnitude {
        /// 1 channel.
        dmp: Dmp,
    },
}

impl LearnedForce {
    /// The constant value, for forces that have one.
    pub fn value_n(&self) -> Option<f64> {
        match self {
            LearnedForce::Constant { value_n, .. }
            | LearnedForce::At { value_n }
            | LearnedForce::Literal { value_n }
            | LearnedForce::Tracked { value_n } => Some(*value_n),
            LearnedForce::Dmp { .. } | LearnedForce::Magnitude { .. } => None,
        }
    }
}

/// A learned threshold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearnedThreshold {
    /// The value \[N or N m\].
    pub value: f64,
}

/// Reconstruction and fit figures.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Quality {
    /// Per motion: RMS error of the DMP rollout against the demonstration.
    pub motions: BTreeMap<String, MotionQuality>,
    /// Per DMP force: RMS error of the rollout \[N\].
    pub forces_rms_n: BTreeMap<String, f64>,
    /// Per fitted frame: the constraint fits (every candidate, the chosen one marked).
    pub constraints: BTreeMap<String, Vec<ConstraintQuality>>,
    /// Estimated position noise per axis of the demonstration as read \[m\] (docs/method.md §1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_noise_m: Option<f64>,
    /// How the demonstration was smoothed before learning, e.g. `motion low-pass 20 Hz (default)`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub smoothing: String,
    /// The wrench's frame, bias and sign as found before learning (docs/method.md §1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wrench: Option<crate::wrench::WrenchReport>,
    /// Per frame fitted to a plane: its normal checked against the applied force (docs/method.md §4).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub normals: BTreeMap<String, NormalCheck>,
    /// Per segment a frame imposes a plane on: its boundaries checked against the tool's
    /// distance from that plane (docs/method.md §3).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub contacts: Vec<ContactBoundaries>,
    /// The contact phases of the demonstration and the one learned (docs/method.md §3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phases: Option<PhaseReport>,
    /// Per frame at a point: the window of first contact whose force it follows (docs/method.md §4).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub onset_frames: BTreeMap<String, OnsetFrame>,
}

/// The contact phases found in a demonstration and which of them was learned (docs/method.md §3).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PhaseReport {
    /// Each phase's onset and release \[s\], in time order.
    pub phases_s: Vec<[f64; 2]>,
    /// Each phase's median force magnitude \[N\].
    pub median_n: Vec<f64>,
    /// The force noise per axis \[N\] and the on-threshold \[N\] the phases were found with.
    pub noise_n: f64,
    /// The on-threshold \[N\] (the off-threshold is half of it).
    pub on_n: f64,
    /// The phase learned from (1-based), when the demonstration was cut to one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub learned: Option<usize>,
    /// Why that phase: `--phase`, `longest`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub chosen_by: String,
    /// Segment boundaries moved to a contact's onset or release: segment (1-based), which end,
    /// from and to \[s\].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub moved: Vec<OnsetMove>,
}

/// A segment boundary moved to a contact's onset or release (docs/method.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OnsetMove {
    /// The segment whose start moved, 1-based.
    pub segment: usize,
    /// `onset` (the segment starts where the contact does) or `release` (where it ends).
    pub end: String,
    /// Where segmentation put it and where it is now \[s\].
    pub from_to_s: [f64; 2],
}

/// A frame at a point whose force came from the first window in contact (docs/method.md §4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OnsetFrame {
    /// The window \[s\].
    pub window_s: [f64; 2],
    /// Samples averaged.
    pub samples: usize,
    /// The mean applied force's magnitude over the window \[N\].
    pub mean_n: f64,
    /// RMS angle of the window's force directions about their mean \[°\].
    pub scatter_deg: f64,
}

/// A planar contact segment's boundaries before and after the geometric check (docs/method.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactBoundaries {
    /// The frame that imposes the plane.
    pub frame: String,
    /// The segment (1-based).
    pub segment: usize,
    /// RMS distance of the segment (of its middle half when that is not a plane) from its fitted
    /// plane \[m\].
    pub residual_m: f64,
    /// How far above the plane the tool may be and still count as on it \[m\] (0 when the
    /// check was not made).
    pub tolerance_m: f64,
    /// The segment's first sample time as segmentation found it, and after the check \[s\].
    pub start_s: [f64; 2],
    /// The segment's last sample time as segmentation found it, and after the check \[s\].
    pub end_s: [f64; 2],
    /// Why a boundary was left where segmentation put it, if one was.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kept: Option<String>,
}

/// A fitted plane's normal against the mean applied force of its segment (docs/method.md §4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NormalCheck {
    /// The segment the plane was fitted to (1-based).
    pub segment: usize,
    /// The fitted normal, into the surface (unit, base frame).
    pub fitted_z: [f64; 3],
    /// The direction of the mean applied force over the segment's samples in contact (unit, base frame).
    pub force_direction: [f64; 3],
    /// The angle between them \[°\].
    pub angle_deg: f64,
    /// The friction cone's half angle, `atan µ` \[°\].
    pub cone_deg: f64,
    /// The steady friction coefficient the sliding samples show (removed from the force when
    /// the normal is replaced).
    pub friction: f64,
    /// Whether z was replaced by the applied force's direction (without friction).
    pub replaced: bool,
    /// How far the measured contact normal turns over the segment while the tool slides: the
    /// 90th percentile of its angle from its mean direction \[°\] (docs/method.md §4, curved
    /// surfaces). `None` when too few samples slide in contact.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spread_deg: Option<f64>,
    /// The same percentile about the normals of a quadric fitted to the tool's path \[°\]: what
    /// the surface's shape leaves unexplained (a hand's lean on a flat part leaves it all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unexplained_deg: Option<f64>,
    /// Whether the surface curves (the spread above the learner's bound) and the frame follows
    /// the measured normal sample by sample instead of holding the plane's.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub follows_surface: bool,
}

/// How well a motion reproduces its segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotionQuality {
    /// RMS position error per axis x, y, z \[m\].
    pub position_rms_m: [f64; 3],
    /// RMS orientation error \[rad\].
    pub orientation_rms_rad: f64,
    /// Peak speed of the rollout \[m/s\] (0 in files written before it was recorded).
    #[serde(default)]
    pub peak_speed_mps: f64,
    /// Peak speed of the demonstrated segment, smoothed \[m/s\].
    #[serde(default)]
    pub demo_peak_speed_mps: f64,
    /// A strokes motion's strokes as `[start, end]` in demonstration time \[s\] (empty for a
    /// plain motion).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strokes_s: Vec<[f64; 2]>,
}

/// One constraint model's fit on a segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintQuality {
    /// The model.
    pub kind: FrameKind,
    /// RMS position residual \[m\].
    pub residual_m: f64,
    /// RMS orientation residual \[rad\].
    pub residual_rad: f64,
    /// Agreement of the forces with the constrained directions, 0..1.
    pub force_agreement: f64,
    /// Whether it was chosen.
    pub chosen: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [FrameKind; 8] = [
        FrameKind::FixedPoint,
        FrameKind::PointOnPlane,
        FrameKind::Planar,
        FrameKind::ConcentricCylinder,
        FrameKind::Prismatic,
        FrameKind::AxialRotation,
        FrameKind::ForceAligned,
        FrameKind::Fixed,
    ];

    #[test]
    fn a_frame_kind_is_written_and_printed_with_one_name() {
        for kind in ALL {
            let written = serde_json::to_string(&kind).expect("serialises");
            assert_eq!(written, format!("\"{}\"", kind.name()));
            assert_eq!(serde_json::from_str::<FrameKind>(&written).expect("reads back"), kind);
            assert_eq!(format!("{kind:<16}|"), format!("{:<16}|", kind.name()), "Display pads");
        }
        assert_eq!(FrameKind::ConcentricCylinder.name(), "cylinder");
        let alias: FrameKind = serde_json::from_str("\"concentric_cylinder\"").expect("the IR's name is read");
        assert_eq!(alias, FrameKind::ConcentricCylinder);
    }

    #[test]
    fn only_points_of_the_task_keep_their_learned_origin() {
        let learned: Vec<FrameKind> = ALL.into_iter().filter(|k| k.origin() == FrameOrigin::Learned).collect();
        assert_eq!(
            learned,
            [FrameKind::FixedPoint, FrameKind::AxialRotation, FrameKind::Fixed]
        );
    }
}

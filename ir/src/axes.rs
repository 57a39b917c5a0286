//! Frames and their axes: how states, guards and learned features name a direction.

use crate::FrameId;
use serde::{Deserialize, Serialize};

/// A reference to a frame: a learned one or a built-in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "id", rename_all = "snake_case")]
pub enum FrameRef {
    /// The robot base frame.
    Base,
    /// The tool frame, moving with the tool.
    Tool,
    /// A learned frame.
    Learned(FrameId),
}

/// A frame axis, `x y z rx ry rz` as 0..6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    /// Translation along x.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation about x.
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
}

impl Axis {
    /// All axes in order.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::Rx, Axis::Ry, Axis::Rz];

    /// The axis from its source name.
    pub fn from_name(name: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|axis| axis.name() == name)
    }

    /// The source name: `x`, `rz`, ...
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
            Axis::Rx => "rx",
            Axis::Ry => "ry",
            Axis::Rz => "rz",
        }
    }

    /// 0..6 in `x y z rx ry rz` order.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Whether it is a rotation.
    pub fn is_rotation(self) -> bool {
        self.index() >= 3
    }
}

/// A frame axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameAxis {
    /// The frame.
    pub frame: FrameRef,
    /// The axis.
    pub axis: Axis,
}

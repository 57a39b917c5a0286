//! The constraint models a contact segment can be fitted with (their names and degrees of
//! freedom): the part of constraint fitting that the learned file stores.

use serde::{Deserialize, Serialize};
use skill_ir as ir;

/// The six constraint models of Subramani et al. 2018.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstraintKind {
    /// A point of the tool stays fixed; the tool rotates freely (ball joint).
    FixedPoint,
    /// A point of the tool stays on a plane; the tool rotates freely.
    PointOnPlane,
    /// The tool slides on a plane and rotates only about its normal.
    Planar,
    /// The tool translates along an axis and rotates about it (peg in hole).
    ConcentricCylinder,
    /// The tool translates along a line without rotating (drawer).
    Prismatic,
    /// The tool rotates about a fixed axis (hinge).
    AxialRotation,
}

impl ConstraintKind {
    /// All six models.
    pub const ALL: [ConstraintKind; 6] = [
        ConstraintKind::FixedPoint,
        ConstraintKind::PointOnPlane,
        ConstraintKind::Planar,
        ConstraintKind::ConcentricCylinder,
        ConstraintKind::Prismatic,
        ConstraintKind::AxialRotation,
    ];

    /// Degrees of freedom the constraint leaves to the tool.
    pub fn dof(self) -> usize {
        match self {
            ConstraintKind::Prismatic | ConstraintKind::AxialRotation => 1,
            ConstraintKind::ConcentricCylinder => 2,
            ConstraintKind::Planar | ConstraintKind::FixedPoint => 3,
            ConstraintKind::PointOnPlane => 5,
        }
    }
}

/// The IR names the same six models.
impl From<ir::ConstraintModel> for ConstraintKind {
    fn from(model: ir::ConstraintModel) -> Self {
        match model {
            ir::ConstraintModel::FixedPoint => ConstraintKind::FixedPoint,
            ir::ConstraintModel::PointOnPlane => ConstraintKind::PointOnPlane,
            ir::ConstraintModel::Planar => ConstraintKind::Planar,
            ir::ConstraintModel::ConcentricCylinder => ConstraintKind::ConcentricCylinder,
            ir::ConstraintModel::Prismatic => ConstraintKind::Prismatic,
            ir::ConstraintModel::AxialRotation => ConstraintKind::AxialRotation,
        }
    }
}

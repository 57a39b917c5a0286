//! Geometric constraints of a segment (Subramani et al. 2018; thesis 4.1.2) and compliant frames.
//!
//! Six models are fitted by least squares to the tool poses of a segment: each has free
//! translational and rotational directions ([`ConstraintKind::dof`]). Every fit reports
//! - `residual_m`: RMS distance of the constrained point from its constraint set (m),
//! - `residual_rad`: RMS rotation outside the allowed rotation axes (rad),
//! - `force_agreement`: `1 − mean(|F_free| / |F|)` over samples in contact, where `F_free` is
//!   the measured force along the model's free translation directions (a constraint can only
//!   push along its constrained directions; friction lowers the figure a little).
//!
//! A model is *accepted* when both residuals are within tolerance. The chosen model is the
//! accepted one with the fewest degrees of freedom (the most specific explanation), ties broken
//! by force agreement and then by the normalised residual; when none is accepted, the one with
//! the smallest score `(residual_m / tol_m)² + (residual_rad / tol_rad)² + (1 − agreement)`.
//!
//! # Compliant-frame conventions (all in the robot base frame)
//!
//! "Applied force" is the force the tool exerts on the environment, `−force_n`.
//!
//! | model | origin | z | x |
//! |---|---|---|---|
//! | planar, point on plane | centroid of the segment's positions (planar) or of the moved tool points (point on plane), on the plane | plane normal pointing *into* the surface (along the mean applied force; if there is no contact, pointing down, `−z_base`) | main direction of motion in the plane |
//! | prismatic | centroid on the line | mean applied force perpendicular to the line (else the minimal rotation of base z) | along the line, in the direction of travel |
//! | concentric cylinder | point on the axis nearest the data | along the axis, in the direction of travel | towards the tool, perpendicular to the axis |
//! | axial rotation (hinge) | point on the axis nearest the data | along the axis, right-handed with the demonstrated rotation | from the axis towards the tool |
//! | fixed point | the fixed point | along the mean applied force (else base z) | minimal rotation from base x |
//!
//! y completes a right-handed frame (`y = z × x`).
//!
//! A slide along a straight line does not determine its plane: when the points lie within
//! `5 × position_tolerance_m` of a line, the plane normal is taken as the mean applied force
//! made perpendicular to the line.

mod frame;
mod models;

pub use self::frame::{
    force_aligned_frame_at, force_aligned_frames, rotation_between, CompliantFrame, ForceFrameConfig,
};
pub use self::models::fit_constraints;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

pub use skill_model::constraint::ConstraintKind;

/// Parameters of constraint fitting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConstraintConfig {
    /// Models to try.
    pub candidates: Vec<ConstraintKind>,
    /// Largest accepted RMS position residual (m).
    pub position_tolerance_m: f64,
    /// Largest accepted RMS rotation residual (rad).
    pub rotation_tolerance_rad: f64,
    /// Samples with a smaller force (N) do not count for force agreement or frame direction.
    pub contact_threshold_n: f64,
}

impl Default for ConstraintConfig {
    fn default() -> Self {
        Self {
            candidates: ConstraintKind::ALL.to_vec(),
            position_tolerance_m: 0.002,
            rotation_tolerance_rad: 2f64.to_radians(),
            contact_threshold_n: 1.0,
        }
    }
}

/// One fitted constraint model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintFit {
    /// The model.
    pub kind: ConstraintKind,
    /// RMS position residual (m).
    pub residual_m: f64,
    /// RMS rotation residual (rad).
    pub residual_rad: f64,
    /// Agreement of the measured force with the constrained directions, in `[0, 1]`.
    pub force_agreement: f64,
    /// Both residuals within tolerance.
    pub accepted: bool,
    /// `(residual_m / tol_m)² + (residual_rad / tol_rad)² + (1 − force_agreement)`.
    pub score: f64,
    /// The model's main direction (unit, base frame): the plane normal (into the surface), the
    /// line or cylinder axis, the hinge axis; `None` for a fixed point.
    pub axis: Option<Vector3<f64>>,
    /// A point of the constraint (on the plane, line or axis; the fixed point) (m), base frame.
    pub point_m: Vector3<f64>,
    /// The compliant frame (conventions in the [module docs](self)).
    pub frame: CompliantFrame,
}

/// All fits of a segment and the chosen one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstraintReport {
    /// Index into `fits` of the chosen model.
    pub best: usize,
    /// Every candidate's fit, in the order of `ConstraintConfig::candidates`.
    pub fits: Vec<ConstraintFit>,
}

impl ConstraintReport {
    /// The chosen fit.
    pub fn chosen(&self) -> &ConstraintFit {
        &self.fits[self.best]
    }
}

/// Problems fitting constraints or building frames.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConstraintError {
    /// Too few samples.
    #[error("constraint fitting needs at least {required} samples, the segment has {found}")]
    TooFewSamples {
        /// Samples given.
        found: usize,
        /// Samples needed.
        required: usize,
    },
    /// Inputs differ in length.
    #[error("`{what}` has length {found}, expected {expected}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// NaN or infinite input.
    #[error("`{what}` is not finite at sample {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// 0-based sample index.
        index: usize,
    },
    /// A configuration value is out of range.
    #[error("invalid constraint parameter `{name}`: {reason}")]
    InvalidConfig {
        /// Parameter name.
        name: &'static str,
        /// Why it is rejected.
        reason: String,
    },
    /// The force never reaches the threshold, so no force direction exists.
    #[error("no contact: the peak force {peak_n:.3} N stays below `min_force_n` = {threshold_n} N")]
    NoContact {
        /// Largest force magnitude (N).
        peak_n: f64,
        /// Threshold (N).
        threshold_n: f64,
    },
}

#[cfg(test)]
mod tests;

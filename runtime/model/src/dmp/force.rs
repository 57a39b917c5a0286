//! Force DMPs: the same 1-D transformation systems, on force channels.
//!
//! The channels carry whatever force the caller fits: the learning driver fits the force the
//! robot applies (the negated sensor reading, docs/method.md §1), projected on the compliant
//! frame where the template asks for it.

use nalgebra::Vector3;

use super::{Dmp, DmpConfig, DmpError};

/// Learns a 3-channel DMP of the force vectors `forces_n` (N) at times `t_s`.
pub fn fit_force(config: &DmpConfig, t_s: &[f64], forces_n: &[Vector3<f64>]) -> Result<Dmp, DmpError> {
    Dmp::fit_points(config, t_s, forces_n)
}

/// Learns a 1-channel DMP of a scalar profile (e.g. the force along a frame's z axis (N)).
pub fn fit_scalar(config: &DmpConfig, t_s: &[f64], values: &[f64]) -> Result<Dmp, DmpError> {
    Dmp::fit(config, t_s, &[values])
}

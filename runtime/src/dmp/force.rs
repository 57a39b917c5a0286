//! Force DMPs: the same 1-D transformation systems, on force channels.
//!
//! Forces follow the demonstration's sign convention (the force the environment exerts on the
//! tool) unless the caller projects them first, e.g. onto a compliant frame's z axis.

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

//! Standardised feature matrices for segmentation.

use serde::{Deserialize, Serialize};

use super::SegmentError;
use crate::demo::Demo;

/// Which demonstration channels become segmentation features.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FeatureSet {
    /// Use the tool position (3 columns).
    pub position: bool,
    /// Use the measured force (3 columns).
    pub force: bool,
    /// Use the force magnitude (1 column), which does not depend on direction.
    pub force_magnitude: bool,
}

impl Default for FeatureSet {
    fn default() -> Self {
        Self {
            position: true,
            force: true,
            force_magnitude: false,
        }
    }
}

/// A row-major feature matrix: `data[k * dims + c]` is column `c` of sample `k`.
#[derive(Debug, Clone, PartialEq)]
pub struct Features {
    /// The values.
    pub data: Vec<f64>,
    /// Number of columns.
    pub dims: usize,
}

impl Features {
    /// Number of samples (rows).
    pub fn len(&self) -> usize {
        self.data.len().checked_div(self.dims).unwrap_or(0)
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Builds the standardised features `set` of `demo`.
    pub fn from_demo(demo: &Demo, set: &FeatureSet) -> Result<Self, SegmentError> {
        let dims = 3 * usize::from(set.position) + 3 * usize::from(set.force) + usize::from(set.force_magnitude);
        if dims == 0 {
            return Err(SegmentError::InvalidConfig {
                name: "features",
                reason: "select at least one feature".to_owned(),
            });
        }
        let mut data = Vec::with_capacity(demo.len() * dims);
        for k in 0..demo.len() {
            if set.position {
                data.extend_from_slice(demo.position_m[k].as_slice());
            }
            if set.force {
                data.extend_from_slice(demo.force_n[k].as_slice());
            }
            if set.force_magnitude {
                data.push(demo.force_n[k].norm());
            }
        }
        let mut features = Self { data, dims };
        standardise(&mut features);
        Ok(features)
    }
}

/// Scales every column to zero mean and unit standard deviation (constant columns become 0).
pub fn standardise(features: &mut Features) {
    let (n, dims) = (features.len(), features.dims);
    if n == 0 {
        return;
    }
    for c in 0..dims {
        let mean = (0..n).map(|k| features.data[k * dims + c]).sum::<f64>() / n as f64;
        let var = (0..n)
            .map(|k| (features.data[k * dims + c] - mean).powi(2))
            .sum::<f64>()
            / n as f64;
        let scale = if var > 1e-24 { 1.0 / var.sqrt() } else { 0.0 };
        for k in 0..n {
            let value = &mut features.data[k * dims + c];
            *value = (*value - mean) * scale;
        }
    }
}

//! Splitting a touch demonstration at the force peak (thesis Table 4.3).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::{Segment, SegmentError};

/// Parameters of the split at the force peak.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TouchConfig {
    /// The force magnitude is averaged over this many samples (centred) before the peak is
    /// searched, so a single noisy sample cannot win.
    pub smoothing_samples: usize,
    /// The peak must exceed this force (N), otherwise there was no contact.
    pub contact_threshold_n: f64,
}

impl Default for TouchConfig {
    fn default() -> Self {
        Self {
            smoothing_samples: 5,
            contact_threshold_n: 1.0,
        }
    }
}

/// Splits at the sample of largest (smoothed) force magnitude into the approach
/// `0..peak` and the return `peak..n` (the peak sample starts the second segment).
pub fn split_at_force_peak(force_n: &[Vector3<f64>], config: &TouchConfig) -> Result<[Segment; 2], SegmentError> {
    let n = force_n.len();
    if n < 3 {
        return Err(SegmentError::TooFewSamples { found: n, required: 3 });
    }
    if let Some(index) = force_n.iter().position(|f| !f.iter().all(|v| v.is_finite())) {
        return Err(SegmentError::NonFinite { what: "force_n", index });
    }
    let half = config.smoothing_samples / 2;
    let magnitude: Vec<f64> = force_n.iter().map(|f| f.norm()).collect();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    for m in &magnitude {
        prefix.push(prefix[prefix.len() - 1] + m);
    }
    let (mut peak, mut peak_value) = (0usize, f64::NEG_INFINITY);
    for k in 0..n {
        let (a, b) = (k.saturating_sub(half), (k + half + 1).min(n));
        let value = (prefix[b] - prefix[a]) / (b - a) as f64;
        if value > peak_value {
            (peak, peak_value) = (k, value);
        }
    }
    if peak_value < config.contact_threshold_n {
        return Err(SegmentError::NoContact {
            peak_n: peak_value,
            threshold_n: config.contact_threshold_n,
        });
    }
    let peak = peak.clamp(1, n - 1);
    Ok([Segment { start: 0, end: peak }, Segment { start: peak, end: n }])
}

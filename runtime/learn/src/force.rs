//! Desired forces from a demonstration (thesis 4.2.2): a constant normal force from the
//! lowest-variance in-contact region, the force magnitude along a frame's z axis as a profile,
//! and the force at a point (a touch threshold).
//!
//! Sign convention: the demonstration holds the force the environment exerts on the tool
//! (`force_n`). Everything returned here is the force the tool *applies*, `−force_n`, projected
//! onto the compliant frame's z axis, which points into the surface; pressing gives positive
//! values.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::constraint::CompliantFrame;
use super::segment::{changepoint, ChangepointConfig, Features, LengthPrior, Segment, SegmentError, SegmentModel};

/// Problems extracting forces.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ForceError {
    /// Inputs differ in length or an index is out of range.
    #[error("`{what}` has length {found}, expected {expected}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// No in-contact region long enough.
    #[error("no contact region of at least `min_region_s` = {min_region_s} s above `contact_threshold_n` = {threshold_n} N (peak {peak_n:.3} N)")]
    NoContact {
        /// Largest applied force (N).
        peak_n: f64,
        /// Threshold (N).
        threshold_n: f64,
        /// Shortest region (s).
        min_region_s: f64,
    },
    /// The change-point segmentation of the force profile failed.
    #[error("cannot segment the force profile")]
    Segment(#[from] SegmentError),
}

/// Parameters of the constant-force extraction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConstantForceConfig {
    /// A region counts as in contact when its mean applied force exceeds this (N).
    pub contact_threshold_n: f64,
    /// Shortest region considered (s).
    pub min_region_s: f64,
    /// Mean region length for the change-point prior (s).
    pub mean_region_s: f64,
    /// Pieces whose variance is at most this multiple of the smallest piece variance are
    /// averaged together (1 = only the quietest piece).
    pub variance_ratio: f64,
    /// Particles kept by the change-point detection (fewer is faster; a 1-D step profile
    /// needs few).
    pub max_particles: usize,
}

impl Default for ConstantForceConfig {
    fn default() -> Self {
        Self {
            contact_threshold_n: 1.0,
            min_region_s: 0.2,
            mean_region_s: 1.0,
            max_particles: 30,
            variance_ratio: 2.0,
        }
    }
}

/// A constant force and the regions it was taken from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstantForce {
    /// Mean applied force over the regions (N).
    pub value_n: f64,
    /// Standard deviation over the regions (N).
    pub std_n: f64,
    /// The quietest constant-mean piece.
    pub region: Segment,
    /// All pieces averaged (constant-mean pieces about as quiet as `region`, in time order).
    pub regions: Vec<Segment>,
}

/// The applied force along each frame's z axis, `−force_n[k] · z_k` (N).
pub fn profile_along(force_n: &[Vector3<f64>], frames: &[CompliantFrame]) -> Result<Vec<f64>, ForceError> {
    if frames.len() != force_n.len() {
        return Err(ForceError::LengthMismatch {
            what: "frames",
            expected: force_n.len(),
            found: frames.len(),
        });
    }
    Ok(force_n
        .iter()
        .zip(frames)
        .map(|(f, frame)| -f.dot(&frame.z_axis()))
        .collect())
}

/// The applied force along one fixed axis `z` (unit, base frame), `−force_n[k] · z` (N).
pub fn profile_along_axis(force_n: &[Vector3<f64>], z: &Vector3<f64>) -> Vec<f64> {
    let z = z.normalize();
    force_n.iter().map(|f| -f.dot(&z)).collect()
}

/// The applied force along `z` at sample `index`, averaged over `window` samples centred on it
/// (N): the contact force at a touch point, used as a threshold.
pub fn force_at(force_n: &[Vector3<f64>], z: &Vector3<f64>, index: usize, window: usize) -> Result<f64, ForceError> {
    if index >= force_n.len() {
        return Err(ForceError::LengthMismatch {
            what: "index",
            expected: force_n.len(),
            found: index,
        });
    }
    let half = window / 2;
    let (a, b) = (index.saturating_sub(half), (index + half + 1).min(force_n.len()));
    let z = z.normalize();
    Ok(force_n[a..b].iter().map(|f| -f.dot(&z)).sum::<f64>() / (b - a) as f64)
}

/// The constant force of a profile `profile_n` (applied force along the frame's z, sampled at
/// `t_s`): the profile is cut into constant-mean pieces by change-point detection; among the
/// in-contact pieces, those whose variance is within `variance_ratio` of the lowest and whose
/// mean is within two standard deviations of the quietest piece's mean form the low-variance
/// region, and their mean is returned. Touch-down and lift-off transients fall into
/// their own, noisier pieces and so do not bias the value, unlike a plain mean.
pub fn constant_normal_force(
    t_s: &[f64],
    profile_n: &[f64],
    config: &ConstantForceConfig,
) -> Result<ConstantForce, ForceError> {
    if t_s.len() != profile_n.len() {
        return Err(ForceError::LengthMismatch {
            what: "profile_n",
            expected: t_s.len(),
            found: profile_n.len(),
        });
    }
    let features = Features {
        data: profile_n.to_vec(),
        dims: 1,
    };
    let cp_config = ChangepointConfig {
        models: vec![SegmentModel::Constant],
        min_length_s: config.min_region_s,
        length_prior: LengthPrior::Geometric {
            mean_s: config.mean_region_s,
        },
        noise_floor: 1e-3,
        max_particles: config.max_particles,
        ..ChangepointConfig::default()
    };
    let pieces = changepoint(&features, t_s, &cp_config)?;
    let min_samples = if t_s.len() > 1 {
        ((config.min_region_s / ((t_s[t_s.len() - 1] - t_s[0]) / (t_s.len() - 1) as f64)).round() as usize).max(2)
    } else {
        2
    };
    // In-contact pieces long enough to count: (segment, mean, std).
    let mut candidates = Vec::new();
    for piece in pieces {
        let region = piece.segment;
        if region.len() < min_samples {
            continue;
        }
        let values = &profile_n[region.range()];
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let std = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt();
        if mean >= config.contact_threshold_n {
            candidates.push((region, mean, std));
        }
    }
    let Some(&(region, quiet_mean, min_std)) = candidates.iter().min_by(|a, b| a.2.total_cmp(&b.2)) else {
        return Err(ForceError::NoContact {
            peak_n: profile_n.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            threshold_n: config.contact_threshold_n,
            min_region_s: config.min_region_s,
        });
    };
    // Every piece about as quiet as the quietest one, with a mean within two of its standard
    // deviations, belongs to the constant region (a slow drift splits a plateau into several
    // quiet pieces; transients are noisier or sit at another level).
    let limit = config.variance_ratio.max(1.0).sqrt() * min_std;
    let regions: Vec<Segment> = candidates
        .iter()
        .filter(|c| c.2 <= limit && (c.1 - quiet_mean).abs() <= 2.0 * min_std)
        .map(|c| c.0)
        .collect();
    let count: usize = regions.iter().map(Segment::len).sum();
    let value_n = regions.iter().flat_map(|r| &profile_n[r.range()]).sum::<f64>() / count as f64;
    let std_n = (regions
        .iter()
        .flat_map(|r| &profile_n[r.range()])
        .map(|v| (v - value_n).powi(2))
        .sum::<f64>()
        / count as f64)
        .sqrt();
    Ok(ConstantForce {
        value_n,
        std_n,
        region,
        regions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::Rng;

    /// A slide at 12 N: approach, touch-down overshoot, noisy plateau, lift-off.
    fn slide(rng: &mut Rng) -> (Vec<f64>, Vec<Vector3<f64>>) {
        let t: Vec<f64> = (0..8000).map(|k| k as f64 * 1e-3).collect();
        let z_out = Vector3::new(0.2, -0.1, 1.0).normalize();
        let force = t
            .iter()
            .map(|&t| {
                let applied = if t < 1.0 {
                    0.0
                } else if t < 1.1 {
                    18.0 * (t - 1.0) / 0.1
                } else if t < 1.6 {
                    12.0 + 6.0 * (-(t - 1.1) / 0.1).exp() * (30.0 * (t - 1.1)).cos()
                } else if t < 6.5 {
                    12.0 + 0.4 * (2.0 * t).sin()
                } else if t < 7.0 {
                    12.0 + 10.0 * (t - 6.5) - 40.0 * (t - 6.5).powi(2)
                } else {
                    0.0
                };
                // The sensor measures the reaction: out of the surface, plus friction and noise.
                z_out * applied + Vector3::new(0.0, 0.3 * applied, 0.0).cross(&z_out) + rng.vector(0.5)
            })
            .collect();
        (t, force)
    }

    #[test]
    fn constant_force_of_a_12n_slide_is_within_2_percent() {
        let mut rng = Rng::new(11);
        let (t, force) = slide(&mut rng);
        let z_into = -Vector3::new(0.2, -0.1, 1.0).normalize();
        let profile = profile_along_axis(&force, &z_into);
        let found = constant_normal_force(&t, &profile, &ConstantForceConfig::default()).expect("contact");
        eprintln!("slide at 12 N: found {:.3} N from {:?}", found.value_n, found.regions);
        assert!((found.value_n - 12.0).abs() < 0.24, "found {} N", found.value_n);
        // Neither the touch-down overshoot (1.0-1.1 s) nor the drop at lift-off (after 6.8 s,
        // where the force leaves the plateau level) is used.
        for region in &found.regions {
            assert!(
                region.start >= 1100 && region.end <= 6850,
                "region {region:?} includes a transient"
            );
        }
        // A plain mean over the contact samples is biased by the transients.
        let contact: Vec<f64> = profile.iter().copied().filter(|f| *f > 1.0).collect();
        let plain = contact.iter().sum::<f64>() / contact.len() as f64;
        eprintln!("plain mean over contact samples: {plain:.3} N");
        assert!((plain - 12.0).abs() > (found.value_n - 12.0).abs());
    }

    #[test]
    fn force_at_a_point_and_profiles() {
        // A table below pushes the tool up; the tool presses down, along -z.
        let force = vec![Vector3::new(0.0, 0.0, 5.0); 10];
        assert!((force_at(&force, &-Vector3::z(), 4, 3).expect("in range") - 5.0).abs() < 1e-12);
        assert!((force_at(&force, &Vector3::z(), 9, 5).expect("in range") + 5.0).abs() < 1e-12);
        assert!(force_at(&force, &Vector3::z(), 10, 1).is_err());
        let frames = vec![CompliantFrame::z_aligned(Vector3::zeros(), &-Vector3::z()); 10];
        let profile = profile_along(&force, &frames).expect("same length");
        assert!(profile.iter().all(|f| (f - 5.0).abs() < 1e-12));
    }

    #[test]
    fn no_contact_is_an_error() {
        let t: Vec<f64> = (0..1000).map(|k| k as f64 * 1e-3).collect();
        let profile = vec![0.1; 1000];
        assert!(matches!(
            constant_normal_force(&t, &profile, &ConstantForceConfig::default()),
            Err(ForceError::NoContact { .. })
        ));
    }
}

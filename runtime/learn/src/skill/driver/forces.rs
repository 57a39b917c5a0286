//! Learning a plan's desired forces (literal, at a point, constant, DMP, magnitude DMP) and its
//! thresholds.

use nalgebra::Vector3;
use skill_ir as ir;

use super::smoothing::{smooth, smooth_points, smoothing_window};
use super::{LearnError, Learner, CONTACT_N};
use crate::dmp::{fit_force, fit_scalar, Dmp, DmpConfig};
use crate::force::{constant_normal_force, ConstantForceConfig, ForceError};
use crate::skill::learned::{LearnedForce, LearnedThreshold};

impl Learner<'_> {
    pub(super) fn force(&mut self, decl: &ir::ForceDecl) -> Result<LearnedForce, LearnError> {
        let wrap = |source| LearnError::Force {
            name: decl.name.clone(),
            source,
        };
        Ok(match &decl.source {
            ir::ForceSource::Literal { value_n } => LearnedForce::Literal { value_n: *value_n },
            ir::ForceSource::Tracked => LearnedForce::Tracked { value_n: 0.0 },
            ir::ForceSource::At { point, along } => {
                let index = self.point(*point);
                let value_n = self.applied_along(index, *along);
                self.require_contact(&decl.name, value_n)?;
                LearnedForce::At { value_n }
            }
            ir::ForceSource::Constant { segment, along } => {
                let seg = self.seg(*segment);
                let t = self.segment_times(seg, &decl.name, segment.index())?;
                let profile: Vec<f64> = seg.range().map(|k| self.applied_along(k, *along)).collect();
                // The steady region must last `min_region_s` (0.2 s) or, in a shorter segment
                // (a tap), half the segment: a time, whatever the sampling rate.
                let duration_s = t[t.len() - 1] - t[0];
                if duration_s < MIN_CONSTANT_SEGMENT_S || seg.len() < MIN_CONSTANT_SAMPLES {
                    return Err(LearnError::TooShortForConstant {
                        segment: segment.index() + 1,
                        samples: seg.len(),
                        duration_s,
                        required_s: MIN_CONSTANT_SEGMENT_S,
                        required_samples: MIN_CONSTANT_SAMPLES,
                        name: decl.name.clone(),
                    });
                }
                let defaults = ConstantForceConfig::default();
                let config = ConstantForceConfig {
                    contact_threshold_n: CONTACT_N,
                    min_region_s: defaults.min_region_s.min(duration_s / 2.0),
                    ..defaults
                };
                let found = constant_normal_force(&t, &profile, &config).map_err(|err| match err {
                    ForceError::NoContact { peak_n, .. } => LearnError::NoContact {
                        source_name: self.demo.source.clone(),
                        name: decl.name.clone(),
                        peak_n,
                    },
                    other => wrap(other),
                })?;
                let region_s = match (found.regions.first(), found.regions.last()) {
                    (Some(first), Some(last)) => [t[first.start], t[last.end - 1]],
                    _ => [t[0], t[t.len() - 1]],
                };
                let contact = ContactLevel::of(&profile);
                if let Some(contact) = &contact {
                    check_against_recording(&decl.name, found.value_n, contact, region_s)?;
                }
                match contact.filter(|contact| contact.unsteady(found.value_n)) {
                    Some(contact) => {
                        let median_n = contact.median_n;
                        self.warnings.push(format!(
                            "`{}`: the force in segment {} was not steady (its quietest stretch, {:.2}-{:.2} s, held {:.2} N; \
                             the contact's median is {median_n:.2} N): learned the median",
                            decl.name,
                            segment.index() + 1,
                            region_s[0],
                            region_s[1],
                            found.value_n
                        ));
                        LearnedForce::Constant {
                            value_n: median_n,
                            std_n: contact.deviation_n(),
                            region_s: [t[contact.first], t[contact.last]],
                        }
                    }
                    None => LearnedForce::Constant {
                        value_n: found.value_n,
                        std_n: found.std_n,
                        region_s,
                    },
                }
            }
            ir::ForceSource::Dmp { segment, basis } => {
                let seg = self.seg(*segment);
                let t = self.segment_times(seg, &decl.name, segment.index())?;
                let raw: Vec<Vector3<f64>> = self.demo.force_n[seg.range()].iter().map(|f| -f).collect();
                let applied = smooth_points(&raw, smoothing_window(&t));
                let peak = applied.iter().map(|f| f.norm()).fold(0.0, f64::max);
                self.require_contact(&decl.name, peak)?;
                let config = force_dmp_config(*basis);
                let dmp = fit_force(&config, &t, &applied).map_err(|source| LearnError::Dmp {
                    name: decl.name.clone(),
                    source,
                })?;
                let rms = force_rms(&dmp, &t, |k, channel| raw[k][channel]);
                self.quality.forces_rms_n.insert(decl.name.clone(), rms);
                let levels: Vec<f64> = applied.iter().map(|f| f.norm()).collect();
                self.warn_on_fit(&decl.name, rms, &levels);
                LearnedForce::Dmp { dmp }
            }
            ir::ForceSource::Magnitude { segment, along, basis } => {
                let seg = self.seg(*segment);
                let t = self.segment_times(seg, &decl.name, segment.index())?;
                let raw: Vec<f64> = seg.range().map(|k| self.applied_along(k, *along)).collect();
                let profile = smooth(&raw, smoothing_window(&t));
                let peak = profile.iter().copied().fold(0.0, f64::max);
                self.require_contact(&decl.name, peak)?;
                let config = force_dmp_config(*basis);
                let dmp = fit_scalar(&config, &t, &profile).map_err(|source| LearnError::Dmp {
                    name: decl.name.clone(),
                    source,
                })?;
                let rms = force_rms(&dmp, &t, |k, _| raw[k]);
                self.quality.forces_rms_n.insert(decl.name.clone(), rms);
                self.warn_on_fit(&decl.name, rms, &profile);
                LearnedForce::Magnitude { dmp }
            }
        })
    }

    /// Warns when a force profile's fit misses the demonstration by more than [`FIT_SHARE`] of
    /// the profile's level (the median of its contact samples): the reproduction would press
    /// with another force than the demonstrator did.
    fn warn_on_fit(&mut self, name: &str, rms_n: f64, levels_n: &[f64]) {
        let Some(level_n) = ContactLevel::of(levels_n).map(|contact| contact.median_n) else {
            return;
        };
        if rms_n > FIT_SHARE * level_n {
            self.warnings.push(format!(
                "force profile `{name}` is fitted with {rms_n:.2} N RMS error, {:.0} % of its level of {level_n:.2} N: \
                 the reproduction will not press as the demonstration did (give it more basis functions, `basis:`, or \
                 check the segment it is learned from)",
                100.0 * rms_n / level_n
            ));
        }
    }

    pub(super) fn threshold(&self, decl: &ir::ThresholdDecl) -> Result<LearnedThreshold, LearnError> {
        let value = match &decl.source {
            ir::ThresholdSource::Literal { value } => *value,
            ir::ThresholdSource::ForceAt { point, along, scale } => {
                let index = self.point(*point);
                let value = self.applied_along(index, *along);
                self.require_contact(&decl.name, value)?;
                value * scale
            }
        };
        Ok(LearnedThreshold { value })
    }
}

/// A learned constant force must lie within this share of the median contact force of the
/// segment it was learned from, and at most [`FORCE_RATIO_MAX`] times it.
pub(super) const FORCE_RATIO_MIN: f64 = 0.5;
/// See [`FORCE_RATIO_MIN`].
pub(super) const FORCE_RATIO_MAX: f64 = 2.0;

/// The contact samples of a force profile (those pushing with more than the contact
/// threshold): their level, and where the first and last of them lie.
struct ContactLevel {
    /// The samples' forces, sorted \[N\].
    sorted_n: Vec<f64>,
    /// Their median \[N\].
    median_n: f64,
    /// The profile's first contact sample.
    first: usize,
    /// Its last.
    last: usize,
}

impl ContactLevel {
    /// `None` when no sample of `profile` is in contact.
    fn of(profile: &[f64]) -> Option<ContactLevel> {
        let first = profile.iter().position(|&f| f > CONTACT_N)?;
        let last = profile.iter().rposition(|&f| f > CONTACT_N)?;
        let mut sorted_n: Vec<f64> = profile.iter().copied().filter(|&f| f > CONTACT_N).collect();
        sorted_n.sort_by(f64::total_cmp);
        let median_n = sorted_n[sorted_n.len() / 2];
        Some(ContactLevel {
            sorted_n,
            median_n,
            first,
            last,
        })
    }

    /// Whether a steady stretch's force `steady_n` lies more than [`UNSTEADY_SHARE`] from the
    /// contact's median: the contact held no steady force (a peeling stroke rises and falls).
    fn unsteady(&self, steady_n: f64) -> bool {
        (steady_n - self.median_n).abs() > UNSTEADY_SHARE * self.median_n
    }

    /// The samples' robust deviation from their median (1.4826 × MAD) \[N\].
    fn deviation_n(&self) -> f64 {
        let mut deviations: Vec<f64> = self.sorted_n.iter().map(|f| (f - self.median_n).abs()).collect();
        deviations.sort_by(f64::total_cmp);
        1.4826 * deviations[deviations.len() / 2]
    }
}

/// Refuses a constant force outside [`FORCE_RATIO_MIN`]-[`FORCE_RATIO_MAX`] times the median of
/// the segment's contact samples: a value learned from a short steady stretch of a hand's load
/// between contacts (2.2 N for a wipe's 21 N) is not the demonstrator's intent.
fn check_against_recording(
    name: &str,
    learned_n: f64,
    contact: &ContactLevel,
    region_s: [f64; 2],
) -> Result<(), LearnError> {
    let median_n = contact.median_n;
    if learned_n >= FORCE_RATIO_MIN * median_n && learned_n <= FORCE_RATIO_MAX * median_n {
        return Ok(());
    }
    Err(LearnError::ForceOffRecording {
        name: name.to_string(),
        learned_n,
        median_n,
        from_s: region_s[0],
        to_s: region_s[1],
    })
}

/// A steady stretch's force farther than this share from the contact's median means the
/// contact held no steady force: the median is learned.
pub(super) const UNSTEADY_SHARE: f64 = 0.15;

/// A force profile fitted with an RMS error above this share of its level is warned about.
pub(super) const FIT_SHARE: f64 = 0.15;

/// Force DMPs use the default (ridge) regression, which reproduces better than LWR.
fn force_dmp_config(basis: u32) -> DmpConfig {
    DmpConfig {
        n_basis: basis as usize,
        ..DmpConfig::default()
    }
}

/// RMS error of a force DMP's rollout at the demonstration's sample times \[N\].
fn force_rms(dmp: &Dmp, t: &[f64], demo: impl Fn(usize, usize) -> f64) -> f64 {
    let mut rollout = dmp.rollout();
    let mut sum = 0.0;
    let mut count = 0.0f64;
    for k in 0..t.len() {
        if k > 0 {
            rollout.step(dmp, t[k] - t[k - 1]);
        }
        let error: f64 = (0..dmp.n_dims())
            .map(|c| (rollout.position()[c] - demo(k, c)).powi(2))
            .sum();
        sum += error;
        count += 1.0;
    }
    (sum / count.max(1.0)).sqrt()
}

/// The shortest segment `constant(...)` learns from \[s\]: its steady region (half the segment
/// at most) then lasts 50 ms or more.
pub(super) const MIN_CONSTANT_SEGMENT_S: f64 = 0.1;

/// The fewest samples `constant(...)` learns from: with fewer, change-point detection cannot
/// set a touch-down apart from the plateau and the value is the plain mean (a 5 N tap with a
/// 30 ms rise at 100 Hz: 4.3 N from 12 or 15 samples, 5.04 N from 20).
pub(super) const MIN_CONSTANT_SAMPLES: usize = 20;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_force_profile_that_starts_rising_is_reproduced() {
        // Touch-down: the force is already rising fast when the segment starts. A DMP that
        // starts at rest cannot follow (5 N RMS on this profile); one that starts with the
        // demonstrated velocity does.
        let t: Vec<f64> = (0..2320).map(|k| k as f64 * 0.001).collect();
        let mut rng = crate::rng::SplitMix64::new(1);
        let raw: Vec<f64> = t
            .iter()
            .map(|&t| 10.0 * (1.0 - (-t / 0.05).exp()) + 0.15 * rng.normal())
            .collect();
        let profile = smooth(&raw, smoothing_window(&t));
        let dmp = fit_scalar(&force_dmp_config(40), &t, &profile).expect("fits");
        let rms = force_rms(&dmp, &t, |k, _| raw[k]);
        assert!(rms < 0.5, "RMS {rms} N (5 % of the 10 N plateau)");
    }
}

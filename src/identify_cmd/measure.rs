//! The measurements `identify` judges a demonstration by, taken on its contact phases after the
//! force the sensor shows in the air is removed.
//!
//! A real recording's wrist sensor rarely reads zero in free space: the tool's weight is
//! compensated for one orientation, a cable pulls, the sensor drifts, so after the approach it
//! may read 1-5 N in the air and keep reading it after the retreat (the LASA rim wipes end at
//! 2 N with the tool 30 cm above the part). Taken as contact, that force makes a touch last until
//! the recording's end and a wipe end "in contact". So the contact spans (from the first to the
//! last sample at 30 % of a phase's peak) are found first, the samples more than 2 cm from every
//! contact position are in the air, the force there (averaged over 0.1 s) is the in-air force,
//! interpolated in time across the contacts, and it is removed before the phases are found again.
//!
//! Travel is measured in the plane of the contact (perpendicular to the mean contact force), so
//! an approach the phase still holds (a push in the air just above the part) does not count as
//! sliding; the recording ends in contact only if its last phase runs to the end with the tool
//! still within 2 cm of where it pressed.

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use skill_runtime::demo::Demo;
use skill_runtime::learn::phases::{contact_phases, ContactPhase, Phases};

/// Travel in contact under this is staying put \[m\]; also how near a contact position the
/// tool is still at the part.
pub(super) const STILL_M: f64 = 0.01;
/// A sample this far from every contact position is in the air \[m\].
const AIR_M: f64 = 0.02;
/// A contact span runs between the first and the last sample at this share of its phase's peak.
const FIRM_SHARE: f64 = 0.3;
/// Phases whose peak is under this share of the strongest are in-air bumps, not contacts.
const MINOR_SHARE: f64 = 0.25;
/// Phases under this share of the strongest phase's peak do not say where the part is.
const CONTACT_SHARE: f64 = 0.4;
/// The in-air force is averaged over this long \[s\].
const AIR_AVERAGE_S: f64 = 0.1;
/// At most this many contact positions are compared with each sample.
const CONTACT_POINTS: usize = 400;
/// A hold holds its level within this share of its median.
const HOLD_BAND: f64 = 0.1;

/// What was measured on a demonstration.
#[derive(Debug, Clone, Serialize)]
pub struct Measures {
    /// Contact phases (in-air bumps under a quarter of the strongest phase's peak left out).
    pub phases: usize,
    /// The longest phase's duration \[s\].
    pub duration_s: f64,
    /// The longest phase's travel along its main direction in the plane of contact \[m\].
    pub travel_m: f64,
    /// Reversals of that travel.
    pub reversals: usize,
    /// How far the contact force's direction turns from the phase's first quarter to its last \[°\].
    pub turn_deg: f64,
    /// The share of the phase the force stays within 10 % of its median.
    pub hold_share: f64,
    /// The force of the phase's last fifth over its first half's.
    pub end_ratio: f64,
    /// The recording ends in contact.
    pub ends_in_contact: bool,
    /// Per phase: duration \[s\] and travel \[m\].
    pub per_phase: Vec<[f64; 2]>,
    /// Distance between the first two phases' centres \[m\] (0 with fewer).
    pub apart_m: f64,
    /// The largest in-air force removed \[N\] (0: none found).
    pub air_force_n: f64,
    /// How far the tool ends from where it pressed \[m\].
    pub end_away_m: f64,
}

/// A demonstration with its in-air force removed, its contact phases and what was measured.
pub(super) struct Measured {
    /// The demonstration, its force less the in-air force.
    pub(super) demo: Demo,
    /// Its contact phases (the minor ones left out).
    pub(super) phases: Vec<ContactPhase>,
    /// The measures.
    pub(super) measures: Measures,
}

/// Finds the contact phases of a prepared demonstration and measures them.
pub(super) fn measure_demo(demo: &Demo) -> Result<Measured, String> {
    let found = contact_phases(demo);
    if found.phases.is_empty() {
        return Err(no_contact(demo, &found));
    }
    let (corrected, air_force_n) = without_air_force(demo, &found.phases);
    let mut refound = contact_phases(&corrected);
    if refound.phases.is_empty() {
        return Err(no_contact(&corrected, &refound));
    }
    let strongest = refound.phases.iter().map(|p| p.peak_n).fold(0.0, f64::max);
    refound.phases.retain(|p| p.peak_n >= MINOR_SHARE * strongest);
    let mut measures = measure(&corrected, &refound.phases);
    measures.air_force_n = air_force_n;
    Ok(Measured {
        demo: corrected,
        phases: refound.phases,
        measures,
    })
}

fn no_contact(demo: &Demo, found: &Phases) -> String {
    let peak = demo.force_n.iter().map(|f| f.norm()).fold(0.0, f64::max);
    format!(
        "no contact phase (the debiased force peaks at {peak:.2} N, under the {:.2} N a contact needs): every standard template learns a contact",
        found.on_n
    )
}

/// The samples from the first to the last at [`FIRM_SHARE`] of the way from the phase's low
/// level (the lower of its first and last 5 %: a load it starts and ends with is not contact)
/// to its peak.
fn firm_span(demo: &Demo, phase: &ContactPhase) -> std::ops::Range<usize> {
    let magnitude: Vec<f64> = demo.force_n[phase.on..phase.off].iter().map(|f| f.norm()).collect();
    let edge = (magnitude.len() / 20).max(1);
    let low = median(magnitude[..edge].to_vec()).min(median(magnitude[magnitude.len() - edge..].to_vec()));
    let threshold = low + FIRM_SHARE * (phase.peak_n - low);
    let firm = |k: &usize| demo.force_n[*k].norm() >= threshold;
    let first = (phase.on..phase.off).find(firm).unwrap_or(phase.on);
    let last = (phase.on..phase.off).rev().find(firm).unwrap_or(phase.off - 1);
    first..last + 1
}

/// The demonstration less the force it shows in the air, and the largest such force.
fn without_air_force(demo: &Demo, phases: &[ContactPhase]) -> (Demo, f64) {
    let n = demo.len();
    // Only the firmer phases say where the part is: a weak one may be the in-air load itself.
    let strongest = phases.iter().map(|p| p.peak_n).fold(0.0, f64::max);
    let spans: Vec<std::ops::Range<usize>> = phases
        .iter()
        .filter(|p| p.peak_n >= CONTACT_SHARE * strongest)
        .map(|p| firm_span(demo, p))
        .collect();
    let mut in_span = vec![false; n];
    let mut in_phase = vec![false; n];
    let mut contact_points = Vec::new();
    for span in &spans {
        in_span[span.clone()].iter_mut().for_each(|s| *s = true);
        contact_points.extend(span.clone().map(|k| demo.position_m[k]));
    }
    for phase in phases {
        in_phase[phase.on..phase.off].iter_mut().for_each(|s| *s = true);
    }
    let normal = spans
        .iter()
        .max_by_key(|span| span.len())
        .and_then(|span| normal_of(demo, span.clone()));
    let step = contact_points.len().div_ceil(CONTACT_POINTS).max(1);
    let contact_points: Vec<Vector3<f64>> = contact_points.into_iter().step_by(step).collect();
    // Outside the phases: 2 cm from every contact position. Inside one (a load that keeps the
    // phase on after the lift-off): also 2 cm off the surface, above or below every contact
    // position along the contact's normal, so a light slide before a press stays contact.
    let air: Vec<bool> = (0..n)
        .map(|k| {
            let p = demo.position_m[k];
            !in_span[k]
                && contact_points.iter().all(|c| (p - c).norm_squared() > AIR_M * AIR_M)
                && (!in_phase[k]
                    || normal.is_some_and(|normal| contact_points.iter().all(|c| (p - c).dot(&normal).abs() > AIR_M)))
        })
        .collect();
    if !air.iter().any(|a| *a) {
        return (demo.clone(), 0.0);
    }
    // The in-air force at each air sample: its mean over the air samples around it.
    let rate = (n - 1) as f64 / demo.duration_s().max(1e-9);
    let half = ((0.5 * AIR_AVERAGE_S * rate).round() as usize).max(1);
    let mut sums = vec![Vector3::zeros(); n + 1];
    let mut counts = vec![0usize; n + 1];
    for k in 0..n {
        sums[k + 1] = sums[k] + if air[k] { demo.force_n[k] } else { Vector3::zeros() };
        counts[k + 1] = counts[k] + usize::from(air[k]);
    }
    let local = |k: usize| {
        let (a, b) = (k.saturating_sub(half), (k + half + 1).min(n));
        let count = counts[b] - counts[a];
        (sums[b] - sums[a]) / count.max(1) as f64
    };
    let mut baseline = vec![Vector3::zeros(); n];
    let mut previous: Option<usize> = None;
    for k in 0..n {
        if !air[k] {
            continue;
        }
        baseline[k] = local(k);
        let from = previous.map_or(0, |p| p + 1);
        // The stretch since the previous air sample: interpolated (held before the first).
        for j in from..k {
            baseline[j] = match previous {
                Some(p) => {
                    let u = (demo.t_s[j] - demo.t_s[p]) / (demo.t_s[k] - demo.t_s[p]).max(1e-12);
                    baseline[p] * (1.0 - u) + baseline[k] * u
                }
                None => baseline[k],
            };
        }
        previous = Some(k);
    }
    if let Some(p) = previous {
        for j in p + 1..n {
            baseline[j] = baseline[p];
        }
    }
    let largest = (0..n)
        .filter(|k| air[*k])
        .map(|k| baseline[k].norm())
        .fold(0.0, f64::max);
    let mut corrected = demo.clone();
    for (f, b) in corrected.force_n.iter_mut().zip(&baseline) {
        *f -= b;
    }
    (corrected, largest)
}

/// The main direction of `points` and their extent along it.
fn extent(points: &[Vector3<f64>]) -> (Vector3<f64>, f64) {
    if points.len() < 2 {
        return (Vector3::x(), 0.0);
    }
    let centre: Vector3<f64> = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let covariance: Matrix3<f64> = points.iter().map(|p| (p - centre) * (p - centre).transpose()).sum();
    let eigen = covariance.symmetric_eigen();
    let index = eigen.eigenvalues.imax();
    let axis: Vector3<f64> = eigen.eigenvectors.column(index).into();
    let along: Vec<f64> = points.iter().map(|p| p.dot(&axis)).collect();
    let (lo, hi) = along.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(*v), hi.max(*v))
    });
    (axis, hi - lo)
}

/// `points` projected on the plane perpendicular to `normal` (unchanged without a normal).
fn in_plane(points: &[Vector3<f64>], normal: Option<Vector3<f64>>) -> Vec<Vector3<f64>> {
    match normal {
        Some(n) => points.iter().map(|p| p - n * p.dot(&n)).collect(),
        None => points.to_vec(),
    }
}

/// Reversals of the travel along `axis`: extremes the path comes back from by a quarter of the range.
fn reversals(points: &[Vector3<f64>], axis: &Vector3<f64>, range: f64) -> usize {
    if range < STILL_M {
        return 0;
    }
    let band = 0.25 * range;
    let along: Vec<f64> = points.iter().map(|p| p.dot(axis)).collect();
    let (mut high, mut low) = (along[0], along[0]);
    let mut direction = 0i8;
    let mut count = 0;
    for &s in &along {
        high = high.max(s);
        low = low.min(s);
        if direction >= 0 && s < high - band {
            if direction > 0 {
                count += 1;
            }
            direction = -1;
            low = s;
        } else if direction <= 0 && s > low + band {
            if direction < 0 {
                count += 1;
            }
            direction = 1;
            high = s;
        }
    }
    count
}

fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// The mean direction of the force over `range` (the contact's outward normal, up to sign).
fn normal_of(demo: &Demo, range: std::ops::Range<usize>) -> Option<Vector3<f64>> {
    demo.force_n[range].iter().sum::<Vector3<f64>>().try_normalize(1e-12)
}

fn measure(demo: &Demo, phases: &[ContactPhase]) -> Measures {
    let n = demo.len();
    let travel = |p: &ContactPhase| {
        let normal = normal_of(demo, firm_span(demo, p));
        extent(&in_plane(&demo.position_m[p.on..p.off], normal)).1
    };
    let per_phase: Vec<[f64; 2]> = phases.iter().map(|p| [p.duration_s(demo), travel(p)]).collect();
    let longest = (0..phases.len()).max_by(|&a, &b| per_phase[a][0].total_cmp(&per_phase[b][0]));
    let centre = |p: &ContactPhase| demo.position_m[p.on..p.off].iter().sum::<Vector3<f64>>() / (p.off - p.on) as f64;
    let apart_m = if phases.len() >= 2 {
        (centre(&phases[0]) - centre(&phases[1])).norm()
    } else {
        0.0
    };
    // The tool's distance at the end from where the last phase pressed.
    let end_away_m = phases.last().map_or(f64::INFINITY, |p| {
        let end = demo.position_m[n - 1];
        firm_span(demo, p)
            .map(|k| (demo.position_m[k] - end).norm())
            .fold(f64::INFINITY, f64::min)
    });
    let mut measures = Measures {
        phases: phases.len(),
        duration_s: 0.0,
        travel_m: 0.0,
        reversals: 0,
        turn_deg: 0.0,
        hold_share: 0.0,
        end_ratio: 1.0,
        ends_in_contact: phases.last().is_some_and(|p| p.off >= n.saturating_sub(1)) && end_away_m <= AIR_M,
        per_phase: per_phase.clone(),
        apart_m,
        air_force_n: 0.0,
        end_away_m,
    };
    let Some(index) = longest else {
        return measures;
    };
    let phase = &phases[index];
    let core = phase.on..phase.off;
    let normal = normal_of(demo, firm_span(demo, phase));
    let points = in_plane(&demo.position_m[core.clone()], normal);
    let (axis, travel) = extent(&points);
    measures.duration_s = per_phase[index][0];
    measures.travel_m = travel;
    measures.reversals = reversals(&points, &axis, travel);
    // The force without its friction: the component along the direction of travel removed
    // where the tool slides (faster than 5 mm/s over 50 ms), so the turn is the normal's.
    let rate = (n - 1) as f64 / demo.duration_s().max(1e-9);
    let half = ((0.025 * rate).round() as usize).max(1);
    let forces: Vec<Vector3<f64>> = core
        .clone()
        .map(|k| {
            let (a, b) = (k.saturating_sub(half), (k + half).min(n - 1));
            let dt = demo.t_s[b] - demo.t_s[a];
            let velocity = if dt > 0.0 {
                (demo.position_m[b] - demo.position_m[a]) / dt
            } else {
                Vector3::zeros()
            };
            let f = demo.force_n[k];
            match velocity.try_normalize(1e-12) {
                Some(direction) if velocity.norm() > 0.005 => f - direction * f.dot(&direction),
                _ => f,
            }
        })
        .collect();
    let forces = &forces[..];
    let quarter = (forces.len() / 4).max(1);
    let mean_direction = |fs: &[Vector3<f64>]| fs.iter().sum::<Vector3<f64>>().try_normalize(1e-12);
    if let (Some(first), Some(last)) = (
        mean_direction(&forces[..quarter]),
        mean_direction(&forces[forces.len() - quarter..]),
    ) {
        measures.turn_deg = first.dot(&last).clamp(-1.0, 1.0).acos().to_degrees();
    }
    let magnitude: Vec<f64> = demo.force_n[core.clone()].iter().map(|f| f.norm()).collect();
    let level = median(magnitude.clone());
    measures.hold_share = magnitude
        .iter()
        .filter(|f| (**f - level).abs() <= HOLD_BAND * level)
        .count() as f64
        / magnitude.len() as f64;
    // The end: the last fifth before the release ramp (the last 10 % of the phase) against the first half.
    let len = magnitude.len();
    let first_half = median(magnitude[..len / 2].to_vec());
    let end = median(magnitude[(len * 7 / 10)..(len * 9 / 10).max(len * 7 / 10 + 1)].to_vec());
    measures.end_ratio = if first_half > 0.0 { end / first_half } else { 1.0 };
    measures
}

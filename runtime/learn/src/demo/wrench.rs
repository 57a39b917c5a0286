//! The wrench's conventions, settled in one step before anything else is learned
//! (docs/method.md §1): the axes it is written in (base or sensor), the sensor's bias and its
//! sign (the force on the tool or the force the robot applies). Each decision is declared (by a
//! `# wrench_frame:` / `# force_sign:` line in the file or by the caller) or detected, and
//! [`WrenchReport`] says which, with the evidence.
//!
//! Order: the still, contact-free period is found first (it depends on neither decision), the
//! frame is detected on forces with that period's mean removed, the bias is then estimated in
//! the sensor's own axes and removed, sensor-frame wrenches are rotated into the base frame by
//! the flange orientation, and last the sign is checked in the base frame (it compares the force
//! with where the tool came from, so it needs base-frame forces).

use nalgebra::{UnitQuaternion, Vector3};

use super::sign::{negate_wrench, sign_evidence};
use super::Demo;

pub use skill_model::wrench::{
    BiasFinding, ForceSign, FrameEvidence, FrameFinding, FrameStatistic, Origin, SignFinding, WrenchDeclaration,
    WrenchFrame, WrenchReport, SENSOR_TURNS_DEG,
};

/// Options of [`prepare_wrench`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WrenchOptions {
    /// What the file or the caller declares.
    pub declared: WrenchDeclaration,
    /// Leave the bias in (for a file whose recorder already removed it).
    pub keep_bias: bool,
}

/// The still period is found on positions and forces averaged over this window \[s\]; 0.1 s
/// spans a whole period of the 8-12 Hz hand tremor, so the tremor averages out.
const AVERAGE_S: f64 = 0.1;
/// Slower than this the flange is still \[m/s\]; hand-guided motion is faster than 2 cm/s.
const STILL_SPEED_M_S: f64 = 0.01;
/// The flange may turn this far from its orientation at the period's start and still be still.
const STILL_TURN_RAD: f64 = 3.0 * std::f64::consts::PI / 180.0;
/// The averaged force may move this far from its value at the period's start \[N\]: a contact
/// changes it by more, sensor noise (0.1-0.5 N per sample, averaged over 0.1 s) by less.
const STILL_FORCE_N: f64 = 1.0;
/// A still period must last this long \[s\] (and hold 10 samples) to estimate a bias: ten
/// samples at 100 Hz already average the noise down to a third.
const MIN_STILL_S: f64 = 0.1;
/// A bias larger than this share of the largest debiased force looks like a contact.
const MAX_BIAS_SHARE: f64 = 0.5;
/// Samples whose force exceeds this share of the peak (and 2 N) are in contact for detection.
const CONTACT_SHARE: f64 = 0.25;
/// The least force in contact \[N\].
const CONTACT_N: f64 = 2.0;
/// Faster than this, a sample in contact is sliding \[m/s\] ...
const MOVING_M_S: f64 = 0.01;
/// ... when its travel is at least this far from the tool's axis \[°\]: a tool moving along
/// its own axis is pressing in or lifting off, and its force lies along the travel (`asin(f̂ · v̂)`
/// near ±90°, both signs in one press) whatever the frame, which says nothing about friction.
const SLIDING_FROM_AXIS_DEG: f64 = 45.0;
/// Fewest samples a statistic is computed on.
const MIN_SAMPLES: usize = 20;
/// A frame wins when its statistic is at most this share of the other's ...
const WIN_RATIO: f64 = 0.8;
/// ... and smaller by at least this much \[°\].
const WIN_MARGIN_DEG: f64 = 2.0;

/// Settles the wrench of `demo` (as read, before resampling or smoothing): finds its frame,
/// bias and sign (declared in `options` or detected), rotates sensor-frame wrenches into the
/// base frame, removes the bias and negates an applied wrench, so that the result follows the
/// convention of [`Demo`]. Never fails: what cannot be decided is assumed and reported.
pub fn prepare_wrench(demo: &Demo, options: &WrenchOptions) -> (Demo, WrenchReport) {
    let motion = Motion::of(demo);
    let still = still_period(demo, &motion);
    // For detection only: the still period's mean, removed in the file's own axes.
    let file_bias = still
        .as_ref()
        .ok()
        .map_or_else(Vector3::zeros, |range| mean(&demo.force_n[range.0..=range.1]));
    let debiased: Vec<Vector3<f64>> = demo.force_n.iter().map(|f| f - file_bias).collect();

    let frame = detect_frame(demo, &debiased, &motion, &options.declared);
    let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), frame.turn_deg.to_radians());
    let mut out = demo.clone();
    // The wrench in the sensor's axes, where a bias is constant.
    let to_sensor = |k: usize, v: &Vector3<f64>| match frame.frame {
        WrenchFrame::Sensor => *v,
        WrenchFrame::Base => demo.orientation[k].inverse_transform_vector(v),
    };
    let bias = match (options.keep_bias, still) {
        (true, _) => BiasFinding::Kept,
        (false, Err(reason)) => BiasFinding::NotRemoved { reason },
        (false, Ok((first, last))) => {
            let count = (last - first + 1) as f64;
            let force: Vector3<f64> = (first..=last)
                .map(|k| to_sensor(k, &demo.force_n[k]))
                .sum::<Vector3<f64>>()
                / count;
            let torque: Vector3<f64> = (first..=last)
                .map(|k| to_sensor(k, &demo.torque_nm[k]))
                .sum::<Vector3<f64>>()
                / count;
            let peak = debiased.iter().map(|f| f.norm()).fold(0.0, f64::max);
            if force.norm() > MAX_BIAS_SHARE * peak {
                BiasFinding::NotRemoved {
                    reason: format!(
                        "the force while still ({:.2} N, samples {first}..{last}) is more than half the largest force ({peak:.2} N): it may be a contact, not a bias",
                        force.norm()
                    ),
                }
            } else {
                BiasFinding::Removed {
                    force_n: force.into(),
                    torque_nm: torque.into(),
                    first,
                    last,
                    t_s: [demo.t_s[first], demo.t_s[last]],
                }
            }
        }
    };
    let (force_bias, torque_bias) = match &bias {
        BiasFinding::Removed { force_n, torque_nm, .. } => (Vector3::from(*force_n), Vector3::from(*torque_nm)),
        _ => (Vector3::zeros(), Vector3::zeros()),
    };
    for k in 0..out.len() {
        let rotation = demo.orientation[k];
        // Base-frame values lose the bias as it points at sample k; without one they stay as read.
        match frame.frame {
            WrenchFrame::Base => {
                out.force_n[k] = demo.force_n[k] - rotation * force_bias;
                out.torque_nm[k] = demo.torque_nm[k] - rotation * torque_bias;
            }
            WrenchFrame::Sensor => {
                out.force_n[k] = rotation * turn * (demo.force_n[k] - force_bias);
                out.torque_nm[k] = rotation * turn * (demo.torque_nm[k] - torque_bias);
            }
        }
    }

    let evidence = sign_evidence(&out);
    let sign = match options.declared.sign {
        Some(sign) => SignFinding {
            sign,
            origin: Origin::Declared,
            evidence,
        },
        None => match evidence {
            Some(found) if found.decisive() => SignFinding {
                sign: if found.cos_back < 0.0 {
                    ForceSign::Applied
                } else {
                    ForceSign::OnTool
                },
                origin: Origin::Detected,
                evidence,
            },
            _ => SignFinding {
                sign: ForceSign::OnTool,
                origin: Origin::Assumed,
                evidence,
            },
        },
    };
    if sign.sign == ForceSign::Applied {
        negate_wrench(&mut out);
    }
    (out, WrenchReport { frame, bias, sign })
}

fn mean(values: &[Vector3<f64>]) -> Vector3<f64> {
    values.iter().sum::<Vector3<f64>>() / values.len().max(1) as f64
}

/// The flange's velocity from positions averaged over [`AVERAGE_S`], differenced across that window.
struct Motion {
    /// Velocity per sample \[m/s\].
    velocity: Vec<Vector3<f64>>,
    /// Forces averaged the same way \[N\].
    force: Vec<Vector3<f64>>,
}

impl Motion {
    fn of(demo: &Demo) -> Motion {
        let n = demo.len();
        let rate = if demo.duration_s() > 0.0 {
            (n - 1) as f64 / demo.duration_s()
        } else {
            1.0
        };
        let half = ((0.5 * AVERAGE_S * rate).round() as usize).max(1);
        let position = moving_average(&demo.position_m, half);
        let force = moving_average(&demo.force_n, half);
        // Differences across the averaging window, not between neighbours: averaged positions a
        // sample apart differ by their noise over 2 ms (0.2 mm of tracker noise at 1 kHz reads
        // as 3 mm/s and more), a window apart by it over the window.
        let velocity = (0..n)
            .map(|k| {
                let (a, b) = (k.saturating_sub(half), (k + half).min(n.saturating_sub(1)));
                let dt = demo.t_s[b] - demo.t_s[a];
                if dt > 0.0 {
                    (position[b] - position[a]) / dt
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        Motion { velocity, force }
    }
}

/// A moving average over `half` samples on each side, the window kept inside the data (so the
/// ends average as many samples as the middle, one-sided).
fn moving_average(values: &[Vector3<f64>], half: usize) -> Vec<Vector3<f64>> {
    let n = values.len();
    let width = (2 * half + 1).min(n);
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(Vector3::zeros());
    for v in values {
        let last = prefix[prefix.len() - 1];
        prefix.push(last + v);
    }
    (0..n)
        .map(|k| {
            let start = k.saturating_sub(half).min(n - width);
            (prefix[start + width] - prefix[start]) / width as f64
        })
        .collect()
}

/// The still, contact-free period a bias is estimated on: the run of samples from the first
/// (else, failing that, up to the last) in which the averaged flange moves slower than 1 cm/s,
/// turns less than 3° and its averaged force stays within 1 N of where the run began. It must
/// last [`MIN_STILL_S`] and 10 samples, and its force must not repeat exactly (a sensor that
/// stopped streaming). Returns its first and last sample, or why there is none.
fn still_period(demo: &Demo, motion: &Motion) -> Result<(usize, usize), String> {
    let n = demo.len();
    if n < 10 {
        return Err(format!("{n} samples are too few to find a still period"));
    }
    let run_from = |order: &mut dyn Iterator<Item = usize>| -> Vec<usize> {
        let mut taken = Vec::new();
        let mut reference = None;
        for k in order {
            let (q0, f0) = *reference.get_or_insert((demo.orientation[k], motion.force[k]));
            if motion.velocity[k].norm() >= STILL_SPEED_M_S
                || demo.orientation[k].angle_to(&q0) >= STILL_TURN_RAD
                || (motion.force[k] - f0).norm() >= STILL_FORCE_N
            {
                break;
            }
            taken.push(k);
        }
        taken
    };
    let check = |run: Vec<usize>, end: &str| -> Result<(usize, usize), String> {
        let (Some(&a), Some(&b)) = (run.iter().min(), run.iter().max()) else {
            return Err(format!("the flange moves or the force changes at once at the {end}"));
        };
        let lasts = demo.t_s[b] - demo.t_s[a];
        if run.len() < 10 || lasts < MIN_STILL_S {
            return Err(format!(
                "the flange is still and the force steady for only {lasts:.2} s at the {end} ({} samples)",
                run.len()
            ));
        }
        let repeated = (a + 1..=b).filter(|&k| demo.force_n[k] == demo.force_n[k - 1]).count();
        if 2 * repeated > b - a {
            return Err(format!(
                "the force repeats exactly in {repeated} of the {} steps of the still period {a}..{b} at the {end}: the sensor was not streaming",
                b - a
            ));
        }
        Ok((a, b))
    };
    let start = check(run_from(&mut (0..n)), "start");
    start.or_else(|at_start| {
        check(run_from(&mut (0..n).rev()), "end")
            .map_err(|at_end| format!("no still, contact-free period of {MIN_STILL_S} s: {at_start}; {at_end}"))
    })
}

/// Decides the frame of the file's wrench and, for a sensor frame, the sensor's turn about the
/// tool axis: what `declared` leaves open is detected from `force` (the file's columns with the
/// still period's mean removed) by the statistics of [`FrameStatistic`] (docs/method.md §1).
/// A reading wins when its statistic is at most 0.8 times the other's and 2° smaller; when
/// neither wins, the base frame (or no turn) is assumed.
fn detect_frame(demo: &Demo, force: &[Vector3<f64>], motion: &Motion, declared: &WrenchDeclaration) -> FrameFinding {
    let peak = force.iter().map(|f| f.norm()).fold(0.0, f64::max);
    let threshold = CONTACT_N.max(CONTACT_SHARE * peak);
    let contact: Vec<usize> = (0..force.len()).filter(|&k| force[k].norm() >= threshold).collect();
    // The tool's axis is the flange's z in the base frame whatever the columns' frame.
    let across_axis = SLIDING_FROM_AXIS_DEG.to_radians().cos();
    let moving: Vec<usize> = contact
        .iter()
        .copied()
        .filter(|&k| {
            let v = motion.velocity[k];
            let axis = demo.orientation[k] * Vector3::z();
            v.norm() >= MOVING_M_S && v.normalize().dot(&axis).abs() <= across_axis
        })
        .collect();
    // The force at sample k read as base axes (`None`) or as sensor axes turned by `turn`.
    let in_base = |k: usize, turn: Option<f64>| match turn {
        None => force[k],
        Some(deg) => {
            demo.orientation[k] * (UnitQuaternion::from_axis_angle(&Vector3::z_axis(), deg.to_radians()) * force[k])
        }
    };
    let statistic = |turn: Option<f64>, kind: FrameStatistic| -> f64 {
        match kind {
            FrameStatistic::LeanSpread => {
                let lean: Vec<f64> = moving
                    .iter()
                    .map(|&k| {
                        let f = in_base(k, turn);
                        let v = motion.velocity[k];
                        (f.dot(&v) / (f.norm() * v.norm())).clamp(-1.0, 1.0).asin().to_degrees()
                    })
                    .collect();
                mad_spread(&lean)
            }
            FrameStatistic::DirectionSpread => {
                let units: Vec<Vector3<f64>> = contact.iter().map(|&k| in_base(k, turn).normalize()).collect();
                let centre = mean(&units).normalize();
                let mut angles: Vec<f64> = units
                    .iter()
                    .map(|u| u.dot(&centre).clamp(-1.0, 1.0).acos().to_degrees())
                    .collect();
                median(&mut angles)
            }
        }
    };
    let kind = if moving.len() >= MIN_SAMPLES {
        Some((FrameStatistic::LeanSpread, moving.len()))
    } else if contact.len() >= MIN_SAMPLES {
        Some((FrameStatistic::DirectionSpread, contact.len()))
    } else {
        None
    };
    let evidence = kind.map(|(kind, samples)| FrameEvidence {
        statistic: kind,
        samples,
        base_deg: statistic(None, kind),
        sensor_deg: SENSOR_TURNS_DEG.map(|deg| statistic(Some(deg), kind)),
    });
    let wins = |mine: f64, theirs: f64| mine <= WIN_RATIO * theirs && theirs - mine >= WIN_MARGIN_DEG;
    // The best turn, and whether it beats reading the sensor's axes as the flange's.
    let best_turn = evidence.map(|e| {
        let best = (0..4).fold(0, |best, i| if e.sensor_deg[i] < e.sensor_deg[best] { i } else { best });
        (best, best == 0 || wins(e.sensor_deg[best], e.sensor_deg[0]))
    });
    let (frame, origin) = match (declared.frame, evidence) {
        (Some(frame), _) => (frame, Origin::Declared),
        (None, Some(e)) => {
            let sensor = match declared.sensor_turn_deg {
                Some(deg) => statistic(Some(deg), e.statistic),
                None => best_turn.map_or(e.sensor_deg[0], |(best, _)| e.sensor_deg[best]),
            };
            if wins(sensor, e.base_deg) {
                (WrenchFrame::Sensor, Origin::Detected)
            } else if wins(e.base_deg, sensor) {
                (WrenchFrame::Base, Origin::Detected)
            } else {
                (WrenchFrame::Base, Origin::Assumed)
            }
        }
        (None, None) => (WrenchFrame::Base, Origin::Assumed),
    };
    let (turn_deg, turn_origin) = match (frame, declared.sensor_turn_deg, best_turn) {
        (WrenchFrame::Base, _, _) => (0.0, Origin::Assumed),
        (WrenchFrame::Sensor, Some(deg), _) => (deg, Origin::Declared),
        (WrenchFrame::Sensor, None, Some((best, true))) => (SENSOR_TURNS_DEG[best], Origin::Detected),
        (WrenchFrame::Sensor, None, _) => (0.0, Origin::Assumed),
    };
    FrameFinding {
        frame,
        origin,
        turn_deg,
        turn_origin,
        evidence,
    }
}

/// `1.4826 × median |x − median x|`: the standard deviation of normal data, robust to outliers.
fn mad_spread(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    let centre = median(&mut sorted);
    let mut deviations: Vec<f64> = values.iter().map(|v| (v - centre).abs()).collect();
    1.4826 * median(&mut deviations)
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_moving_average_keeps_lines_and_its_ends() {
        let line: Vec<Vector3<f64>> = (0..20).map(|k| Vector3::new(k as f64, 2.0, -(k as f64))).collect();
        let averaged = moving_average(&line, 3);
        // A centred window keeps a line; the one-sided windows at the ends average 7 samples too.
        for k in 3..17 {
            assert!((averaged[k] - line[k]).norm() < 1e-12);
        }
        assert!((averaged[0] - Vector3::new(3.0, 2.0, -3.0)).norm() < 1e-12);
        assert!((averaged[19] - Vector3::new(16.0, 2.0, -16.0)).norm() < 1e-12);
    }

    #[test]
    fn the_spread_ignores_outliers() {
        // 0, 1, ..., 100: the median is 50 and half the values lie within 25 of it.
        let mut values: Vec<f64> = (0..=100).map(f64::from).collect();
        assert!((mad_spread(&values) - 1.4826 * 25.0).abs() < 1e-9);
        values[0] = 1e6;
        assert!(
            (mad_spread(&values) - 1.4826 * 25.0).abs() < 1.5,
            "{}",
            mad_spread(&values)
        );
    }

    #[test]
    fn declarations_parse_as_the_flags_write_them() {
        assert_eq!("Sensor".parse::<WrenchFrame>(), Ok(WrenchFrame::Sensor));
        assert_eq!("base".parse::<WrenchFrame>(), Ok(WrenchFrame::Base));
        assert_eq!("on_tool".parse::<ForceSign>(), Ok(ForceSign::OnTool));
        assert_eq!("applied".parse::<ForceSign>(), Ok(ForceSign::Applied));
        assert!("tool0".parse::<WrenchFrame>().is_err());
        let file = WrenchDeclaration {
            frame: Some(WrenchFrame::Sensor),
            sign: Some(ForceSign::Applied),
            sensor_turn_deg: Some(90.0),
        };
        let flags = WrenchDeclaration {
            sign: Some(ForceSign::OnTool),
            ..WrenchDeclaration::default()
        };
        assert_eq!(
            flags.or(file),
            WrenchDeclaration {
                frame: Some(WrenchFrame::Sensor),
                sign: Some(ForceSign::OnTool),
                sensor_turn_deg: Some(90.0),
            }
        );
    }
}

//! Checks of a demonstration's time column: a sample rate no recorder produces (time written in
//! the wrong unit) and gaps (docs/method.md §1).

use super::{Demo, DemoError, DemoWarning};

/// Slowest plausible median sample rate \[Hz\]. Hand-guided motion carries content up to about
/// 5-10 Hz; below 10 Hz a recorder cannot capture it at all (Nyquist), so such a rate means
/// the time column is not in seconds (1 kHz written in milliseconds reads as 1 Hz).
pub const MIN_RATE_HZ: f64 = 10.0;

/// Fastest plausible median sample rate \[Hz\]. Robot controllers and F/T sensors stream at
/// 100 Hz .. 10 kHz; a rate above 100 kHz means the time column is not in seconds (e.g. minutes
/// or hours), or the file repeats rows with nearly equal times.
pub const MAX_RATE_HZ: f64 = 100_000.0;

/// A step longer than this many median steps is a gap: jitter of a real-time loop stays
/// within a few periods, dropped samples or a paused recording do not.
pub const GAP_FACTOR: f64 = 10.0;

/// A gap longer than this is an error, shorter ones a warning \[s\]. 0.1 s is half a period at
/// 5 Hz, where hand-guided motion still carries its energy: across a longer hole the motion in
/// between is unknown, and every primitive would learn the straight line drawn across it.
pub const GAP_ERROR_S: f64 = 0.1;

/// The median of the steps between consecutive samples \[s\] (0 for fewer than two samples).
pub fn median_step_s(t_s: &[f64]) -> f64 {
    let mut steps: Vec<f64> = t_s.windows(2).map(|pair| pair[1] - pair[0]).collect();
    if steps.is_empty() {
        return 0.0;
    }
    let mid = steps.len() / 2;
    let (_, median, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    *median
}

/// Checks the time column of `demo` (strictly increasing, as the reader guarantees).
///
/// Errors: a median rate outside [`MIN_RATE_HZ`]..[`MAX_RATE_HZ`] (with the unit the column
/// probably is in), a step above `GAP_FACTOR` median steps that is also longer than
/// [`GAP_ERROR_S`] (naming its rows). Shorter such steps are a warning.
pub fn check_timing(demo: &Demo) -> Result<Vec<DemoWarning>, DemoError> {
    let t = &demo.t_s;
    if t.len() < 2 {
        return Ok(Vec::new());
    }
    let median = median_step_s(t);
    let rate_hz = 1.0 / median;
    if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
        return Err(DemoError::TimeUnit {
            file: demo.source.clone(),
            median_step: median,
            hint: unit_hint(median),
        });
    }
    let limit = GAP_FACTOR * median;
    let mut gaps = t
        .windows(2)
        .enumerate()
        .filter(|(_, pair)| pair[1] - pair[0] > limit)
        .map(|(k, pair)| (k, pair[1] - pair[0]));
    let Some(first) = gaps.next() else {
        return Ok(Vec::new());
    };
    let all: Vec<(usize, f64)> = std::iter::once(first).chain(gaps).collect();
    // Rows are data rows, 1-based: sample k is data row k + 1.
    if let Some(&(k, step)) = all.iter().find(|(_, step)| *step > GAP_ERROR_S) {
        return Err(DemoError::TimeGap {
            file: demo.source.clone(),
            row: k + 1,
            from_s: t[k],
            to_s: t[k + 1],
            step_s: step,
            median_step_s: median,
            count: all.iter().filter(|(_, step)| *step > GAP_ERROR_S).count(),
        });
    }
    let largest = all.iter().map(|(_, step)| *step).fold(0.0, f64::max);
    Ok(vec![DemoWarning::TimeSteps {
        file: demo.source.clone(),
        count: all.len(),
        first_row: all[0].0 + 1,
        largest_step_s: largest,
        median_step_s: median,
    }])
}

/// What the time column probably is in, judged from its median step.
fn unit_hint(median: f64) -> String {
    let rate = 1.0 / median;
    if rate < MIN_RATE_HZ {
        for (unit, scale) in [("milliseconds", 1e-3), ("microseconds", 1e-6), ("nanoseconds", 1e-9)] {
            let scaled = 1.0 / (median * scale);
            if (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&scaled) {
                return format!(
                    "it looks like {unit} (that would be {scaled:.0} Hz): convert `t` to seconds (multiply by {scale:e})"
                );
            }
        }
        "convert `t` to seconds".to_owned()
    } else {
        "is `t` in seconds? Convert it, or drop repeated rows".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{UnitQuaternion, Vector3};

    use super::*;

    fn demo_at(t_s: Vec<f64>) -> Demo {
        let n = t_s.len();
        Demo {
            source: "demo.csv".into(),
            t_s,
            position_m: vec![Vector3::zeros(); n],
            orientation: vec![UnitQuaternion::identity(); n],
            force_n: vec![Vector3::zeros(); n],
            torque_nm: vec![Vector3::zeros(); n],
        }
    }

    #[test]
    fn even_and_jittered_time_passes() {
        let t: Vec<f64> = (0..500).map(|k| k as f64 * 0.01 + 0.002 * ((k % 3) as f64)).collect();
        assert_eq!(check_timing(&demo_at(t)).expect("plausible").len(), 0);
    }

    #[test]
    fn time_in_microseconds_or_milliseconds_is_named() {
        let micro: Vec<f64> = (0..500).map(|k| k as f64 * 1000.0).collect();
        let err = check_timing(&demo_at(micro)).expect_err("microseconds");
        let text = err.to_string();
        assert!(matches!(err, DemoError::TimeUnit { .. }));
        assert!(text.contains("microseconds") && text.contains("1000 Hz"), "{text}");
        let milli: Vec<f64> = (0..500).map(|k| k as f64 * 10.0).collect();
        let text = check_timing(&demo_at(milli)).expect_err("milliseconds").to_string();
        assert!(text.contains("milliseconds") && text.contains("100 Hz"), "{text}");
        let hours: Vec<f64> = (0..500).map(|k| k as f64 * 1e-3 / 3600.0).collect();
        assert!(check_timing(&demo_at(hours)).is_err());
    }

    #[test]
    fn a_gap_names_its_rows_and_dropped_samples_warn() {
        let mut t: Vec<f64> = (0..3000).map(|k| k as f64 * 0.001).collect();
        for value in &mut t[2000..] {
            *value += 10.0;
        }
        let err = check_timing(&demo_at(t)).expect_err("a 10 s gap");
        let text = err.to_string();
        assert!(text.contains("rows 2000 and 2001"), "{text}");
        let mut t: Vec<f64> = (0..3000).map(|k| k as f64 * 0.001).collect();
        t.drain(1000..1020);
        let warnings = check_timing(&demo_at(t)).expect("a 21 ms hole is a warning");
        assert!(warnings[0].to_string().contains("row 1000"), "{}", warnings[0]);
    }
}

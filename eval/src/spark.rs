//! The report's small per-skill chart: the force along the compliant z against its target over
//! the worst trial, as an inline SVG in the first screen's summary line.

use std::fmt::Write;

use skill_runtime::exec::RunLog;

use super::Outcome;

/// The chart's size in CSS pixels.
const WIDTH: f64 = 200.0;
const HEIGHT: f64 = 30.0;

/// Room for the axis labels \[px\]: left of the plot and below it.
const LEFT: f64 = 30.0;
const BOTTOM: f64 = 9.0;

/// Points per line: one per column of pixels is as much as the eye can use.
const POINTS: usize = 150;

/// The trial a skill's or task's chart shows: a failed one first (the first failed, as the
/// failures list has it), else the one with the largest force RMS, else the one nearest its peak
/// bound. `None` when no trial has ticks to draw.
pub(super) fn worst<'a>(trials: &[&'a Outcome]) -> Option<&'a Outcome> {
    let drawable: Vec<&Outcome> = trials.iter().copied().filter(|o| tick_count(o) > 1).collect();
    if let Some(failed) = drawable.iter().find(|o| o.result.error || !o.result.success) {
        return Some(failed);
    }
    let share = |o: &Outcome| {
        o.result
            .peak_bound_n
            .map_or(0.0, |b| o.result.peak_force_n / b.max(1e-9))
    };
    drawable.into_iter().max_by(|a, b| {
        let rms = |o: &Outcome| o.result.force_rms_rel.unwrap_or(f64::NEG_INFINITY);
        rms(a).total_cmp(&rms(b)).then(share(a).total_cmp(&share(b)))
    })
}

fn tick_count(outcome: &Outcome) -> usize {
    logs(outcome).map(|log| log.ticks.len()).sum()
}

/// A trial's logs in time order: its own, or a task's steps'.
fn logs(outcome: &Outcome) -> impl Iterator<Item = &RunLog> {
    std::iter::once(&outcome.log)
        .filter(|log| !log.ticks.is_empty())
        .chain(outcome.step_logs.iter())
}

/// The chart of `outcome`: measured force along the compliant z (blue) and its desired value
/// (black, dashed) against time, the force axis from 0 (or the lowest force) to the highest,
/// labelled in N and s; a tooltip names the trial. Lines are thinned to [`POINTS`] points, each
/// the extreme of its stretch of ticks that is furthest from zero (a peak survives the
/// thinning).
pub(super) fn chart(outcome: &Outcome) -> String {
    let ticks: Vec<(f64, f64, f64)> = logs(outcome)
        .flat_map(|log| log.ticks.iter())
        .map(|tick| (tick.t_s, tick.wrench_cf[2], tick.desired_cf[2]))
        .filter(|(t, m, d)| t.is_finite() && m.is_finite() && d.is_finite())
        .collect();
    let (Some(first), Some(last)) = (ticks.first(), ticks.last()) else {
        return String::new();
    };
    let (t0, t1) = (first.0, last.0.max(first.0 + 1e-9));
    let high = ticks.iter().map(|(_, m, d)| m.max(*d)).fold(1.0_f64, f64::max);
    let low = ticks.iter().map(|(_, m, d)| m.min(*d)).fold(0.0_f64, f64::min);
    let x = |t: f64| LEFT + (t - t0) / (t1 - t0) * (WIDTH - LEFT - 1.0);
    let y = |f: f64| 1.0 + (high - f) / (high - low) * (HEIGHT - BOTTOM - 2.0);
    let line = |pick: fn(&(f64, f64, f64)) -> f64| {
        let mut points = String::new();
        let stride = ticks.len().div_ceil(POINTS).max(1);
        for chunk in ticks.chunks(stride) {
            let extreme = chunk
                .iter()
                .max_by(|a, b| pick(a).abs().total_cmp(&pick(b).abs()))
                .expect("chunks are not empty");
            let _ = write!(points, "{:.1},{:.1} ", x(extreme.0), y(pick(extreme)));
        }
        points
    };
    let r = &outcome.result;
    let mut svg = String::new();
    let _ = write!(
        svg,
        "<svg class=spark width=\"{WIDTH}\" height=\"{HEIGHT}\" viewBox=\"0 0 {WIDTH} {HEIGHT}\" role=img aria-label=\"force along the compliant z against its target, {}\">",
        super::report::escape(&format!("{} {} ({})", r.skill, r.variant, r.mode))
    );
    let _ = write!(
        svg,
        "<title>{}: measured force (blue) and its target (black, dashed) along the compliant z</title>",
        super::report::escape(&format!("{} {} ({})", r.skill, r.variant, r.mode))
    );
    // Axes: the zero line, and the labels of the force range and the duration.
    let _ = write!(
        svg,
        "<line x1=\"{LEFT}\" y1=\"{z:.1}\" x2=\"{WIDTH}\" y2=\"{z:.1}\" stroke=\"#bbb\" stroke-width=\"0.5\"/>",
        z = y(0.0)
    );
    // A low end that rounds to zero is labelled 0, not -0.
    let newtons = |f: f64| format!("{:.0} N", if f.abs() < 0.5 { 0.0 } else { f });
    let _ = write!(
        svg,
        "<text x=\"{}\" y=\"7\" font-size=\"7\" text-anchor=end>{}</text><text x=\"{}\" y=\"{:.1}\" font-size=\"7\" text-anchor=end>{}</text>",
        LEFT - 2.0,
        newtons(high),
        LEFT - 2.0,
        HEIGHT - BOTTOM,
        newtons(low)
    );
    let _ = write!(
        svg,
        "<text x=\"{LEFT}\" y=\"{:.1}\" font-size=\"7\">0</text><text x=\"{WIDTH}\" y=\"{:.1}\" font-size=\"7\" text-anchor=end>{:.1} s</text>",
        HEIGHT - 1.0,
        HEIGHT - 1.0,
        t1 - t0
    );
    let _ = write!(
        svg,
        "<polyline fill=none stroke=\"#000\" stroke-width=\"1\" stroke-dasharray=\"3 2\" points=\"{}\"/>",
        line(|t| t.2)
    );
    let _ = write!(
        svg,
        "<polyline fill=none stroke=\"#1f6fd0\" stroke-width=\"1\" points=\"{}\"/>",
        line(|t| t.1)
    );
    svg.push_str("</svg>");
    svg
}

#[cfg(test)]
mod tests {
    use skill_runtime::exec::{JointValues, Tick};

    use super::*;

    fn tick(t_s: f64, measured: f64, desired: f64) -> Tick {
        let mut wrench_cf = [0.0; 6];
        wrench_cf[2] = measured;
        let mut desired_cf = [0.0; 6];
        desired_cf[2] = desired;
        Tick {
            t_s,
            state: 0,
            desired: [0.0; 7],
            measured: [0.0; 7],
            wrench_base: [0.0; 6],
            wrench_cf,
            desired_cf,
            frame: [1.0, 0.0, 0.0, 0.0],
            selection: 0,
            torques: JointValues::from_slices(&[]),
            joint_state: JointValues::from_slices(&[]),
        }
    }

    /// A trial named `variant` whose log holds `ticks` at 1 kHz of a force ramp up to `peak`.
    fn trial(variant: &str, ticks: usize, peak: f64, rms: Option<f64>, success: bool) -> Outcome {
        let mut outcome = Outcome::error("press", variant, "skill", Vec::new(), String::new());
        outcome.result.error = false;
        outcome.result.success = success;
        outcome.result.reason = (!success).then(|| "reflex".to_string());
        outcome.result.force_rms_rel = rms;
        for i in 0..ticks {
            let share = i as f64 / ticks.max(1) as f64;
            outcome
                .log
                .ticks
                .push(tick(i as f64 * 1e-3, peak * share, 0.9 * peak * share));
        }
        outcome
    }

    /// The polylines' points, parsed back from the SVG: (x, y) pairs per line.
    fn polylines(svg: &str) -> Vec<Vec<(f64, f64)>> {
        svg.split("points=\"")
            .skip(1)
            .map(|rest| {
                rest.split('"')
                    .next()
                    .unwrap()
                    .split_whitespace()
                    .map(|pair| {
                        let (x, y) = pair.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn a_failed_trial_is_the_worst_else_the_largest_rms() {
        let good = trial("default", 100, 10.0, Some(0.02), true);
        let rough = trial("stiff", 100, 10.0, Some(0.04), true);
        let failed = trial("far", 100, 10.0, Some(0.01), false);
        let empty = trial("empty", 0, 10.0, Some(0.09), false);
        assert_eq!(worst(&[&good, &rough]).unwrap().result.variant, "stiff");
        assert_eq!(worst(&[&good, &failed, &rough]).unwrap().result.variant, "far");
        // A trial with nothing to draw is never chosen, even when it failed.
        assert_eq!(worst(&[&empty, &good]).unwrap().result.variant, "default");
        assert!(worst(&[&empty]).is_none());
    }

    #[test]
    fn the_chart_thins_to_its_point_budget_and_keeps_the_peak() {
        let mut outcome = trial("default", 5000, 10.0, Some(0.02), true);
        // A one-tick spike in the middle must survive thinning 5000 ticks to 150 points.
        outcome.log.ticks[2500].wrench_cf[2] = 30.0;
        let svg = chart(&outcome);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        assert!(
            svg.contains("30 N"),
            "the force axis is labelled with the highest force: {svg}"
        );
        assert!(svg.contains("5.0 s"), "the time axis is labelled with the duration");
        assert!(
            svg.contains(">0 N<") && !svg.contains("-0 N"),
            "the low end of a ramp from 0 is 0 N"
        );
        let lines = polylines(&svg);
        assert_eq!(lines.len(), 2, "target and measured");
        for line in &lines {
            assert!(
                line.len() <= POINTS && line.len() >= POINTS - 5,
                "{} points",
                line.len()
            );
            for &(x, y) in line {
                assert!(
                    (LEFT..=WIDTH).contains(&x) && (0.0..=HEIGHT - BOTTOM).contains(&y),
                    "({x}, {y})"
                );
            }
        }
        // The measured line's highest point (smallest y) is at the top of the plot: the spike.
        let top = lines[1].iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert!((top - 1.0).abs() < 0.06, "spike drawn at y = {top}");
        // Time runs left to right.
        assert!(lines[1].windows(2).all(|w| w[0].0 < w[1].0));
    }

    #[test]
    fn a_trial_without_ticks_draws_nothing_and_names_are_escaped() {
        assert!(chart(&trial("none", 0, 1.0, None, true)).is_empty());
        let mut outcome = trial("<b>&", 10, 5.0, None, true);
        outcome.result.skill = "a\"b".to_string();
        let svg = chart(&outcome);
        assert!(!svg.contains("<b>") && svg.contains("&lt;b&gt;&amp;"), "{svg}");
    }
}

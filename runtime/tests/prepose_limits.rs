//! Pre-positioning obeys the run's limits (issue 25, item 4): the guarded move to the
//! demonstrated start stays within `--limit speed=…`, a skill's `limits { speed: … }` and a
//! slower `--speed`, instead of moving at its own 8 cm/s (a minimum-jerk peak of 15 cm/s).

mod support;

use skill_ir as ir;
use skill_runtime::exec::{ExecOptions, RunLog, RunReport};
use support::{learn, run, span, Touch};

/// The largest tool-point speed over the ticks of state `state` (from the logged positions), and
/// how many ticks it ran.
fn peak_speed(log: &RunLog, state: &str) -> (f64, usize) {
    let Some(index) = log.states.iter().position(|name| name == state) else {
        return (0.0, 0);
    };
    let ticks: Vec<_> = log.ticks.iter().filter(|tick| tick.state as usize == index).collect();
    let peak = ticks
        .windows(2)
        .map(|pair| {
            let (a, b) = (&pair[0].measured, &pair[1].measured);
            let dt = pair[1].t_s - pair[0].t_s;
            ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt() / dt
        })
        .fold(0.0, f64::max);
    (peak, ticks.len())
}

fn touch(limits: Vec<ir::Limit>) -> ir::Skill {
    support::touch(Touch {
        limits,
        ..Touch::default()
    })
}

fn speed_limit(value: f64) -> ir::Limit {
    ir::Limit {
        name: "speed".into(),
        value_si: Some(value),
        doc: String::new(),
        span: span(),
    }
}

fn no_reflex(report: &RunReport) {
    assert!(report.reflex.is_none(), "a reflex stopped the run: {}", report.message);
}

#[test]
fn prepose_stays_within_a_speed_limit_from_the_command_line() {
    let skill = touch(Vec::new());
    let learned = learn(&skill);
    let (_, free) = run(&skill, &learned, &ExecOptions::default());
    let (free_peak, _) = peak_speed(&free, "prepose");
    // The case of the issue: the default move peaks above 6 cm/s, so the limit binds.
    assert!(
        free_peak > 0.06,
        "the default pre-positioning peaks at {free_peak:.4} m/s"
    );
    let options = ExecOptions {
        limits: vec![("speed".into(), 0.06)],
        ..ExecOptions::default()
    };
    let (report, log) = run(&skill, &learned, &options);
    no_reflex(&report);
    let (peak, _) = peak_speed(&log, "prepose");
    assert!(
        peak <= 0.06,
        "pre-positioning peaked at {peak:.4} m/s under a 0.06 m/s limit"
    );
}

#[test]
fn prepose_stays_within_the_skills_own_speed_limit() {
    let skill = touch(vec![speed_limit(0.04)]);
    let learned = learn(&skill);
    let (report, log) = run(&skill, &learned, &ExecOptions::default());
    no_reflex(&report);
    let (peak, _) = peak_speed(&log, "prepose");
    assert!(
        peak <= 0.04,
        "pre-positioning peaked at {peak:.4} m/s under the skill's 0.04 m/s"
    );
}

#[test]
fn prepose_slows_with_the_speed_factor() {
    let skill = touch(Vec::new());
    let learned = learn(&skill);
    let (_, normal) = run(&skill, &learned, &ExecOptions::default());
    let mut slow = ExecOptions::default();
    slow.overrides.speed_factor = 0.5;
    let (report, half) = run(&skill, &learned, &slow);
    no_reflex(&report);
    let (normal_peak, normal_ticks) = peak_speed(&normal, "prepose");
    let (half_peak, half_ticks) = peak_speed(&half, "prepose");
    // The move takes twice as long (the 0.3 s hold is the same) at about half the speed.
    assert!(
        half_ticks as f64 >= 1.9 * (normal_ticks as f64 - 300.0) + 300.0,
        "prepose {half_ticks} ticks at --speed 0.5 against {normal_ticks}"
    );
    assert!(
        half_peak <= 0.55 * normal_peak,
        "prepose peaked at {half_peak:.4} m/s at --speed 0.5 against {normal_peak:.4}"
    );
}

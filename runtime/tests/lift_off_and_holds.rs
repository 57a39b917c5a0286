//! A state's declared `lift off D at V` and guards that must hold for a while (`G for D`), run in
//! the simulated table scene with the standard touch written out as IR (tests/support).
//!
//! The touch's `retract` is entered from force control in contact, so it lifts off before its
//! learned return: by default 1 cm at 25 mm/s, as declared 2 cm at 10 mm/s, or not at all with
//! `lift off 0 mm`. A held guard fires no earlier than its duration after its guard began to hold
//! and starts counting again whenever its guard drops.

mod support;

use nalgebra::Vector3;
use skill_ir as ir;
use skill_runtime::exec::{ExecOptions, RunLog, RunReport};
use support::{learn, run, Touch, CONTACT_Z};

fn held(guard: ir::Guard, duration_s: f64) -> ir::Guard {
    ir::Guard::Held {
        guard: Box::new(guard),
        duration_s,
    }
}

/// A run of the touch as `spec` says, which must succeed.
fn touch_run(spec: Touch) -> (RunReport, RunLog) {
    let skill = support::touch(spec);
    let learned = learn(&skill);
    let (report, log) = run(&skill, &learned, &ExecOptions::default());
    assert_eq!(report.outcome, ir::Outcome::Success, "{}", report.message);
    (report, log)
}

/// How long the run stayed in `state` \[s\] (its one visit).
fn time_in(report: &RunReport, state: &str) -> f64 {
    let visit = report
        .visits
        .iter()
        .find(|visit| visit.state == state)
        .unwrap_or_else(|| panic!("`{state}` was visited: {:?}", report.visits));
    visit.exit_s - visit.enter_s
}

/// The `retract` state's ticks, measured from where it was entered.
struct Retract {
    /// Time since entry \[s\].
    t_s: Vec<f64>,
    /// Unit direction away from the surface: against the force applied at entry, base frame.
    away: Vector3<f64>,
    /// Commanded tool point minus the measured tool point at entry \[m\], base frame.
    commanded: Vec<Vector3<f64>>,
    /// Measured tool point minus the measured tool point at entry \[m\], base frame.
    measured: Vec<Vector3<f64>>,
}

impl Retract {
    fn of(log: &RunLog) -> Self {
        let state = log.states.iter().position(|s| s == "retract").expect("the retract ran") as u32;
        let ticks: Vec<_> = log.ticks.iter().filter(|tick| tick.state == state).collect();
        let first = ticks.first().expect("retract ticks");
        let position = |p: &[f64; 7]| Vector3::new(p[0], p[1], p[2]);
        let from = position(&first.measured);
        let force = Vector3::new(first.wrench_base[0], first.wrench_base[1], first.wrench_base[2]);
        assert!(force.norm() > 1.0, "entered in contact: {force:?} N");
        Retract {
            t_s: ticks.iter().map(|tick| tick.t_s - first.t_s).collect(),
            away: -force.normalize(),
            commanded: ticks.iter().map(|tick| position(&tick.desired) - from).collect(),
            measured: ticks.iter().map(|tick| position(&tick.measured) - from).collect(),
        }
    }

    /// How far `offset` is along the normal, and across it \[m\].
    fn split(&self, offset: &Vector3<f64>) -> (f64, f64) {
        let along = offset.dot(&self.away);
        (along, (offset - self.away * along).norm())
    }

    /// The first tick at `t_s` or later.
    fn at(&self, t_s: f64) -> usize {
        self.t_s
            .iter()
            .position(|t| *t >= t_s - 1e-9)
            .expect("the state lasted that long")
    }
}

#[test]
fn a_declared_lift_off_lifts_that_far_that_fast_before_the_return_and_zero_does_not_lift() {
    let lift = |distance_m, speed_mps| Touch {
        lift_off: Some(ir::LiftOffSpec { distance_m, speed_mps }),
        ..Touch::default()
    };
    let (declared, log) = touch_run(lift(0.02, 0.01));
    let retract = Retract::of(&log);

    // The commanded tool rises along the normal at 10 mm/s, straight: the motion waits.
    let done = (0..retract.t_s.len())
        .find(|&k| retract.split(&retract.commanded[k]).0 >= 0.02 - 1e-9)
        .expect("the lift completes");
    let lift_s = retract.t_s[done];
    let widest = (0..=done)
        .map(|k| retract.split(&retract.commanded[k]).1)
        .fold(0.0, f64::max);
    let half = retract.split(&retract.commanded[retract.at(1.0)]).0;
    // The measured tool follows: how far it rose and how fast in the middle of the lift.
    let (risen, _) = retract.split(&retract.measured[done]);
    let (k0, k1) = (retract.at(0.5), retract.at(1.5));
    let measured_speed = (retract.split(&retract.measured[k1]).0 - retract.split(&retract.measured[k0]).0)
        / (retract.t_s[k1] - retract.t_s[k0]);
    // Then the learned return moves on from the lifted pose.
    let last = retract.commanded.len() - 1;
    let moved_on = (retract.commanded[last] - retract.away * 0.02).norm();
    let lowest = retract
        .commanded
        .iter()
        .map(|offset| retract.split(offset).0)
        .fold(f64::INFINITY, f64::min);
    eprintln!(
        "lift off 2 cm at 10 mm/s: commanded 2 cm after {lift_s:.3} s ({:.2} mm at 1 s), at most \
         {:.3} mm across; measured {:.1} mm risen, {:.2} mm/s from 0.5 to 1.5 s; the return then \
         moved {:.1} mm, never below {:.2} mm",
        half * 1e3,
        widest * 1e3,
        risen * 1e3,
        measured_speed * 1e3,
        moved_on * 1e3,
        lowest * 1e3,
    );
    assert!(
        (1.99..=2.01).contains(&lift_s),
        "2 cm at 10 mm/s takes 2 s, took {lift_s} s"
    );
    assert!((half - 0.01).abs() < 1e-4, "half way after 1 s: {half} m");
    assert!(widest < 1e-4, "the lift is along the normal only: {widest} m across");
    assert!((0.018..=0.0215).contains(&risen), "the tool rose {risen} m");
    assert!(
        (0.009..=0.011).contains(&measured_speed),
        "the tool rose at {measured_speed} m/s"
    );
    assert!(moved_on > 0.01, "the return moved on after the lift: {moved_on} m");
    assert!(
        lowest > -1e-6,
        "never commanded back below the lift's start: {lowest} m"
    );

    // `lift off 0 mm`: no lift; the default: 1 cm at 25 mm/s. The return's own time is the same
    // in all three, so the retract's time differs by the lift's.
    let (none, log) = touch_run(lift(0.0, 0.0));
    let retract = Retract::of(&log);
    let (first_100ms_along, first_100ms_across) = retract.split(&retract.commanded[retract.at(0.1)]);
    let (default, _) = touch_run(Touch::default());
    let declared_extra = time_in(&declared, "retract") - time_in(&none, "retract");
    let default_extra = time_in(&default, "retract") - time_in(&none, "retract");
    eprintln!(
        "retract: {:.3} s with no lift, {declared_extra:.3} s more with 2 cm at 10 mm/s, \
         {default_extra:.3} s more with the default; without a lift the return moved {:.3} mm \
         along and {:.3} mm across the normal in its first 100 ms",
        time_in(&none, "retract"),
        first_100ms_along * 1e3,
        first_100ms_across * 1e3,
    );
    assert!((declared_extra - 2.0).abs() < 0.01, "{declared_extra} s");
    assert!((default_extra - 0.4).abs() < 0.01, "{default_extra} s");
    assert!(
        first_100ms_along < 0.0025 * 0.5,
        "no lift at 25 mm/s (or 10) without one: {first_100ms_along} m in 100 ms"
    );
}

/// Whether the applied force along the contact normal was at least `threshold_n` at each logged
/// tick of `log` from the start of state `from` to the first tick of the next state (when the
/// transition fired), with the ticks' times.
fn force_above(log: &RunLog, from: &str, threshold_n: f64) -> Vec<(f64, bool)> {
    let state = log.states.iter().position(|s| s == from).expect("the state ran") as u32;
    let first = log.ticks.iter().position(|tick| tick.state == state).expect("ticks");
    let after = first
        + log.ticks[first..]
            .iter()
            .position(|tick| tick.state != state)
            .expect("the state was left");
    // The compliant frame of `approach` is the contact frame: its z is the normal, and a log's
    // wrench is what the guards saw at that tick.
    log.ticks[first..=after]
        .iter()
        .map(|tick| (tick.t_s, tick.wrench_cf[2] >= threshold_n))
        .collect()
}

#[test]
fn a_held_guard_fires_once_its_guard_has_held_its_time_and_counts_again_after_a_drop() {
    // A low contact threshold, which sensor noise crosses now and then before the contact.
    let threshold_n = 0.2;
    let contact = held(
        ir::Guard::Force {
            along: CONTACT_Z,
            op: ir::Comparison::Ge,
            rhs: ir::Threshold::Literal { value: threshold_n },
        },
        0.1,
    );
    let settled = held(ir::Guard::ForceReached { tolerance_n: 0.5 }, 0.1);
    let (report, log) = touch_run(Touch {
        contact,
        settled,
        ..Touch::default()
    });
    let above = force_above(&log, "approach", threshold_n);
    let (fired_s, _) = *above.last().expect("ticks");
    // The last stretch of ticks above the threshold, up to the firing.
    let stretch_start = above.iter().rposition(|(_, holds)| !holds).map_or(0, |k| k + 1);
    let (held_from_s, _) = above[stretch_start];
    // Every earlier stretch was shorter than 100 ms (else the guard would have fired then).
    let mut longest_earlier: f64 = 0.0;
    let mut started = None;
    let mut first_above = None;
    for &(t, holds) in &above[..stretch_start] {
        match (holds, started) {
            (true, None) => {
                started = Some(t);
                first_above.get_or_insert(t);
            }
            (false, Some(from)) => {
                longest_earlier = longest_earlier.max(t - from);
                started = None;
            }
            _ => {}
        }
    }
    eprintln!(
        "force >= {threshold_n} N for 100 ms: first above at {:?} s, held from {held_from_s:.3} s, \
         fired at {fired_s:.3} s; longest earlier stretch {:.1} ms; settle took {:.3} s",
        first_above,
        longest_earlier * 1e3,
        time_in(&report, "settle"),
    );
    let held_s = fired_s - held_from_s;
    assert!(
        (0.1 - 1e-9..=0.1011).contains(&held_s),
        "fired {held_s} s after its guard began to hold, at the first tick at 100 ms"
    );
    assert!(
        longest_earlier < 0.1,
        "no earlier stretch of 100 ms: {longest_earlier} s"
    );
    let first_above = first_above.expect("the guard held before and dropped: the timer restarted");
    assert!(
        first_above + 0.1 < fired_s,
        "a timer that did not restart would have fired at {} s",
        first_above + 0.1
    );
    // `force_reached within 0.5 N for 100 ms` settles after at least 100 ms.
    assert!(
        time_in(&report, "settle") >= 0.1,
        "settle {} s",
        time_in(&report, "settle")
    );
}

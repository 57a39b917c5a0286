//! Unit tests of the state machine's parts: force-profile rates, held guards, the followed normal.

use nalgebra::{UnitQuaternion, Vector3};
use skill_ir as ir;

use super::follow::{NormalFollow, FOLLOW_MAX_TILT_RAD, FOLLOW_MIN_FORCE_N, FOLLOW_MIN_SPEED_MPS};
use super::guards::{HeldKey, HeldTimers};
use super::profile::{
    moving_profile_rate, profile_rate, push_only, MOVING_PROFILE_HALF_N, PROFILE_MIN_RATE, PROFILE_STOP_N,
};

/// Feeds a guard's values at 1 ms ticks from `t0`, returning the ticks at which the hold fired.
fn fired(timers: &mut HeldTimers, key: HeldKey, t0: f64, values: &[bool], duration_s: f64) -> Vec<usize> {
    (0..values.len())
        .filter(|&k| timers.update(key, values[k], t0 + k as f64 * 1e-3, duration_s))
        .collect()
}

#[test]
fn a_force_profile_runs_slower_the_more_the_force_lags() {
    assert_eq!(profile_rate(None), 1.0);
    assert_eq!(profile_rate(Some(0.0)), 1.0);
    assert!((profile_rate(Some(0.5 * PROFILE_STOP_N)) - 0.5).abs() < 1e-12);
    assert!((profile_rate(Some(-0.5 * PROFILE_STOP_N)) - 0.5).abs() < 1e-12);
    assert_eq!(profile_rate(Some(PROFILE_STOP_N)), PROFILE_MIN_RATE);
    assert_eq!(profile_rate(Some(30.0)), PROFILE_MIN_RATE, "never stopped for ever");
    assert_eq!(profile_rate(Some(f64::INFINITY)), 1.0, "no reading: no stopping");
    let mut last = 1.0;
    for k in 1..40 {
        let rate = profile_rate(Some(k as f64 * 0.01));
        assert!(rate < last && rate >= PROFILE_MIN_RATE);
        last = rate;
    }
}

#[test]
fn a_moving_states_profile_slows_gently() {
    assert_eq!(moving_profile_rate(Some(0.0)), 1.0);
    assert!((moving_profile_rate(Some(MOVING_PROFILE_HALF_N)) - 0.5).abs() < 1e-12);
    assert!((moving_profile_rate(Some(-3.0 * MOVING_PROFILE_HALF_N)) - 0.1).abs() < 1e-12);
    assert_eq!(moving_profile_rate(Some(f64::NAN)), 1.0);
}

#[test]
fn a_desired_force_never_pulls_along_the_compliant_z() {
    let z = Vector3::new(0.0, 0.6, -0.8);
    let pushing = Vector3::new(1.0, 0.6, -0.8) * 2.0;
    assert_eq!(push_only(pushing, &z), pushing);
    let pulling = Vector3::new(1.0, 0.0, 0.0) - z * 3.0;
    let kept = push_only(pulling, &z);
    assert!(kept.dot(&z).abs() < 1e-12, "no pull left: {kept}");
    assert!(
        (kept - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12,
        "the other components stay"
    );
}

#[test]
fn a_hold_fires_after_its_time_of_holding_and_restarts_after_a_drop() {
    let mut timers = HeldTimers::default();
    // Holds from tick 10 on: fires from tick 110 (100 ms later), every tick after.
    let mut values = vec![false; 10];
    values.extend([true; 150]);
    let ticks = fired(&mut timers, (0, 0), 0.0, &values, 0.1);
    assert_eq!(ticks.first(), Some(&110));
    assert_eq!(ticks.len(), 50);
    // Drops at tick 60 for one tick: counts again from tick 61, fires at 161.
    let mut timers = HeldTimers::default();
    let mut values = vec![true; 200];
    values[60] = false;
    let ticks = fired(&mut timers, (0, 0), 0.0, &values, 0.1);
    assert_eq!(ticks.first(), Some(&161));
    // Holds never reach 100 ms when the guard drops every 99 ticks.
    let mut timers = HeldTimers::default();
    let values: Vec<bool> = (0..1000).map(|k| k % 99 != 0).collect();
    assert!(fired(&mut timers, (0, 0), 0.0, &values, 0.1).is_empty());
}

#[test]
fn holds_are_kept_apart_by_place_and_forgotten_on_entry() {
    let mut timers = HeldTimers::default();
    assert!(!timers.update((0, 0), true, 0.0, 0.1));
    assert!(!timers.update((0, 1), true, 0.05, 0.1));
    assert!(timers.update((0, 0), true, 0.1, 0.1));
    assert!(!timers.update((0, 1), true, 0.1, 0.1));
    assert!(
        !timers.update((1, 0), true, 0.1, 0.1),
        "another transition's hold starts now"
    );
    // Entering a state clears them: a guard that held before counts from the entry.
    timers.clear();
    assert!(!timers.update((0, 0), true, 0.15, 0.1));
    assert!(timers.update((0, 0), true, 0.25, 0.1));
}

/// A follower of a frame whose learned z points down, as a table's contact frame does.
fn follower() -> NormalFollow {
    NormalFollow {
        frame: ir::FrameRef::Base,
        z: None,
        last_s: 0.0,
    }
}

/// Feeds `follow` `ticks` 1 ms ticks of the same wrench and velocity; returns the estimate.
fn feed(
    follow: &mut NormalFollow,
    ticks: usize,
    applied: Vector3<f64>,
    velocity: Vector3<f64>,
    learned_z: Vector3<f64>,
) -> Vector3<f64> {
    let t0 = follow.last_s;
    let mut z = learned_z;
    for k in 1..=ticks {
        z = follow.update(t0 + k as f64 * 1e-3, &applied, &velocity, &learned_z);
    }
    z
}

/// A surface whose normal is turned `tilt` about x from straight down, pushed with 10 N along
/// it while sliding at 5 cm/s along its tangent with friction 0.4: the direction the tool
/// pushes, the force it applies and its velocity.
fn tilted_contact(tilt: f64, speed: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let turn = UnitQuaternion::from_euler_angles(tilt, 0.0, 0.0);
    let normal = turn * -Vector3::z();
    let tangent = turn * Vector3::x();
    let applied = normal * 10.0 + tangent * (0.4 * 10.0);
    (normal, applied, tangent * speed)
}

#[test]
fn the_followed_normal_converges_on_the_surface_with_the_friction_taken_out() {
    let learned_z = -Vector3::z();
    let tilt = 10f64.to_radians();
    let (normal, applied, velocity) = tilted_contact(tilt, 0.05);
    let mut follow = follower();
    // One time constant: the discrete low-pass has covered about 1 - 1/e of the turn.
    let z = feed(&mut follow, 80, applied, velocity, learned_z);
    let covered = learned_z.angle(&z) / tilt;
    assert!((covered - (1.0 - (-1f64).exp())).abs() < 0.03, "covered {covered}");
    // Ten time constants: on the normal, not on the force (friction tilts that by 21.8°).
    let z = feed(&mut follow, 720, applied, velocity, learned_z);
    assert!(z.angle(&normal) < 1e-3, "{:.4} rad off the normal", z.angle(&normal));
    assert!(applied.angle(&normal) > 0.35);
    assert!((z.norm() - 1.0).abs() < 1e-12);
}

#[test]
fn the_followed_normal_holds_while_the_tool_barely_moves_or_barely_pushes() {
    let learned_z = -Vector3::z();
    let tilt = 10f64.to_radians();
    // At a stroke's reversal (5 mm/s) the friction may point anywhere: no update.
    let (_, applied, slow) = tilted_contact(tilt, 0.5 * FOLLOW_MIN_SPEED_MPS);
    let mut follow = follower();
    assert_eq!(feed(&mut follow, 500, applied, slow, learned_z), learned_z);
    // Off the surface, or barely touching it: no update.
    let (_, _, velocity) = tilted_contact(tilt, 0.05);
    let light = applied * (0.9 * FOLLOW_MIN_FORCE_N / applied.dot(&learned_z));
    assert_eq!(feed(&mut follow, 500, light, velocity, learned_z), learned_z);
    let pulling = -applied;
    assert_eq!(feed(&mut follow, 500, pulling, velocity, learned_z), learned_z);
}

#[test]
fn the_followed_normal_turns_at_most_thirty_degrees_from_the_learned_one() {
    let learned_z = -Vector3::z();
    let (normal, applied, velocity) = tilted_contact(50f64.to_radians(), 0.05);
    let mut follow = follower();
    let z = feed(&mut follow, 2000, applied, velocity, learned_z);
    assert!((learned_z.angle(&z) - FOLLOW_MAX_TILT_RAD).abs() < 1e-9);
    // Turned towards the measured normal, in the plane of the two.
    assert!(z.dot(&learned_z.cross(&normal)).abs() < 1e-9);
    assert!(z.angle(&normal) < 20.5f64.to_radians());
}

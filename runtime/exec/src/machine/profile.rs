//! The force a state asks for: the ramp at the switch to force control, how fast a force
//! profile's clock runs while the applied force lags it, and no pull along the compliant z.

use nalgebra::Vector3;

/// How long the desired force takes to ramp from the force applied when force control begins
/// to the state's own \[s\]: a step in the desired force is a step in the commanded torques.
pub(super) const FORCE_RAMP_S: f64 = 0.15;

/// The force lag at which a force profile's clock stops (but for [`PROFILE_MIN_RATE`]) \[N\]
/// (see [`profile_rate`]): about three times the filtered wrist sensor's noise (0.12 N at the
/// scenes' 0.2 N per sample through the 200 Hz low-pass).
pub(super) const PROFILE_STOP_N: f64 = 0.4;

/// The slowest a force profile's clock runs \[-\]: a force the world never gives stretches the
/// shipped press's 2.8 s profile to 140 s, past any state's timeout, instead of holding it
/// for ever.
pub(super) const PROFILE_MIN_RATE: f64 = 0.02;

/// How fast a force profile's clock runs while the applied force lags the desired one by
/// `lag_n`: `max(1 − lag / PROFILE_STOP_N, PROFILE_MIN_RATE)`, the phase stopping of Ijspeert et
/// al. (2013) with the force error in place of the position error. Full speed on the profile,
/// half at 0.2 N behind, (nearly) stopped at 0.4 N. The profile waits for a force the world does
/// not give yet (a button's cap travelling against its spring at the force axis's speed limit,
/// a surface that is farther), and for one it gives back too slowly (the cap pushing the tool up
/// as the profile releases), instead of running ahead. The lag it leaves is below
/// [`PROFILE_STOP_N`] however steep the profile is: with `1 / (1 + (lag / 1 N)²)` the lag settled
/// where the slowed profile's rate met the rate the cap's spring gives at the speed limit (2-4 N
/// on the shipped press's rise, 12 % force RMS; docs/method.md §7, press).
///
/// A state that also runs a motion keeps the gentler `1 / (1 + (lag / 1 N)²)` of before
/// ([`moving_profile_rate`]): its force belongs to a place on its path, and the path's clock does
/// not wait (a contour whose profile stopped at 0.4 N behind fell to half its force and out of
/// contact for 9 % of its arc).
pub(super) fn profile_rate(lag_n: Option<f64>) -> f64 {
    let lag = lag_n.unwrap_or(0.0);
    if lag.is_finite() {
        (1.0 - lag.abs() / PROFILE_STOP_N).max(PROFILE_MIN_RATE)
    } else {
        1.0
    }
}

/// The force lag at which the profile of a state that also moves runs at half speed \[N\].
pub(super) const MOVING_PROFILE_HALF_N: f64 = 1.0;

/// How fast the force profile of a state with a motion runs while the force lags by `lag_n`:
/// `1 / (1 + (lag / MOVING_PROFILE_HALF_N)²)`, half speed at 1 N, a tenth at 3 N.
pub(super) fn moving_profile_rate(lag_n: Option<f64>) -> f64 {
    let lag = lag_n.unwrap_or(0.0);
    if lag.is_finite() {
        1.0 / (1.0 + (lag / MOVING_PROFILE_HALF_N).powi(2))
    } else {
        1.0
    }
}

/// The desired force `force` with no pull along the compliant z `z` (base frame), for a state
/// that presses in place: a contact only pushes, so a profile whose fit dips below zero there
/// (the shipped press's fit, -2 N for 60 ms where the demonstration rests near 0 N) asks for
/// nothing instead of lifting the tool off the cap, which the force loop then has to find
/// again. A state that moves keeps a 3-D profile as learned: its frame's z need not be the
/// normal all along its path (a contour's demonstrated force directions turn over the drum
/// while its frame does not); a magnitude profile acts along z alone and is held to pushing
/// whether the state moves or not.
pub(super) fn push_only(force: Vector3<f64>, z: &Vector3<f64>) -> Vector3<f64> {
    let along = force.dot(z);
    if along < 0.0 {
        force - z * along
    } else {
        force
    }
}

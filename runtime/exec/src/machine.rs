//! The skill's state machine between ticks (docs/method.md §7): the current state and what it
//! runs (motion, force profile, goal extension), state entry and its actions, guards, the choice
//! of at most one transition a tick, and the command of an active state.

use std::collections::HashMap;

use nalgebra::{Isometry3, UnitQuaternion, Vector3, Vector6};
use skill_ir as ir;

use super::bind::BoundSkill;
use super::motion::{motion_start, offset_to_place, start_profile, MotionRollout};
use super::rig::Rig;
use super::run::ExecError;
use crate::control::travel::TravelFeedForward;
use crate::control::Command;
use crate::dmp::{DmpError, DmpRollout};
use crate::skill::LearnedForce;

/// A running motion: which one, which of its runs (`repeat`, strokes), and the rollouts of
/// that run.
struct RunningMotion {
    /// Index into the bound skill's motions.
    id: usize,
    rollout: MotionRollout,
    /// The run now (0-based): which piece of the motion runs ([`crate::skill::LearnedMotion::piece`]).
    run: usize,
    /// How many runs the state makes.
    runs: usize,
    /// The goal offset every run is started with (fixed at entry) \[m\].
    offset: Vector3<f64>,
    /// The speed override, the tool speed limit and the flange-to-tool lever every run is
    /// started with.
    speed: f64,
    max_tool_speed_mps: f64,
    lever_m: f64,
}

impl RunningMotion {
    /// Whether the last run has run out.
    fn finished(&self) -> bool {
        self.run + 1 >= self.runs && self.run_finished()
    }

    fn run_finished(&self) -> bool {
        self.rollout.position.time_s() >= self.rollout.position.tau_s()
    }
}

/// A running goal extension (touch/press case II).
struct Extension {
    transition: usize,
    axis: Vector3<f64>,
    speed_mps: f64,
    max_m: f64,
    done_m: f64,
    exhausted_at_s: Option<f64>,
    /// The tool point when the extension began (base frame): how far the tool itself travelled
    /// along the axis is what the extension found (the goal leads the compliant tool).
    from_tool: Vector3<f64>,
}

/// The state of the machine between ticks.
pub(super) struct Machine<'b, 'a> {
    bound: &'b BoundSkill<'a>,
    overrides: ir::Overrides,
    state: ir::StateId,
    entered_s: f64,
    held: Isometry3<f64>,
    /// The tool point's pose when the current state was entered (base frame): `moved` guards
    /// measure from it.
    entry_tool: Isometry3<f64>,
    motion: Option<RunningMotion>,
    force_profile: Option<DmpRollout>,
    extension: Option<Extension>,
    velocity: [f64; 3],
    /// Scratch for the force profile's velocity.
    force_velocity: [f64; 3],
    /// Guarded approach of the current state: near its motion's goal, where contact is expected,
    /// the motion slows to a contact-safe speed.
    guarded: Option<GuardedApproach>,
    /// Time the current run of the state's motion has run on its own clock \[s\] (slower than
    /// the run's during a guarded approach): per-sample frames follow the motion, not the wall
    /// clock, and start again with each run of a `repeat`.
    motion_clock_s: f64,
    /// Lift-off of the current state from the contact it was entered in, if any.
    lift: Option<LiftOff>,
    /// When the current state's force control began and the force the tool applied then (base
    /// frame): the desired force ramps from it.
    ramp_from: Option<(f64, Vector3<f64>)>,
    /// The desired force of the last command before its ramp (base frame).
    target_force: Vector3<f64>,
    /// The compliant z of the last command (base frame).
    last_frame_z: Vector3<f64>,
    /// How fast the motion's clock runs against the run's (below 1 in a guarded approach): the
    /// commanded velocity is the motion's times this.
    clock_rate: f64,
    /// The current state's `for D` guards: since when each one's guard has held.
    hold_timers: HeldTimers,
    /// Whether each guard of the active state holds this tick (a buffer kept between ticks so
    /// that choosing allocates nothing).
    guard_holds: Vec<bool>,
    /// How many times each state has been entered in this run (`entered(STATE)` guards).
    entries: Vec<u32>,
    /// How far the tool travelled during goal extensions of earlier states (base frame, along
    /// each extension's axis): the surface or button they found is that much farther than
    /// demonstrated, so later motions that are not `relative` move their goals by it too.
    found_offset: Vector3<f64>,
    /// The tool point's pose (base frame) on the last entry of each state that captures a
    /// name (`capture NAME`), by name: `move M at NAME` ends there.
    captures: HashMap<String, Isometry3<f64>>,
    /// The current state's watch over its contact (see [`ContactWatch`]).
    contact: ContactWatch,
    /// The measured contact normal the current state's compliant frame follows, if it does
    /// (see [`NormalFollow`]).
    follow: Option<NormalFollow>,
    /// The stiffness a state pressing in place meets and its desired force's rate, for the
    /// force axis's rate feed-forward (`None` in other states; see [`crate::control::travel`]).
    travel: Option<TravelFeedForward>,
}

/// How long the force of a state that pushes while it moves may stay below half its desired
/// force before the contact counts as lost \[s\]: the force axis follows a drop of 5 mm in that
/// time at its speed limit (25 mm/s), so a step down or a dip the surface has is not a loss, and
/// a tool that ran off the surface is at most a few millimetres below it when the run stops.
pub(super) const LOST_CONTACT_S: f64 = 0.2;

/// A contact lost within this much of the end of a state's stroke is no failure \[m\]: the
/// motion's remaining path, measured in the directions under position control, from its
/// commanded position to its goal (a slide whose surface ends where the slide does).
pub(super) const LOST_CONTACT_STROKE_M: f64 = 0.005;

/// Whether the contact a pushing, moving state holds has been lost: armed once the applied
/// force along the desired force reaches half of it in the state, it counts the time since the
/// force was last at half the desired force or more. Ticks whose desired force is below
/// [`IN_CONTACT_N`] (a profile that releases) expect no contact and restart the count.
#[derive(Debug, Clone, Copy, Default)]
struct ContactWatch {
    armed: bool,
    /// Run time of the last tick with the force at half the desired force or more \[s\].
    last_held_s: f64,
    /// The tool point then (base frame) \[m\].
    last_held_tool_m: Vector3<f64>,
    /// The motion's stroke left then \[m\] (see [`LOST_CONTACT_STROKE_M`]) and its runs left
    /// after the current one.
    stroke_left_m: f64,
    runs_left: usize,
}

/// A contact lost mid-stroke: when, where and how much of the stroke was left.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LostContact {
    /// Run time at which the loss was confirmed \[s\].
    pub(super) t_s: f64,
    /// Run time of the last tick in contact \[s\].
    pub(super) since_s: f64,
    /// The tool point then, where the contact was lost (base frame) \[m\].
    pub(super) lost_at_m: Vector3<f64>,
    /// The tool point now (base frame) \[m\].
    pub(super) tool_m: Vector3<f64>,
    /// The stroke left where the contact was lost \[m\], and the runs left after that one.
    pub(super) stroke_left_m: f64,
    pub(super) runs_left: usize,
    /// The desired force's magnitude and the applied force along it now \[N\].
    pub(super) desired_n: f64,
    pub(super) applied_n: f64,
}

/// Where a held guard (`G for D`) sits: the index of its transition and its place in a
/// pre-order walk of that transition's guard. Every guard of the state is walked in full at
/// every evaluation, so the place is the same each time.
type HeldKey = (usize, usize);

/// Since when the guard of each held guard (`G for D`) of the current state has held without a
/// break, as run time \[s\]. Cleared when a state is entered, so a hold never counts time from
/// before the state.
#[derive(Debug, Default)]
struct HeldTimers {
    since: HashMap<HeldKey, f64>,
}

impl HeldTimers {
    fn clear(&mut self) {
        self.since.clear();
    }

    /// Records whether the guard of held guard `key` holds at run time `t`, and returns whether
    /// it has held at every evaluation since at least `duration_s` ago (compared as `dwell` is).
    fn update(&mut self, key: HeldKey, holds: bool, t: f64, duration_s: f64) -> bool {
        if !holds {
            self.since.remove(&key);
            return false;
        }
        let since = *self.since.entry(key).or_insert(t);
        t - since >= duration_s
    }
}

/// A state that leaves a contact with a learned motion first lifts the tool off along the
/// contact normal, with its motion paused, and afterwards never commands the tool back nearer
/// the surface it left than the lift: a learned path that starts with the tail of the
/// demonstrator's push (it does: segments split where the force peaks) would press into the
/// surface again.
#[derive(Debug, Clone, Copy)]
struct LiftOff {
    /// Unit direction away from the surface (against the force the tool applied), base frame.
    away: Vector3<f64>,
    /// The tool point where the state was entered, base frame.
    from: Vector3<f64>,
    /// How far to lift \[m\].
    distance_m: f64,
    /// Lift speed \[m/s\].
    speed_mps: f64,
    /// Lifted so far \[m\].
    done_m: f64,
}

impl LiftOff {
    fn lifting(&self) -> bool {
        self.done_m < self.distance_m
    }
}

/// How far a state that leaves a contact lifts off first \[m\]: clear of the surface's
/// compliance and of sensor noise, short enough to cost a fraction of a second.
pub(super) const LIFT_OFF_M: f64 = 0.01;

/// Lift-off speed \[m/s\]: the contact-safe speed.
const LIFT_OFF_SPEED_MPS: f64 = GUARD_SPEED_MPS;

/// The applied force above which a state is entered in contact \[N\] (several times the wrist
/// sensor's noise).
const IN_CONTACT_N: f64 = 1.0;

/// The compliant frame of a state that moves while it pushes along its z (a contour, a slide, a
/// wipe) follows the contact normal the wrist measures (docs/method.md §7, following the
/// normal): its learned orientation is turned by the smallest rotation that takes its z onto
/// the direction the tool pushes, with the friction taken out along the tool's velocity. A
/// learned frame holds the demonstrated surface's directions, sample by sample; a drum moved
/// 2 cm sideways or a table tilted 8° has other normals under the same path, and force control
/// along a z 10-30° off them leaks the position loop's stiffness into the force.
#[derive(Debug, Clone, Copy)]
struct NormalFollow {
    /// The frame followed (the state's compliant frame).
    frame: ir::FrameRef,
    /// The estimate: the unit direction the tool pushes the surface along, base frame; `None`
    /// until the state's first command.
    z: Option<Vector3<f64>>,
    /// Run time of the last update \[s\].
    last_s: f64,
}

/// The time constant of the normal estimate \[s\]: several periods of a hand's 8-12 Hz tremor
/// and of the sensor's noise, a few millimetres of stroke at the shipped 5-10 cm/s.
const FOLLOW_TAU_S: f64 = 0.08;

/// The slowest tool speed at which the normal estimate is updated \[m/s\]: friction acts along
/// the sliding direction only while the tool slides; at a stroke's reversal it may point
/// anywhere in the tangent plane, up to the friction coefficient times the normal force.
const FOLLOW_MIN_SPEED_MPS: f64 = 0.01;

/// The least force the tool must push along the estimate for it to be updated \[N\].
const FOLLOW_MIN_FORCE_N: f64 = 2.0;

/// The most the followed z may turn away from the learned one \[rad\] (30°): a surface that
/// turns farther is another task, and the estimate is not trusted to lead the frame there.
const FOLLOW_MAX_TILT_RAD: f64 = std::f64::consts::FRAC_PI_6;

impl NormalFollow {
    /// The frame a state follows, if it does: a learned frame placed at the tool (its
    /// orientation learned from a surface or a force), of a state with a motion and a desired
    /// force, force-controlled along z and position-controlled along x and y.
    fn of(bound: &BoundSkill<'_>, active: &ir::ActiveState, t: f64) -> Option<NormalFollow> {
        active.motion?;
        active.force?;
        let [x, y, z, ..] = active.position_controlled;
        let ir::FrameRef::Learned(id) = active.frame else {
            return None;
        };
        let at_tool = bound.frames[id.index()].kind().origin() == crate::skill::FrameOrigin::AtTool;
        (x && y && !z && at_tool).then_some(NormalFollow {
            frame: active.frame,
            z: None,
            last_s: t,
        })
    }

    /// Updates the estimate at run time `t` from the applied force and the tool's velocity (base
    /// frame), with `learned_z` the learned frame's z now; returns the estimate.
    fn update(
        &mut self,
        t: f64,
        applied: &Vector3<f64>,
        velocity: &Vector3<f64>,
        learned_z: &Vector3<f64>,
    ) -> Vector3<f64> {
        let dt = (t - self.last_s).max(0.0);
        self.last_s = t;
        let mut z = self.z.unwrap_or(*learned_z);
        let speed = velocity.norm();
        if applied.dot(&z) > FOLLOW_MIN_FORCE_N && speed > FOLLOW_MIN_SPEED_MPS {
            let sliding = velocity / speed;
            let pushing = applied - sliding * applied.dot(&sliding);
            if let Some(measured) = pushing.try_normalize(1e-9) {
                let alpha = dt / (FOLLOW_TAU_S + dt);
                z = (z + (measured - z) * alpha).try_normalize(1e-12).unwrap_or(z);
            }
        }
        let tilt = learned_z.angle(&z);
        if tilt > FOLLOW_MAX_TILT_RAD {
            if let Some(turn) = UnitQuaternion::rotation_between(learned_z, &z) {
                z = turn.powf(FOLLOW_MAX_TILT_RAD / tilt) * learned_z;
            }
        }
        self.z = Some(z);
        z
    }
}

/// How long the desired force takes to ramp from the force applied when force control begins
/// to the state's own \[s\]: a step in the desired force is a step in the commanded torques.
pub(super) const FORCE_RAMP_S: f64 = 0.15;

/// The force lag at which a force profile's clock stops (but for [`PROFILE_MIN_RATE`]) \[N\]
/// (see [`profile_rate`]): about three times the filtered wrist sensor's noise (0.12 N at the
/// scenes' 0.2 N per sample through the 200 Hz low-pass).
const PROFILE_STOP_N: f64 = 0.4;

/// The slowest a force profile's clock runs \[-\]: a force the world never gives stretches the
/// shipped press's 2.8 s profile to 140 s, past any state's timeout, instead of holding it
/// for ever.
const PROFILE_MIN_RATE: f64 = 0.02;

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
fn profile_rate(lag_n: Option<f64>) -> f64 {
    let lag = lag_n.unwrap_or(0.0);
    if lag.is_finite() {
        (1.0 - lag.abs() / PROFILE_STOP_N).max(PROFILE_MIN_RATE)
    } else {
        1.0
    }
}

/// The force lag at which the profile of a state that also moves runs at half speed \[N\].
const MOVING_PROFILE_HALF_N: f64 = 1.0;

/// How fast the force profile of a state with a motion runs while the force lags by `lag_n`:
/// `1 / (1 + (lag / MOVING_PROFILE_HALF_N)²)`, half speed at 1 N, a tenth at 3 N.
fn moving_profile_rate(lag_n: Option<f64>) -> f64 {
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
/// again. A state that moves keeps its profile as learned: its frame's z need not be the
/// normal all along its path (a contour's demonstrated force directions turn over the drum
/// while its frame does not).
fn push_only(force: Vector3<f64>, z: &Vector3<f64>) -> Vector3<f64> {
    let along = force.dot(z);
    if along < 0.0 {
        force - z * along
    } else {
        force
    }
}

/// How a state that expects contact approaches it: within `zone_m` of its motion's goal (flange
/// positions) the motion's time runs slower, so that the tool moves at most `speed_mps`.
#[derive(Debug, Clone, Copy)]
struct GuardedApproach {
    zone_m: f64,
    speed_mps: f64,
}

/// The contact-safe speed of a guarded approach without a search speed of its own \[m/s\]: the
/// controller's force-axis speed limit, for the same reason (an impact at `v` peaks near `v √(k m)`).
const GUARD_SPEED_MPS: f64 = 0.025;

/// How far before the expected contact a guarded approach slows down when the state declares no
/// search range \[m\] (scene changes of a few centimetres).
const GUARD_ZONE_M: f64 = 0.03;

/// The guarded approach of a state with a motion: the one it declares (`approach within D at
/// V`), whatever its guards; otherwise, if it waits for contact (a force guard on one of its
/// transitions, `on watch` guards left out), its search (`extend ... at V, up to D`) gives the speed and the zone, and
/// without one [`GUARD_SPEED_MPS`] within [`GUARD_ZONE_M`].
fn guarded_approach(skill: &ir::Skill, active: &ir::ActiveState) -> Option<GuardedApproach> {
    active.motion?;
    if let Some(declared) = active.approach {
        return Some(GuardedApproach {
            zone_m: declared.within_m,
            speed_mps: declared.speed_mps,
        });
    }
    let mut expects_contact = false;
    let mut search = None;
    for id in &active.transitions {
        let transition = &skill.transitions[id.index()];
        // `on watch ...` looks out for a limit; it expects no contact.
        expects_contact |= !transition.watch && mentions_force(&transition.guard);
        if let ir::TransitionAction::Extend { speed_mps, max_m, .. } = transition.action {
            search = Some(GuardedApproach {
                zone_m: max_m.max(GUARD_ZONE_M),
                speed_mps: speed_mps.min(GUARD_SPEED_MPS),
            });
        }
    }
    expects_contact.then(|| {
        search.unwrap_or(GuardedApproach {
            zone_m: GUARD_ZONE_M,
            speed_mps: GUARD_SPEED_MPS,
        })
    })
}

fn mentions_force(guard: &ir::Guard) -> bool {
    match guard {
        ir::Guard::And { all } => all.iter().any(mentions_force),
        ir::Guard::Or { any } => any.iter().any(mentions_force),
        ir::Guard::Not { guard } | ir::Guard::Held { guard, .. } => mentions_force(guard),
        ir::Guard::Force { .. } | ir::Guard::ForceMagnitude { .. } | ir::Guard::MomentMagnitude { .. } => true,
        _ => false,
    }
}

/// What guards see this tick.
pub(super) struct Sensed {
    /// The applied wrench at the tool point, base frame.
    applied: Vector6<f64>,
    /// The largest force error over the force-controlled axes (compliant frame), if any.
    force_error_max: Option<f64>,
    /// The largest force error over the force-controlled translations \[N\], if any.
    force_lag_n: Option<f64>,
}

impl Sensed {
    /// What the rig's controller measured, judged against the last command (if any) with the
    /// state's own desired force (`force_reached` waits for it, not for a force on its ramp).
    pub(super) fn of(rig: &Rig<'_>, last_cmd: Option<&Command>, target_force: Vector3<f64>) -> Self {
        let applied = rig.controller.state().applied;
        let (force_error_max, force_lag_n) =
            last_cmd.map_or((None, None), |cmd| force_errors(cmd, &target_force, &applied));
        Sensed {
            applied,
            force_error_max,
            force_lag_n,
        }
    }
}

impl<'b, 'a> Machine<'b, 'a> {
    /// The machine in the skill's initial state, entered now.
    pub(super) fn start(
        bound: &'b BoundSkill<'a>,
        overrides: ir::Overrides,
        rig: &mut Rig<'_>,
    ) -> Result<Self, ExecError> {
        let skill = bound.skill;
        let mut machine = Machine {
            bound,
            overrides,
            state: skill.initial,
            entered_s: rig.time_s(),
            held: rig.flange(),
            entry_tool: rig.tool(),
            motion: None,
            force_profile: None,
            extension: None,
            velocity: [0.0; 3],
            force_velocity: [0.0; 3],
            guarded: None,
            motion_clock_s: 0.0,
            lift: None,
            ramp_from: None,
            target_force: Vector3::zeros(),
            last_frame_z: Vector3::z(),
            clock_rate: 1.0,
            hold_timers: HeldTimers::default(),
            guard_holds: Vec::new(),
            entries: vec![0; skill.states.len()],
            found_offset: Vector3::zeros(),
            captures: HashMap::new(),
            contact: ContactWatch::default(),
            follow: None,
            travel: None,
        };
        machine.enter(skill.initial, rig.time_s(), rig)?;
        Ok(machine)
    }

    fn skill(&self) -> &'a ir::Skill {
        self.bound.skill
    }

    /// The current state.
    pub(super) fn state(&self) -> &'a ir::State {
        &self.skill().states[self.state.index()]
    }

    /// The current state when it is active (not terminal).
    pub(super) fn active(&self) -> Option<&'a ir::ActiveState> {
        match &self.state().kind {
            ir::StateKind::Active(active) => Some(active),
            ir::StateKind::Terminal { .. } => None,
        }
    }

    /// Enters a state at run time `t`: restart its motion from the flange pose, run entry actions.
    pub(super) fn enter(&mut self, state: ir::StateId, t: f64, rig: &mut Rig<'_>) -> Result<(), ExecError> {
        let was_forcing = self
            .active()
            .is_some_and(|active| active.position_controlled.contains(&false));
        if let Some(extension) = &self.extension {
            let travelled = extension
                .axis
                .dot(&(rig.tool().translation.vector - extension.from_tool));
            self.found_offset += extension.axis * travelled.clamp(0.0, extension.done_m);
        }
        self.state = state;
        if let Some(count) = self.entries.get_mut(state.index()) {
            *count = count.saturating_add(1);
        }
        self.entered_s = t;
        self.extension = None;
        self.motion = None;
        self.force_profile = None;
        self.guarded = None;
        self.motion_clock_s = 0.0;
        self.lift = None;
        self.ramp_from = None;
        self.clock_rate = 1.0;
        self.hold_timers.clear();
        self.contact = ContactWatch::default();
        self.follow = None;
        self.travel = None;
        let flange = rig.flange();
        self.held = flange;
        self.entry_tool = rig.tool();
        let Some(active) = self.active() else { return Ok(()) };
        if let Some(name) = &active.capture {
            if !(active.capture_once && self.captures.contains_key(name)) {
                self.captures.insert(name.clone(), self.entry_tool);
            }
        }
        self.guarded = guarded_approach(self.skill(), active);
        self.follow = NormalFollow::of(self.bound, active, t);
        // Pressing in place along the compliant z: the tool's travel along it is the give of
        // what it presses (a moving state travels along z with the surface's shape too).
        if !active.position_controlled[2] && active.motion.is_none() {
            self.travel = Some(TravelFeedForward::new());
        }
        let applied = rig.controller.state().applied.fixed_rows::<3>(0).into_owned();
        let forcing = active.position_controlled.contains(&false);
        if forcing && !was_forcing {
            self.ramp_from = Some((t, applied));
        }
        // Leaving a contact on a learned path under pure position control: lift off first, away
        // from the force the tool applied or, when a force profile has let it drop to nothing
        // (a press that releases), against the compliant z it was controlled along.
        let in_contact = applied.norm() > IN_CONTACT_N || was_forcing;
        if active.motion.is_some() && !forcing && self.guarded.is_none() && in_contact {
            let away = if applied.norm() > IN_CONTACT_N {
                -applied.normalize()
            } else if self.target_force.norm() > 1e-3 {
                // The force it was asked to push with points into the surface.
                -self.target_force.normalize()
            } else {
                -self.last_frame_z
            };
            // As the state declares (`lift off D at V`, not scaled by the task's speed; `lift
            // off 0 mm` for none), or by default.
            let (distance_m, speed_mps) = match active.lift_off {
                Some(declared) => (declared.distance_m, declared.speed_mps),
                None => (LIFT_OFF_M, LIFT_OFF_SPEED_MPS * self.overrides.speed_factor.min(1.0)),
            };
            if distance_m > 0.0 {
                self.lift = Some(LiftOff {
                    away,
                    from: rig.tool().translation.vector,
                    distance_m,
                    speed_mps,
                    done_m: 0.0,
                });
            }
        }
        let speed = self.overrides.speed_factor;
        if let Some(motion_id) = active.motion {
            let learned = self.bound.motions[motion_id.index()];
            let lever = rig.flange_to_tool().translation.vector.norm();
            let max_speed = rig.limits().tool_speed_mps;
            // `move M relative`: the goal moves by the offset of the entry pose from the
            // motion's demonstrated start. A task step's `goal_offset` is not added again: the
            // entry pose carries it already (the state began where the offset goals led). Other
            // motions move by the step's offset and by what earlier extensions found.
            // `move M at NAME`: the goal moves to where the tool point was captured, and on by
            // `+ OFFSET in FRAME` along that frame's axes as they are at this entry.
            let offset = if let Some(name) = &active.motion_at {
                let shift = active.motion_at_offset.as_ref().map_or_else(Vector3::zeros, |at| {
                    self.frame_pose(at.frame, rig, t).rotation * Vector3::from(at.offset_m)
                });
                self.capture_offset(name, motion_id, rig.flange_to_tool(), shift)?
            } else if active.motion_relative {
                flange.translation.vector - motion_start(learned).translation.vector
            } else {
                Vector3::from(self.overrides.goal_offset_m) + self.found_offset
            };
            let rollout = MotionRollout::start(learned.piece(0), &flange, offset.into(), speed, max_speed, lever)
                .map_err(|err| self.motion_error(&self.skill().learn.motions[motion_id.index()].name, &err))?;
            self.motion = Some(RunningMotion {
                id: motion_id.index(),
                rollout,
                run: 0,
                runs: active.repeat.map_or(learned.default_runs(), |n| n as usize),
                offset,
                speed,
                max_tool_speed_mps: max_speed,
                lever_m: lever,
            });
        }
        if let Some(force_id) = active.force {
            if let LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } = self.bound.forces[force_id.index()] {
                let rollout = start_profile(dmp, speed)
                    .map_err(|err| self.motion_error(&self.skill().learn.forces[force_id.index()].name, &err))?;
                self.force_profile = Some(rollout);
            }
        }
        for action in &active.entry {
            match action {
                ir::EntryAction::ResetIntegral => rig.controller.reset_integral(),
                ir::EntryAction::Tare => {
                    let obs = rig.observation().clone();
                    rig.controller.tare(&obs);
                }
                ir::EntryAction::ShiftGoal { along, distance_m } => {
                    let axis = self.axis_vector(along, rig);
                    let shift = axis * *distance_m;
                    match &mut self.motion {
                        Some(motion) => {
                            motion.offset += shift;
                            motion.rollout.goal += shift;
                            let goal = motion.rollout.goal;
                            let result = motion.rollout.position.set_goal(goal.as_slice());
                            self.check_goal(result)?;
                        }
                        None => self.held.translation.vector += shift,
                    }
                }
            }
        }
        Ok(())
    }

    /// The goal offset that ends motion `motion_id` of the current state at capture `name`; an
    /// error naming the capture and the state when the run has not captured it.
    fn capture_offset(
        &self,
        name: &str,
        motion_id: ir::MotionId,
        flange_to_tool: &Isometry3<f64>,
        shift: Vector3<f64>,
    ) -> Result<Vector3<f64>, ExecError> {
        let motion_name = &self.skill().learn.motions[motion_id.index()].name;
        let Some(pose) = self.captures.get(name) else {
            let capturing: Vec<String> = self
                .skill()
                .states
                .iter()
                .filter(|state| match &state.kind {
                    ir::StateKind::Active(active) => active.capture.as_deref() == Some(name),
                    ir::StateKind::Terminal { .. } => false,
                })
                .map(|state| format!("`{}`", state.name))
                .collect();
            let where_ = match capturing.is_empty() {
                true => "no state captures it".to_string(),
                false => format!("`capture {name}` is in {}, not entered before", capturing.join(", ")),
            };
            return Err(ExecError::NotCaptured {
                state: self.state().name.clone(),
                message: format!(
                    "state `{}` moves `{motion_name}` at `{name}`, but the run has not captured `{name}` ({where_})",
                    self.state().name
                ),
            });
        };
        offset_to_place(
            self.bound.motions[motion_id.index()],
            (pose.translation.vector + shift).into(),
            flange_to_tool,
        )
        .map(Vector3::from)
        .ok_or_else(|| ExecError::Motion {
            state: self.state().name.clone(),
            motion: motion_name.clone(),
            reason: "its goal is not a position to place".to_string(),
        })
    }

    /// The error for a motion or force profile `name` of the current state that could not be set up.
    fn motion_error(&self, name: &str, err: &DmpError) -> ExecError {
        ExecError::Motion {
            state: self.state().name.clone(),
            motion: name.to_string(),
            reason: err.to_string(),
        }
    }

    /// Turns a failed goal change of the running motion into an error.
    fn check_goal(&self, result: Result<(), DmpError>) -> Result<(), ExecError> {
        result.map_err(|err| {
            let id = self.motion.as_ref().map_or(0, |m| m.id);
            self.motion_error(&self.skill().learn.motions[id].name, &err)
        })
    }

    fn time_in_state(&self, t: f64) -> f64 {
        t - self.entered_s
    }

    /// A compliant frame's pose now (origin moved to the tool point where that is meant).
    fn frame_pose(&self, frame: ir::FrameRef, rig: &Rig<'_>, t: f64) -> Isometry3<f64> {
        let tool = rig.tool();
        let at_tool = |rotation: UnitQuaternion<f64>| Isometry3::from_parts(tool.translation, rotation);
        match frame {
            ir::FrameRef::Base => at_tool(UnitQuaternion::identity()),
            ir::FrameRef::Tool => tool,
            ir::FrameRef::Learned(id) => {
                let learned = self.bound.frames[id.index()];
                let clock = if self.motion.is_some() {
                    self.motion_clock_s
                } else {
                    self.time_in_state(t)
                };
                let speed = self
                    .motion
                    .as_ref()
                    .map_or(self.overrides.speed_factor, |m| m.rollout.speed);
                let elapsed = match self.frame_segment_order(id.index()) {
                    // A frame per sample of a later segment holds its first pose (the approach
                    // to a contour meets the drum where the contour starts), of an earlier one
                    // its last (the leaving lifts off where the contour ended).
                    Some(std::cmp::Ordering::Less) => 0.0,
                    Some(std::cmp::Ordering::Greater) => f64::INFINITY,
                    _ => self.strokes_demo_time_s().unwrap_or(clock * speed),
                };
                let pose = learned.at(elapsed);
                let rotation = match self.follow {
                    Some(NormalFollow {
                        frame: followed,
                        z: Some(z),
                        ..
                    }) if followed == frame => {
                        let learned_z = pose.rotation * Vector3::z();
                        UnitQuaternion::rotation_between(&learned_z, &z)
                            .map_or(pose.rotation, |turn| turn * pose.rotation)
                    }
                    _ => pose.rotation,
                };
                match learned.kind().origin() {
                    crate::skill::FrameOrigin::Learned => Isometry3::from_parts(pose.translation, rotation),
                    crate::skill::FrameOrigin::AtTool => at_tool(rotation),
                }
            }
        }
    }

    /// For a strokes motion, the demonstration time within its segment the running stroke has
    /// reached \[s\]: the demonstrated strokes before it plus its own progress. Each stroke runs
    /// at its own speed (slowed for the tool speed limit or not), so one clock times them all
    /// wrong; past the demonstrated strokes the runs alternate the last two
    /// ([`crate::skill::LearnedMotion::piece`]) and so do their times. `None` for other motions.
    fn strokes_demo_time_s(&self) -> Option<f64> {
        let motion = self.motion.as_ref()?;
        let strokes = &self.bound.motions[motion.id].strokes;
        let k = strokes.len();
        let index = match k {
            0 => return None,
            1 => 0,
            _ if motion.run < k => motion.run,
            _ => k - 2 + (motion.run - k) % 2,
        };
        let before: f64 = strokes[..index].iter().map(|stroke| stroke.position.tau_s).sum();
        let rollout = &motion.rollout.position;
        let progress = if rollout.tau_s() > 0.0 {
            (rollout.time_s() / rollout.tau_s()).clamp(0.0, 1.0)
        } else {
            1.0
        };
        Some(before + progress * strokes[index].position.tau_s)
    }

    /// Where the current state's motion lies against the segment learned frame `id` was
    /// learned from: `Less` when the motion's segment is earlier, `Equal` when it is that
    /// segment; `None` without a motion or for a frame not learned from a segment.
    fn frame_segment_order(&self, id: usize) -> Option<std::cmp::Ordering> {
        let motion = self.motion.as_ref()?;
        let learn = &self.skill().learn;
        let frame_segment = match &learn.frames.get(id)?.source {
            ir::FrameSource::Constraint { segment, .. } | ir::FrameSource::ForceAlignedSamples { segment } => {
                segment.index()
            }
            _ => return None,
        };
        Some(learn.motions.get(motion.id)?.segment.index().cmp(&frame_segment))
    }

    /// Updates the contact normal the current state's frame follows, if it follows one.
    fn follow_normal(&mut self, rig: &Rig<'_>, t: f64) {
        let Some(mut follow) = self.follow else { return };
        // The learned frame's own z now: the estimate is turned from it.
        let learned = NormalFollow { z: None, ..follow };
        self.follow = Some(learned);
        let learned_z = self.frame_pose(follow.frame, rig, t).rotation * Vector3::z();
        let state = rig.controller.state();
        let applied = state.applied.fixed_rows::<3>(0).into_owned();
        let velocity = state.twist.fixed_rows::<3>(0).into_owned();
        follow.update(t, &applied, &velocity, &learned_z);
        self.follow = Some(follow);
    }

    fn axis_vector(&self, along: &ir::FrameAxis, rig: &Rig<'_>) -> Vector3<f64> {
        let rotation = self.frame_pose(along.frame, rig, rig.time_s()).rotation;
        rotation * unit(along.axis)
    }

    fn scaled_threshold(&self, threshold: ir::Threshold) -> f64 {
        let scale = self.overrides.force_scale;
        match threshold {
            ir::Threshold::Learned { id } => self.bound.thresholds[id.index()] * scale,
            ir::Threshold::Force { id } => self.bound.forces[id.index()].value_n().unwrap_or(0.0) * scale,
            ir::Threshold::Literal { value } => value * scale,
        }
    }

    /// Whether every DMP of the state has run out (and any extension is used up and settled).
    fn motion_done(&self, t: f64) -> bool {
        let motion_finished = self.motion.as_ref().is_none_or(RunningMotion::finished);
        let profile_finished = self.force_profile.as_ref().is_none_or(|p| p.time_s() >= p.tau_s());
        let runs_something = self.motion.is_some() || self.force_profile.is_some();
        let extension_finished = self
            .extension
            .as_ref()
            .is_none_or(|e| e.exhausted_at_s.is_some_and(|at| t - at >= 0.2));
        runs_something && motion_finished && profile_finished && extension_finished
    }

    /// Whether `guard` holds now. `place` is where the next held guard of the transition sits
    /// (see [`HeldKey`]). `and` and `or` evaluate every operand, without short cuts, so that every
    /// held guard sees its guard at every evaluation.
    fn guard(&mut self, guard: &ir::Guard, sensed: &Sensed, rig: &Rig<'_>, t: f64, place: &mut HeldKey) -> bool {
        match guard {
            ir::Guard::And { all } => {
                let mut holds = true;
                for g in all {
                    holds &= self.guard(g, sensed, rig, t, place);
                }
                holds
            }
            ir::Guard::Or { any } => {
                let mut holds = false;
                for g in any {
                    holds |= self.guard(g, sensed, rig, t, place);
                }
                holds
            }
            ir::Guard::Not { guard } => !self.guard(guard, sensed, rig, t, place),
            ir::Guard::Held { guard, duration_s } => {
                let key = *place;
                place.1 += 1;
                let holds = self.guard(guard, sensed, rig, t, place);
                self.hold_timers.update(key, holds, t, *duration_s)
            }
            ir::Guard::Force { along, op, rhs } => {
                let axis = self.axis_vector(along, rig);
                let value = if along.axis.is_rotation() {
                    sensed.applied.fixed_rows::<3>(3).dot(&axis)
                } else {
                    sensed.applied.fixed_rows::<3>(0).dot(&axis)
                };
                op.holds(value, self.scaled_threshold(*rhs))
            }
            ir::Guard::Moved { along, op, value } => {
                let axis = self.axis_vector(along, rig);
                let tool = rig.tool();
                let moved = if along.axis.is_rotation() {
                    (tool.rotation * self.entry_tool.rotation.inverse())
                        .scaled_axis()
                        .dot(&axis)
                } else {
                    (tool.translation.vector - self.entry_tool.translation.vector).dot(&axis)
                };
                op.holds(moved, *value)
            }
            ir::Guard::MovedDistance { op, value_m } => {
                let moved = rig.tool().translation.vector - self.entry_tool.translation.vector;
                op.holds(moved.norm(), *value_m)
            }
            ir::Guard::MovedSince { capture, op, value_m } => self.captures.get(capture).is_some_and(|kept| {
                op.holds(
                    (rig.tool().translation.vector - kept.translation.vector).norm(),
                    *value_m,
                )
            }),
            ir::Guard::ForceMagnitude { op, rhs } => {
                op.holds(sensed.applied.fixed_rows::<3>(0).norm(), self.scaled_threshold(*rhs))
            }
            ir::Guard::MomentMagnitude { op, rhs } => {
                op.holds(sensed.applied.fixed_rows::<3>(3).norm(), self.scaled_threshold(*rhs))
            }
            ir::Guard::Entered { state, op, count } => {
                let entries = self.entries.get(state.index()).copied().unwrap_or(0);
                op.holds(f64::from(entries), f64::from(*count))
            }
            ir::Guard::Speed { op, value_mps } => {
                op.holds(rig.controller.state().twist.fixed_rows::<3>(0).norm(), *value_mps)
            }
            ir::Guard::MotionDone => self.motion_done(t),
            ir::Guard::ForceReached { tolerance_n } => sensed.force_error_max.is_some_and(|e| e <= *tolerance_n),
            ir::Guard::Dwell { duration_s } | ir::Guard::Timeout { duration_s } => self.time_in_state(t) >= *duration_s,
        }
    }

    /// Evaluates the active state's guards in priority order and returns the transition taken
    /// (target state, transition index), if any: at most one a tick. A holding `extend` guard
    /// starts its goal extension instead, and leaves once the extension is used up.
    pub(super) fn choose(
        &mut self,
        active: &ir::ActiveState,
        sensed: &Sensed,
        rig: &Rig<'_>,
        t: f64,
    ) -> Option<(ir::StateId, usize)> {
        let skill = self.skill();
        // Every guard is evaluated, also after the one that fires, so that held guards see
        // their guards at every tick.
        let mut holds = std::mem::take(&mut self.guard_holds);
        holds.clear();
        for id in &active.transitions {
            let mut place = (id.index(), 0);
            let held = self.guard(&skill.transitions[id.index()].guard, sensed, rig, t, &mut place);
            holds.push(held);
        }
        let mut next = None;
        for (transition_id, &holds) in active.transitions.iter().zip(&holds) {
            let transition = &skill.transitions[transition_id.index()];
            if !holds {
                continue;
            }
            match &transition.action {
                ir::TransitionAction::Goto { target } => {
                    next = Some((*target, transition_id.index()));
                    break;
                }
                ir::TransitionAction::Extend {
                    along,
                    speed_mps,
                    max_m,
                    then,
                } => {
                    match &self.extension {
                        Some(extension) if extension.transition == transition_id.index() => {
                            if extension.exhausted_at_s.is_some() {
                                next = Some((*then, transition_id.index()));
                                break;
                            }
                            // Still extending: this guard holding again changes nothing.
                        }
                        _ => {
                            let axis = self.axis_vector(along, rig);
                            self.extension = Some(Extension {
                                transition: transition_id.index(),
                                axis,
                                speed_mps: speed_mps * self.overrides.speed_factor,
                                max_m: *max_m,
                                done_m: 0.0,
                                exhausted_at_s: None,
                                from_tool: rig.tool().translation.vector,
                            });
                            break;
                        }
                    }
                }
            }
        }
        self.guard_holds = holds;
        if let Some(extension) = &mut self.extension {
            if extension.exhausted_at_s.is_none() && extension.done_m >= extension.max_m {
                extension.exhausted_at_s = Some(t);
            }
        }
        next
    }

    /// Advances the DMPs and extension by `dt`; a force profile's clock runs slower while the
    /// applied force lags it (see [`profile_rate`]).
    pub(super) fn advance(&mut self, dt: f64, sensed: &Sensed) -> Result<(), ExecError> {
        if let Some(extension) = &mut self.extension {
            if extension.exhausted_at_s.is_none() {
                extension.done_m = (extension.done_m + extension.speed_mps * dt).min(extension.max_m);
            }
            let shift = extension.axis * extension.done_m;
            if let Some(motion) = &mut self.motion {
                let goal = motion.rollout.goal + shift;
                let result = motion.rollout.position.set_goal(goal.as_slice());
                self.check_goal(result)?;
            }
        }
        if let Some(lift) = &mut self.lift {
            if lift.lifting() {
                lift.done_m = (lift.done_m + lift.speed_mps * dt).min(lift.distance_m);
                // The motion waits until the tool is off the surface.
                return Ok(());
            }
        }
        if self.motion.as_ref().is_some_and(|m| m.run_finished() && !m.finished()) {
            self.next_run()?;
        }
        if let Some(motion) = &mut self.motion {
            let learned = self.bound.motions[motion.id].piece(motion.run);
            // Guarded approach: near the goal, run the motion's clock slower (a DMP's time
            // scaling), so the desired speed stays at the contact-safe speed.
            // Not during a search: its goal moves at the search speed already.
            let mut step = dt;
            if let (Some(guard), None) = (self.guarded, &self.extension) {
                let position = Vector3::from_column_slice(motion.rollout.position.position());
                let goal = Vector3::from_column_slice(motion.rollout.position.goal());
                motion.rollout.position.velocity_into(&mut self.velocity);
                let speed = Vector3::from(self.velocity).norm();
                if (goal - position).norm() < guard.zone_m && speed > guard.speed_mps {
                    step = dt * guard.speed_mps / speed;
                }
            }
            motion.rollout.step(learned, step);
            self.motion_clock_s += step;
            self.clock_rate = step / dt;
        }
        let profile_dmp =
            self.active()
                .and_then(|active| active.force)
                .and_then(|id| match self.bound.forces[id.index()] {
                    LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } => Some(dmp),
                    _ => None,
                });
        if let (Some(profile), Some(dmp)) = (&mut self.force_profile, profile_dmp) {
            let rate = match self.motion {
                Some(_) => moving_profile_rate(sensed.force_lag_n),
                None => {
                    // The profile's own rate along the compliant z, at full clock.
                    profile.velocity_into(&mut self.force_velocity[..profile.position().len()]);
                    let nominal = match profile.position().len() {
                        1 => self.force_velocity[0],
                        _ => Vector3::from(self.force_velocity).dot(&self.last_frame_z),
                    } * self.overrides.force_scale;
                    let travel = self.travel.as_ref().and_then(|travel| travel.clock_rate(nominal));
                    profile_rate(sensed.force_lag_n).min(travel.unwrap_or(1.0))
                }
            };
            // A profile ends at its duration and holds its last value: past it, without the
            // learned term, a force that dropped steeply would swing on (a contour's 0.6 N end
            // to -22 N) while a guard or a slowed motion keeps the state.
            if profile.time_s() < profile.tau_s() {
                profile.step(dmp, dt * rate);
            }
        }
        Ok(())
    }

    /// Starts the next run of the state's motion where the last one ended (its commanded
    /// flange pose), towards the next piece's goal moved by the offset fixed at entry: runs
    /// chain without a jump and do not drift.
    fn next_run(&mut self) -> Result<(), ExecError> {
        let Some(motion) = &self.motion else { return Ok(()) };
        let learned = self.bound.motions[motion.id];
        let run = motion.run + 1;
        let from = motion.rollout.flange();
        let started = MotionRollout::start(
            learned.piece(run),
            &from,
            motion.offset.into(),
            motion.speed,
            motion.max_tool_speed_mps,
            motion.lever_m,
        );
        let rollout = started.map_err(|err| self.motion_error(&self.skill().learn.motions[motion.id].name, &err))?;
        if let Some(motion) = &mut self.motion {
            motion.rollout = rollout;
            motion.run = run;
        }
        // Each run replays its segment from the start, and its per-sample frames with it (a
        // strokes motion times them by its stroke instead: `strokes_demo_time_s`).
        self.motion_clock_s = 0.0;
        Ok(())
    }

    /// Watches the contact of a state that controls a force along a translation while its
    /// motion runs (docs/method.md §7, lost contact): the contact is lost when the applied force
    /// along the desired one has stayed below half of it for longer than [`LOST_CONTACT_S`]
    /// after reaching it in the state, and the motion had more than [`LOST_CONTACT_STROKE_M`]
    /// of its path left, or runs still to make, when it was last in contact. States without a
    /// motion (a press in place), or before the force was first reached, are never judged.
    pub(super) fn lost_contact(
        &mut self,
        active: &ir::ActiveState,
        sensed: &Sensed,
        rig: &Rig<'_>,
        t: f64,
    ) -> Option<LostContact> {
        let forcing = active.position_controlled[..3].contains(&false);
        let motion = self.motion.as_ref()?;
        let desired_n = self.target_force.norm();
        if !forcing || desired_n < IN_CONTACT_N {
            self.contact.last_held_s = t;
            return None;
        }
        let applied_n = sensed.applied.fixed_rows::<3>(0).dot(&(self.target_force / desired_n));
        if applied_n >= 0.5 * desired_n {
            // The path left in the directions under position control: the force axis's own
            // component is where the surface is, not how far the stroke goes.
            let position = Vector3::from_column_slice(motion.rollout.position.position());
            let goal = Vector3::from_column_slice(motion.rollout.position.goal());
            let left = goal - position;
            let z = self.last_frame_z;
            self.contact = ContactWatch {
                armed: true,
                last_held_s: t,
                last_held_tool_m: rig.tool().translation.vector,
                stroke_left_m: (left - z * left.dot(&z)).norm(),
                runs_left: motion.runs.saturating_sub(motion.run + 1),
            };
            return None;
        }
        let watch = self.contact;
        if !watch.armed || t - watch.last_held_s <= LOST_CONTACT_S {
            return None;
        }
        (watch.runs_left > 0 || watch.stroke_left_m > LOST_CONTACT_STROKE_M).then(|| LostContact {
            t_s: t,
            since_s: watch.last_held_s,
            lost_at_m: watch.last_held_tool_m,
            tool_m: rig.tool().translation.vector,
            stroke_left_m: watch.stroke_left_m,
            runs_left: watch.runs_left,
            desired_n,
            applied_n,
        })
    }

    /// The desired force of the last command before its ramp (base frame).
    pub(super) fn target_force(&self) -> Vector3<f64> {
        self.target_force
    }

    /// The command of the current (active) state.
    pub(super) fn command(&mut self, active: &ir::ActiveState, rig: &Rig<'_>, t: f64) -> Command {
        let (flange, flange_v, omega) = match &self.motion {
            Some(motion) => {
                motion.rollout.position.velocity_into(&mut self.velocity);
                // A slowed clock slows the path's velocity too (the feed-forward the
                // controller tracks), not only the path.
                let rate = if self.lift.is_some_and(|lift| lift.lifting()) {
                    0.0
                } else {
                    self.clock_rate
                };
                (
                    motion.rollout.flange(),
                    Vector3::from(self.velocity) * rate,
                    motion.rollout.orientation.angular_velocity() * rate,
                )
            }
            None => {
                let mut held = self.held;
                if let Some(extension) = &self.extension {
                    held.translation.vector += extension.axis * extension.done_m;
                }
                (held, Vector3::zeros(), Vector3::zeros())
            }
        };
        let (mut pose, mut twist) = rig.tool_command(&flange, &flange_v, &omega);
        if let Some(lift) = &self.lift {
            let p = pose.translation.vector;
            let above = (p - lift.from).dot(&lift.away);
            if above < lift.done_m {
                pose.translation.vector += lift.away * (lift.done_m - above);
            }
            if lift.lifting() {
                let v = lift.away * lift.speed_mps;
                twist = Vector6::new(v.x, v.y, v.z, 0.0, 0.0, 0.0);
            }
        }
        self.follow_normal(rig, t);
        let frame = self.frame_pose(active.frame, rig, t);
        let scale = self.overrides.force_scale;
        let z = frame.rotation * Vector3::z();
        self.last_frame_z = z;
        let force = match active.force.map(|id| self.bound.forces[id.index()]) {
            None => Vector3::zeros(),
            Some(LearnedForce::Dmp { .. }) => {
                let p = self.force_profile.as_ref().map_or([0.0; 3], |r| {
                    let x = r.position();
                    [x[0], x[1], x[2]]
                });
                let force = Vector3::from(p) * scale;
                if self.motion.is_none() {
                    push_only(force, &z)
                } else {
                    force
                }
            }
            Some(LearnedForce::Magnitude { .. }) => {
                let force = z * self.force_profile.as_ref().map_or(0.0, |r| r.position()[0]) * scale;
                if self.motion.is_none() {
                    push_only(force, &z)
                } else {
                    force
                }
            }
            Some(other) => z * other.value_n().unwrap_or(0.0) * scale,
        };
        self.target_force = force;
        // At the switch to force control the desired force ramps from what the tool applied.
        let force = match self.ramp_from {
            Some((t0, from)) if t - t0 < FORCE_RAMP_S => from + (force - from) * ((t - t0) / FORCE_RAMP_S).max(0.0),
            _ => force,
        };
        let force_twist = match &mut self.travel {
            Some(travel) => {
                let applied = rig.controller.state().applied.fixed_rows::<3>(0).dot(&z);
                let desired = force.dot(&z);
                travel.update(t, rig.tool().translation.vector.dot(&z), applied, desired);
                let limit = rig
                    .controller
                    .gains()
                    .force_axis_speed_limit(desired - applied, desired);
                let v = z * travel.velocity(limit);
                travel.set_speed_limit(limit);
                Vector6::new(v.x, v.y, v.z, 0.0, 0.0, 0.0)
            }
            None => Vector6::zeros(),
        };
        Command {
            pose,
            twist,
            wrench: Vector6::new(force.x, force.y, force.z, 0.0, 0.0, 0.0),
            force_twist,
            frame,
            position: active.position_controlled,
            stiffness: active.stiffness,
            kp: active.gains.kp,
            ki: active.gains.ki,
            integral_limit: active.gains.integral_limit_n,
        }
    }
}

fn unit(axis: ir::Axis) -> Vector3<f64> {
    match axis {
        ir::Axis::X | ir::Axis::Rx => Vector3::x(),
        ir::Axis::Y | ir::Axis::Ry => Vector3::y(),
        ir::Axis::Z | ir::Axis::Rz => Vector3::z(),
    }
}

/// The largest force error over the force-controlled axes of `cmd`, in the compliant frame,
/// against `target_force` (the state's own, before any ramp) and the commanded moments: over all
/// of them, and over the translations only \[N\] (`None` where no such axis is force-controlled).
fn force_errors(cmd: &Command, target_force: &Vector3<f64>, applied: &Vector6<f64>) -> (Option<f64>, Option<f64>) {
    let rotation = cmd.frame.rotation.inverse();
    let desired = (
        rotation * target_force,
        rotation * cmd.wrench.fixed_rows::<3>(3).into_owned(),
    );
    let measured = (
        rotation * applied.fixed_rows::<3>(0).into_owned(),
        rotation * applied.fixed_rows::<3>(3).into_owned(),
    );
    let worst = |axes: std::ops::Range<usize>| {
        axes.filter(|&axis| !cmd.position[axis])
            .map(|axis| {
                if axis < 3 {
                    (desired.0[axis] - measured.0[axis]).abs()
                } else {
                    (desired.1[axis - 3] - measured.1[axis - 3]).abs()
                }
            })
            .reduce(f64::max)
    };
    let forces = worst(0..3);
    let moments = worst(3..6);
    let all = match (forces, moments) {
        (Some(f), Some(m)) => Some(f.max(m)),
        (f, m) => f.or(m),
    };
    (all, forces)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}

//! The skill's state machine between ticks (docs/method.md §7): the current state and what it
//! runs (motion, force profile, goal extension), state entry and its actions, guards, the choice
//! of at most one transition a tick, and the command of an active state.
//!
//! This file holds the machine's state and its start; the rest is split by job: [`entry`] (state
//! entry and its actions, the guarded approach), [`guards`] (what guards see, their evaluation and
//! the choice of a transition), [`contact`] (the watch over a pushing state's contact), [`frames`]
//! (compliant frames and axes now), [`follow`] (lift-off and following the contact normal),
//! [`profile`] (the force profile's clock and the desired force), [`tick`] (advancing a state and
//! its command).

use std::collections::HashMap;

use nalgebra::{Isometry3, Vector3};
use skill_ir as ir;

use super::bind::BoundSkill;
use super::motion::MotionRollout;
use super::rig::Rig;
use super::run::ExecError;
use crate::control::travel::TravelFeedForward;
use crate::dmp::DmpRollout;

mod contact;
mod entry;
mod follow;
mod frames;
mod guards;
mod profile;
mod tick;

#[cfg(test)]
mod tests;

use contact::ContactWatch;
pub(super) use contact::LostContact;
use entry::GuardedApproach;
use follow::{LiftOff, NormalFollow};
use guards::HeldTimers;
pub(super) use guards::Sensed;

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

    fn time_in_state(&self, t: f64) -> f64 {
        t - self.entered_s
    }

    /// The desired force of the last command before its ramp (base frame).
    pub(super) fn target_force(&self) -> Vector3<f64> {
        self.target_force
    }
}

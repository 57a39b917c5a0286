//! A run on a rig: the skill's state machine tick by tick until a terminal state or the time
//! limit ([`run_skill`]), or the thesis's replay baseline ([`run_replay`]); what a run is told
//! ([`ExecOptions`]), how it ended ([`RunReport`]) and why it could not go on ([`ExecError`]).

use nalgebra::Vector3;
use skill_ir as ir;

use super::bind::BoundSkill;
use super::limits::{limits_for, reflex_message};
use super::log::RunLog;
use super::machine::{LostContact, Machine, Sensed};
use super::motion::{motion_start, motions_in_order, MotionRollout};
use super::rig::Rig;
use crate::control::Command;
use crate::plant::{ContactAudit, PlantError};
use crate::robot::RobotError;
use crate::safety::{SafetyStats, Violation};
use crate::skill::Learned;

/// How a run is carried out.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecOptions {
    /// Control period \[s\] (1 ms, as on the LWR's fast research interface).
    pub dt_s: f64,
    /// A run longer than this fails \[s\].
    pub max_duration_s: f64,
    /// Task overrides (force scale, speed, goal offset).
    pub overrides: ir::Overrides,
    /// First move to the demonstration's start pose in free space, as an operator would.
    pub prepose: bool,
    /// Record every tick.
    pub log: bool,
    /// Stiffness of the replay baseline and of the pre-positioning move, per axis (N/m, N m/rad).
    pub replay_stiffness: [f64; 6],
    /// Safety limits a task step sets (its `limits: { }`), applied after the skill's own
    /// `limits { }` block and before [`ExecOptions::limits`].
    pub step_limits: Vec<ir::Limit>,
    /// Safety limits set by the user, applied in order last: over the defaults the learned file
    /// implies, the skill's `limits { }` and the step's (names as in
    /// [`crate::safety::Limits::set`], SI values).
    pub limits: Vec<(String, f64)>,
    /// Where the logs of the runs made with these options also send their ticks as they are
    /// logged (a file writer on another thread); `None` keeps them in the log only.
    pub tap: Option<super::log::LogTap>,
}

impl Default for ExecOptions {
    fn default() -> Self {
        ExecOptions {
            dt_s: 0.001,
            max_duration_s: 120.0,
            overrides: ir::Overrides::default(),
            prepose: true,
            log: true,
            replay_stiffness: [2000.0, 2000.0, 2000.0, 150.0, 150.0, 150.0],
            step_limits: Vec::new(),
            limits: Vec::new(),
            tap: None,
        }
    }
}

/// Why a run could not go on (a skill reaching a failure state is not an error).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExecError {
    /// The plant failed (e.g. its state became NaN).
    #[error("the plant failed in state `{state}` at t = {t_s:.3} s")]
    Plant {
        /// The state running when the plant failed (`prepose`, `replay:<motion>` or a skill state).
        state: String,
        /// Run time at the start of the failed step \[s\].
        t_s: f64,
        /// What the plant reported.
        #[source]
        source: PlantError,
    },
    /// The robot model does not fit the run.
    #[error(transparent)]
    Robot(#[from] RobotError),
    /// A DMP could not be set up (non-finite goal or start, or a duration that is not positive).
    #[error("cannot start motion `{motion}` in state `{state}`: {reason}")]
    Motion {
        /// The state whose motion or force profile it is (`replay:<motion>` in a replay).
        state: String,
        /// The learned motion, or the learned force whose profile it is.
        motion: String,
        /// The DMP's complaint (which value was out of range).
        reason: String,
    },
    /// A limit override that cannot be set (unknown name, not positive).
    #[error("{reason}")]
    Limits {
        /// What is wrong with it.
        reason: String,
    },
    /// A state moves `at NAME` before the run has captured NAME. `run_skill` turns this into a
    /// failed [`RunReport`] whose message names the capture, the state and its `.skill` line.
    #[error("{message}")]
    NotCaptured {
        /// The state that moves at the capture.
        state: String,
        /// The capture and where it is made, in words.
        message: String,
    },
    /// The supervisor stopped the arm. `run_skill` and `run_replay` turn this into a failed
    /// [`RunReport`]; callers of lower-level functions see it as an error.
    #[error("reflex stop in `{state}`: {violation}")]
    Reflex {
        /// The state running when the limit was crossed.
        state: String,
        /// What was crossed.
        violation: Box<Violation>,
    },
}

/// A time in one state.
#[derive(Debug, Clone, PartialEq)]
pub struct Visit {
    /// The state's name.
    pub state: String,
    /// Entry \[s\].
    pub enter_s: f64,
    /// Exit \[s\].
    pub exit_s: f64,
    /// Where the tool point was at entry \[m\], base frame (what a later task step's
    /// `at: STEP.STATE` places its goal at).
    pub enter_position_m: [f64; 3],
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub struct RunReport {
    /// Success or failure.
    pub outcome: ir::Outcome,
    /// The terminal state reached, if any.
    pub terminal: Option<String>,
    /// A message for the user (for failures: the state, the guard and where it is written).
    pub message: String,
    /// States in the order visited.
    pub visits: Vec<Visit>,
    /// Run time \[s\].
    pub duration_s: f64,
    /// The limit whose crossing stopped the run, if one did.
    pub reflex: Option<Violation>,
    /// Peak force and speed, smallest joint margin, time at the torque limit.
    pub safety: SafetyStats,
    /// The plant's contact witness over the run (`None` for plants without one).
    pub contact: Option<ContactAudit>,
}

impl RunReport {
    /// A failure before anything moved, e.g. a task step whose `at:` pose was never found.
    pub fn not_started(message: String) -> Self {
        RunReport {
            outcome: ir::Outcome::Failure,
            terminal: None,
            message,
            visits: Vec::new(),
            duration_s: 0.0,
            reflex: None,
            safety: SafetyStats::default(),
            contact: None,
        }
    }

    /// Whether the run failed because the contact was lost mid-stroke (its message starts
    /// with [`LOST_CONTACT`]).
    pub fn lost_contact(&self) -> bool {
        self.outcome == ir::Outcome::Failure && self.message.starts_with(LOST_CONTACT)
    }
}

/// The word a lost-contact failure's message starts with, and the reason eval gives it.
pub const LOST_CONTACT: &str = "lost_contact";

/// The name of the replay state that covers `segment` (0-based): `replay:<motion>` for the
/// segment's learned motion (the first by name), `replay:segment <n>` (1-based) without one.
pub fn replay_state(learned: &Learned, segment: usize) -> String {
    match learned.motions.iter().find(|(_, motion)| motion.segment == segment) {
        Some((name, _)) => format!("replay:{name}"),
        None => format!("replay:segment {}", segment + 1),
    }
}

fn location(span: &ir::SourceSpan) -> String {
    format!("{}:{}:{}", span.file, span.line, span.column)
}

/// Moves to the start of the first learned motion (moved by the goal offset), when asked to.
fn prepose_for(
    learned: &Learned,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    log: &mut Option<&mut RunLog>,
) -> Result<(), ExecError> {
    if options.prepose {
        if let Some((_, first)) = motions_in_order(learned).first() {
            let mut target = motion_start(first);
            target.translation.vector += Vector3::from(options.overrides.goal_offset_m);
            rig.prepose(&target, options, log)?;
        }
    }
    Ok(())
}

/// Runs a bound skill on a rig until a terminal state (or the time limit), under the
/// supervisor with the limits [`limits_for`] gives (defaults from the learned file, then the
/// skill's `limits { }`, [`ExecOptions::step_limits`] and [`ExecOptions::limits`]). A reflex ends the run as a failure whose message names the time,
/// the state and its `.skill` line, the quantity, the measured value and the limit.
pub fn run_skill(
    bound: &BoundSkill<'_>,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    log: Option<&mut RunLog>,
) -> Result<RunReport, ExecError> {
    let start_s = arm_supervisor(bound.learned, &bound.skill.limits, rig, options)?;
    let mut visits = Vec::new();
    let mut log = log;
    reserve_log(&mut log, options);
    let result = skill_loop(bound, rig, options, log.as_deref_mut(), &mut visits, start_s);
    if let Some(log) = log {
        log.finish();
    }
    let location_of = |state: &str| {
        bound
            .skill
            .states
            .iter()
            .find(|s| s.name == state)
            .map(|s| location(&s.span))
    };
    finish(result, rig, visits, start_s, location_of)
}

/// The longest nominal pre-positioning move, hold included \[s\] (`Rig::prepose`: at most 8 s and
/// 0.3 s; tight speed limits or `--speed` below 1 make it longer, and the log then grows).
const PREPOSE_MAX_S: f64 = 8.3;
/// Runs longer than this many ticks reserve their log only this far (then it grows).
const MAX_RESERVED_TICKS: usize = 300_000;

/// Reserves the log for the longest run `options` allow (pre-positioning, the run, a reflex
/// hold), so that no tick reallocates it; the caller shrinks it to its length afterwards.
fn reserve_log(log: &mut Option<&mut RunLog>, options: &ExecOptions) {
    if let Some(log) = log.as_deref_mut() {
        let longest_s = options.max_duration_s + PREPOSE_MAX_S + crate::safety::REFLEX_HOLD_S;
        let ticks = (longest_s / options.dt_s).ceil() + 2.0;
        let ticks = if ticks.is_finite() && ticks > 0.0 {
            (ticks as usize).min(MAX_RESERVED_TICKS)
        } else {
            MAX_RESERVED_TICKS
        };
        log.reserve(ticks);
    }
}

/// Sets the supervisor's limits for a run of `learned` (with the limits its skill declares, if
/// any) and starts its figures afresh; returns the run's start time.
fn arm_supervisor(
    learned: &Learned,
    skill_limits: &[ir::Limit],
    rig: &mut Rig<'_>,
    options: &ExecOptions,
) -> Result<f64, ExecError> {
    rig.sense();
    let tool = rig.tool().translation.vector;
    let declared: Vec<&ir::Limit> = skill_limits.iter().chain(&options.step_limits).collect();
    let limits = limits_for(
        learned,
        rig.flange_to_tool(),
        Some([tool.x, tool.y, tool.z]),
        options.overrides.force_scale,
        &declared,
        &options.limits,
    )
    .map_err(|err| ExecError::Limits {
        reason: err.to_string(),
    })?;
    rig.set_limits(limits);
    rig.reset_safety_stats();
    // The witness counts this run's steps only.
    rig.plant.take_contact_audit();
    Ok(rig.time_s())
}

/// Turns a run's result into its report: a reflex becomes a failure, the safety figures and the
/// contact witness's findings are added, and a run whose contacts broke the witness's rules is a
/// failure (`contact_witness`): its forces were not where the geometry is, so its verdict would
/// claim nothing about the world.
fn finish(
    result: Result<RunReport, ExecError>,
    rig: &mut Rig<'_>,
    mut visits: Vec<Visit>,
    start_s: f64,
    location_of: impl Fn(&str) -> Option<String>,
) -> Result<RunReport, ExecError> {
    // A run stopped on the way: the last visit ends now, the run is a failure without a terminal.
    let stopped = |message: String, reflex: Option<Violation>| {
        let duration_s = rig.time_s() - start_s;
        if let Some(last) = visits.last_mut() {
            last.exit_s = duration_s;
        }
        RunReport {
            outcome: ir::Outcome::Failure,
            terminal: None,
            message,
            visits,
            duration_s,
            reflex,
            safety: SafetyStats::default(),
            contact: None,
        }
    };
    let mut report = match result {
        Ok(report) => report,
        Err(ExecError::Reflex { state, violation }) => stopped(
            reflex_message(&violation, &state, location_of(&state).as_deref()),
            Some(*violation),
        ),
        Err(ExecError::NotCaptured { state, message }) => {
            let message = match location_of(&state) {
                Some(location) => format!("{message} ({location})"),
                None => message,
            };
            stopped(message, None)
        }
        // A plant in another process that fell silent: the run cannot go on; a plant still
        // running stops the arm on its own side when commands stop (docs/split.md). A failure
        // of the run with its reason, not an error: the ticks up to it are the run's log.
        Err(ExecError::Plant {
            state,
            t_s,
            source: PlantError::Link { reason, .. },
        }) => stopped(
            format!(
                "{PLANT_LINK}: the link to the plant failed in state `{state}` at t = {t_s:.3} s: {reason}; a plant still running brings the arm to its damped stop when commands stop coming"
            ),
            None,
        ),
        Err(other) => return Err(other),
    };
    report.safety = rig.safety_stats().clone();
    report.contact = rig.plant.take_contact_audit();
    if let Some(audit) = report.contact.as_ref().filter(|audit| audit.violated()) {
        if report.outcome == ir::Outcome::Success {
            report.outcome = ir::Outcome::Failure;
            report.terminal = None;
            report.message = format!(
                "{CONTACT_WITNESS}: the simulated contacts are not where the shapes are; {}",
                audit.summary()
            );
        }
    }
    Ok(report)
}

/// The word a failure of the contact witness's rules starts with, and the reason eval gives it.
pub const CONTACT_WITNESS: &str = "contact_witness";

/// The word the failure of a run whose plant (in another process) fell silent starts with.
pub const PLANT_LINK: &str = "plant_link";

fn skill_loop(
    bound: &BoundSkill<'_>,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    mut log: Option<&mut RunLog>,
    visits: &mut Vec<Visit>,
    start_s: f64,
) -> Result<RunReport, ExecError> {
    let skill = bound.skill;
    prepose_for(bound.learned, rig, options, &mut log)?;
    let run_start = rig.time_s();
    rig.sense();
    let mut machine = Machine::start(bound, options.overrides, rig)?;
    visits.push(Visit {
        state: machine.state().name.clone(),
        enter_s: rig.time_s() - start_s,
        exit_s: 0.0,
        enter_position_m: rig.tool().translation.vector.into(),
    });
    let mut last_cmd: Option<Command> = None;
    let dt = options.dt_s;
    loop {
        let t = rig.time_s();
        let state = machine.state();
        if let ir::StateKind::Terminal { outcome, message } = &state.kind {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            let text = message.clone().unwrap_or_else(|| match outcome {
                ir::Outcome::Success => format!("reached `{}`", state.name),
                ir::Outcome::Failure => format!("ended in failure state `{}`", state.name),
            });
            return Ok(RunReport {
                outcome: *outcome,
                terminal: Some(state.name.clone()),
                message: text,
                visits: std::mem::take(visits),
                duration_s: t - start_s,
                reflex: None,
                safety: SafetyStats::default(),
                contact: None,
            });
        }
        if t - run_start > options.max_duration_s {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            return Ok(RunReport {
                outcome: ir::Outcome::Failure,
                terminal: None,
                message: format!(
                    "the run exceeded {:.0} s in state `{}` ({})",
                    options.max_duration_s,
                    state.name,
                    location(&state.span)
                ),
                visits: std::mem::take(visits),
                duration_s: t - start_s,
                reflex: None,
                safety: SafetyStats::default(),
                contact: None,
            });
        }
        let active = machine.active().expect("terminal states returned above");
        let sensed = Sensed::of(rig, last_cmd.as_ref(), machine.target_force());
        if let Some((target, transition)) = machine.choose(active, &sensed, rig, t) {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            let transition = &skill.transitions[transition];
            visits.push(Visit {
                state: skill.states[target.index()].name.clone(),
                enter_s: t - start_s,
                exit_s: 0.0,
                enter_position_m: rig.tool().translation.vector.into(),
            });
            machine.enter(target, t, rig)?;
            if let ir::StateKind::Terminal {
                outcome: ir::Outcome::Failure,
                message,
            } = &skill.states[target.index()].kind
            {
                let from = &skill.states[transition.from.index()].name;
                let why = message
                    .clone()
                    .unwrap_or_else(|| format!("ended in failure state `{}`", skill.states[target.index()].name));
                let timed_out = matches!(transition.guard, ir::Guard::Timeout { .. });
                let text = format!(
                    "{why}: {} `on {}` in state `{from}` ({})",
                    if timed_out { "timed out on" } else { "left by" },
                    transition.guard_text,
                    location(&transition.span)
                );
                return Ok(RunReport {
                    outcome: ir::Outcome::Failure,
                    terminal: Some(skill.states[target.index()].name.clone()),
                    message: text,
                    visits: std::mem::take(visits),
                    duration_s: t - start_s,
                    reflex: None,
                    safety: SafetyStats::default(),
                    contact: None,
                });
            }
            continue;
        }
        if let Some(lost) = machine.lost_contact(active, &sensed, rig, t) {
            let last = visits.last_mut().expect("a visit per state");
            last.exit_s = t - start_s;
            return Ok(RunReport {
                outcome: ir::Outcome::Failure,
                terminal: None,
                message: lost_contact_message(&lost, &state.name, &location(&state.span), start_s),
                visits: std::mem::take(visits),
                duration_s: t - start_s,
                reflex: None,
                safety: SafetyStats::default(),
                contact: None,
            });
        }

        machine.advance(dt, &sensed)?;
        let cmd = machine.command(active, rig, t);
        let state_index = log.as_mut().map_or(0, |log| log.state_index(&state.name));
        rig.act(&cmd, state_index, &state.name, log.as_deref_mut(), dt)?;
        rig.sense();
        last_cmd = Some(cmd);
    }
}

/// The failure message of a contact lost mid-stroke (docs/method.md §7): it starts with
/// `lost_contact`, then when (run time, as the report's visits count it), the state and its
/// `.skill` line, where the tool was and how much of the stroke was left.
fn lost_contact_message(lost: &LostContact, state: &str, location: &str, start_s: f64) -> String {
    let (at, now) = (lost.lost_at_m, lost.tool_m);
    let left = match lost.runs_left {
        0 => format!("{:.1} mm of its stroke left", lost.stroke_left_m * 1e3),
        n => format!(
            "{:.1} mm of this stroke and {n} more run(s) left",
            lost.stroke_left_m * 1e3
        ),
    };
    format!(
        "{LOST_CONTACT}: the contact was lost at t = {:.3} s in state `{state}` ({location}), the tool at \
         ({:.3}, {:.3}, {:.3}) m with {left}: the force along the desired {:.1} N stayed below half of it \
         for {:.0} ms (now {:.1} N, the tool at ({:.3}, {:.3}, {:.3}) m)",
        lost.since_s - start_s,
        at.x,
        at.y,
        at.z,
        lost.desired_n,
        (lost.t_s - lost.since_s) * 1e3,
        lost.applied_n,
        now.x,
        now.y,
        now.z,
    )
}

/// The thesis's baseline: the demonstration replayed under pure impedance control, with no
/// force control and no contact adaptation. It has no skill, so no skill's `limits { }`: the
/// supervisor uses the defaults, [`ExecOptions::step_limits`] and [`ExecOptions::limits`]. Segments run in order: a segment with a learned
/// motion replays it from the current pose; a segment without one (e.g. the press itself)
/// holds the pose for the segment's duration, as the demonstration did.
pub fn run_replay(
    learned: &Learned,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    log: Option<&mut RunLog>,
) -> Result<RunReport, ExecError> {
    let start_s = arm_supervisor(learned, &[], rig, options)?;
    let mut visits = Vec::new();
    let mut log = log;
    reserve_log(&mut log, options);
    let result = replay_loop(learned, rig, options, log.as_deref_mut(), &mut visits, start_s);
    if let Some(log) = log {
        log.finish();
    }
    finish(result, rig, visits, start_s, |_| None)
}

fn replay_loop(
    learned: &Learned,
    rig: &mut Rig<'_>,
    options: &ExecOptions,
    mut log: Option<&mut RunLog>,
    visits: &mut Vec<Visit>,
    start_s: f64,
) -> Result<RunReport, ExecError> {
    let order = motions_in_order(learned);
    prepose_for(learned, rig, options, &mut log)?;
    let dt = options.dt_s;
    let speed = options.overrides.speed_factor;
    let mut velocity = [0.0; 3];
    rig.sense();
    let mut held = rig.flange();
    for (segment_index, segment) in learned.segments.iter().enumerate() {
        let motion = order.iter().find(|(_, motion)| motion.segment == segment_index);
        let state_name = replay_state(learned, segment_index);
        let state = log.as_mut().map_or(0, |log| log.state_index(&state_name));
        let enter_s = rig.time_s() - start_s;
        let enter_position_m: [f64; 3] = rig.tool().translation.vector.into();
        match motion {
            Some((name, motion)) => {
                let mut rollout = MotionRollout::start(
                    motion,
                    &held,
                    options.overrides.goal_offset_m,
                    speed,
                    rig.limits().tool_speed_mps,
                    rig.flange_to_tool().translation.vector.norm(),
                )
                .map_err(|err| ExecError::Motion {
                    state: state_name.clone(),
                    motion: (*name).clone(),
                    reason: err.to_string(),
                })?;
                let steps = ((motion.position.tau_s / speed) / dt).round() as usize;
                for _ in 0..steps {
                    rollout.step(motion, dt);
                    rollout.position.velocity_into(&mut velocity);
                    held = rollout.flange();
                    let (pose, twist) =
                        rig.tool_command(&held, &Vector3::from(velocity), &rollout.orientation.angular_velocity());
                    let cmd = rig.impedance_hold(pose, twist, options.replay_stiffness);
                    rig.act(&cmd, state, &state_name, log.as_deref_mut(), dt)?;
                    rig.sense();
                }
            }
            None => {
                let steps = (((segment.end_s - segment.start_s) / speed) / dt).round() as usize;
                let (pose, _) = rig.tool_command(&held, &Vector3::zeros(), &Vector3::zeros());
                for _ in 0..steps {
                    let cmd = rig.impedance_hold(pose, nalgebra::Vector6::zeros(), options.replay_stiffness);
                    rig.act(&cmd, state, &state_name, log.as_deref_mut(), dt)?;
                    rig.sense();
                }
            }
        }
        visits.push(Visit {
            state: state_name,
            enter_s,
            exit_s: rig.time_s() - start_s,
            enter_position_m,
        });
    }
    Ok(RunReport {
        outcome: ir::Outcome::Success,
        terminal: None,
        message: "replayed every segment".to_string(),
        visits: std::mem::take(visits),
        duration_s: rig.time_s() - start_s,
        reflex: None,
        safety: SafetyStats::default(),
        contact: None,
    })
}

//! Serving a plant: each control period the state goes out on `/skillc/state`, `/joint_states` and
//! `/wrench`, and torques come in on `/joint_effort_commands`. A run opens a session with the
//! start query, in one of two modes:
//!
//! - **lockstep**: the plant steps once per command, so a run over the link computes exactly what
//!   it computes in one process. Without commands it stands still and repeats its state every
//!   [`HEARTBEAT`] (so a run or a ROS 2 tool that joins late sees it).
//! - **realtime**: the plant steps on its own clock, one period at a time. A command counts for a
//!   tick only if it answers the state published just before (its sequence number is that state's
//!   tick + 1); when none has come by the tick, the plant holds the last torques and counts the
//!   tick late, and a command that comes after its tick is dropped, never applied to another. A
//!   controller silent for longer than [`ServeOptions::silence`] gets the damped stop: gravity
//!   compensation with joint damping, until commands come again.
//!
//! Foreign ROS 2 controllers drive the plant in lockstep (its default before any session): every
//! command they publish steps it once.
//!
//! A second query, the witness ([`crate::witness_key`]), hands the run what the plant's contact
//! witness found since the run last asked, as JSON; the plant keeps the sum of all it handed out
//! for its own summary.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use skill_robot::plant::{ContactAudit, Observation, Plant};
use skill_robot::Robot;
use skill_ros::msgs::{self, Float64MultiArray, Header, JointState, MsgType, Time, WrenchStamped};
use zenoh::query::Query;
use zenoh::{Session, Wait};

use crate::node::{self, Node, RosPublisher};
use crate::wire::{self, State};
use crate::{start_key, witness_key, TransportError, COMMANDS, JOINT_STATES, STATE, WRENCH};

/// How often a plant that is not stepping repeats its state.
pub const HEARTBEAT: Duration = Duration::from_millis(100);
/// In realtime, how long before each tick the plant polls for its command instead of sleeping.
const SPIN: Duration = Duration::from_micros(400);

/// How a plant is served.
#[derive(Debug, Clone)]
pub struct ServeOptions {
    /// The ROS domain.
    pub domain: u32,
    /// The control period, s.
    pub period_s: f64,
    /// In realtime, how long without a command before the damped stop.
    pub silence: Duration,
    /// The node's name.
    pub node_name: String,
    /// The frame the wrench is written in (the sensor's link).
    pub sensor_frame: String,
}

/// What a plant did while it was served.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ServeSummary {
    /// Steps taken.
    pub ticks: u64,
    /// Sessions runs opened.
    pub sessions: u64,
    /// Commands applied.
    pub commands: u64,
    /// Realtime ticks without their command (the last torques held).
    pub late: u64,
    /// Commands dropped because their tick had passed.
    pub dropped: u64,
    /// Commands that could not be read (wrong length or bytes), dropped.
    pub malformed: u64,
    /// Times the damped stop took over from a silent controller.
    pub damped_stops: u64,
    /// What the contact witness found over the steps it handed to runs (`None` for a plant without
    /// one, or before any run asked); the steps since the last question are the plant's to take.
    pub contact: Option<ContactAudit>,
}

/// How a session runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pace {
    Lockstep,
    Realtime,
}

enum Event {
    /// Torques, or (`stop`) the plant's own damped stop from now on.
    Command {
        torques: Vec<f64>,
        stop: bool,
        sequence: Option<i64>,
    },
    Malformed,
    Start(Query),
    Witness(Query),
}

struct Outlets {
    state: RosPublisher,
    joints: RosPublisher,
    wrench: RosPublisher,
    names: Vec<String>,
    sensor_frame: String,
}

impl Outlets {
    fn publish(&self, state: &State, effort: &[f64]) -> Result<(), TransportError> {
        self.state.put(state.encode().encode())?;
        let header = Header {
            stamp: Time::from_seconds(state.obs.t),
            frame_id: String::new(),
        };
        let joints = JointState {
            header: header.clone(),
            name: self.names.clone(),
            position: state.obs.q.as_slice().to_vec(),
            velocity: state.obs.qd.as_slice().to_vec(),
            effort: effort.to_vec(),
        };
        self.joints.put(joints.encode())?;
        let w = &state.obs.wrench_sensor;
        let wrench = WrenchStamped {
            header: Header {
                frame_id: self.sensor_frame.clone(),
                ..header
            },
            force: [w[0], w[1], w[2]],
            torque: [w[3], w[4], w[5]],
        };
        self.wrench.put(wrench.encode())
    }
}

/// Serves `plant` (whose arm `robot` models) on `session` until `stop` is set (by a signal).
pub fn serve(
    session: &Session,
    plant: &mut dyn Plant,
    robot: &Robot,
    options: &ServeOptions,
    stop: &AtomicBool,
) -> Result<ServeSummary, TransportError> {
    let dof = plant.dof();
    let (tx, rx) = mpsc::channel::<Event>();
    let mut ros = Node::new(session, options.domain, &options.node_name)?;
    let outlets = Outlets {
        state: ros.publisher(session, STATE, MsgType::Float64MultiArray)?,
        joints: ros.publisher(session, JOINT_STATES, MsgType::JointState)?,
        wrench: ros.publisher(session, WRENCH, MsgType::WrenchStamped)?,
        names: robot.joints().iter().map(|joint| joint.name.clone()).collect(),
        sensor_frame: options.sensor_frame.clone(),
    };
    let commands_tx = tx.clone();
    let _commands = ros.subscription(session, COMMANDS, MsgType::Float64MultiArray, move |sample| {
        let (payload, attachment) = node::sample_parts(&sample);
        let sequence = attachment.map(|a| a.sequence);
        let event = match Float64MultiArray::decode(&payload).ok().and_then(|array| {
            match wire::decode_command(&array, dof).ok()? {
                wire::Command::Effort(torques) => Some((torques.to_vec(), false)),
                wire::Command::DampedStop => Some((Vec::new(), true)),
            }
        }) {
            Some((torques, stop)) => Event::Command {
                torques,
                stop,
                sequence,
            },
            None => Event::Malformed,
        };
        let _ = commands_tx.send(event);
    })?;
    let queryable = |key: String, event: fn(Query) -> Event| {
        let tx = tx.clone();
        session
            .declare_queryable(key.clone())
            .callback(move |query| {
                let _ = tx.send(event(query));
            })
            .wait()
            .map_err(|err| TransportError::Zenoh {
                what: format!("declaring the queryable `{key}`"),
                reason: err.to_string(),
            })
    };
    let _start = queryable(start_key(options.domain), Event::Start)?;
    let _witness = queryable(witness_key(options.domain), Event::Witness)?;
    drop(tx);

    let mut server = Server {
        plant,
        robot,
        data: robot.data(),
        obs: Observation::zeros(dof),
        torques: vec![0.0; dof],
        hold: vec![0.0; dof],
        tick: 0,
        published_at: Instant::now(),
        round_trip_us: f64::NAN,
        summary: ServeSummary::default(),
        period_s: options.period_s,
    };
    server.publish(&outlets, false, f64::NAN)?;
    let mut pace = Pace::Lockstep;
    while !stop.load(Ordering::Relaxed) {
        pace = match pace {
            Pace::Lockstep => server.lockstep(&rx, &outlets, stop)?,
            Pace::Realtime => server.realtime(&rx, &outlets, options, stop)?,
        };
    }
    Ok(server.summary)
}

struct Server<'a> {
    plant: &'a mut dyn Plant,
    robot: &'a Robot,
    data: skill_robot::RobotData,
    obs: Observation,
    /// The torques applied last.
    torques: Vec<f64>,
    hold: Vec<f64>,
    tick: u64,
    published_at: Instant,
    round_trip_us: f64,
    summary: ServeSummary,
    period_s: f64,
}

impl Server<'_> {
    /// The state to publish now.
    fn state(&mut self, round_trip_us: f64, late: bool, period_us: f64) -> State {
        self.plant.observe_into(&mut self.obs);
        let mut parts = Vec::new();
        self.plant
            .visit_parts(&mut |name, offset| parts.push((name.to_owned(), offset)));
        State {
            tick: self.tick,
            obs: self.obs.clone(),
            round_trip_us,
            late,
            period_us,
            parts,
        }
    }

    fn publish(&mut self, outlets: &Outlets, late: bool, period_us: f64) -> Result<(), TransportError> {
        let state = self.state(self.round_trip_us, late, period_us);
        outlets.publish(&state, &self.torques)?;
        self.published_at = Instant::now();
        self.round_trip_us = f64::NAN;
        Ok(())
    }

    fn step(&mut self, torques: Option<&[f64]>) -> Result<(), TransportError> {
        if let Some(torques) = torques {
            self.plant.apply(torques)?;
            self.torques.copy_from_slice(torques);
        }
        self.plant.step(self.period_s)?;
        self.tick += 1;
        Ok(())
    }

    /// Answers a start query with the current state; the mode it asks for.
    fn start(&mut self, query: &Query) -> Option<Pace> {
        let asked = query
            .payload()
            .and_then(|bytes| msgs::decode_string(&bytes.to_bytes()).ok())
            .unwrap_or_default();
        let pace = match asked.as_str() {
            "lockstep" => Pace::Lockstep,
            "realtime" => Pace::Realtime,
            _ => {
                let _ = query
                    .reply_err(msgs::encode_string(&format!(
                        "unknown mode `{asked}`: ask for `lockstep` or `realtime`"
                    )))
                    .wait();
                return None;
            }
        };
        let state = self.state(f64::NAN, false, f64::NAN);
        let _ = query.reply(query.key_expr().clone(), state.encode().encode()).wait();
        self.published_at = Instant::now();
        self.summary.sessions += 1;
        Some(pace)
    }

    /// Answers a witness query with what the contact witness found since the last one, and adds
    /// it to the plant's own sum.
    fn witness(&mut self, query: &Query) {
        let audit = self.plant.take_contact_audit();
        if let Some(audit) = &audit {
            self.summary
                .contact
                .get_or_insert_with(ContactAudit::default)
                .merge(audit.clone());
        }
        let json = serde_json::to_string(&audit).unwrap_or_else(|_| "null".to_owned());
        let _ = query.reply(query.key_expr().clone(), msgs::encode_string(&json)).wait();
    }

    fn lockstep(
        &mut self,
        rx: &mpsc::Receiver<Event>,
        outlets: &Outlets,
        stop: &AtomicBool,
    ) -> Result<Pace, TransportError> {
        while !stop.load(Ordering::Relaxed) {
            match rx.recv_timeout(HEARTBEAT) {
                Ok(Event::Command { torques, stop, .. }) => {
                    self.round_trip_us = self.published_at.elapsed().as_secs_f64() * 1e6;
                    if stop {
                        // The same torques the run's supervisor computes from the same state.
                        self.step_damped_stop()?;
                    } else {
                        self.step(Some(&torques))?;
                    }
                    self.summary.commands += 1;
                    self.summary.ticks += 1;
                    self.publish(outlets, false, f64::NAN)?;
                }
                Ok(Event::Malformed) => self.summary.malformed += 1,
                Ok(Event::Start(query)) => {
                    if let Some(Pace::Realtime) = self.start(&query) {
                        return Ok(Pace::Realtime);
                    }
                }
                Ok(Event::Witness(query)) => self.witness(&query),
                Err(mpsc::RecvTimeoutError::Timeout) => self.publish(outlets, false, f64::NAN)?,
                Err(mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
        Ok(Pace::Lockstep)
    }

    /// One step under the damped stop, its torques computed at the current state (the same
    /// function and state as the run's supervisor, so lockstep stays bit for bit).
    fn step_damped_stop(&mut self) -> Result<(), TransportError> {
        self.plant.observe_into(&mut self.obs);
        self.robot.damped_stop_torques(
            &mut self.data,
            self.obs.q.as_slice(),
            self.obs.qd.as_slice(),
            &mut self.hold,
        );
        let hold = std::mem::take(&mut self.hold);
        let stepped = self.step(Some(&hold));
        self.hold = hold;
        stepped
    }

    fn realtime(
        &mut self,
        rx: &mpsc::Receiver<Event>,
        outlets: &Outlets,
        options: &ServeOptions,
        stop: &AtomicBool,
    ) -> Result<Pace, TransportError> {
        let period = Duration::from_secs_f64(self.period_s);
        // The session's clock starts with the run's first command (its answer to the state the
        // start query returned): until then the plant stands still, repeating its state, so the
        // run's preparations (pre-positioning's plan, say) cost it no ticks.
        let (first, mut run_stopped) = loop {
            if stop.load(Ordering::Relaxed) {
                return Ok(Pace::Realtime);
            }
            match rx.recv_timeout(HEARTBEAT) {
                Ok(Event::Command {
                    torques,
                    stop: stop_asked,
                    sequence,
                }) if sequence == Some(self.tick as i64 + 1) => break (torques, stop_asked),
                Ok(Event::Command { .. }) => self.summary.dropped += 1,
                Ok(Event::Malformed) => self.summary.malformed += 1,
                Ok(Event::Start(query)) => {
                    if let Some(Pace::Lockstep) = self.start(&query) {
                        return Ok(Pace::Lockstep);
                    }
                }
                Ok(Event::Witness(query)) => self.witness(&query),
                Err(mpsc::RecvTimeoutError::Timeout) => self.publish(outlets, false, f64::NAN)?,
                Err(mpsc::RecvTimeoutError::Disconnected) => return Ok(Pace::Realtime),
            }
        };
        self.round_trip_us = self.published_at.elapsed().as_secs_f64() * 1e6;
        let mut pending = Some(first);
        let ticks_before = self.summary.ticks;
        let mut last_tick = Instant::now();
        let mut next = last_tick;
        let mut last_command = last_tick;
        let mut stopped = false;
        while !stop.load(Ordering::Relaxed) {
            let mut fresh: Option<Vec<f64>> = pending.take();
            loop {
                let now = Instant::now();
                if now >= next {
                    break;
                }
                match node::recv_until(rx, next - SPIN, next) {
                    Ok(Event::Command {
                        torques,
                        stop: stop_asked,
                        sequence,
                    }) => {
                        run_stopped |= stop_asked;
                        if sequence == Some(self.tick as i64 + 1) {
                            self.round_trip_us = self.published_at.elapsed().as_secs_f64() * 1e6;
                            fresh = Some(torques);
                        } else {
                            self.summary.dropped += 1;
                        }
                    }
                    Ok(Event::Malformed) => self.summary.malformed += 1,
                    Ok(Event::Start(query)) => match self.start(&query) {
                        Some(Pace::Lockstep) => return Ok(Pace::Lockstep),
                        // A new realtime session: its clock starts with its first command.
                        Some(Pace::Realtime) => return Ok(Pace::Realtime),
                        None => {}
                    },
                    Ok(Event::Witness(query)) => self.witness(&query),
                    Err(mpsc::RecvTimeoutError::Timeout) => break,
                    Err(mpsc::RecvTimeoutError::Disconnected) => return Ok(Pace::Realtime),
                }
            }
            let now = Instant::now();
            // The session's first tick has no period before it.
            let period_us = if self.summary.ticks == ticks_before {
                f64::NAN
            } else {
                now.duration_since(last_tick).as_secs_f64() * 1e6
            };
            last_tick = now;
            let late = fresh.is_none();
            if fresh.is_some() {
                last_command = now;
            }
            match fresh {
                _ if run_stopped => {
                    self.step_damped_stop()?;
                    self.summary.commands += u64::from(!late);
                    // After the run has gone quiet (it ended), held ticks are not late ones.
                    self.summary.late += u64::from(late && now.duration_since(last_command) <= options.silence);
                }
                Some(torques) => {
                    stopped = false;
                    self.step(Some(&torques))?;
                    self.summary.commands += 1;
                }
                None if now.duration_since(last_command) > options.silence => {
                    if !stopped {
                        self.summary.damped_stops += 1;
                        stopped = true;
                    }
                    self.step_damped_stop()?;
                }
                None => {
                    self.summary.late += 1;
                    self.step(None)?;
                }
            }
            self.summary.ticks += 1;
            self.publish(outlets, late, period_us)?;
            next += period;
            if next + period < Instant::now() {
                // Far behind (the machine stalled): start the clock afresh rather than rush.
                next = Instant::now() + period;
            }
        }
        Ok(Pace::Realtime)
    }
}

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
//! **Who drives it.** A run names its command publisher's GID in the rmw_zenoh attachment of its
//! start query; from then until that publisher's liveliness token goes (the run's session closed)
//! the run holds the plant: commands (torques, damped stops) from any other publisher and start
//! queries from any other run are refused, counted and reported through
//! [`ServeOptions::notice`] with who sent them. The start's answer carries the GID of the plant's
//! `/skillc/state` publisher, so the run can ignore states from anyone else. Without
//! authentication a GID is a claim, not a proof: this keeps stray and foreign peers out, not one
//! that copies the GIDs it sees on the wire.
//!
//! **What it applies.** Torques are saturated at the joints' effort limits before they are applied,
//! and `/joint_states` reports the saturated ones. A command with a NaN or an infinity is a
//! [`Fault`]: none of it is applied, the plant holds its damped stop until the next session starts,
//! and every state carries the fault, so the run fails with it.
//!
//! A second query, the witness ([`crate::witness_key`]), hands the run what the plant's contact
//! witness found since the run last asked, as JSON; the plant keeps the sum of all it handed out
//! for its own summary.

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use skill_robot::plant::{saturate, ContactAudit, Observation, Plant};
use skill_robot::Robot;
use skill_ros::msgs::{self, Float64MultiArray, Header, JointState, MsgType, Time, WrenchStamped};
use skill_ros::rmw::{self, Attachment};
use zenoh::bytes::ZBytes;
use zenoh::query::Query;
use zenoh::sample::SampleKind;
use zenoh::{Session, Wait};

use crate::node::{self, Node, RosPublisher};
use crate::wire::{self, Fault, State};
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
    /// Told, in words, each refusal of a session, the first refusal of a damped stop and of torques
    /// from each sender in a session, and each fault.
    pub notice: fn(&str),
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
    /// Commands with a NaN or an infinity (a [`Fault`]: none applied, the damped stop held).
    pub faults: u64,
    /// Commands refused because another run held the plant.
    pub foreign_commands: u64,
    /// Start queries refused: another run held the plant, or the query named no command publisher.
    pub refused_starts: u64,
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

/// A publisher's GID, as rmw_zenoh's attachment carries it.
type Gid = [u8; rmw::GID_BYTES];

enum Event {
    /// Torques, or (`stop`) the plant's own damped stop from now on; `gid` is the publisher's.
    Command {
        torques: Vec<f64>,
        stop: bool,
        sequence: Option<i64>,
        gid: Option<Gid>,
    },
    Malformed,
    Start(Query),
    Witness(Query),
    /// A ROS 2 liveliness token came (`alive`) or went.
    Token {
        key: String,
        alive: bool,
    },
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
        let gid = attachment.map(|a| a.gid);
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
                gid,
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
    // ROS 2 nodes' tokens: who a GID belongs to, and when the run holding the plant has gone.
    let tokens_tx = tx.clone();
    let tokens_key = format!("@ros2_lv/{}/**", options.domain);
    let _tokens = session
        .liveliness()
        .declare_subscriber(tokens_key.clone())
        .history(true)
        .callback(move |sample| {
            let _ = tokens_tx.send(Event::Token {
                key: sample.key_expr().as_str().to_owned(),
                alive: sample.kind() == SampleKind::Put,
            });
        })
        .wait()
        .map_err(|err| TransportError::Zenoh {
            what: format!("subscribing to the liveliness tokens `{tokens_key}`"),
            reason: err.to_string(),
        })?;
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
        notice: options.notice,
        owner: None,
        fault: None,
        held_stop: false,
        tokens: HashMap::new(),
        noticed: HashSet::new(),
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
    notice: fn(&str),
    /// The command publisher of the run that holds the plant.
    owner: Option<Gid>,
    /// The fault of this session, held until the next one starts.
    fault: Option<Fault>,
    /// Whether the last step was the plant's own damped stop.
    held_stop: bool,
    /// The liveliness tokens alive, by the GID they give their publisher or subscription.
    tokens: HashMap<Gid, String>,
    /// The senders (and whether of a stop) already reported this session.
    noticed: HashSet<(Option<Gid>, bool)>,
}

/// The first joint whose torque is NaN or infinite, as a fault.
fn non_finite(torques: &[f64]) -> Option<Fault> {
    torques
        .iter()
        .position(|tau| !tau.is_finite())
        .map(|joint| Fault::NonFiniteTorque { joint })
}

impl Server<'_> {
    /// Who published with `gid`, in words: the node and Zenoh session its liveliness token names.
    fn who(&self, gid: Option<Gid>) -> String {
        let Some(gid) = gid else {
            return "a publisher without rmw_zenoh's attachment (no GID)".to_owned();
        };
        let hex: String = gid.iter().map(|byte| format!("{byte:02x}")).collect();
        match self.tokens.get(&gid).map(|token| token.split('/').collect::<Vec<_>>()) {
            // @ros2_lv/<domain>/<zid>/<nid>/<eid>/<kind>/<enclave>/<namespace>/<node>/...
            Some(parts) if parts.len() > 8 => format!(
                "node `{}` of Zenoh session {} (GID {hex})",
                parts[8].replace('%', "/"),
                parts[2]
            ),
            _ => format!("GID {hex} (no liveliness token names it)"),
        }
    }

    /// Whether a command from `gid` may drive the plant: anyone's while no run holds it, only that
    /// run's while one does. A refusal is counted, and told the first time a sender tries it (a
    /// damped stop, or torques) in a session.
    fn admit(&mut self, gid: Option<Gid>, stop: bool) -> bool {
        let Some(owner) = self.owner else {
            return true;
        };
        if gid == Some(owner) {
            return true;
        }
        self.summary.foreign_commands += 1;
        if self.noticed.insert((gid, stop)) {
            (self.notice)(&format!(
                "plant: refused {} from {}: the plant is held by the run of {}",
                if stop { "a damped stop" } else { "torque commands" },
                self.who(gid),
                self.who(Some(owner))
            ));
        }
        false
    }

    /// Raises `fault`, found in a command from `gid`, unless one is held already.
    fn raise(&mut self, fault: Fault, gid: Option<Gid>) {
        self.summary.faults += 1;
        if self.fault.is_none() {
            self.fault = Some(fault);
            let names: Vec<String> = self.robot.joints().iter().map(|joint| joint.name.clone()).collect();
            (self.notice)(&format!(
                "plant: fault: {} (from {})",
                fault.words(&names),
                self.who(gid)
            ));
        }
    }

    /// Takes a liveliness token's coming or going; the plant is free again when the run holding it
    /// has gone.
    fn token(&mut self, key: String, alive: bool) {
        let gid = rmw::gid(&key);
        if alive {
            self.tokens.insert(gid, key);
            return;
        }
        if self.owner == Some(gid) {
            self.owner = None;
            self.noticed.clear();
        }
        self.tokens.remove(&gid);
    }

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
            fault: self.fault,
            damped_stop: self.held_stop,
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

    /// One step with `torques` (finite), saturated at the joints' effort limits as applied and as
    /// `/joint_states` reports them, or the last ones held.
    fn step(&mut self, torques: Option<&[f64]>) -> Result<(), TransportError> {
        self.held_stop = false;
        if let Some(torques) = torques {
            saturate(self.robot, torques, &mut self.torques)?;
            self.plant.apply(&self.torques)?;
        }
        self.plant.step(self.period_s)?;
        self.tick += 1;
        Ok(())
    }

    /// Answers a start query with the current state and the GID of the plant's state publisher;
    /// the mode it asks for. The run that asks holds the plant from then on; a start from another
    /// run while one holds it, or from one that names no command publisher, is refused.
    fn start(&mut self, query: &Query, outlets: &Outlets) -> Option<Pace> {
        let asked = query
            .payload()
            .and_then(|bytes| msgs::decode_string(&bytes.to_bytes()).ok())
            .unwrap_or_default();
        let refuse = |why: &str| {
            let _ = query.reply_err(msgs::encode_string(why)).wait();
        };
        let pace = match asked.as_str() {
            "lockstep" => Pace::Lockstep,
            "realtime" => Pace::Realtime,
            _ => {
                refuse(&format!("unknown mode `{asked}`: ask for `lockstep` or `realtime`"));
                return None;
            }
        };
        let gid = query
            .attachment()
            .and_then(|bytes| Attachment::decode(&bytes.to_bytes()))
            .map(|attachment| attachment.gid);
        let Some(gid) = gid else {
            self.summary.refused_starts += 1;
            refuse("a start query names the run's command publisher in rmw_zenoh's attachment; this one has none");
            (self.notice)("plant: refused a session whose start named no command publisher");
            return None;
        };
        if let Some(owner) = self.owner.filter(|owner| *owner != gid) {
            self.summary.refused_starts += 1;
            let (holder, asker) = (self.who(Some(owner)), self.who(Some(gid)));
            refuse(&format!(
                "the plant is held by the run of {holder}; it serves one run at a time: start again when that run has \
                 ended"
            ));
            (self.notice)(&format!(
                "plant: refused a {asked} session from {asker}: held by the run of {holder}"
            ));
            return None;
        }
        self.owner = Some(gid);
        self.fault = None;
        self.noticed.clear();
        let state = self.state(f64::NAN, false, f64::NAN);
        let attachment = Attachment {
            sequence: self.tick as i64,
            timestamp_ns: node::now_ns(),
            gid: outlets.state.gid(),
        };
        let _ = query
            .reply(query.key_expr().clone(), state.encode().encode())
            .attachment(ZBytes::from(attachment.encode().to_vec()))
            .wait();
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

    /// Takes an event that is not a command; the mode of a session it started.
    fn other(&mut self, event: Event, outlets: &Outlets) -> Option<Pace> {
        match event {
            Event::Malformed => self.summary.malformed += 1,
            Event::Start(query) => return self.start(&query, outlets),
            Event::Witness(query) => self.witness(&query),
            Event::Token { key, alive } => self.token(key, alive),
            Event::Command { .. } => {}
        }
        None
    }

    fn lockstep(
        &mut self,
        rx: &mpsc::Receiver<Event>,
        outlets: &Outlets,
        stop: &AtomicBool,
    ) -> Result<Pace, TransportError> {
        while !stop.load(Ordering::Relaxed) {
            match rx.recv_timeout(HEARTBEAT) {
                Ok(Event::Command { torques, stop, gid, .. }) => {
                    if !self.admit(gid, stop) {
                        continue;
                    }
                    self.round_trip_us = self.published_at.elapsed().as_secs_f64() * 1e6;
                    if let Some(fault) = non_finite(&torques).filter(|_| !stop) {
                        self.raise(fault, gid);
                    }
                    if stop || self.fault.is_some() {
                        // The same torques the run's supervisor computes from the same state.
                        self.step_damped_stop()?;
                    } else {
                        self.step(Some(&torques))?;
                    }
                    self.summary.commands += 1;
                    self.summary.ticks += 1;
                    self.publish(outlets, false, f64::NAN)?;
                }
                Ok(other) => {
                    if let Some(Pace::Realtime) = self.other(other, outlets) {
                        return Ok(Pace::Realtime);
                    }
                }
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
        self.held_stop = true;
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
                    gid,
                }) => {
                    if !self.admit(gid, stop_asked) {
                        continue;
                    }
                    if sequence == Some(self.tick as i64 + 1) {
                        if let Some(fault) = non_finite(&torques).filter(|_| !stop_asked) {
                            self.raise(fault, gid);
                        }
                        break (torques, stop_asked);
                    }
                    self.summary.dropped += 1;
                }
                Ok(other) => {
                    if let Some(Pace::Lockstep) = self.other(other, outlets) {
                        return Ok(Pace::Lockstep);
                    }
                }
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
                        gid,
                    }) => {
                        if !self.admit(gid, stop_asked) {
                            continue;
                        }
                        run_stopped |= stop_asked;
                        if sequence == Some(self.tick as i64 + 1) {
                            self.round_trip_us = self.published_at.elapsed().as_secs_f64() * 1e6;
                            if let Some(fault) = non_finite(&torques).filter(|_| !stop_asked) {
                                self.raise(fault, gid);
                            }
                            fresh = Some(torques);
                        } else {
                            self.summary.dropped += 1;
                        }
                    }
                    // A new session: its clock starts with its first command.
                    Ok(other) => {
                        if let Some(pace) = self.other(other, outlets) {
                            return Ok(pace);
                        }
                    }
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
                // The run's supervisor asked for the stop, or a command was a fault: the plant
                // holds its damped stop for the rest of the session.
                _ if run_stopped || self.fault.is_some() => {
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
                    let held_stop = self.held_stop;
                    self.step(None)?;
                    // The last torques held are the damped stop's if that was the last step.
                    self.held_stop = held_stop;
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

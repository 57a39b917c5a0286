//! A [`Plant`] whose arm is served by another process ([`mod@crate::serve`]): each step publishes the
//! torques, numbered with the tick of the state they answer, and waits for the plant's next state.
//! In lockstep that state is the plant's next tick, exactly as in one process; in realtime it is
//! the next state the plant's own clock published (in order, none skipped, so the controller's
//! clock stays the plant's), and the loop's timing as the plant measured it is gathered in
//! [`LoopStats`].
//!
//! The run takes states only from the plant it opened: the start query's answer names the GID of
//! the plant's `/skillc/state` publisher, and states whose rmw_zenoh attachment names another (or
//! none) are ignored and counted ([`LoopStats::foreign`]). A state that carries a
//! [`Fault`](crate::wire::Fault) ends the run in a link failure with the fault's words.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use skill_robot::plant::{ContactAudit, Observation, Plant, PlantError};
use skill_ros::msgs::{self, Float64MultiArray, MsgType};
use skill_ros::rmw::{self, Attachment};
use zenoh::bytes::ZBytes;
use zenoh::pubsub::Subscriber;
use zenoh::{Session, Wait};

use crate::node::{self, Node, Role, RosPublisher};
use crate::wire::{self, State};
use crate::{start_key, witness_key, TransportError, COMMANDS, STATE};

/// In realtime, how long before the plant's next state is due the run polls for it.
const SPIN: Duration = Duration::from_micros(300);
/// How long the run waits for the plant to answer the witness query.
const WITNESS_TIMEOUT: Duration = Duration::from_secs(2);

/// How the run and the plant keep time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkMode {
    /// The plant steps once per command.
    Lockstep,
    /// The plant steps on its own clock and holds the last torques when a command is late.
    Realtime,
}

impl LinkMode {
    /// The word the start query carries.
    pub fn word(self) -> &'static str {
        match self {
            LinkMode::Lockstep => "lockstep",
            LinkMode::Realtime => "realtime",
        }
    }
}

/// Where the plant is and how to talk to it.
#[derive(Debug, Clone)]
pub struct RemoteOptions {
    /// `tcp/HOST:PORT`.
    pub endpoint: String,
    /// The ROS domain.
    pub domain: u32,
    /// Lockstep or realtime.
    pub mode: LinkMode,
    /// How long to look for the plant before giving up.
    pub connect_timeout: Duration,
    /// How long a step waits for the plant's next state before the plant counts as silent.
    pub silence: Duration,
}

/// The loop's figures over a run, as the plant measured them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoopStats {
    /// Steps taken.
    pub ticks: u64,
    /// Ticks for which the plant held the last torques.
    pub late: u64,
    /// States the plant published that the run never saw (realtime; 0 unless the link lost some).
    pub skipped: u64,
    /// Publish of a state to the arrival of its command, µs, per tick that had one.
    pub round_trips_us: Vec<f64>,
    /// The plant's real time between ticks, µs (realtime).
    pub periods_us: Vec<f64>,
    /// The plant's control period, µs.
    pub nominal_period_us: f64,
    /// States on `/skillc/state` from a publisher other than the plant's, ignored.
    pub foreign: u64,
    /// States in which the plant held its own damped stop.
    pub damped_stop: u64,
}

/// The `p`-quantile (0..=1) of `values`, by the nearest rank; NaN when empty.
fn quantile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let rank = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

impl LoopStats {
    /// One line: `loop: N ticks, L late commands (P %), round trip µs: median A, p99 B, max C,
    /// jitter µs: p99 D` (jitter: how far the plant's period strayed from its nominal one).
    pub fn line(&self) -> String {
        let share = if self.ticks == 0 {
            0.0
        } else {
            100.0 * self.late as f64 / self.ticks as f64
        };
        let jitter: Vec<f64> = self
            .periods_us
            .iter()
            .map(|period| (period - self.nominal_period_us).abs())
            .collect();
        format!(
            "loop: {} ticks, {} late commands ({share:.2} %), round trip µs: median {:.0}, p99 {:.0}, max {:.0}, \
             jitter µs: p99 {:.0}",
            self.ticks,
            self.late,
            quantile(&self.round_trips_us, 0.5),
            quantile(&self.round_trips_us, 0.99),
            quantile(&self.round_trips_us, 1.0),
            quantile(&jitter, 0.99),
        )
    }

    /// `foreign: N states on /skillc/state not from the plant's publisher, ignored`, when there
    /// were any.
    pub fn foreign_line(&self) -> Option<String> {
        (self.foreign > 0).then(|| {
            format!(
                "foreign: {} state(s) on /skillc/state not from the plant's publisher, ignored",
                self.foreign
            )
        })
    }
}

/// The arm on the other side of the link.
pub struct RemotePlant {
    // Declared before the session so they are undeclared before it closes.
    _subscription: Subscriber<()>,
    commands: RosPublisher,
    _node: Node,
    session: Session,
    states: mpsc::Receiver<(Vec<u8>, Option<[u8; rmw::GID_BYTES]>)>,
    /// The GID of the plant's state publisher, as its answer to the start named it.
    plant_gid: [u8; rmw::GID_BYTES],
    options: RemoteOptions,
    dof: usize,
    current: State,
    torques: Vec<f64>,
    stats: LoopStats,
    /// When the last state came, and the period the run steps by.
    last_arrival: Option<Instant>,
    period_s: f64,
    /// The supervisor's damped stop is on: the plant holds it itself.
    stopping: bool,
}

impl std::fmt::Debug for RemotePlant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RemotePlant")
            .field("endpoint", &self.options.endpoint)
            .field("tick", &self.current.tick)
            .finish()
    }
}

impl RemotePlant {
    /// Connects to the plant at `options.endpoint`, starts a session in `options.mode` and takes
    /// its state; `dof` is the run's robot's, which the plant's must match.
    pub fn connect(options: RemoteOptions, dof: usize) -> Result<RemotePlant, TransportError> {
        let session = node::open(&options.endpoint, Role::Connect)?;
        let mut ros = Node::new(&session, options.domain, "skillc_run")?;
        let (tx, states) = mpsc::channel();
        let subscription = ros.subscription(&session, STATE, MsgType::Float64MultiArray, move |sample| {
            let (payload, attachment) = node::sample_parts(&sample);
            let _ = tx.send((payload, attachment.map(|a| a.gid)));
        })?;
        let commands = ros.publisher(&session, COMMANDS, MsgType::Float64MultiArray)?;
        let (current, plant_gid) = start(&session, &options, dof, commands.gid())?;
        let nominal_period_us = f64::NAN;
        Ok(RemotePlant {
            _subscription: subscription,
            commands,
            _node: ros,
            session,
            states,
            plant_gid,
            dof,
            torques: vec![0.0; dof],
            stats: LoopStats {
                nominal_period_us,
                ..LoopStats::default()
            },
            current,
            options,
            last_arrival: None,
            period_s: 1e-3,
            stopping: false,
        })
    }

    /// The loop's figures so far.
    pub fn stats(&self) -> &LoopStats {
        &self.stats
    }

    fn link_error(&self, reason: String) -> PlantError {
        PlantError::Link {
            t: self.current.obs.t,
            reason,
        }
    }

    /// Waits for a state newer than the current one.
    fn next_state(&mut self) -> Result<State, PlantError> {
        let now = Instant::now();
        let deadline = now + self.options.silence;
        // Realtime: sleep until shortly before the plant's next tick is due, then poll. Lockstep
        // polls from the start: the plant answers within a step's computation.
        let spin_from = match self.options.mode {
            LinkMode::Realtime => self
                .last_arrival
                .map_or(now, |at| at + Duration::from_secs_f64(self.period_s) - SPIN),
            LinkMode::Lockstep => now,
        };
        loop {
            let payload = match node::recv_until(&self.states, spin_from, deadline) {
                Ok((payload, gid)) if gid == Some(self.plant_gid) => payload,
                Ok(_) => {
                    // Another publisher on the plant's topic (a second plant on the domain, a
                    // replay, a stranger): not the plant this run opened.
                    self.stats.foreign += 1;
                    continue;
                }
                Err(_) => {
                    return Err(self.link_error(format!(
                        "no state from the plant at `{}` for {} ms (is it still running?)",
                        self.options.endpoint,
                        self.options.silence.as_millis()
                    )))
                }
            };
            let state = Float64MultiArray::decode(&payload)
                .map_err(|err| err.to_string())
                .and_then(|array| State::decode(&array, self.dof).map_err(|err| err.0))
                .map_err(|reason| self.link_error(format!("a state from the plant is unreadable: {reason}")))?;
            if state.tick > self.current.tick {
                self.last_arrival = Some(Instant::now());
                return Ok(state);
            }
            // The plant repeating a state it already sent (its heartbeat) or one from before the session.
        }
    }
}

/// Asks the plant to start a session, naming the run's command publisher (`commands`, its GID in
/// rmw_zenoh's attachment), until it answers or `options.connect_timeout` passes; its state and
/// the GID of its state publisher.
fn start(
    session: &Session,
    options: &RemoteOptions,
    dof: usize,
    commands: [u8; rmw::GID_BYTES],
) -> Result<(State, [u8; rmw::GID_BYTES]), TransportError> {
    let began = Instant::now();
    let key = start_key(options.domain);
    loop {
        let replies = session
            .get(key.clone())
            .payload(msgs::encode_string(options.mode.word()))
            .attachment(ZBytes::from(
                Attachment {
                    sequence: 1,
                    timestamp_ns: node::now_ns(),
                    gid: commands,
                }
                .encode()
                .to_vec(),
            ))
            .timeout(Duration::from_millis(500))
            .wait()
            .map_err(|err| TransportError::Zenoh {
                what: format!("asking `{key}`"),
                reason: err.to_string(),
            })?;
        // The first answer decides (one plant serves a domain's start key).
        if let Ok(reply) = replies.recv() {
            let mismatch = |reason: String| TransportError::Mismatch {
                endpoint: options.endpoint.clone(),
                reason,
            };
            match reply.result() {
                Ok(sample) => {
                    let array = Float64MultiArray::decode(&sample.payload().to_bytes())
                        .map_err(|err| mismatch(format!("answered with bytes that are no state: {err}")))?;
                    let state = State::decode(&array, dof).map_err(|err| mismatch(err.0))?;
                    let gid = sample
                        .attachment()
                        .and_then(|bytes| Attachment::decode(&bytes.to_bytes()))
                        .map(|attachment| attachment.gid)
                        .ok_or_else(|| {
                            mismatch("answered without naming its state publisher (is it an older skillc?)".to_owned())
                        })?;
                    return Ok((state, gid));
                }
                Err(err) => {
                    let words = msgs::decode_string(&err.payload().to_bytes()).unwrap_or_default();
                    return Err(mismatch(format!("refused the session: {words}")));
                }
            }
        }
        if began.elapsed() >= options.connect_timeout {
            return Err(TransportError::NoPlant {
                endpoint: options.endpoint.clone(),
                domain: options.domain,
                waited_s: options.connect_timeout.as_secs_f64(),
            });
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

impl Plant for RemotePlant {
    fn dof(&self) -> usize {
        self.dof
    }

    fn time(&self) -> f64 {
        self.current.obs.t
    }

    fn observe_into(&self, out: &mut Observation) {
        out.clone_from(&self.current.obs);
    }

    fn apply(&mut self, torques: &[f64]) -> Result<(), PlantError> {
        if torques.len() != self.dof {
            return Err(PlantError::WrongDof {
                expected: self.dof,
                got: torques.len(),
            });
        }
        self.torques.copy_from_slice(torques);
        Ok(())
    }

    fn hold_damped_stop(&mut self) -> bool {
        self.stopping = true;
        true
    }

    /// Asks the plant's own witness (the witness query): `None` when the plant has none, or does
    /// not answer within 2 s (a plant of an older skillc), so the run reports no
    /// witness rather than a wrong one.
    fn take_contact_audit(&mut self) -> Option<ContactAudit> {
        let replies = self
            .session
            .get(witness_key(self.options.domain))
            .timeout(WITNESS_TIMEOUT)
            .wait()
            .ok()?;
        let sample = replies.recv().ok()?.into_result().ok()?;
        let json = msgs::decode_string(&sample.payload().to_bytes()).ok()?;
        serde_json::from_str::<Option<ContactAudit>>(&json).ok()?
    }

    fn visit_parts(&self, visit: &mut dyn FnMut(&str, f64)) {
        for (name, offset) in &self.current.parts {
            visit(name, *offset);
        }
    }

    fn step(&mut self, dt: f64) -> Result<(), PlantError> {
        self.period_s = dt;
        let payload = wire::encode_command(&self.torques, self.stopping).encode();
        self.commands
            .put_numbered(payload, self.current.tick as i64 + 1)
            .map_err(|err| self.link_error(err.to_string()))?;
        let state = self.next_state()?;
        if let Some(fault) = state.fault {
            return Err(self.link_error(format!(
                "the plant at `{}` reports a fault: {}",
                self.options.endpoint,
                fault.words(&[])
            )));
        }
        match self.options.mode {
            LinkMode::Lockstep => {
                if state.tick != self.current.tick + 1 {
                    return Err(self.link_error(format!(
                        "the plant went from tick {} to {}: another controller is commanding it",
                        self.current.tick, state.tick
                    )));
                }
                let stepped = state.obs.t - self.current.obs.t;
                if (stepped - dt).abs() > 1e-9 {
                    return Err(self.link_error(format!(
                        "the plant stepped {stepped} s, the run {dt} s: give `skillc plant` the run's period"
                    )));
                }
            }
            LinkMode::Realtime => {
                // States are taken in order, never skipped: the controller's clock stays the
                // plant's, one period a step (a run that fell behind catches up; the plant holds
                // the torques of the ticks whose commands came late).
                self.stats.nominal_period_us = dt * 1e6;
                self.stats.skipped += state.tick - self.current.tick - 1;
            }
        }
        self.stats.ticks += 1;
        self.stats.late += u64::from(state.late);
        self.stats.damped_stop += u64::from(state.damped_stop);
        if state.round_trip_us.is_finite() {
            self.stats.round_trips_us.push(state.round_trip_us);
        }
        if state.period_us.is_finite() {
            self.stats.periods_us.push(state.period_us);
        }
        self.current = state;
        Ok(())
    }
}

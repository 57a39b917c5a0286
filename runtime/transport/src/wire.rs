//! What the plant and the run say to each other on skillc's own topics, as
//! `std_msgs/msg/Float64MultiArray` so ROS 2 tools can show them: the plant's state each tick
//! (its whole [`Observation`], the tick it belongs to and the loop's timing as the plant measured
//! it) and the run's joint torques.
//!
//! A state is one array whose layout names its blocks in order, each dimension's `size` the block's
//! length: `tick`, `t`, `q`, `qd`, `wrench_sensor`, `wrench_base`, `arm_contact_n`,
//! `arm_contact_link` (−1 for none), `round_trip_us` (publish of the previous state to the arrival
//! of the command that answered it, NaN when none did), `late` (1 when the plant held the last
//! command because the one for this tick had not come) and `period_us` (the plant's real time since
//! its previous tick, NaN in lockstep), `fault` (two numbers: the [`Fault`]'s kind, 0 for none, and
//! its detail) and `damped_stop` (1 when the plant held its own damped stop for this tick rather
//! than a command's torques), then one block `part:NAME` of length 1 for each of the
//! scene's moving parts: how far it has moved from its rest, m (a button's cap, how deep it is
//! pressed; [`Plant::visit_parts`](skill_robot::plant::Plant::visit_parts)). A command is one block
//! `effort` of the joint torques; which state it answers is its attachment's sequence number (the
//! state's tick + 1).

use skill_robot::plant::Observation;
use skill_ros::msgs::{Float64MultiArray, MultiArrayDimension};

/// The blocks of a state, in order, with their lengths for `dof` joints.
fn state_blocks(dof: usize) -> [(&'static str, usize); 13] {
    [
        ("tick", 1),
        ("t", 1),
        ("q", dof),
        ("qd", dof),
        ("wrench_sensor", 6),
        ("wrench_base", 6),
        ("arm_contact_n", 1),
        ("arm_contact_link", 1),
        ("round_trip_us", 1),
        ("late", 1),
        ("period_us", 1),
        ("fault", 2),
        ("damped_stop", 1),
    ]
}

/// What a moving part's block label starts with; the part's name follows.
pub const PART_PREFIX: &str = "part:";

/// The label of a command's one block.
pub const COMMAND_BLOCK: &str = "effort";
/// The label of a command that asks the plant to hold its own damped stop (the run's supervisor
/// fired a reflex); its numbers are the torques the run computed, which the plant ignores.
pub const STOP_BLOCK: &str = "damped_stop";

/// What a command asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command<'a> {
    /// These joint torques, N m.
    Effort(&'a [f64]),
    /// The plant's own damped stop, from now on.
    DampedStop,
}

/// What the plant refused to apply; it holds the arm in its damped stop from then until a run
/// starts a new session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// A torque command held a NaN or an infinity, first at this joint (URDF order, from 0).
    NonFiniteTorque {
        /// The joint's index.
        joint: usize,
    },
}

impl Fault {
    /// The fault's two numbers on the wire: its kind (from 1) and its detail.
    fn encode(self) -> [f64; 2] {
        match self {
            Fault::NonFiniteTorque { joint } => [1.0, joint as f64],
        }
    }

    /// The fault the two numbers name, `Ok(None)` for none.
    fn decode(numbers: &[f64]) -> Result<Option<Fault>, WireError> {
        match numbers {
            [kind, _] if *kind == 0.0 => Ok(None),
            [kind, joint] if *kind == 1.0 && *joint >= 0.0 && joint.fract() == 0.0 && *joint < 1e6 => {
                Ok(Some(Fault::NonFiniteTorque { joint: *joint as usize }))
            }
            _ => Err(WireError(format!(
                "a state's fault is {numbers:?}, which names no fault"
            ))),
        }
    }

    /// In words, with the joint's name from `names` when it has one.
    pub fn words(self, names: &[String]) -> String {
        match self {
            Fault::NonFiniteTorque { joint } => format!(
                "non-finite torque command (NaN or infinite) for {}: the plant applied none of it and holds the arm \
                 in its damped stop",
                names.get(joint).map_or_else(
                    || format!("joint {} of the arm (URDF order)", joint + 1),
                    |name| format!("joint `{name}`")
                )
            ),
        }
    }
}

/// The plant's state at one tick, as published.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Ticks stepped since the plant started.
    pub tick: u64,
    /// What the controller sees.
    pub obs: Observation,
    /// Publish of the previous state to the arrival of its command, µs (NaN when none came).
    pub round_trip_us: f64,
    /// Whether the plant held the last command for this tick (realtime only).
    pub late: bool,
    /// The plant's real time since its previous tick, µs (NaN in lockstep).
    pub period_us: f64,
    /// What the plant refused in this tick's command, if anything.
    pub fault: Option<Fault>,
    /// Whether the plant held its own damped stop for this tick.
    pub damped_stop: bool,
    /// Each moving part's name and how far it has moved from its rest, m.
    pub parts: Vec<(String, f64)>,
}

/// Why a message is not what this side expects.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct WireError(pub String);

impl State {
    /// The array the plant publishes.
    pub fn encode(&self) -> Float64MultiArray {
        let dof = self.obs.q.len();
        let obs = &self.obs;
        let mut data = Vec::with_capacity(2 * dof + 23 + self.parts.len());
        data.push(self.tick as f64);
        data.push(obs.t);
        data.extend_from_slice(obs.q.as_slice());
        data.extend_from_slice(obs.qd.as_slice());
        data.extend_from_slice(obs.wrench_sensor.as_slice());
        data.extend_from_slice(obs.wrench_base.as_slice());
        data.push(obs.arm_contact_n);
        data.push(obs.arm_contact_link.map_or(-1.0, |link| link as f64));
        data.push(self.round_trip_us);
        data.push(if self.late { 1.0 } else { 0.0 });
        data.push(self.period_us);
        data.extend(self.fault.map_or([0.0, -1.0], Fault::encode));
        data.push(if self.damped_stop { 1.0 } else { 0.0 });
        data.extend(self.parts.iter().map(|(_, offset)| offset));
        let block = |label: String, size: usize| MultiArrayDimension {
            label,
            size: size as u32,
            stride: size as u32,
        };
        Float64MultiArray {
            dim: state_blocks(dof)
                .iter()
                .map(|(label, size)| block((*label).to_owned(), *size))
                .chain(
                    self.parts
                        .iter()
                        .map(|(name, _)| block(format!("{PART_PREFIX}{name}"), 1)),
                )
                .collect(),
            data_offset: 0,
            data,
        }
    }

    /// Reads a state for a robot with `dof` joints, checking every block's label and length.
    pub fn decode(array: &Float64MultiArray, dof: usize) -> Result<State, WireError> {
        let blocks = state_blocks(dof);
        let labels: Vec<(&str, usize)> = array
            .dim
            .iter()
            .map(|dim| (dim.label.as_str(), dim.size as usize))
            .collect();
        if labels.get(..blocks.len()) != Some(blocks.as_slice()) {
            return Err(WireError(format!(
                "a state's blocks are {labels:?}, not the {blocks:?} of a {dof}-joint plant: is the plant serving \
                 another robot?"
            )));
        }
        let mut names = Vec::with_capacity(labels.len() - blocks.len());
        for (label, size) in &labels[blocks.len()..] {
            match label.strip_prefix(PART_PREFIX) {
                Some(name) if *size == 1 => names.push(name.to_owned()),
                _ => {
                    return Err(WireError(format!(
                        "a state's block `{label}` of length {size} after its fixed blocks is not a moving part's \
                         (`{PART_PREFIX}NAME`, length 1)"
                    )))
                }
            }
        }
        let total = blocks.iter().map(|(_, size)| size).sum::<usize>() + names.len();
        if array.data_offset != 0 || array.data.len() != total {
            return Err(WireError(format!(
                "a state holds {} numbers from offset {}, not {total} from 0",
                array.data.len(),
                array.data_offset
            )));
        }
        let mut at = 0;
        let mut take = |n: usize| {
            let block = &array.data[at..at + n];
            at += n;
            block
        };
        let tick = take(1)[0];
        let t = take(1)[0];
        let mut obs = Observation::zeros(dof);
        obs.t = t;
        obs.q.as_mut_slice().copy_from_slice(take(dof));
        obs.qd.as_mut_slice().copy_from_slice(take(dof));
        obs.wrench_sensor.as_mut_slice().copy_from_slice(take(6));
        obs.wrench_base.as_mut_slice().copy_from_slice(take(6));
        obs.arm_contact_n = take(1)[0];
        let link = take(1)[0];
        obs.arm_contact_link = (link >= 0.0).then_some(link as usize);
        let round_trip_us = take(1)[0];
        let late = take(1)[0] != 0.0;
        let period_us = take(1)[0];
        let fault = Fault::decode(take(2))?;
        let damped_stop = take(1)[0] != 0.0;
        let parts = names
            .into_iter()
            .zip(take(labels.len() - blocks.len()).iter().copied())
            .collect();
        if !(tick >= 0.0 && tick.fract() == 0.0 && tick < 2f64.powi(53)) {
            return Err(WireError(format!("a state's tick is {tick}, not a whole number")));
        }
        Ok(State {
            tick: tick as u64,
            obs,
            round_trip_us,
            late,
            period_us,
            fault,
            damped_stop,
            parts,
        })
    }
}

/// A command's array: the joint torques, N m, in URDF order; `stop` labels it a damped stop.
pub fn encode_command(torques: &[f64], stop: bool) -> Float64MultiArray {
    Float64MultiArray {
        dim: vec![MultiArrayDimension {
            label: if stop { STOP_BLOCK } else { COMMAND_BLOCK }.to_owned(),
            size: torques.len() as u32,
            stride: torques.len() as u32,
        }],
        data_offset: 0,
        data: torques.to_vec(),
    }
}

/// A command for a plant with `dof` joints: torques in any layout, as a ROS 2 controller may write
/// them, as long as they are `dof` numbers after the offset; a damped stop when the first
/// dimension is labelled [`STOP_BLOCK`].
pub fn decode_command(array: &Float64MultiArray, dof: usize) -> Result<Command<'_>, WireError> {
    let offset = array.data_offset as usize;
    let torques = match array.data.get(offset..) {
        Some(torques) if torques.len() == dof => torques,
        _ => {
            return Err(WireError(format!(
                "a torque command holds {} numbers after offset {offset}; the arm has {dof} joints",
                array.data.len()
            )))
        }
    };
    Ok(match array.dim.first() {
        Some(dim) if dim.label == STOP_BLOCK => Command::DampedStop,
        _ => Command::Effort(torques),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DVector, Vector6};

    fn state(dof: usize) -> State {
        State {
            tick: 1234,
            obs: Observation {
                t: 1.234,
                q: DVector::from_fn(dof, |i, _| 0.1 * i as f64 - 0.3),
                qd: DVector::from_fn(dof, |i, _| -0.01 * i as f64),
                wrench_sensor: Vector6::new(1.0, -2.0, 3.5, 0.1, 0.2, -0.3),
                wrench_base: Vector6::new(-1.0, 2.0, -3.5, 0.4, 0.5, 0.6),
                arm_contact_n: 12.5,
                arm_contact_link: Some(3),
            },
            round_trip_us: 87.5,
            late: true,
            period_us: f64::NAN,
            fault: Some(Fault::NonFiniteTorque { joint: 3 }),
            damped_stop: true,
            parts: vec![("button".to_owned(), 0.00375), ("lever:2".to_owned(), -1e-9)],
        }
    }

    #[test]
    fn states_round_trip_through_cdr_bit_for_bit() {
        let sent = state(7);
        let bytes = sent.encode().encode();
        let got = State::decode(&Float64MultiArray::decode(&bytes).expect("cdr"), 7).expect("state");
        assert_eq!(got.tick, sent.tick);
        assert_eq!(got.obs, sent.obs);
        assert_eq!(got.round_trip_us, sent.round_trip_us);
        assert!(got.late && got.period_us.is_nan());
        assert_eq!(got.parts, sent.parts);
        assert_eq!(got.fault, sent.fault);
        assert!(got.damped_stop);
        let mut none = sent.clone();
        none.obs.arm_contact_link = None;
        none.fault = None;
        none.damped_stop = false;
        none.parts.clear();
        let got = State::decode(&none.encode(), 7).expect("state");
        assert_eq!(got.obs.arm_contact_link, None);
        assert!(got.parts.is_empty() && got.fault.is_none() && !got.damped_stop);
    }

    #[test]
    fn a_state_of_another_robot_is_named() {
        let err = State::decode(&state(6).encode(), 7).expect_err("6 joints are not 7");
        assert!(err.0.contains("7-joint plant"), "{err}");
        let mut short = state(7).encode();
        short.data.pop();
        assert!(State::decode(&short, 7).is_err());
        let mut stranger = state(7).encode();
        stranger.dim.last_mut().expect("a part").label = "lever".to_owned();
        let err = State::decode(&stranger, 7).expect_err("not a part's label");
        assert!(err.0.contains("`lever`"), "{err}");
        let mut long = state(7).encode();
        long.dim.last_mut().expect("a part").size = 2;
        long.data.push(0.0);
        assert!(State::decode(&long, 7).is_err());
    }

    #[test]
    fn commands_read_with_their_offset() {
        let torques = [1.0, -2.0, 3.0];
        let array = encode_command(&torques, false);
        assert_eq!(decode_command(&array, 3).expect("3"), Command::Effort(&torques));
        assert!(decode_command(&array, 7).is_err());
        assert_eq!(
            decode_command(&encode_command(&torques, true), 3).expect("3"),
            Command::DampedStop
        );
        let padded = Float64MultiArray {
            dim: Vec::new(),
            data_offset: 1,
            data: vec![9.0, 1.0, -2.0, 3.0],
        };
        assert_eq!(decode_command(&padded, 3).expect("offset"), Command::Effort(&torques));
    }
}

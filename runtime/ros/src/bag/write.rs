//! Writing MCAP files with ROS 2 messages: a run log (joint states, tool pose, desired pose,
//! wrench, state changes) and a demonstration (tool pose and wrench), in memory, for the caller
//! to write atomically.

use std::collections::BTreeMap;
use std::io::Cursor;

use skill_exec::{LogBatch, RunLog};
use skill_learn::demo::{Demo, WrenchFrame};

use skill_sim::{ObjectShape, ObjectSpec};

use super::msgs::{
    encode_markers, encode_string, marker_action, marker_type, Header, JointState, Marker, MsgType, PoseStamped, Time,
    WrenchStamped,
};
use super::BagError;

/// The topic a written demonstration's pose goes to (`geometry_msgs/msg/PoseStamped`).
pub const DEMO_POSE_TOPIC: &str = "/tool_pose";
/// The topic a written demonstration's wrench goes to (`geometry_msgs/msg/WrenchStamped`).
pub const DEMO_WRENCH_TOPIC: &str = "/wrench";
/// The robot base frame's name in written headers.
const BASE_FRAME: &str = "base";
/// The tool (flange or tool point) frame's name in written headers.
const TOOL_FRAME: &str = "tool";

/// The topics of a run log written as MCAP.
#[derive(Debug, Clone, Copy)]
pub struct RunLogTopics;

impl RunLogTopics {
    /// `sensor_msgs/msg/JointState` every tick: positions, velocities, and as efforts the
    /// commanded torques.
    pub const JOINT_STATES: &'static str = "/joint_states";
    /// `geometry_msgs/msg/PoseStamped` every tick: the measured tool point in frame `base`.
    pub const TOOL_POSE: &'static str = "/tool_pose";
    /// `geometry_msgs/msg/PoseStamped` every tick: the commanded tool point in frame `base`.
    pub const DESIRED_POSE: &'static str = "/desired_pose";
    /// `geometry_msgs/msg/WrenchStamped` every tick: the wrench the environment exerts on the
    /// tool (what a wrist sensor reports, the negative of the CSV log's applied `fx..mz`), at the
    /// tool point, in the axes of frame `base`.
    pub const WRENCH: &'static str = "/wrench";
    /// `std_msgs/msg/String` at the first tick and at every change of state: the state's name
    /// (`step/state` in a task).
    pub const STATE: &'static str = "/skill_state";
    /// `tf2_msgs/msg/TFMessage` every [`TF_PERIOD_TICKS`] ticks: the pose in frame `base` of
    /// every link the joints move, from the logged joint positions (a star from `base`, not
    /// robot_state_publisher's parent-to-child chain; a viewer composes both alike).
    pub const TF: &'static str = "/tf";
    /// `tf2_msgs/msg/TFMessage` once, latched: the links no joint moves.
    pub const TF_STATIC: &'static str = "/tf_static";
    /// `std_msgs/msg/String` once, first in the file, latched: the robot's URDF.
    pub const ROBOT_DESCRIPTION: &'static str = "/robot_description";
    /// `visualization_msgs/msg/MarkerArray`, latched: the scene's objects (boxes as cubes,
    /// cylinders and button caps as cylinders, in frame `base`), namespace `scene`, and their
    /// names above them, namespace `scene_labels`. Written at the start with every object at
    /// rest, and again whole whenever a moving part's sample in the log moved it (a button's
    /// cap pressed in, every [`PART_PERIOD_TICKS`](skill_exec::PART_PERIOD_TICKS)
    /// ticks at most).
    pub const SCENE: &'static str = "/scene";
    /// `visualization_msgs/msg/MarkerArray` every [`TF_PERIOD_TICKS`] ticks: the contact force
    /// on the tool as arrows from the tool point, [`FORCE_ARROW_M_PER_N`] long per newton
    /// (namespace `contact_force`): id 0 the measured force (as `/wrench` carries it), id 1 the
    /// desired one (the force the controller's target applied force meets back, zero on
    /// position axes). An arrow under [`FORCE_ARROW_MIN_N`] is deleted.
    pub const CONTACT_FORCE: &'static str = "/contact_force";

    /// Every topic with its type, in the order the bag registers them. The first three need the
    /// robot's model and are left out without it.
    pub const ALL: [(&'static str, MsgType); 10] = [
        (Self::ROBOT_DESCRIPTION, MsgType::String),
        (Self::TF_STATIC, MsgType::TfMessage),
        (Self::TF, MsgType::TfMessage),
        (Self::SCENE, MsgType::MarkerArray),
        (Self::JOINT_STATES, MsgType::JointState),
        (Self::TOOL_POSE, MsgType::PoseStamped),
        (Self::DESIRED_POSE, MsgType::PoseStamped),
        (Self::WRENCH, MsgType::WrenchStamped),
        (Self::CONTACT_FORCE, MsgType::MarkerArray),
        (Self::STATE, MsgType::String),
    ];
}

/// The length of a force arrow per newton of force \[m/N\]: 10 N draws 5 cm.
pub const FORCE_ARROW_M_PER_N: f64 = 0.005;

/// A force below this draws no arrow \[N\] (free motion: sensor noise and the tool's inertia).
pub const FORCE_ARROW_MIN_N: f64 = 0.5;

/// `/tf` is written every this many ticks: 100 Hz at the 1 kHz control rate (every tick would
/// triple the file for a 3-D view that cannot show more).
pub const TF_PERIOD_TICKS: usize = 10;

/// What a run log's bag needs of the robot to carry its transforms and description.
pub struct RobotDescription<'a> {
    /// The model whose forward kinematics give the links' poses.
    pub robot: &'a skill_robot::Robot,
    /// The URDF text, for `/robot_description`.
    pub urdf: &'a str,
}

/// rosbag2's QoS metadata of a latched topic (transient local, keep last 1), as `ros2 bag
/// record` writes it in a channel's `offered_qos_profiles`, so `ros2 bag play` republishes the
/// topic to late subscribers.
const LATCHED_QOS: &str = "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false";

/// A link's pose as a transform from `base`.
fn link_transform(t: Time, name: &str, pose: &nalgebra::Isometry3<f64>) -> super::msgs::TransformStamped {
    let q = pose.rotation.quaternion();
    super::msgs::TransformStamped {
        header: header(t, BASE_FRAME),
        child_frame_id: name.to_owned(),
        translation: [pose.translation.x, pose.translation.y, pose.translation.z],
        rotation_xyzw: [q.i, q.j, q.k, q.w],
    }
}

/// An MCAP writer into memory with the channels registered by topic.
struct Bag {
    writer: mcap::Writer<Cursor<Vec<u8>>>,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
}

impl Bag {
    fn new(channels: &[(&'static str, MsgType)]) -> Result<Bag, BagError> {
        let mut writer = mcap::WriteOptions::new()
            .profile("ros2")
            .compression(Some(mcap::Compression::Zstd))
            // zstd level 1: 12 % fewer instructions for writing a run log than the default
            // level 3, and no larger a file (slide: 4.96 MB against 5.00 MB).
            .compression_level(1)
            // Compressed on the writer's own thread: a run log is encoded beside the run
            // (src/run_log.rs), whose one core zstd's workers would otherwise take turns with.
            .compression_threads(0)
            .create(Cursor::new(Vec::new()))
            .map_err(BagError::Write)?;
        let mut ids = BTreeMap::new();
        for &(topic, ty) in channels {
            let schema = writer
                .add_schema(ty.schema_name(), "ros2msg", ty.definition().as_bytes())
                .map_err(BagError::Write)?;
            let mut metadata = BTreeMap::new();
            if [
                RunLogTopics::TF_STATIC,
                RunLogTopics::ROBOT_DESCRIPTION,
                RunLogTopics::SCENE,
            ]
            .contains(&topic)
            {
                metadata.insert("offered_qos_profiles".to_string(), LATCHED_QOS.to_string());
            }
            let id = writer
                .add_channel(schema, topic, "cdr", &metadata)
                .map_err(BagError::Write)?;
            ids.insert(topic, id);
        }
        Ok(Bag {
            writer,
            channels: ids,
            sequence: 0,
        })
    }

    fn put(&mut self, topic: &'static str, t: Time, data: &[u8]) -> Result<(), BagError> {
        let channel_id = *self
            .channels
            .get(topic)
            .expect("Bag::put: every topic is registered in Bag::new");
        self.sequence = self.sequence.wrapping_add(1);
        let ns = u64::try_from(t.nanos()).unwrap_or(0);
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: ns,
            publish_time: ns,
        };
        self.writer
            .write_to_known_channel(&header, data)
            .map_err(BagError::Write)
    }

    fn finish(mut self) -> Result<Vec<u8>, BagError> {
        self.writer.finish().map_err(BagError::Write)?;
        Ok(self.writer.into_inner().into_inner())
    }
}

fn header(t: Time, frame: &str) -> Header {
    Header {
        stamp: t,
        frame_id: frame.to_owned(),
    }
}

/// A pose `[x, y, z, qw, qx, qy, qz]` (the log's order) as a PoseStamped.
fn pose(t: Time, pose: &[f64; 7]) -> PoseStamped {
    let [x, y, z, qw, qx, qy, qz] = *pose;
    PoseStamped {
        header: header(t, BASE_FRAME),
        position: [x, y, z],
        orientation_xyzw: [qx, qy, qz, qw],
    }
}

/// A marker with the fields every marker here shares filled in.
fn marker(t: Time, ns: &str, id: usize, shape: i32) -> Marker {
    Marker {
        header: header(t, BASE_FRAME),
        ns: ns.to_owned(),
        id: i32::try_from(id).unwrap_or(i32::MAX),
        shape,
        action: marker_action::ADD,
        orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
        ..Marker::default()
    }
}

/// The scene's objects as markers, each with its name above it (see [`RunLogTopics::SCENE`]),
/// each moved by its offset in `offsets_m` (by the objects' order; none given: at rest) down its
/// own z axis: a button's cap pressed in. The labels stay where the objects stand at rest.
fn scene_markers(t: Time, objects: &BTreeMap<String, ObjectSpec>, offsets_m: &[f64]) -> Vec<Marker> {
    let mut markers = Vec::with_capacity(2 * objects.len());
    for (index, (name, object)) in objects.iter().enumerate() {
        let offset_m = offsets_m.get(index).copied().unwrap_or(0.0);
        let pose = object.pose() * nalgebra::Translation3::new(0.0, 0.0, -offset_m);
        let q = pose.rotation.quaternion();
        let (shape, scale, color, half_height) = match object.shape() {
            ObjectShape::Box { size } => (marker_type::CUBE, size, [0.62, 0.62, 0.66, 1.0], size[2] / 2.0),
            ObjectShape::Cylinder { radius, length } => (
                marker_type::CYLINDER,
                [2.0 * radius, 2.0 * radius, length],
                [0.55, 0.62, 0.75, 1.0],
                length / 2.0,
            ),
            ObjectShape::Button { radius, height, .. } => (
                marker_type::CYLINDER,
                [2.0 * radius, 2.0 * radius, height],
                [0.85, 0.22, 0.2, 1.0],
                height / 2.0,
            ),
        };
        let mut body = marker(t, "scene", index, shape);
        body.position = [pose.translation.x, pose.translation.y, pose.translation.z];
        body.orientation_xyzw = [q.i, q.j, q.k, q.w];
        body.scale = scale;
        body.color_rgba = color;
        markers.push(body);
        // The label stands 2 cm above the object's top along the world's z (a tilted object's
        // highest point is not sought: the label only names it).
        let top = object.pose() * nalgebra::Point3::new(0.0, 0.0, half_height);
        let mut label = marker(t, "scene_labels", index, marker_type::TEXT_VIEW_FACING);
        label.position = [top.x, top.y, top.z + 0.02];
        label.scale = [0.0, 0.0, 0.02];
        label.color_rgba = [1.0, 1.0, 1.0, 1.0];
        label.text = name.clone();
        markers.push(label);
    }
    markers
}

/// The measured and desired force on the tool as arrows from the tool point (see
/// [`RunLogTopics::CONTACT_FORCE`]).
fn force_arrows(t: Time, tool: [f64; 3], measured: [f64; 3], desired: [f64; 3]) -> Vec<Marker> {
    [(measured, [1.0, 0.55, 0.0, 1.0]), (desired, [0.2, 0.8, 0.3, 0.6])]
        .into_iter()
        .enumerate()
        .map(|(id, (force, color))| {
            let mut arrow = marker(t, "contact_force", id, marker_type::ARROW);
            let norm = force.iter().map(|f| f * f).sum::<f64>().sqrt();
            if norm < FORCE_ARROW_MIN_N {
                arrow.action = marker_action::DELETE;
                return arrow;
            }
            let tip = std::array::from_fn(|axis| tool[axis] + FORCE_ARROW_M_PER_N * force[axis]);
            arrow.points = vec![tool, tip];
            // Shaft diameter, head diameter, head length.
            arrow.scale = [0.003, 0.008, 0.01];
            arrow.color_rgba = color;
            arrow
        })
        .collect()
}

/// A demonstration as MCAP: its flange pose on [`DEMO_POSE_TOPIC`] and its wrench on
/// [`DEMO_WRENCH_TOPIC`], both stamped with the sample times. The wrench's header names frame
/// `base` or `tool` as `wrench_frame` says, and no frame when it is not known (the reader then
/// leaves it to be detected).
pub fn write_demo(demo: &Demo, wrench_frame: Option<WrenchFrame>) -> Result<Vec<u8>, BagError> {
    let wrench_frame_id = match wrench_frame {
        Some(WrenchFrame::Base) => BASE_FRAME,
        Some(WrenchFrame::Sensor) => TOOL_FRAME,
        None => "",
    };
    let mut bag = Bag::new(&[
        (DEMO_POSE_TOPIC, MsgType::PoseStamped),
        (DEMO_WRENCH_TOPIC, MsgType::WrenchStamped),
    ])?;
    for k in 0..demo.len() {
        let t = Time::from_seconds(demo.t_s[k]);
        let q = demo.orientation[k].quaternion();
        let p = demo.position_m[k];
        let message = PoseStamped {
            header: header(t, BASE_FRAME),
            position: [p.x, p.y, p.z],
            orientation_xyzw: [q.i, q.j, q.k, q.w],
        };
        bag.put(DEMO_POSE_TOPIC, t, &message.encode())?;
        let (f, m) = (demo.force_n[k], demo.torque_nm[k]);
        let message = WrenchStamped {
            header: header(t, wrench_frame_id),
            force: [f.x, f.y, f.z],
            torque: [m.x, m.y, m.z],
        };
        bag.put(DEMO_WRENCH_TOPIC, t, &message.encode())?;
    }
    bag.finish()
}

/// Consecutive run logs (one, or a task's steps: states written `step/state`) as MCAP on the
/// [`RunLogTopics`]. `joint_names` name the joints (fewer names than joints: `joint_N`);
/// `objects` are the scene's, drawn on `/scene`. A log whose clock starts again is shifted to
/// follow the one before it, so times never go back.
pub fn write_run_log(
    logs: &[(Option<&str>, &RunLog)],
    joint_names: &[String],
    description: Option<&RobotDescription<'_>>,
    objects: &BTreeMap<String, ObjectSpec>,
) -> Result<Vec<u8>, BagError> {
    let mut writer = RunLogWriter::new(joint_names, description, objects);
    for (step, log) in logs {
        writer.start_log(step.map(str::to_owned));
        writer.push(log.batch())?;
    }
    writer.finish()
}

/// A run log written as MCAP as its ticks arrive (through a tap, while the run goes on): the
/// bytes [`write_run_log`] makes of the whole logs. The bag starts at the first tick, whose
/// time the latched topics carry.
pub struct RunLogWriter {
    /// The robot and its URDF, for `/robot_description` and `/tf`.
    robot: Option<(skill_robot::Robot, String)>,
    objects: BTreeMap<String, ObjectSpec>,
    /// How far each object (by the map's order) has moved from its rest, as last drawn, m.
    offsets_m: Vec<f64>,
    /// The joint names, `joint_N` added for joints past the robot's.
    names: Vec<String>,
    /// The bag and, with a robot, its model's data and the links joints move; from the first tick.
    bag: Option<(Bag, Option<Kinematics>)>,
    /// The task step of the log being written, and whether its first tick is still to come.
    step: Option<String>,
    log_started: bool,
    /// Ticks written of the whole bag, and of the current log.
    tick_index: usize,
    log_ticks: usize,
    offset_s: f64,
    last_s: f64,
    last_state: Option<String>,
}

/// The robot model's data and the links its joints move, for `/tf`.
type Kinematics = (skill_robot::RobotData, Vec<usize>);

impl RunLogWriter {
    /// A writer of logs of an arm with `joint_names` (see [`write_run_log`]).
    pub fn new(
        joint_names: &[String],
        description: Option<&RobotDescription<'_>>,
        objects: &BTreeMap<String, ObjectSpec>,
    ) -> Self {
        RunLogWriter {
            robot: description.map(|d| (d.robot.clone(), d.urdf.to_owned())),
            objects: objects.clone(),
            offsets_m: vec![0.0; objects.len()],
            names: joint_names.to_vec(),
            bag: None,
            step: None,
            log_started: false,
            tick_index: 0,
            log_ticks: 0,
            offset_s: 0.0,
            last_s: f64::NEG_INFINITY,
            last_state: None,
        }
    }

    /// The next ticks are the next log's, of task step `step`.
    pub fn start_log(&mut self, step: Option<String>) {
        self.step = step;
        self.log_started = true;
        self.log_ticks = 0;
    }

    /// The bag with its latched topics, begun at `first_t`.
    fn begin(&self, first_t: Time) -> Result<(Bag, Option<Kinematics>), BagError> {
        let robot_topics = if self.robot.is_some() { 0 } else { 3 };
        let topics = &RunLogTopics::ALL[robot_topics..];
        let mut bag = Bag::new(topics)?;
        let mut kinematics = None;
        if let Some((robot, urdf)) = &self.robot {
            bag.put(RunLogTopics::ROBOT_DESCRIPTION, first_t, &encode_string(urdf))?;
            let mut data = robot.data();
            robot.forward_kinematics(&mut data, &vec![0.0; robot.dof()]);
            // Links no joint moves go on /tf_static once, the others on /tf.
            let (fixed, moving): (Vec<usize>, Vec<usize>) =
                (0..robot.links().len()).partition(|&link| robot.links()[link].body.is_none());
            let fixed: Vec<_> = fixed
                .into_iter()
                .map(|link| link_transform(first_t, &robot.links()[link].name, &robot.link_in_base(&data, link)))
                .collect();
            bag.put(RunLogTopics::TF_STATIC, first_t, &super::msgs::encode_tf(&fixed))?;
            kinematics = Some((data, moving));
        }
        bag.put(
            RunLogTopics::SCENE,
            first_t,
            &encode_markers(&scene_markers(first_t, &self.objects, &[])),
        )?;
        Ok((bag, kinematics))
    }

    /// Writes `batch`, the next ticks of the current log with their part samples: each sample
    /// moves its object on `/scene`.
    pub fn push(&mut self, batch: LogBatch<'_>) -> Result<(), BagError> {
        let LogBatch {
            states,
            ticks,
            part_names,
            parts,
        } = batch;
        let Some(first) = ticks.first() else { return Ok(()) };
        if self.bag.is_none() {
            self.bag = Some(self.begin(Time::from_seconds(first.t_s))?);
        }
        if std::mem::take(&mut self.log_started) && first.t_s + self.offset_s <= self.last_s {
            self.offset_s = self.last_s + 1e-3 - first.t_s;
        }
        let Some((bag, kinematics)) = self.bag.as_mut() else {
            return Ok(());
        };
        let mut parts = parts.iter().peekable();
        for tick in ticks {
            let t_s = tick.t_s + self.offset_s;
            self.last_s = t_s;
            let t = Time::from_seconds(t_s);
            let dof = tick.joint_state.len() / 2;
            while self.names.len() < dof {
                self.names.push(format!("joint_{}", self.names.len() + 1));
            }
            let joints = JointState {
                header: header(t, ""),
                name: self.names[..dof].to_vec(),
                position: tick.joint_state[..dof].to_vec(),
                velocity: tick.joint_state[dof..2 * dof].to_vec(),
                effort: tick.torques.to_vec(),
            };
            bag.put(RunLogTopics::JOINT_STATES, t, &joints.encode())?;
            bag.put(RunLogTopics::TOOL_POSE, t, &pose(t, &tick.measured).encode())?;
            bag.put(RunLogTopics::DESIRED_POSE, t, &pose(t, &tick.desired).encode())?;
            let w = &tick.wrench_base;
            let wrench = WrenchStamped {
                header: header(t, BASE_FRAME),
                force: [-w[0], -w[1], -w[2]],
                torque: [-w[3], -w[4], -w[5]],
            };
            bag.put(RunLogTopics::WRENCH, t, &wrench.encode())?;
            let on_view_tick = self.tick_index.is_multiple_of(TF_PERIOD_TICKS);
            if on_view_tick {
                let desired = tick.desired_force_base();
                let arrows = force_arrows(
                    t,
                    [tick.measured[0], tick.measured[1], tick.measured[2]],
                    wrench.force,
                    [-desired[0], -desired[1], -desired[2]],
                );
                bag.put(RunLogTopics::CONTACT_FORCE, t, &encode_markers(&arrows))?;
            }
            if let (Some((robot, _)), Some((data, moving_links))) = (&self.robot, kinematics.as_mut()) {
                if on_view_tick && dof == robot.dof() {
                    robot.forward_kinematics(data, &tick.joint_state[..dof]);
                    let moving: Vec<_> = moving_links
                        .iter()
                        .map(|&link| link_transform(t, &robot.links()[link].name, &robot.link_in_base(data, link)))
                        .collect();
                    bag.put(RunLogTopics::TF, t, &super::msgs::encode_tf(&moving))?;
                }
            }
            // The whole scene again when a part moved: a latched topic's last message is
            // what a viewer that joins late draws.
            let mut moved = false;
            while let Some(sample) = parts.next_if(|sample| sample.tick <= self.log_ticks) {
                let name = part_names.get(sample.part as usize);
                if let Some(index) = name.and_then(|name| self.objects.keys().position(|key| key == name)) {
                    self.offsets_m[index] = sample.offset_m;
                    moved = true;
                }
            }
            if moved {
                bag.put(
                    RunLogTopics::SCENE,
                    t,
                    &encode_markers(&scene_markers(t, &self.objects, &self.offsets_m)),
                )?;
            }
            self.tick_index += 1;
            self.log_ticks += 1;
            let state = states.get(tick.state as usize).map_or("?", String::as_str);
            let state = match &self.step {
                Some(step) => format!("{step}/{state}"),
                None => state.to_owned(),
            };
            if self.last_state.as_deref() != Some(state.as_str()) {
                bag.put(RunLogTopics::STATE, t, &encode_string(&state))?;
                self.last_state = Some(state);
            }
        }
        Ok(())
    }

    /// The whole file.
    pub fn finish(mut self) -> Result<Vec<u8>, BagError> {
        let (bag, _) = match self.bag.take() {
            Some(begun) => begun,
            None => self.begin(Time::from_seconds(0.0))?,
        };
        bag.finish()
    }
}

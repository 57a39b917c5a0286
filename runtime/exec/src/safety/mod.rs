//! The safety supervisor between controller and plant: checks every tick against [`Limits`],
//! turns a violation into a reflex (a damped stop), and keeps the run's safety figures.
//!
//! Every tick the run loop hands it the observation, what the controller measured, the command
//! and the torques about to be applied. [`Supervisor::check`] returns the first limit crossed, in
//! a fixed order of severity (non-finite numbers first: nothing non-finite ever reaches
//! [`crate::plant::Plant::apply`]). After a violation the loop applies [`Supervisor::stop_torques`]
//! (gravity compensation with joint damping: the arm comes to rest where it is, as a real arm's
//! reflex brakes it) for [`REFLEX_HOLD_S`] and ends the run as a failure.
//!
//! Nothing here allocates after [`Supervisor::new`].

mod limits;

pub use limits::{
    LimitError, Limits, Workspace, ARM_CONTACT_N, LIMIT_NAMES, REDUCED_SPEED_MPS, SATURATION_FRACTION,
    WORKSPACE_MARGIN_M,
};

use nalgebra::UnitQuaternion;
use std::fmt;

use crate::control::{Command, ControlState};
use crate::plant::Observation;
use crate::robot::{Robot, RobotData};

/// How long the damped stop is held after a reflex before the run ends \[s\].
pub const REFLEX_HOLD_S: f64 = 0.3;

/// The quantity a reflex is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Quantity {
    /// A NaN or infinite number in the sensed state, the command or the torques.
    NonFinite,
    /// The magnitude of the applied force \[N\].
    ContactForce,
    /// The magnitude of the applied moment \[N m\].
    ContactMoment,
    /// Tool-point speed \[m/s\].
    ToolSpeed,
    /// Tool angular speed \[rad/s\].
    ToolAngularSpeed,
    /// Distance of a joint from its position limit \[rad\].
    JointMargin,
    /// Joint speed as a fraction of its velocity limit.
    JointSpeed,
    /// Time a joint torque stayed at its effort limit \[s\].
    TorqueSaturation,
    /// Position error on position-controlled axes \[m\].
    TrackingError,
    /// Orientation error on position-controlled axes \[rad\].
    TrackingAngle,
    /// Distance of the tool point outside the workspace box \[m\].
    Workspace,
    /// The contact force on a link of the arm other than the tool \[N\]: a link touches an
    /// object of the scene.
    ArmContact,
}

impl Quantity {
    /// A short stable name (the `reason` in eval summaries).
    pub fn name(self) -> &'static str {
        match self {
            Quantity::NonFinite => "non_finite",
            Quantity::ContactForce => "contact_force",
            Quantity::ContactMoment => "contact_moment",
            Quantity::ToolSpeed => "tool_speed",
            Quantity::ToolAngularSpeed => "tool_angular_speed",
            Quantity::JointMargin => "joint_margin",
            Quantity::JointSpeed => "joint_speed",
            Quantity::TorqueSaturation => "torque_saturation",
            Quantity::TrackingError => "tracking_error",
            Quantity::TrackingAngle => "tracking_angle",
            Quantity::Workspace => "workspace",
            Quantity::ArmContact => "arm_contact",
        }
    }

    /// The name of the limit that bounds it on the command line and in [`Limits::set`], if any
    /// (non-finite numbers and the workspace box cannot be loosened by name).
    pub fn limit_name(self) -> Option<&'static str> {
        match self {
            Quantity::ContactForce => Some("force"),
            Quantity::ContactMoment => Some("moment"),
            Quantity::ToolSpeed => Some("speed"),
            Quantity::ToolAngularSpeed => Some("angular_speed"),
            Quantity::JointMargin => Some("joint_margin"),
            Quantity::JointSpeed => Some("joint_speed"),
            Quantity::TorqueSaturation => Some("saturation"),
            Quantity::TrackingError => Some("tracking"),
            Quantity::TrackingAngle => Some("tracking_angle"),
            Quantity::ArmContact => Some("arm_contact"),
            Quantity::NonFinite | Quantity::Workspace => None,
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Quantity::NonFinite => "a non-finite number",
            Quantity::ContactForce => "contact force",
            Quantity::ContactMoment => "contact moment",
            Quantity::ToolSpeed => "tool speed",
            Quantity::ToolAngularSpeed => "tool angular speed",
            Quantity::JointMargin => "joint limit margin",
            Quantity::JointSpeed => "joint speed",
            Quantity::TorqueSaturation => "torque saturation",
            Quantity::TrackingError => "tracking error",
            Quantity::TrackingAngle => "orientation tracking error",
            Quantity::Workspace => "distance outside the workspace",
            Quantity::ArmContact => "arm contact with the scene",
        }
    }

    fn unit(self) -> &'static str {
        match self {
            Quantity::NonFinite => "",
            Quantity::ContactForce | Quantity::ArmContact => " N",
            Quantity::ContactMoment => " N m",
            Quantity::ToolSpeed => " m/s",
            Quantity::ToolAngularSpeed => " rad/s",
            Quantity::JointMargin | Quantity::TrackingAngle => " rad",
            Quantity::JointSpeed => " × the velocity limit",
            Quantity::TorqueSaturation => " s",
            Quantity::TrackingError | Quantity::Workspace => " m",
        }
    }

    /// Whether the limit is a lower bound (the measured value fell below it).
    fn is_lower_bound(self) -> bool {
        matches!(self, Quantity::JointMargin)
    }
}

/// A limit crossed: what, by how much, where.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    /// Run time \[s\].
    pub t_s: f64,
    /// What was crossed.
    pub quantity: Quantity,
    /// The measured value, in the quantity's unit.
    pub measured: f64,
    /// The limit, in the same unit.
    pub limit: f64,
    /// What it concerns: a joint name, an object, the number that was not finite.
    pub detail: String,
    /// Index of the joint concerned, for joint quantities.
    pub joint: Option<usize>,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let unit = self.quantity.unit();
        if self.quantity == Quantity::NonFinite {
            return write!(
                f,
                "{} in {} at t = {:.3} s",
                self.quantity.describe(),
                self.detail,
                self.t_s
            );
        }
        let relation = if self.quantity.is_lower_bound() {
            "below"
        } else {
            "above"
        };
        write!(
            f,
            "{}{} {:.4}{unit} {relation} the limit {:.4}{unit} at t = {:.3} s",
            self.quantity.describe(),
            if self.detail.is_empty() {
                String::new()
            } else {
                format!(" ({})", self.detail)
            },
            self.measured,
            self.limit,
            self.t_s
        )
    }
}

/// The safety figures of a run, kept every tick.
#[derive(Debug, Clone, PartialEq)]
pub struct SafetyStats {
    /// Largest applied force magnitude \[N\].
    pub peak_force_n: f64,
    /// Largest tool-point speed \[m/s\].
    pub peak_tool_speed_mps: f64,
    /// Smallest distance of any joint from its position limits \[rad\].
    pub min_joint_margin_rad: f64,
    /// Total time any joint torque was at its effort limit \[s\].
    pub torque_limit_s: f64,
    /// Largest joint speed as a fraction of its velocity limit.
    pub peak_joint_speed_fraction: f64,
}

impl Default for SafetyStats {
    fn default() -> Self {
        SafetyStats {
            peak_force_n: 0.0,
            peak_tool_speed_mps: 0.0,
            min_joint_margin_rad: f64::INFINITY,
            torque_limit_s: 0.0,
            peak_joint_speed_fraction: 0.0,
        }
    }
}

/// Checks every tick against [`Limits`] and brings the arm to a damped stop after a violation.
#[derive(Debug, Clone)]
pub struct Supervisor {
    limits: Limits,
    lower: Vec<f64>,
    upper: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
    names: Vec<String>,
    link_names: Vec<String>,
    saturated_s: Vec<f64>,
    stats: SafetyStats,
    data: RobotData,
    robot: Robot,
}

impl Supervisor {
    /// A supervisor for `robot` (its joint limits come from the robot file).
    pub fn new(robot: &Robot, limits: Limits) -> Self {
        let joints = robot.joints();
        Supervisor {
            limits,
            lower: joints.iter().map(|j| j.lower).collect(),
            upper: joints.iter().map(|j| j.upper).collect(),
            velocity: joints.iter().map(|j| j.velocity).collect(),
            effort: joints.iter().map(|j| j.effort).collect(),
            names: joints.iter().map(|j| format!("joint `{}`", j.name)).collect(),
            link_names: robot.links().iter().map(|l| format!("link `{}`", l.name)).collect(),
            saturated_s: vec![0.0; joints.len()],
            stats: SafetyStats::default(),
            data: robot.data(),
            robot: robot.clone(),
        }
    }

    /// The limits in force.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Replaces the limits (a task step with its own), keeping the statistics.
    pub fn set_limits(&mut self, limits: Limits) {
        self.limits = limits;
    }

    /// The figures so far.
    pub fn stats(&self) -> &SafetyStats {
        &self.stats
    }

    /// Starts the figures and the saturation windows afresh.
    pub fn reset_stats(&mut self) {
        self.stats = SafetyStats::default();
        self.saturated_s.iter_mut().for_each(|s| *s = 0.0);
    }

    /// Checks one tick of `dt` seconds: the sensed state, what the controller measured, the
    /// command and the torques about to be applied. Updates the statistics; returns the first
    /// limit crossed.
    pub fn check(
        &mut self,
        t_s: f64,
        dt: f64,
        obs: &Observation,
        sensed: &ControlState,
        cmd: &Command,
        torques: &[f64],
    ) -> Result<(), Violation> {
        let violation = |quantity, measured, limit, detail: &str, joint| Violation {
            t_s,
            quantity,
            measured,
            limit,
            detail: detail.to_string(),
            joint,
        };
        if let Some(what) = first_non_finite(obs, sensed, cmd, torques) {
            return Err(violation(Quantity::NonFinite, f64::NAN, f64::NAN, what, None));
        }
        let limits = &self.limits;
        let force = sensed.applied.fixed_rows::<3>(0).norm();
        let moment = sensed.applied.fixed_rows::<3>(3).norm();
        let speed = sensed.twist.fixed_rows::<3>(0).norm();
        let angular = sensed.twist.fixed_rows::<3>(3).norm();
        let stats = &mut self.stats;
        stats.peak_force_n = stats.peak_force_n.max(force);
        stats.peak_tool_speed_mps = stats.peak_tool_speed_mps.max(speed);

        let mut joint_problem = None;
        for (idx, tau) in torques.iter().enumerate().take(self.lower.len()) {
            let q = obs.q[idx];
            let margin = (q - self.lower[idx]).min(self.upper[idx] - q);
            stats.min_joint_margin_rad = stats.min_joint_margin_rad.min(margin);
            let fraction = obs.qd[idx].abs() / self.velocity[idx];
            stats.peak_joint_speed_fraction = stats.peak_joint_speed_fraction.max(fraction);
            if tau.abs() >= SATURATION_FRACTION * self.effort[idx] {
                self.saturated_s[idx] += dt;
                stats.torque_limit_s += dt;
            } else {
                self.saturated_s[idx] = 0.0;
            }
            if joint_problem.is_some() {
                continue;
            }
            if margin < limits.joint_margin {
                joint_problem = Some((Quantity::JointMargin, margin, limits.joint_margin, idx));
            } else if fraction > limits.joint_speed_fraction {
                joint_problem = Some((Quantity::JointSpeed, fraction, limits.joint_speed_fraction, idx));
            } else if self.saturated_s[idx] > limits.torque_saturation_s + 0.5 * dt {
                joint_problem = Some((
                    Quantity::TorqueSaturation,
                    self.saturated_s[idx],
                    limits.torque_saturation_s,
                    idx,
                ));
            }
        }

        let cartesian = [
            (Quantity::ContactForce, force, limits.force_n),
            (Quantity::ContactMoment, moment, limits.moment_nm),
            (Quantity::ToolSpeed, speed, limits.tool_speed_mps),
            (Quantity::ToolAngularSpeed, angular, limits.tool_angular_speed_radps),
        ];
        // A link that has no business touching anything comes first: the contact force at the
        // tool may well follow from it.
        if obs.arm_contact_n > limits.arm_contact_n {
            let link = obs
                .arm_contact_link
                .and_then(|idx| self.link_names.get(idx))
                .map_or("an unknown link", String::as_str);
            return Err(violation(
                Quantity::ArmContact,
                obs.arm_contact_n,
                limits.arm_contact_n,
                link,
                None,
            ));
        }
        if let Some((quantity, measured, limit)) = first_above(cartesian) {
            return Err(violation(quantity, measured, limit, "", None));
        }
        if let Some((quantity, measured, limit, idx)) = joint_problem {
            return Err(violation(quantity, measured, limit, &self.names[idx], Some(idx)));
        }
        let (position_error, angle_error) = tracking_errors(sensed, cmd);
        let tracking = [
            (Quantity::TrackingError, position_error, limits.tracking_error_m),
            (Quantity::TrackingAngle, angle_error, limits.tracking_error_rad),
        ];
        if let Some((quantity, measured, limit)) = first_above(tracking) {
            return Err(violation(quantity, measured, limit, "", None));
        }
        if let Some(workspace) = &limits.workspace {
            let p = sensed.tool.translation.vector;
            let outside = workspace.outside_by([p.x, p.y, p.z]);
            if outside > 0.0 {
                return Err(violation(Quantity::Workspace, outside, 0.0, "", None));
            }
        }
        Ok(())
    }

    /// Counts a tick of the reflex stop in the statistics: the force and speed peaks of a run
    /// include the ticks after the crossing, while the arm is brought to its damped stop (an
    /// impact's force goes on rising for a few ticks after it crosses the limit).
    pub fn record_stop(&mut self, sensed: &ControlState) {
        let force = sensed.applied.fixed_rows::<3>(0).norm();
        let speed = sensed.twist.fixed_rows::<3>(0).norm();
        let stats = &mut self.stats;
        if force.is_finite() {
            stats.peak_force_n = stats.peak_force_n.max(force);
        }
        if speed.is_finite() {
            stats.peak_tool_speed_mps = stats.peak_tool_speed_mps.max(speed);
        }
    }

    /// The torques of the reflex stop at `obs` ([`Robot::damped_stop_torques`]).
    pub fn stop_torques(&mut self, obs: &Observation, out: &mut [f64]) {
        self.robot
            .damped_stop_torques(&mut self.data, obs.q.as_slice(), obs.qd.as_slice(), out);
    }
}

/// The first `(quantity, measured, limit)` whose measured value is above its limit.
fn first_above<const N: usize>(checks: [(Quantity, f64, f64); N]) -> Option<(Quantity, f64, f64)> {
    checks.into_iter().find(|(_, measured, limit)| measured > limit)
}

/// Where the first non-finite number is, if any.
fn first_non_finite(obs: &Observation, sensed: &ControlState, cmd: &Command, torques: &[f64]) -> Option<&'static str> {
    let all = |values: &[f64]| values.iter().all(|v| v.is_finite());
    if !all(obs.q.as_slice()) || !all(obs.qd.as_slice()) {
        return Some("the joint state");
    }
    if !all(obs.wrench_base.as_slice()) || !all(obs.wrench_sensor.as_slice()) {
        return Some("the force/torque sensor reading");
    }
    if !obs.arm_contact_n.is_finite() {
        return Some("the arm's contact force");
    }
    if !all(sensed.applied.as_slice()) || !all(sensed.twist.as_slice()) {
        return Some("the measured tool wrench or twist");
    }
    let pose = &cmd.pose;
    if !all(pose.translation.vector.as_slice()) || !all(pose.rotation.coords.as_slice()) {
        return Some("the desired pose");
    }
    if !all(cmd.twist.as_slice()) || !all(cmd.wrench.as_slice()) {
        return Some("the desired twist or wrench");
    }
    let frame = &cmd.frame;
    if !all(frame.translation.vector.as_slice()) || !all(frame.rotation.coords.as_slice()) {
        return Some("the compliant frame");
    }
    if !all(&cmd.stiffness) || !cmd.kp.is_finite() || !cmd.ki.is_finite() {
        return Some("the stiffness or force gains");
    }
    if !all(torques) {
        return Some("the joint torques");
    }
    None
}

/// The position and orientation errors along the command's position-controlled axes, in the
/// compliant frame \[m, rad\].
fn tracking_errors(sensed: &ControlState, cmd: &Command) -> (f64, f64) {
    let to_frame = cmd.frame.rotation.inverse();
    let error_p = to_frame * (cmd.pose.translation.vector - sensed.tool.translation.vector);
    let rotation: UnitQuaternion<f64> = cmd.pose.rotation * sensed.tool.rotation.inverse();
    let error_r = to_frame * rotation.scaled_axis();
    let mut squared_p = 0.0;
    let mut squared_r = 0.0;
    for axis in 0..3 {
        if cmd.position[axis] {
            squared_p += error_p[axis] * error_p[axis];
        }
        if cmd.position[axis + 3] {
            squared_r += error_r[axis] * error_r[axis];
        }
    }
    (squared_p.sqrt(), squared_r.sqrt())
}

#[cfg(test)]
mod tests;

//! The hybrid control law, evaluated once per tick without allocation.

use nalgebra::{DVector, Isometry3, Matrix6, Matrix6xX, UnitQuaternion, Vector3, Vector6};

use super::adjoint;
use crate::plant::Observation;
use crate::robot::{Robot, RobotData, RobotError};

/// Gains of the controller that do not come from the skill (the skill gives `K`, `S` and the
/// force gains per state). Defaults are tuned for the LWR-IV at 1 kHz.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerGains {
    /// Damping ratio of the position-controlled axes: `D = 2 ζ √(K m)`.
    pub damping_ratio: f64,
    /// Nominal effective mass for translational damping \[kg\].
    pub effective_mass_kg: f64,
    /// Nominal effective inertia for rotational damping \[kg m²\].
    pub effective_inertia_kgm2: f64,
    /// Upper bound of the rotational damping \[N m s/rad\]. The LWR-IV's last joint is light (the
    /// effective inertia about the tool axis is a few 1e-4 kg m²), and damping computed from the
    /// last tick's velocity is explicit: at 1 kHz, 0.8 N m s/rad made the wrist oscillate in
    /// simulation and 0.6 held; the default keeps a margin.
    pub max_rotational_damping: f64,
    /// Damping of force-controlled translations \[N s/m\]: bounds the speed of free motion under
    /// a force command to `f / d`.
    pub force_axis_damping: f64,
    /// Damping of force-controlled rotations \[N m s/rad\].
    pub force_axis_rotational_damping: f64,
    /// Upper bound of the speed along force-controlled translations \[m/s\]. A force loop that
    /// finds no resistance (a button's spring, a surface that gave way) accelerates until
    /// something stops it; what stops it must survive the impact. Hitting a stiff stop at speed
    /// `v` adds a force peak near `v √(k m)` to what the tool applied: with
    /// [`ControllerGains::force_axis_stop_stiffness`] and the arm's ~2.5 kg at the tool, 25 mm/s
    /// adds about 9 N. Below this bound the limit follows the force still missing, see
    /// [`ControllerGains::force_axis_speed_limit`].
    pub force_axis_speed_mps: f64,
    /// The force an unforeseen stop may add above the desired one \[N\]: the force-axis speed
    /// limit never goes below the speed whose impact adds this much (14 mm/s with the defaults),
    /// which is what a force loop may always move at to follow its surface (a contour over a
    /// drum moves up to 11-17 mm/s along its normal).
    pub force_axis_impact_n: f64,
    /// The arm's effective mass at the tool for the force-axis speed limit \[kg\]; `None` (the
    /// default) has [`HybridController::new`] take the robot's own along the base z at the rest
    /// posture (3.7 kg for the LWR-IV's start, 5.4 kg for the iiwa's): a heavier arm hits
    /// harder at the same speed, so it moves slower.
    pub force_axis_mass_kg: Option<f64>,
    /// The stiffness a force loop is assumed to meet when it hits something \[N/m\]: the scenes'
    /// default contact stiffness (a stop on a real fixture is stiffer: lower the speeds there).
    pub force_axis_stop_stiffness: f64,
    /// Braking gain on the speed above [`ControllerGains::force_axis_speed_mps`] \[N s/m\]. Kept
    /// below `m / dt` (2500 N s/m for 2.5 kg at 1 kHz; the default is 2000) so the explicit brake cannot overshoot.
    pub force_axis_brake: f64,
    /// Null-space posture stiffness \[N m/rad\].
    pub nullspace_stiffness: f64,
    /// Null-space posture damping \[N m s/rad\].
    pub nullspace_damping: f64,
    /// Fraction of each joint's velocity limit above which braking starts.
    pub velocity_limit_fraction: f64,
    /// Braking gain on the excess joint velocity \[N m s/rad\].
    pub velocity_brake_gain: f64,
}

impl ControllerGains {
    /// The speed limit along a force-controlled translation missing `force_error_n` of its
    /// desired force: the speed at which hitting a stop of stiffness
    /// [`ControllerGains::force_axis_stop_stiffness`] adds the larger of the missing force and
    /// [`ControllerGains::force_axis_impact_n`], `max(|e|, F) / √(k m)`, at most
    /// [`ControllerGains::force_axis_speed_mps`]. A loop far from its force (contact lost, a
    /// force just switched on) may move fast to find it; one that is nearly there (a button's
    /// cap travelling against its spring) meets the cap's end stop slowly enough that the peak
    /// stays within `F` of the desired force.
    pub fn force_axis_speed_limit(&self, force_error_n: f64, desired_n: f64) -> f64 {
        let mass = self.force_axis_mass_kg.unwrap_or(self.effective_mass_kg);
        let impedance = (self.force_axis_stop_stiffness * mass).max(0.0).sqrt();
        let force = force_error_n.abs().max(desired_n.abs()).max(self.force_axis_impact_n);
        if impedance > 0.0 && force.is_finite() {
            (force / impedance).min(self.force_axis_speed_mps)
        } else {
            self.force_axis_speed_mps
        }
    }
}

impl Default for ControllerGains {
    fn default() -> Self {
        ControllerGains {
            damping_ratio: 0.8,
            effective_mass_kg: 2.5,
            effective_inertia_kgm2: 0.0005,
            max_rotational_damping: 0.4,
            force_axis_damping: 40.0,
            force_axis_rotational_damping: 0.3,
            force_axis_speed_mps: 0.025,
            force_axis_impact_n: 5.0,
            force_axis_mass_kg: None,
            force_axis_stop_stiffness: 5.0e4,
            force_axis_brake: 2000.0,
            nullspace_stiffness: 10.0,
            nullspace_damping: 0.5,
            velocity_limit_fraction: 0.9,
            velocity_brake_gain: 1.0,
        }
    }
}

/// What the controller is asked to do this tick. Everything in the robot base frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Command {
    /// Desired tool pose.
    pub pose: Isometry3<f64>,
    /// Desired tool twist `[v; ω]` (feed-forward on position axes; zero to hold).
    pub twist: Vector6<f64>,
    /// Desired applied wrench `[f; m]` at the tool point (used on force-controlled axes).
    pub wrench: Vector6<f64>,
    /// The twist `[v; ω]` the force-controlled axes are expected to move at (used on them only;
    /// zero for none): their damping acts on the difference, so travel the desired force asks
    /// for (a button's cap going down its spring as the force rises, see
    /// [`crate::control::travel`]) is not paid for in force.
    pub force_twist: Vector6<f64>,
    /// The compliant frame in which `position` and `stiffness` are given.
    pub frame: Isometry3<f64>,
    /// Per compliant-frame axis: position-controlled (`true`) or force-controlled.
    pub position: [bool; 6],
    /// Stiffness per compliant-frame axis: N/m, N m/rad.
    pub stiffness: [f64; 6],
    /// Proportional force gain \[-\].
    pub kp: f64,
    /// Integral force gain \[1/s\].
    pub ki: f64,
    /// Clamp of each integral component \[N or N m\]; `None` leaves it unbounded.
    pub integral_limit: Option<f64>,
}

impl Command {
    /// Holds `pose` with all axes position-controlled at `stiffness`, in the base frame.
    pub fn hold(pose: Isometry3<f64>, stiffness: [f64; 6]) -> Self {
        Command {
            pose,
            twist: Vector6::zeros(),
            wrench: Vector6::zeros(),
            force_twist: Vector6::zeros(),
            frame: Isometry3::identity(),
            position: [true; 6],
            stiffness,
            kp: 0.0,
            ki: 0.0,
            integral_limit: None,
        }
    }
}

/// What the controller measured this tick (base frame, at the tool point).
#[derive(Debug, Clone, PartialEq)]
pub struct ControlState {
    /// Tool pose.
    pub tool: Isometry3<f64>,
    /// Tool twist `[v; ω]`.
    pub twist: Vector6<f64>,
    /// The wrench the robot applies `[f; m]`, about the tool point, sensor bias removed.
    pub applied: Vector6<f64>,
}

/// The hybrid controller with its preallocated workspace.
#[derive(Debug, Clone)]
pub struct HybridController {
    robot: Robot,
    data: RobotData,
    sensor_link: usize,
    gains: ControllerGains,
    q_rest: DVector<f64>,
    jacobian: Matrix6xX<f64>,
    gravity: DVector<f64>,
    torques: DVector<f64>,
    task_torques: DVector<f64>,
    posture: DVector<f64>,
    integral_cf: Vector6<f64>,
    bias_sensor: Vector6<f64>,
    state: ControlState,
}

/// The controller's period \[s\]: it runs at 1 kHz.
const CONTROL_PERIOD_S: f64 = 1e-3;
/// The share of the wrist's stability bound `2 I / dt` the rotational damping may take: 0.46,
/// which leaves the LWR-IV's 0.4 N m s/rad as it was (its bound, about 0.88) and caps the
/// FR3's at about 0.12.
const WRIST_DAMPING_SHARE: f64 = 0.46;

impl HybridController {
    /// A controller for `robot`, reading the wrist sensor at `sensor_link`, with the null space
    /// pulled towards `q_rest`.
    pub fn new(
        robot: Robot,
        sensor_link: &str,
        q_rest: &[f64],
        mut gains: ControllerGains,
    ) -> Result<Self, RobotError> {
        robot.check_dof(q_rest.len())?;
        if gains.force_axis_mass_kg.is_none() {
            gains.force_axis_mass_kg = robot.tool_effective_mass(q_rest, &Vector3::z());
        }
        // Damping from the last tick's velocity is stable only below 2 I / dt, I the inertia
        // about the tool's axis: each arm's wrist bounds its own (the FR3's, 1.3e-4 kg m², rang
        // at the LWR-IV's 0.4 N m s/rad).
        let mut rest = robot.data();
        robot.forward_kinematics(&mut rest, q_rest);
        let tool_axis = robot.tool_in_base(&rest).rotation * Vector3::z();
        if let Some(inertia) = robot.tool_effective_inertia(q_rest, &tool_axis) {
            let stable = WRIST_DAMPING_SHARE * 2.0 * inertia / CONTROL_PERIOD_S;
            gains.max_rotational_damping = gains.max_rotational_damping.min(stable);
            gains.force_axis_rotational_damping = gains.force_axis_rotational_damping.min(stable);
        }
        let sensor_link = robot.require_link(sensor_link)?;
        let n = robot.dof();
        let data = robot.data();
        Ok(HybridController {
            data,
            sensor_link,
            gains,
            q_rest: DVector::from_column_slice(q_rest),
            jacobian: Matrix6xX::zeros(n),
            gravity: DVector::zeros(n),
            torques: DVector::zeros(n),
            task_torques: DVector::zeros(n),
            posture: DVector::zeros(n),
            integral_cf: Vector6::zeros(),
            bias_sensor: Vector6::zeros(),
            state: ControlState {
                tool: Isometry3::identity(),
                twist: Vector6::zeros(),
                applied: Vector6::zeros(),
            },
            robot,
        })
    }

    /// The robot model the controller uses.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }

    /// The gains.
    pub fn gains(&self) -> &ControllerGains {
        &self.gains
    }

    /// What the last [`HybridController::observe`] measured.
    pub fn state(&self) -> &ControlState {
        &self.state
    }

    /// The integral term in compliant-frame coordinates (for logs and tests).
    pub fn integral(&self) -> &Vector6<f64> {
        &self.integral_cf
    }

    /// Zeroes the force integral (entry action `reset_integral`).
    pub fn reset_integral(&mut self) {
        self.integral_cf = Vector6::zeros();
    }

    /// Takes the current sensor reading as its zero (entry action `tare`).
    pub fn tare(&mut self, obs: &Observation) {
        self.bias_sensor = obs.wrench_base;
    }

    /// Kinematics, twist and applied wrench at the tool point for this observation. Call once per
    /// tick before [`HybridController::torques`]; guards read [`HybridController::state`].
    pub fn observe(&mut self, obs: &Observation) -> &ControlState {
        self.robot.forward_kinematics(&mut self.data, obs.q.as_slice());
        self.robot.tool_jacobian(&self.data, &mut self.jacobian);
        let tool = self.robot.tool_in_base(&self.data);
        let sensor = self.robot.link_in_base(&self.data, self.sensor_link);
        let twist = &self.jacobian * &obs.qd;
        // The sensor measures the environment's wrench on the tool about the sensor origin
        // (base axes); the robot applies its negative. Move the moment to the tool point.
        let measured = obs.wrench_base - self.bias_sensor;
        let force = measured.fixed_rows::<3>(0).into_owned();
        let moment_sensor = measured.fixed_rows::<3>(3).into_owned();
        let lever = sensor.translation.vector - tool.translation.vector;
        let moment_tool = moment_sensor + lever.cross(&force);
        let mut applied = Vector6::zeros();
        applied.fixed_rows_mut::<3>(0).copy_from(&(-force));
        applied.fixed_rows_mut::<3>(3).copy_from(&(-moment_tool));
        self.state = ControlState {
            tool,
            twist: Vector6::from_iterator(twist.iter().copied()),
            applied,
        };
        &self.state
    }

    /// The Cartesian wrench of the hybrid law at the tool point, base frame, and the integral
    /// update. Depends only on Cartesian quantities, so it is testable without a robot.
    pub fn cartesian_wrench(
        gains: &ControllerGains,
        state: &ControlState,
        cmd: &Command,
        integral_cf: &mut Vector6<f64>,
        dt: f64,
    ) -> Vector6<f64> {
        let frame_in_control = Self::frame_in_control(state, cmd);
        // Every operator of the law is `Adg · diag · Ad⁻¹` or `Adg · diag · Adg⁻¹` (Ω, Ω̃, the
        // damping, the twist selection; docs/method.md §6), so the law runs in the compliant
        // frame: each vector goes in once (`Ad⁻¹ v`, `Adg⁻¹ w = Adᵀ w`), the diagonals act per
        // axis, and one `Adg = Ad⁻ᵀ` brings the sum out: six matrix-vector products instead of
        // eight 6×6 matrix products and ten matrix-vector ones; equal to the matrix form
        // (`matches_the_operator_form`).
        let ad = adjoint::adjoint(&frame_in_control);
        let ad_inv = adjoint::adjoint_inverse(&frame_in_control);

        // Pose error: position difference and the rotation vector of q_d q⁻¹ (shortest way).
        let mut e_p = Vector6::zeros();
        e_p.fixed_rows_mut::<3>(0)
            .copy_from(&(cmd.pose.translation.vector - state.tool.translation.vector));
        e_p.fixed_rows_mut::<3>(3)
            .copy_from(&rotation_error(&cmd.pose.rotation, &state.tool.rotation));
        let e_p_cf = ad_inv * e_p;

        // Damping in the compliant frame, acting on the twist minus the commanded twist's
        // position-controlled part (Ad S Ad⁻¹ in the control frame).
        let twist_cf = ad_inv * state.twist;
        let cmd_twist_cf = ad_inv * cmd.twist;
        let force_twist_cf = ad_inv * cmd.force_twist;
        let mut d_cf = Vector6::zeros();
        let mut k_s = Vector6::zeros();
        for axis in 0..6 {
            let rotation = axis >= 3;
            d_cf[axis] = if cmd.position[axis] {
                k_s[axis] = cmd.stiffness[axis];
                let mass = if rotation {
                    gains.effective_inertia_kgm2
                } else {
                    gains.effective_mass_kg
                };
                let d = 2.0 * gains.damping_ratio * (cmd.stiffness[axis].max(0.0) * mass).sqrt();
                if rotation {
                    d.min(gains.max_rotational_damping)
                } else {
                    d
                }
            } else if rotation {
                gains.force_axis_rotational_damping
            } else {
                gains.force_axis_damping
            };
        }

        // Force error, in the compliant frame too.
        let desired_cf = ad.tr_mul(&cmd.wrench);
        let e_f_cf = desired_cf - ad.tr_mul(&state.applied);

        let brake_cf = Self::brake_and_integrate(gains, cmd, &twist_cf, &e_f_cf, &desired_cf, integral_cf, dt);

        let mut wrench_cf = *integral_cf * cmd.ki + brake_cf;
        for axis in 0..6 {
            wrench_cf[axis] += if cmd.position[axis] {
                k_s[axis] * e_p_cf[axis] - d_cf[axis] * (twist_cf[axis] - cmd_twist_cf[axis])
            } else {
                desired_cf[axis] + cmd.kp * e_f_cf[axis] - d_cf[axis] * (twist_cf[axis] - force_twist_cf[axis])
            };
        }
        ad_inv.tr_mul(&wrench_cf)
    }

    /// The compliant frame relative to the control frame (the tool point, base axes).
    fn frame_in_control(state: &ControlState, cmd: &Command) -> Isometry3<f64> {
        Isometry3::from_parts(
            (cmd.frame.translation.vector - state.tool.translation.vector).into(),
            cmd.frame.rotation,
        )
    }

    /// The speed limit's brake on force-controlled translations (returned) and the integral's
    /// update, in compliant-frame coordinates: twist `twist_cf`, force error `e_f_cf`, desired
    /// wrench `desired_cf`.
    fn brake_and_integrate(
        gains: &ControllerGains,
        cmd: &Command,
        twist_cf: &Vector6<f64>,
        e_f_cf: &Vector6<f64>,
        desired_cf: &Vector6<f64>,
        integral_cf: &mut Vector6<f64>,
        dt: f64,
    ) -> Vector6<f64> {
        // Speed limit on force-controlled translations, in the compliant frame, following the
        // force each still misses.
        let mut brake_cf = Vector6::zeros();
        for axis in 0..3 {
            let excess = twist_cf[axis].abs() - gains.force_axis_speed_limit(e_f_cf[axis], desired_cf[axis]);
            if !cmd.position[axis] && excess > 0.0 {
                brake_cf[axis] = -gains.force_axis_brake * excess * twist_cf[axis].signum();
            }
        }

        // The saturated integral, kept in compliant-frame coordinates. An axis held at its speed
        // limit does not integrate (the force it has not reached yet would wind the integral up
        // and push through the limit).
        for axis in 0..6 {
            if cmd.position[axis] {
                integral_cf[axis] = 0.0;
            } else if brake_cf[axis] != 0.0 {
                continue;
            } else {
                let mut value = integral_cf[axis] + e_f_cf[axis] * dt;
                if let Some(limit) = cmd.integral_limit {
                    // The integral term is k_i ∫: clamp the term, not the raw integral.
                    if cmd.ki > 0.0 {
                        let bound = limit / cmd.ki;
                        value = value.clamp(-bound, bound);
                    }
                }
                integral_cf[axis] = value;
            }
        }
        brake_cf
    }

    /// Joint torques for this tick (after [`HybridController::observe`] on the same observation).
    pub fn torques(&mut self, obs: &Observation, cmd: &Command, dt: f64) -> &[f64] {
        let wrench = Self::cartesian_wrench(&self.gains, &self.state, cmd, &mut self.integral_cf, dt);
        self.robot.gravity_torques(&mut self.data, self.gravity.as_mut_slice());
        self.task_torques.gemv_tr(1.0, &self.jacobian, &wrench, 0.0);

        // Null space: N = I − Jᵀ (J Jᵀ + λ² I)⁻¹ J applied to the posture torque.
        for i in 0..self.posture.len() {
            self.posture[i] = -self.gains.nullspace_stiffness * (obs.q[i] - self.q_rest[i])
                - self.gains.nullspace_damping * obs.qd[i];
        }
        // Without temporaries (no allocation per tick): J Jᵀ column by column, the projection in place.
        let mut jjt = Matrix6::identity() * 1e-6;
        let mut j_posture = Vector6::zeros();
        for (column, posture) in self.jacobian.column_iter().zip(self.posture.iter()) {
            jjt += column * column.transpose();
            j_posture += column * *posture;
        }
        if let Some(chol) = jjt.cholesky() {
            let solved = chol.solve(&j_posture);
            self.posture.gemv_tr(-1.0, &self.jacobian, &solved, 1.0);
        }
        let projected = &self.posture;

        for (i, joint) in self.robot.joints().iter().enumerate() {
            let mut tau = self.task_torques[i] + self.gravity[i] + projected[i];
            let limit = joint.velocity * self.gains.velocity_limit_fraction;
            let excess = obs.qd[i].abs() - limit;
            if joint.velocity.is_finite() && excess > 0.0 {
                tau -= self.gains.velocity_brake_gain * excess * obs.qd[i].signum();
            }
            self.torques[i] = if tau.is_finite() {
                tau.clamp(-joint.effort, joint.effort)
            } else {
                0.0
            };
        }
        self.torques.as_slice()
    }
}

/// The rotation vector of `desired · current⁻¹` taking the shorter way round.
fn rotation_error(desired: &UnitQuaternion<f64>, current: &UnitQuaternion<f64>) -> Vector3<f64> {
    let mut error = desired * current.inverse();
    if error.w < 0.0 {
        error = UnitQuaternion::new_unchecked(-error.into_inner());
    }
    error.scaled_axis()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Translation3;

    /// Each arm's wrist bounds its rotational damping: the LWR-IV keeps the 0.4 N m s/rad it
    /// was tuned with, the FR3, whose wrist is about three times lighter, gets about 0.12.
    #[test]
    fn the_rotational_damping_stays_under_each_wrists_stability_bound() {
        let damping = |robot: skill_robot::BuiltinRobot, q: &[f64]| {
            let model = robot.load().expect("shipped robot");
            let controller =
                HybridController::new(model, robot.sensor, q, ControllerGains::default()).expect("controller");
            (
                controller.gains().max_rotational_damping,
                controller.gains().force_axis_rotational_damping,
            )
        };
        let defaults = ControllerGains::default();
        let lwr = damping(skill_robot::LWR4, &skill_robot::LWR4_ELBOW_UP);
        assert_eq!(
            lwr,
            (defaults.max_rotational_damping, defaults.force_axis_rotational_damping)
        );
        // The FR3 at its scenes' start (joint 4 bent, joint 6 at 2 rad).
        let fr3 = damping(skill_robot::FR3, &[0.0, -0.5, 0.0, -2.0, 0.0, 2.0, 0.0]);
        assert!(fr3.0 > 0.08 && fr3.0 < 0.16, "{fr3:?}");
        assert!(fr3.1 <= fr3.0, "{fr3:?}");
    }

    fn state_at(tool: Isometry3<f64>, applied: Vector6<f64>) -> ControlState {
        ControlState {
            tool,
            twist: Vector6::zeros(),
            applied,
        }
    }

    fn command(frame: Isometry3<f64>, position: [bool; 6]) -> Command {
        Command {
            pose: Isometry3::from_parts(
                Translation3::new(0.5, 0.1, 0.3),
                UnitQuaternion::from_euler_angles(3.0, 0.1, 0.2),
            ),
            twist: Vector6::zeros(),
            wrench: Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            force_twist: Vector6::zeros(),
            frame,
            position,
            stiffness: [2000.0, 1500.0, 1000.0, 150.0, 120.0, 100.0],
            kp: 0.5,
            ki: 5.0,
            integral_limit: Some(10.0),
        }
    }

    /// The law in its operator form (docs/method.md §6), term by term with 6×6 matrices: the
    /// reference for [`HybridController::cartesian_wrench`], which runs it in the compliant frame
    /// (the per-axis brake and integral rules are the law's own).
    fn operator_form(
        gains: &ControllerGains,
        state: &ControlState,
        cmd: &Command,
        integral_cf: &mut Vector6<f64>,
        dt: f64,
    ) -> Vector6<f64> {
        let frame_in_control = HybridController::frame_in_control(state, cmd);
        let (omega, omega_tilde) = adjoint::operators(&frame_in_control, &cmd.position, &cmd.stiffness);
        let ad = adjoint::adjoint(&frame_in_control);
        let ad_inv = adjoint::adjoint_inverse(&frame_in_control);
        let (adg, adg_inv) = (ad_inv.transpose(), ad.transpose());
        let mut e_p = Vector6::zeros();
        e_p.fixed_rows_mut::<3>(0)
            .copy_from(&(cmd.pose.translation.vector - state.tool.translation.vector));
        e_p.fixed_rows_mut::<3>(3)
            .copy_from(&rotation_error(&cmd.pose.rotation, &state.tool.rotation));
        let (mut d_cf, mut select) = (Matrix6::zeros(), Matrix6::zeros());
        for axis in 0..6 {
            let rotation = axis >= 3;
            d_cf[(axis, axis)] = match (cmd.position[axis], rotation) {
                (true, false) => 2.0 * gains.damping_ratio * (cmd.stiffness[axis] * gains.effective_mass_kg).sqrt(),
                (true, true) => {
                    (2.0 * gains.damping_ratio * (cmd.stiffness[axis] * gains.effective_inertia_kgm2).sqrt())
                        .min(gains.max_rotational_damping)
                }
                (false, false) => gains.force_axis_damping,
                (false, true) => gains.force_axis_rotational_damping,
            };
            select[(axis, axis)] = if cmd.position[axis] { 1.0 } else { 0.0 };
        }
        let damping = adg * d_cf * ad_inv;
        let twist_selected = ad * select * ad_inv * cmd.twist;
        let force_twist_selected = ad * (Matrix6::identity() - select) * ad_inv * cmd.force_twist;
        let e_f = cmd.wrench - state.applied;
        let (e_f_cf, twist_cf, desired_cf) = (adg_inv * e_f, ad_inv * state.twist, adg_inv * cmd.wrench);
        // The brake and the integral are per-axis rules in the compliant frame, shared.
        let brake_cf =
            HybridController::brake_and_integrate(gains, cmd, &twist_cf, &e_f_cf, &desired_cf, integral_cf, dt);
        omega * e_p - damping * (state.twist - twist_selected - force_twist_selected)
            + omega_tilde * cmd.wrench
            + omega_tilde * e_f * cmd.kp
            + adg * (*integral_cf * cmd.ki)
            + adg * brake_cf
    }

    #[test]
    fn a_force_axis_does_not_damp_the_travel_its_force_twist_asks_for() {
        let gains = ControllerGains::default();
        // Pressing down (compliant z along −z of the base) at 5 N with 4 N applied, moving
        // down at 10 mm/s.
        let frame = Isometry3::from_parts(
            Translation3::new(0.5, 0.0, 0.3),
            UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0),
        );
        let mut cmd = command(frame, [true, true, false, true, true, true]);
        cmd.pose = frame;
        cmd.wrench = Vector6::new(0.0, 0.0, -5.0, 0.0, 0.0, 0.0);
        cmd.ki = 0.0;
        let mut state = state_at(frame, Vector6::new(0.0, 0.0, -4.0, 0.0, 0.0, 0.0));
        state.twist = Vector6::new(0.0, 0.0, -0.01, 0.0, 0.0, 0.0);
        let along_z = |cmd: &Command| {
            let mut integral = Vector6::zeros();
            -HybridController::cartesian_wrench(&gains, &state, cmd, &mut integral, 1e-3)[2]
        };
        // Damped: 5 + 0.5 · 1 − 40 · 0.01 = 5.1 N.
        let damped = along_z(&cmd);
        assert!(
            (damped - (5.0 + 0.5 - gains.force_axis_damping * 0.01)).abs() < 1e-9,
            "{damped}"
        );
        // Asked to travel at what it travels at: no damping, 5.5 N.
        cmd.force_twist = state.twist;
        assert!((along_z(&cmd) - 5.5).abs() < 1e-9, "{}", along_z(&cmd));
        // A force twist along a position-controlled axis changes nothing there.
        cmd.force_twist = Vector6::new(0.3, 0.0, -0.01, 0.0, 0.0, 0.0);
        let mut integral = Vector6::zeros();
        let sideways = HybridController::cartesian_wrench(&gains, &state, &cmd, &mut integral, 1e-3)[0];
        cmd.force_twist = state.twist;
        let mut integral = Vector6::zeros();
        let plain = HybridController::cartesian_wrench(&gains, &state, &cmd, &mut integral, 1e-3)[0];
        assert_eq!(sideways, plain);
    }

    #[test]
    fn matches_the_operator_form() {
        // A deterministic spread of frames, poses, twists, wrenches and selections, with the
        // speed limit engaged on some force axes and the integral saturated on others.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let gains = ControllerGains::default();
        let mut braked = 0;
        for case in 0..200 {
            let mut vec6 = |scale: f64| Vector6::from_fn(|_, _| scale * next());
            let (twist, cmd_twist) = (vec6(0.3), vec6(0.2));
            let (applied, wrench) = (vec6(30.0), vec6(20.0));
            let force_twist = vec6(0.02);
            let mut pose = |offset: f64| {
                Isometry3::from_parts(
                    Translation3::new(0.5 + 0.1 * next(), 0.1 * next(), offset + 0.1 * next()),
                    UnitQuaternion::from_euler_angles(3.0 * next(), 1.5 * next(), 3.0 * next()),
                )
            };
            let (tool, frame, goal) = (pose(0.3), pose(0.25), pose(0.3));
            let position: [bool; 6] = std::array::from_fn(|axis| (case >> axis) & 1 == 1);
            let mut cmd = command(frame, position);
            cmd.pose = goal;
            cmd.twist = cmd_twist;
            cmd.wrench = wrench;
            cmd.force_twist = force_twist;
            let state = ControlState { tool, twist, applied };
            let start = Vector6::from_fn(|_, _| 3.0 * next());
            let (mut fast_integral, mut reference_integral) = (start, start);
            let fast = HybridController::cartesian_wrench(&gains, &state, &cmd, &mut fast_integral, 0.01);
            let reference = operator_form(&gains, &state, &cmd, &mut reference_integral, 0.01);
            assert!(
                (fast - reference).norm() < 1e-10 * (1.0 + reference.norm()),
                "case {case}: {fast} against {reference}"
            );
            assert!((fast_integral - reference_integral).norm() < 1e-12 * (1.0 + reference_integral.norm()));
            braked += usize::from(fast_integral.iter().zip(&start).any(|(x, y)| x == y) && position.contains(&false));
        }
        assert!(braked > 0, "no case held an axis at its speed limit");
    }

    #[test]
    fn all_position_is_plain_impedance_control() {
        let gains = ControllerGains::default();
        let tool = Isometry3::from_parts(
            Translation3::new(0.49, 0.12, 0.31),
            UnitQuaternion::from_euler_angles(3.0, 0.12, 0.2),
        );
        // The compliant frame at the control point, unrotated: Ω is K and Ω̃ vanishes.
        let frame = Isometry3::from_parts(tool.translation, UnitQuaternion::identity());
        let cmd = Command {
            stiffness: [1000.0, 1000.0, 1000.0, 100.0, 100.0, 100.0],
            ..command(frame, [true; 6])
        };
        let mut integral = Vector6::zeros();
        let wrench = HybridController::cartesian_wrench(
            &gains,
            &state_at(tool, Vector6::new(5.0, 0.0, 3.0, 0.0, 0.0, 0.0)),
            &cmd,
            &mut integral,
            0.001,
        );
        let expected_force = (cmd.pose.translation.vector - tool.translation.vector) * 1000.0;
        let expected_moment = rotation_error(&cmd.pose.rotation, &tool.rotation) * 100.0;
        assert!((wrench.fixed_rows::<3>(0) - expected_force).norm() < 1e-9, "{wrench}");
        assert!((wrench.fixed_rows::<3>(3) - expected_moment).norm() < 1e-9, "{wrench}");
        assert_eq!(
            integral,
            Vector6::zeros(),
            "measured forces are ignored on position axes"
        );
    }

    #[test]
    fn force_axis_pushes_along_the_frame_z_with_the_sign_of_the_applied_force() {
        // A surface frame with z pointing down (into a table below the tool).
        let frame = Isometry3::from_parts(
            Translation3::new(0.5, 0.1, 0.3),
            UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0),
        );
        let tool = Isometry3::from_parts(
            Translation3::new(0.5, 0.1, 0.3),
            UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0),
        );
        let mut cmd = command(frame, [true, true, false, true, true, true]);
        cmd.pose = tool;
        // Desired: press down with 10 N (applied force along frame z = −base z).
        cmd.wrench = Vector6::new(0.0, 0.0, -10.0, 0.0, 0.0, 0.0);
        let gains = ControllerGains::default();
        let mut integral = Vector6::zeros();
        // Not in contact yet: the measured applied force is zero.
        let wrench =
            HybridController::cartesian_wrench(&gains, &state_at(tool, Vector6::zeros()), &cmd, &mut integral, 0.001);
        assert!(
            wrench[2] < -10.0,
            "commands more than the feed-forward downwards: {wrench}"
        );
        assert!(wrench.fixed_rows::<2>(0).norm() < 1e-9);
        // In contact with exactly the desired force: feed-forward only, no error.
        let mut integral = Vector6::zeros();
        let wrench =
            HybridController::cartesian_wrench(&gains, &state_at(tool, cmd.wrench), &cmd, &mut integral, 0.001);
        assert!((wrench[2] + 10.0).abs() < 1e-9, "{wrench}");
        assert!(integral.norm() < 1e-12);
    }

    #[test]
    fn the_force_axis_speed_limit_is_the_speed_whose_impact_adds_the_larger_force() {
        let gains = ControllerGains {
            force_axis_mass_kg: Some(3.2),
            ..ControllerGains::default()
        };
        // √(5e4 N/m · 3.2 kg) = 400 N s/m.
        let at = |error: f64, desired: f64| gains.force_axis_speed_limit(error, desired);
        assert!(
            (at(0.0, 0.0) - 5.0 / 400.0).abs() < 1e-12,
            "the impact floor: 12.5 mm/s"
        );
        assert!((at(-0.4, 2.0) - 5.0 / 400.0).abs() < 1e-12);
        assert!((at(1.0, 8.0) - 8.0 / 400.0).abs() < 1e-12, "the desired force: 20 mm/s");
        assert!(
            (at(-7.0, 4.0) - 7.0 / 400.0).abs() < 1e-12,
            "the missing force, either sign"
        );
        assert_eq!(at(30.0, 0.0), gains.force_axis_speed_mps, "capped");
        assert!((at(f64::NAN, 0.0) - 5.0 / 400.0).abs() < 1e-12, "no reading: the floor");
        // Without a mass of its own it uses the nominal one.
        let nominal = ControllerGains::default();
        let expected = 5.0 / (5.0e4 * nominal.effective_mass_kg).sqrt();
        assert!((nominal.force_axis_speed_limit(0.0, 0.0) - expected).abs() < 1e-12);
    }

    #[test]
    fn a_force_axis_brakes_above_its_limit_and_not_below() {
        // Force control along base z with 8 N desired and 6 N applied: limit max(2, 8, 5) N /
        // 400 N s/m = 20 mm/s.
        let gains = ControllerGains {
            force_axis_mass_kg: Some(3.2),
            ..ControllerGains::default()
        };
        let mut cmd = command(Isometry3::identity(), [true, true, false, true, true, true]);
        cmd.wrench = Vector6::new(0.0, 0.0, 8.0, 0.0, 0.0, 0.0);
        let applied = Vector6::new(0.0, 0.0, 6.0, 0.0, 0.0, 0.0);
        let wrench_at = |speed: f64| {
            let mut state = state_at(cmd.pose, applied);
            state.twist[2] = speed;
            let mut integral = Vector6::zeros();
            HybridController::cartesian_wrench(&gains, &state, &cmd, &mut integral, 0.001)[2]
        };
        let (slow, fast) = (wrench_at(0.019), wrench_at(0.030));
        // Below the limit: feed-forward, P term and the axis damping only.
        let expected_slow = 8.0 + 2.0 * cmd.kp - gains.force_axis_damping * 0.019 + 2.0 * 0.001 * cmd.ki;
        assert!((slow - expected_slow).abs() < 1e-9, "{slow} vs {expected_slow}");
        // Above it the brake adds −2000 N s/m · (30 − 20) mm/s = −20 N (the integral holds).
        let expected_fast = 8.0 + 2.0 * cmd.kp - gains.force_axis_damping * 0.030 - gains.force_axis_brake * 0.010;
        assert!((fast - expected_fast).abs() < 1e-9, "{fast} vs {expected_fast}");
    }

    #[test]
    fn the_integral_saturates() {
        let frame = Isometry3::identity();
        let mut cmd = command(frame, [true, true, false, true, true, true]);
        cmd.wrench = Vector6::new(0.0, 0.0, 20.0, 0.0, 0.0, 0.0);
        let gains = ControllerGains::default();
        let tool = cmd.pose;
        let mut integral = Vector6::zeros();
        for _ in 0..1_000 {
            HybridController::cartesian_wrench(&gains, &state_at(tool, Vector6::zeros()), &cmd, &mut integral, 0.001);
        }
        assert!(
            (integral[2] * cmd.ki - 10.0).abs() < 1e-9,
            "k_i ∫ is clamped at the limit: {}",
            integral[2] * cmd.ki
        );
    }

    #[test]
    fn the_law_is_invariant_under_a_rigid_motion_of_the_whole_scene() {
        let gains = ControllerGains::default();
        let frame = Isometry3::from_parts(
            Translation3::new(0.52, 0.08, 0.25),
            UnitQuaternion::from_euler_angles(2.9, 0.2, -0.4),
        );
        let tool = Isometry3::from_parts(
            Translation3::new(0.49, 0.12, 0.31),
            UnitQuaternion::from_euler_angles(3.0, 0.12, 0.2),
        );
        let mut cmd = command(frame, [true, false, false, true, true, false]);
        cmd.twist = Vector6::new(0.01, -0.02, 0.03, 0.1, 0.0, -0.1);
        cmd.wrench = Vector6::new(1.0, 2.0, -8.0, 0.1, 0.0, 0.3);
        let state = ControlState {
            tool,
            twist: Vector6::new(0.02, 0.01, -0.01, 0.05, -0.1, 0.2),
            applied: Vector6::new(0.5, 1.0, -6.0, 0.0, 0.05, 0.1),
        };
        let mut integral = Vector6::zeros();
        let wrench = HybridController::cartesian_wrench(&gains, &state, &cmd, &mut integral, 0.001);

        let motion = Isometry3::from_parts(
            Translation3::new(-1.0, 2.0, 0.5),
            UnitQuaternion::from_euler_angles(0.7, -0.3, 1.9),
        );
        let rot = motion.rotation;
        let spin = |v: &Vector6<f64>| {
            let mut out = Vector6::zeros();
            out.fixed_rows_mut::<3>(0).copy_from(&(rot * v.fixed_rows::<3>(0)));
            out.fixed_rows_mut::<3>(3).copy_from(&(rot * v.fixed_rows::<3>(3)));
            out
        };
        let moved_cmd = Command {
            pose: motion * cmd.pose,
            frame: motion * cmd.frame,
            twist: spin(&cmd.twist),
            wrench: spin(&cmd.wrench),
            ..cmd.clone()
        };
        let moved_state = ControlState {
            tool: motion * state.tool,
            twist: spin(&state.twist),
            applied: spin(&state.applied),
        };
        let mut moved_integral = Vector6::zeros();
        let moved = HybridController::cartesian_wrench(&gains, &moved_state, &moved_cmd, &mut moved_integral, 0.001);
        assert!((moved - spin(&wrench)).norm() < 1e-9, "{moved} vs {}", spin(&wrench));
        assert!(
            (moved_integral - integral).norm() < 1e-12,
            "the integral lives in the compliant frame"
        );
    }

    #[test]
    fn damping_opposes_velocity_on_every_axis() {
        let gains = ControllerGains::default();
        let tool = Isometry3::identity();
        let cmd = Command {
            pose: tool,
            ..command(Isometry3::identity(), [true, true, false, true, false, true])
        };
        for axis in 0..6 {
            let mut twist = Vector6::zeros();
            twist[axis] = 0.1;
            let mut integral = Vector6::zeros();
            let state = ControlState {
                tool,
                twist,
                applied: Vector6::zeros(),
            };
            let wrench = HybridController::cartesian_wrench(&gains, &state, &cmd, &mut integral, 0.001);
            assert!(wrench[axis] < 0.0, "axis {axis}: {wrench}");
        }
    }
}

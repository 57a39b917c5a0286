//! The `Plant` interface the controller drives (simulated or real arm), and a model-based test plant.
//!
//! Sign convention (docs/method.md §1, everywhere in skillc): the wrench a plant reports is the force and moment
//! the **environment exerts on the tool**. The force the robot applies to the environment is its negative.

use nalgebra::{DMatrix, DVector, Matrix6xX, Vector3, Vector6};

use crate::{Robot, RobotData, RobotError};

/// What the controller sees each tick, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Plant time, s.
    pub t: f64,
    /// Joint positions, rad (m for prismatic joints).
    pub q: DVector<f64>,
    /// Joint velocities, rad/s.
    pub qd: DVector<f64>,
    /// Wrist sensor wrench `[fx fy fz mx my mz]` (N, N m) about the sensor origin, in the sensor frame.
    pub wrench_sensor: Vector6<f64>,
    /// The same wrench about the sensor origin, in base-frame axes.
    pub wrench_base: Vector6<f64>,
    /// The largest contact force on a link of the arm the wrist sensor does not measure (any
    /// link before the sensor: the upper arm, the elbow, the wrist) \[N\], 0 without such
    /// contact. Skills touch the world with the tool only, so any such force is a collision.
    ///
    /// The simulation sums the solver's contact forces per link. A real arm fills it from its
    /// external-torque estimate (the LWR-IV's joint torque sensors minus the model's torques, as
    /// KUKA's FRI reports them): the residual `τ_ext − Jᵀ w` that the wrist sensor's wrench `w`
    /// does not explain comes from contact elsewhere; the most distal joint with a residual above
    /// the estimate's noise bounds the link (the one after it), and the residual over the lever
    /// from that joint to the link's far end bounds the force from below.
    pub arm_contact_n: f64,
    /// The link [`Observation::arm_contact_n`] acts on, as an index into
    /// [`crate::Robot::links`]; `None` without such contact (or when a plant cannot tell).
    pub arm_contact_link: Option<usize>,
}

impl Observation {
    /// An all-zero observation for `dof` joints (allocate once, then fill with [`Plant::observe_into`]).
    pub fn zeros(dof: usize) -> Self {
        Observation {
            t: 0.0,
            q: DVector::zeros(dof),
            qd: DVector::zeros(dof),
            wrench_sensor: Vector6::zeros(),
            wrench_base: Vector6::zeros(),
            arm_contact_n: 0.0,
            arm_contact_link: None,
        }
    }
}

/// Why a plant could not step.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlantError {
    /// The state became NaN or infinite.
    #[error("plant state is not finite at t = {t} s (joint `{joint}`)")]
    NonFinite {
        /// Plant time when it was noticed.
        t: f64,
        /// The first joint with a non-finite state.
        joint: String,
    },
    /// The link to a plant in another process failed (it fell silent, or sent what cannot be read).
    #[error("the link to the plant failed at t = {t:.3} s: {reason}")]
    Link {
        /// Plant time of the last state received.
        t: f64,
        /// What happened.
        reason: String,
    },
    /// A torque vector of the wrong length.
    #[error("expected {expected} joint torques, got {got}")]
    WrongDof {
        /// The plant's number of joints.
        expected: usize,
        /// What was given.
        got: usize,
    },
}

/// A torque-controlled arm with a wrist force/torque sensor: the rapier simulation, the model-based
/// [`KinematicPlant`], or later a real robot. The controller only talks to this trait.
pub trait Plant {
    /// Number of joints.
    fn dof(&self) -> usize;

    /// Current plant time, s.
    fn time(&self) -> f64;

    /// Writes the current state into `out` without allocating.
    fn observe_into(&self, out: &mut Observation);

    /// The current state (allocates; use [`Plant::observe_into`] in a loop).
    fn observe(&self) -> Observation {
        let mut out = Observation::zeros(self.dof());
        self.observe_into(&mut out);
        out
    }

    /// Commands joint torques (N m), held until the next call. Plants saturate them at the joint's
    /// effort limit, as a real drive does.
    fn apply(&mut self, torques: &[f64]) -> Result<(), PlantError>;

    /// Advances the plant by `dt` seconds (1 ms in skillc).
    fn step(&mut self, dt: f64) -> Result<(), PlantError>;

    /// The supervisor is bringing the arm to its damped stop ([`crate::Robot::damped_stop_torques`]).
    /// A plant that can hold that stop by itself, at its own rate and without a link's delay in
    /// the loop (a plant in another process), does so from now until the run ends, ignoring the
    /// torques applied, and returns `true`; a plant in this process returns `false` and goes on
    /// taking the supervisor's torques.
    fn hold_damped_stop(&mut self) -> bool {
        false
    }

    /// What the plant's contact witness found since the last call (and starts it afresh): a
    /// simulation checks every step's contact force on the tool against the analytic distance
    /// between the tool and the scene's shapes. `None` for plants without one (a real arm, the
    /// model-based test plant); a plant across a link asks the simulation on its other side.
    fn take_contact_audit(&mut self) -> Option<ContactAudit> {
        None
    }

    /// Calls `visit` with each of the scene's moving parts, by its object's name, and how far
    /// it has moved from its rest along its own axis, m: a button's cap and how deep it is
    /// pressed in (0 at rest). Without allocating; plants without moving parts (a real arm,
    /// the model-based test plant) call it for none, and a plant across a link for those its
    /// last state named.
    fn visit_parts(&self, visit: &mut dyn FnMut(&str, f64)) {
        let _ = visit;
    }
}

/// A simulation's contact force checked against its geometry, tick by tick (docs/method.md §7):
/// a force on the tool only where the tool is within [`ContactAudit::FORCE_FREE_BEYOND_M`] of an
/// object, and never deeper into one than the contact's compliance explains
/// (`|F| / k` plus [`ContactAudit::DEPTH_SLACK_M`]).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactAudit {
    /// Steps checked.
    pub ticks: u64,
    /// Steps with a force on the tool above [`ContactAudit::FORCE_N`].
    pub touching_ticks: u64,
    /// Steps with a force while the tool was farther than [`ContactAudit::FORCE_FREE_BEYOND_M`]
    /// from every object.
    pub far_ticks: u64,
    /// The largest such force.
    pub far_force: Option<ContactFinding>,
    /// Steps in which the tool was deeper in an object than its compliance explains.
    pub deep_ticks: u64,
    /// The deepest such step (the largest depth beyond what the force explains).
    pub too_deep: Option<ContactFinding>,
    /// The deepest the tool went into any object, m (0 if it never did).
    pub max_depth_m: f64,
    /// The largest force on the tool, N.
    pub max_force_n: f64,
}

/// One step the witness names.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactFinding {
    /// Plant time, s.
    pub t_s: f64,
    /// The force on the tool, N (noise-free).
    pub force_n: f64,
    /// The tool's distance to the nearest object, m (negative inside it).
    pub gap_m: f64,
    /// What the force explains: the depth `|F| / k` plus the slack, m (for depth findings).
    pub allowed_m: f64,
    /// The nearest object's name.
    pub object: String,
    /// The tool point (the tool link's origin) then, base frame, m.
    pub tool_m: [f64; 3],
}

impl ContactAudit {
    /// A force below this is no force, N.
    pub const FORCE_N: f64 = 0.01;
    /// Farther than this from every object, the tool feels no force, m.
    pub const FORCE_FREE_BEYOND_M: f64 = 1e-3;
    /// Depth allowed beyond what the contact's compliance explains, m.
    pub const DEPTH_SLACK_M: f64 = 1e-3;

    /// Whether the contacts broke either rule.
    pub fn violated(&self) -> bool {
        self.far_ticks > 0 || self.deep_ticks > 0
    }

    /// Adds `other` (a later stretch of the same run).
    pub fn merge(&mut self, other: ContactAudit) {
        let larger =
            |a: Option<ContactFinding>, b: Option<ContactFinding>, key: fn(&ContactFinding) -> f64| match (a, b) {
                (Some(a), Some(b)) => Some(if key(&b) > key(&a) { b } else { a }),
                (a, b) => a.or(b),
            };
        self.ticks += other.ticks;
        self.touching_ticks += other.touching_ticks;
        self.far_ticks += other.far_ticks;
        self.deep_ticks += other.deep_ticks;
        self.far_force = larger(self.far_force.take(), other.far_force, |f| f.force_n);
        self.too_deep = larger(self.too_deep.take(), other.too_deep, |f| -f.gap_m - f.allowed_m);
        self.max_depth_m = self.max_depth_m.max(other.max_depth_m);
        self.max_force_n = self.max_force_n.max(other.max_force_n);
    }

    /// One line for a run's output: what was checked and what broke.
    pub fn summary(&self) -> String {
        let mut text = format!(
            "contact witness: {} steps checked, {} in contact (peak {:.1} N, deepest {:.2} mm)",
            self.ticks,
            self.touching_ticks,
            self.max_force_n,
            self.max_depth_m * 1e3
        );
        if let Some(far) = &self.far_force {
            text += &format!(
                "; {} steps with force away from every object, worst {:.2} N at t = {:.3} s with the tool {:.1} mm from `{}`",
                self.far_ticks,
                far.force_n,
                far.t_s,
                far.gap_m * 1e3,
                far.object
            );
        }
        if let Some(deep) = &self.too_deep {
            text += &format!(
                "; {} steps deeper than the compliance explains, worst {:.2} mm into `{}` at t = {:.3} s under {:.1} N (allowed {:.2} mm)",
                self.deep_ticks,
                -deep.gap_m * 1e3,
                deep.object,
                deep.t_s,
                deep.force_n,
                deep.allowed_m * 1e3
            );
        }
        text
    }
}

/// Saturates `torques` at ±effort per joint, writing into `out`.
pub fn saturate(robot: &Robot, torques: &[f64], out: &mut [f64]) -> Result<(), PlantError> {
    if torques.len() != robot.dof() {
        return Err(PlantError::WrongDof {
            expected: robot.dof(),
            got: torques.len(),
        });
    }
    for ((slot, tau), joint) in out.iter_mut().zip(torques).zip(robot.joints()) {
        *slot = if tau.is_nan() {
            0.0
        } else {
            tau.clamp(-joint.effort, joint.effort)
        };
    }
    Ok(())
}

/// A fast plant for tests: the robot model's own rigid-body dynamics (q̈ = M⁻¹(τ + Jᵀw − C q̇ − g),
/// semi-implicit Euler, joint position limits as hard stops), with the environment's wrench on the
/// tool scripted by the test instead of simulated contacts. No rapier involved.
#[derive(Debug, Clone)]
pub struct KinematicPlant {
    robot: Robot,
    data: RobotData,
    sensor_link: usize,
    t: f64,
    q: DVector<f64>,
    qd: DVector<f64>,
    torque: Vec<f64>,
    /// Wrench the environment exerts on the tool, at the tool point, base axes.
    wrench_at_tool: Vector6<f64>,
    mass: DMatrix<f64>,
    bias: Vec<f64>,
    jacobian: Matrix6xX<f64>,
    rhs: DVector<f64>,
}

impl KinematicPlant {
    /// A plant at rest at `q0`, its sensor at link `sensor_link`.
    pub fn new(robot: Robot, sensor_link: &str, q0: &[f64]) -> Result<Self, RobotError> {
        robot.check_dof(q0.len())?;
        let sensor_link = robot.require_link(sensor_link)?;
        let n = robot.dof();
        Ok(KinematicPlant {
            data: robot.data(),
            robot,
            sensor_link,
            t: 0.0,
            q: DVector::from_column_slice(q0),
            qd: DVector::zeros(n),
            torque: vec![0.0; n],
            wrench_at_tool: Vector6::zeros(),
            mass: DMatrix::zeros(n, n),
            bias: vec![0.0; n],
            jacobian: Matrix6xX::zeros(n),
            rhs: DVector::zeros(n),
        })
    }

    /// Scripts the wrench the environment exerts on the tool (at the tool link origin, base axes),
    /// felt by the dynamics and reported by the sensor until changed.
    pub fn set_tool_wrench(&mut self, wrench_at_tool_base: Vector6<f64>) {
        self.wrench_at_tool = wrench_at_tool_base;
    }

    /// The robot model the plant integrates.
    pub fn robot(&self) -> &Robot {
        &self.robot
    }
}

impl Plant for KinematicPlant {
    fn dof(&self) -> usize {
        self.robot.dof()
    }

    fn time(&self) -> f64 {
        self.t
    }

    fn observe_into(&self, out: &mut Observation) {
        out.t = self.t;
        out.q.copy_from(&self.q);
        out.qd.copy_from(&self.qd);
        // Move the wrench from the tool point to the sensor origin: m_s = m + (p_tool − p_s) × f.
        let mut data = self.data.clone();
        self.robot.forward_kinematics(&mut data, self.q.as_slice());
        let tool = self.robot.link_in_base_matrix(&data, self.robot.tool_link());
        let sensor = self.robot.link_in_base_matrix(&data, self.sensor_link);
        let force: Vector3<f64> = self.wrench_at_tool.fixed_rows::<3>(0).into();
        let moment: Vector3<f64> = self.wrench_at_tool.fixed_rows::<3>(3).into();
        let lever = tool.translation.vector - sensor.translation.vector;
        let moment_sensor = moment + lever.cross(&force);
        out.wrench_base = Vector6::new(
            force.x,
            force.y,
            force.z,
            moment_sensor.x,
            moment_sensor.y,
            moment_sensor.z,
        );
        let rot_t = sensor.rotation.inverse();
        let f_s = rot_t * force;
        let m_s = rot_t * moment_sensor;
        out.wrench_sensor = Vector6::new(f_s.x, f_s.y, f_s.z, m_s.x, m_s.y, m_s.z);
        // Only the tool meets the scripted environment.
        out.arm_contact_n = 0.0;
        out.arm_contact_link = None;
    }

    fn apply(&mut self, torques: &[f64]) -> Result<(), PlantError> {
        saturate(&self.robot, torques, &mut self.torque)
    }

    fn step(&mut self, dt: f64) -> Result<(), PlantError> {
        let robot = &self.robot;
        robot.forward_kinematics(&mut self.data, self.q.as_slice());
        robot.mass_matrix(&mut self.data, &mut self.mass);
        robot.inverse_dynamics(
            &mut self.data,
            self.qd.as_slice(),
            &vec![0.0; robot.dof()],
            &mut self.bias,
        );
        robot.tool_jacobian(&self.data, &mut self.jacobian);
        let external = self.jacobian.transpose() * self.wrench_at_tool;
        for idx in 0..robot.dof() {
            self.rhs[idx] = self.torque[idx] + external[idx] - self.bias[idx];
        }
        let qdd = self
            .mass
            .clone()
            .cholesky()
            .map(|chol| chol.solve(&self.rhs))
            .unwrap_or_else(|| DVector::from_element(robot.dof(), f64::NAN));
        self.qd += qdd * dt;
        for (idx, joint) in robot.joints().iter().enumerate() {
            let next = self.q[idx] + self.qd[idx] * dt;
            self.q[idx] = next.clamp(joint.lower, joint.upper);
            if self.q[idx] != next {
                self.qd[idx] = 0.0;
            }
            if !self.q[idx].is_finite() || !self.qd[idx].is_finite() {
                return Err(PlantError::NonFinite {
                    t: self.t,
                    joint: joint.name.clone(),
                });
            }
        }
        self.t += dt;
        Ok(())
    }
}

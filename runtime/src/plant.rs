//! The `Plant` interface the controller drives (simulated or real arm), and a model-based test plant.
//!
//! Sign convention (docs/method.md §1, everywhere in skillc): the wrench a plant reports is the force and moment
//! the **environment exerts on the tool**. The force the robot applies to the environment is its negative.

use nalgebra::{DMatrix, DVector, Matrix6xX, Vector3, Vector6};

use crate::robot::{Robot, RobotData, RobotError};

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
    /// [`crate::robot::Robot::links`]; `None` without such contact (or when a plant cannot tell).
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
}

/// Saturates `torques` at ±effort per joint, writing into `out`.
pub(crate) fn saturate(robot: &Robot, torques: &[f64], out: &mut [f64]) -> Result<(), PlantError> {
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

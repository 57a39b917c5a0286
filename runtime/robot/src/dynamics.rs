//! Rigid-body dynamics of the chain: recursive Newton-Euler (inverse dynamics, Coriolis), gravity
//! torques from composite centres of mass, and the composite-rigid-body mass matrix.

use nalgebra::{DMatrix, Matrix3, Vector3};

use super::{JointKind, Robot, RobotData};

/// The time constant of the damped stop \[s\]: the stop decelerates the joints as
/// `q̈ = −q̇ / T` through the arm's own mass matrix, so a joint at 1 rad/s is at 5 % of that in
/// 3 T (75 ms). Damping each joint by a fixed gain per unit of its effort limit (0.2 N m s/rad per
/// N m, before) is explicit damping, stable only while `d dt / I < 2`: the LWR-IV's wrist (38 N m,
/// 7.6 N m s/rad, a few 1e-3 kg m² at 1 kHz) was not, and a reflex with the wrist moving spun it
/// up to 28 rad/s at its torque limits instead of stopping it. With `M q̇ / T` the decay per tick
/// is `1 − dt / T` for every joint, whatever its inertia (stable for `dt < 2 T`).
pub const STOP_TIME_CONSTANT_S: f64 = 0.025;

impl Robot {
    /// Gravity torques g(q) (N m, N) at the configuration of the last
    /// [`Robot::forward_kinematics`]: the torques that hold the arm still.
    ///
    /// One backward pass over composite masses: joint i holds the bodies i.. whose mass `M` and
    /// first moment `H = Σ m c` (base frame) it carries, so a revolute joint at `p` with axis `a`
    /// needs `−a · ((H − M p) × g)` and a prismatic one `−M a · g`. The same torques as Newton-Euler
    /// with q̇ = q̈ = 0 (`runtime/tests/robot_model.rs`) for a tenth of its work: the controller
    /// needs them every tick.
    ///
    /// # Panics
    /// If `out.len()` differs from [`Robot::dof`].
    pub fn gravity_torques(&self, data: &mut RobotData, out: &mut [f64]) {
        let n = self.dof();
        assert_eq!(out.len(), n, "gravity torques need dof entries");
        debug_assert!(data.kinematics_done, "call forward_kinematics first");
        let mut mass = 0.0;
        let mut first = Vector3::zeros();
        for i in (0..n).rev() {
            let body = &self.bodies[i];
            let (rot, pos) = (&data.rot[i], &data.pos[i]);
            mass += body.mass;
            first += (rot * body.com + pos) * body.mass;
            let axis = rot * body.axis;
            out[i] = match body.kind {
                JointKind::Revolute => -axis.dot(&(first - pos * mass).cross(&self.gravity)),
                JointKind::Prismatic => -mass * axis.dot(&self.gravity),
            };
        }
    }

    /// The torques of a damped stop at `(q, q̇)`: gravity compensation from the model and
    /// `−M(q) q̇ / T` with `T` = [`STOP_TIME_CONSTANT_S`], within the effort limits (a joint at its
    /// limit stops more slowly), so the arm comes to rest where it is, as a real arm's stop
    /// category 1 does. Zero torques when the state is not finite (the supervisor's reflex and a
    /// served plant whose controller fell silent both stop the arm this way).
    ///
    /// # Panics
    /// If a slice length differs from [`Robot::dof`].
    pub fn damped_stop_torques(&self, data: &mut RobotData, q: &[f64], qd: &[f64], out: &mut [f64]) {
        let finite = q.iter().chain(qd).all(|v| v.is_finite());
        if !finite {
            out.iter_mut().for_each(|tau| *tau = 0.0);
            return;
        }
        self.forward_kinematics(data, q);
        self.gravity_torques(data, out);
        let mut mass = std::mem::take(&mut data.mass);
        self.mass_matrix(data, &mut mass);
        for (i, (tau, joint)) in out.iter_mut().zip(self.joints()).enumerate() {
            let momentum: f64 = mass.row(i).iter().zip(qd).map(|(m, v)| m * v).sum();
            let value = *tau - momentum / STOP_TIME_CONSTANT_S;
            *tau = if value.is_finite() {
                value.clamp(-joint.effort, joint.effort)
            } else {
                0.0
            };
        }
        data.mass = mass;
    }

    /// Inverse dynamics τ = M(q) q̈ + C(q, q̇) q̇ + g(q) at the configuration of the last
    /// [`Robot::forward_kinematics`], by recursive Newton-Euler.
    ///
    /// # Panics
    /// If a slice length differs from [`Robot::dof`].
    pub fn inverse_dynamics(&self, data: &mut RobotData, qd: &[f64], qdd: &[f64], out: &mut [f64]) {
        self.rnea(data, qd, qdd, true, out);
    }

    /// Coriolis and centrifugal torques C(q, q̇) q̇ at the configuration of the last
    /// [`Robot::forward_kinematics`].
    ///
    /// # Panics
    /// If a slice length differs from [`Robot::dof`].
    pub fn coriolis_torques(&self, data: &mut RobotData, qd: &[f64], out: &mut [f64]) {
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea(data, qd, &zeros, false, out);
        data.zeros = zeros;
    }

    /// The arm's effective mass at the tool point along the unit vector `direction` (base
    /// frame) at configuration `q`: `1 / (u J_v M⁻¹ J_vᵀ u)` \[kg\], the mass a contact along
    /// `u` meets. `None` at a singular configuration. Allocates: for set-up, not for a tick.
    ///
    /// # Panics
    /// If `q.len()` differs from [`Robot::dof`].
    pub fn tool_effective_mass(&self, q: &[f64], direction: &Vector3<f64>) -> Option<f64> {
        self.tool_effective(q, 0, direction)
    }

    /// The effective rotational inertia of the tool about the unit `axis` (base frame) at `q`
    /// \[kg m²\]: `1 / (aᵀ J_ω M⁻¹ J_ωᵀ a)`, what a torque about that axis at the tool meets.
    /// `None` where the mass matrix is singular.
    pub fn tool_effective_inertia(&self, q: &[f64], axis: &Vector3<f64>) -> Option<f64> {
        self.tool_effective(q, 3, axis)
    }

    /// `1 / (uᵀ J M⁻¹ Jᵀ u)` with `J` the tool Jacobian's three rows from `first` (0: linear,
    /// 3: angular) at `q`: the effective mass or inertia along or about `u`.
    fn tool_effective(&self, q: &[f64], first: usize, u: &Vector3<f64>) -> Option<f64> {
        let n = self.dof();
        let mut data = self.data();
        self.forward_kinematics(&mut data, q);
        let mut mass = DMatrix::zeros(n, n);
        self.mass_matrix(&mut data, &mut mass);
        let mut jacobian = nalgebra::Matrix6xX::zeros(n);
        self.tool_jacobian(&data, &mut jacobian);
        let row = jacobian.fixed_rows::<3>(first).tr_mul(u);
        mass.cholesky()
            .map(|chol| 1.0 / row.dot(&chol.solve(&row)))
            .filter(|m| m.is_finite() && *m > 0.0)
    }

    /// The joint-space mass matrix M(q) at the configuration of the last
    /// [`Robot::forward_kinematics`], by the composite-rigid-body algorithm (Walker and Orin;
    /// Featherstone, *Rigid Body Dynamics Algorithms*, §6.2) for a serial chain: one backward
    /// pass accumulates each body's composite inertia (itself and every body after it) in its
    /// own frame, and `M[i][j]` is joint `j`'s motion axis applied to the spatial force joint
    /// `i`'s unit motion needs from that composite, carried back to body `j`. About a fifth of
    /// the work of one Newton-Euler pass per column.
    ///
    /// # Panics
    /// If `out` is not dof × dof.
    pub fn mass_matrix(&self, data: &mut RobotData, out: &mut DMatrix<f64>) {
        let n = self.dof();
        assert_eq!(out.shape(), (n, n), "mass matrix must be dof x dof");
        debug_assert!(data.kinematics_done, "call forward_kinematics first");
        // Composite inertia of bodies i.. in body i's frame, about its origin: mass m, first
        // moment h = m c, rotational inertia about the origin. Built from the last body back.
        let mut mass = 0.0;
        let mut first = Vector3::zeros();
        let mut rotational = Matrix3::zeros();
        for i in (0..n).rev() {
            if i + 1 < n {
                // Carry the composite of bodies i+1.. from frame i+1 into frame i.
                let rot = &data.local_rot[i + 1];
                let pos = &data.local_pos[i + 1];
                let h = rot * first;
                rotational = rot * rotational * rot.transpose()
                    + (Matrix3::identity() * (2.0 * pos.dot(&h) + mass * pos.dot(pos))
                        - (h * pos.transpose() + pos * h.transpose() + mass * pos * pos.transpose()));
                first = h + pos * mass;
            }
            let body = &self.bodies[i];
            let c = body.com;
            mass += body.mass;
            first += c * body.mass;
            rotational += body.inertia + (Matrix3::identity() * c.dot(&c) - c * c.transpose()) * body.mass;
            // The spatial force (moment about the origin, force) the composite needs for a unit
            // motion of joint i: momentum of the motion S_i.
            let (mut moment, mut force) = match body.kind {
                JointKind::Revolute => (rotational * body.axis, -first.cross(&body.axis)),
                JointKind::Prismatic => (first.cross(&body.axis), body.axis * mass),
            };
            out[(i, i)] = self.project(i, &moment, &force);
            for j in (0..i).rev() {
                // From frame j+1 into frame j.
                let rot = &data.local_rot[j + 1];
                force = rot * force;
                moment = rot * moment + data.local_pos[j + 1].cross(&force);
                let value = self.project(j, &moment, &force);
                out[(i, j)] = value;
                out[(j, i)] = value;
            }
        }
    }

    /// Joint `j`'s motion axis applied to a spatial force in body `j`'s frame.
    fn project(&self, j: usize, moment: &Vector3<f64>, force: &Vector3<f64>) -> f64 {
        let body = &self.bodies[j];
        match body.kind {
            JointKind::Revolute => body.axis.dot(moment),
            JointKind::Prismatic => body.axis.dot(force),
        }
    }

    /// Recursive Newton-Euler in body frames (Luh, Walker, Paul), gravity optional.
    fn rnea(&self, data: &mut RobotData, qd: &[f64], qdd: &[f64], with_gravity: bool, out: &mut [f64]) {
        let n = self.dof();
        debug_assert!(data.kinematics_done, "call forward_kinematics first");
        assert!(
            qd.len() == n && qdd.len() == n && out.len() == n,
            "vectors must have dof entries"
        );
        let mut omega_prev = Vector3::zeros();
        let mut omega_dot_prev = Vector3::zeros();
        // The base accelerates upwards at g: gravity enters as a fictitious base acceleration.
        let mut acc_prev = if with_gravity { -self.gravity } else { Vector3::zeros() };
        for (idx, body) in self.bodies.iter().enumerate() {
            let rot_t = data.local_rot[idx].transpose();
            let pos = &data.local_pos[idx];
            let acc = rot_t * (acc_prev + omega_dot_prev.cross(pos) + omega_prev.cross(&omega_prev.cross(pos)));
            let omega_in = rot_t * omega_prev;
            let omega_dot_in = rot_t * omega_dot_prev;
            let (omega, omega_dot, acc) = match body.kind {
                JointKind::Revolute => {
                    let spin = body.axis * qd[idx];
                    (
                        omega_in + spin,
                        omega_dot_in + omega_in.cross(&spin) + body.axis * qdd[idx],
                        acc,
                    )
                }
                JointKind::Prismatic => {
                    let slide = body.axis * qd[idx];
                    (
                        omega_in,
                        omega_dot_in,
                        acc + 2.0 * omega_in.cross(&slide) + body.axis * qdd[idx],
                    )
                }
            };
            let acc_com = acc + omega_dot.cross(&body.com) + omega.cross(&omega.cross(&body.com));
            let force = acc_com * body.mass;
            let inertia_omega = body.inertia * omega;
            data.force[idx] = force;
            data.moment[idx] = body.inertia * omega_dot + omega.cross(&inertia_omega) + body.com.cross(&force);
            data.omega[idx] = omega;
            data.omega_dot[idx] = omega_dot;
            omega_prev = omega;
            omega_dot_prev = omega_dot;
            acc_prev = acc;
        }
        let mut child_force = Vector3::zeros();
        let mut child_moment = Vector3::zeros();
        for idx in (0..n).rev() {
            let force = data.force[idx] + child_force;
            let moment = data.moment[idx] + child_moment;
            let body = &self.bodies[idx];
            out[idx] = match body.kind {
                JointKind::Revolute => body.axis.dot(&moment),
                JointKind::Prismatic => body.axis.dot(&force),
            };
            // The wrench this body's joint transmits, seen in the parent frame about the parent origin.
            let rot = &data.local_rot[idx];
            child_force = rot * force;
            child_moment = rot * moment + data.local_pos[idx].cross(&child_force);
        }
    }
}

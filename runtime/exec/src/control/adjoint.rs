//! Adjoint maps between a compliant frame and the control frame, and the selection and
//! stiffness operators Ω and Ω̃ of the hybrid law (docs/method.md §6, thesis eq. 4.18-4.21).
//!
//! Twists are ordered `[v; ω]`, wrenches `[f; m]`. With the compliant frame's pose relative to
//! the control frame given by rotation `R` and translation `p`:
//!
//! ```text
//! Ad  = [[R, p̂R], \[0, R\]]     maps compliant-frame twists to control-frame twists
//! Adg = Ad⁻ᵀ = [\[R, 0\], [p̂R, R]]   maps compliant-frame wrenches to control-frame wrenches
//! Ω   = Adg K S Ad⁻¹          pose error (control frame) → restoring wrench (control frame)
//! Ω̃   = Adg S̃ Adg⁻¹          force error (control frame) → selected force error (control frame)
//! ```

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3};

/// The skew-symmetric matrix `p̂` with `p̂ x = p × x`.
pub fn hat(p: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -p.z, p.y, p.z, 0.0, -p.x, -p.y, p.x, 0.0)
}

/// `Ad` of a frame pose: maps that frame's twists to the reference frame's twists.
pub fn adjoint(pose: &Isometry3<f64>) -> Matrix6<f64> {
    let r = pose.rotation.to_rotation_matrix().into_inner();
    let p = pose.translation.vector;
    let mut ad = Matrix6::zeros();
    ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    ad.fixed_view_mut::<3, 3>(0, 3).copy_from(&(hat(&p) * r));
    ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    ad
}

/// `Ad⁻¹` of a frame pose, in closed form: `[[Rᵀ, −Rᵀp̂], [0, Rᵀ]]`.
pub fn adjoint_inverse(pose: &Isometry3<f64>) -> Matrix6<f64> {
    let rt = pose.rotation.to_rotation_matrix().into_inner().transpose();
    let p = pose.translation.vector;
    let mut ad = Matrix6::zeros();
    ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&rt);
    ad.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-rt * hat(&p)));
    ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&rt);
    ad
}

/// `Adg = Ad⁻ᵀ`: maps that frame's wrenches to the reference frame's wrenches.
pub fn wrench_adjoint(pose: &Isometry3<f64>) -> Matrix6<f64> {
    adjoint_inverse(pose).transpose()
}

/// `Adg⁻¹ = Adᵀ`: maps reference-frame wrenches to that frame's wrenches.
pub fn wrench_adjoint_inverse(pose: &Isometry3<f64>) -> Matrix6<f64> {
    adjoint(pose).transpose()
}

/// Ω = Adg K S Ad⁻¹ and Ω̃ = Adg S̃ Adg⁻¹ for a compliant frame at `frame_in_control`,
/// with the selection (`true` = position-controlled) and stiffness given per compliant-frame axis.
pub fn operators(
    frame_in_control: &Isometry3<f64>,
    position: &[bool; 6],
    stiffness: &[f64; 6],
) -> (Matrix6<f64>, Matrix6<f64>) {
    let ad_inv = adjoint_inverse(frame_in_control);
    let adg = ad_inv.transpose();
    let adg_inv = adjoint(frame_in_control).transpose();
    let mut k_s = Matrix6::zeros();
    let mut s_tilde = Matrix6::zeros();
    for axis in 0..6 {
        if position[axis] {
            k_s[(axis, axis)] = stiffness[axis];
        } else {
            s_tilde[(axis, axis)] = 1.0;
        }
    }
    (adg * k_s * ad_inv, adg * s_tilde * adg_inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector6};

    fn pose(seed: u64) -> Isometry3<f64> {
        let a = (seed as f64 * 0.37).sin();
        let b = (seed as f64 * 1.11).cos();
        Isometry3::from_parts(
            Translation3::new(0.3 * a, -0.2 * b, 0.1 + 0.05 * a * b),
            UnitQuaternion::from_euler_angles(0.4 * a, -0.7 * b, 1.3 * a * b),
        )
    }

    #[test]
    fn inverses_are_inverses() {
        for seed in 0..10 {
            let g = pose(seed);
            assert!((adjoint(&g) * adjoint_inverse(&g) - Matrix6::identity()).norm() < 1e-12);
            assert!((wrench_adjoint(&g) * wrench_adjoint_inverse(&g) - Matrix6::identity()).norm() < 1e-12);
        }
    }

    #[test]
    fn adjoint_moves_twists_like_rigid_motion() {
        // A twist given in frame B (at B's origin, B's axes) seen in frame A: v_A = R v_B + p × (R ω_B).
        let g = pose(3);
        let twist_b = Vector6::new(0.1, -0.2, 0.3, 0.5, 0.1, -0.4);
        let twist_a = adjoint(&g) * twist_b;
        let r = g.rotation.to_rotation_matrix().into_inner();
        let omega_a = r * twist_b.fixed_rows::<3>(3);
        let v_a = r * twist_b.fixed_rows::<3>(0) + g.translation.vector.cross(&omega_a);
        assert!((twist_a.fixed_rows::<3>(0) - v_a).norm() < 1e-12);
        assert!((twist_a.fixed_rows::<3>(3) - omega_a).norm() < 1e-12);
    }

    #[test]
    fn power_is_frame_invariant() {
        let g = pose(7);
        let twist_b = Vector6::new(0.3, 0.1, -0.2, 0.2, -0.5, 0.9);
        let wrench_b = Vector6::new(4.0, -1.0, 9.0, 0.2, 0.3, -0.1);
        let power_b = twist_b.dot(&wrench_b);
        let power_a = (adjoint(&g) * twist_b).dot(&(wrench_adjoint(&g) * wrench_b));
        assert!((power_a - power_b).abs() < 1e-12);
    }

    #[test]
    fn at_the_control_point_unrotated_the_operators_are_ks_and_s_tilde() {
        let position = [true, true, false, true, true, true];
        let stiffness = [1000.0, 2000.0, 3000.0, 10.0, 20.0, 30.0];
        let (omega, omega_tilde) = operators(&Isometry3::identity(), &position, &stiffness);
        let ks = Matrix6::from_diagonal(&Vector6::new(1000.0, 2000.0, 0.0, 10.0, 20.0, 30.0));
        let s_tilde = Matrix6::from_diagonal(&Vector6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0));
        assert!((omega - ks).norm() < 1e-12);
        assert!((omega_tilde - s_tilde).norm() < 1e-12);
    }

    #[test]
    fn omega_tilde_is_a_projection_and_complements_the_position_axes() {
        for seed in 0..10 {
            let g = pose(seed);
            let position = [seed % 2 == 0, true, false, seed % 3 == 0, true, false];
            let (omega, omega_tilde) = operators(&g, &position, &[500.0; 6]);
            assert!((omega_tilde * omega_tilde - omega_tilde).norm() < 1e-10, "idempotent");
            // A wrench Ω produces (from stiffness on position axes) is removed by Ω̃.
            let e = Vector6::new(0.01, -0.02, 0.03, 0.1, 0.05, -0.02);
            assert!((omega_tilde * (omega * e)).norm() < 1e-9);
        }
    }

    #[test]
    fn all_position_makes_omega_tilde_vanish_and_omega_the_transformed_stiffness() {
        let g = Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_euler_angles(0.3, 0.2, -0.1),
        );
        let (omega, omega_tilde) = operators(&g, &[true; 6], &[800.0, 800.0, 800.0, 50.0, 50.0, 50.0]);
        assert!(omega_tilde.norm() < 1e-12);
        // Isotropic stiffness per block is invariant under rotation.
        let expected = Matrix6::from_diagonal(&Vector6::new(800.0, 800.0, 800.0, 50.0, 50.0, 50.0));
        assert!((omega - expected).norm() < 1e-9);
    }
}

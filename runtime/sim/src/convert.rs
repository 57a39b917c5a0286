//! Conversions between nalgebra (f64, the rest of skillc) and rapier's glam types (`Real`, f32 or
//! f64 by flavour): the one place in `sim` where values cross that boundary, so rapier types never
//! leave this module. Also the shape conventions that differ (rapier's cylinders run along y).
// `Real` is f32 or f64 depending on the rapier flavour: casts and conversions to it are identities in one.
#![allow(clippy::unnecessary_cast, clippy::useless_conversion)]

use nalgebra::{Isometry3, IsometryMatrix3, Matrix3, UnitQuaternion, Vector3};
use rapier3d::math::{Pose, Real, Rotation, Vector};
use rapier3d::prelude::MassProperties;

/// Whether the simulation runs in double precision (`rapier3d-f64`); `false` with `rapier3d` (f32).
pub const SIM_F64: bool = std::mem::size_of::<Real>() == 8;

/// A vector in rapier's scalar.
pub(super) fn vec3(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as Real, v.y as Real, v.z as Real)
}

/// A rapier vector in f64.
pub(super) fn from_vec3(v: Vector) -> Vector3<f64> {
    Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

/// A rotation matrix as rapier's (normalised) quaternion.
pub(super) fn quat(rot: &Matrix3<f64>) -> Rotation {
    let q = UnitQuaternion::from_matrix(rot);
    Rotation::from_xyzw(q.i as Real, q.j as Real, q.k as Real, q.w as Real).normalize()
}

/// A pose (rotation matrix form) as rapier's pose.
pub(super) fn pose_of(iso: &IsometryMatrix3<f64>) -> Pose {
    Pose::from_parts(vec3(&iso.translation.vector), quat(iso.rotation.matrix()))
}

/// A pose (quaternion form) as rapier's pose.
pub(super) fn pose_of_quat(iso: &Isometry3<f64>) -> Pose {
    pose_of(&IsometryMatrix3::from_parts(
        iso.translation,
        iso.rotation.to_rotation_matrix(),
    ))
}

/// A rapier pose in f64.
pub(super) fn iso_of(pose: &Pose) -> IsometryMatrix3<f64> {
    let r = pose.rotation;
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        f64::from(r.w),
        f64::from(r.x),
        f64::from(r.y),
        f64::from(r.z),
    ));
    IsometryMatrix3::from_parts(
        nalgebra::Translation3::from(from_vec3(pose.translation)),
        q.to_rotation_matrix(),
    )
}

/// A rapier pose from a position \[m\] and roll-pitch-yaw angles \[rad\] (the scene file's `xyz`, `rpy`).
pub(super) fn rpy_pose(xyz: [f64; 3], rpy: [f64; 3]) -> Pose {
    pose_of(&IsometryMatrix3::from_parts(
        nalgebra::Translation3::new(xyz[0], xyz[1], xyz[2]),
        nalgebra::Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    ))
}

/// rapier's cylinders and capsules run along y; URDF's and the scene's along z.
pub(super) fn z_to_y() -> Pose {
    Pose::from_rotation(Rotation::from_rotation_x(std::f64::consts::FRAC_PI_2 as Real))
}

/// rapier mass properties; diagonal tensors go in as principal moments (no eigen-solve here; rapier may still
/// re-diagonalise when it sums them with the tool colliders' zero mass, which only permutes the axes).
pub(super) fn mass_properties(mass: f64, com: &Vector3<f64>, inertia: &Matrix3<f64>) -> MassProperties {
    let off_diagonal = inertia[(0, 1)].abs() + inertia[(0, 2)].abs() + inertia[(1, 2)].abs();
    if off_diagonal == 0.0 {
        MassProperties::new(vec3(com), mass as Real, vec3(&inertia.diagonal()))
    } else {
        MassProperties::with_inertia_matrix(
            vec3(com),
            mass as Real,
            rapier3d::math::Matrix::from_cols(
                vec3(&inertia.column(0).into_owned()),
                vec3(&inertia.column(1).into_owned()),
                vec3(&inertia.column(2).into_owned()),
            ),
        )
    }
}

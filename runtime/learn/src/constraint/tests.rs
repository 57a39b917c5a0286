//! Ground-truth tests: synthetic segments on tilted planes, cylinders, lines and hinges.

use nalgebra::{UnitQuaternion, Vector3};

use super::*;
use crate::testutil::Rng;

struct Segment {
    position: Vec<Vector3<f64>>,
    orientation: Vec<UnitQuaternion<f64>>,
    force: Vec<Vector3<f64>>,
}

const N: usize = 800;
const POS_NOISE: f64 = 3e-4;
const ROT_NOISE_DEG: f64 = 0.2;

fn noisy(rng: &mut Rng, p: Vector3<f64>, q: UnitQuaternion<f64>) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let rot_noise = UnitQuaternion::from_scaled_axis(rng.vector(ROT_NOISE_DEG.to_radians()));
    (p + rng.vector(POS_NOISE), rot_noise * q)
}

fn unit(v: Vector3<f64>) -> Vector3<f64> {
    v.normalize()
}

fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.normalize().dot(&b.normalize()).clamp(-1.0, 1.0).acos().to_degrees()
}

/// A slide on a plane with outward normal `n_out`, pressing 12 N into it, with friction.
fn plane_slide(n_out: Vector3<f64>, seed: u64) -> Segment {
    let mut rng = Rng::new(seed);
    let u = unit(n_out.cross(&Vector3::x()));
    let v = n_out.cross(&u);
    let origin = Vector3::new(0.5, 0.1, 0.2);
    let base_q = UnitQuaternion::from_euler_angles(3.0, 0.2, 0.4);
    let mut seg = Segment {
        position: vec![],
        orientation: vec![],
        force: vec![],
    };
    for k in 0..N {
        let s = k as f64 / (N - 1) as f64;
        let p = origin + u * (0.15 * s) + v * (0.05 * (6.0 * s).sin());
        // Rotation about the normal only (allowed by the planar constraint).
        let q = UnitQuaternion::from_scaled_axis(n_out * (0.4 * s)) * base_q;
        let velocity = unit(u * 0.15 + v * (0.3 * (6.0 * s).cos()));
        let (p, q) = noisy(&mut rng, p, q);
        seg.position.push(p);
        seg.orientation.push(q);
        seg.force.push(n_out * 12.0 - velocity * 3.0 + rng.vector(0.3));
    }
    seg
}

#[test]
fn tilted_planes_choose_planar_with_normal_within_1_degree() {
    for (seed, n_out) in [
        (1, Vector3::z()),
        (2, unit(Vector3::new(0.3, -0.2, 1.0))),
        (3, unit(Vector3::new(-0.6, 0.1, 0.8))),
        (4, unit(Vector3::new(1.0, 0.0, 0.05))),
    ] {
        let seg = plane_slide(n_out, seed);
        let report = fit_constraints(
            &seg.position,
            &seg.orientation,
            &seg.force,
            &ConstraintConfig::default(),
        )
        .expect("valid");
        let best = report.chosen();
        assert_eq!(best.kind, ConstraintKind::Planar, "seed {seed}: {:#?}", report.fits);
        // z points into the surface, i.e. along the applied force −F.
        let error = angle_deg(&best.frame.z_axis(), &(-n_out));
        eprintln!(
            "plane seed {seed}: normal error {error:.3} deg, residual {:.3} mm",
            best.residual_m * 1e3
        );
        assert!(error < 1.0, "seed {seed}: normal off by {error} deg");
        assert!(best.residual_m < 1e-3);
    }
}

#[test]
fn straight_slide_takes_its_plane_normal_from_the_force() {
    let mut rng = Rng::new(12);
    let n_out = unit(Vector3::new(0.25, 0.3, 1.0));
    let along = unit(n_out.cross(&Vector3::y()));
    let base_q = UnitQuaternion::from_euler_angles(3.0, -0.1, 0.5);
    let mut seg = Segment {
        position: vec![],
        orientation: vec![],
        force: vec![],
    };
    for k in 0..N {
        let s = k as f64 / (N - 1) as f64;
        let q = UnitQuaternion::from_scaled_axis(n_out * (0.5 * s)) * base_q;
        let (p, q) = noisy(&mut rng, Vector3::new(0.4, 0.0, 0.1) + along * (0.2 * s), q);
        seg.position.push(p);
        seg.orientation.push(q);
        seg.force.push(n_out * 12.0 - along * 3.0 + rng.vector(0.3));
    }
    let report = fit_constraints(
        &seg.position,
        &seg.orientation,
        &seg.force,
        &ConstraintConfig::default(),
    )
    .expect("valid");
    let best = report.chosen();
    assert_eq!(best.kind, ConstraintKind::Planar, "{:#?}", report.fits);
    let error = angle_deg(&best.frame.z_axis(), &(-n_out));
    eprintln!("straight slide: normal error {error:.3} deg");
    assert!(error < 1.0, "normal off by {error} deg");
}

#[test]
fn line_chooses_prismatic_with_axis_within_2_degrees() {
    let mut rng = Rng::new(5);
    let axis = unit(Vector3::new(0.4, 0.8, -0.3));
    let q0 = UnitQuaternion::from_euler_angles(0.1, -0.5, 1.0);
    let push = unit(axis.cross(&Vector3::z()));
    let mut seg = Segment {
        position: vec![],
        orientation: vec![],
        force: vec![],
    };
    for k in 0..N {
        let s = k as f64 / (N - 1) as f64;
        let (p, q) = noisy(&mut rng, Vector3::new(0.3, 0.0, 0.4) + axis * (0.25 * s * s), q0);
        seg.position.push(p);
        seg.orientation.push(q);
        seg.force.push(push * 8.0 + rng.vector(0.3));
    }
    let report = fit_constraints(
        &seg.position,
        &seg.orientation,
        &seg.force,
        &ConstraintConfig::default(),
    )
    .expect("valid");
    let best = report.chosen();
    assert_eq!(best.kind, ConstraintKind::Prismatic, "{:#?}", report.fits);
    let found = best.axis.expect("prismatic has an axis");
    eprintln!("line: axis error {:.3} deg", angle_deg(&found, &axis));
    assert!(
        angle_deg(&found, &axis) < 2.0,
        "axis off by {} deg",
        angle_deg(&found, &axis)
    );
    assert!(
        angle_deg(&best.frame.x_axis(), &axis) < 2.0,
        "x must run along the line, in the direction of travel"
    );
    assert!(
        angle_deg(&best.frame.z_axis(), &(-push)) < 2.0,
        "z along the applied force"
    );
}

#[test]
fn cylinder_chooses_concentric_cylinder_with_axis_within_2_degrees() {
    let mut rng = Rng::new(6);
    let axis = unit(Vector3::new(0.2, -0.3, -1.0));
    let on_axis = Vector3::new(0.6, -0.1, 0.3);
    let offset = 0.03 * unit(axis.cross(&Vector3::x()));
    let q0 = UnitQuaternion::from_euler_angles(0.4, 0.3, -0.2);
    let mut seg = Segment {
        position: vec![],
        orientation: vec![],
        force: vec![],
    };
    for k in 0..N {
        let s = k as f64 / (N - 1) as f64;
        let turn = UnitQuaternion::from_scaled_axis(axis * (1.5 * s));
        let p = on_axis + axis * (0.12 * s) + turn * offset;
        let (p, q) = noisy(&mut rng, p, turn * q0);
        seg.position.push(p);
        seg.orientation.push(q);
        seg.force.push(-(turn * offset).normalize() * 5.0 + rng.vector(0.3));
    }
    let report = fit_constraints(
        &seg.position,
        &seg.orientation,
        &seg.force,
        &ConstraintConfig::default(),
    )
    .expect("valid");
    let best = report.chosen();
    assert_eq!(best.kind, ConstraintKind::ConcentricCylinder, "{:#?}", report.fits);
    let found = best.axis.expect("cylinder has an axis");
    eprintln!("cylinder: axis error {:.3} deg", angle_deg(&found, &axis));
    assert!(
        angle_deg(&found, &axis) < 2.0,
        "axis off by {} deg",
        angle_deg(&found, &axis)
    );
    // The axis passes through the true axis line.
    let miss = (best.point_m - on_axis) - axis * axis.dot(&(best.point_m - on_axis));
    assert!(miss.norm() < 2e-3, "axis point {} m off", miss.norm());
}

#[test]
fn hinge_chooses_axial_rotation_with_axis_within_2_degrees() {
    let mut rng = Rng::new(7);
    let axis = unit(Vector3::new(-0.1, 1.0, 0.25));
    let pivot = Vector3::new(0.5, 0.2, 0.6);
    let arm = 0.15 * unit(axis.cross(&Vector3::z()));
    let q0 = UnitQuaternion::from_euler_angles(-0.3, 0.6, 0.1);
    let mut seg = Segment {
        position: vec![],
        orientation: vec![],
        force: vec![],
    };
    for k in 0..N {
        let s = k as f64 / (N - 1) as f64;
        let turn = UnitQuaternion::from_scaled_axis(axis * (70f64.to_radians() * s));
        let (p, q) = noisy(&mut rng, pivot + turn * arm, turn * q0);
        seg.position.push(p);
        seg.orientation.push(q);
        seg.force
            .push(axis.cross(&(turn * arm)).normalize() * -6.0 + rng.vector(0.3));
    }
    let report = fit_constraints(
        &seg.position,
        &seg.orientation,
        &seg.force,
        &ConstraintConfig::default(),
    )
    .expect("valid");
    let best = report.chosen();
    assert_eq!(best.kind, ConstraintKind::AxialRotation, "{:#?}", report.fits);
    let found = best.axis.expect("hinge has an axis");
    eprintln!("hinge: axis error {:.3} deg", angle_deg(&found, &axis));
    assert!(
        angle_deg(&found, &axis) < 2.0,
        "axis off by {} deg",
        angle_deg(&found, &axis)
    );
    let miss = (best.point_m - pivot) - axis * axis.dot(&(best.point_m - pivot));
    assert!(miss.norm() < 3e-3, "axis point {} m off", miss.norm());
}

#[test]
fn fixed_point_is_found_for_a_ball_joint() {
    let mut rng = Rng::new(8);
    let pivot = Vector3::new(0.4, -0.2, 0.3);
    let tool_point = Vector3::new(0.0, 0.0, 0.12);
    let mut seg = Segment {
        position: vec![],
        orientation: vec![],
        force: vec![],
    };
    for k in 0..N {
        let s = k as f64 / (N - 1) as f64;
        let q = UnitQuaternion::from_euler_angles(0.5 * (3.0 * s).sin(), 0.4 * (2.0 * s).cos(), 1.2 * s);
        let (p, q) = noisy(&mut rng, pivot - q * tool_point, q);
        seg.position.push(p);
        seg.orientation.push(q);
        seg.force.push(Vector3::new(0.0, 0.0, 5.0) + rng.vector(0.3));
    }
    let report = fit_constraints(
        &seg.position,
        &seg.orientation,
        &seg.force,
        &ConstraintConfig::default(),
    )
    .expect("valid");
    let best = report.chosen();
    assert_eq!(best.kind, ConstraintKind::FixedPoint, "{:#?}", report.fits);
    assert!(
        (best.point_m - pivot).norm() < 2e-3,
        "pivot {} m off",
        (best.point_m - pivot).norm()
    );
}

#[test]
fn minimal_rotation_is_exact_near_parallel_and_antiparallel() {
    let mut rng = Rng::new(9);
    let mut pairs: Vec<(Vector3<f64>, Vector3<f64>)> = (0..200)
        .map(|_| (unit(rng.vector(1.0)), unit(rng.vector(1.0))))
        .collect();
    for _ in 0..50 {
        let a = unit(rng.vector(1.0));
        let tiny = rng.vector(1e-9);
        pairs.push((a, unit(a + tiny)));
        pairs.push((a, unit(-a + tiny)));
        pairs.push((a, a));
        pairs.push((a, -a));
    }
    pairs.push((Vector3::z(), -Vector3::z()));
    for (from, to) in pairs {
        let r = rotation_between(&from, &to);
        let m = r.matrix();
        assert!((m * from - to).norm() < 1e-9, "does not map {from:?} to {to:?}");
        assert!((m.transpose() * m - nalgebra::Matrix3::identity()).norm() < 1e-9);
        assert!((m.determinant() - 1.0).abs() < 1e-9);
        if from.dot(&to) > -0.999 {
            // Minimal: the rotation angle is the angle between the vectors.
            let angle = from.dot(&to).clamp(-1.0, 1.0).acos();
            let found = UnitQuaternion::from_rotation_matrix(&r).angle();
            assert!((found - angle).abs() < 1e-6, "angle {found} vs {angle}");
        }
    }
}

#[test]
fn force_aligned_frames_follow_the_force_and_hold_when_it_vanishes() {
    let n = 300;
    let position: Vec<Vector3<f64>> = (0..n).map(|k| Vector3::new(k as f64 * 1e-3, 0.0, 0.0)).collect();
    let force: Vec<Vector3<f64>> = (0..n)
        .map(|k| match k {
            0..50 => Vector3::zeros(),
            50..200 => {
                let a = k as f64 * 0.01;
                Vector3::new(a.sin(), 0.0, a.cos()) * 10.0
            }
            _ => Vector3::new(0.0, 0.0, 0.1),
        })
        .collect();
    let frames = force_aligned_frames(&force, &position, &ForceFrameConfig::default()).expect("contact");
    for k in 0..n {
        let expected = -force[k.clamp(50, 199)].normalize();
        assert!(angle_deg(&frames[k].z_axis(), &expected) < 1e-6, "sample {k}");
        assert_eq!(frames[k].origin_m, position[k]);
    }
    let at = force_aligned_frame_at(&force, &position, 250, &ForceFrameConfig::default()).expect("contact before");
    assert!(angle_deg(&at.z_axis(), &(-force[199])) < 1e-6);
    let none = vec![Vector3::zeros(); 10];
    assert!(matches!(
        force_aligned_frames(&none, &position[..10], &ForceFrameConfig::default()),
        Err(ConstraintError::NoContact { .. })
    ));
}

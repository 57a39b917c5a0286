//! Least-squares fits of the six constraint models and the choice between them.

use nalgebra::{Matrix3, Matrix6, SymmetricEigen, UnitQuaternion, Vector3, Vector4, Vector6};

use super::frame::CompliantFrame;
use super::{ConstraintConfig, ConstraintError, ConstraintFit, ConstraintKind, ConstraintReport};
use crate::dmp::quat_error;

/// What all models share: centroid, principal directions of the positions and of the rotations.
struct Shared<'a> {
    position: &'a [Vector3<f64>],
    rotation: Vec<Matrix3<f64>>,
    /// Rotation vectors from the mean orientation to each sample (base frame).
    rotvec: Vec<Vector3<f64>>,
    centroid: Vector3<f64>,
    /// Eigenvalues (descending) and unit eigenvectors of the position covariance.
    pos_eig: ([f64; 3], [Vector3<f64>; 3]),
    /// Main rotation axis and RMS rotation.
    rot_axis: Vector3<f64>,
    rot_rms: f64,
    /// Mean applied force over contact samples (`−force_n`), if any sample is in contact.
    applied: Option<Vector3<f64>>,
    travel: Vector3<f64>,
}

fn eigen_sorted(m: Matrix3<f64>) -> ([f64; 3], [Vector3<f64>; 3]) {
    let eig = SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values = order.map(|i| eig.eigenvalues[i].max(0.0));
    let vectors = order.map(|i| eig.eigenvectors.column(i).into_owned().normalize());
    (values, vectors)
}

fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v * v, c + 1));
    (sum / count.max(1) as f64).sqrt()
}

/// Some unit vector perpendicular to `axis`.
fn perpendicular(axis: &Vector3<f64>) -> Vector3<f64> {
    let candidate = if axis.z.abs() < 0.9 { Vector3::z() } else { Vector3::x() };
    (candidate - axis * axis.dot(&candidate)).normalize()
}

/// Right-handed frame from z and a hint for x (projected to be perpendicular to z).
fn frame_from(origin: Vector3<f64>, z: Vector3<f64>, x_hint: Vector3<f64>) -> CompliantFrame {
    let z = z.normalize();
    let mut x = x_hint - z * z.dot(&x_hint);
    if x.norm() < 1e-9 {
        x = perpendicular(&z);
    }
    let x = x.normalize();
    CompliantFrame::from_axes(origin, x, z.cross(&x), z)
}

/// Least squares for a tool point `o` (tool frame) and a base point `c` with
/// `M (R_k o + p_k − c) ≈ 0` for all samples; returns `(o, c, rms residual)`.
fn solve_point(shared: &Shared<'_>, projector: &Matrix3<f64>) -> (Vector3<f64>, Vector3<f64>, f64) {
    let mut ata = Matrix6::zeros();
    let mut atb = Vector6::zeros();
    for (r, p) in shared.rotation.iter().zip(shared.position) {
        let mut a = nalgebra::Matrix3x6::zeros();
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(&(projector * r));
        a.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-projector));
        let b = -(projector * p);
        ata += a.transpose() * a;
        atb += a.transpose() * b;
    }
    let ridge = 1e-9 * ata.trace() / 6.0 + 1e-12;
    for i in 0..6 {
        ata[(i, i)] += ridge;
    }
    let solution = ata.cholesky().map(|c| c.solve(&atb)).unwrap_or_else(Vector6::zeros);
    let o = Vector3::new(solution[0], solution[1], solution[2]);
    let c = Vector3::new(solution[3], solution[4], solution[5]);
    let residual = rms(shared
        .rotation
        .iter()
        .zip(shared.position)
        .map(|(r, p)| (projector * (r * o + p - c)).norm()));
    (o, c, residual)
}

/// Point-on-plane: a tool point `o` with `n·(R_k o + p_k) = d`, by alternating the plane fit
/// (principal components of the moved points) and the linear solve for `(o, d)`.
fn point_on_plane(shared: &Shared<'_>, line_tolerance_m: f64) -> (Vector3<f64>, Vector3<f64>, f64, Vector3<f64>) {
    let mut o = Vector3::zeros();
    let mut normal = shared.pos_eig.1[2];
    for _ in 0..10 {
        let points: Vec<Vector3<f64>> = shared
            .rotation
            .iter()
            .zip(shared.position)
            .map(|(r, p)| r * o + p)
            .collect();
        let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
        let cov = points
            .iter()
            .map(|p| (p - centroid) * (p - centroid).transpose())
            .sum::<Matrix3<f64>>()
            / points.len() as f64;
        normal = plane_normal(&eigen_sorted(cov), shared.applied, line_tolerance_m);
        let mut ata = nalgebra::Matrix4::zeros();
        let mut atb = Vector4::zeros();
        for (r, p) in shared.rotation.iter().zip(shared.position) {
            let nr = r.transpose() * normal;
            let a = Vector4::new(nr.x, nr.y, nr.z, -1.0);
            ata += a * a.transpose();
            atb += a * (-normal.dot(p));
        }
        let ridge = 1e-6 * ata.trace() / 4.0 + 1e-12;
        for i in 0..3 {
            ata[(i, i)] += ridge;
        }
        match ata.cholesky() {
            Some(c) => {
                let s = c.solve(&atb);
                o = Vector3::new(s[0], s[1], s[2]);
            }
            None => break,
        }
    }
    let points: Vec<Vector3<f64>> = shared
        .rotation
        .iter()
        .zip(shared.position)
        .map(|(r, p)| r * o + p)
        .collect();
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let residual = rms(points.iter().map(|p| normal.dot(&(p - centroid))));
    let main = eigen_sorted(points.iter().map(|p| (p - centroid) * (p - centroid).transpose()).sum()).1[0];
    (normal, centroid, residual, main)
}

/// The plane normal from the principal directions `(values, vectors)` of a point cloud. When the
/// points lie along a line (`√λ₂ < line_tolerance_m`) geometry leaves the normal free to turn
/// about the line; then the normal is the mean applied force made perpendicular to the line,
/// if there is contact.
fn plane_normal(
    eig: &([f64; 3], [Vector3<f64>; 3]),
    applied: Option<Vector3<f64>>,
    line_tolerance_m: f64,
) -> Vector3<f64> {
    let ([_, l2, _], [e1, _, e3]) = *eig;
    if l2.sqrt() < line_tolerance_m {
        if let Some(f) = applied {
            let perpendicular = f - e1 * e1.dot(&f);
            if perpendicular.norm() > 1e-9 {
                return perpendicular.normalize();
            }
        }
    }
    e3
}

/// `1 − mean(|F_free| / |F|)` over samples in contact (1 when nothing is in contact or free).
fn force_agreement(force_n: &[Vector3<f64>], free: &[Vector3<f64>], threshold_n: f64) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for f in force_n {
        let norm = f.norm();
        if norm >= threshold_n {
            let along: f64 = free.iter().map(|d| d.dot(f).powi(2)).sum::<f64>().sqrt();
            sum += along / norm;
            count += 1;
        }
    }
    if count == 0 || free.is_empty() {
        1.0
    } else {
        1.0 - sum / count as f64
    }
}

/// Orients `normal` into the surface: along the applied force, or downwards without contact.
fn into_surface(normal: Vector3<f64>, applied: Option<Vector3<f64>>) -> Vector3<f64> {
    let reference = applied.unwrap_or(-Vector3::z());
    if normal.dot(&reference) < 0.0 {
        -normal
    } else {
        normal
    }
}

fn along_travel(axis: Vector3<f64>, travel: &Vector3<f64>) -> Vector3<f64> {
    if axis.dot(travel) < 0.0 {
        -axis
    } else {
        axis
    }
}

/// Fits every candidate model to a segment's tool poses and forces and chooses the best.
///
/// `position_m` and `orientation` are the tool pose in the base frame, `force_n` the measured
/// force (environment on tool), all of equal length (at least 5 samples).
pub fn fit_constraints(
    position_m: &[Vector3<f64>],
    orientation: &[UnitQuaternion<f64>],
    force_n: &[Vector3<f64>],
    config: &ConstraintConfig,
) -> Result<ConstraintReport, ConstraintError> {
    let n = position_m.len();
    if orientation.len() != n {
        return Err(ConstraintError::LengthMismatch {
            what: "orientation",
            expected: n,
            found: orientation.len(),
        });
    }
    if force_n.len() != n {
        return Err(ConstraintError::LengthMismatch {
            what: "force_n",
            expected: n,
            found: force_n.len(),
        });
    }
    if n < 5 {
        return Err(ConstraintError::TooFewSamples { found: n, required: 5 });
    }
    for index in 0..n {
        let finite = position_m[index]
            .iter()
            .chain(orientation[index].coords.iter())
            .chain(force_n[index].iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(ConstraintError::NonFinite { what: "segment", index });
        }
    }
    for (name, value) in [
        ("position_tolerance_m", config.position_tolerance_m),
        ("rotation_tolerance_rad", config.rotation_tolerance_rad),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(ConstraintError::InvalidConfig {
                name,
                reason: "must be a positive number".to_owned(),
            });
        }
    }
    if config.candidates.is_empty() {
        return Err(ConstraintError::InvalidConfig {
            name: "candidates",
            reason: "give at least one model".to_owned(),
        });
    }

    let centroid = position_m.iter().sum::<Vector3<f64>>() / n as f64;
    let cov = position_m
        .iter()
        .map(|p| (p - centroid) * (p - centroid).transpose())
        .sum::<Matrix3<f64>>()
        / n as f64;
    let reference = orientation[0];
    let mean_coords = orientation
        .iter()
        .map(|q| {
            if q.coords.dot(&reference.coords) < 0.0 {
                -q.coords
            } else {
                q.coords
            }
        })
        .sum::<Vector4<f64>>();
    let mean_q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::from(mean_coords));
    let rotvec: Vec<Vector3<f64>> = orientation.iter().map(|q| quat_error(&mean_q, q)).collect();
    let rot_moment = rotvec.iter().map(|r| r * r.transpose()).sum::<Matrix3<f64>>() / n as f64;
    let (rot_values, rot_vectors) = eigen_sorted(rot_moment);
    let contact: Vec<Vector3<f64>> = force_n
        .iter()
        .filter(|f| f.norm() >= config.contact_threshold_n)
        .map(|f| -f)
        .collect();
    let applied = (!contact.is_empty()).then(|| contact.iter().sum::<Vector3<f64>>() / contact.len() as f64);
    let shared = Shared {
        position: position_m,
        rotation: orientation
            .iter()
            .map(|q| q.to_rotation_matrix().into_inner())
            .collect(),
        rotvec,
        centroid,
        pos_eig: eigen_sorted(cov),
        rot_axis: rot_vectors[0],
        rot_rms: rot_values.iter().sum::<f64>().sqrt(),
        applied,
        travel: position_m[n - 1] - position_m[0],
    };
    let fits: Vec<ConstraintFit> = config
        .candidates
        .iter()
        .map(|&kind| fit_one(&shared, kind, force_n, config))
        .collect();
    let best = choose(&fits);
    Ok(ConstraintReport { best, fits })
}

fn choose(fits: &[ConstraintFit]) -> usize {
    let accepted = fits
        .iter()
        .enumerate()
        .filter(|(_, fit)| fit.accepted)
        .min_by(|(_, a), (_, b)| {
            a.kind
                .dof()
                .cmp(&b.kind.dof())
                .then(b.force_agreement.total_cmp(&a.force_agreement))
                .then(a.score.total_cmp(&b.score))
        });
    match accepted {
        Some((idx, _)) => idx,
        None => fits
            .iter()
            .enumerate()
            .min_by(|(_, a), (_, b)| a.score.total_cmp(&b.score))
            .map_or(0, |(idx, _)| idx),
    }
}

fn off_axis_rms(rotvec: &[Vector3<f64>], axis: &Vector3<f64>) -> f64 {
    rms(rotvec.iter().map(|r| (r - axis * axis.dot(r)).norm()))
}

fn fit_one(
    shared: &Shared<'_>,
    kind: ConstraintKind,
    force_n: &[Vector3<f64>],
    config: &ConstraintConfig,
) -> ConstraintFit {
    let ([_, l2, l3], [e1, _, _]) = shared.pos_eig;
    // Motion closer to a line than this leaves a plane's normal to the force direction.
    let line_tolerance = 5.0 * config.position_tolerance_m;
    let applied_dir = shared.applied.filter(|f| f.norm() > 1e-12).map(|f| f.normalize());
    let (residual_m, residual_rad, free, axis, point, frame) = match kind {
        ConstraintKind::Planar => {
            let normal = into_surface(
                plane_normal(&shared.pos_eig, shared.applied, line_tolerance),
                shared.applied,
            );
            let across = normal.cross(&e1).normalize();
            let x = along_travel(e1, &shared.travel);
            let frame = frame_from(shared.centroid, normal, x);
            (
                rms(shared.position.iter().map(|p| normal.dot(&(p - shared.centroid)))),
                off_axis_rms(&shared.rotvec, &normal),
                vec![e1, across],
                Some(normal),
                shared.centroid,
                frame,
            )
        }
        ConstraintKind::PointOnPlane => {
            let (normal, centroid, residual, main) = point_on_plane(shared, line_tolerance);
            let normal = into_surface(normal, shared.applied);
            let frame = frame_from(centroid, normal, along_travel(main, &shared.travel));
            let in_plane = [perpendicular(&normal), normal.cross(&perpendicular(&normal))];
            (residual, 0.0, in_plane.to_vec(), Some(normal), centroid, frame)
        }
        ConstraintKind::Prismatic => {
            let x = along_travel(e1, &shared.travel);
            let z_hint = applied_dir
                .map(|f| f - x * x.dot(&f))
                .filter(|z| z.norm() > 1e-6)
                .unwrap_or_else(|| perpendicular(&x));
            let z = z_hint.normalize();
            let frame = CompliantFrame::from_axes(shared.centroid, x, z.cross(&x), z);
            (
                (l2 + l3).sqrt(),
                rms(shared.rotvec.iter().map(|r| r.norm())),
                vec![x],
                Some(x),
                shared.centroid,
                frame,
            )
        }
        ConstraintKind::ConcentricCylinder => {
            let axis = if shared.rot_rms > 2.0 * config.rotation_tolerance_rad {
                shared.rot_axis
            } else {
                e1
            };
            let axis = along_travel(axis, &shared.travel);
            let projector = Matrix3::identity() - axis * axis.transpose();
            let (_, c, residual) = solve_point(shared, &projector);
            let origin = c + axis * axis.dot(&(shared.centroid - c));
            let frame = frame_from(origin, axis, shared.centroid - origin);
            (
                residual,
                off_axis_rms(&shared.rotvec, &axis),
                vec![axis],
                Some(axis),
                origin,
                frame,
            )
        }
        ConstraintKind::AxialRotation => {
            let n = shared.rotvec.len();
            let axis = along_travel(shared.rot_axis, &(shared.rotvec[n - 1] - shared.rotvec[0]));
            let (_, c, residual) = solve_point(shared, &Matrix3::identity());
            let origin = c + axis * axis.dot(&(shared.centroid - c));
            let frame = frame_from(origin, axis, shared.centroid - origin);
            (
                residual,
                off_axis_rms(&shared.rotvec, &axis),
                vec![],
                Some(axis),
                origin,
                frame,
            )
        }
        ConstraintKind::FixedPoint => {
            let (_, c, residual) = solve_point(shared, &Matrix3::identity());
            let frame = CompliantFrame::z_aligned(c, &applied_dir.unwrap_or_else(Vector3::z));
            (residual, 0.0, vec![], None, c, frame)
        }
    };
    let force_agreement = force_agreement(force_n, &free, config.contact_threshold_n);
    let accepted = residual_m <= config.position_tolerance_m && residual_rad <= config.rotation_tolerance_rad;
    let score = (residual_m / config.position_tolerance_m).powi(2)
        + (residual_rad / config.rotation_tolerance_rad).powi(2)
        + (1.0 - force_agreement);
    ConstraintFit {
        kind,
        residual_m,
        residual_rad,
        force_agreement,
        accepted,
        score,
        axis,
        point_m: point,
        frame,
    }
}

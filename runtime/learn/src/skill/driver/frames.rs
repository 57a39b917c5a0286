//! Learning a plan's compliant frames: constraint fits, force-aligned frames (per sample or at
//! a point) and literal frames.

use nalgebra::{Isometry3, Vector3};
use skill_ir as ir;

use super::smoothing::{smooth_points, smoothing_window};
use super::{LearnError, Learner, CONTACT_N};
use crate::constraint::{
    fit_constraints, force_aligned_frame_at, force_aligned_frames, CompliantFrame, ConstraintConfig, ConstraintKind,
    ForceFrameConfig,
};
use crate::skill::learned::{ConstraintQuality, FrameKind, FramePose, LearnedFrame, NormalCheck};

/// Per-sample frames are stored every this many seconds.
const FRAME_SAMPLE_PERIOD_S: f64 = 0.01;

/// The friction coefficient the normal check assumes unless told otherwise: a cloth, sponge,
/// rubber or plastic tip on a hard surface ranges from 0.3 to 0.8, and 0.5 bounds the contact
/// force's lean from the surface normal at `atan 0.5 = 26.6°` (docs/method.md §4).
pub const DEFAULT_FRICTION_MU: f64 = 0.5;

impl Learner<'_> {
    pub(super) fn frame(&mut self, decl: &ir::FrameDecl) -> Result<LearnedFrame, LearnError> {
        let demo = self.demo;
        let wrap = |source| LearnError::Frame {
            name: decl.name.clone(),
            source,
        };
        Ok(match &decl.source {
            ir::FrameSource::Constraint { segment, candidates } => {
                let range = self.seg(*segment).range();
                let config = ConstraintConfig::from_candidates(candidates);
                let report = fit_constraints(
                    &demo.position_m[range.clone()],
                    &demo.orientation[range.clone()],
                    &demo.force_n[range],
                    &config,
                )
                .map_err(wrap)?;
                let chosen = report.chosen();
                self.quality.constraints.insert(
                    decl.name.clone(),
                    report
                        .fits
                        .iter()
                        .enumerate()
                        .map(|(index, fit)| ConstraintQuality {
                            kind: fit.kind.into(),
                            residual_m: fit.residual_m,
                            residual_rad: fit.residual_rad,
                            force_agreement: fit.force_agreement,
                            chosen: index == report.best,
                        })
                        .collect(),
                );
                let mut frame = chosen.frame;
                let mut following = None;
                if matches!(chosen.kind, ConstraintKind::Planar | ConstraintKind::PointOnPlane) {
                    let warned = self.warnings.len();
                    if let Some((mut check, checked)) = self.check_normal(&decl.name, segment.index(), &frame) {
                        frame = checked;
                        if chosen.kind == ConstraintKind::Planar {
                            // A plane fitted to strokes over a curved part (a fender) holds one
                            // normal where the surface has many: follow the measured one.
                            let range = self.seg(*segment).range();
                            let normals = measured_normals(
                                &demo.t_s[range.clone()],
                                &demo.position_m[range.clone()],
                                &demo.force_n[range.clone()],
                            );
                            let spread = normal_spread(&normals, &demo.position_m[range.clone()]);
                            check.spread_deg = spread.map(|s| s.about_mean_rad.to_degrees());
                            check.unexplained_deg = spread.map(|s| s.about_shape_rad.to_degrees());
                            if spread.is_some_and(NormalSpread::curved) {
                                // The plane is not the surface: its check's warning (a normal
                                // outside the friction cone) is about a frame not learned.
                                self.warnings.truncate(warned);
                                check.follows_surface = true;
                                following = Some(surface_frames(
                                    &demo.t_s[range.clone()],
                                    &demo.position_m[range],
                                    &normals,
                                    &frame,
                                ));
                            }
                        }
                        self.quality.normals.insert(decl.name.clone(), check);
                    }
                }
                match following {
                    Some(poses) => LearnedFrame::Samples(poses),
                    None => {
                        let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                        LearnedFrame::Constant(FramePose::from_isometry(chosen.kind.into(), &pose, None))
                    }
                }
            }
            ir::FrameSource::ForceAlignedSamples { segment } => {
                let seg = self.seg(*segment);
                let range = seg.range();
                let normal_force = without_friction(
                    &demo.t_s[range.clone()],
                    &demo.position_m[range.clone()],
                    &demo.force_n[range.clone()],
                );
                let frames = force_aligned_frames(&normal_force, &demo.position_m[range], &ForceFrameConfig::default())
                    .map_err(wrap)?;
                let t0 = demo.t_s[seg.start];
                let mut poses = Vec::new();
                let mut next_t = 0.0;
                for (offset, frame) in frames.iter().enumerate() {
                    let t = demo.t_s[seg.start + offset] - t0;
                    if t + 1e-9 >= next_t || offset + 1 == frames.len() {
                        let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                        poses.push(FramePose::from_isometry(FrameKind::ForceAligned, &pose, Some(t)));
                        next_t = t + FRAME_SAMPLE_PERIOD_S;
                    }
                }
                LearnedFrame::Samples(poses)
            }
            ir::FrameSource::ForceAlignedAt { point } => {
                let index = self.point(*point);
                // The force of the first in-contact window, not of one sample: at a contact's
                // onset one sample's force is mostly noise (docs/method.md §4).
                let frame = match super::phases::window_force(demo, self.phases, index) {
                    Some((mean, report)) => {
                        self.quality.onset_frames.insert(decl.name.clone(), report);
                        force_aligned_frame_at(
                            &[mean],
                            &demo.position_m[index..=index],
                            0,
                            &ForceFrameConfig::default(),
                        )
                    }
                    None => {
                        force_aligned_frame_at(&demo.force_n, &demo.position_m, index, &ForceFrameConfig::default())
                    }
                }
                .map_err(wrap)?;
                let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
                LearnedFrame::Constant(FramePose::from_isometry(FrameKind::ForceAligned, &pose, None))
            }
            ir::FrameSource::Fixed {
                origin_m,
                quaternion_wxyz,
            } => LearnedFrame::Constant(FramePose {
                kind: FrameKind::Fixed,
                origin: *origin_m,
                quaternion_wxyz: *quaternion_wxyz,
                t_s: None,
            }),
        })
    }
}

impl Learner<'_> {
    /// Checks a fitted plane's normal against the mean applied force over its segment's
    /// samples in contact (docs/method.md §4). Within the friction cone (`atan µ`) the frame is
    /// kept; beyond it the force cannot have come from that surface, and z is replaced by the
    /// direction of the mean applied force without its friction ([`steady_friction`]), x kept
    /// as near as possible. `None` when no sample of the segment is in contact.
    fn check_normal(
        &mut self,
        name: &str,
        segment: usize,
        frame: &CompliantFrame,
    ) -> Option<(NormalCheck, CompliantFrame)> {
        let demo = self.demo;
        let range = self.segments[segment].range();
        let contact: Vec<usize> = range.clone().filter(|&k| demo.force_n[k].norm() >= CONTACT_N).collect();
        if contact.is_empty() {
            return None;
        }
        let applied: Vector3<f64> = -contact.iter().map(|&k| demo.force_n[k]).sum::<Vector3<f64>>();
        let direction = applied.try_normalize(1e-12)?;
        let z = frame.z_axis();
        let angle = z.dot(&direction).clamp(-1.0, 1.0).acos();
        let cone = self.friction_mu.atan();
        let (friction, normal_force) = steady_friction(
            &demo.t_s[range.clone()],
            &demo.position_m[range.clone()],
            &demo.force_n[range.clone()],
        );
        let mut check = NormalCheck {
            segment: segment + 1,
            fitted_z: z.into(),
            force_direction: direction.into(),
            angle_deg: angle.to_degrees(),
            cone_deg: cone.to_degrees(),
            friction,
            replaced: false,
            spread_deg: None,
            unexplained_deg: None,
            follows_surface: false,
        };
        if angle <= cone {
            return Some((check, *frame));
        }
        let free: Vector3<f64> = -contact
            .iter()
            .map(|&k| normal_force[k - range.start])
            .sum::<Vector3<f64>>();
        let new_z = free.try_normalize(1e-12).unwrap_or(direction);
        let x = frame.x_axis();
        let replaced = match (x - new_z * x.dot(&new_z)).try_normalize(1e-6) {
            Some(new_x) => CompliantFrame::from_axes(frame.origin_m, new_x, new_z.cross(&new_x), new_z),
            None => CompliantFrame::z_aligned(frame.origin_m, &new_z),
        };
        check.replaced = true;
        let v = |a: &Vector3<f64>| format!("[{:+.3}, {:+.3}, {:+.3}]", a.x, a.y, a.z);
        self.warnings.push(format!(
            "frame `{name}`: the normal {} fitted to segment {} is {:.1}° from the mean applied force {} there, outside the friction cone ({:.1}° at µ = {}): a force along it would be {:.0} % short, so z follows the applied force without friction (µ ≈ {friction:.2}) {} instead (if the surface is flat and the forces are suspect, check their frame and sign, or allow more friction with --friction)",
            v(&z),
            segment + 1,
            angle.to_degrees(),
            v(&direction),
            cone.to_degrees(),
            self.friction_mu,
            100.0 * (1.0 - angle.cos()),
            v(&new_z),
        ));
        Some((check, replaced))
    }
}

/// A plane's segment is a curved surface when the measured contact normal turns farther than
/// this about its mean direction while the tool slides (90th percentile) \[rad\] (10°), and
/// the path's shape explains it ([`NormalSpread::curved`]): on the shipped flat wipes and
/// slides and on tilted tables it turns 1.3-1.5° (the hand's tremor and the sensor's noise),
/// across a fender's crown 19° for a ±20° arc and more for wider ones.
const CURVED_SPREAD_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// The slowest slide whose force says where the surface's normal is \[m/s\]: at rest friction
/// may point anywhere in the tangent plane, and near a reversal or at touch-down the smoothed
/// velocity's direction lags the slide's, so friction leaks into the estimate (9-13° of error
/// at 10 mm/s on generated fenders, under 3° from 30 mm/s).
const MIN_SLIDE_MPS: f64 = 0.03;

/// The measured normals are averaged over this long \[s\]: a period of the hand's 8-12 Hz
/// tremor, 5-10 mm of stroke at 5-10 cm/s.
const NORMAL_WINDOW_S: f64 = 0.1;

/// The direction the tool pushes the surface along at each sample (unit, base frame, into the
/// surface), its friction taken out along the velocity and averaged over [`NORMAL_WINDOW_S`];
/// `None` where the tool pushes less than [`CONTACT_N`] or slides slower than
/// [`MIN_SLIDE_MPS`]. On any surface the tool slides along the tangent plane and friction acts
/// against the slide, so what is left is the normal force (and a hand's sideways lean).
fn measured_normals(t: &[f64], position: &[Vector3<f64>], force: &[Vector3<f64>]) -> Vec<Option<Vector3<f64>>> {
    let n = position.len();
    let smoothed = smooth_points(position, smoothing_window(t));
    let pushing: Vec<Option<Vector3<f64>>> = (0..n)
        .map(|k| {
            let velocity = central_velocity(t, &smoothed, k);
            let speed = velocity.norm();
            (speed >= MIN_SLIDE_MPS && force[k].norm() >= CONTACT_N).then(|| {
                let along = velocity / speed;
                -(force[k] - along * force[k].dot(&along))
            })
        })
        .collect();
    // Prefix sums of the valid samples' directions, for a centred window in time.
    let mut sums = Vec::with_capacity(n + 1);
    let mut total = Vector3::zeros();
    sums.push(total);
    for push in &pushing {
        if let Some(direction) = push.and_then(|p| p.try_normalize(1e-12)) {
            total += direction;
        }
        sums.push(total);
    }
    let half = NORMAL_WINDOW_S / 2.0;
    (0..n)
        .map(|k| {
            pushing[k]?;
            let a = t.partition_point(|&s| s < t[k] - half);
            let b = t.partition_point(|&s| s <= t[k] + half);
            (sums[b] - sums[a]).try_normalize(1e-12)
        })
        .collect()
}

/// How far the measured normals of a segment turn, and how much of it the surface's shape
/// explains.
#[derive(Debug, Clone, Copy)]
struct NormalSpread {
    /// The 90th percentile of their angle from their mean direction \[rad\].
    about_mean_rad: f64,
    /// The 90th percentile of their angle from the normal of a quadric fitted to the tool's
    /// path (heights along the mean normal over the plane across it) \[rad\].
    about_shape_rad: f64,
}

impl NormalSpread {
    /// A curved surface: the normal turns by more than [`CURVED_SPREAD_RAD`], and the path's
    /// own shape explains at least half of that turn. A hand that leans while wiping a flat
    /// part turns the force but not the path (the LASA rim demonstrations turn 11-24°, their
    /// paths explain little of it); a fender's crown turns both.
    fn curved(self) -> bool {
        self.about_mean_rad > CURVED_SPREAD_RAD && self.about_shape_rad < 0.5 * self.about_mean_rad
    }
}

/// How far `normals` turn (see [`NormalSpread`]), over the tool positions `position` they were
/// measured at; `None` with fewer than 20 normals or a path the quadric cannot be fitted to (a
/// line).
fn normal_spread(normals: &[Option<Vector3<f64>>], position: &[Vector3<f64>]) -> Option<NormalSpread> {
    let valid: Vec<(Vector3<f64>, Vector3<f64>)> = normals
        .iter()
        .zip(position)
        .filter_map(|(n, p)| n.map(|n| (n, *p)))
        .collect();
    if valid.len() < 20 {
        return None;
    }
    let mean = valid
        .iter()
        .map(|(n, _)| n)
        .sum::<Vector3<f64>>()
        .try_normalize(1e-12)?;
    let about_mean_rad = percentile_90(valid.iter().map(|(n, _)| n.angle(&mean)).collect());
    // The path's heights along the mean normal, fitted by least squares about the path's
    // centroid over its principal directions s (the longest) and w in the tangent plane: a
    // quadric h = a + b s + c w + d s² + e s w + f w² where the path covers an area (a circular
    // wipe), else h = a + b s + c w + d s² (back-and-forth strokes cover a band: a curvature
    // across it would be fitted to the hand's sideways bow).
    let any = mean
        .cross(&Vector3::x())
        .try_normalize(1e-3)
        .unwrap_or_else(|| mean.cross(&Vector3::y()).normalize());
    let other = mean.cross(&any);
    let centre = valid.iter().map(|(_, p)| p).sum::<Vector3<f64>>() / valid.len() as f64;
    let mut spread = nalgebra::Matrix2::<f64>::zeros();
    for (_, p) in &valid {
        let d = nalgebra::Vector2::new((p - centre).dot(&any), (p - centre).dot(&other));
        spread += d * d.transpose();
    }
    let eigen = spread.symmetric_eigen();
    let (major, minor) = if eigen.eigenvalues[0] >= eigen.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let along = |k: usize| (any * eigen.eigenvectors[(0, k)] + other * eigen.eigenvectors[(1, k)]).normalize();
    let (s_axis, w_axis) = (along(major), along(minor));
    let area = eigen.eigenvalues[minor].max(0.0) > 0.09 * eigen.eigenvalues[major].max(0.0);
    let terms = |d: &Vector3<f64>| {
        let (s, w) = (d.dot(&s_axis), d.dot(&w_axis));
        let (sw, ww) = if area { (s * w, w * w) } else { (0.0, 0.0) };
        nalgebra::SVector::<f64, 6>::new(1.0, s, w, s * s, sw, ww)
    };
    let mut normal_matrix = nalgebra::SMatrix::<f64, 6, 6>::zeros();
    let mut rhs = nalgebra::SVector::<f64, 6>::zeros();
    for (_, p) in &valid {
        let d = p - centre;
        let row = terms(&d);
        normal_matrix += row * row.transpose();
        rhs += row * d.dot(&mean);
    }
    if !area {
        // The two unused terms: keep the system regular, their coefficients zero.
        normal_matrix[(4, 4)] = 1.0;
        normal_matrix[(5, 5)] = 1.0;
    }
    let c = normal_matrix.cholesky()?.solve(&rhs);
    let about_shape_rad = percentile_90(
        valid
            .iter()
            .map(|(n, p)| {
                let d = p - centre;
                let (s, w) = (d.dot(&s_axis), d.dot(&w_axis));
                let (fs, fw) = (c[1] + 2.0 * c[3] * s + c[4] * w, c[2] + c[4] * s + 2.0 * c[5] * w);
                // Into the surface: the surface h = f lies on the side the tool pushes towards.
                let shaped = (mean - s_axis * fs - w_axis * fw).normalize();
                n.angle(&shaped)
            })
            .collect(),
    );
    Some(NormalSpread {
        about_mean_rad,
        about_shape_rad,
    })
}

/// The 90th percentile of `values` (not empty).
fn percentile_90(mut values: Vec<f64>) -> f64 {
    let at = ((values.len() * 9) / 10).min(values.len() - 1);
    let (_, p90, _) = values.select_nth_unstable_by(at, f64::total_cmp);
    *p90
}

/// A frame per [`FRAME_SAMPLE_PERIOD_S`] over a curved segment: z along the measured normal
/// (held where the tool does not slide, the first one before it does), x the plane's x turned
/// into the tangent plane, timed from the segment's start.
fn surface_frames(
    t: &[f64],
    position: &[Vector3<f64>],
    normals: &[Option<Vector3<f64>>],
    plane: &CompliantFrame,
) -> Vec<FramePose> {
    let mut held = normals
        .iter()
        .flatten()
        .next()
        .copied()
        .unwrap_or_else(|| plane.z_axis());
    let x = plane.x_axis();
    let mut poses = Vec::new();
    let mut next_t = 0.0;
    for k in 0..t.len() {
        if let Some(normal) = normals[k] {
            held = normal;
        }
        let at = t[k] - t[0];
        if at + 1e-9 >= next_t || k + 1 == t.len() {
            let frame = match (x - held * x.dot(&held)).try_normalize(1e-6) {
                Some(x) => CompliantFrame::from_axes(position[k], x, held.cross(&x), held),
                None => CompliantFrame::z_aligned(position[k], &held),
            };
            let pose = Isometry3::from_parts(frame.origin_m.into(), frame.orientation);
            poses.push(FramePose::from_isometry(FrameKind::Planar, &pose, Some(at)));
            next_t = at + FRAME_SAMPLE_PERIOD_S;
        }
    }
    poses
}

/// The friction coefficient of a segment and its forces without that friction.
///
/// A surface pushes perpendicular to the motion whatever its shape, and friction pushes
/// against the motion in proportion to the normal force. So where the tool slides (faster than
/// 5 mm/s, force at least 1 N) the force's component along the direction of travel over its
/// component across it estimates −µ; the median over the segment is the steady friction
/// (clamped at 0: a force leaning *along* the motion is not friction, and is kept). The force
/// without friction adds `µ |f⊥| v̂` back to each sliding sample. Unlike removing everything
/// along the motion, this leaves a force that leans sideways (the disagreement the normal
/// check is about) as it is, wherever the path turns.
fn steady_friction(t: &[f64], position: &[Vector3<f64>], force: &[Vector3<f64>]) -> (f64, Vec<Vector3<f64>>) {
    let n = position.len();
    let smoothed = smooth_points(position, smoothing_window(t));
    let direction: Vec<Option<Vector3<f64>>> = (0..n)
        .map(|k| {
            let velocity = central_velocity(t, &smoothed, k);
            (velocity.norm() >= 0.005 && force[k].norm() >= CONTACT_N).then(|| velocity.normalize())
        })
        .collect();
    let mut ratios: Vec<f64> = (0..n)
        .filter_map(|k| {
            let along = direction[k]?;
            let tangential = force[k].dot(&along);
            let across = (force[k] - along * tangential).norm();
            (across > 0.0).then(|| -tangential / across)
        })
        .collect();
    let friction = if ratios.is_empty() {
        0.0
    } else {
        let mid = ratios.len() / 2;
        let (_, median, _) = ratios.select_nth_unstable_by(mid, f64::total_cmp);
        median.max(0.0)
    };
    let free = (0..n)
        .map(|k| match direction[k] {
            Some(along) => {
                let across = (force[k] - along * force[k].dot(&along)).norm();
                force[k] + along * (friction * across)
            }
            None => force[k],
        })
        .collect();
    (friction, free)
}

/// The velocity at sample `k` by central differences of `points` (one-sided at the ends; zero
/// where the time does not advance).
fn central_velocity(t: &[f64], points: &[Vector3<f64>], k: usize) -> Vector3<f64> {
    let n = points.len();
    let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
    let dt = t[b] - t[a];
    if dt > 0.0 {
        (points[b] - points[a]) / dt
    } else {
        Vector3::zeros()
    }
}

/// The measured forces without their component along the direction of motion.
///
/// While sliding, friction tilts the contact force against the motion by up to atan(µ) (17° at
/// µ = 0.3); a frame aligned with the raw force would put its z 17° off the surface normal, and
/// position control along its x would then push into and pull off the surface. Friction acts
/// along the sliding direction, so removing the force component along the (smoothed) velocity
/// leaves the normal force. Where the tool hardly moves (below 5 mm/s) the force is kept as is.
fn without_friction(t: &[f64], position: &[Vector3<f64>], force: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let n = position.len();
    let window = smoothing_window(t);
    let smoothed = smooth_points(position, window);
    (0..n)
        .map(|k| {
            let velocity = central_velocity(t, &smoothed, k);
            let speed = velocity.norm();
            if speed < 0.005 {
                force[k]
            } else {
                let along = velocity / speed;
                force[k] - along * force[k].dot(&along)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Samples 1 ms apart of a tool stroking back and forth over `height(x)` along x (±10 cm,
    /// 16 cm/s at most) with a 5 mm sideways bow, pushing `normal(x)` (into the surface) plus tremor-like noise.
    fn strokes(
        height: impl Fn(f64) -> f64,
        normal: impl Fn(f64, f64) -> Vector3<f64>,
    ) -> (Vec<f64>, Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let mut rng = SplitMix64::new(7);
        let (mut t, mut position, mut force) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..8000 {
            let time = k as f64 * 1e-3;
            let phase = 0.5 * std::f64::consts::PI * time;
            let x = 0.1 * phase.sin();
            let y = 0.005 * (3.0 * phase).sin();
            let n = normal(x, time);
            t.push(time);
            position.push(Vector3::new(x, y, height(x)));
            // The force on the tool: the surface's push back (against `n`), 0.3 N of noise.
            force.push(-n * 8.0 + Vector3::new(rng.normal(), rng.normal(), rng.normal()) * 0.3);
        }
        (t, position, force)
    }

    #[test]
    fn a_drum_crown_is_curved_and_its_normals_are_measured() {
        // A drum of radius 0.15 m under the path, axis along y: ±42° of arc.
        let radius: f64 = 0.15;
        let (t, position, force) = strokes(
            |x| (radius * radius - x * x).sqrt(),
            |x, _| -Vector3::new(x, 0.0, (radius * radius - x * x).sqrt()).normalize(),
        );
        let normals = measured_normals(&t, &position, &force);
        let spread = normal_spread(&normals, &position).expect("enough sliding samples");
        assert!(spread.curved(), "{spread:?}");
        assert!(spread.about_mean_rad.to_degrees() > 25.0, "{spread:?}");
        // Each measured normal lies within 2° of the drum's.
        for (k, normal) in normals.iter().enumerate() {
            if let Some(normal) = normal {
                let p = position[k];
                let truth = -Vector3::new(p.x, 0.0, p.z).normalize();
                assert!(
                    normal.angle(&truth).to_degrees() < 2.0,
                    "sample {k}: {normal:?} for {truth:?}"
                );
            }
        }
    }

    #[test]
    fn a_hand_leaning_on_a_flat_part_is_not_a_curved_surface() {
        // The force leans ±20° along y in time, at 0.7 Hz; the path is a plane.
        let (t, position, force) = strokes(
            |_| 0.3,
            |_, time| {
                let lean = 20f64.to_radians() * (2.0 * std::f64::consts::PI * 0.7 * time).sin();
                Vector3::new(0.0, lean.sin(), -lean.cos())
            },
        );
        let normals = measured_normals(&t, &position, &force);
        let spread = normal_spread(&normals, &position).expect("enough sliding samples");
        assert!(spread.about_mean_rad > CURVED_SPREAD_RAD, "the force turns: {spread:?}");
        assert!(!spread.curved(), "but the path does not: {spread:?}");
    }
}

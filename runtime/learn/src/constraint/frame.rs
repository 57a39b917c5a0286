//! Compliant frames, the minimal rotation between two vectors (Möller & Hughes 1999), and
//! force-aligned frames.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::ConstraintError;

/// A compliant frame: origin and orientation in the robot base frame. Its z axis is the
/// direction along which the tool pushes (see each constructor for the other axes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CompliantFrame {
    /// Origin in the base frame (m).
    pub origin_m: Vector3<f64>,
    /// Orientation in the base frame (columns of its matrix are the frame's x, y, z axes).
    pub orientation: UnitQuaternion<f64>,
}

impl CompliantFrame {
    /// A frame from an origin and right-handed orthonormal axes.
    pub fn from_axes(origin_m: Vector3<f64>, x: Vector3<f64>, y: Vector3<f64>, z: Vector3<f64>) -> Self {
        let rotation = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
        Self {
            origin_m,
            orientation: UnitQuaternion::from_rotation_matrix(&rotation),
        }
    }

    /// The frame whose z axis is `z` (need not be unit) and whose x, y axes are the base
    /// frame's turned by the minimal rotation taking base z onto `z`.
    pub fn z_aligned(origin_m: Vector3<f64>, z: &Vector3<f64>) -> Self {
        let rotation = rotation_between(&Vector3::z(), &z.normalize());
        Self {
            origin_m,
            orientation: UnitQuaternion::from_rotation_matrix(&rotation),
        }
    }

    /// The frame's x axis in the base frame.
    pub fn x_axis(&self) -> Vector3<f64> {
        self.orientation * Vector3::x()
    }

    /// The frame's y axis in the base frame.
    pub fn y_axis(&self) -> Vector3<f64> {
        self.orientation * Vector3::y()
    }

    /// The frame's z axis in the base frame.
    pub fn z_axis(&self) -> Vector3<f64> {
        self.orientation * Vector3::z()
    }

    /// The orientation as `[w, x, y, z]`.
    pub fn quaternion_wxyz(&self) -> [f64; 4] {
        let q = self.orientation.quaternion();
        [q.w, q.i, q.j, q.k]
    }
}

/// The minimal rotation taking unit vector `from` onto unit vector `to` (Möller & Hughes 1999,
/// "Efficiently building a matrix to rotate one vector to another"). Uses the direct formula
/// when the vectors are far from parallel (`|from·to| < 0.99`) and the product of two
/// reflections otherwise, so it is exact and well conditioned for parallel and antiparallel
/// vectors alike.
pub fn rotation_between(from: &Vector3<f64>, to: &Vector3<f64>) -> Rotation3<f64> {
    let e = from.dot(to);
    let m = if e.abs() < 0.99 {
        let v = from.cross(to);
        let h = 1.0 / (1.0 + e);
        Matrix3::new(
            e + h * v.x * v.x,
            h * v.x * v.y - v.z,
            h * v.x * v.z + v.y,
            h * v.x * v.y + v.z,
            e + h * v.y * v.y,
            h * v.y * v.z - v.x,
            h * v.x * v.z - v.y,
            h * v.y * v.z + v.x,
            e + h * v.z * v.z,
        )
    } else {
        // The coordinate axis most nearly orthogonal to `from`.
        let abs = from.abs();
        let x = if abs.x < abs.y && abs.x < abs.z {
            Vector3::x()
        } else if abs.y < abs.z {
            Vector3::y()
        } else {
            Vector3::z()
        };
        let u = x - from;
        let v = x - to;
        let c1 = 2.0 / u.dot(&u);
        let c2 = 2.0 / v.dot(&v);
        let c3 = c1 * c2 * u.dot(&v);
        Matrix3::from_fn(|i, j| f64::from(u8::from(i == j)) - c1 * u[i] * u[j] - c2 * v[i] * v[j] + c3 * v[i] * u[j])
    };
    Rotation3::from_matrix_unchecked(m)
}

/// Parameters of force-aligned frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ForceFrameConfig {
    /// Below this force magnitude (N) the direction is not trusted and the last valid frame is held.
    pub min_force_n: f64,
    /// Forces are averaged over this many samples (centred) before taking the direction.
    pub smoothing_samples: usize,
}

impl Default for ForceFrameConfig {
    fn default() -> Self {
        Self {
            min_force_n: 1.0,
            smoothing_samples: 1,
        }
    }
}

fn check_inputs(force_n: &[Vector3<f64>], position_m: &[Vector3<f64>]) -> Result<(), ConstraintError> {
    if force_n.len() != position_m.len() {
        return Err(ConstraintError::LengthMismatch {
            what: "force_n",
            expected: position_m.len(),
            found: force_n.len(),
        });
    }
    if force_n.is_empty() {
        return Err(ConstraintError::TooFewSamples { found: 0, required: 1 });
    }
    for (index, (f, p)) in force_n.iter().zip(position_m).enumerate() {
        if !(f.iter().all(|v| v.is_finite()) && p.iter().all(|v| v.is_finite())) {
            return Err(ConstraintError::NonFinite {
                what: "force_n or position_m",
                index,
            });
        }
    }
    Ok(())
}

fn smoothed(force_n: &[Vector3<f64>], index: usize, half: usize) -> Vector3<f64> {
    let (a, b) = (index.saturating_sub(half), (index + half + 1).min(force_n.len()));
    force_n[a..b].iter().sum::<Vector3<f64>>() / (b - a) as f64
}

/// One force-aligned frame per sample: origin at the tool position, z along the force the tool
/// applies (`−force_n`, since the sensor measures the environment's force on the tool), x and y
/// by the minimal rotation from the base frame. Where the force is below `min_force_n` the last
/// valid frame is held (before the first valid sample, the first valid orientation is used).
pub fn force_aligned_frames(
    force_n: &[Vector3<f64>],
    position_m: &[Vector3<f64>],
    config: &ForceFrameConfig,
) -> Result<Vec<CompliantFrame>, ConstraintError> {
    check_inputs(force_n, position_m)?;
    let half = config.smoothing_samples / 2;
    let mut orientations: Vec<Option<UnitQuaternion<f64>>> = Vec::with_capacity(force_n.len());
    let mut held = None;
    let mut peak: f64 = 0.0;
    for index in 0..force_n.len() {
        let applied = -smoothed(force_n, index, half);
        peak = peak.max(applied.norm());
        if applied.norm() >= config.min_force_n {
            held = Some(CompliantFrame::z_aligned(Vector3::zeros(), &applied).orientation);
        }
        orientations.push(held);
    }
    let first = orientations
        .iter()
        .flatten()
        .next()
        .copied()
        .ok_or(ConstraintError::NoContact {
            peak_n: peak,
            threshold_n: config.min_force_n,
        })?;
    Ok(orientations
        .into_iter()
        .zip(position_m)
        .map(|(q, p)| CompliantFrame {
            origin_m: *p,
            orientation: q.unwrap_or(first),
        })
        .collect())
}

/// The force-aligned frame at sample `index` (e.g. the touch point at a segment boundary), with
/// the force averaged over `config.smoothing_samples` around it; if that force is too small,
/// the nearest earlier valid frame is used, else the nearest later one.
pub fn force_aligned_frame_at(
    force_n: &[Vector3<f64>],
    position_m: &[Vector3<f64>],
    index: usize,
    config: &ForceFrameConfig,
) -> Result<CompliantFrame, ConstraintError> {
    check_inputs(force_n, position_m)?;
    if index >= force_n.len() {
        return Err(ConstraintError::LengthMismatch {
            what: "index",
            expected: force_n.len(),
            found: index,
        });
    }
    let half = config.smoothing_samples / 2;
    let valid = |k: usize| {
        let applied = -smoothed(force_n, k, half);
        (applied.norm() >= config.min_force_n).then_some(applied)
    };
    let found = (0..=index)
        .rev()
        .find_map(valid)
        .or_else(|| (index + 1..force_n.len()).find_map(valid));
    match found {
        Some(applied) => Ok(CompliantFrame::z_aligned(position_m[index], &applied)),
        None => {
            let peak = force_n.iter().map(|f| f.norm()).fold(0.0, f64::max);
            Err(ConstraintError::NoContact {
                peak_n: peak,
                threshold_n: config.min_force_n,
            })
        }
    }
}

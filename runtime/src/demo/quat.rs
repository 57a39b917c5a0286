//! Quaternion sign continuity.

use nalgebra::UnitQuaternion;

/// Negates quaternions so that each lies in the same hemisphere as its predecessor
/// (`q[k]·q[k-1] ≥ 0`) and returns the indices it negated. The first sample keeps its sign.
pub(crate) fn make_continuous(orientation: &mut [UnitQuaternion<f64>]) -> Vec<usize> {
    let mut flipped = Vec::new();
    for idx in 1..orientation.len() {
        if orientation[idx].coords.dot(&orientation[idx - 1].coords) < 0.0 {
            orientation[idx] = UnitQuaternion::new_unchecked(-orientation[idx].into_inner());
            flipped.push(idx);
        }
    }
    flipped
}

//! Quaternion sign continuity, and the warnings every demonstration reader raises about the
//! orientations it read (normalised, negated).

use nalgebra::UnitQuaternion;

use super::DemoWarning;

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

/// The quaternions a reader normalised: how many, the first one's row and the largest norm
/// error. A reader calls [`Normalised::note`] with each raw quaternion's norm.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Normalised {
    count: usize,
    first_row: usize,
    max_deviation: f64,
}

impl Normalised {
    /// Records a quaternion of norm `norm` read at `row` (normalised when its norm differs from
    /// 1 by more than `1e-6`).
    pub fn note(&mut self, norm: f64, row: usize) {
        let deviation = (norm - 1.0).abs();
        if deviation > 1e-6 {
            if self.count == 0 {
                self.first_row = row;
            }
            self.count += 1;
            self.max_deviation = self.max_deviation.max(deviation);
        }
    }

    /// Adds what a reader noted of the rows after those of `self`.
    pub fn merge(&mut self, later: &Normalised) {
        if self.count == 0 {
            self.first_row = later.first_row;
        }
        self.count += later.count;
        self.max_deviation = self.max_deviation.max(later.max_deviation);
    }
}

/// Makes `orientation` (read from `file`) sign-continuous (each quaternion negated into its
/// predecessor's hemisphere, the first kept) and returns the warnings about it: the quaternions
/// `normalised`, and those negated, the first named by its row (`row_of` maps a sample index to
/// the row or message number the reader reports).
pub fn orientation_warnings(
    file: &str,
    orientation: &mut [UnitQuaternion<f64>],
    normalised: &Normalised,
    row_of: impl Fn(usize) -> usize,
) -> Vec<DemoWarning> {
    let mut warnings = Vec::new();
    if normalised.count > 0 {
        warnings.push(DemoWarning::Renormalised {
            file: file.to_owned(),
            count: normalised.count,
            first_row: normalised.first_row,
            max_deviation: normalised.max_deviation,
        });
    }
    let flipped = make_continuous(orientation);
    if let Some(&first) = flipped.first() {
        warnings.push(DemoWarning::SignFlipped {
            file: file.to_owned(),
            count: flipped.len(),
            first_row: row_of(first),
        });
    }
    warnings
}

//! The sign convention at the file boundary (docs/method.md §1): skillc keeps the wrench the
//! environment exerts on the tool; some files store the wrench the robot applies. Recognising
//! such a file, and negating its wrench.

use nalgebra::Vector3;

use super::Demo;

/// Negates the demonstration's forces and torques (to or from the force the robot applies).
pub fn negate_wrench(demo: &mut Demo) {
    for (f, m) in demo.force_n.iter_mut().zip(demo.torque_nm.iter_mut()) {
        *f = -*f;
        *m = -*m;
    }
}

pub use skill_model::wrench::SignEvidence;

/// The figures of the sign check, or `None` without any force: the contact is taken where the
/// force is largest, the way back as the direction to the first sample. In contact, the force
/// on the tool points away from the surface, back towards where the tool came from.
pub fn sign_evidence(demo: &Demo) -> Option<SignEvidence> {
    let (peak, _) = demo
        .force_n
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))?;
    let peak_n = demo.force_n[peak].norm();
    if peak_n == 0.0 {
        return None;
    }
    let back = demo.position_m[0] - demo.position_m[peak];
    let strong: Vec<&Vector3<f64>> = demo.force_n.iter().filter(|f| f.norm() > 0.5 * peak_n).collect();
    let mean: Vector3<f64> = strong.iter().copied().sum::<Vector3<f64>>() / strong.len().max(1) as f64;
    let scale = mean.norm() * back.norm();
    Some(SignEvidence {
        back_m: back.norm(),
        cos_back: if scale > 0.0 { mean.dot(&back) / scale } else { 0.0 },
    })
}

/// Whether a demonstration stores the force the robot applies rather than the force on the
/// tool (the LASA files do not document theirs), by [`sign_evidence`]: the tool came from more
/// than 1 cm away and the contact force points away from where it came from. The forces must
/// be in the base frame.
pub fn stores_applied_force(demo: &Demo) -> bool {
    sign_evidence(demo).is_some_and(|e| e.back_m > 0.01 && e.cos_back < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{parse_csv, ReadOptions};

    #[test]
    fn the_force_convention_of_a_file_is_recognised() {
        use crate::demogen::{generate, to_csv, StdSkill};
        for skill in [StdSkill::Touch, StdSkill::Slide] {
            let text = to_csv(&generate(skill, skill.default_seed()));
            let demo = parse_csv("demo.csv", &text, &ReadOptions::default())
                .expect("parses")
                .demo;
            assert!(
                !stores_applied_force(&demo),
                "{skill:?}: the generator stores the force on the tool"
            );
            let mut flipped = demo.clone();
            flipped.force_n.iter_mut().for_each(|f| *f = -*f);
            assert!(
                stores_applied_force(&flipped),
                "{skill:?}: negated forces are recognised"
            );
        }
    }
}

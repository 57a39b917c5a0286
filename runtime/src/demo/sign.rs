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

/// Whether a demonstration stores the force the robot applies rather than the force on the
/// tool (the LASA files do not document theirs): in contact, the force on the tool points away
/// from the surface, back towards where the tool came from. The contact is taken where the
/// force is largest, the way back as the direction to the first sample.
pub fn stores_applied_force(demo: &Demo) -> bool {
    let Some((peak, _)) = demo
        .force_n
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))
    else {
        return false;
    };
    let back = demo.position_m[0] - demo.position_m[peak];
    let strong: Vec<&Vector3<f64>> = demo
        .force_n
        .iter()
        .filter(|f| f.norm() > 0.5 * demo.force_n[peak].norm())
        .collect();
    let mean: Vector3<f64> = strong.iter().copied().sum::<Vector3<f64>>() / strong.len().max(1) as f64;
    back.norm() > 0.01 && mean.dot(&back) < 0.0
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

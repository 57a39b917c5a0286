//! The kinematic preview of a learned skill: every motion rolled out in segment order, each
//! starting where the previous one ended, with the demonstration's sample columns.

use nalgebra::{UnitQuaternion, Vector3};

use super::learned::Learned;

/// One preview sample: flange pose and the learned desired force at that time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreviewSample {
    /// Time from the start of the preview \[s\].
    pub t_s: f64,
    /// Flange position \[m\], base frame.
    pub position_m: Vector3<f64>,
    /// Flange orientation, base frame.
    pub orientation: UnitQuaternion<f64>,
    /// Index of the motion (in segment order) producing this sample.
    pub motion: usize,
}

/// Rolls out every motion in segment order at `dt_s`, chaining starts, with the goals moved by
/// `goal_offset_m` (base frame). Returns the samples and the motions' names in that order.
pub fn preview(learned: &Learned, dt_s: f64, goal_offset_m: Vector3<f64>) -> (Vec<PreviewSample>, Vec<String>) {
    let mut order: Vec<(&String, &super::learned::LearnedMotion)> = learned.motions.iter().collect();
    order.sort_by_key(|(name, motion)| (motion.segment, (*name).clone()));
    let mut samples = Vec::new();
    let mut names = Vec::new();
    let mut t = 0.0;
    let mut current: Option<(Vector3<f64>, UnitQuaternion<f64>)> = None;
    for (index, (name, motion)) in order.into_iter().enumerate() {
        names.push(name.clone());
        let mut position = motion.position.rollout();
        let mut orientation = motion.orientation.rollout();
        let goal: Vec<f64> = motion
            .position
            .goal
            .iter()
            .zip(goal_offset_m.iter())
            .map(|(g, o)| g + o)
            .collect();
        // Goals are validated finite by construction; a failure leaves the demonstrated goal.
        let _ = position.set_goal(&goal);
        if let Some((p, q)) = current {
            let _ = position.restart_from(p.as_slice());
            orientation.restart_from(q);
        }
        let steps = (motion.position.tau_s / dt_s).ceil() as usize;
        for step in 0..=steps {
            if step > 0 {
                position.step(&motion.position, dt_s);
                orientation.step(&motion.orientation, dt_s);
                t += dt_s;
            }
            let p = Vector3::from_column_slice(position.position());
            samples.push(PreviewSample {
                t_s: t,
                position_m: p,
                orientation: orientation.orientation(),
                motion: index,
            });
        }
        current = samples.last().map(|s| (s.position_m, s.orientation));
    }
    (samples, names)
}

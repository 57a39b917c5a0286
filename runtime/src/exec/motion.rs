//! Starting learned DMPs at run time, the one way every caller does it: a motion restarted from
//! the current flange pose towards its (offset) goal, or a force profile, both time-scaled by the
//! speed override (docs/method.md §2).

use nalgebra::{Isometry3, Translation3, Vector3};

use crate::dmp::{Dmp, DmpError, DmpRollout, QuatRollout};
use crate::skill::{Learned, LearnedMotion};

/// A learned motion running: its position and orientation rollouts and the position goal.
#[derive(Debug, Clone)]
pub(super) struct MotionRollout {
    /// The position rollout, 3 channels \[m\], base frame (the flange).
    pub(super) position: DmpRollout,
    /// The orientation rollout, base frame (the flange).
    pub(super) orientation: QuatRollout,
    /// The position goal set at the start (learned goal plus the goal offset) \[m\].
    pub(super) goal: Vector3<f64>,
}

impl MotionRollout {
    /// Starts `motion` at the flange pose `from`, towards its learned goal moved by
    /// `goal_offset_m`, with its durations divided by `speed`.
    pub(super) fn start(
        motion: &LearnedMotion,
        from: &Isometry3<f64>,
        goal_offset_m: [f64; 3],
        speed: f64,
    ) -> Result<Self, DmpError> {
        let mut position = motion.position.rollout();
        let mut orientation = motion.orientation.rollout();
        position.restart_from(from.translation.vector.as_slice())?;
        orientation.restart_from(from.rotation);
        let goal = Vector3::from_column_slice(&motion.position.goal) + Vector3::from(goal_offset_m);
        position.set_goal(goal.as_slice())?;
        position.set_tau(motion.position.tau_s / speed)?;
        orientation.set_tau(motion.orientation.tau_s / speed)?;
        Ok(MotionRollout {
            position,
            orientation,
            goal,
        })
    }

    /// Advances both rollouts by `dt` \[s\].
    pub(super) fn step(&mut self, motion: &LearnedMotion, dt: f64) {
        self.position.step(&motion.position, dt);
        self.orientation.step(&motion.orientation, dt);
    }

    /// The flange pose now.
    pub(super) fn flange(&self) -> Isometry3<f64> {
        let p = Vector3::from_column_slice(self.position.position());
        Isometry3::from_parts(Translation3::from(p), self.orientation.orientation())
    }
}

/// Starts a learned force profile with its duration divided by `speed`.
pub(super) fn start_profile(dmp: &Dmp, speed: f64) -> Result<DmpRollout, DmpError> {
    let mut rollout = dmp.rollout();
    rollout.set_tau(dmp.tau_s / speed)?;
    Ok(rollout)
}

/// The flange pose at the start of a learned motion.
pub(super) fn motion_start(motion: &LearnedMotion) -> Isometry3<f64> {
    let p = &motion.position.start;
    Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), motion.orientation.start)
}

/// The learned motions in segment order (by name within a segment).
pub(super) fn motions_in_order(learned: &Learned) -> Vec<(&String, &LearnedMotion)> {
    let mut order: Vec<_> = learned.motions.iter().collect();
    order.sort_by_key(|(name, motion)| (motion.segment, (*name).clone()));
    order
}

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
    /// The speed factor it runs at: the override's, lowered when the motion as demonstrated
    /// would move the tool faster than allowed (per-sample frames run on the same clock).
    pub(super) speed: f64,
}

/// The share of the tool speed limit a motion is planned to stay under: tracking overshoots
/// the plan a little, and the supervisor stops the arm at the limit itself.
pub(super) const PLANNED_SPEED_SHARE: f64 = 0.8;

impl MotionRollout {
    /// Starts `motion` at the flange pose `from`, towards its learned goal moved by
    /// `goal_offset_m`, with its durations divided by `speed`, and slowed further when the
    /// tool (`lever_m` from the flange) would otherwise move faster than
    /// [`PLANNED_SPEED_SHARE`] of `max_tool_speed_mps`: a demonstrator's hand is often faster
    /// than a robot may move (0.28-0.46 m/s in the LASA wiping recordings).
    pub(super) fn start(
        motion: &LearnedMotion,
        from: &Isometry3<f64>,
        goal_offset_m: [f64; 3],
        speed: f64,
        max_tool_speed_mps: f64,
        lever_m: f64,
    ) -> Result<Self, DmpError> {
        let started = Self::start_at(motion, from, goal_offset_m, speed)?;
        let planned = PLANNED_SPEED_SHARE * max_tool_speed_mps;
        let peak = started.peak_tool_speed(motion, lever_m);
        if planned.is_finite() && planned > 0.0 && peak > planned {
            return Self::start_at(motion, from, goal_offset_m, speed * planned / peak);
        }
        Ok(started)
    }

    fn start_at(
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
            speed,
        })
    }

    /// The largest tool speed of the whole rollout from here (flange speed plus angular speed
    /// times the lever, an upper bound), sampled every 5 ms on a copy.
    fn peak_tool_speed(&self, motion: &LearnedMotion, lever_m: f64) -> f64 {
        const STEP_S: f64 = 0.005;
        let mut copy = self.clone();
        let steps = (self.position.tau_s().max(self.orientation.tau_s()) * 1.2 / STEP_S)
            .ceil()
            .min(1e6) as usize;
        let mut velocity = [0.0; 3];
        let mut peak: f64 = 0.0;
        for _ in 0..steps {
            copy.position.velocity_into(&mut velocity);
            let speed = Vector3::from(velocity).norm() + copy.orientation.angular_velocity().norm() * lever_m;
            if speed.is_finite() {
                peak = peak.max(speed);
            }
            copy.step(motion, STEP_S);
        }
        peak
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

/// The goal offset that makes `motion` end with the tool point at `at` (base frame \[m\]): `at`
/// minus where the tool point is at the learned goal (the flange's goal position and orientation
/// with `flange_to_tool`), `None` when the goal is not a point. The one rule by which a task
/// step's `at: STEP.STATE` and a state's `move M at NAME` place a motion; its orientation goal
/// stays.
pub fn offset_to_place(motion: &LearnedMotion, at: [f64; 3], flange_to_tool: &Isometry3<f64>) -> Option<[f64; 3]> {
    let goal = &motion.position.goal;
    (goal.len() == 3).then(|| {
        let tool_goal = Vector3::from_column_slice(goal) + motion.orientation.goal * flange_to_tool.translation.vector;
        std::array::from_fn(|axis| at[axis] - tool_goal[axis])
    })
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

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, UnitQuaternion, Vector3};

    use super::{MotionRollout, PLANNED_SPEED_SHARE};
    use crate::dmp::{Dmp, DmpConfig, QuatDmp};
    use crate::skill::LearnedMotion;

    /// A 0.5 m stroke in 1 s along x (minimum jerk: peak 0.94 m/s) with a constant orientation.
    fn fast_stroke() -> LearnedMotion {
        let t_s: Vec<f64> = (0..=1000).map(|k| k as f64 * 1e-3).collect();
        let points: Vec<Vector3<f64>> = t_s
            .iter()
            .map(|&t| {
                let s = t * t * t * (10.0 - 15.0 * t + 6.0 * t * t);
                Vector3::new(0.5 * s, 0.0, 0.3)
            })
            .collect();
        let config = DmpConfig::default();
        let orientation = vec![UnitQuaternion::identity(); t_s.len()];
        LearnedMotion {
            segment: 0,
            position: Dmp::fit_points(&config, &t_s, &points).expect("fits"),
            orientation: QuatDmp::fit(&config, &t_s, &orientation).expect("fits"),
            strokes: Vec::new(),
        }
    }

    fn peak_speed(motion: &LearnedMotion, rollout: &mut MotionRollout) -> f64 {
        let mut velocity = [0.0; 3];
        let mut peak: f64 = 0.0;
        for _ in 0..20_000 {
            rollout.position.velocity_into(&mut velocity);
            peak = peak.max(Vector3::from(velocity).norm());
            rollout.step(motion, 1e-3);
        }
        peak
    }

    #[test]
    fn a_motion_faster_than_the_tool_may_move_is_slowed_to_the_planned_share() {
        let motion = fast_stroke();
        let from = Isometry3::translation(0.0, 0.0, 0.3);
        let mut free = MotionRollout::start(&motion, &from, [0.0; 3], 1.0, f64::INFINITY, 0.0).expect("starts");
        let demonstrated = peak_speed(&motion, &mut free);
        assert!(
            (demonstrated - 0.9375).abs() < 0.05,
            "demonstrated peak {demonstrated} m/s"
        );
        let mut capped = MotionRollout::start(&motion, &from, [0.0; 3], 1.0, 0.25, 0.0).expect("starts");
        assert!(capped.speed < 0.3, "speed factor {}", capped.speed);
        let peak = peak_speed(&motion, &mut capped);
        let planned = PLANNED_SPEED_SHARE * 0.25;
        assert!(
            peak <= planned * 1.02 && peak > planned * 0.9,
            "peak {peak} m/s, planned {planned}"
        );
        // A slow motion keeps its speed.
        let mut slow = MotionRollout::start(&motion, &from, [0.0; 3], 0.1, 0.25, 0.0).expect("starts");
        assert_eq!(slow.speed, 0.1);
        assert!(peak_speed(&motion, &mut slow) < planned);
    }
}

//! Learning a plan's motions: a position DMP and a quaternion DMP per segment, with their
//! reconstruction error.

use skill_ir as ir;

use super::{LearnError, Learner};
use crate::dmp::{Dmp, DmpConfig, QuatDmp};
use crate::skill::learned::{LearnedMotion, MotionQuality};

impl Learner<'_> {
    pub(super) fn motion(&mut self, decl: &ir::MotionDecl) -> Result<LearnedMotion, LearnError> {
        let seg = self.seg(decl.segment);
        let t = self.segment_times(seg, &decl.name, decl.segment.index())?;
        let config = DmpConfig {
            n_basis: decl.basis as usize,
            ..DmpConfig::default()
        };
        let wrap = |source| LearnError::Dmp {
            name: decl.name.clone(),
            source,
        };
        let positions = &self.demo.position_m[seg.range()];
        let orientations = &self.demo.orientation[seg.range()];
        let position = Dmp::fit_points(&config, &t, positions).map_err(wrap)?;
        let orientation = QuatDmp::fit(&config, &t, orientations).map_err(wrap)?;

        // Reconstruction: roll out at the demonstration's own sample times.
        let mut rollout = position.rollout();
        let mut q_rollout = orientation.rollout();
        let mut sum = [0.0; 3];
        let mut sum_rot = 0.0;
        for (k, (p, q)) in positions.iter().zip(orientations).enumerate() {
            if k > 0 {
                let dt = t[k] - t[k - 1];
                rollout.step(&position, dt);
                q_rollout.step(&orientation, dt);
            }
            for (axis, slot) in sum.iter_mut().enumerate() {
                *slot += (rollout.position()[axis] - p[axis]).powi(2);
            }
            sum_rot += q_rollout.orientation().angle_to(q).powi(2);
        }
        let count = positions.len() as f64;
        self.quality.motions.insert(
            decl.name.clone(),
            MotionQuality {
                position_rms_m: sum.map(|s| (s / count).sqrt()),
                orientation_rms_rad: (sum_rot / count).sqrt(),
            },
        );
        Ok(LearnedMotion {
            segment: decl.segment.index(),
            position,
            orientation,
        })
    }
}

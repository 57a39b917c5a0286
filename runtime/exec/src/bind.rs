//! Binding a compiled skill to its learned features: names become indices, and a learned file
//! for another version of the skill is refused.

use skill_ir as ir;

use crate::skill::{ir_hash, Learned, LearnedForce, LearnedFrame, LearnedMotion};

/// Why a learned file does not fit a skill.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BindError {
    /// The file was learned for another skill.
    #[error("the learned file is for skill `{found}`, not `{expected}`")]
    WrongSkill {
        /// The name of the skill being run.
        expected: String,
        /// The name of the skill the file was learned for.
        found: String,
    },
    /// The skill changed since the file was learned.
    #[error("skill `{skill}` changed since it was learned (IR hash {found}, now {expected}); learn it again")]
    Stale {
        /// The skill's name.
        skill: String,
        /// The IR hash of the skill as compiled now.
        expected: String,
        /// The IR hash recorded in the learned file.
        found: String,
    },
    /// A feature the skill needs is missing from the file.
    #[error("the learned file lacks {kind} `{name}`")]
    Missing {
        /// What is missing: `frame`, `motion`, `force` or `threshold`.
        kind: &'static str,
        /// The name the skill declares it under.
        name: String,
    },
    /// A learned file of a newer format.
    #[error("the learned file has format version {found}; this skillc reads version {supported}")]
    Version {
        /// The format version written in the file.
        found: u32,
        /// The newest format version this build reads.
        supported: u32,
    },
}

/// A skill with its learned features, addressed by the IR's ids.
#[derive(Debug, Clone)]
pub struct BoundSkill<'a> {
    /// The compiled skill.
    pub skill: &'a ir::Skill,
    /// The learned file.
    pub learned: &'a Learned,
    /// `frames[FrameId]`.
    pub frames: Vec<&'a LearnedFrame>,
    /// `motions[MotionId]`.
    pub motions: Vec<&'a LearnedMotion>,
    /// `forces[ForceId]`.
    pub forces: Vec<&'a LearnedForce>,
    /// `thresholds[ThresholdId]`.
    pub thresholds: Vec<f64>,
}

/// Binds `learned` to `skill`.
pub fn bind<'a>(skill: &'a ir::Skill, learned: &'a Learned) -> Result<BoundSkill<'a>, BindError> {
    if learned.learned_version != crate::skill::LEARNED_VERSION {
        return Err(BindError::Version {
            found: learned.learned_version,
            supported: crate::skill::LEARNED_VERSION,
        });
    }
    if learned.skill != skill.name {
        return Err(BindError::WrongSkill {
            expected: skill.name.clone(),
            found: learned.skill.clone(),
        });
    }
    let expected = ir_hash(skill);
    if learned.ir_hash != expected {
        return Err(BindError::Stale {
            skill: skill.name.clone(),
            expected,
            found: learned.ir_hash.clone(),
        });
    }
    let missing = |kind: &'static str, name: &str| BindError::Missing {
        kind,
        name: name.to_string(),
    };
    let plan = &skill.learn;
    Ok(BoundSkill {
        skill,
        learned,
        frames: plan
            .frames
            .iter()
            .map(|f| learned.frames.get(&f.name).ok_or_else(|| missing("frame", &f.name)))
            .collect::<Result<_, _>>()?,
        motions: plan
            .motions
            .iter()
            .map(|m| learned.motions.get(&m.name).ok_or_else(|| missing("motion", &m.name)))
            .collect::<Result<_, _>>()?,
        forces: plan
            .forces
            .iter()
            .map(|f| learned.forces.get(&f.name).ok_or_else(|| missing("force", &f.name)))
            .collect::<Result<_, _>>()?,
        thresholds: plan
            .thresholds
            .iter()
            .map(|t| {
                learned
                    .thresholds
                    .get(&t.name)
                    .map(|v| v.value)
                    .ok_or_else(|| missing("threshold", &t.name))
            })
            .collect::<Result<_, _>>()?,
    })
}

impl<'a> BoundSkill<'a> {
    /// The learned frame of a declared frame.
    pub fn frame(&self, id: ir::FrameId) -> &'a LearnedFrame {
        self.frames[id.index()]
    }

    /// The learned motion of a declared motion.
    pub fn motion(&self, id: ir::MotionId) -> &'a LearnedMotion {
        self.motions[id.index()]
    }

    /// The learned force of a declared force.
    pub fn force(&self, id: ir::ForceId) -> &'a LearnedForce {
        self.forces[id.index()]
    }

    /// The declared frames with what was learned for each.
    pub fn declared_frames(&self) -> impl Iterator<Item = (&'a ir::FrameDecl, &'a LearnedFrame)> + '_ {
        self.skill.learn.frames.iter().zip(self.frames.iter().copied())
    }

    /// The declared forces with what was learned for each.
    pub fn declared_forces(&self) -> impl Iterator<Item = (&'a ir::ForceDecl, &'a LearnedForce)> + '_ {
        self.skill.learn.forces.iter().zip(self.forces.iter().copied())
    }

    /// The name of the replay baseline's state covering `segment` (0-based); see
    /// [`replay_state`](super::replay_state).
    pub fn replay_state(&self, segment: usize) -> String {
        super::replay_state(self.learned, segment)
    }
}

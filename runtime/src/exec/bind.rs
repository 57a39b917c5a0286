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
        /// The skill run.
        expected: String,
        /// The skill in the file.
        found: String,
    },
    /// The skill changed since the file was learned.
    #[error("skill `{skill}` changed since it was learned (IR hash {found}, now {expected}); learn it again")]
    Stale {
        /// The skill.
        skill: String,
        /// The hash now.
        expected: String,
        /// The hash in the file.
        found: String,
    },
    /// A feature the skill needs is missing from the file.
    #[error("the learned file lacks {kind} `{name}`")]
    Missing {
        /// Frame, motion, force or threshold.
        kind: &'static str,
        /// Its name.
        name: String,
    },
    /// A learned file of a newer format.
    #[error("the learned file has format version {found}; this skillc reads version {supported}")]
    Version {
        /// In the file.
        found: u32,
        /// What this build reads.
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

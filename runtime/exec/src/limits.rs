//! The supervisor's limits for one run: the defaults a learned file implies (its peak force, the
//! workspace of its motions), then the limits the skill and the task step declare, then the
//! user's overrides, and how a reflex reads in a report.

use nalgebra::{Isometry3, Translation3};
use skill_ir as ir;

use crate::safety::{LimitError, Limits, Violation, Workspace, WORKSPACE_MARGIN_M};
use crate::skill::{Learned, LearnedForce};

/// The largest force a learned file asks for or watches for \[N\]: constants, literals, the peak
/// of force DMPs (rolled out at 10 ms), thresholds. 0 when it learned none.
pub fn learned_peak_force(learned: &Learned) -> f64 {
    let mut peak: f64 = 0.0;
    for force in learned.forces.values() {
        let value = match force {
            LearnedForce::Constant { value_n, .. }
            | LearnedForce::At { value_n }
            | LearnedForce::Literal { value_n }
            | LearnedForce::Tracked { value_n } => value_n.abs(),
            LearnedForce::Dmp { dmp } | LearnedForce::Magnitude { dmp } => {
                if dmp.validate().is_err() {
                    continue;
                }
                let mut rollout = dmp.rollout();
                let steps = (dmp.tau_s / 0.01).ceil().min(1e6) as usize;
                let mut largest: f64 = 0.0;
                for _ in 0..=steps {
                    let norm = rollout.position().iter().map(|v| v * v).sum::<f64>().sqrt();
                    largest = largest.max(norm);
                    rollout.step(dmp, 0.01);
                }
                largest
            }
        };
        if value.is_finite() {
            peak = peak.max(value);
        }
    }
    for threshold in learned.thresholds.values() {
        if threshold.value.is_finite() {
            peak = peak.max(threshold.value.abs());
        }
    }
    peak
}

/// The box the learned motions' tool points start and end in, and the tool's position when the
/// run starts (`start`, where pre-positioning begins), grown by [`WORKSPACE_MARGIN_M`].
pub fn learned_workspace(
    learned: &Learned,
    flange_to_tool: &Isometry3<f64>,
    start: Option<[f64; 3]>,
) -> Option<Workspace> {
    let mut points: Vec<[f64; 3]> = start.into_iter().collect();
    for motion in learned.motions.values() {
        let position = &motion.position;
        let orientation = &motion.orientation;
        for (p, q) in [(&position.start, orientation.start), (&position.goal, orientation.goal)] {
            if p.len() != 3 {
                continue;
            }
            let flange = Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), q);
            let tool = (flange * flange_to_tool).translation.vector;
            points.push([tool.x, tool.y, tool.z]);
        }
    }
    Workspace::around(points.iter(), WORKSPACE_MARGIN_M)
}

/// The limits of a run of `learned` starting with the tool at `start`: its defaults, scaled by a
/// task's force scale, then the limits declared in the `.skill` text (`declared`: the skill's
/// `limits { }` block, then the task step's `limits:`), then each user override (`force=60`,
/// `speed=0.1`, …); later settings of a limit win. Declared values are absolute: a task's force
/// scale only raises the defaults.
pub fn limits_for(
    learned: &Learned,
    flange_to_tool: &Isometry3<f64>,
    start: Option<[f64; 3]>,
    force_scale: f64,
    declared: &[&ir::Limit],
    overrides: &[(String, f64)],
) -> Result<Limits, LimitError> {
    let workspace = learned_workspace(learned, flange_to_tool, start);
    let mut limits = Limits::for_skill(learned_peak_force(learned), workspace);
    limits.scale_force(force_scale);
    apply_limits(&mut limits, declared, overrides)?;
    Ok(limits)
}

/// Sets the `declared` limits (in `.skill` order: skill, then task step) and then the user's
/// `overrides` on `limits`, so that the command line wins over the step and the step over the
/// skill.
pub fn apply_limits(
    limits: &mut Limits,
    declared: &[&ir::Limit],
    overrides: &[(String, f64)],
) -> Result<(), LimitError> {
    for limit in declared {
        limits.set(&limit.name, limit.value())?;
    }
    for (name, value) in overrides {
        limits.set(name, *value)?;
    }
    Ok(())
}

/// The failure message of a reflex: when, where (state and `.skill` line), what, how much.
pub(super) fn reflex_message(violation: &Violation, state: &str, location: Option<&str>) -> String {
    let place = match location {
        Some(location) => format!("in state `{state}` ({location})"),
        None => format!("in `{state}`"),
    };
    let hint = match violation.quantity.limit_name() {
        Some(name) => format!(
            " (if the limit is wrong for this skill, set it in the skill's `limits {{ {name}: ... }}` or with `--limit {name}=...`)"
        ),
        None => String::new(),
    };
    format!("reflex stop {place}: {violation}; the arm was brought to a damped stop{hint}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limit(name: &str, value_si: Option<f64>) -> ir::Limit {
        ir::Limit {
            name: name.into(),
            value_si,
            doc: String::new(),
            span: ir::SourceSpan {
                file: "t.skill".into(),
                line: 1,
                column: 1,
                start: 0,
                end: 0,
            },
        }
    }

    #[test]
    fn the_command_line_wins_over_the_step_and_the_step_over_the_skill() {
        let skill = [
            limit("force", Some(10.0)),
            limit("speed", Some(0.1)),
            limit("tracking", None),
        ];
        let step = [limit("force", Some(20.0))];
        let declared: Vec<&ir::Limit> = skill.iter().chain(&step).collect();
        let defaults = Limits::for_skill(5.0, None);

        let mut limits = defaults.clone();
        apply_limits(&mut limits, &declared[..3], &[]).expect("valid");
        assert_eq!(limits.force_n, 10.0, "the skill's block over the defaults");
        assert_eq!(limits.tool_speed_mps, 0.1);
        assert_eq!(limits.tracking_error_m, f64::INFINITY, "`inf` switches the check off");
        assert_eq!(
            limits.moment_nm, defaults.moment_nm,
            "what no one sets keeps its default"
        );

        let mut limits = defaults.clone();
        apply_limits(&mut limits, &declared, &[]).expect("valid");
        assert_eq!(limits.force_n, 20.0, "the step over the skill");
        assert_eq!(limits.tool_speed_mps, 0.1, "the step changes only what it names");

        let mut limits = defaults;
        apply_limits(&mut limits, &declared, &[("force".into(), 30.0)]).expect("valid");
        assert_eq!(limits.force_n, 30.0, "the command line over both");
    }
}

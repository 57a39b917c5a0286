//! The eval's verdict lines: trials passed of run, the contact witness's count, and a failed
//! run's reason in words.

use super::{Outcome, TrialResult};

/// What the contact witness found over every trial: steps checked, steps in contact, steps
/// that broke its rules, and the deepest the tool went into an object (with the trial).
pub(super) fn witness_line(outcomes: &[Outcome]) -> String {
    let mut all = skill_runtime::plant::ContactAudit::default();
    let mut deepest: Option<(f64, &TrialResult)> = None;
    let mut trials = 0;
    for result in outcomes.iter().map(|o| &o.result) {
        let Some(audit) = &result.contact else { continue };
        trials += 1;
        if deepest.is_none_or(|(depth, _)| audit.max_depth_m > depth) {
            deepest = Some((audit.max_depth_m, result));
        }
        all.merge(audit.clone());
    }
    let broken = outcomes
        .iter()
        .filter(|o| o.result.contact.as_ref().is_some_and(|audit| audit.violated()))
        .count();
    let mut line = format!(
        "contact witness: {} steps of {trials} trials checked against the shapes, {} in contact; {} with force away from \
         every object, {} deeper than the compliance explains ({broken} trials)",
        all.ticks, all.touching_ticks, all.far_ticks, all.deep_ticks
    );
    if let Some((depth, result)) = deepest.filter(|(depth, _)| *depth > 0.0) {
        line.push_str(&format!(
            "; deepest {:.2} mm ({} {}, {})",
            depth * 1e3,
            result.skill,
            result.variant,
            result.mode
        ));
    }
    line
}

/// The first reason a run itself gives for failing, in order of gravity, before any criterion
/// is looked at: contacts that are not where the shapes are (every other figure of the run is
/// suspect then), a reflex, a contact lost mid-stroke.
pub(crate) fn run_reason(report: &skill_runtime::exec::RunReport) -> Option<String> {
    if report.contact.as_ref().is_some_and(|audit| audit.violated()) {
        Some(skill_runtime::exec::CONTACT_WITNESS.to_string())
    } else if let Some(violation) = &report.reflex {
        Some(format!("reflex:{}", violation.quantity.name()))
    } else if report.lost_contact() {
        Some(skill_runtime::exec::LOST_CONTACT.to_string())
    } else {
        None
    }
}

/// `N/M skill trials pass`, and `K/L task trials pass` when there are task trials.
pub(super) fn pass_line(outcomes: &[Outcome]) -> String {
    let count = |mode: &str| {
        let of_mode: Vec<&TrialResult> = outcomes.iter().map(|o| &o.result).filter(|r| r.mode == mode).collect();
        (of_mode.iter().filter(|r| r.success && !r.error).count(), of_mode.len())
    };
    let (skills_ok, skills) = count("skill");
    let mut line = format!("{skills_ok}/{skills} skill trials pass");
    let (tasks_ok, tasks) = count("task");
    if tasks > 0 {
        line.push_str(&format!(
            ", {tasks_ok}/{tasks} task trials pass (tasks have no replay baseline)"
        ));
    }
    line
}

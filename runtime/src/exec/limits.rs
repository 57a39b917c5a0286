//! The supervisor's limits for one run: the defaults a learned file implies (its peak force, the
//! workspace of its motions), then the user's overrides, and how a reflex reads in a report.

use nalgebra::{Isometry3, Translation3};

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

/// The limits of a run of `learned` starting with the tool at `start`: its defaults, scaled by a task's force scale, then each
/// user override (`force=60`, `speed=0.1`, …) in order.
pub fn limits_for(
    learned: &Learned,
    flange_to_tool: &Isometry3<f64>,
    start: Option<[f64; 3]>,
    force_scale: f64,
    overrides: &[(String, f64)],
) -> Result<Limits, LimitError> {
    let workspace = learned_workspace(learned, flange_to_tool, start);
    let mut limits = Limits::for_skill(learned_peak_force(learned), workspace);
    limits.scale_force(force_scale);
    for (name, value) in overrides {
        limits.set(name, *value)?;
    }
    Ok(limits)
}

/// The failure message of a reflex: when, where (state and `.skill` line), what, how much.
pub(super) fn reflex_message(violation: &Violation, state: &str, location: Option<&str>) -> String {
    let place = match location {
        Some(location) => format!("in state `{state}` ({location})"),
        None => format!("in `{state}`"),
    };
    let hint = match violation.quantity.limit_name() {
        Some(name) => format!(" (if the limit is wrong for this skill, set it with `--limit {name}=...`)"),
        None => String::new(),
    };
    format!("reflex stop {place}: {violation}; the arm was brought to a damped stop{hint}")
}

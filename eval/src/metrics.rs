//! The metrics of one trial (docs/method.md §8): force tracking in the compliant frame during contact,
//! the share of the contact phase in contact, the peak force, the stop force of a touch, the
//! position error at the goal.

use nalgebra::Vector3;
use serde::Serialize;
use skill_ir as ir;
use skill_runtime::exec::{BoundSkill, RunLog, Tick};
use skill_runtime::skill::LearnedForce;

use skill_kit::profile::DesiredProfile;

/// Ticks after the start of a contact visit that are not judged (settling) \[s\].
pub const SETTLE_S: f64 = 0.2;

/// What a trial measured.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Metrics {
    /// RMS of (desired − applied) along the compliant z during contact, over the learned force
    /// (over its peak for a force-vector DMP such as press's profile, over its mean otherwise); `None` when the skill has no contact phase.
    pub force_rms_rel: Option<f64>,
    /// Share of the contact phase with the applied force above contact level.
    pub contact_share: Option<f64>,
    /// Largest applied force magnitude after pre-positioning \[N\].
    pub peak_force_n: f64,
    /// The applied force along the compliant z when the contact phase ended \[N\] (touch).
    pub stop_force_n: Option<f64>,
    /// Distance between measured and commanded tool position at the end \[m\].
    pub goal_error_m: f64,
    /// Ticks judged in the contact phase.
    pub contact_ticks: usize,
}

/// How to read the contact phase of one skill, derived from its IR and learned file.
#[derive(Debug, Clone)]
pub struct ContactPlan {
    /// The skill's contact states (force-controlled with a desired force).
    pub skill_states: Vec<String>,
    /// The replay states covering the same segment.
    pub replay_states: Vec<String>,
    /// The learned force used as the desired force.
    pub force: Option<LearnedForce>,
    /// The compliant frame of the contact state (for replay ticks, which have no frame).
    pub frame: Option<ir::FrameRef>,
    /// Normalise the RMS error by the peak (force profiles) instead of the mean.
    pub relative_to_peak: bool,
}

impl ContactPlan {
    /// The contact phase of a bound skill: its first force-controlled state with a desired force.
    pub fn of(bound: &BoundSkill<'_>) -> ContactPlan {
        let skill = bound.skill;
        let mut plan = ContactPlan {
            skill_states: Vec::new(),
            replay_states: Vec::new(),
            force: None,
            frame: None,
            relative_to_peak: false,
        };
        for state in &skill.states {
            let ir::StateKind::Active(active) = &state.kind else {
                continue;
            };
            let Some(force_id) = active.force else { continue };
            if active.position_controlled.iter().all(|p| *p) {
                continue;
            }
            let decl = &skill.learn.forces[force_id.index()];
            if matches!(decl.source, ir::ForceSource::Tracked) {
                continue;
            }
            plan.skill_states.push(state.name.clone());
            if plan.force.is_some() {
                continue;
            }
            plan.force = Some(bound.force(force_id).clone());
            plan.frame = Some(active.frame);
            plan.relative_to_peak = matches!(decl.source, ir::ForceSource::Dmp { .. });
            let segment = match &decl.source {
                ir::ForceSource::Constant { segment, .. }
                | ir::ForceSource::Dmp { segment, .. }
                | ir::ForceSource::Magnitude { segment, .. } => Some(segment.index()),
                ir::ForceSource::At { point, .. } => match point {
                    ir::Point::End(segment) | ir::Point::Start(segment) | ir::Point::PeakForceIn(segment) => {
                        Some(segment.index())
                    }
                    ir::Point::PeakForce => None,
                },
                _ => None,
            };
            if let Some(segment) = segment {
                plan.replay_states.push(bound.replay_state(segment));
            }
        }
        plan
    }
}

fn applied_along(tick: &Tick, z: &Vector3<f64>) -> f64 {
    Vector3::new(tick.wrench_base[0], tick.wrench_base[1], tick.wrench_base[2]).dot(z)
}

/// Computes the metrics of one trial. `replay_frame_z` gives the compliant z for replay ticks
/// at a time into the contact phase.
pub fn measure(
    log: &RunLog,
    plan: &ContactPlan,
    replay: bool,
    replay_frame_z: &dyn Fn(f64) -> Vector3<f64>,
) -> Metrics {
    let contact_states = if replay {
        &plan.replay_states
    } else {
        &plan.skill_states
    };
    let contact_index: Vec<u32> = log
        .states
        .iter()
        .enumerate()
        .filter(|(_, name)| contact_states.contains(name))
        .map(|(i, _)| i as u32)
        .collect();

    let mut metrics = Metrics::default();
    let mut sq = 0.0;
    let mut desired_sum = 0.0;
    let mut desired_peak: f64 = 0.0;
    let mut in_contact = 0usize;
    let mut visit_start: Option<(u32, f64)> = None;
    let replay_profile = plan.force.as_ref().map(|force| DesiredProfile::new(force, 0.01));
    let mut last_contact_z: Vec<f64> = Vec::new();
    for tick in &log.ticks {
        // Every tick counts, pre-positioning too: a bump on the way to the start is a bump.
        let f = Vector3::new(tick.wrench_base[0], tick.wrench_base[1], tick.wrench_base[2]).norm();
        metrics.peak_force_n = metrics.peak_force_n.max(f);
        if !contact_index.contains(&tick.state) {
            visit_start = None;
            continue;
        }
        let start = match visit_start {
            Some((state, start)) if state == tick.state => start,
            _ => {
                visit_start = Some((tick.state, tick.t_s));
                last_contact_z.clear();
                tick.t_s
            }
        };
        let t_in = tick.t_s - start;
        let (desired, measured) = if replay {
            let z = replay_frame_z(t_in);
            let desired = replay_profile.as_ref().map_or(0.0, |profile| profile.at(t_in));
            (desired, applied_along(tick, &z))
        } else {
            (tick.desired_cf[2], tick.wrench_cf[2])
        };
        last_contact_z.push(measured);
        if t_in < SETTLE_S {
            continue;
        }
        metrics.contact_ticks += 1;
        sq += (desired - measured).powi(2);
        desired_sum += desired;
        desired_peak = desired_peak.max(desired.abs());
        if measured > (0.2 * desired).max(1.0) {
            in_contact += 1;
        }
    }
    if metrics.contact_ticks > 0 {
        let n = metrics.contact_ticks as f64;
        let norm = if plan.relative_to_peak {
            desired_peak
        } else {
            desired_sum / n
        };
        if norm.abs() > 1e-9 {
            metrics.force_rms_rel = Some((sq / n).sqrt() / norm.abs());
        }
        metrics.contact_share = Some(in_contact as f64 / n);
    }
    if !last_contact_z.is_empty() {
        let tail = (last_contact_z.len()).min(100);
        metrics.stop_force_n = Some(last_contact_z[last_contact_z.len() - tail..].iter().sum::<f64>() / tail as f64);
    }
    if let Some(last) = log.ticks.last() {
        let d = Vector3::new(last.desired[0], last.desired[1], last.desired[2]);
        let m = Vector3::new(last.measured[0], last.measured[1], last.measured[2]);
        metrics.goal_error_m = (d - m).norm();
    }
    metrics
}

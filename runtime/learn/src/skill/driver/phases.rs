//! Contact phases in the learning driver (docs/method.md §3): which phase of a demonstration
//! with several a template learns from, segment boundaries moved to a contact's onset and
//! release, and the first in-contact window frames at a point take their force from.

use nalgebra::Vector3;
use skill_ir as ir;

use super::LearnError;
use crate::demo::Demo;
use crate::phases::{contact_phases, crop, first_contact_window, phase_window, ContactPhase, Phases};
use crate::segment::Segment;
use crate::skill::learned::{OnsetFrame, OnsetMove, PhaseReport};

/// A boundary at most this far from a contact's onset or release is moved onto it \[s\].
const MAX_MOVE_S: f64 = 1.0;
/// A frame at a point this long before a phase's onset still takes that phase's window \[s\].
const BEFORE_ONSET_S: f64 = 0.3;

/// What the driver learns from: the demonstration (all of it, or the part around one phase), its
/// phases (indices into that part) and the report.
pub(super) struct Chosen {
    pub(super) demo: Demo,
    pub(super) phases: Vec<ContactPhase>,
    pub(super) report: PhaseReport,
    pub(super) segments: Vec<Segment>,
    pub(super) warning: Option<String>,
}

/// Finds the phases of `demo` and picks what to learn from: phase `asked` (1-based) when given;
/// otherwise all of it, unless a segment would span several phases, and then the longest phase.
pub(super) fn choose(
    plan: &ir::LearnPlan,
    demo: Demo,
    asked: Option<usize>,
    segment: impl Fn(&Demo) -> Result<Vec<Segment>, LearnError>,
) -> Result<Chosen, LearnError> {
    // Without a phase asked for, the whole demonstration is cut anyway: finding its contact
    // phases runs beside the cut (the largest parts of learning, both only read the demo).
    let (found, whole) = match asked {
        Some(_) => (contact_phases(&demo), None),
        None => std::thread::scope(|scope| {
            let phases = scope.spawn(|| contact_phases(&demo));
            let whole = segment(&demo);
            let found = phases.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (found, Some(whole))
        }),
    };
    let expected = expected_phases(plan);
    let mut report = PhaseReport {
        phases_s: found
            .phases
            .iter()
            .map(|p| [demo.t_s[p.onset], demo.t_s[p.release.min(demo.len()) - 1]])
            .collect(),
        median_n: found.phases.iter().map(|p| p.median_n).collect(),
        noise_n: found.noise_n,
        on_n: found.on_n,
        ..PhaseReport::default()
    };
    let list = |found: &Phases| {
        if found.phases.is_empty() {
            String::new()
        } else {
            format!(": {}", found.describe(&demo))
        }
    };
    if let Some(phase) = asked {
        if phase == 0 || phase > found.phases.len() {
            return Err(LearnError::NoSuchPhase {
                source_name: demo.source.clone(),
                phase,
                count: found.phases.len(),
                list: list(&found),
            });
        }
        report.learned = Some(phase);
        report.chosen_by = "--phase".into();
        let (part, phases) = part_around(&demo, &found, phase - 1);
        let segments = segment(&part)?;
        return Ok(Chosen {
            demo: part,
            phases,
            report,
            segments,
            warning: None,
        });
    }
    let whole = whole.unwrap_or_else(|| segment(&demo));
    let mixed = match &whole {
        Ok(segments) => mixing_segment(segments, &found.phases),
        Err(_) => None,
    };
    let too_many = found.phases.len() > expected;
    let (Some(longest), true) = (
        found.longest(&demo),
        found.phases.len() > 1 && (too_many || mixed.is_some() || whole.is_err()),
    ) else {
        return Ok(Chosen {
            segments: whole?,
            phases: found.phases,
            demo,
            report,
            warning: None,
        });
    };
    let (part, phases) = part_around(&demo, &found, longest);
    match segment(&part) {
        Ok(segments) => {
            report.learned = Some(longest + 1);
            report.chosen_by = "longest".into();
            let warning = format!(
                "`{}` has {} contact phases ({}); the template expects {}: learned phase {}, the longest ({:.2} s); --phase N picks another",
                demo.source,
                found.phases.len(),
                found.describe(&demo),
                if expected == 1 { "one".to_string() } else { format!("at most {expected}") },
                longest + 1,
                found.phases[longest].duration_s(&demo)
            );
            Ok(Chosen {
                demo: part,
                phases,
                report,
                segments,
                warning: Some(warning),
            })
        }
        Err(err) => match mixed {
            Some(segment) => Err(LearnError::PhasesMixed {
                source_name: demo.source.clone(),
                segment: segment + 1,
                count: found.phases.len(),
                list: found.describe(&demo),
                longest: longest + 1,
                reason: crate::skill::driver::error_text(&err),
            }),
            None => Err(whole.err().unwrap_or(err)),
        },
    }
}

/// How many contact phases a template can take: the number of segments its forces are learned
/// on (a wipe's one, a double tap's two), or as many as its segments can hold apart when free
/// and contact segments alternate between an approach and a leave ((N - 1) / 2 of N: a
/// five-segment tap loop that learns one force for both its taps takes two), at least one. A
/// segment holding two phases is caught after segmentation too ([`mixing_segment`]).
pub(super) fn expected_phases(plan: &ir::LearnPlan) -> usize {
    let mut segments: Vec<Option<usize>> = plan
        .forces
        .iter()
        .filter_map(|decl| match &decl.source {
            ir::ForceSource::Constant { segment, .. }
            | ir::ForceSource::Dmp { segment, .. }
            | ir::ForceSource::Magnitude { segment, .. } => Some(Some(segment.index())),
            ir::ForceSource::At { point, .. } => Some(match point {
                ir::Point::Start(segment) | ir::Point::End(segment) | ir::Point::PeakForceIn(segment) => {
                    Some(segment.index())
                }
                ir::Point::PeakForce => None,
            }),
            _ => None,
        })
        .collect();
    segments.sort_unstable();
    segments.dedup();
    let alternating = (plan.segments as usize).saturating_sub(1) / 2;
    segments.len().max(alternating).max(1)
}

/// The part of `demo` around phase `index` and the phases inside it, re-indexed.
fn part_around(demo: &Demo, found: &Phases, index: usize) -> (Demo, Vec<ContactPhase>) {
    let range = phase_window(&found.phases, index, demo.len());
    let shift = |k: usize| k.saturating_sub(range.start).min(range.len());
    let phases = found
        .phases
        .iter()
        .filter(|p| p.onset >= range.start && p.release <= range.end)
        .map(|p| ContactPhase {
            on: shift(p.on),
            off: shift(p.off),
            onset: shift(p.onset),
            release: shift(p.release),
            ..*p
        })
        .collect();
    (crop(demo, range), phases)
}

/// The first segment holding at least half of each of two or more phases.
fn mixing_segment(segments: &[Segment], phases: &[ContactPhase]) -> Option<usize> {
    segments.iter().position(|segment| {
        phases
            .iter()
            .filter(|p| {
                let overlap = p.off.min(segment.end).saturating_sub(p.on.max(segment.start));
                2 * overlap >= p.off - p.on
            })
            .count()
            >= 2
    })
}

/// Moves segment boundaries next to a contact onto its onset or release: a boundary within
/// [`MAX_MOVE_S`] of a phase's onset whose next segment is mostly in that phase, or of its
/// release whose previous segment is. Segments a frame imposes a plane on are left to the
/// geometric check (`contact.rs`), segments learned as `constant(...)` to segmentation, and a
/// touch's split at the force peak is no contact edge.
pub(super) fn move_to_onsets(
    plan: &ir::LearnPlan,
    demo: &Demo,
    segments: &mut [Segment],
    phases: &[ContactPhase],
) -> Vec<OnsetMove> {
    if matches!(plan.segmentation, ir::Segmentation::MaxForce | ir::Segmentation::None) {
        return Vec::new();
    }
    // Segments a plane is imposed on (the geometric check bounds them) and segments whose force
    // is `constant(...)`: its steady-region search is tuned to segmentation's cut, and a tap that
    // gains its touch-down and lift-off ramps learns 5.2 N for 6 N.
    let planar: Vec<usize> = plan
        .frames
        .iter()
        .filter_map(|decl| match &decl.source {
            ir::FrameSource::Constraint { segment, candidates }
                if candidates.as_slice() == [ir::ConstraintModel::Planar] =>
            {
                Some(segment.index())
            }
            _ => None,
        })
        .chain(plan.forces.iter().filter_map(|decl| match &decl.source {
            ir::ForceSource::Constant { segment, .. } => Some(segment.index()),
            _ => None,
        }))
        .collect();
    let in_phase = |segment: &Segment, phase: &ContactPhase| {
        let overlap = phase
            .release
            .min(segment.end)
            .saturating_sub(phase.onset.max(segment.start));
        2 * overlap > segment.len()
    };
    let mut moved = Vec::new();
    for boundary in 1..segments.len() {
        if planar.contains(&boundary) || planar.contains(&(boundary - 1)) {
            continue;
        }
        let at = segments[boundary].start;
        let t_at = demo.t_s[at];
        let target = phases
            .iter()
            .flat_map(|phase| {
                [
                    (phase.onset, in_phase(&segments[boundary], phase), "onset"),
                    (phase.release, in_phase(&segments[boundary - 1], phase), "release"),
                ]
            })
            .filter(|&(k, fits, _)| fits && k < demo.len() && (demo.t_s[k] - t_at).abs() <= MAX_MOVE_S)
            .min_by_key(|&(k, _, _)| k.abs_diff(at));
        let Some((target, _, kind)) = target else { continue };
        // Both neighbours keep at least 5 samples.
        if target == at || target < segments[boundary - 1].start + 5 || target + 5 > segments[boundary].end {
            continue;
        }
        segments[boundary - 1].end = target;
        segments[boundary].start = target;
        moved.push(OnsetMove {
            segment: boundary + 1,
            end: kind.into(),
            from_to_s: [t_at, demo.t_s[target]],
        });
    }
    moved
}

/// The force a frame at sample `index` follows: the mean over the first in-contact window of the
/// phase the sample is in (or shortly before), with the window's report; `None` when the sample
/// is in no phase.
pub(super) fn window_force(demo: &Demo, phases: &[ContactPhase], index: usize) -> Option<(Vector3<f64>, OnsetFrame)> {
    let before = (BEFORE_ONSET_S * demo.len() as f64 / demo.duration_s().max(1e-9)).round() as usize;
    let phase = phases
        .iter()
        .find(|p| index + before >= p.onset && index < p.release.max(p.off))?;
    let window = first_contact_window(demo, phase);
    // Against the force just before the onset: what debiasing left does not tilt the frame.
    let baseline = crate::phases::baseline_before(demo, phase).unwrap_or_else(Vector3::zeros);
    let forces: Vec<Vector3<f64>> = demo.force_n[window.clone()].iter().map(|f| f - baseline).collect();
    let mean: Vector3<f64> = forces.iter().sum::<Vector3<f64>>() / forces.len() as f64;
    let direction = mean.try_normalize(1e-12)?;
    let scatter = (forces
        .iter()
        .filter_map(|f| f.try_normalize(1e-12))
        .map(|d| d.dot(&direction).clamp(-1.0, 1.0).acos().powi(2))
        .sum::<f64>()
        / forces.len() as f64)
        .sqrt();
    Some((
        mean,
        OnsetFrame {
            window_s: [demo.t_s[window.start], demo.t_s[window.end - 1]],
            samples: window.len(),
            mean_n: mean.norm(),
            scatter_deg: scatter.to_degrees(),
        },
    ))
}

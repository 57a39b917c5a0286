//! States: their statements (move, control, stiffness, apply, gains, entry, approach, lift off)
//! and transition targets, lowered to the controller's settings per state (docs/method.md §6).

use super::scope::{SkillScope, SymKind};
use super::values::Args;
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, AxisSet, ExprKind, StmtKind};
use crate::diag::Code;
use crate::source::Span;
use crate::units::Dim;
use skill_ir as ir;
use std::collections::HashMap;

/// The most times a state may repeat its motion: it bounds the work a run does, and a thousand
/// strokes is already hours of wiping.
pub(super) const MAX_REPEAT: u32 = 1000;

/// Default stiffness per axis in the compliant frame: N/m for x y z, Nm/rad for rx ry rz.
/// Values of the order used for Cartesian impedance control on the LWR-IV.
pub const DEFAULT_STIFFNESS: [f64; 6] = [1500.0, 1500.0, 1500.0, 150.0, 150.0, 150.0];

/// Default PI force gains when a state writes no `gains`.
pub const DEFAULT_GAINS: ir::ForceGains = ir::ForceGains {
    kp: 0.5,
    ki: 5.0,
    integral_limit_n: Some(10.0),
};

/// Whether a guard compares a force anywhere (so the state waits for contact).
fn mentions_force(guard: &ast::Guard) -> bool {
    match &guard.kind {
        ast::GuardKind::Or(parts) | ast::GuardKind::And(parts) => parts.iter().any(mentions_force),
        ast::GuardKind::Not(inner) | ast::GuardKind::Held { guard: inner, .. } => mentions_force(inner),
        ast::GuardKind::Force { .. } | ast::GuardKind::Magnitude { .. } => true,
        ast::GuardKind::Moved { .. }
        | ast::GuardKind::Speed { .. }
        | ast::GuardKind::Entered { .. }
        | ast::GuardKind::Timed { .. }
        | ast::GuardKind::ForceReached(_)
        | ast::GuardKind::Named(_) => false,
    }
}

impl Checker<'_> {
    pub(super) fn states(
        &mut self,
        skill: &ast::Skill,
        scope: &mut SkillScope,
    ) -> (Vec<ir::State>, Vec<ir::Transition>, Option<ir::StateId>) {
        let mut ids: HashMap<&str, (ir::StateId, Span)> = HashMap::new();
        let mut unique: Vec<&ast::State> = Vec::new();
        for state in &skill.states {
            if let Some((_, earlier)) = ids.get(state.name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        state.name.span,
                        format!("state `{}` is declared twice", state.name.name),
                        "second declaration",
                    )
                    .label(*earlier, "first declared here")
                    .help("rename one of them");
                self.report(diag);
                continue;
            }
            ids.insert(&state.name.name, (ir::StateId(unique.len() as u32), state.name.span));
            unique.push(state);
        }
        if unique.is_empty() {
            let diag = self
                .diag(Code::NoStates, skill.name.span, format!("skill `{}` has no state", skill.name.name), "nothing to run")
                .help("add a state, e.g. `state approach { move path from current\n on motion_done -> done }` and `terminal done: success`");
            self.report(diag);
            return (Vec::new(), Vec::new(), None);
        }
        let state_names: Vec<&str> = unique.iter().map(|s| s.name.name.as_str()).collect();
        scope.state_ids = ids.iter().map(|(name, (id, _))| (name.to_string(), id.0)).collect();
        scope.state_names = state_names.iter().map(|name| name.to_string()).collect();
        self.collect_captures(skill, &unique, scope);

        let mut states = Vec::new();
        let mut transitions = Vec::new();
        for (index, state) in unique.iter().enumerate() {
            let id = ir::StateId(index as u32);
            let kind = match &state.body {
                ast::StateBody::Terminal { outcome, message } => {
                    let outcome = match outcome.name.as_str() {
                        "success" => Some(ir::Outcome::Success),
                        "failure" => Some(ir::Outcome::Failure),
                        other => {
                            let diag = self
                                .diag(
                                    Code::UnknownOutcome,
                                    outcome.span,
                                    format!("unknown outcome `{other}`"),
                                    "not an outcome",
                                )
                                .help(
                                    suggest(other, ["success", "failure"])
                                        .unwrap_or_else(|| "a terminal is `success` or `failure`".to_string()),
                                );
                            self.report(diag);
                            None
                        }
                    };
                    outcome.map(|outcome| ir::StateKind::Terminal {
                        outcome,
                        message: message.clone(),
                    })
                }
                ast::StateBody::Active(stmts) => self
                    .active_state(id, stmts, state, &ids, &state_names, scope, &mut transitions)
                    .map(|active| ir::StateKind::Active(Box::new(active))),
            };
            if let Some(kind) = kind {
                states.push(ir::State {
                    id,
                    name: state.name.name.clone(),
                    doc: state.doc.join("\n"),
                    kind,
                    span: self.ir_span(state.name.span),
                });
            }
        }
        // The machine's shape comes from the source, so it is analysed even when guards or
        // statements have errors; only unknown targets make the analysis meaningless.
        let mut successors: Vec<Vec<usize>> = vec![Vec::new(); unique.len()];
        let mut targets_known = true;
        for (index, state) in unique.iter().enumerate() {
            let ast::StateBody::Active(stmts) = &state.body else {
                continue;
            };
            for stmt in stmts {
                let StmtKind::Transition { target, .. } = &stmt.kind else {
                    continue;
                };
                let name = match target {
                    ast::Target::State(name) => name,
                    ast::Target::Extend { then, .. } => then,
                };
                match ids.get(name.name.as_str()) {
                    Some((target, _)) => successors[index].push(target.index()),
                    None => targets_known = false,
                }
            }
        }
        if targets_known {
            let terminal: Vec<bool> = unique
                .iter()
                .map(|state| matches!(state.body, ast::StateBody::Terminal { .. }))
                .collect();
            self.graph(&unique, &successors, &terminal);
            self.at_before_capture(&unique, &successors, scope);
        }
        self.unused_captures(scope);
        (states, transitions, Some(ir::StateId(0)))
    }

    #[allow(clippy::too_many_arguments)] // One call site; the pieces are the checker's context.
    fn active_state(
        &mut self,
        id: ir::StateId,
        stmts: &[ast::Stmt],
        state: &ast::State,
        ids: &HashMap<&str, (ir::StateId, Span)>,
        state_names: &[&str],
        scope: &mut SkillScope,
        transitions: &mut Vec<ir::Transition>,
    ) -> Option<ir::ActiveState> {
        let errors_before = self.error_count();
        let mut seen: HashMap<&'static str, Span> = HashMap::new();
        let mut motion = None;
        let mut motion_relative = false;
        let mut motion_at = None;
        let mut motion_at_offset = None;
        let mut capture = None;
        let mut capture_once = false;
        let mut frame = ir::FrameRef::Base;
        let mut position_controlled = [true; 6];
        let mut control_span = None;
        let mut stiffness = DEFAULT_STIFFNESS;
        let mut force = None;
        let mut apply_span = None;
        let mut gains = DEFAULT_GAINS;
        let mut gains_span = None;
        let mut entry = Vec::new();
        let mut approach = None;
        let mut approach_span = None;
        let mut lift_off = None;
        let mut lift_off_span = None;
        let mut repeat = None;
        let mut repeat_span = None;
        let mut state_transitions: Vec<(ir::Transition, &ast::Guard, Span)> = Vec::new();

        for stmt in stmts {
            let keyword = match &stmt.kind {
                StmtKind::Move { .. } => Some("move"),
                StmtKind::Control { .. } => Some("control"),
                StmtKind::Stiffness(_) => Some("stiffness"),
                StmtKind::Apply(_) => Some("apply"),
                StmtKind::Gains(_) => Some("gains"),
                StmtKind::Entry(_) => Some("entry"),
                StmtKind::Approach { .. } => Some("approach"),
                StmtKind::LiftOff { .. } => Some("lift off"),
                StmtKind::Repeat(_) => Some("repeat"),
                StmtKind::Capture { .. } => Some("capture"),
                StmtKind::Transition { .. } => None,
            };
            if let Some(keyword) = keyword {
                if let Some(earlier) = seen.get(keyword) {
                    let diag = self
                        .diag(
                            Code::DuplicateStatement,
                            stmt.span,
                            format!("state `{}` has two `{keyword}` statements", state.name.name),
                            "second one",
                        )
                        .label(*earlier, "first one here")
                        .help(match keyword {
                            "capture" => "a state captures one pose, its entry pose: keep one name for it".to_string(),
                            _ => format!("a state has at most one `{keyword}`; merge them"),
                        });
                    self.report(diag);
                    continue;
                }
                seen.insert(keyword, stmt.span);
            }
            match &stmt.kind {
                StmtKind::Move {
                    motion: name,
                    relative,
                    at,
                    offset,
                    ..
                } => {
                    motion = self.resolve(name, SymKind::Motion, scope).map(ir::MotionId);
                    motion_relative = *relative;
                    if let Some(at) = at {
                        motion_at = self.move_at(name, at, *relative, scope);
                    }
                    if let Some(offset) = offset {
                        let value = self.vector3(&offset.value, Dim::Length, "the offset from a captured pose");
                        let frame = match &offset.frame {
                            Some(name) => self.frame_ref(name, scope),
                            None => Some(ir::FrameRef::Base),
                        };
                        if let (Some(offset_m), Some(frame)) = (value, frame) {
                            motion_at_offset = Some(ir::AtOffset { offset_m, frame });
                        }
                    }
                }
                StmtKind::Capture { name, once } => {
                    capture = Some(name.name.clone());
                    capture_once = once.is_some();
                }
                StmtKind::Control {
                    groups,
                    frame: frame_name,
                } => {
                    control_span = Some(stmt.span);
                    if let Some(name) = frame_name {
                        if let Some(resolved) = self.frame_ref(name, scope) {
                            frame = resolved;
                        }
                    }
                    if let Some(selection) = self.selection(groups, stmt.span) {
                        position_controlled = selection;
                    }
                }
                StmtKind::Stiffness(values) => self.stiffness(values, &mut stiffness),
                StmtKind::Apply(name) => {
                    apply_span = Some(stmt.span);
                    force = self.resolve(name, SymKind::Force, scope).map(ir::ForceId);
                }
                StmtKind::Gains(args) => {
                    gains_span = Some(stmt.span);
                    gains = self.gains(args);
                }
                StmtKind::Entry(actions) => {
                    for action in actions {
                        if let Some(action) = self.entry_action(action, scope) {
                            entry.push(action);
                        }
                    }
                }
                StmtKind::Approach { within, speed } => {
                    approach_span = Some(stmt.span);
                    approach = self.approach(within, speed);
                }
                StmtKind::LiftOff { distance, speed } => {
                    lift_off_span = Some(stmt.span);
                    lift_off = self.lift_off(distance, speed.as_ref(), stmt.span);
                }
                StmtKind::Repeat(count) => {
                    repeat_span = Some(stmt.span);
                    repeat = self.repeat_count(count);
                }
                StmtKind::Transition { watch, guard, target } => {
                    let resolved_guard = self.guard(guard, scope);
                    let action = self.target(target, ids, state_names, scope);
                    if let (Some(resolved_guard), Some(action)) = (resolved_guard, action) {
                        let transition = ir::Transition {
                            id: ir::TransitionId(0),
                            from: id,
                            guard: resolved_guard,
                            action,
                            guard_text: self
                                .src
                                .slice(guard.span)
                                .split_whitespace()
                                .collect::<Vec<_>>()
                                .join(" "),
                            watch: watch.is_some(),
                            span: self.ir_span(stmt.span),
                        };
                        state_transitions.push((transition, guard, stmt.span));
                    }
                }
            }
        }

        let has_force_axes = position_controlled.iter().any(|p| !p);
        if has_force_axes && force.is_none() && apply_span.is_none() {
            let span = control_span.unwrap_or(state.name.span);
            let diag = self
                .diag(
                    Code::MissingForceSource,
                    span,
                    format!("state `{}` force-controls axes but applies no force", state.name.name),
                    "force-controlled axes here",
                )
                .help(
                    "add `apply NAME` with a force from `learn`, or declare `force NAME = tracked` for pure compliance",
                );
            self.report(diag);
        }
        if !has_force_axes {
            if let Some(span) = apply_span {
                let diag = self
                    .diag(
                        Code::ForceWithoutForceAxes,
                        span,
                        format!(
                            "state `{}` applies a force but controls no axis in force",
                            state.name.name
                        ),
                        "this force is ignored",
                    )
                    .help("make an axis force-controlled, e.g. `control force z, position x y rx ry rz in FRAME`");
                self.report(diag);
            }
        }
        if has_force_axes && gains_span.is_some() && gains.integral_limit_n.is_none() && gains.ki > 0.0 {
            let diag = self
                .diag(
                    Code::NoIntegralLimit,
                    gains_span.unwrap_or(state.name.span),
                    format!("the force integral of state `{}` is unbounded", state.name.name),
                    "no `limit`",
                )
                .help("add `limit: 10 N` so the integral cannot wind up while contact is lost");
            self.report(diag);
        }

        // A `move` that failed to resolve still runs a motion: judge guards by what was written.
        let writes_move = seen.contains_key("move");
        if let Some(span) = approach_span {
            self.approach_use(state, stmts, span, writes_move);
        }
        if let Some(span) = lift_off_span {
            let lifts = lift_off.is_some_and(|spec| spec.distance_m > 0.0);
            let approaches = approach_span.is_some()
                || stmts.iter().any(|stmt| match &stmt.kind {
                    StmtKind::Transition { guard, watch, .. } => watch.is_none() && mentions_force(guard),
                    _ => false,
                });
            self.lift_off_use(state, span, writes_move, lifts && (has_force_axes || approaches));
        }
        if let (Some(span), false) = (repeat_span, writes_move) {
            let diag = self
                .diag(
                    Code::RepeatWithoutMove,
                    span,
                    format!("state `{}` repeats but runs no motion", state.name.name),
                    "nothing to repeat",
                )
                .help("add `move MOTION` to this state: `repeat N` runs its motion N times");
            self.report(diag);
        }
        self.transition_analysis(state, &state_transitions, writes_move, force, has_force_axes, scope);

        if self.error_count() > errors_before {
            return None;
        }
        let mut ids_out = Vec::new();
        for (mut transition, _, _) in state_transitions {
            transition.id = ir::TransitionId(transitions.len() as u32);
            ids_out.push(transition.id);
            transitions.push(transition);
        }
        Some(ir::ActiveState {
            motion,
            motion_relative,
            motion_at,
            motion_at_offset,
            capture,
            capture_once,
            frame,
            position_controlled,
            stiffness,
            force,
            gains,
            entry,
            transitions: ids_out,
            approach,
            lift_off,
            repeat,
        })
    }

    /// `repeat N`: a whole number from 1 to [`MAX_REPEAT`].
    fn repeat_count(&mut self, count: &ast::Expr) -> Option<u32> {
        // A whole number out of range (0, or more than fits) gets the same message as one above
        // the maximum: the bounds are 1 and MAX_REPEAT, whatever `count` allows.
        let whole = match &count.kind {
            ExprKind::Number(number) => super::values::whole_number(&number.text),
            _ => None,
        };
        let n = match whole {
            Some(n) if (1..=u64::from(MAX_REPEAT)).contains(&n) => n as u32,
            Some(_) => {
                let diag = self
                    .diag(
                        Code::OutOfRange,
                        count.span,
                        format!("the repeat count must be between 1 and {MAX_REPEAT}"),
                        "out of range",
                    )
                    .help("split the work into several task steps, or repeat fewer times; `repeat 1` runs the motion once");
                self.report(diag);
                return None;
            }
            None => self.count(count, "the repeat count")?,
        };
        Some(n)
    }

    /// `approach within D at V`: a positive distance and a positive speed.
    fn approach(&mut self, within: &ast::Expr, speed: &ast::Expr) -> Option<ir::Approach> {
        let within_value = self.quantity(within, Dim::Length, "the approach distance");
        let within_m = self.positive(within_value, within.span, "the approach distance");
        let speed_value = self.quantity(speed, Dim::Speed, "the approach speed");
        let speed_mps = self.positive(speed_value, speed.span, "the approach speed");
        Some(ir::Approach {
            within_m: within_m?,
            speed_mps: speed_mps?,
        })
    }

    /// An `approach` needs a motion to slow down, and is pointless without a force guard.
    fn approach_use(&mut self, state: &ast::State, stmts: &[ast::Stmt], span: Span, writes_move: bool) {
        if !writes_move {
            let diag = self
                .diag(
                    Code::ApproachWithoutMove,
                    span,
                    format!("state `{}` declares an approach but runs no motion", state.name.name),
                    "no `move` to slow down",
                )
                .help("add `move MOTION` to this state, or declare the approach in the state that moves towards the contact");
            self.report(diag);
            return;
        }
        // A `watch` guard expects no contact: an approach is slowed for guards that do.
        let watches_force = stmts.iter().any(|stmt| match &stmt.kind {
            StmtKind::Transition { guard, watch, .. } => watch.is_none() && mentions_force(guard),
            _ => false,
        });
        if !watches_force {
            let diag = self
                .diag(
                    Code::ApproachWithoutForceGuard,
                    span,
                    format!(
                        "state `{}` approaches a contact that no guard waits for",
                        state.name.name
                    ),
                    "no `force(...)` guard in this state",
                )
                .help("add `on force(FRAME.z) >= THRESHOLD -> STATE` to leave the state on contact, or remove the approach");
            self.report(diag);
        }
    }

    /// `lift off D [at V]`: a distance of zero or more, and a positive speed when it lifts.
    fn lift_off(&mut self, distance: &ast::Expr, speed: Option<&ast::Expr>, span: Span) -> Option<ir::LiftOffSpec> {
        let distance_m = self.quantity(distance, Dim::Length, "the lift-off distance");
        if distance_m.is_some_and(|d| d < 0.0) {
            let diag = self
                .diag(
                    Code::OutOfRange,
                    distance.span,
                    "the lift-off distance is negative",
                    "negative distance",
                )
                .help("lift a positive distance away from the surface, or write `lift off 0 mm` for no lift");
            self.report(diag);
            return None;
        }
        let speed_mps = match speed {
            Some(speed) => {
                let value = self.quantity(speed, Dim::Speed, "the lift-off speed");
                self.positive(value, speed.span, "the lift-off speed")
            }
            None if distance_m.is_some_and(|d| d > 0.0) => {
                let diag = self
                    .diag(Code::BadArgument, span, "a lift-off needs a speed", "how fast?")
                    .help(format!("write `lift off {} at 25 mm/s`", self.src.slice(distance.span)));
                self.report(diag);
                None
            }
            // `lift off 0 mm`: no lift, no speed.
            None => Some(0.0),
        };
        Some(ir::LiftOffSpec {
            distance_m: distance_m?,
            speed_mps: speed_mps?,
        })
    }

    /// A `lift off` needs a motion to pause; it is never used where the state force-controls an
    /// axis or approaches a contact (the runtime lifts off only on a learned path under pure
    /// position control that expects no contact).
    fn lift_off_use(&mut self, state: &ast::State, span: Span, writes_move: bool, ignored: bool) {
        if !writes_move {
            let diag = self
                .diag(
                    Code::LiftOffWithoutMove,
                    span,
                    format!("state `{}` declares a lift-off but runs no motion", state.name.name),
                    "no `move` to lift off before",
                )
                .help("add `move MOTION` to this state, or declare the lift-off in the state that leaves the contact");
            self.report(diag);
            return;
        }
        if ignored {
            let diag = self
                .diag(
                    Code::LiftOffIgnored,
                    span,
                    format!("state `{}` never lifts off", state.name.name),
                    "never used here",
                )
                .help("only a state under pure position control that approaches no contact (no `approach`, no `force(...)` guard) lifts off; move the lift-off to a state that leaves the contact, or remove it");
            self.report(diag);
        }
    }

    /// The axes of a `control` statement as position (`true`) or force (`false`).
    fn selection(&mut self, groups: &[ast::ControlGroup], span: Span) -> Option<[bool; 6]> {
        let mut assigned: [Option<(bool, Span)>; 6] = [None; 6];
        let mut ok = true;
        for group in groups {
            for (axis, axis_span) in self.axis_list(&group.axes) {
                let Some(axis) = axis else {
                    ok = false;
                    continue;
                };
                if let Some((_, earlier)) = assigned[axis.index()] {
                    let diag = self
                        .diag(
                            Code::RepeatedAxis,
                            axis_span,
                            format!("axis `{}` is assigned twice", axis.name()),
                            "again here",
                        )
                        .label(earlier, "first assigned here")
                        .help("name each of x y z rx ry rz once");
                    self.report(diag);
                    ok = false;
                    continue;
                }
                assigned[axis.index()] = Some((!group.force, axis_span));
            }
        }
        let missing: Vec<&str> = ir::Axis::ALL
            .iter()
            .filter(|axis| assigned[axis.index()].is_none())
            .map(|axis| axis.name())
            .collect();
        if ok && !missing.is_empty() {
            let diag = self
                .diag(
                    Code::MissingAxis,
                    span,
                    format!("`control` leaves {} unassigned", join_ticked(&missing)),
                    "not every axis is assigned",
                )
                .help(format!("add `, position {}`", missing.join(" ")));
            self.report(diag);
            ok = false;
        }
        ok.then(|| assigned.map(|slot| slot.is_none_or(|(position, _)| position)))
    }

    fn axis_list(&mut self, axes: &AxisSet) -> Vec<(Option<ir::Axis>, Span)> {
        match axes {
            AxisSet::All(span) => ir::Axis::ALL.iter().map(|axis| (Some(*axis), *span)).collect(),
            AxisSet::List(names) => names.iter().map(|name| (self.axis(name), name.span)).collect(),
        }
    }

    fn stiffness(&mut self, values: &[ast::AxisValue], stiffness: &mut [f64; 6]) {
        let mut assigned: [Option<Span>; 6] = [None; 6];
        for value in values {
            let axes = self.axis_list(&value.axes);
            let translation = axes.iter().any(|(axis, _)| axis.is_some_and(|a| !a.is_rotation()));
            let rotation = axes.iter().any(|(axis, _)| axis.is_some_and(|a| a.is_rotation()));
            if translation && rotation {
                let diag = self
                    .diag(
                        Code::UnitMismatch,
                        value.axes.span(),
                        "one stiffness cannot serve translations and rotations",
                        "mixes x y z with rx ry rz",
                    )
                    .help("write `x y z: 1500 N/m, rx ry rz: 150 Nm/rad`");
                self.report(diag);
                continue;
            }
            let dim = if rotation { Dim::RotStiffness } else { Dim::Stiffness };
            let Some(k) = self.quantity(&value.value, dim, "the stiffness") else {
                continue;
            };
            if k <= 0.0 {
                let diag = self
                    .diag(
                        Code::NonPositiveStiffness,
                        value.value.span,
                        "stiffness must be positive",
                        "zero or negative",
                    )
                    .help("to let an axis comply, force-control it with `control force ...` instead");
                self.report(diag);
                continue;
            }
            for (axis, span) in axes {
                let Some(axis) = axis else { continue };
                if let Some(earlier) = assigned[axis.index()] {
                    let diag = self
                        .diag(
                            Code::RepeatedAxis,
                            span,
                            format!("stiffness of `{}` is given twice", axis.name()),
                            "again here",
                        )
                        .label(earlier, "first given here");
                    self.report(diag);
                    continue;
                }
                assigned[axis.index()] = Some(span);
                stiffness[axis.index()] = k;
            }
        }
    }

    fn gains(&mut self, args: &[ast::Arg]) -> ir::ForceGains {
        let bound = self.bind_args("gains", args, &["kp", "ki", "limit"], 0);
        let mut gains = ir::ForceGains {
            kp: DEFAULT_GAINS.kp,
            ki: DEFAULT_GAINS.ki,
            integral_limit_n: None,
        };
        for (name, slot) in [("kp", &mut gains.kp), ("ki", &mut gains.ki)] {
            if let Some(expr) = bound.get(name) {
                if let Some(value) = self.plain_number(expr, &format!("the gain `{name}`")) {
                    if value < 0.0 {
                        let diag = self
                            .diag(
                                Code::NegativeGain,
                                expr.span,
                                format!("the gain `{name}` is negative"),
                                "negative gain",
                            )
                            .help(
                                "force gains are zero or positive; a negative gain pushes away from the desired force",
                            );
                        self.report(diag);
                    } else {
                        *slot = value;
                    }
                }
            }
        }
        if let Some(expr) = bound.get("limit") {
            if let Some(value) = self.quantity(expr, Dim::Force, "the integral limit") {
                if value < 0.0 {
                    let diag = self
                        .diag(
                            Code::NegativeGain,
                            expr.span,
                            "the integral limit is negative",
                            "negative limit",
                        )
                        .help("write a positive bound such as `limit: 10 N`");
                    self.report(diag);
                } else {
                    gains.integral_limit_n = Some(value);
                }
            }
        }
        gains
    }

    fn entry_action(&mut self, expr: &ast::Expr, scope: &mut SkillScope) -> Option<ir::EntryAction> {
        const ACTIONS: [&str; 3] = ["reset_integral", "tare", "shift_goal"];
        match &expr.kind {
            ExprKind::Name(name) if name.name == "reset_integral" => Some(ir::EntryAction::ResetIntegral),
            ExprKind::Name(name) if name.name == "tare" => Some(ir::EntryAction::Tare),
            ExprKind::Call { name, args } if name.name == "shift_goal" => {
                let args = Args {
                    function: "shift_goal",
                    example: "shift_goal(along: contact.z, by: 5 mm)",
                    span: expr.span,
                    bound: self.bind_args("shift_goal", args, &["along", "by"], 0),
                };
                let along = self.along(&args, scope);
                let distance = self
                    .required(&args, "by")
                    .and_then(|by| self.quantity(by, Dim::Length, "the goal shift"));
                Some(ir::EntryAction::ShiftGoal {
                    along: along?,
                    distance_m: distance?,
                })
            }
            ExprKind::Name(name) | ExprKind::Call { name, .. } => {
                let diag = self
                    .diag(
                        Code::UnknownFunction,
                        name.span,
                        format!("unknown entry action `{}`", name.name),
                        "not an action",
                    )
                    .help(
                        suggest(&name.name, ACTIONS)
                            .unwrap_or_else(|| format!("entry actions are {}", join_ticked(&ACTIONS))),
                    );
                self.report(diag);
                None
            }
            _ => {
                let diag = self
                    .diag(
                        Code::BadArgument,
                        expr.span,
                        "not an entry action",
                        "expected an action",
                    )
                    .help(format!("entry actions are {}", join_ticked(&ACTIONS)));
                self.report(diag);
                None
            }
        }
    }

    fn target(
        &mut self,
        target: &ast::Target,
        ids: &HashMap<&str, (ir::StateId, Span)>,
        state_names: &[&str],
        scope: &mut SkillScope,
    ) -> Option<ir::TransitionAction> {
        match target {
            ast::Target::State(name) => self
                .state_ref(name, ids, state_names)
                .map(|target| ir::TransitionAction::Goto { target }),
            ast::Target::Extend {
                axis, speed, max, then, ..
            } => {
                let along = self.frame_axis(axis, true, scope);
                if let Some(direction) =
                    along.and_then(|along| super::frames::known_direction(along, &scope.fixed_frames))
                {
                    self.extend_upwards(axis, direction);
                }
                let speed_value = self.quantity(speed, Dim::Speed, "the extension speed");
                let speed_mps = self.positive(speed_value, speed.span, "the extension speed");
                let max_value = self.quantity(max, Dim::Length, "the extension bound");
                let max_m = self.positive(max_value, max.span, "the extension bound");
                let then = self.state_ref(then, ids, state_names);
                Some(ir::TransitionAction::Extend {
                    along: along?,
                    speed_mps: speed_mps?,
                    max_m: max_m?,
                    then: then?,
                })
            }
        }
    }

    /// `extend along base.z`: the search moves the goal along the axis's positive direction, and
    /// this one points up (more than 30° above the horizontal), away from any table or part below.
    fn extend_upwards(&mut self, axis: &ast::AxisRef, direction: [f64; 3]) {
        if direction[2] <= 0.5 {
            return;
        }
        let frame = axis.frame.name.as_str();
        let why = if frame == "base" {
            "the base's z points up".to_string()
        } else {
            format!("`{frame}.{}` points up in the base frame", axis.axis.name)
        };
        let diag = self
            .diag(
                Code::ExtendUpwards,
                axis.span,
                format!("`extend along {frame}.{}` searches upwards", axis.axis.name),
                format!("{why}: the goal moves away from a surface below"),
            )
            .help(
                "a search moves into the surface: extend along a contact frame's z, which points into it \
                 (`frame contact = force_aligned(at: end(segment 1))`, then `extend along contact.z`), \
                 or along a literal frame turned over (`fixed(origin: [...], rpy: [180 deg, 0 deg, 0 deg])`)",
            );
        self.report(diag);
    }

    fn state_ref(
        &mut self,
        name: &ast::Ident,
        ids: &HashMap<&str, (ir::StateId, Span)>,
        state_names: &[&str],
    ) -> Option<ir::StateId> {
        if let Some((id, _)) = ids.get(name.name.as_str()) {
            return Some(*id);
        }
        let help = suggest(&name.name, state_names.iter().copied())
            .unwrap_or_else(|| format!("states: {}", join_ticked(state_names)));
        let diag = self
            .diag(
                Code::UnknownName,
                name.span,
                format!("unknown state `{}`", name.name),
                "no state of this name",
            )
            .help(help);
        self.report(diag);
        None
    }
}

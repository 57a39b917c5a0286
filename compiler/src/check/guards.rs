//! Guards: resolving them, and the logic that finds transitions that can never fire, repeat an
//! earlier guard, or wait for contact with no way out.

use super::scope::{SkillScope, SymKind};
use super::{suggest, Checker};
use crate::ast::{self, ExprKind, GuardKind};
use crate::diag::Code;
use crate::source::Span;
use crate::units::Dim;
use skill_ir as ir;

/// Guards written as a bare name.
const NAMED_GUARDS: [&str; 1] = ["motion_done"];

impl Checker<'_> {
    pub(super) fn guard(&mut self, guard: &ast::Guard, scope: &mut SkillScope) -> Option<ir::Guard> {
        match &guard.kind {
            GuardKind::Or(parts) | GuardKind::And(parts) => {
                let resolved: Vec<Option<ir::Guard>> = parts.iter().map(|part| self.guard(part, scope)).collect();
                let resolved: Option<Vec<ir::Guard>> = resolved.into_iter().collect();
                let resolved = resolved?;
                Some(if matches!(guard.kind, GuardKind::Or(_)) {
                    ir::Guard::Or { any: resolved }
                } else {
                    ir::Guard::And { all: resolved }
                })
            }
            GuardKind::Not(inner) => Some(ir::Guard::Not {
                guard: Box::new(self.guard(inner, scope)?),
            }),
            GuardKind::Held { guard: inner, duration } => {
                let resolved = self.guard(inner, scope);
                let value = self.quantity(duration, Dim::Time, "the hold time");
                let duration_s = self.positive(value, duration.span, "the hold time");
                if only_time(inner) {
                    self.for_on_timed_guard(guard, resolved.as_ref(), duration_s);
                    return None;
                }
                Some(ir::Guard::Held {
                    guard: Box::new(resolved?),
                    duration_s: duration_s?,
                })
            }
            GuardKind::Force { axis, op, rhs } => {
                let along = self.frame_axis(axis, false, scope);
                let dim = match along {
                    Some(along) if along.axis.is_rotation() => Dim::Torque,
                    _ => Dim::Force,
                };
                let rhs = match &rhs.kind {
                    ExprKind::Name(name) => self.threshold_ref(name, dim, scope),
                    _ => self
                        .quantity(rhs, dim, "the threshold")
                        .map(|value| ir::Threshold::Literal { value }),
                };
                Some(ir::Guard::Force {
                    along: along?,
                    op: comparison(*op),
                    rhs: rhs?,
                })
            }
            GuardKind::Moved {
                since: Some(capture),
                axis,
                op,
                rhs,
                ..
            } => {
                if let Some(axis) = axis {
                    let diag = self
                        .diag(
                            Code::BadArgument,
                            axis.frame.span.to(axis.axis.span),
                            format!("`moved since {}` measures a distance, not along an axis", capture.name),
                            "an axis",
                        )
                        .help(format!("write `moved since {} >= 3 mm`", capture.name));
                    self.report(diag);
                }
                let capture = self.capture_named(capture, scope);
                let value = self.quantity(rhs, Dim::Length, "`moved since`");
                Some(ir::Guard::MovedSince {
                    capture: capture?,
                    op: comparison(*op),
                    value_m: value?,
                })
            }
            GuardKind::Moved { axis, op, rhs, .. } => {
                let along = axis.as_ref().map(|axis| self.frame_axis(axis, false, scope));
                let (dim, what) = match along {
                    Some(Some(along)) if along.axis.is_rotation() => (Dim::Angle, "`moved` about a rotation axis"),
                    _ => (Dim::Length, "`moved`"),
                };
                let value = match &rhs.kind {
                    ExprKind::Name(name) => {
                        let example = if dim == Dim::Angle { "5 deg" } else { "6 mm" };
                        let kind = dim.describe();
                        let diag = self
                            .diag(
                                Code::UnitMismatch,
                                name.span,
                                format!("`moved` compares with {kind} written out, not a name"),
                                "a name",
                            )
                            .help(format!(
                                "learned thresholds and forces are forces; write {kind} with its unit, like `{example}`"
                            ));
                        self.report(diag);
                        None
                    }
                    _ => self.quantity(rhs, dim, what),
                };
                let op = comparison(*op);
                match along {
                    Some(along) => Some(ir::Guard::Moved {
                        along: along?,
                        op,
                        value: value?,
                    }),
                    None => Some(ir::Guard::MovedDistance { op, value_m: value? }),
                }
            }
            GuardKind::Magnitude { moment, op, rhs } => {
                let dim = if *moment { Dim::Torque } else { Dim::Force };
                let rhs = match &rhs.kind {
                    ExprKind::Name(name) => self.threshold_ref(name, dim, scope),
                    _ => self
                        .quantity(rhs, dim, "the threshold")
                        .map(|value| ir::Threshold::Literal { value }),
                };
                let op = comparison(*op);
                Some(if *moment {
                    ir::Guard::MomentMagnitude { op, rhs: rhs? }
                } else {
                    ir::Guard::ForceMagnitude { op, rhs: rhs? }
                })
            }
            GuardKind::Entered { state, op, rhs } => {
                let count = self.count(rhs, "the number of entries");
                let Some(&id) = scope.state_ids.get(&state.name) else {
                    let names: Vec<&str> = scope.state_names.iter().map(String::as_str).collect();
                    let help = suggest(&state.name, names.iter().copied())
                        .unwrap_or_else(|| format!("states: {}", super::join_ticked(&names)));
                    let diag = self
                        .diag(
                            Code::UnknownName,
                            state.span,
                            format!("unknown state `{}`", state.name),
                            "no such state",
                        )
                        .help(help);
                    self.report(diag);
                    return None;
                };
                Some(ir::Guard::Entered {
                    state: ir::StateId(id),
                    op: comparison(*op),
                    count: count?,
                })
            }
            GuardKind::Speed { op, rhs } => {
                let value = self.quantity(rhs, Dim::Speed, "the speed")?;
                Some(ir::Guard::Speed {
                    op: comparison(*op),
                    value_mps: value,
                })
            }
            GuardKind::Timed { timeout, duration } => {
                let what = if *timeout { "the timeout" } else { "the dwell time" };
                let value = self.quantity(duration, Dim::Time, what)?;
                if value < 0.0 {
                    let diag = self.diag(
                        Code::OutOfRange,
                        duration.span,
                        format!("{what} is negative"),
                        "negative duration",
                    );
                    self.report(diag);
                    return None;
                }
                Some(if *timeout {
                    ir::Guard::Timeout { duration_s: value }
                } else {
                    ir::Guard::Dwell { duration_s: value }
                })
            }
            GuardKind::ForceReached(tolerance) => {
                let value = self.quantity(tolerance, Dim::Force, "the force tolerance");
                let tolerance_n = self.positive(value, tolerance.span, "the force tolerance")?;
                Some(ir::Guard::ForceReached { tolerance_n })
            }
            GuardKind::Named(name) => {
                if name.name == "motion_done" {
                    return Some(ir::Guard::MotionDone);
                }
                let help = match name.name.as_str() {
                    "timeout" | "dwell" => format!("`{}` needs a duration: `{} 5 s`", name.name, name.name),
                    "force_reached" => "write `force_reached within 1 N`".to_string(),
                    "contact" => "contact is a force guard: `force(contact.z) >= touch`".to_string(),
                    "moved" => "compare it: `moved >= 5 cm`, or along an axis: `moved(contact.z) >= 6 mm`".to_string(),
                    "force_magnitude" | "moment_magnitude" => {
                        format!("compare it: `{} >= {}`", name.name, if name.name == "force_magnitude" { "20 N" } else { "2 Nm" })
                    }
                    other => suggest(
                        other,
                        NAMED_GUARDS
                            .iter()
                            .copied()
                            .chain(["timeout", "dwell", "force_reached"]),
                    )
                    .unwrap_or_else(|| {
                        "guards are `motion_done`, `force(F.z) >= X`, `force_magnitude >= X`, `moment_magnitude >= X`, `moved(F.z) >= D`, `moved >= D`, `force_reached within X`, `timeout T`, `dwell T`"
                            .to_string()
                    }),
                };
                let diag = self
                    .diag(
                        Code::UnknownGuard,
                        name.span,
                        format!("unknown guard `{}`", name.name),
                        "not a guard",
                    )
                    .help(help);
                self.report(diag);
                None
            }
        }
    }

    /// `dwell 100 ms for 50 ms`: `dwell` and `timeout` already count time since entry, and once
    /// they hold they hold until the state is left, so a `for` only adds to their time.
    fn for_on_timed_guard(&mut self, held: &ast::Guard, inner: Option<&ir::Guard>, hold_s: Option<f64>) {
        let help = match (inner, hold_s) {
            (Some(ir::Guard::Dwell { duration_s }), Some(hold_s)) => {
                format!("write `dwell {}` instead", seconds(duration_s + hold_s))
            }
            (Some(ir::Guard::Timeout { duration_s }), Some(hold_s)) => {
                format!("write `timeout {}` instead", seconds(duration_s + hold_s))
            }
            _ => "add the time to the `dwell` or `timeout` and drop the `for`".to_string(),
        };
        let diag = self
            .diag(
                Code::ForOnTimedGuard,
                held.span,
                "`for` on a guard that only counts time",
                "`dwell` and `timeout` keep holding once they hold",
            )
            .help(help);
        self.report(diag);
    }

    fn threshold_ref(&mut self, name: &ast::Ident, dim: Dim, scope: &mut SkillScope) -> Option<ir::Threshold> {
        match scope.symbols.get_mut(&name.name) {
            Some(sym) if sym.kind == SymKind::Threshold => {
                sym.used = true;
                Some(ir::Threshold::Learned {
                    id: ir::ThresholdId(sym.id),
                })
            }
            Some(sym) if sym.kind == SymKind::Force => {
                sym.used = true;
                let (id, span) = (sym.id, sym.span);
                match scope.force_sources.get(id as usize) {
                    Some(
                        ir::ForceSource::Constant { .. } | ir::ForceSource::At { .. } | ir::ForceSource::Literal { .. },
                    ) => {
                        if dim == Dim::Torque {
                            let diag = self
                                .diag(
                                    Code::UnitMismatch,
                                    name.span,
                                    format!("`{}` is a force; a rotation axis compares torques", name.name),
                                    "a force",
                                )
                                .help("compare a rotation axis with a torque, like `0.5 Nm`");
                            self.report(diag);
                            return None;
                        }
                        Some(ir::Threshold::Force { id: ir::ForceId(id) })
                    }
                    _ => {
                        let diag = self
                            .diag(
                                Code::WrongKind,
                                name.span,
                                format!("`{}` is not a constant force and cannot be a threshold", name.name),
                                "a profile, not a value",
                            )
                            .label(span, "declared here")
                            .help(
                                "declare a threshold: `threshold touch = force_at(end(segment 1), along: contact.z)`",
                            );
                        self.report(diag);
                        None
                    }
                }
            }
            _ => self
                .resolve(name, SymKind::Threshold, scope)
                .map(|id| ir::Threshold::Learned {
                    id: ir::ThresholdId(id),
                }),
        }
    }

    /// Guards that can never fire, repeated guards, and contact waits without a way out.
    pub(super) fn transition_analysis(
        &mut self,
        state: &ast::State,
        transitions: &[(ir::Transition, &ast::Guard, Span)],
        has_motion: bool,
        force: Option<ir::ForceId>,
        has_force_axes: bool,
        scope: &SkillScope,
    ) {
        let force_profile = force
            .and_then(|id| scope.force_sources.get(id.index()))
            .is_some_and(|source| matches!(source, ir::ForceSource::Dmp { .. } | ir::ForceSource::Magnitude { .. }));
        for (index, (transition, guard, _)) in transitions.iter().enumerate() {
            // Atoms that cannot hold in this state.
            if let Some(reason) = impossible_atom(&transition.guard, has_motion || force_profile, has_force_axes) {
                let diag = self
                    .diag(Code::NeverFires, guard.span, "this transition can never fire", reason.0)
                    .help(reason.1);
                self.report(diag);
                continue;
            }
            if unsatisfiable(&transition.guard) {
                let diag = self
                    .diag(
                        Code::NeverFires,
                        guard.span,
                        "this transition can never fire",
                        "this guard contradicts itself",
                    )
                    .help("remove the contradicting condition");
                self.report(diag);
                continue;
            }
            let mut shadowed = false;
            for (earlier, earlier_guard, _) in &transitions[..index] {
                // An earlier `extend` keeps the state: once its search runs, later transitions
                // are evaluated whenever its guard holds.
                if matches!(earlier.action, ir::TransitionAction::Extend { .. }) {
                    continue;
                }
                if earlier.guard == transition.guard {
                    let diag = self
                        .diag(
                            Code::DuplicateGuard,
                            guard.span,
                            "this guard repeats an earlier one",
                            "same guard",
                        )
                        .label(earlier_guard.span, "first written here; it always fires first")
                        .help("remove one of the two transitions");
                    self.report(diag);
                    shadowed = true;
                    break;
                }
                if implies(&transition.guard, &earlier.guard) {
                    let diag = self
                        .diag(
                            Code::NeverFires,
                            guard.span,
                            "this transition can never fire",
                            "whenever this holds, the earlier guard holds too",
                        )
                        .label(earlier_guard.span, "this earlier transition fires first")
                        .help("reorder the transitions or make this guard weaker than the earlier one");
                    self.report(diag);
                    shadowed = true;
                    break;
                }
            }
            if shadowed {
                continue;
            }
            if let Some(later) = left_before_held(transitions, index) {
                let diag = self
                    .diag(
                        Code::NeverFires,
                        guard.span,
                        "this transition can never fire",
                        "a guard here must hold for a while first",
                    )
                    .label(later, "but this later transition leaves as soon as that guard holds")
                    .help("make the later guard stronger (hold it too, or add a condition), or remove one of the two transitions");
                self.report(diag);
                continue;
            }
            if let Some((later, earliest_s, leaves_s)) = left_before_it_can_hold(transitions, index) {
                let diag = self
                    .diag(
                        Code::NeverFires,
                        guard.span,
                        "this transition can never fire",
                        format!("holds {} after entry at the earliest", seconds(earliest_s)),
                    )
                    .label(later, format!("but this later transition leaves {} after entry", seconds(leaves_s)))
                    .help(format!(
                        "guards are tried in the order written: make the later guard wait at least {}, or this one at most {}",
                        seconds(earliest_s),
                        seconds(leaves_s)
                    ));
                self.report(diag);
            }
        }
        if has_motion || has_force_axes {
            let ends_on_entry = transitions.iter().find(|(transition, _, _)| {
                matches!(transition.action, ir::TransitionAction::Goto { .. })
                    && surely_holds_after(&transition.guard) == Some(0.0)
            });
            if let Some((_, guard, _)) = ends_on_entry {
                let what = if has_motion { "its `move`" } else { "its force control" };
                let diag = self
                    .diag(
                        Code::EndsOnEntry,
                        guard.span,
                        format!("state `{}` ends as soon as it is entered", state.name.name),
                        "holds at entry",
                    )
                    .help(format!(
                        "{what} never runs: give the guard a duration (`timeout 5 s`), or leave the state \
                         without {}",
                        if has_motion { "a `move`" } else { "`control force`" }
                    ));
                self.report(diag);
            }
        }
        let all_force_only = !transitions.is_empty()
            && transitions
                .iter()
                .all(|(transition, _, _)| only_force_atoms(&transition.guard));
        let all_force_or_movement = !transitions.is_empty()
            && transitions
                .iter()
                .all(|(transition, _, _)| only_force_or_movement_atoms(&transition.guard));
        if all_force_only {
            let diag = self
                .diag(
                    Code::ContactWaitWithoutTimeout,
                    state.name.span,
                    format!("state `{}` waits for a force with no timeout", state.name.name),
                    "may wait forever if contact never comes",
                )
                .help("add `on timeout 10 s -> STATE` or `on motion_done -> STATE`");
            self.report(diag);
        } else if all_force_or_movement {
            let diag = self
                .diag(
                    Code::ContactWaitWithoutTimeout,
                    state.name.span,
                    format!(
                        "state `{}` waits for a force or a movement with no timeout",
                        state.name.name
                    ),
                    "may wait forever if the contact never comes or the tool cannot move (a jammed button)",
                )
                .help("add `on timeout 10 s -> STATE` or `on motion_done -> STATE`");
            self.report(diag);
        }
    }
}

fn comparison(op: ast::CmpOp) -> ir::Comparison {
    match op {
        ast::CmpOp::Ge => ir::Comparison::Ge,
        ast::CmpOp::Gt => ir::Comparison::Gt,
        ast::CmpOp::Le => ir::Comparison::Le,
        ast::CmpOp::Lt => ir::Comparison::Lt,
    }
}

/// Whether a guard is `dwell`s and `timeout`s joined by `and`/`or`: it depends only on the time
/// since entry and keeps holding once it holds, so `for D` only adds `D` to its times. (`not
/// dwell 1 s for 50 ms`, true from 50 ms to 1 s, is left alone.)
fn only_time(guard: &ast::Guard) -> bool {
    match &guard.kind {
        GuardKind::Or(parts) | GuardKind::And(parts) => parts.iter().all(only_time),
        GuardKind::Timed { .. } => true,
        // A `for` inside is judged on its own.
        GuardKind::Not(_)
        | GuardKind::Held { .. }
        | GuardKind::Force { .. }
        | GuardKind::Moved { .. }
        | GuardKind::Magnitude { .. }
        | GuardKind::Speed { .. }
        | GuardKind::Entered { .. }
        | GuardKind::ForceReached(_)
        | GuardKind::Named(_) => false,
    }
}

/// A duration as a user writes it: `150 ms`, `2.5 s`.
fn seconds(duration_s: f64) -> String {
    let trim = |value: f64| {
        let text = format!("{value:.3}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    };
    if duration_s < 1.0 {
        format!("{} ms", trim(duration_s * 1e3))
    } else {
        format!("{} s", trim(duration_s))
    }
}

/// The conjunctive atoms of a guard (the guard itself when it is not an `and`).
fn conjuncts(guard: &ir::Guard) -> Vec<&ir::Guard> {
    match guard {
        ir::Guard::And { all } => all.iter().flat_map(conjuncts).collect(),
        other => vec![other],
    }
}

/// A held guard (`G for D`) that transition `index` needs, and the span of a later transition
/// that leaves the state whenever `G` holds, so that `G` never holds for `D` in the state: at
/// the first tick of any stretch in which `G` holds, the later transition (or an earlier one)
/// fires. Only when every other transition before the later one enters a state: an `extend`
/// that starts keeps the state and the later transitions unevaluated that tick.
fn left_before_held(transitions: &[(ir::Transition, &ast::Guard, Span)], index: usize) -> Option<Span> {
    let goto = |transition: &ir::Transition| matches!(transition.action, ir::TransitionAction::Goto { .. });
    let (transition, _, _) = &transitions[index];
    for atom in necessary(&transition.guard) {
        let ir::Guard::Held { guard: inner, .. } = atom else {
            continue;
        };
        for (later_index, (later, later_guard, _)) in transitions.iter().enumerate().skip(index + 1) {
            let others_enter = transitions[..later_index]
                .iter()
                .enumerate()
                .all(|(other, (t, _, _))| other == index || goto(t));
            if others_enter && goto(later) && implies(inner, &later.guard) {
                return Some(later_guard.span);
            }
        }
    }
    None
}

/// How long after the entry a guard can first hold: a held guard (`G for D`), a `dwell` and a
/// `timeout` wait from the entry, an `and` as long as its slowest part, an `or` as its quickest.
fn earliest_after_entry(guard: &ir::Guard) -> f64 {
    match guard {
        ir::Guard::Dwell { duration_s } | ir::Guard::Timeout { duration_s } => *duration_s,
        ir::Guard::Held {
            guard: inner,
            duration_s,
        } => duration_s.max(earliest_after_entry(inner)),
        ir::Guard::And { all } => all.iter().map(earliest_after_entry).fold(0.0, f64::max),
        ir::Guard::Or { any } => any.iter().map(earliest_after_entry).fold(f64::INFINITY, f64::min),
        // A negation holds from the entry if its guard does not; other atoms may hold at once.
        _ => 0.0,
    }
}

/// How long after the entry a guard surely holds, whatever the world does: a `dwell` or a
/// `timeout`, an `or` with one, an `and` of them. `None` when it may never hold.
fn surely_holds_after(guard: &ir::Guard) -> Option<f64> {
    match guard {
        ir::Guard::Dwell { duration_s } | ir::Guard::Timeout { duration_s } => Some(*duration_s),
        ir::Guard::Or { any } => any.iter().filter_map(surely_holds_after).reduce(f64::min),
        ir::Guard::And { all } => all
            .iter()
            .map(surely_holds_after)
            .try_fold(0.0, |latest: f64, part| part.map(|part| latest.max(part))),
        _ => None,
    }
}

/// A later transition that leaves the state before transition `index` can first hold
/// (`on G for 3 s -> a` before `on timeout 2 s -> b`: `b` is entered at 2 s, before `G` can have
/// held 3 s), with how long after the entry `index` can first hold and the later one surely
/// leaves. Only when every other transition before the later one enters a state: an `extend`
/// that starts keeps the state and the later transitions unevaluated that tick.
fn left_before_it_can_hold(
    transitions: &[(ir::Transition, &ast::Guard, Span)],
    index: usize,
) -> Option<(Span, f64, f64)> {
    let goto = |transition: &ir::Transition| matches!(transition.action, ir::TransitionAction::Goto { .. });
    let earliest_s = earliest_after_entry(&transitions[index].0.guard);
    if earliest_s <= 0.0 {
        return None;
    }
    for (later_index, (later, later_guard, _)) in transitions.iter().enumerate().skip(index + 1) {
        let others_enter = transitions[..later_index]
            .iter()
            .enumerate()
            .all(|(other, (t, _, _))| other == index || goto(t));
        if !others_enter {
            return None;
        }
        if let Some(leaves_s) = surely_holds_after(&later.guard).filter(|leaves_s| *leaves_s < earliest_s) {
            if goto(later) {
                return Some((later_guard.span, earliest_s, leaves_s));
            }
        }
    }
    None
}

/// What a guard holding implies at the same evaluation, as atoms: its conjuncts and, for a held
/// guard (`g for D`), also what `g` implies, since it holds only while `g` holds. A `not` or an
/// `or` is one atom: nothing is read into them.
fn necessary(guard: &ir::Guard) -> Vec<&ir::Guard> {
    match guard {
        ir::Guard::And { all } => all.iter().flat_map(necessary).collect(),
        ir::Guard::Held { guard: inner, .. } => {
            let mut atoms = vec![guard];
            atoms.extend(necessary(inner));
            atoms
        }
        other => vec![other],
    }
}

/// Whether `a` holding guarantees `b` holds, for the atom forms we can compare. Every guard of a
/// state is evaluated at every tick, so implications hold tick by tick and for held guards too.
fn atom_implies(a: &ir::Guard, b: &ir::Guard) -> bool {
    use ir::Guard::*;
    if a == b {
        return true;
    }
    match (a, b) {
        (_, Dwell { duration_s } | Timeout { duration_s }) if *duration_s == 0.0 => true,
        (
            Dwell { duration_s: da } | Timeout { duration_s: da },
            Dwell { duration_s: db } | Timeout { duration_s: db },
        ) => da >= db,
        // A guard held for `da` was entered at least `da` ago.
        (Held { duration_s: da, .. }, Dwell { duration_s: db } | Timeout { duration_s: db }) => da >= db,
        // `ga` implying `gb` at every tick, `gb` has held at least as long as `ga`.
        (
            Held {
                guard: ga,
                duration_s: da,
            },
            Held {
                guard: gb,
                duration_s: db,
            },
        ) => da >= db && implies(ga, gb),
        (a, b) => match (literal_bound(a), literal_bound(b)) {
            (Some((qa, oa, va)), Some((qb, ob, vb))) if qa == qb => {
                use ir::Comparison::*;
                match (oa, ob) {
                    (Ge | Gt, Ge) => va >= vb,
                    (Gt, Gt) => va >= vb,
                    (Ge, Gt) => va > vb,
                    (Le | Lt, Le) => va <= vb,
                    (Lt, Lt) => va <= vb,
                    (Le, Lt) => va < vb,
                    _ => false,
                }
            }
            _ => false,
        },
    }
}

/// What a comparison with a literal measures (two atoms with the same one compare the same
/// number).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Measured {
    Force(ir::FrameAxis),
    Moved(ir::FrameAxis),
    Distance,
    ForceMagnitude,
    MomentMagnitude,
    Speed,
    Entered(ir::StateId),
}

/// A comparison of a measured quantity with a literal: what, how, and the literal.
fn literal_bound(guard: &ir::Guard) -> Option<(Measured, ir::Comparison, f64)> {
    use ir::Threshold::Literal;
    match *guard {
        ir::Guard::Force {
            along,
            op,
            rhs: Literal { value },
        } => Some((Measured::Force(along), op, value)),
        ir::Guard::Moved { along, op, value } => Some((Measured::Moved(along), op, value)),
        ir::Guard::MovedDistance { op, value_m } => Some((Measured::Distance, op, value_m)),
        ir::Guard::Speed { op, value_mps } => Some((Measured::Speed, op, value_mps)),
        ir::Guard::Entered { state, op, count } => Some((Measured::Entered(state), op, f64::from(count))),
        ir::Guard::ForceMagnitude {
            op,
            rhs: Literal { value },
        } => Some((Measured::ForceMagnitude, op, value)),
        ir::Guard::MomentMagnitude {
            op,
            rhs: Literal { value },
        } => Some((Measured::MomentMagnitude, op, value)),
        _ => None,
    }
}

/// Whether `later ⇒ earlier` for conjunctions of atoms: every atom of `earlier` follows from
/// some atom of `later`. Disjunctions and negations are compared only for equality.
fn implies(later: &ir::Guard, earlier: &ir::Guard) -> bool {
    let later_atoms = necessary(later);
    conjuncts(earlier)
        .iter()
        .all(|needed| later_atoms.iter().any(|have| atom_implies(have, needed)))
}

/// Whether a conjunction contradicts itself: `a and not a`, or disjoint literal force bounds.
fn unsatisfiable(guard: &ir::Guard) -> bool {
    let atoms = necessary(guard);
    for (i, a) in atoms.iter().enumerate() {
        for b in &atoms[i + 1..] {
            if let ir::Guard::Not { guard } = a {
                if guard.as_ref() == *b {
                    return true;
                }
            }
            if let ir::Guard::Not { guard } = b {
                if guard.as_ref() == *a {
                    return true;
                }
            }
            if let (Some((qa, oa, va)), Some((qb, ob, vb))) = (literal_bound(a), literal_bound(b)) {
                if qa == qb {
                    use ir::Comparison::*;
                    let lower_upper =
                        |lo_op: ir::Comparison, lo: f64, hi_op: ir::Comparison, hi: f64| match (lo_op, hi_op) {
                            (Ge, Le) => lo > hi,
                            (Ge | Gt, Le | Lt) => lo >= hi,
                            _ => false,
                        };
                    if matches!(oa, Ge | Gt) && matches!(ob, Le | Lt) && lower_upper(oa, va, ob, vb) {
                        return true;
                    }
                    if matches!(ob, Ge | Gt) && matches!(oa, Le | Lt) && lower_upper(ob, vb, oa, va) {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// An atom of a conjunction that cannot hold in this state, with a label and a help line.
fn impossible_atom(guard: &ir::Guard, runs_dmp: bool, has_force_axes: bool) -> Option<(&'static str, &'static str)> {
    for atom in necessary(guard) {
        match atom {
            ir::Guard::MotionDone if !runs_dmp => {
                return Some((
                    "`motion_done` in a state that runs no motion",
                    "add `move NAME` to the state, or wait with `dwell T` instead",
                ))
            }
            ir::Guard::ForceReached { .. } if !has_force_axes => {
                return Some((
                    "`force_reached` in a state with no force-controlled axis",
                    "force-control an axis, or compare the force: `force(FRAME.z) >= X`",
                ))
            }
            ir::Guard::ForceMagnitude {
                op,
                rhs: ir::Threshold::Literal { value },
            }
            | ir::Guard::MomentMagnitude {
                op,
                rhs: ir::Threshold::Literal { value },
            }
            | ir::Guard::MovedDistance { op, value_m: value }
            | ir::Guard::MovedSince { op, value_m: value, .. }
            | ir::Guard::Speed { op, value_mps: value }
                if below_zero(*op, *value) =>
            {
                return Some((
                    "a magnitude below zero",
                    "a force's, moment's or movement's length, or a speed, is never negative; compare with a positive value",
                ))
            }
            _ => {}
        }
    }
    None
}

/// Whether `x OP value` asks a length `x` (zero or more) to be below zero.
fn below_zero(op: ir::Comparison, value: f64) -> bool {
    match op {
        ir::Comparison::Lt => value <= 0.0,
        ir::Comparison::Le => value < 0.0,
        ir::Comparison::Ge | ir::Comparison::Gt => false,
    }
}

/// Whether every atom of a guard is a force comparison (a wait that needs contact).
fn only_force_atoms(guard: &ir::Guard) -> bool {
    match guard {
        ir::Guard::And { all } => all.iter().all(only_force_atoms),
        ir::Guard::Or { any } => any.iter().all(only_force_atoms),
        ir::Guard::Not { guard } | ir::Guard::Held { guard, .. } => only_force_atoms(guard),
        ir::Guard::Force { .. } | ir::Guard::ForceMagnitude { .. } | ir::Guard::MomentMagnitude { .. } => true,
        _ => false,
    }
}

/// Whether every atom of a guard compares a force or a movement (a wait that needs the world to
/// give way: contact, or a button that travels), and at least one a movement.
fn only_force_or_movement_atoms(guard: &ir::Guard) -> bool {
    fn all(guard: &ir::Guard) -> bool {
        match guard {
            ir::Guard::And { all: parts } | ir::Guard::Or { any: parts } => parts.iter().all(all),
            ir::Guard::Not { guard } | ir::Guard::Held { guard, .. } => all(guard),
            ir::Guard::Moved { .. } | ir::Guard::MovedDistance { .. } | ir::Guard::MovedSince { .. } => true,
            other => only_force_atoms(other),
        }
    }
    all(guard)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn longer_timeouts_imply_shorter_ones() {
        let short = ir::Guard::Timeout { duration_s: 1.0 };
        let long = ir::Guard::Dwell { duration_s: 2.0 };
        assert!(implies(&long, &short));
        assert!(!implies(&short, &long));
        let both = ir::Guard::And {
            all: vec![ir::Guard::MotionDone, long.clone()],
        };
        assert!(implies(&both, &short));
        assert!(!implies(&short, &both));
    }

    fn held(guard: ir::Guard, duration_s: f64) -> ir::Guard {
        ir::Guard::Held {
            guard: Box::new(guard),
            duration_s,
        }
    }

    #[test]
    fn a_held_guard_implies_its_guard_and_its_time_but_not_the_other_way() {
        let reached = ir::Guard::ForceReached { tolerance_n: 0.5 };
        let held_100 = held(reached.clone(), 0.1);
        assert!(implies(&held_100, &reached));
        assert!(!implies(&reached, &held_100));
        // Held 100 ms means entered at least 100 ms ago, and no more.
        assert!(implies(&held_100, &ir::Guard::Timeout { duration_s: 0.1 }));
        assert!(!implies(&held_100, &ir::Guard::Dwell { duration_s: 0.2 }));
        assert!(!implies(&ir::Guard::Dwell { duration_s: 5.0 }, &held_100));
        // Longer holds of stronger guards imply shorter holds of weaker ones.
        let held_200 = held(
            ir::Guard::And {
                all: vec![reached.clone(), ir::Guard::MotionDone],
            },
            0.2,
        );
        assert!(implies(&held_200, &held_100));
        assert!(!implies(&held_100, &held_200));
        assert!(!implies(&held(reached.clone(), 0.05), &held_100));
        // `(a and b) for D` implies `a` and `b`; `(a or b) for D` implies neither.
        assert!(implies(&held_200, &ir::Guard::MotionDone));
        let either = held(
            ir::Guard::Or {
                any: vec![reached.clone(), ir::Guard::MotionDone],
            },
            0.2,
        );
        assert!(!implies(&either, &reached));
        // A negated hold tells nothing about its guard.
        let not_held = ir::Guard::Not {
            guard: Box::new(held_100.clone()),
        };
        assert!(!implies(&not_held, &reached));
        assert!(!implies(
            &not_held,
            &ir::Guard::Not {
                guard: Box::new(reached.clone())
            }
        ));
    }

    #[test]
    fn contradictions_and_impossible_atoms_are_found_through_a_hold_only() {
        let touch = ir::Guard::MotionDone;
        let not_touch = ir::Guard::Not {
            guard: Box::new(touch.clone()),
        };
        let both = |a: ir::Guard, b: ir::Guard| ir::Guard::And { all: vec![a, b] };
        assert!(unsatisfiable(&both(held(touch.clone(), 0.1), not_touch.clone())));
        assert!(unsatisfiable(&held(both(touch.clone(), not_touch.clone()), 0.1)));
        // `not (a for D) and a` holds while `a` has not held for D yet.
        let not_held = ir::Guard::Not {
            guard: Box::new(held(touch.clone(), 0.1)),
        };
        assert!(!unsatisfiable(&both(not_held.clone(), touch.clone())));
        assert!(impossible_atom(&held(touch.clone(), 0.1), false, true).is_some());
        assert!(impossible_atom(&not_held, false, true).is_none());
        assert!(impossible_atom(&held(ir::Guard::ForceReached { tolerance_n: 1.0 }, 0.1), true, false).is_some());
    }

    fn moved(axis: ir::Axis, op: ir::Comparison, value: f64) -> ir::Guard {
        ir::Guard::Moved {
            along: ir::FrameAxis {
                frame: ir::FrameRef::Base,
                axis,
            },
            op,
            value,
        }
    }

    #[test]
    fn displacement_and_magnitude_bounds_imply_and_contradict_like_force_bounds() {
        use ir::Comparison::{Ge, Gt, Le, Lt};
        let far = moved(ir::Axis::Z, Ge, 0.008);
        let near = moved(ir::Axis::Z, Ge, 0.006);
        assert!(implies(&far, &near));
        assert!(!implies(&near, &far));
        assert!(!implies(&moved(ir::Axis::X, Ge, 0.008), &near), "another axis");
        let both = |a: ir::Guard, b: ir::Guard| ir::Guard::And { all: vec![a, b] };
        assert!(unsatisfiable(&both(far.clone(), moved(ir::Axis::Z, Lt, 0.008))));
        assert!(!unsatisfiable(&both(near.clone(), moved(ir::Axis::Z, Le, 0.008))));
        let distance = |op, value_m| ir::Guard::MovedDistance { op, value_m };
        assert!(implies(&distance(Gt, 0.1), &distance(Ge, 0.05)));
        assert!(
            !implies(&distance(Gt, 0.1), &near),
            "a distance says nothing about an axis"
        );
        let force = |op, value| ir::Guard::ForceMagnitude {
            op,
            rhs: ir::Threshold::Literal { value },
        };
        let moment = |op, value| ir::Guard::MomentMagnitude {
            op,
            rhs: ir::Threshold::Literal { value },
        };
        assert!(implies(&force(Ge, 20.0), &force(Ge, 10.0)));
        assert!(!implies(&force(Ge, 20.0), &moment(Ge, 10.0)), "a force is not a moment");
        assert!(unsatisfiable(&both(force(Ge, 20.0), force(Le, 10.0))));
        // Lengths are never negative.
        assert!(impossible_atom(&force(Lt, 0.0), true, true).is_some());
        assert!(impossible_atom(&distance(Le, -0.01), true, true).is_some());
        assert!(
            impossible_atom(&distance(Le, 0.0), true, true).is_none(),
            "holds at entry"
        );
        assert!(
            impossible_atom(&moved(ir::Axis::Z, Lt, 0.0), true, true).is_none(),
            "a signed component"
        );
    }

    #[test]
    fn a_later_guard_is_not_shadowed_by_an_earlier_extend_which_keeps_the_state() {
        let text = "skill s {
    learn {
        segments = max_force
        frame contact = force_aligned(at: end(segment 1))
        motion approach = dmp(segment 1)
    }
    state search {
        move approach from current
        on force(contact.z) >= 2 N -> done
        on dwell 0 s -> extend along contact.z at 10 mm/s, up to 5 cm, then done
        on timeout 10 s -> done
    }
    terminal done: success
}";
        let compilation = crate::compile_str("t.skill", text);
        assert!(compilation.diags.is_empty(), "{:?}", compilation.diags);
    }
}

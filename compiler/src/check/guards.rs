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
                let op = match op {
                    ast::CmpOp::Ge => ir::Comparison::Ge,
                    ast::CmpOp::Gt => ir::Comparison::Gt,
                    ast::CmpOp::Le => ir::Comparison::Le,
                    ast::CmpOp::Lt => ir::Comparison::Lt,
                };
                Some(ir::Guard::Force {
                    along: along?,
                    op,
                    rhs: rhs?,
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
                    other => suggest(
                        other,
                        NAMED_GUARDS
                            .iter()
                            .copied()
                            .chain(["timeout", "dwell", "force_reached"]),
                    )
                    .unwrap_or_else(|| {
                        "guards are `motion_done`, `force(F.z) >= X`, `force_reached within X`, `timeout T`, `dwell T`"
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
            for (earlier, earlier_guard, _) in &transitions[..index] {
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
                    break;
                }
            }
        }
        let all_force_only = !transitions.is_empty()
            && transitions
                .iter()
                .all(|(transition, _, _)| only_force_atoms(&transition.guard));
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
        }
    }
}

/// The conjunctive atoms of a guard (the guard itself when it is not an `and`).
fn conjuncts(guard: &ir::Guard) -> Vec<&ir::Guard> {
    match guard {
        ir::Guard::And { all } => all.iter().flat_map(conjuncts).collect(),
        other => vec![other],
    }
}

/// Whether `a` holding guarantees `b` holds, for the atom forms we can compare.
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
        (
            Force {
                along: la,
                op: oa,
                rhs: ir::Threshold::Literal { value: va },
            },
            Force {
                along: lb,
                op: ob,
                rhs: ir::Threshold::Literal { value: vb },
            },
        ) if la == lb => {
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
    }
}

/// Whether `later ⇒ earlier` for conjunctions of atoms: every atom of `earlier` follows from
/// some atom of `later`. Disjunctions and negations are compared only for equality.
fn implies(later: &ir::Guard, earlier: &ir::Guard) -> bool {
    let later_atoms = conjuncts(later);
    conjuncts(earlier)
        .iter()
        .all(|needed| later_atoms.iter().any(|have| atom_implies(have, needed)))
}

/// Whether a conjunction contradicts itself: `a and not a`, or disjoint literal force bounds.
fn unsatisfiable(guard: &ir::Guard) -> bool {
    let atoms = conjuncts(guard);
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
            if let (
                ir::Guard::Force {
                    along: la,
                    op: oa,
                    rhs: ir::Threshold::Literal { value: va },
                },
                ir::Guard::Force {
                    along: lb,
                    op: ob,
                    rhs: ir::Threshold::Literal { value: vb },
                },
            ) = (a, b)
            {
                if la == lb {
                    use ir::Comparison::*;
                    let lower_upper =
                        |lo_op: ir::Comparison, lo: f64, hi_op: ir::Comparison, hi: f64| match (lo_op, hi_op) {
                            (Ge, Le) => lo > hi,
                            (Ge | Gt, Le | Lt) => lo >= hi,
                            _ => false,
                        };
                    if matches!(oa, Ge | Gt) && matches!(ob, Le | Lt) && lower_upper(*oa, *va, *ob, *vb) {
                        return true;
                    }
                    if matches!(ob, Ge | Gt) && matches!(oa, Le | Lt) && lower_upper(*ob, *vb, *oa, *va) {
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
    for atom in conjuncts(guard) {
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
            _ => {}
        }
    }
    None
}

/// Whether every atom of a guard is a force comparison (a wait that needs contact).
fn only_force_atoms(guard: &ir::Guard) -> bool {
    match guard {
        ir::Guard::And { all } => all.iter().all(only_force_atoms),
        ir::Guard::Or { any } => any.iter().all(only_force_atoms),
        ir::Guard::Not { guard } => only_force_atoms(guard),
        ir::Guard::Force { .. } => true,
        _ => false,
    }
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
}

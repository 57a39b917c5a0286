//! Skill parameters: `param NAME = VALUE` declarations, the values a task step or `--param`
//! sets for them, and their substitution into the skill's states and limits before those are
//! checked, so that every use is checked (units, ranges, never-fires) with the value it runs with.

use super::arith::{self, ArithError};
use super::task::STEP_ARGS;
use super::{join_ticked, suggest, Checker};
use crate::ast::{self, ExprKind, GuardKind, StateBody, StmtKind, Target};
use crate::diag::{Code, Diag};
use crate::units::{self, Dim};
use skill_ir as ir;
use std::collections::HashMap;

/// A value given to a parameter from outside its skill: a task step's argument or `--param`.
#[derive(Debug, Clone)]
pub struct ParamSetting {
    /// The parameter's name as written where it is set.
    pub name: ast::Ident,
    /// The value, with spans into file `file`.
    pub value: ast::Expr,
    /// The file (index into the compilation's files) the setting is written in.
    pub file: usize,
    /// Who sets it.
    pub source: ir::ParamSource,
}

/// Names a parameter cannot take besides a task step's own arguments ([`STEP_ARGS`]: a step
/// sets parameters by name beside them): the words states and limits already give a meaning to.
const RESERVED_IN_STATES: [&str; 3] = ["inf", "reset_integral", "tare"];

/// What kind of value a parameter holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Shape {
    Number,
    Quantity(Dim),
    /// Three quantities of one dimension: `[0 mm, 0 mm, 5 mm]`.
    Vector(Dim),
}

impl Shape {
    fn of(expr: &ast::Expr) -> Option<Shape> {
        match &expr.kind {
            ExprKind::Number(_) => Some(Shape::Number),
            ExprKind::Quantity { unit, .. } => units::lookup(&unit.name).map(|(dim, _)| Shape::Quantity(dim)),
            ExprKind::List(items) if items.len() == 3 => {
                let dims: Vec<Option<Shape>> = items.iter().map(Shape::of).collect();
                match dims[0] {
                    Some(Shape::Quantity(dim)) if dims.iter().all(|d| *d == Some(Shape::Quantity(dim))) => {
                        Some(Shape::Vector(dim))
                    }
                    _ => None,
                }
            }
            _ => None,
        }
    }

    fn describe(self) -> String {
        match self {
            Shape::Number => "a plain number".to_string(),
            Shape::Quantity(dim) => dim.describe().to_string(),
            Shape::Vector(dim) => format!("a list of three values, each {}", dim.describe()),
        }
    }

    fn example(self) -> String {
        match self {
            Shape::Number => "3".to_string(),
            Shape::Quantity(dim) => format!("2 {}", dim.example_unit()),
            Shape::Vector(dim) => {
                let unit = dim.example_unit();
                format!("[0 {unit}, 0 {unit}, 5 {unit}]")
            }
        }
    }
}

/// The SI unit of a dimension: its unit with factor 1.
fn si_unit(dim: Dim) -> &'static str {
    units::UNITS
        .iter()
        .find(|(_, d, factor)| *d == dim && *factor == 1.0)
        .map(|(name, _, _)| *name)
        .unwrap_or("")
}

/// One parameter with the value it takes in this compilation.
struct Bound<'s> {
    decl: &'s ast::ParamDecl,
    shape: Shape,
    value: ast::Expr,
    source: ir::ParamSource,
    /// Whether the default names parameters declared before it: it is evaluated again with
    /// their values once settings are applied.
    derived: bool,
}

/// `default` with the values of the parameters `earlier` substituted for their names.
fn with_earlier(default: &ast::Expr, earlier: &[Bound<'_>]) -> ast::Expr {
    let values: HashMap<&str, &ast::Expr> = earlier.iter().map(|b| (b.decl.name.name.as_str(), &b.value)).collect();
    let mut value = default.clone();
    substitute(&mut value, &values, &mut HashMap::new());
    value
}

impl Checker<'_> {
    /// Checks a skill whose parameters take their defaults, overridden by `settings`; returns
    /// its IR, with the values used listed in [`ir::Skill::params`], when there is no error.
    /// `warn_unused` reports parameters the body never uses (off for a task step's copy, whose
    /// warnings the skill's own check already gave).
    pub(crate) fn skill_with(
        &mut self,
        skill: &ast::Skill,
        settings: &[ParamSetting],
        warn_unused: bool,
    ) -> Option<ir::Skill> {
        let bound = self.bind_params(skill, settings)?;
        let values: HashMap<&str, &ast::Expr> = bound.iter().map(|b| (b.decl.name.name.as_str(), &b.value)).collect();
        let mut body = skill.clone();
        let mut used: HashMap<String, bool> = values.keys().map(|name| (name.to_string(), false)).collect();
        // A parameter another's default uses is used.
        for derived in bound.iter().filter(|b| b.derived) {
            visit_names(&derived.decl.value, &mut |name| {
                if let Some(flag) = used.get_mut(&name.name) {
                    *flag = true;
                }
            });
        }
        self.params_in_learn(&body, &values);
        let mut unfolded = Vec::new();
        substitute_body(&mut body, &values, &mut used, &mut unfolded);
        if !unfolded.is_empty() {
            for error in unfolded {
                self.report(error.into_diag(self.file));
            }
            return None;
        }
        if warn_unused {
            for b in &bound {
                if !used.get(&b.decl.name.name).copied().unwrap_or(true) {
                    let diag = self
                        .diag(
                            Code::Unused,
                            b.decl.name.span,
                            format!("parameter `{}` is never used", b.decl.name.name),
                            "unused",
                        )
                        .help("use it in a state or a limit by its name, or remove it");
                    self.report(diag);
                }
            }
        }
        let mut lowered = self.skill(&body)?;
        lowered.params = bound
            .iter()
            .filter_map(|b| {
                let si = |expr: &ast::Expr| match &expr.kind {
                    ExprKind::Quantity { number, unit } => units::lookup(&unit.name).map(|(_, f)| number.value * f),
                    _ => None,
                };
                let mut vector_si = None;
                let (value_si, unit) = match (&b.value.kind, b.shape) {
                    (ExprKind::Number(number), Shape::Number) => (number.value, String::new()),
                    (ExprKind::Quantity { .. }, Shape::Quantity(dim)) => (si(&b.value)?, si_unit(dim).to_string()),
                    (ExprKind::List(items), Shape::Vector(dim)) => {
                        vector_si = Some([si(&items[0])?, si(&items[1])?, si(&items[2])?]);
                        (0.0, si_unit(dim).to_string())
                    }
                    _ => return None,
                };
                Some(ir::Param {
                    name: b.decl.name.name.clone(),
                    value_si,
                    vector_si,
                    unit,
                    set_by: b.source.clone(),
                    doc: b.decl.doc.join("\n"),
                })
            })
            .collect();
        Some(lowered)
    }

    /// Checks the declarations and the settings against them.
    fn bind_params<'s>(&mut self, skill: &'s ast::Skill, settings: &[ParamSetting]) -> Option<Vec<Bound<'s>>> {
        let errors_before = self.error_count();
        let mut taken: HashMap<&str, (ast::Ident, &'static str)> = HashMap::new();
        for decl in &skill.learn {
            if let Some(name) = &decl.name {
                taken.insert(&name.name, (name.clone(), decl.kind.keyword()));
            }
        }
        // States are named only where a state is expected (`-> NAME`), never where a value is:
        // a parameter may share a state's name.
        let mut bound: Vec<Bound<'s>> = Vec::new();
        for decl in &skill.params {
            let name = &decl.name;
            if let Some(earlier) = bound.iter().find(|b| b.decl.name.name == name.name) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        name.span,
                        format!("parameter `{}` is declared twice", name.name),
                        "second declaration",
                    )
                    .label(earlier.decl.name.span, "first declared here")
                    .help("remove or rename one of them");
                self.report(diag);
                continue;
            }
            if let Some((other, kind)) = taken.get(name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        name.span,
                        format!("`{}` names a parameter and a {kind}", name.name),
                        "parameter",
                    )
                    .label(other.span, format!("the {kind}"))
                    .help("a parameter's name must be unique in its skill: rename one of them");
                self.report(diag);
                continue;
            }
            if STEP_ARGS.contains(&name.name.as_str()) || RESERVED_IN_STATES.contains(&name.name.as_str()) {
                let diag = self
                    .diag(
                        Code::DuplicateName,
                        name.span,
                        format!("`{}` cannot name a parameter", name.name),
                        "reserved",
                    )
                    .help(format!(
                        "it already means something to a task step ({}) or a state ({}): rename it, e.g. `{}_value`",
                        join_ticked(&STEP_ARGS),
                        join_ticked(&RESERVED_IN_STATES),
                        name.name
                    ));
                self.report(diag);
                continue;
            }
            let Some(derived) = self.earlier_params_in(decl, skill, &bound) else {
                continue;
            };
            let mut value = if derived {
                with_earlier(&decl.value, &bound)
            } else {
                decl.value.clone()
            };
            if !self.fold_reporting(&mut value) {
                continue;
            }
            let Some(shape) = Shape::of(&value) else {
                let mut diag = self.diag(
                    Code::BadArgument,
                    decl.value.span,
                    format!(
                        "parameter `{}` needs a number, a quantity or three quantities as its default",
                        name.name
                    ),
                    "not a number or a quantity",
                );
                diag = match &decl.value.kind {
                    ExprKind::Quantity { unit, .. } => diag.help(format!(
                        "unknown unit `{}`; units skillc knows: {}",
                        unit.name,
                        units::UNITS.iter().map(|(n, _, _)| *n).collect::<Vec<_>>().join(", ")
                    )),
                    _ => diag.help(format!(
                        "write e.g. `param {0} = 2 s`, `param {0} = 3` or `param {0} = [0 mm, 0 mm, 5 mm]`",
                        name.name
                    )),
                };
                self.report(diag);
                continue;
            };
            if !finite_literal(&value) {
                let diag = self.diag(
                    Code::OutOfRange,
                    decl.value.span,
                    format!("parameter `{}` is not finite", name.name),
                    "too large",
                );
                self.report(diag);
                continue;
            }
            bound.push(Bound {
                decl,
                shape,
                value,
                source: ir::ParamSource::Default,
                derived,
            });
        }
        for setting in settings {
            let Some(slot) = bound.iter_mut().find(|b| b.decl.name.name == setting.name.name) else {
                let names: Vec<&str> = skill.params.iter().map(|p| p.name.name.as_str()).collect();
                let help = suggest(&setting.name.name, names.iter().copied()).unwrap_or_else(|| {
                    if names.is_empty() {
                        format!("`{}` declares no parameter", skill.name.name)
                    } else {
                        format!("its parameters: {}", join_ticked(&names))
                    }
                });
                let diag = Diag::new(
                    Code::UnknownName,
                    setting.file,
                    setting.name.span,
                    format!("skill `{}` has no parameter `{}`", skill.name.name, setting.name.name),
                    "no such parameter",
                )
                .help(help);
                self.report(diag);
                continue;
            };
            let mut value = setting.value.clone();
            if !self.fold_in(&mut value, setting.file) {
                continue;
            }
            let found = Shape::of(&value);
            if found != Some(slot.shape) || !finite_literal(&value) {
                let what = match found {
                    Some(shape) if finite_literal(&value) => shape.describe(),
                    Some(_) => "not finite".to_string(),
                    None => "not a number or a quantity".to_string(),
                };
                let diag = Diag::new(
                    Code::UnitMismatch,
                    setting.file,
                    setting.value.span,
                    format!(
                        "parameter `{}` of `{}` is {}, this value is {what}",
                        setting.name.name,
                        skill.name.name,
                        slot.shape.describe()
                    ),
                    "wrong kind of value",
                )
                .help(format!(
                    "give {} like its default `{}`, e.g. `{}`",
                    slot.shape.describe(),
                    crate::fmt::expr_text(&slot.decl.value),
                    slot.shape.example()
                ));
                self.report(diag);
                continue;
            }
            slot.value = value;
            slot.source = setting.source.clone();
        }
        // Defaults that use earlier parameters follow the values those were set to.
        for index in 0..bound.len() {
            if !bound[index].derived || !matches!(bound[index].source, ir::ParamSource::Default) {
                continue;
            }
            let mut value = with_earlier(&bound[index].decl.value, &bound[..index]);
            if !self.fold_reporting(&mut value) {
                continue;
            }
            if Shape::of(&value) != Some(bound[index].shape) || !finite_literal(&value) {
                let decl = bound[index].decl;
                let set: Vec<String> = bound[..index]
                    .iter()
                    .filter(|b| !matches!(b.source, ir::ParamSource::Default))
                    .map(|b| format!("`{}` = {}", b.decl.name.name, crate::fmt::expr_text(&b.value)))
                    .collect();
                let diag = self
                    .diag(
                        Code::UnitMismatch,
                        decl.value.span,
                        format!(
                            "with {}, the default of `{}` is not {}",
                            set.join(", "),
                            decl.name.name,
                            bound[index].shape.describe()
                        ),
                        "its default",
                    )
                    .help("set the parameters its default uses to values of the kinds they were declared with");
                self.report(diag);
                continue;
            }
            bound[index].value = value;
        }
        (self.error_count() == errors_before).then_some(bound)
    }

    /// Whether `decl`'s default names parameters: `Some(true)` when it names only parameters
    /// declared before it (`bound`), `Some(false)` when it names none, and `None` (reported)
    /// when it names itself or one declared after it, which would make a cycle possible, or
    /// an earlier one that was refused.
    fn earlier_params_in(&mut self, decl: &ast::ParamDecl, skill: &ast::Skill, bound: &[Bound<'_>]) -> Option<bool> {
        let mut names = Vec::new();
        visit_names(&decl.value, &mut |name| names.push(name.clone()));
        let mut uses_earlier = false;
        let mut fine = true;
        for name in names {
            if bound.iter().any(|b| b.decl.name.name == name.name) {
                uses_earlier = true;
                continue;
            }
            let position = |wanted: &str| skill.params.iter().position(|p| p.name.name == wanted);
            let problem = match (position(&name.name), position(&decl.name.name)) {
                // Not a parameter: the arithmetic's check names it.
                (None, _) => continue,
                _ if name.name == decl.name.name => format!("the default of `{}` uses itself", decl.name.name),
                (Some(at), Some(mine)) if at < mine => {
                    // An earlier parameter that was refused: its own error says why.
                    fine = false;
                    continue;
                }
                _ => format!(
                    "the default of `{}` uses `{}`, which is declared after it",
                    decl.name.name, name.name
                ),
            };
            let diag = self
                .diag(Code::BadArgument, name.span, problem, "not declared before")
                .help(format!(
                    "a default may use the parameters declared above it: declare `{}` before `{}`, or write a value",
                    name.name, decl.name.name
                ));
            self.report(diag);
            fine = false;
        }
        fine.then_some(uses_earlier)
    }

    /// Reports a parameter used inside `learn`, where it is not substituted: what is learned
    /// must not depend on a value a task step sets.
    fn params_in_learn(&mut self, skill: &ast::Skill, values: &HashMap<&str, &ast::Expr>) {
        let mut found = Vec::new();
        for decl in &skill.learn {
            visit_names(&decl.value, &mut |name| {
                if values.contains_key(name.name.as_str()) {
                    found.push(name.clone());
                }
            });
        }
        for name in found {
            let diag = self
                .diag(
                    Code::BadArgument,
                    name.span,
                    format!("parameter `{}` cannot be used in `learn`", name.name),
                    "a parameter",
                )
                .help(
                    "what is learned must not change with a value a task step sets: write the value here; \
                     parameters serve states and limits",
                );
            self.report(diag);
        }
    }
}

/// Whether a number or quantity literal is finite.
fn finite_literal(expr: &ast::Expr) -> bool {
    match &expr.kind {
        ExprKind::Number(number) => number.value.is_finite(),
        ExprKind::Quantity { number, unit } => {
            let factor = units::lookup(&unit.name).map_or(1.0, |(_, factor)| factor);
            (number.value * factor).is_finite()
        }
        ExprKind::List(items) => items.iter().all(finite_literal),
        _ => true,
    }
}

/// Calls `f` on every bare name inside `expr`.
fn visit_names(expr: &ast::Expr, f: &mut dyn FnMut(&ast::Ident)) {
    match &expr.kind {
        ExprKind::Name(name) => f(name),
        ExprKind::List(items) => items.iter().for_each(|item| visit_names(item, f)),
        ExprKind::Record(args) | ExprKind::Call { args, .. } => args.iter().for_each(|arg| visit_names(&arg.value, f)),
        ExprKind::Neg(inner) => visit_names(inner, f),
        ExprKind::Arith { first, rest } => {
            visit_names(first, f);
            rest.iter().for_each(|(_, operand)| visit_names(operand, f));
        }
        _ => {}
    }
}

/// Replaces every parameter's name in the skill's body by its value, spanned where the
/// name is written (so that a message about the value points at its use), then folds the
/// arithmetic; what does not fold lands in `unfolded`.
fn substitute_body(
    skill: &mut ast::Skill,
    values: &HashMap<&str, &ast::Expr>,
    used: &mut HashMap<String, bool>,
    unfolded: &mut Vec<ArithError>,
) {
    let mut put = |expr: &mut ast::Expr| {
        substitute(expr, values, used);
        if let Err(error) = arith::fold(expr) {
            unfolded.push(error);
        }
    };
    // A use in `learn` is an error (reported before); substituting it keeps the learn block's
    // own check from reporting the name again.
    for decl in &mut skill.learn {
        put(&mut decl.value);
    }
    for entry in &mut skill.limits {
        put(&mut entry.value);
    }
    for state in &mut skill.states {
        let StateBody::Active(stmts) = &mut state.body else {
            continue;
        };
        for stmt in stmts {
            match &mut stmt.kind {
                StmtKind::Stiffness(values) => values.iter_mut().for_each(|v| put(&mut v.value)),
                StmtKind::Gains(args) => args.iter_mut().for_each(|arg| put(&mut arg.value)),
                StmtKind::Entry(exprs) => exprs.iter_mut().for_each(&mut put),
                StmtKind::Approach { within, speed } => {
                    put(within);
                    put(speed);
                }
                StmtKind::LiftOff { distance, speed } => {
                    put(distance);
                    if let Some(speed) = speed {
                        put(speed);
                    }
                }
                StmtKind::Repeat(count) => put(count),
                StmtKind::Transition { guard, target, .. } => {
                    guard_exprs(guard, &mut put);
                    if let Target::Extend { speed, max, .. } = target {
                        put(speed);
                        put(max);
                    }
                }
                StmtKind::Move {
                    offset: Some(offset), ..
                } => put(&mut offset.value),
                StmtKind::Move { .. } | StmtKind::Control { .. } | StmtKind::Apply(_) | StmtKind::Capture { .. } => {}
            }
        }
    }
}

fn guard_exprs(guard: &mut ast::Guard, put: &mut dyn FnMut(&mut ast::Expr)) {
    match &mut guard.kind {
        GuardKind::Or(guards) | GuardKind::And(guards) => guards.iter_mut().for_each(|g| guard_exprs(g, put)),
        GuardKind::Not(inner) => guard_exprs(inner, put),
        GuardKind::Held { guard, duration } => {
            guard_exprs(guard, put);
            put(duration);
        }
        GuardKind::Force { rhs, .. }
        | GuardKind::Moved { rhs, .. }
        | GuardKind::Magnitude { rhs, .. }
        | GuardKind::Speed { rhs, .. }
        | GuardKind::Entered { rhs, .. } => put(rhs),
        GuardKind::Timed { duration, .. } => put(duration),
        GuardKind::ForceReached(tolerance) => put(tolerance),
        GuardKind::Named(_) => {}
    }
}

fn substitute(expr: &mut ast::Expr, values: &HashMap<&str, &ast::Expr>, used: &mut HashMap<String, bool>) {
    match &mut expr.kind {
        ExprKind::Name(name) => {
            if let Some(value) = values.get(name.name.as_str()) {
                used.insert(name.name.clone(), true);
                let span = expr.span;
                *expr = respan((*value).clone(), span);
            }
        }
        ExprKind::List(items) => items.iter_mut().for_each(|item| substitute(item, values, used)),
        ExprKind::Record(args) | ExprKind::Call { args, .. } => {
            args.iter_mut().for_each(|arg| substitute(&mut arg.value, values, used))
        }
        ExprKind::Neg(inner) => substitute(inner, values, used),
        ExprKind::Arith { first, rest } => {
            substitute(first, values, used);
            rest.iter_mut()
                .for_each(|(_, operand)| substitute(operand, values, used));
        }
        _ => {}
    }
}

/// `expr` with every span set to `span`.
fn respan(mut expr: ast::Expr, span: crate::source::Span) -> ast::Expr {
    expr.span = span;
    match &mut expr.kind {
        ExprKind::Quantity { number: _, unit } => unit.span = span,
        // A vector's values may come from another file (a step's, `--param`'s): a message about
        // one of them points at the use.
        ExprKind::List(items) => {
            for item in items.iter_mut() {
                *item = respan(item.clone(), span);
            }
        }
        _ => {}
    }
    expr
}

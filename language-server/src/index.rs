//! The symbol index of a compilation: every declaration (skills, tasks, steps, parameters,
//! learned names, states, terminals, captures) and every place a name is written, resolved to
//! its declaration as the checker resolves it. Hover, definition, references, rename and
//! document symbols all read it.

use skill_compiler::ast::{self, Expr, ExprKind, Guard, GuardKind, StateBody, StmtKind, Target};
use skill_compiler::{SourceFile, Span};

/// What a declaration declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `skill NAME { }`.
    Skill,
    /// `task NAME { }`.
    Task,
    /// `step NAME = ...` or `fallback NAME = ...`.
    Step,
    /// `param NAME = VALUE`.
    Param,
    /// `frame NAME = ...`.
    Frame,
    /// `motion NAME = ...`.
    Motion,
    /// `force NAME = ...`.
    Force,
    /// `threshold NAME = ...`.
    Threshold,
    /// `state NAME { }`.
    State,
    /// `terminal NAME: ...`.
    Terminal,
    /// `capture NAME`.
    Capture,
}

impl Kind {
    /// The word the language uses for it.
    pub fn word(self) -> &'static str {
        match self {
            Kind::Skill => "skill",
            Kind::Task => "task",
            Kind::Step => "step",
            Kind::Param => "param",
            Kind::Frame => "frame",
            Kind::Motion => "motion",
            Kind::Force => "force",
            Kind::Threshold => "threshold",
            Kind::State => "state",
            Kind::Terminal => "terminal",
            Kind::Capture => "capture",
        }
    }
}

/// One declaration.
#[derive(Debug, Clone)]
pub struct Def {
    /// What it declares.
    pub kind: Kind,
    /// The name.
    pub name: String,
    /// The file (index into the compilation's files).
    pub file: usize,
    /// The name as written in the declaration.
    pub span: Span,
    /// The whole declaration.
    pub full: Span,
    /// The skill or task it belongs to (an index into `defs`), `None` for skills and tasks.
    pub parent: Option<usize>,
    /// Its doc comment lines.
    pub doc: Vec<String>,
    /// What it is, in one line: `frame contact = force_aligned(at: end(segment 1))`.
    pub detail: String,
}

/// What a name written somewhere is.
#[derive(Debug, Clone, PartialEq)]
pub enum What {
    /// A declared name (the declaration itself or a use of it).
    Def(usize),
    /// A learn function; `kind` is what it produces there (`motion`, `point`, ...).
    Function {
        /// The function's name.
        name: String,
        /// Where it stands: `segments`, `cut`, `point`, `frame`, `motion`, `force` or `threshold`.
        kind: &'static str,
    },
    /// A unit after a number.
    Unit(String),
    /// A supervisor limit's name.
    Limit(String),
    /// A guard written as a name: `motion_done`.
    Guard(String),
    /// The built-in frames `base` and `tool`.
    BuiltinFrame(String),
    /// An import's path string, and the file it names (an index into the files).
    Import(Option<usize>),
    /// A task step's own argument: `demo`, `force_scale`, ...
    StepArg(String),
    /// A word that changes a statement's meaning: `watch`, `once`.
    Keyword(&'static str),
}

/// A place a name is written.
#[derive(Debug, Clone)]
pub struct Occurrence {
    /// The file.
    pub file: usize,
    /// Where.
    pub span: Span,
    /// What it is.
    pub what: What,
}

/// Declarations and occurrences of a compilation.
#[derive(Debug, Default)]
pub struct Index {
    /// Every declaration.
    pub defs: Vec<Def>,
    /// Every occurrence, declarations included.
    pub occurrences: Vec<Occurrence>,
}

/// The names that stand where a learn function goes.
fn is_learn_function(name: &str) -> Option<&'static str> {
    skill_compiler::info::learn_functions()
        .into_iter()
        .find(|f| f.name == name)
        .map(|f| f.kind)
}

impl Index {
    /// Indexes `asts[i]`, the syntax tree of `files[i]` (`None` for a file that did not parse).
    pub fn build(files: &[SourceFile], asts: &[ast::File]) -> Index {
        let mut index = Index::default();
        // Skills and tasks first: tasks name skills of any file.
        let mut skills = Vec::new();
        for (file, tree) in asts.iter().enumerate() {
            for skill in &tree.skills {
                let id = index.declare(Def {
                    kind: Kind::Skill,
                    name: skill.name.name.clone(),
                    file,
                    span: skill.name.span,
                    full: skill.span,
                    parent: None,
                    doc: skill.doc.clone(),
                    detail: format!("skill {}", skill.name.name),
                });
                skills.push((file, id, skill));
            }
        }
        for (file, tree) in asts.iter().enumerate() {
            for import in &tree.imports {
                let base = parent_dir(&files[file].name);
                let path = join_path(&base, &import.path);
                let target = files.iter().position(|f| f.name == path);
                index.occurrences.push(Occurrence {
                    file,
                    span: import.span,
                    what: What::Import(target),
                });
            }
        }
        for &(file, id, skill) in &skills {
            SkillWalk {
                index: &mut index,
                file,
                skill: id,
            }
            .skill(skill, &files[file]);
        }
        for (file, tree) in asts.iter().enumerate() {
            for task in &tree.tasks {
                index.task(file, task);
            }
        }
        // A rule's span may take in the spaces and line breaks after it; a symbol's range
        // ends where its text does.
        for def in &mut index.defs {
            let text = files[def.file].text.as_bytes();
            while def.full.end > def.full.start && text.get(def.full.end - 1).is_some_and(u8::is_ascii_whitespace) {
                def.full.end -= 1;
            }
        }
        index
    }

    fn declare(&mut self, def: Def) -> usize {
        let id = self.defs.len();
        self.occurrences.push(Occurrence {
            file: def.file,
            span: def.span,
            what: What::Def(id),
        });
        self.defs.push(def);
        id
    }

    /// The declaration named `name` among the children of `parent` (or the skills and tasks
    /// for `None`), preferring the first of `kinds` that has one, then any kind.
    pub fn lookup(&self, parent: Option<usize>, name: &str, kinds: &[Kind]) -> Option<usize> {
        let mut found = None;
        for kind in kinds {
            found = self
                .defs
                .iter()
                .position(|d| d.parent == parent && d.name == name && d.kind == *kind);
            if found.is_some() {
                break;
            }
        }
        found.or_else(|| {
            self.defs
                .iter()
                .position(|d| d.parent == parent && d.name == name && !kinds.is_empty())
        })
    }

    /// The occurrence at a byte offset of a file (touching its end counts).
    pub fn at(&self, file: usize, offset: usize) -> Option<&Occurrence> {
        self.occurrences
            .iter()
            .filter(|o| o.file == file && o.span.start <= offset && offset <= o.span.end)
            .min_by_key(|o| o.span.len())
    }

    /// Every occurrence of a declaration, the declaration first.
    pub fn uses(&self, def: usize) -> Vec<&Occurrence> {
        let mut uses: Vec<&Occurrence> = self.occurrences.iter().filter(|o| o.what == What::Def(def)).collect();
        uses.sort_by_key(|o| (o.file, o.span.start));
        uses.dedup_by_key(|o| (o.file, o.span.start));
        uses
    }

    fn note(&mut self, file: usize, span: Span, what: What) {
        self.occurrences.push(Occurrence { file, span, what });
    }

    fn task(&mut self, file: usize, task: &ast::Task) {
        let id = self.declare(Def {
            kind: Kind::Task,
            name: task.name.name.clone(),
            file,
            span: task.name.span,
            full: task.span,
            parent: None,
            doc: task.doc.clone(),
            detail: format!("task {}", task.name.name),
        });
        let mut steps = Vec::new();
        for step in &task.steps {
            let word = if step.fallback { "fallback" } else { "step" };
            let step_id = self.declare(Def {
                kind: Kind::Step,
                name: step.name.name.clone(),
                file,
                span: step.name.span,
                full: step.span,
                parent: Some(id),
                doc: step.doc.clone(),
                detail: format!("{word} {} = {}(...)", step.name.name, step.skill.name),
            });
            steps.push(step_id);
        }
        for step in &task.steps {
            let skill = self.lookup(None, &step.skill.name, &[Kind::Skill]);
            if let Some(skill) = skill {
                self.note(file, step.skill.span, What::Def(skill));
            }
            for arg in &step.args {
                if let Some(key) = &arg.key {
                    let param = skill.and_then(|s| self.lookup(Some(s), &key.name, &[Kind::Param]));
                    match param {
                        Some(param) if self.defs[param].kind == Kind::Param => {
                            self.note(file, key.span, What::Def(param))
                        }
                        _ => self.note(file, key.span, What::StepArg(key.name.clone())),
                    }
                    if key.name == "at" {
                        if let ExprKind::Axis(axis) = &arg.value.kind {
                            if let Some(earlier) = self.lookup(Some(id), &axis.frame.name, &[Kind::Step]) {
                                self.note(file, axis.frame.span, What::Def(earlier));
                                let earlier_skill = task
                                    .steps
                                    .iter()
                                    .find(|s| s.name.name == axis.frame.name)
                                    .and_then(|s| self.lookup(None, &s.skill.name, &[Kind::Skill]));
                                if let Some(state) = earlier_skill
                                    .and_then(|s| self.lookup(Some(s), &axis.axis.name, &[Kind::State, Kind::Terminal]))
                                {
                                    self.note(file, axis.axis.span, What::Def(state));
                                }
                            }
                            continue;
                        }
                    }
                    if key.name == "limits" {
                        if let ExprKind::Record(entries) = &arg.value.kind {
                            for entry in entries {
                                if let Some(key) = &entry.key {
                                    self.note(file, key.span, What::Limit(key.name.clone()));
                                }
                                self.plain_expr(file, &entry.value);
                            }
                            continue;
                        }
                    }
                }
                self.plain_expr(file, &arg.value);
            }
            if let Some(ast::OnFailure::Fallback(name)) = &step.on_failure {
                if let Some(target) = self.lookup(Some(id), &name.name, &[Kind::Step]) {
                    self.note(file, name.span, What::Def(target));
                }
            }
        }
    }

    /// Units inside a value outside any skill.
    fn plain_expr(&mut self, file: usize, expr: &Expr) {
        match &expr.kind {
            ExprKind::Quantity { unit, .. } => self.note(file, unit.span, What::Unit(unit.name.clone())),
            ExprKind::List(items) => items.iter().for_each(|e| self.plain_expr(file, e)),
            ExprKind::Record(args) | ExprKind::Call { args, .. } => {
                args.iter().for_each(|a| self.plain_expr(file, &a.value))
            }
            ExprKind::Neg(inner) => self.plain_expr(file, inner),
            ExprKind::Arith { first, rest } => {
                self.plain_expr(file, first);
                rest.iter().for_each(|(_, e)| self.plain_expr(file, e));
            }
            _ => {}
        }
    }
}

/// The walk over one skill's body.
struct SkillWalk<'a> {
    index: &'a mut Index,
    file: usize,
    skill: usize,
}

impl SkillWalk<'_> {
    fn declare(&mut self, kind: Kind, name: &ast::Ident, full: Span, doc: &[String], detail: String) -> usize {
        self.index.declare(Def {
            kind,
            name: name.name.clone(),
            file: self.file,
            span: name.span,
            full,
            parent: Some(self.skill),
            doc: doc.to_vec(),
            detail,
        })
    }

    fn skill(&mut self, skill: &ast::Skill, source: &SourceFile) {
        for param in &skill.params {
            let detail = format!("param {} = {}", param.name.name, source.slice(param.value.span));
            self.declare(Kind::Param, &param.name, param.span, &param.doc, detail);
        }
        for decl in &skill.learn {
            let Some(name) = &decl.name else { continue };
            let kind = match decl.kind {
                ast::LearnKind::Frame => Kind::Frame,
                ast::LearnKind::Motion => Kind::Motion,
                ast::LearnKind::Force => Kind::Force,
                ast::LearnKind::Threshold => Kind::Threshold,
                _ => continue,
            };
            let detail = format!("{} {} = {}", kind.word(), name.name, source.slice(decl.value.span));
            self.declare(kind, name, decl.span, &decl.doc, detail);
        }
        for state in &skill.states {
            match &state.body {
                StateBody::Active(_) => {
                    let detail = format!("state {}", state.name.name);
                    self.declare(Kind::State, &state.name, state.span, &state.doc, detail);
                }
                StateBody::Terminal { outcome, message } => {
                    let detail = match message {
                        Some(message) => format!("terminal {}: {} {message:?}", state.name.name, outcome.name),
                        None => format!("terminal {}: {}", state.name.name, outcome.name),
                    };
                    self.declare(Kind::Terminal, &state.name, state.span, &state.doc, detail);
                }
            }
        }
        // Captures: the first `capture NAME` declares it, later ones use it.
        for state in &skill.states {
            let StateBody::Active(stmts) = &state.body else {
                continue;
            };
            for stmt in stmts {
                if let StmtKind::Capture { name, .. } = &stmt.kind {
                    match self.index.lookup(Some(self.skill), &name.name, &[Kind::Capture]) {
                        Some(id) if self.index.defs[id].kind == Kind::Capture => {
                            self.index.note(self.file, name.span, What::Def(id))
                        }
                        _ => {
                            let detail = format!("capture {} (in state `{}`)", name.name, state.name.name);
                            self.declare(Kind::Capture, name, stmt.span, &stmt.doc, detail);
                        }
                    }
                }
            }
        }
        for decl in &skill.learn {
            let kind = match decl.kind {
                ast::LearnKind::Segments => "segments",
                ast::LearnKind::Frame => "frame",
                ast::LearnKind::Motion => "motion",
                ast::LearnKind::Force => "force",
                ast::LearnKind::Threshold => "threshold",
                ast::LearnKind::Lowpass | ast::LearnKind::Resample => "",
            };
            self.learn_expr(&decl.value, kind);
        }
        for limit in &skill.limits {
            self.index
                .note(self.file, limit.name.span, What::Limit(limit.name.name.clone()));
            self.value(&limit.value);
        }
        for param in &skill.params {
            self.value(&param.value);
        }
        for state in &skill.states {
            let StateBody::Active(stmts) = &state.body else {
                continue;
            };
            for stmt in stmts {
                self.stmt(&stmt.kind);
            }
        }
    }

    fn refer(&mut self, name: &ast::Ident, kinds: &[Kind]) {
        if kinds.contains(&Kind::Frame) && (name.name == "base" || name.name == "tool") {
            self.index
                .note(self.file, name.span, What::BuiltinFrame(name.name.clone()));
            return;
        }
        if let Some(id) = self.index.lookup(Some(self.skill), &name.name, kinds) {
            self.index.note(self.file, name.span, What::Def(id));
        }
    }

    /// A value inside `learn`: calls are learn functions, `kind` is where the value stands.
    fn learn_expr(&mut self, expr: &Expr, kind: &'static str) {
        match &expr.kind {
            ExprKind::Call { name, args } => {
                let kind = if kind.is_empty() {
                    is_learn_function(&name.name).unwrap_or("")
                } else {
                    kind
                };
                self.index.note(
                    self.file,
                    name.span,
                    What::Function {
                        name: name.name.clone(),
                        kind,
                    },
                );
                for arg in args {
                    let inner = match arg.key.as_ref().map(|k| k.name.as_str()) {
                        Some("at") | Some("point") => "point",
                        Some("cut") => "cut",
                        None if matches!(name.name.as_str(), "force_at") => "point",
                        _ => "",
                    };
                    self.learn_expr(&arg.value, inner);
                }
            }
            ExprKind::Name(name) => match is_learn_function(&name.name) {
                Some(found) => {
                    let kind = if kind.is_empty() { found } else { kind };
                    self.index.note(
                        self.file,
                        name.span,
                        What::Function {
                            name: name.name.clone(),
                            kind,
                        },
                    );
                }
                None => self.refer(name, &[Kind::Frame, Kind::Threshold, Kind::Force, Kind::Motion]),
            },
            ExprKind::List(items) => items.iter().for_each(|e| self.learn_expr(e, "")),
            _ => self.value(expr),
        }
    }

    /// A value outside `learn`.
    fn value(&mut self, expr: &Expr) {
        match &expr.kind {
            ExprKind::Quantity { unit, .. } => self.index.note(self.file, unit.span, What::Unit(unit.name.clone())),
            ExprKind::Name(name) => self.refer(
                name,
                &[
                    Kind::Param,
                    Kind::Threshold,
                    Kind::Force,
                    Kind::Frame,
                    Kind::Motion,
                    Kind::Capture,
                ],
            ),
            ExprKind::Axis(axis) => self.refer(&axis.frame, &[Kind::Frame]),
            ExprKind::List(items) => items.iter().for_each(|e| self.value(e)),
            ExprKind::Record(args) => args.iter().for_each(|a| self.value(&a.value)),
            ExprKind::Call { args, .. } => args.iter().for_each(|a| self.value(&a.value)),
            ExprKind::Neg(inner) => self.value(inner),
            ExprKind::Arith { first, rest } => {
                self.value(first);
                rest.iter().for_each(|(_, e)| self.value(e));
            }
            ExprKind::Number(_) | ExprKind::Str(_) | ExprKind::Segment(_) => {}
        }
    }

    fn stmt(&mut self, stmt: &StmtKind) {
        match stmt {
            StmtKind::Move { motion, at, offset, .. } => {
                self.refer(motion, &[Kind::Motion]);
                if let Some(at) = at {
                    self.refer(at, &[Kind::Capture]);
                }
                if let Some(offset) = offset {
                    self.value(&offset.value);
                    if let Some(frame) = &offset.frame {
                        self.refer(frame, &[Kind::Frame]);
                    }
                }
            }
            StmtKind::Control { frame, .. } => {
                if let Some(frame) = frame {
                    self.refer(frame, &[Kind::Frame]);
                }
            }
            StmtKind::Stiffness(values) => values.iter().for_each(|v| self.value(&v.value)),
            StmtKind::Apply(force) => self.refer(force, &[Kind::Force]),
            StmtKind::Gains(args) => args.iter().for_each(|a| self.value(&a.value)),
            StmtKind::Entry(exprs) => exprs.iter().for_each(|e| self.value(e)),
            StmtKind::Approach { within, speed } => {
                self.value(within);
                self.value(speed);
            }
            StmtKind::LiftOff { distance, speed } => {
                self.value(distance);
                if let Some(speed) = speed {
                    self.value(speed);
                }
            }
            StmtKind::Repeat(count) => self.value(count),
            StmtKind::Capture { once, .. } => {
                if let Some(span) = once {
                    self.index.note(self.file, *span, What::Keyword("once"));
                }
            }
            StmtKind::Transition { guard, target, watch } => {
                if let Some(span) = watch {
                    self.index.note(self.file, *span, What::Keyword("watch"));
                }
                self.guard(guard);
                match target {
                    Target::State(name) => self.refer(name, &[Kind::State, Kind::Terminal]),
                    Target::Extend {
                        axis, speed, max, then, ..
                    } => {
                        self.refer(&axis.frame, &[Kind::Frame]);
                        self.value(speed);
                        self.value(max);
                        self.refer(then, &[Kind::State, Kind::Terminal]);
                    }
                }
            }
        }
    }

    fn guard(&mut self, guard: &Guard) {
        match &guard.kind {
            GuardKind::Or(all) | GuardKind::And(all) => all.iter().for_each(|g| self.guard(g)),
            GuardKind::Not(inner) => self.guard(inner),
            GuardKind::Held { guard, duration } => {
                self.guard(guard);
                self.value(duration);
            }
            GuardKind::Force { axis, rhs, .. } => {
                self.refer(&axis.frame, &[Kind::Frame]);
                self.value(rhs);
            }
            GuardKind::Moved {
                axis,
                since,
                since_keyword,
                rhs,
                ..
            } => {
                if let Some(axis) = axis {
                    self.refer(&axis.frame, &[Kind::Frame]);
                }
                if let Some(span) = since_keyword {
                    self.index.note(self.file, *span, What::Keyword("since"));
                }
                if let Some(since) = since {
                    self.refer(since, &[Kind::Capture]);
                }
                self.value(rhs);
            }
            GuardKind::Magnitude { rhs, .. } | GuardKind::Speed { rhs, .. } => self.value(rhs),
            GuardKind::Entered { state, rhs, .. } => {
                self.refer(state, &[Kind::State, Kind::Terminal]);
                self.value(rhs);
            }
            GuardKind::Timed { duration, .. } => self.value(duration),
            GuardKind::ForceReached(within) => self.value(within),
            GuardKind::Named(name) => self.index.note(self.file, name.span, What::Guard(name.name.clone())),
        }
    }
}

/// The directory part of a file name, as the compiler joins imports to it.
pub fn parent_dir(path: &str) -> String {
    match path.rfind('/') {
        Some(at) => path[..at].to_string(),
        None => String::new(),
    }
}

/// A path written in a file joined to that file's directory, lexically: the compiler's rule.
pub use skill_compiler::join_path;

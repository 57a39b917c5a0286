//! The canonical formatter behind `skillc fmt`: prints a parsed file in one layout, keeping
//! every line comment, so that formatting is idempotent and the output compiles to the same IR.

use crate::ast::*;
use crate::source::{SourceFile, Span};

const INDENT: &str = "    ";

/// A line comment of the source, with whether code precedes it on its line.
#[derive(Debug, Clone)]
pub(crate) struct Comment {
    /// From its `//` to the end of its line, trailing whitespace left out.
    pub(crate) span: Span,
    /// The comment's text, `//` included.
    pub(crate) text: String,
    /// Whether code stands before it on its line.
    pub(crate) trailing: bool,
}

/// Formats a parsed file. `src` must be the text `file` was parsed from.
pub fn format(src: &SourceFile, file: &File) -> String {
    let mut printer = Printer {
        src,
        comments: line_comments(&src.text),
        next_comment: 0,
        out: String::new(),
        depth: 0,
        last_end: 0,
    };
    let mut items: Vec<(Span, Item<'_>)> = Vec::new();
    items.extend(file.imports.iter().map(|import| (import.span, Item::Import(import))));
    items.extend(file.skills.iter().map(|skill| (skill.span, Item::Skill(skill))));
    items.extend(file.tasks.iter().map(|task| (task.span, Item::Task(task))));
    items.sort_by_key(|(span, _)| *span);
    let mut previous_import = false;
    for (index, (span, item)) in items.iter().enumerate() {
        let is_import = matches!(item, Item::Import(_));
        if index > 0 && !(is_import && previous_import) {
            printer.blank();
        }
        match item {
            Item::Import(import) => {
                printer.line_at(span.start, &format!("import {}", quote(&import.path)));
                printer.finish(span.end);
            }
            Item::Skill(skill) => printer.skill(skill),
            Item::Task(task) => printer.task(task),
        }
        previous_import = is_import;
    }
    printer.flush_comments(usize::MAX);
    let mut out = printer.out;
    while out.ends_with("\n\n") {
        out.pop();
    }
    if !out.is_empty() && !out.ends_with('\n') {
        out.push('\n');
    }
    out
}

enum Item<'a> {
    Import(&'a Import),
    Skill(&'a Skill),
    Task(&'a Task),
}

struct Printer<'a> {
    src: &'a SourceFile,
    comments: Vec<Comment>,
    next_comment: usize,
    out: String,
    depth: usize,
    last_end: usize,
}

impl Printer<'_> {
    /// Emits the comments that start before `pos`, each on its line or after the last line.
    fn flush_comments(&mut self, pos: usize) {
        while let Some(comment) = self.comments.get(self.next_comment) {
            if comment.span.start >= pos {
                break;
            }
            let comment = comment.clone();
            self.next_comment += 1;
            if comment.trailing && !self.out.is_empty() && comment.span.start >= self.last_end {
                if self.out.ends_with('\n') {
                    self.out.pop();
                }
                self.out.push_str("  ");
                self.out.push_str(&comment.text);
                self.out.push('\n');
            } else {
                self.keep_blank_line(comment.span.start);
                self.indent();
                self.out.push_str(&comment.text);
                self.out.push('\n');
            }
            self.last_end = comment.span.end;
        }
    }

    /// The end of the code before `end`, skipping trailing whitespace and line comments.
    fn code_end(&self, mut end: usize) -> usize {
        let text = self.src.text.as_bytes();
        loop {
            while end > 0 && text[end - 1].is_ascii_whitespace() {
                end -= 1;
            }
            match self.comments.iter().find(|comment| comment.span.end == end) {
                Some(comment) => end = comment.span.start,
                None => return end,
            }
        }
    }

    /// Keeps one blank line where the source had at least one before `pos`.
    fn keep_blank_line(&mut self, pos: usize) {
        let between = self.src.text.get(self.last_end..pos).unwrap_or("");
        let lines: Vec<&str> = between.split('\n').collect();
        let has_blank_line = lines.len() > 2 && lines[1..lines.len() - 1].iter().any(|line| line.trim().is_empty());
        if has_blank_line && !self.out.is_empty() && !self.out.ends_with("{\n") {
            self.blank();
        }
    }

    fn blank(&mut self) {
        if !self.out.is_empty() && !self.out.ends_with("\n\n") {
            self.out.push('\n');
        }
    }

    fn indent(&mut self) {
        for _ in 0..self.depth {
            self.out.push_str(INDENT);
        }
    }

    /// Starts a line for a node at `pos`: comments before it first, then its text.
    fn line_at(&mut self, pos: usize, text: &str) {
        self.flush_comments(pos);
        self.keep_blank_line(pos);
        self.indent();
        self.out.push_str(text);
        self.out.push('\n');
        self.last_end = pos;
    }

    /// Marks the node ending at `end` as printed, so comments after it on its line trail it.
    fn finish(&mut self, end: usize) {
        // pest spans may include the whitespace and comments after the node: step back over them.
        let end = self.code_end(end);
        self.last_end = end;
        // Comments inside the node (between its start and end) follow it.
        self.flush_comments(end);
        self.last_end = end;
    }

    fn docs(&mut self, pos: usize, doc: &[String]) {
        if doc.is_empty() {
            return;
        }
        self.flush_comments(pos);
        self.keep_blank_line(pos);
        for line in doc {
            self.indent();
            if line.is_empty() {
                self.out.push_str("///\n");
            } else {
                self.out.push_str("/// ");
                self.out.push_str(line);
                self.out.push('\n');
            }
        }
        self.last_end = pos;
    }

    fn close(&mut self, end: usize) {
        // Comments before the closing brace stay inside the block.
        self.flush_comments(end.saturating_sub(1));
        self.depth -= 1;
        self.indent();
        self.out.push_str("}\n");
        self.last_end = end;
    }

    fn skill(&mut self, skill: &Skill) {
        self.docs(skill.span.start, &skill.doc);
        self.line_at(skill.name.span.start, &format!("skill {} {{", skill.name.name));
        self.depth += 1;
        for param in &skill.params {
            self.docs(param.span.start, &param.doc);
            self.line_at(
                param.span.start,
                &format!("param {} = {}", param.name.name, expr(&param.value)),
            );
            self.finish(param.span.end);
        }
        if !skill.learn.is_empty() {
            if !skill.params.is_empty() {
                self.blank();
            }
            self.line_at(skill.learn[0].span.start, "learn {");
            self.depth += 1;
            for decl in &skill.learn {
                self.docs(decl.span.start, &decl.doc);
                let mut text = decl.kind.keyword().to_string();
                if let Some(name) = &decl.name {
                    text.push(' ');
                    text.push_str(&name.name);
                }
                text.push_str(" = ");
                text.push_str(&expr(&decl.value));
                if let Some((n, _)) = decl.expect {
                    text.push_str(&format!(" expect {n}"));
                }
                self.line_at(decl.span.start, &text);
                self.finish(decl.span.end);
            }
            self.depth -= 1;
            self.indent();
            self.out.push_str("}\n");
        }
        if !skill.limits.is_empty() {
            self.blank();
            self.line_at(skill.limits[0].span.start, "limits {");
            self.depth += 1;
            for entry in &skill.limits {
                self.docs(entry.span.start, &entry.doc);
                self.line_at(
                    entry.span.start,
                    &format!("{}: {}", entry.name.name, expr(&entry.value)),
                );
                self.finish(entry.span.end);
            }
            self.depth -= 1;
            self.indent();
            self.out.push_str("}\n");
        }
        let mut previous_terminal = false;
        for state in &skill.states {
            let terminal = matches!(state.body, StateBody::Terminal { .. });
            // Consecutive terminals stay together (unless the source separates them).
            if !(terminal && previous_terminal) {
                self.blank();
            }
            previous_terminal = terminal;
            self.docs(state.span.start, &state.doc);
            match &state.body {
                StateBody::Terminal { outcome, message } => {
                    let mut text = format!("terminal {}: {}", state.name.name, outcome.name);
                    if let Some(message) = message {
                        text.push(' ');
                        text.push_str(&quote(message));
                    }
                    self.line_at(state.name.span.start, &text);
                    self.finish(state.span.end);
                }
                StateBody::Active(stmts) => {
                    self.line_at(state.name.span.start, &format!("state {} {{", state.name.name));
                    self.depth += 1;
                    for stmt in stmts {
                        self.docs(stmt.span.start, &stmt.doc);
                        self.line_at(stmt.span.start, &statement(&stmt.kind));
                        self.finish(stmt.span.end);
                    }
                    self.close(state.span.end);
                }
            }
        }
        self.close(skill.span.end);
    }

    fn task(&mut self, task: &Task) {
        self.docs(task.span.start, &task.doc);
        self.line_at(task.name.span.start, &format!("task {} {{", task.name.name));
        self.depth += 1;
        for step in &task.steps {
            self.docs(step.span.start, &step.doc);
            let keyword = if step.fallback { "fallback" } else { "step" };
            let mut text = format!(
                "{keyword} {} = {}({})",
                step.name.name,
                step.skill.name,
                args(&step.args)
            );
            match &step.on_failure {
                Some(OnFailure::Abort(_)) => text.push_str(" on failure abort"),
                Some(OnFailure::Fallback(name)) => text.push_str(&format!(" on failure -> {}", name.name)),
                None => {}
            }
            self.line_at(step.span.start, &text);
            self.finish(step.span.end);
        }
        self.close(task.span.end);
    }
}

fn statement(stmt: &StmtKind) -> String {
    match stmt {
        StmtKind::Move {
            motion,
            relative,
            at: Some(at),
            offset,
            ..
        } => {
            let offset = match offset {
                Some(AtOffset {
                    value,
                    frame: Some(frame),
                }) => format!(" + {} in {}", expr(value), frame.name),
                Some(AtOffset { value, frame: None }) => format!(" + {}", expr(value)),
                None => String::new(),
            };
            match relative {
                true => format!("move {} relative at {}{offset}", motion.name, at.name),
                false => format!("move {} at {}{offset}", motion.name, at.name),
            }
        }
        StmtKind::Move {
            motion, relative: true, ..
        } => format!("move {} relative", motion.name),
        StmtKind::Move { motion, .. } => format!("move {} from current", motion.name),
        StmtKind::Control { groups, frame } => {
            let groups: Vec<String> = groups
                .iter()
                .map(|group| {
                    format!(
                        "{} {}",
                        if group.force { "force" } else { "position" },
                        axis_set(&group.axes)
                    )
                })
                .collect();
            let mut text = format!("control {}", groups.join(", "));
            if let Some(frame) = frame {
                text.push_str(" in ");
                text.push_str(&frame.name);
            }
            text
        }
        StmtKind::Stiffness(values) => {
            let values: Vec<String> = values
                .iter()
                .map(|value| format!("{}: {}", axis_set(&value.axes), expr(&value.value)))
                .collect();
            format!("stiffness {}", values.join(", "))
        }
        StmtKind::Apply(name) => format!("apply {}", name.name),
        StmtKind::Gains(list) => format!("gains {}", args(list)),
        StmtKind::Entry(actions) => {
            let actions: Vec<String> = actions.iter().map(expr).collect();
            format!("entry {}", actions.join(", "))
        }
        StmtKind::Approach { within, speed } => format!("approach within {} at {}", expr(within), expr(speed)),
        StmtKind::LiftOff { distance, speed } => match speed {
            Some(speed) => format!("lift off {} at {}", expr(distance), expr(speed)),
            None => format!("lift off {}", expr(distance)),
        },
        StmtKind::Repeat(count) => format!("repeat {}", expr(count)),
        StmtKind::Capture { name, once: None } => format!("capture {}", name.name),
        StmtKind::Capture { name, once: Some(_) } => format!("capture {} once", name.name),
        StmtKind::Transition {
            watch,
            guard: g,
            target,
        } => {
            let target = match target {
                Target::State(name) => name.name.clone(),
                Target::Extend {
                    axis, speed, max, then, ..
                } => format!(
                    "extend along {}.{} at {}, up to {}, then {}",
                    axis.frame.name,
                    axis.axis.name,
                    expr(speed),
                    expr(max),
                    then.name
                ),
            };
            let watch = if watch.is_some() { "watch " } else { "" };
            format!("on {watch}{} -> {target}", guard(g))
        }
    }
}

fn axis_set(axes: &AxisSet) -> String {
    match axes {
        AxisSet::All(_) => "all".to_string(),
        AxisSet::List(names) => names.iter().map(|n| n.name.as_str()).collect::<Vec<_>>().join(" "),
    }
}

/// Prints a guard with the fewest parentheses that keep its meaning (`not` > `for` > `and` >
/// `or`; one `for` a condition).
pub fn guard(g: &Guard) -> String {
    match &g.kind {
        GuardKind::Or(parts) => parts.iter().map(guard).collect::<Vec<_>>().join(" or "),
        GuardKind::And(parts) => parts
            .iter()
            .map(|part| match part.kind {
                GuardKind::Or(_) => format!("({})", guard(part)),
                _ => guard(part),
            })
            .collect::<Vec<_>>()
            .join(" and "),
        GuardKind::Held { guard: inner, duration } => match inner.kind {
            GuardKind::Or(_) | GuardKind::And(_) | GuardKind::Held { .. } => {
                format!("({}) for {}", guard(inner), expr(duration))
            }
            _ => format!("{} for {}", guard(inner), expr(duration)),
        },
        GuardKind::Not(inner) => match inner.kind {
            GuardKind::Or(_) | GuardKind::And(_) | GuardKind::Held { .. } => format!("not ({})", guard(inner)),
            _ => format!("not {}", guard(inner)),
        },
        GuardKind::Force { axis, op, rhs } => {
            format!(
                "force({}.{}) {} {}",
                axis.frame.name,
                axis.axis.name,
                op.as_str(),
                expr(rhs)
            )
        }
        GuardKind::Moved {
            axis, since, op, rhs, ..
        } => {
            let axis = axis.as_ref().map_or(String::new(), |axis| {
                format!("({}.{})", axis.frame.name, axis.axis.name)
            });
            let since = since
                .as_ref()
                .map_or(String::new(), |name| format!(" since {}", name.name));
            format!("moved{axis}{since} {} {}", op.as_str(), expr(rhs))
        }
        GuardKind::Magnitude { moment, op, rhs } => format!(
            "{} {} {}",
            if *moment { "moment_magnitude" } else { "force_magnitude" },
            op.as_str(),
            expr(rhs)
        ),
        GuardKind::Speed { op, rhs } => format!("speed {} {}", op.as_str(), expr(rhs)),
        GuardKind::Entered { state, op, rhs } => format!("entered({}) {} {}", state.name, op.as_str(), expr(rhs)),
        GuardKind::Timed { timeout, duration } => {
            format!("{} {}", if *timeout { "timeout" } else { "dwell" }, expr(duration))
        }
        GuardKind::ForceReached(tolerance) => format!("force_reached within {}", expr(tolerance)),
        GuardKind::Named(name) => name.name.clone(),
    }
}

fn args(list: &[Arg]) -> String {
    list.iter()
        .map(|arg| match &arg.key {
            Some(key) => format!("{}: {}", key.name, expr(&arg.value)),
            None => expr(&arg.value),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// An expression as the formatter writes it.
pub(crate) fn expr_text(e: &Expr) -> String {
    expr(e)
}

fn expr(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Quantity { number, unit } => format!("{} {}", number.text, unit.name),
        ExprKind::Number(number) => number.text.clone(),
        ExprKind::Str(text) => quote(text),
        ExprKind::List(items) => format!("[{}]", items.iter().map(expr).collect::<Vec<_>>().join(", ")),
        ExprKind::Record(entries) if entries.is_empty() => "{}".to_string(),
        ExprKind::Record(entries) => format!("{{ {} }}", args(entries)),
        ExprKind::Segment(n) => format!("segment {n}"),
        ExprKind::Call { name, args: list } => format!("{}({})", name.name, args(list)),
        ExprKind::Axis(axis) => format!("{}.{}", axis.frame.name, axis.axis.name),
        ExprKind::Name(name) => name.name.clone(),
        ExprKind::Neg(inner) => {
            let text = expr(inner);
            // `-(a + b)`, and `-(-4 mm)` rather than `--4 mm`.
            if matches!(inner.kind, ExprKind::Arith { .. }) || text.starts_with('-') {
                format!("-({text})")
            } else {
                format!("-{text}")
            }
        }
        ExprKind::Arith { first, rest } => {
            // The tree keeps no parentheses: a chain inside a chain was grouped by them, and
            // gets them back where leaving them out would change its meaning.
            let additive = rest.first().is_some_and(|(op, _)| op.is_additive());
            let operand = |e: &Expr, leading: bool| match &e.kind {
                ExprKind::Arith { rest: inner, .. } => {
                    let inner_additive = inner.first().is_some_and(|(op, _)| op.is_additive());
                    let grouped = if inner_additive {
                        // A sum in a product, or after an operator of a sum: `a - (b + c)`.
                        !(additive && leading)
                    } else {
                        // A product after an operator of a product: `a / (b * c)`.
                        !additive && !leading
                    };
                    if grouped {
                        format!("({})", expr(e))
                    } else {
                        expr(e)
                    }
                }
                _ => expr(e),
            };
            let mut out = operand(first, true);
            for (op, e) in rest {
                out.push_str(&format!(" {} {}", op.symbol(), operand(e, false)));
            }
            out
        }
    }
}

fn quote(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Finds every `//` comment (not `///` doc comments) outside strings.
pub(crate) fn line_comments(text: &str) -> Vec<Comment> {
    let mut comments = Vec::new();
    let mut line_start = 0;
    for line in text.split_inclusive('\n') {
        let bytes = line.as_bytes();
        let mut in_string = false;
        let mut at = 0;
        while at < bytes.len() {
            match bytes[at] {
                b'\\' if in_string => at += 1,
                b'"' => in_string = !in_string,
                b'/' if !in_string && bytes.get(at + 1) == Some(&b'/') => {
                    if bytes.get(at + 2) != Some(&b'/') {
                        let body = line[at..].trim_end();
                        let trailing = !line[..at].trim().is_empty();
                        comments.push(Comment {
                            span: Span::new(line_start + at, line_start + at + body.len()),
                            text: body.to_string(),
                            trailing,
                        });
                    }
                    break;
                }
                _ => {}
            }
            at += 1;
        }
        line_start += line.len();
    }
    comments
}

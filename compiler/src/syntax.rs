//! Parsing: source text to the spanned [`ast`](crate::ast), through pest.
//!
//! pest cannot recover after an error, so a file with a syntax error yields one
//! diagnostic and an empty tree. Input that would make pest recurse or run long
//! (deep nesting, huge files) is refused before pest sees it, and so are characters the
//! grammar cannot take, each named (`syntax/prescan.rs`).

use crate::ast::*;
use crate::diag::{Code, Diag};
use crate::source::{SourceFile, Span};
use pest::error::InputLocation;
use pest::iterators::Pair;
use pest::Parser;
use skill_grammar::{Rule, SkillParser};

mod prescan;

/// Parses one file. Never panics; bad input gives diagnostics and an empty file.
pub fn parse(src: &SourceFile, file: usize) -> (File, Vec<Diag>) {
    if src.text.len() > crate::MAX_SOURCE_BYTES {
        let diag = Diag::new(
            Code::FileTooLarge,
            file,
            Span::new(0, 0),
            format!("file is {} bytes, more than a skill template can be", src.text.len()),
            "this file",
        )
        .help(format!(
            "templates are small; check that this is the right file or split it below {} bytes",
            crate::MAX_SOURCE_BYTES
        ));
        return (File::default(), vec![diag]);
    }
    let refused = prescan::prescan(&src.text, file);
    if !refused.is_empty() {
        return (File::default(), refused);
    }
    match SkillParser::parse(Rule::file, &src.text) {
        Ok(mut pairs) => {
            let root = pairs.next().expect("grammar: `file` yields one pair");
            (file_rule(root), Vec::new())
        }
        Err(err) => (File::default(), vec![syntax_error(err, file, &src.text)]),
    }
}

fn syntax_error(err: pest::error::Error<Rule>, file: usize, src_text: &str) -> Diag {
    let span = match err.location {
        InputLocation::Pos(at) => Span::new(at, at),
        InputLocation::Span((start, end)) => Span::new(start, end),
    };
    let (message, label) = match &err.variant {
        pest::error::ErrorVariant::ParsingError { positives, negatives } => {
            let mut expected: Vec<&str> = positives.iter().filter_map(|rule| rule_label(*rule)).collect();
            expected.sort_unstable();
            expected.dedup();
            let unexpected: Vec<&str> = negatives.iter().filter_map(|rule| rule_label(*rule)).collect();
            let label = if expected.is_empty() {
                "unexpected here".to_string()
            } else {
                format!("expected {}", join_or(&expected))
            };
            let message = if !unexpected.is_empty() {
                format!("unexpected {}", join_or(&unexpected))
            } else {
                format!("syntax error: {label}")
            };
            (message, label)
        }
        pest::error::ErrorVariant::CustomError { message } => (message.clone(), String::new()),
    };
    // `capture` and `move M at` followed by anything but a name (often the next statement, whose
    // keyword would read as a name refused): say that the name is missing.
    if label == "expected a name" {
        if let Some(diag) = missing_name(src_text, span.start, file) {
            return diag;
        }
    }
    // A doc comment before something it cannot document (a `learn` or `limits` block, the end
    // of a block) reads as a puzzling "expected a doc comment".
    if label.contains("a doc comment") {
        if let Some(diag) = misplaced_doc(src_text, span.start, file) {
            return diag;
        }
    }
    // A reserved word where a name was expected reads as a puzzling "expected a name".
    let word: String = src_text
        .get(span.start..)
        .unwrap_or("")
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    if label.contains("a name") && KEYWORDS.contains(&word.as_str()) {
        let (what, example) = named_here(src_text, span.start, &word);
        return Diag::new(
            Code::Unexpected,
            file,
            Span::new(span.start, span.start + word.len()),
            format!("`{word}` is a keyword and cannot name {what}"),
            "keyword used as a name",
        )
        .help(format!("rename it, e.g. `{example}`"));
    }
    Diag::new(Code::Unexpected, file, span, message, label)
}

/// A doc comment that ends right before `at` (whitespace between) and documents nothing there:
/// the diagnostic at the comment, naming what follows.
fn misplaced_doc(src_text: &str, at: usize, file: usize) -> Option<Diag> {
    let before = src_text.get(..at)?.trim_end();
    let line_start = before.rfind('\n').map_or(0, |n| n + 1);
    let last_line = &before[line_start..];
    let doc_at = line_start + last_line.find("///")?;
    if last_line[..doc_at - line_start].trim() != "" {
        return None;
    }
    let rest = &src_text[at..];
    let word: &str = if rest.starts_with('}') {
        "}"
    } else {
        &rest[..rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(rest.len())]
    };
    let what = match word {
        "limits" => "a `limits` block",
        "learn" => "a `learn` block",
        "}" => "the end of a block",
        _ => return None,
    };
    let help = match word {
        "limits" => "document each limit inside the block (`/// ...` on the line before `force: 40 N`), or write `//` for a plain comment",
        "learn" => "document each declaration inside the block (`/// ...` on the line before `motion ...`), or write `//` for a plain comment",
        _ => "a doc comment documents what follows it: move it before a state, terminal, parameter or declaration, or write `//`",
    };
    Some(
        Diag::new(
            Code::Unexpected,
            file,
            Span::new(doc_at, line_start + last_line.len()),
            format!("a doc comment cannot document {what}"),
            "documents nothing",
        )
        .help(help),
    )
}

/// The word that ends right before `at` (whitespace between), and where it starts.
fn word_before(src_text: &str, at: usize) -> (&str, usize) {
    let before = src_text.get(..at).unwrap_or("").trim_end();
    let start = before
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .map_or(0, |found| found + 1);
    (&before[start..], start)
}

/// A name missing after `capture` or after `at` in a `move` (the only `at` that takes nothing
/// but a name), where the error at `at` expects a name.
fn missing_name(src_text: &str, at: usize, file: usize) -> Option<Diag> {
    let (word, start) = word_before(src_text, at);
    let span = Span::new(start, start + word.len());
    match word {
        "capture" => Some(
            Diag::new(
                Code::Unexpected,
                file,
                span,
                "`capture` needs a name for the pose it keeps",
                "a name should follow `capture`",
            )
            .help("write e.g. `capture found`; a later state's `move M at found` ends there"),
        ),
        "at" => Some(
            Diag::new(
                Code::Unexpected,
                file,
                span,
                "`move ... at` needs the name of a captured pose",
                "a name should follow `at`",
            )
            .help("write e.g. `move back at found`, where a state the run passes first has `capture found`"),
        ),
        _ => None,
    }
}

/// What the name at `at` would name, judged by the word before it (`state up`, `motion up =`,
/// `-> up`), and a legal name for it built from `word`.
fn named_here(src_text: &str, at: usize, word: &str) -> (&'static str, String) {
    let before = src_text.get(..at).unwrap_or("").trim_end();
    let previous: String = before
        .chars()
        .rev()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '>' || *c == '-')
        .collect::<Vec<char>>()
        .into_iter()
        .rev()
        .collect();
    let (what, suffix) = match previous.as_str() {
        "state" | "->" | "then" => ("a state", "state"),
        "terminal" => ("a terminal state", "done"),
        "frame" => ("a frame", "frame"),
        "motion" | "move" => ("a motion", "motion"),
        "force" | "apply" => ("a force", "force"),
        "threshold" => ("a threshold", "threshold"),
        "skill" => ("a skill", "skill"),
        "task" => ("a task", "task"),
        "step" | "fallback" => ("a step", "step"),
        _ => ("anything", "name"),
    };
    (what, format!("{word}_{suffix}"))
}

/// Words the grammar reserves (they may not be names); keep in step with `keyword` in skill.pest.
/// The language server refuses to rename a name to one of them.
pub const KEYWORDS: &[&str] = &[
    "skill",
    "state",
    "learn",
    "terminal",
    "task",
    "step",
    "fallback",
    "import",
    "on",
    "in",
    "and",
    "or",
    "not",
    "then",
    "at",
    "up",
    "to",
    "along",
    "expect",
    "from",
    "within",
    "control",
    "move",
    "apply",
    "stiffness",
    "gains",
    "entry",
    "extend",
    "segment",
    "all",
];

fn join_or(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => (*one).to_string(),
        [init @ .., last] => format!("{} or {}", init.join(", "), last),
    }
}

/// The statements of a state, for "expected ..." messages.
const STATEMENTS: &str =
    "a statement (`move`, `control`, `stiffness`, `apply`, `gains`, `entry`, `approach`, `lift off`, `repeat`, `capture`, `on`)";

/// What a rule means to a user, for "expected ..." messages.
fn rule_label(rule: Rule) -> Option<&'static str> {
    Some(match rule {
        Rule::EOI => "end of file",
        Rule::import => "`import`",
        Rule::skill => "`skill`",
        Rule::task => "`task`",
        Rule::doc => "a doc comment",
        Rule::learn => "`learn`",
        Rule::limits => "`limits`",
        Rule::limit_entry => "a limit (`force: 40 N`)",
        Rule::learn_entry | Rule::segments_decl | Rule::frame_decl | Rule::motion_decl => {
            "a learn declaration (`segments`, `frame`, `motion`, `force`, `threshold`)"
        }
        Rule::force_decl | Rule::threshold_decl | Rule::preprocess_decl | Rule::preprocess_kw => {
            "a learn declaration (`segments`, `frame`, `motion`, `force`, `threshold`)"
        }
        Rule::expect_clause => "`expect`",
        Rule::state => "`state`",
        Rule::terminal => "`terminal`",
        Rule::state_entry | Rule::move_stmt | Rule::control_stmt | Rule::stiffness_stmt | Rule::apply_stmt => {
            STATEMENTS
        }
        Rule::gains_stmt | Rule::entry_stmt | Rule::approach_stmt | Rule::approach_kw | Rule::transition => STATEMENTS,
        Rule::lift_off_stmt | Rule::lift_kw | Rule::repeat_stmt | Rule::repeat_kw => STATEMENTS,
        Rule::capture_stmt | Rule::capture_kw => STATEMENTS,
        Rule::move_at => "`at`",
        Rule::off_kw => "`off`",
        Rule::from_current => "`from current`",
        Rule::move_relative => "`relative`",
        Rule::control_group | Rule::control_mode => "`position` or `force`",
        Rule::axis_set | Rule::all_axes => "axes (`x y z rx ry rz` or `all`)",
        Rule::axis_value => "axes followed by `:`",
        Rule::extend => "`extend`",
        Rule::guard | Rule::guard_and | Rule::guard_held | Rule::guard_not | Rule::not_kw | Rule::named_guard => {
            "a guard"
        }
        Rule::for_kw => "`for`",
        Rule::force_cmp | Rule::timed | Rule::timed_kw | Rule::reached => "a guard",
        Rule::moved_cmp
        | Rule::moved_kw
        | Rule::magnitude_cmp
        | Rule::magnitude_kw
        | Rule::speed_cmp
        | Rule::speed_kw
        | Rule::entered_cmp
        | Rule::entered_kw => "a guard",
        Rule::cmp_op => "a comparison (`>=`, `>`, `<=`, `<`)",
        Rule::task_entry | Rule::step | Rule::fallback => "`step` or `fallback`",
        Rule::on_failure => "`on failure`",
        Rule::abort => "`abort`",
        Rule::call => "a call",
        Rule::arg | Rule::key => "an argument",
        Rule::list => "a list",
        Rule::record => "a block (`{ force: 30 N }`)",
        Rule::segment_ref => "`segment N`",
        Rule::axis_ref => "a frame axis (`frame.z`)",
        Rule::quantity | Rule::number => "a number",
        Rule::unit => "a unit",
        Rule::integer => "an integer",
        Rule::string | Rule::string_inner => "a string",
        Rule::ident => "a name",
        Rule::keyword => "a keyword",
        _ => return None,
    })
}

fn span_of(pair: &Pair<'_, Rule>) -> Span {
    let span = pair.as_span();
    Span::new(span.start(), span.end())
}

fn file_rule(pair: Pair<'_, Rule>) -> File {
    let mut out = File::default();
    for item in pair.into_inner() {
        match item.as_rule() {
            Rule::import => out.imports.push(import(item)),
            Rule::skill => out.skills.push(skill(item)),
            Rule::task => out.tasks.push(task(item)),
            Rule::EOI => {}
            rule => unreachable!("grammar: unexpected {rule:?} in file"),
        }
    }
    out
}

fn import(pair: Pair<'_, Rule>) -> Import {
    let string_pair = pair.into_inner().next().expect("grammar: import has a string");
    Import {
        span: span_of(&string_pair),
        path: string(string_pair),
    }
}

fn ident(pair: Pair<'_, Rule>) -> Ident {
    Ident {
        name: pair.as_str().to_string(),
        span: span_of(&pair),
    }
}

fn doc_text(pair: Pair<'_, Rule>) -> String {
    let text = pair.as_str().trim_start_matches("///");
    text.strip_prefix(' ').unwrap_or(text).trim_end().to_string()
}

fn skill(pair: Pair<'_, Rule>) -> Skill {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut name = None;
    let mut params = Vec::new();
    let mut learn = Vec::new();
    let mut limits = Vec::new();
    let mut states = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => name = Some(ident(inner)),
            Rule::param_decl => params.push(param_decl(inner)),
            Rule::learn => learn.extend(inner.into_inner().map(learn_entry)),
            Rule::limits => limits.extend(inner.into_inner().map(limit_entry)),
            Rule::state => states.push(state(inner)),
            Rule::terminal => states.push(terminal(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in skill"),
        }
    }
    Skill {
        doc,
        name: name.expect("grammar: skill has a name"),
        params,
        learn,
        limits,
        states,
        span,
    }
}

fn param_decl(pair: Pair<'_, Rule>) -> ParamDecl {
    let (doc, name, value) = named_value(pair, "a parameter");
    ParamDecl {
        doc,
        span: name.span.to(value.span),
        name,
        value,
    }
}

/// The doc comment, name and value of `NAME = VALUE` or `NAME: VALUE` (a parameter, a limit);
/// `what` names it in the grammar's invariants.
fn named_value(pair: Pair<'_, Rule>, what: &str) -> (Vec<String>, Ident, Expr) {
    let mut doc = Vec::new();
    let mut name = None;
    let mut value = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::param_kw => {}
            Rule::ident | Rule::key if name.is_none() => name = Some(ident(inner)),
            _ => value = Some(expr(inner)),
        }
    }
    let name = name.unwrap_or_else(|| panic!("grammar: {what} has a name"));
    let value = value.unwrap_or_else(|| panic!("grammar: {what} has a value"));
    (doc, name, value)
}

/// Parses `NAME=VALUE` as given to `--param` (`hold=5s`, `hold=5 s`, `strokes=6`). The spans
/// of the value are offsets into `text`.
pub fn parse_param_setting(text: &str) -> Result<(Ident, Expr), String> {
    if text.len() > 1000 {
        return Err("a parameter setting is at most 1000 characters".to_string());
    }
    if let Some(refused) = prescan::prescan(text, 0).first() {
        return Err(refused.message.clone());
    }
    let mut pairs = SkillParser::parse(Rule::param_setting, text)
        .map_err(|_| "expected `NAME=VALUE`, e.g. `--param hold=5s` or `--param strokes=6`".to_string())?;
    let root = pairs.next().expect("grammar: `param_setting` yields one pair");
    let mut name = None;
    let mut value = None;
    for inner in root.into_inner() {
        match inner.as_rule() {
            Rule::ident if name.is_none() => name = Some(ident(inner)),
            Rule::EOI => {}
            _ => value = Some(expr(inner)),
        }
    }
    match (name, value) {
        (Some(name), Some(value)) => Ok((name, value)),
        _ => Err("expected `NAME=VALUE`, e.g. `--param hold=5s`".to_string()),
    }
}

fn learn_entry(pair: Pair<'_, Rule>) -> LearnDecl {
    let mut doc = Vec::new();
    let mut decl = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            _ => decl = Some(inner),
        }
    }
    let decl = decl.expect("grammar: learn entry has a declaration");
    let span = span_of(&decl);
    let rule = decl.as_rule();
    let mut inner = decl.into_inner();
    let kind = match rule {
        Rule::segments_decl => LearnKind::Segments,
        Rule::frame_decl => LearnKind::Frame,
        Rule::motion_decl => LearnKind::Motion,
        Rule::force_decl => LearnKind::Force,
        Rule::threshold_decl => LearnKind::Threshold,
        Rule::preprocess_decl => {
            let keyword = inner.next().expect("grammar: preprocess keyword");
            if keyword.as_str() == "lowpass" {
                LearnKind::Lowpass
            } else {
                LearnKind::Resample
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} in learn"),
    };
    let mut name = None;
    let mut value = None;
    let mut expect = None;
    for part in inner {
        match part.as_rule() {
            Rule::ident if name.is_none() && value.is_none() && !matches!(kind, LearnKind::Segments) => {
                name = Some(ident(part))
            }
            Rule::expect_clause => {
                let integer = part.into_inner().next().expect("grammar: expect has an integer");
                expect = Some((parse_integer(integer.as_str()), span_of(&integer)));
            }
            _ => value = Some(expr(part)),
        }
    }
    LearnDecl {
        doc,
        kind,
        name,
        value: value.expect("grammar: learn declaration has a value"),
        expect,
        span,
    }
}

fn limit_entry(pair: Pair<'_, Rule>) -> LimitEntry {
    let (doc, name, value) = named_value(pair, "a limit");
    // Like a learn declaration's, the span starts after the doc comment.
    LimitEntry {
        doc,
        span: name.span.to(value.span),
        name,
        value,
    }
}

fn parse_integer(text: &str) -> u64 {
    // The grammar admits only digits; an absurdly long integer saturates and is range-checked later.
    text.parse().unwrap_or(u64::MAX)
}

fn state(pair: Pair<'_, Rule>) -> State {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut name = None;
    let mut body = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => name = Some(ident(inner)),
            Rule::state_entry => body.push(stmt(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in state"),
        }
    }
    State {
        doc,
        name: name.expect("grammar: state has a name"),
        body: StateBody::Active(body),
        span,
    }
}

fn terminal(pair: Pair<'_, Rule>) -> State {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut idents = Vec::new();
    let mut message = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => idents.push(ident(inner)),
            Rule::string => message = Some(string(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in terminal"),
        }
    }
    let mut idents = idents.into_iter();
    let name = idents.next().expect("grammar: terminal has a name");
    let outcome = idents.next().expect("grammar: terminal has an outcome");
    State {
        doc,
        name,
        body: StateBody::Terminal { outcome, message },
        span,
    }
}

fn stmt(pair: Pair<'_, Rule>) -> Stmt {
    let mut doc = Vec::new();
    let mut stmt_pair = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            _ => stmt_pair = Some(inner),
        }
    }
    let pair = stmt_pair.expect("grammar: state entry has a statement");
    let span = span_of(&pair);
    let rule = pair.as_rule();
    let mut inner = pair.into_inner();
    let kind = match rule {
        Rule::move_stmt => {
            let motion = ident(inner.next().expect("grammar: move names a motion"));
            let mut start = None;
            let mut at = None;
            let mut offset = None;
            for part in inner {
                match part.as_rule() {
                    Rule::move_at => {
                        let mut parts = part.into_inner();
                        at = parts.next().map(ident);
                        offset = parts.next().map(|offset_pair| {
                            let mut inner = offset_pair.into_inner();
                            AtOffset {
                                value: expr(inner.next().expect("grammar: an offset has a value")),
                                frame: inner.next().map(ident),
                            }
                        });
                    }
                    rule => start = Some(rule),
                }
            }
            StmtKind::Move {
                motion,
                from_current: start == Some(Rule::from_current),
                relative: start == Some(Rule::move_relative),
                at,
                offset,
            }
        }
        Rule::control_stmt => {
            let mut groups = Vec::new();
            let mut frame = None;
            for part in inner {
                match part.as_rule() {
                    Rule::control_group => groups.push(control_group(part)),
                    Rule::ident => frame = Some(ident(part)),
                    rule => unreachable!("grammar: unexpected {rule:?} in control"),
                }
            }
            StmtKind::Control { groups, frame }
        }
        Rule::stiffness_stmt => StmtKind::Stiffness(inner.map(axis_value).collect()),
        Rule::apply_stmt => StmtKind::Apply(ident(inner.next().expect("grammar: apply names a force"))),
        Rule::gains_stmt => StmtKind::Gains(inner.map(arg).collect()),
        Rule::entry_stmt => StmtKind::Entry(inner.map(expr).collect()),
        Rule::approach_stmt => {
            let _keyword = inner.next().expect("grammar: approach keyword");
            let within = expr(inner.next().expect("grammar: approach has a distance"));
            let speed = expr(inner.next().expect("grammar: approach has a speed"));
            StmtKind::Approach { within, speed }
        }
        Rule::lift_off_stmt => {
            let _lift = inner.next().expect("grammar: lift keyword");
            let _off = inner.next().expect("grammar: off keyword");
            let distance = expr(inner.next().expect("grammar: lift off has a distance"));
            let speed = inner.next().map(expr);
            StmtKind::LiftOff { distance, speed }
        }
        Rule::repeat_stmt => {
            let _keyword = inner.next().expect("grammar: repeat keyword");
            StmtKind::Repeat(expr(inner.next().expect("grammar: repeat has a count")))
        }
        Rule::capture_stmt => {
            let _keyword = inner.next().expect("grammar: capture keyword");
            StmtKind::Capture {
                name: ident(inner.next().expect("grammar: capture names a pose")),
                once: inner.next().map(|pair| span_of(&pair)),
            }
        }
        Rule::transition => {
            let watch = match inner.peek() {
                Some(pair) if pair.as_rule() == Rule::watch_kw => inner.next().map(|pair| span_of(&pair)),
                _ => None,
            };
            let guard_pair = inner.next().expect("grammar: transition has a guard");
            let target_pair = inner.next().expect("grammar: transition has a target");
            StmtKind::Transition {
                watch,
                guard: guard(guard_pair),
                target: target(target_pair),
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} in state"),
    };
    Stmt { doc, kind, span }
}

fn control_group(pair: Pair<'_, Rule>) -> ControlGroup {
    let mut inner = pair.into_inner();
    let mode = inner.next().expect("grammar: control group has a mode");
    let axes = axis_set(inner.next().expect("grammar: control group has axes"));
    ControlGroup {
        force: mode.as_str() == "force",
        mode_span: span_of(&mode),
        axes,
    }
}

fn axis_set(pair: Pair<'_, Rule>) -> AxisSet {
    let span = span_of(&pair);
    let idents: Vec<Ident> = pair
        .into_inner()
        .filter(|p| p.as_rule() == Rule::ident)
        .map(ident)
        .collect();
    if idents.is_empty() {
        AxisSet::All(span)
    } else {
        AxisSet::List(idents)
    }
}

fn axis_value(pair: Pair<'_, Rule>) -> AxisValue {
    let mut inner = pair.into_inner();
    let axes = axis_set(inner.next().expect("grammar: axis value has axes"));
    let value = expr(inner.next().expect("grammar: axis value has a value"));
    AxisValue { axes, value }
}

fn target(pair: Pair<'_, Rule>) -> Target {
    match pair.as_rule() {
        Rule::ident => Target::State(ident(pair)),
        Rule::extend => {
            let span = span_of(&pair);
            let mut inner = pair.into_inner();
            let axis = axis_ref(inner.next().expect("grammar: extend has an axis"));
            let speed = expr(inner.next().expect("grammar: extend has a speed"));
            let max = expr(inner.next().expect("grammar: extend has a bound"));
            let then = ident(inner.next().expect("grammar: extend has a then state"));
            Target::Extend {
                axis,
                speed,
                max,
                then,
                span,
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} as target"),
    }
}

fn guard(pair: Pair<'_, Rule>) -> Guard {
    let span = span_of(&pair);
    match pair.as_rule() {
        Rule::guard | Rule::guard_and => {
            let is_or = pair.as_rule() == Rule::guard;
            let mut parts: Vec<Guard> = Vec::new();
            for part in pair.into_inner().map(guard) {
                // `(a and b) and c` is `a and b and c`: flatten so that the formatter's
                // output, which drops redundant parentheses, parses back to the same tree.
                match part.kind {
                    GuardKind::Or(inner) if is_or => parts.extend(inner),
                    GuardKind::And(inner) if !is_or => parts.extend(inner),
                    kind => parts.push(Guard { kind, span: part.span }),
                }
            }
            if parts.len() == 1 {
                return parts.pop().expect("one part");
            }
            Guard {
                kind: if is_or {
                    GuardKind::Or(parts)
                } else {
                    GuardKind::And(parts)
                },
                span,
            }
        }
        Rule::guard_held => {
            let mut inner = pair.into_inner();
            let held = guard(inner.next().expect("grammar: guard_held has a guard"));
            if inner.next().is_none() {
                return held;
            }
            let duration = expr(inner.next().expect("grammar: `for` has a duration"));
            Guard {
                kind: GuardKind::Held {
                    guard: Box::new(held),
                    duration,
                },
                span,
            }
        }
        Rule::guard_not => {
            let mut inner = pair.into_inner();
            let first = inner.next().expect("grammar: guard_not is not empty");
            if first.as_rule() == Rule::not_kw {
                let negated = guard(inner.next().expect("grammar: not has an operand"));
                Guard {
                    kind: GuardKind::Not(Box::new(negated)),
                    span,
                }
            } else {
                guard(first)
            }
        }
        Rule::force_cmp => {
            let mut inner = pair.into_inner();
            let axis = axis_ref(inner.next().expect("grammar: force() has an axis"));
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Force { axis, op, rhs },
                span,
            }
        }
        Rule::moved_cmp => {
            let mut inner = pair.into_inner().skip(1).peekable();
            let axis = match inner.peek().map(Pair::as_rule) {
                Some(Rule::axis_ref) => Some(axis_ref(inner.next().expect("peeked"))),
                _ => None,
            };
            let (since, since_keyword) = match inner.peek().map(Pair::as_rule) {
                Some(Rule::since_clause) => {
                    let mut clause = inner.next().expect("peeked").into_inner();
                    let keyword = clause.next().map(|k| span_of(&k));
                    (clause.next().map(ident), keyword)
                }
                _ => (None, None),
            };
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Moved {
                    axis,
                    since,
                    since_keyword,
                    op,
                    rhs,
                },
                span,
            }
        }
        Rule::magnitude_cmp => {
            let mut inner = pair.into_inner();
            let moment = inner.next().expect("grammar: magnitude keyword").as_str() == "moment_magnitude";
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Magnitude { moment, op, rhs },
                span,
            }
        }
        Rule::entered_cmp => {
            let mut inner = pair.into_inner();
            let _keyword = inner.next().expect("grammar: entered keyword");
            let state = ident(inner.next().expect("grammar: entered names a state"));
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Entered { state, op, rhs },
                span,
            }
        }
        Rule::speed_cmp => {
            let mut inner = pair.into_inner();
            let _keyword = inner.next().expect("grammar: speed keyword");
            let (op, rhs) = comparison(&mut inner);
            Guard {
                kind: GuardKind::Speed { op, rhs },
                span,
            }
        }
        Rule::timed => {
            let mut inner = pair.into_inner();
            let timeout = inner.next().expect("grammar: timed keyword").as_str() == "timeout";
            let duration = expr(inner.next().expect("grammar: timed has a duration"));
            Guard {
                kind: GuardKind::Timed { timeout, duration },
                span,
            }
        }
        Rule::reached => {
            let tolerance = expr(
                pair.into_inner()
                    .next()
                    .expect("grammar: force_reached has a tolerance"),
            );
            Guard {
                kind: GuardKind::ForceReached(tolerance),
                span,
            }
        }
        Rule::named_guard => {
            let name = ident(pair.into_inner().next().expect("grammar: named guard has a name"));
            Guard {
                kind: GuardKind::Named(name),
                span,
            }
        }
        rule => unreachable!("grammar: unexpected {rule:?} in guard"),
    }
}

fn cmp_op(pair: Pair<'_, Rule>) -> CmpOp {
    match pair.as_str() {
        ">=" => CmpOp::Ge,
        ">" => CmpOp::Gt,
        "<=" => CmpOp::Le,
        _ => CmpOp::Lt,
    }
}

fn task(pair: Pair<'_, Rule>) -> Task {
    let span = span_of(&pair);
    let mut doc = Vec::new();
    let mut name = None;
    let mut steps = Vec::new();
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            Rule::ident => name = Some(ident(inner)),
            Rule::task_entry => steps.push(step(inner)),
            rule => unreachable!("grammar: unexpected {rule:?} in task"),
        }
    }
    Task {
        doc,
        name: name.expect("grammar: task has a name"),
        steps,
        span,
    }
}

fn step(pair: Pair<'_, Rule>) -> Step {
    let mut doc = Vec::new();
    let mut step_pair = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::doc => doc.push(doc_text(inner)),
            _ => step_pair = Some(inner),
        }
    }
    let pair = step_pair.expect("grammar: task entry has a step");
    let span = span_of(&pair);
    let fallback = pair.as_rule() == Rule::fallback;
    let mut inner = pair.into_inner();
    let name = ident(inner.next().expect("grammar: step has a name"));
    let call_pair = inner.next().expect("grammar: step has a call");
    let mut call_inner = call_pair.into_inner();
    let skill = ident(call_inner.next().expect("grammar: call has a name"));
    let args = call_inner.map(arg).collect();
    let on_failure = inner.next().map(|policy| {
        let part = policy.into_inner().next().expect("grammar: on failure has a policy");
        match part.as_rule() {
            Rule::abort => OnFailure::Abort(span_of(&part)),
            _ => OnFailure::Fallback(ident(part)),
        }
    });
    Step {
        doc,
        fallback,
        name,
        skill,
        args,
        on_failure,
        span,
    }
}

fn arg(pair: Pair<'_, Rule>) -> Arg {
    let span = span_of(&pair);
    let mut key = None;
    let mut value = None;
    for inner in pair.into_inner() {
        match inner.as_rule() {
            Rule::key => key = Some(ident(inner)),
            _ => value = Some(expr(inner)),
        }
    }
    Arg {
        key,
        value: value.expect("grammar: argument has a value"),
        span,
    }
}

fn axis_ref(pair: Pair<'_, Rule>) -> AxisRef {
    let span = span_of(&pair);
    let mut inner = pair.into_inner();
    let frame = ident(inner.next().expect("grammar: axis ref has a frame"));
    let axis = ident(inner.next().expect("grammar: axis ref has an axis"));
    AxisRef { frame, axis, span }
}

fn number(pair: Pair<'_, Rule>) -> Number {
    let text = pair.as_str().to_string();
    // The grammar admits only decimal literals, which always parse (perhaps to infinity, checked later).
    let value = text.parse().unwrap_or(f64::NAN);
    Number { text, value }
}

fn string(pair: Pair<'_, Rule>) -> String {
    let raw = pair.into_inner().next().map_or("", |inner| inner.as_str());
    let mut out = String::with_capacity(raw.len());
    let mut chars = raw.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(other) => out.push(other),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// The operator and right-hand side that end every comparison guard (`>= 6 mm`).
fn comparison<'i>(inner: &mut impl Iterator<Item = Pair<'i, Rule>>) -> (CmpOp, Expr) {
    let op = cmp_op(inner.next().expect("grammar: comparison operator"));
    let rhs = expr(inner.next().expect("grammar: comparison has a right-hand side"));
    (op, rhs)
}

fn expr(pair: Pair<'_, Rule>) -> Expr {
    let span = span_of(&pair);
    let kind = match pair.as_rule() {
        Rule::quantity => {
            let mut inner = pair.into_inner();
            let number_pair = inner.next().expect("grammar: quantity has a number");
            let unit = ident(inner.next().expect("grammar: quantity has a unit"));
            ExprKind::Quantity {
                number: number(number_pair),
                unit,
            }
        }
        Rule::number => ExprKind::Number(number(pair)),
        Rule::string => ExprKind::Str(string(pair)),
        Rule::list => ExprKind::List(pair.into_inner().map(expr).collect()),
        Rule::record => ExprKind::Record(pair.into_inner().map(arg).collect()),
        Rule::segment_ref => {
            let integer = pair.into_inner().next().expect("grammar: segment has an index");
            ExprKind::Segment(parse_integer(integer.as_str()))
        }
        Rule::call => {
            let mut inner = pair.into_inner();
            let name = ident(inner.next().expect("grammar: call has a name"));
            ExprKind::Call {
                name,
                args: inner.map(arg).collect(),
            }
        }
        Rule::axis_ref => ExprKind::Axis(axis_ref(pair)),
        Rule::ident => ExprKind::Name(ident(pair)),
        Rule::negated => {
            let mut inner = pair.into_inner();
            let _op = inner.next().expect("grammar: negation has its `-`");
            ExprKind::Neg(Box::new(expr(inner.next().expect("grammar: negation has an operand"))))
        }
        Rule::sum | Rule::product => {
            let mut inner = pair.into_inner();
            let first = inner.next().expect("grammar: a chain has a first operand");
            if inner.peek().is_none() {
                // A value without an operator at this level (its span is the operand's: the
                // chain's takes the whitespace after it).
                return expr(first);
            }
            let first = Box::new(expr(first));
            let mut rest = Vec::new();
            while let (Some(op), Some(operand)) = (inner.next(), inner.next()) {
                let op = match op.as_str() {
                    "+" => BinOp::Add,
                    "-" => BinOp::Sub,
                    "*" => BinOp::Mul,
                    _ => BinOp::Div,
                };
                rest.push((op, expr(operand)));
            }
            ExprKind::Arith { first, rest }
        }
        rule => unreachable!("grammar: unexpected {rule:?} as value"),
    };
    Expr { kind, span }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The message and help of the one diagnostic of `text`.
    fn keyword_diag(text: &str) -> (String, String) {
        let (_, diags) = parse(&SourceFile::new("t.skill", text), 0);
        let diag = diags.first().expect("a diagnostic");
        (diag.message.clone(), diag.help.clone().unwrap_or_default())
    }

    #[test]
    fn a_keyword_as_a_name_is_explained_for_what_it_names() {
        let (message, help) = keyword_diag("skill s { state up { on timeout 1 s -> done } }");
        assert_eq!(message, "`up` is a keyword and cannot name a state");
        assert_eq!(help, "rename it, e.g. `up_state`");
        let (message, help) = keyword_diag("skill s { learn { motion up = dmp(segment 1) } }");
        assert_eq!(message, "`up` is a keyword and cannot name a motion");
        assert_eq!(help, "rename it, e.g. `up_motion`");
        let (message, help) = keyword_diag("skill s { learn { frame at = fixed() } }");
        assert_eq!(message, "`at` is a keyword and cannot name a frame");
        assert_eq!(help, "rename it, e.g. `at_frame`");
        let (message, _) = keyword_diag("skill s { learn { threshold to = 2 N } }");
        assert_eq!(message, "`to` is a keyword and cannot name a threshold");
        let (message, help) = keyword_diag("skill s { state a { on timeout 1 s -> up } }");
        assert_eq!(message, "`up` is a keyword and cannot name a state");
        assert_eq!(help, "rename it, e.g. `up_state`");
        let (message, _) = keyword_diag("skill s { terminal from: success }");
        assert_eq!(message, "`from` is a keyword and cannot name a terminal state");
    }

    #[test]
    fn a_doc_comment_before_a_block_says_what_it_cannot_document() {
        let text = "skill s {\n    /// The limits.\n    limits { force: 40 N }\n}\n";
        let (_, diags) = parse(&SourceFile::new("t.skill", text), 0);
        let diag = diags.first().expect("a diagnostic");
        assert_eq!(diag.message, "a doc comment cannot document a `limits` block");
        assert_eq!(&text[diag.span().start..diag.span().end], "/// The limits.");
        assert!(diag.help.as_deref().unwrap_or("").contains("document each limit"));
        let (message, _) = keyword_diag("skill s {\n    /// The plan.\n    learn { }\n}\n");
        assert_eq!(message, "a doc comment cannot document a `learn` block");
        let (message, _) = keyword_diag("skill s {\n    terminal d: success\n    /// Dangling.\n}\n");
        assert_eq!(message, "a doc comment cannot document the end of a block");
    }

    #[test]
    fn arithmetic_parses_with_precedence_and_keeps_arrows_and_comments_apart() {
        let text = "skill s { param a = -1 mm - 2 * -(3 mm + 4 mm) / 2 // c\n state x { on dwell 1 s-> d } }";
        let (file, diags) = parse(&SourceFile::new("t.skill", text), 0);
        assert!(diags.is_empty(), "{diags:?}");
        let value = &file.skills[0].params[0].value;
        // `-1 mm - ((2 * -(3 mm + 4 mm)) / 2)`: one additive chain of a literal and a product.
        let ExprKind::Arith { first, rest } = &value.kind else {
            panic!("{value:?}")
        };
        assert!(matches!(&first.kind, ExprKind::Quantity { number, .. } if number.text == "-1"));
        assert_eq!(rest.len(), 1);
        assert_eq!(rest[0].0, BinOp::Sub);
        let ExprKind::Arith { rest: product, .. } = &rest[0].1.kind else {
            panic!("{:?}", rest[0].1)
        };
        assert_eq!(
            product.iter().map(|(op, _)| *op).collect::<Vec<_>>(),
            [BinOp::Mul, BinOp::Div]
        );
        assert!(matches!(&product[0].1.kind, ExprKind::Neg(inner) if matches!(inner.kind, ExprKind::Arith { .. })));
        // The value's span ends at its last character, not at the comment after it.
        assert!(text[value.span.start..value.span.end].ends_with("/ 2"));
    }

    #[test]
    fn a_capture_or_a_move_at_without_a_name_says_the_name_is_missing() {
        let state = |body: &str| format!("skill s {{ state a {{ {body} }} terminal d: success }}");
        for body in [
            "capture\n control position all on timeout 1 s -> d",
            "capture }",
            "capture 5 mm on timeout 1 s -> d",
        ] {
            let (message, help) = keyword_diag(&state(body));
            assert_eq!(message, "`capture` needs a name for the pose it keeps", "{body}");
            assert!(help.contains("`capture found`"), "{help}");
        }
        for body in [
            "move p at\n control position all on timeout 1 s -> d",
            "move p relative at on motion_done -> d",
            "move p at }",
        ] {
            let (message, _) = keyword_diag(&state(body));
            assert_eq!(message, "`move ... at` needs the name of a captured pose", "{body}");
        }
        // Located at the word that wants the name.
        let text = state("move p at\n control position all on timeout 1 s -> d");
        let (_, diags) = parse(&SourceFile::new("t.skill", text.as_str()), 0);
        let at = text.find(" at").expect("at") + 1;
        assert_eq!(diags[0].span(), Span::new(at, at + 2));
        // An `at` that takes a value is another error.
        let (message, _) = keyword_diag(&state("move p approach within 1 cm at }"));
        assert!(message.starts_with("syntax error"), "{message}");
    }
}

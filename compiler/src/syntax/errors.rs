//! Syntax errors: pest's error turned into one diagnostic in the template's words (what was
//! expected, a keyword used as a name, a doc comment that documents nothing, a missing name).

use crate::diag::{Code, Diag};
use crate::source::Span;
use pest::error::InputLocation;
use skill_grammar::Rule;

pub(super) fn syntax_error(err: pest::error::Error<Rule>, file: usize, src_text: &str) -> Diag {
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

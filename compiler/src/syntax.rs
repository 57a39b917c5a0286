//! Parsing: source text to the spanned [`ast`](crate::ast), through pest.
//!
//! pest cannot recover after an error, so a file with a syntax error yields one
//! diagnostic and an empty tree. Input that would make pest recurse or run long
//! (deep nesting, huge files) is refused before pest sees it, and so are characters the
//! grammar cannot take, each named (`syntax/prescan.rs`).
//!
//! The lowering from pest's pairs to the tree is spread over this module's files by job:
//! `syntax/items.rs` (skills with their `learn` and `limits` blocks, tasks), `states.rs`,
//! `guards.rs` and `values.rs` (expressions); `errors.rs` turns pest's error into the one
//! diagnostic.

use crate::ast::*;
use crate::diag::{Code, Diag};
use crate::source::{SourceFile, Span};
use pest::iterators::Pair;
use pest::Parser;
use skill_grammar::{Rule, SkillParser};

mod errors;
mod guards;
mod items;
mod prescan;
mod states;
mod values;

use errors::syntax_error;
pub use errors::KEYWORDS;
use items::{skill, task};
use values::{expr, string};

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

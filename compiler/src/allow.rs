//! Warnings allowed on purpose: `// allow(extend_upwards): the lid is found from below` on a
//! statement's line, or alone on the line before it, silences that lint there, with its reason.
//!
//! An allow is a comment, so the formatter keeps it where it is and the grammar does not change.
//! It must name a lint (a warning's code, short or in full: `extend_upwards` or
//! `skill::lint::extend_upwards`; errors cannot be allowed), give a reason after the colon, and
//! silence something: otherwise it is itself the warning `skill::lint::unused_allow`, so an allow
//! cannot outlive the warning it was written for unnoticed.

use crate::diag::{Code, Diag, Severity};
use crate::source::{SourceFile, Span};
use std::collections::HashMap;

/// One `// allow(NAME): REASON` comment.
struct Allow {
    /// The comment, from its `//`.
    span: Span,
    /// What it names, as written.
    name: String,
    /// The reason, trimmed (empty when missing).
    reason: String,
    /// The line (0-based) whose warnings it silences.
    line: usize,
}

/// Drops the warnings of `file` that an allow there silences, and reports each allow that is
/// wrong or silences nothing; how many warnings it dropped.
pub(crate) fn apply(file: usize, source: &SourceFile, diags: &mut Vec<Diag>) -> usize {
    let allows = allows_in(&source.text);
    if allows.is_empty() {
        return 0;
    }
    let mut dropped = 0;
    let lines: Vec<usize> = line_starts(&source.text);
    let line_of = |offset: usize| lines.partition_point(|&start| start <= offset).saturating_sub(1);
    let mut problems = Vec::new();
    for allow in allows {
        let code = Code::ALL
            .iter()
            .copied()
            .find(|code| code.as_str() == allow.name || code.as_str().rsplit("::").next() == Some(allow.name.as_str()));
        let problem = match code {
            None => Some((
                format!("`allow({})` names no lint", allow.name),
                format!(
                    "lints that can be allowed: {}",
                    Code::ALL
                        .iter()
                        .filter(|code| code.severity() == Severity::Warning && **code != Code::UnusedAllow)
                        .map(|code| format!("`{}`", code.as_str().rsplit("::").next().unwrap_or("")))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
            Some(code) if code.severity() == Severity::Error => Some((
                format!("`{}` is an error and cannot be allowed", allow.name),
                "fix what it reports: only warnings (`skill::lint::...`) can be allowed".to_string(),
            )),
            Some(_) if allow.reason.is_empty() => Some((
                format!("`allow({})` gives no reason", allow.name),
                format!("say why after a colon: `// allow({}): REASON`", allow.name),
            )),
            Some(code) => {
                let before = diags.len();
                diags.retain(|d| !(d.file == file && d.code == code && line_of(d.span().start) == allow.line));
                dropped += before - diags.len();
                (diags.len() == before).then(|| {
                    (
                        format!("`allow({})` silences nothing", allow.name),
                        format!(
                            "no `{}` warning is on line {}: remove the allow",
                            code.as_str(),
                            allow.line + 1
                        ),
                    )
                })
            }
        };
        if let Some((message, help)) = problem {
            problems.push(Diag::new(Code::UnusedAllow, file, allow.span, message, "this allow").help(help));
        }
    }
    diags.extend(problems);
    dropped
}

fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(at, _)| at + 1))
        .collect()
}

/// The allows of a file's text, each with the line it applies to. The comments are the
/// formatter's ([`crate::fmt::line_comments`]: `//` outside strings, doc comments left out).
fn allows_in(text: &str) -> Vec<Allow> {
    let starts = line_starts(text);
    let line_of = |offset: usize| starts.partition_point(|&start| start <= offset).saturating_sub(1);
    let comments = crate::fmt::line_comments(text);
    let comment_on: HashMap<usize, usize> = comments.iter().map(|c| (line_of(c.span.start), c.span.start)).collect();
    let lines: Vec<&str> = text.split('\n').collect();
    // Whether line `n` holds code: text before its comment, if any, that is not a doc comment.
    let has_code = |n: usize| {
        let end = comment_on.get(&n).map_or(lines[n].len(), |&at| at - starts[n]);
        let code = lines[n][..end].trim();
        !code.is_empty() && !code.starts_with("///")
    };
    let mut allows = Vec::new();
    for comment in &comments {
        let body = comment.text.trim_start_matches('/').trim_start();
        let Some(rest) = body.strip_prefix("allow(") else {
            continue;
        };
        let Some(close) = rest.find(')') else {
            continue;
        };
        let reason = rest[close + 1..].trim_start().strip_prefix(':').unwrap_or("").trim();
        let number = line_of(comment.span.start);
        // Alone on its line, it is about the next line with code on it.
        let target = if comment.trailing {
            Some(number)
        } else {
            (number + 1..lines.len()).find(|&next| has_code(next))
        };
        allows.push(Allow {
            span: comment.span,
            name: rest[..close].trim().to_string(),
            reason: reason.to_string(),
            line: target.unwrap_or(number),
        });
    }
    allows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_allows_before_and_on_their_line_and_skips_strings_and_docs() {
        let text = "a\n    // allow(unused): kept for the next version\n\n    // a note\n    state x {\nb \"// allow(no)\" // allow(extend_upwards)\n/// allow(unused): a doc\n";
        let allows = allows_in(text);
        assert_eq!(allows.len(), 2);
        assert_eq!((allows[0].name.as_str(), allows[0].line), ("unused", 4));
        assert_eq!(allows[0].reason, "kept for the next version");
        assert_eq!(
            (allows[1].name.as_str(), allows[1].line, allows[1].reason.as_str()),
            ("extend_upwards", 5, "")
        );
        assert_eq!(
            &text[allows[1].span.start..allows[1].span.end],
            "// allow(extend_upwards)"
        );
    }
}

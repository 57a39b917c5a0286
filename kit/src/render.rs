//! Rendering diagnostics for people (miette, colour only on a terminal) and for tools (JSON lines).
//! The text renderer lives in the compiler, so that its tests can snapshot what `skillc` prints.

pub use skill_compiler::render::{all_plain, human, plain};
use skill_compiler::{Compilation, Diag, Severity};

/// The JSON object for one diagnostic, for editors and CI.
pub fn json(diag: &Diag, compilation: &Compilation) -> serde_json::Value {
    let source = &compilation.files[diag.file];
    let span = diag.span();
    let (line, column) = source.line_col(span.start);
    let (end_line, end_column) = source.line_col(span.end);
    serde_json::json!({
        "file": source.name,
        "line": line,
        "column": column,
        "end_line": end_line,
        "end_column": end_column,
        "severity": diag.severity().as_str(),
        "code": diag.code.as_str(),
        "message": diag.message,
        "help": diag.help,
        "labels": diag.labels.iter().map(|label| {
            let (line, column) = source.line_col(label.span.start);
            serde_json::json!({ "line": line, "column": column, "text": label.text })
        }).collect::<Vec<_>>(),
    })
}

/// Counts of errors and warnings.
pub fn counts(diags: &[Diag]) -> (usize, usize) {
    let errors = diags.iter().filter(|d| d.severity() == Severity::Error).count();
    (errors, diags.len() - errors)
}

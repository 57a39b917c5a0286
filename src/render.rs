//! Rendering diagnostics for people (miette, colour only on a terminal) and for tools (JSON lines).

use miette::{GraphicalReportHandler, GraphicalTheme};
use skill_compiler::{Compilation, Diag, Severity};

/// Renders one diagnostic as text; `color` picks a coloured unicode theme.
pub fn human(diag: &Diag, compilation: &Compilation, color: bool, width: usize) -> String {
    let theme = if color {
        GraphicalTheme::unicode()
    } else {
        GraphicalTheme::unicode_nocolor()
    };
    let handler = GraphicalReportHandler::new_themed(theme)
        .with_width(width)
        .with_links(false);
    let mut out = String::new();
    let source = &compilation.files[diag.file];
    if handler.render_report(&mut out, &diag.with_source(source)).is_err() {
        // Rendering into a String cannot fail in practice; fall back to a plain line.
        out = plain(diag, compilation);
    }
    out
}

/// One line: `file:line:col: error[code]: message`.
pub fn plain(diag: &Diag, compilation: &Compilation) -> String {
    let source = &compilation.files[diag.file];
    let (line, column) = source.line_col(diag.span().start);
    format!(
        "{}:{line}:{column}: {}[{}]: {}\n",
        source.name,
        diag.severity().as_str(),
        diag.code,
        diag.message
    )
}

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

/// Every diagnostic of a compilation rendered without colour at a fixed width (for snapshots).
pub fn all_plain(compilation: &Compilation, width: usize) -> String {
    compilation
        .diags
        .iter()
        .map(|diag| human(diag, compilation, false, width))
        .collect::<Vec<_>>()
        .join("\n")
}

//! Rendering diagnostics as text for people: miette's report with source excerpts (colour on
//! request), or one plain line each.

use crate::{Compilation, Diag};
use miette::{GraphicalReportHandler, GraphicalTheme};

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

/// Every diagnostic of a compilation rendered without colour at a fixed width (for snapshots).
pub fn all_plain(compilation: &Compilation, width: usize) -> String {
    compilation
        .diags
        .iter()
        .map(|diag| human(diag, compilation, false, width))
        .collect::<Vec<_>>()
        .join("\n")
}

//! Source files and byte spans, with line/column lookup for messages and the IR's source map.

use std::sync::Arc;

/// A byte range in one source file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord)]
pub struct Span {
    /// First byte.
    pub start: usize,
    /// One past the last byte.
    pub end: usize,
}

impl Span {
    /// A span from `start` to `end`.
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }

    /// The smallest span covering both.
    pub fn to(self, other: Span) -> Span {
        Span::new(self.start.min(other.start), self.end.max(other.end))
    }

    /// Its length in bytes.
    pub fn len(self) -> usize {
        self.end - self.start
    }

    /// Whether it covers no byte.
    pub fn is_empty(self) -> bool {
        self.start == self.end
    }
}

impl From<Span> for miette::SourceSpan {
    fn from(span: Span) -> Self {
        (span.start, span.len()).into()
    }
}

/// A named source text, shared cheaply between diagnostics.
///
/// The text is what an editor shows: a byte order mark (U+FEFF) that opens the file, which
/// editors write and hide, is not part of it. Every [`Span`] is a byte offset into this text, so
/// in a file that starts with a byte order mark an offset is three bytes short of the same place
/// in the file's bytes, while lines and columns ([`SourceFile::line_col`]) are those the editor
/// shows either way.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SourceFile {
    /// The name shown to the user (a path as given on the command line).
    pub name: String,
    /// The text.
    pub text: Arc<str>,
    line_starts: Arc<[usize]>,
}

impl SourceFile {
    /// A source file from its name and text, without the byte order mark it may start with.
    pub fn new(name: impl Into<String>, text: impl Into<Arc<str>>) -> Self {
        let mut text: Arc<str> = text.into();
        if let Some(rest) = text.strip_prefix(BYTE_ORDER_MARK) {
            text = rest.into();
        }
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(at, _)| at + 1))
            .collect();
        SourceFile {
            name: name.into(),
            text,
            line_starts,
        }
    }

    /// 1-based line and column (in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = self.line_starts.partition_point(|&start| start <= offset) - 1;
        let start = self.line_starts[line];
        let column = self
            .text
            .get(start..offset)
            .map_or(offset - start, |s| s.chars().count());
        (line + 1, column + 1)
    }

    /// The text of a span.
    pub fn slice(&self, span: Span) -> &str {
        self.text.get(span.start..span.end).unwrap_or("")
    }
}

/// The byte order mark a file may start with; [`SourceFile::new`] drops it.
pub const BYTE_ORDER_MARK: char = '\u{FEFF}';

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_from_one_and_in_characters() {
        let src = SourceFile::new("a.skill", "ab\nçd\n");
        assert_eq!(src.line_col(0), (1, 1));
        assert_eq!(src.line_col(3), (2, 1));
        assert_eq!(src.line_col(5), (2, 2));
        assert_eq!(src.line_col(7), (3, 1));
        assert_eq!(src.line_col(100), (3, 1));
    }

    #[test]
    fn a_leading_byte_order_mark_is_not_part_of_the_text() {
        let src = SourceFile::new("a.skill", "\u{FEFF}skill s {}\n");
        assert_eq!(&*src.text, "skill s {}\n");
        assert_eq!(src.line_col(6), (1, 7), "columns as the editor shows them");
        assert_eq!(src.slice(Span::new(6, 7)), "s");
        // Only one, and only at the start: another is a character of the text.
        let src = SourceFile::new("a.skill", "\u{FEFF}\u{FEFF}x");
        assert_eq!(&*src.text, "\u{FEFF}x");
    }
}

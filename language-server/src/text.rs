//! Positions and addresses: byte offsets to and from the protocol's line and character (in
//! UTF-16 code units by default, UTF-8 bytes when the client offers it), and `file:` URIs to
//! and from the paths the compiler names files by.

use lsp_types::{Position, Range};
use skill_compiler::Span;

/// How the client counts characters within a line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// UTF-16 code units: the protocol's default, what VS Code counts.
    Utf16,
    /// UTF-8 bytes: offered by Neovim and Helix.
    Utf8,
}

impl Encoding {
    /// The width of one character in this encoding's units.
    fn width(self, c: char) -> u32 {
        match self {
            Encoding::Utf16 => c.len_utf16() as u32,
            Encoding::Utf8 => c.len_utf8() as u32,
        }
    }
}

/// The start of every line of a text, for position lookups both ways.
#[derive(Debug, Clone)]
pub struct LineIndex {
    starts: Vec<usize>,
    encoding: Encoding,
}

impl LineIndex {
    /// The index of `text`, counting characters in `encoding`.
    pub fn new(text: &str, encoding: Encoding) -> Self {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(at, _)| at + 1))
            .collect();
        LineIndex { starts, encoding }
    }

    /// The position of a byte offset (clamped to the text, and back to a character boundary).
    pub fn position(&self, text: &str, offset: usize) -> Position {
        let mut offset = offset.min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let line = self.starts.partition_point(|&start| start <= offset) - 1;
        let start = self.starts[line];
        let character = text[start..offset].chars().map(|c| self.encoding.width(c)).sum();
        Position::new(line as u32, character)
    }

    /// The range of a span.
    pub fn range(&self, text: &str, span: Span) -> Range {
        Range::new(self.position(text, span.start), self.position(text, span.end))
    }

    /// The byte offset of a position: a character past the line's end is its end, a line past
    /// the text's end is the text's end, a position inside a character is its start.
    pub fn offset(&self, text: &str, position: Position) -> usize {
        let Some(&start) = self.starts.get(position.line as usize) else {
            return text.len();
        };
        let end = self
            .starts
            .get(position.line as usize + 1)
            .map_or(text.len(), |next| next - 1);
        let mut units = 0;
        for (at, c) in text[start..end].char_indices() {
            if units >= position.character {
                return start + at;
            }
            units += self.encoding.width(c);
            if units > position.character {
                return start + at;
            }
        }
        end
    }
}

/// The path a `file:` URI names (percent-decoded), or the URI itself for other schemes.
pub fn uri_to_name(uri: &str) -> String {
    let Some(rest) = uri.strip_prefix("file://") else {
        return uri.to_string();
    };
    // `file://host/path`: the host is dropped, `file:///c:/x` keeps the drive.
    let path = match rest.find('/') {
        Some(at) => &rest[at..],
        None => "/",
    };
    let decoded = percent_decode(path);
    let bytes = decoded.as_bytes();
    if bytes.len() > 2 && bytes[0] == b'/' && bytes[2] == b':' && bytes[1].is_ascii_alphabetic() {
        decoded[1..].to_string()
    } else {
        decoded
    }
}

/// The `file:` URI of a path (made absolute against the working directory).
pub fn name_to_uri(name: &str) -> String {
    if name.contains("://") || name.starts_with("untitled:") {
        return name.to_string();
    }
    let mut path = name.to_string();
    let drive = path.as_bytes().get(1) == Some(&b':');
    if !path.starts_with('/') && !drive {
        if let Ok(dir) = std::env::current_dir() {
            let dir = dir.to_string_lossy().replace('\\', "/");
            path = format!("{}/{}", dir.trim_end_matches('/'), path.trim_start_matches("./"));
        }
    }
    let mut out = String::from("file://");
    if !path.starts_with('/') {
        out.push('/');
    }
    for byte in path.bytes() {
        match byte {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'/' | b'-' | b'_' | b'.' | b'~' | b':' => out.push(byte as char),
            _ => out.push_str(&format!("%{byte:02X}")),
        }
    }
    out
}

fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut at = 0;
    while at < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[at] == b'%' && at + 2 < bytes.len() {
            if let (Some(hi), Some(lo)) = (hex(bytes[at + 1]), hex(bytes[at + 2])) {
                out.push((hi * 16 + lo) as u8);
                at += 3;
                continue;
            }
        }
        out.push(bytes[at]);
        at += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_utf16_units_or_utf8_bytes() {
        let text = "a°b\n// µ𝄞x\n";
        let utf16 = LineIndex::new(text, Encoding::Utf16);
        let utf8 = LineIndex::new(text, Encoding::Utf8);
        let x = text.find('x').expect("x is there");
        assert_eq!(utf16.position(text, x), Position::new(1, 6));
        assert_eq!(utf8.position(text, x), Position::new(1, 9));
        assert_eq!(utf16.offset(text, Position::new(1, 6)), x);
        assert_eq!(utf8.offset(text, Position::new(1, 9)), x);
        assert_eq!(utf16.offset(text, Position::new(0, 99)), 4, "past the end of a line");
        assert_eq!(utf16.offset(text, Position::new(9, 0)), text.len());
        assert_eq!(utf16.position(text, 2), Position::new(0, 1), "inside `°`");
    }

    #[test]
    fn file_uris_round_trip_with_spaces() {
        assert_eq!(uri_to_name("file:///tmp/a%20b/c.skill"), "/tmp/a b/c.skill");
        assert_eq!(name_to_uri("/tmp/a b/c.skill"), "file:///tmp/a%20b/c.skill");
        assert_eq!(uri_to_name("file:///c%3A/x.skill"), "c:/x.skill");
        assert_eq!(uri_to_name("untitled:Untitled-1"), "untitled:Untitled-1");
    }
}

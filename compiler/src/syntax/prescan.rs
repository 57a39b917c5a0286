//! The pass over the text before pest sees it: nesting too deep for pest's recursion, and
//! characters the grammar cannot take, named by code point and by what they look like.
//!
//! pest parses by recursive descent, so every rule that contains itself costs stack per level:
//! brackets (`(`, `[`, `{`: guards in parentheses, lists, records, calls, blocks, grouped
//! arithmetic), `not` (`not not G`) and minus (`- -x`). All are counted here in one measure, the
//! depth, so that pest never recurses more than [`crate::MAX_NESTING`] levels of them, and
//! neither does anything after it (the AST lowering, the checker, the formatter, a `Debug` dump
//! of the tree): each opening bracket adds one level, each `not` or `-` one more until the
//! operand it applies to ends. (A chain `a + b + c` is flat in the tree: it costs no depth.)
//!
//! Outside strings and comments the grammar is ASCII: names, keywords, numbers, units and
//! whitespace. Any other character there is a syntax error at that character, so it is named
//! here with what to write instead (a no-break space, a Cyrillic `а`, a fullwidth `１`); a NUL is
//! refused anywhere, since no text holds one (a UTF-16 file has one after every ASCII letter).

use crate::diag::{Code, Diag};
use crate::source::Span;

/// At most this many characters are named; a file with more is most likely not a template.
const MAX_CHARACTER_DIAGS: usize = 20;

/// The problems of `text` that must stop it from reaching pest: a nesting too deep (the first
/// place only) or the characters the grammar cannot take. Empty when pest may parse it.
pub(super) fn prescan(text: &str, file: usize) -> Vec<Diag> {
    let mut scan = Scan {
        file,
        diags: Vec::new(),
        depth: 0,
        open: Vec::new(),
        nots: 0,
    };
    let bytes = text.as_bytes();
    let mut at = 0;
    while at < bytes.len() {
        let byte = bytes[at];
        match byte {
            b'/' if bytes.get(at + 1) == Some(&b'/') => {
                // A comment: only a NUL and the bidirectional controls matter in it.
                let end = text[at..].find('\n').map_or(text.len(), |n| at + n);
                scan.nuls(&text[at..end], at);
                at = end;
                continue;
            }
            b'"' => {
                let end = string_end(bytes, at);
                scan.nuls(&text[at..end], at);
                scan.nots = 0;
                at = end;
                continue;
            }
            b'(' | b'[' | b'{' => {
                // The `not`s before a bracket negate what it holds: they end with it.
                let weight = 1 + scan.nots;
                scan.nots = 0;
                scan.depth += weight;
                scan.open.push(weight);
                if scan.depth > crate::MAX_NESTING {
                    return vec![scan.too_deep(Span::new(at, at + 1), weight > 1)];
                }
            }
            b')' | b']' | b'}' => {
                scan.depth -= scan.open.pop().unwrap_or(0);
                scan.nots = 0;
            }
            b if b.is_ascii_alphanumeric() || b == b'_' => {
                let end = at
                    + bytes[at..]
                        .iter()
                        .take_while(|b| b.is_ascii_alphanumeric() || **b == b'_')
                        .count();
                if &text[at..end] == "not" {
                    scan.nots += 1;
                    if scan.depth + scan.nots > crate::MAX_NESTING {
                        return vec![scan.too_deep(Span::new(at, end), true)];
                    }
                } else {
                    scan.nots = 0;
                }
                at = end;
                continue;
            }
            b'-' if bytes.get(at + 1) != Some(&b'>') => {
                // A minus may negate (`- -x`, `-(a + b)`): pest recurses once per `-` in a
                // row, as per `not`. A binary minus (`a - b`) ends with the operand after it.
                scan.nots += 1;
                if scan.depth + scan.nots > crate::MAX_NESTING {
                    return vec![scan.too_deep(Span::new(at, at + 1), true)];
                }
            }
            b' ' | b'\t' | b'\r' | b'\n' => {}
            b if b.is_ascii_graphic() => scan.nots = 0,
            _ => {
                // Not printable ASCII: a control character, or the first byte of a character
                // beyond ASCII (`text` is UTF-8, so `at` is a character boundary here).
                let c = text[at..].chars().next().expect("a character starts here");
                scan.character(c, at);
                at += c.len_utf8();
                continue;
            }
        }
        at += 1;
    }
    scan.diags.truncate(MAX_CHARACTER_DIAGS);
    scan.diags
}

/// The state of the scan: what it found, and how deep it is.
struct Scan {
    file: usize,
    diags: Vec<Diag>,
    /// The depth so far: the weights of the open brackets.
    depth: usize,
    /// Each open bracket's weight: one, and one for each `not` right before it.
    open: Vec<usize>,
    /// The `not`s in a row just read, whose operand has not ended yet.
    nots: usize,
}

impl Scan {
    fn too_deep(&self, span: Span, with_nots: bool) -> Diag {
        let limit = crate::MAX_NESTING;
        if with_nots {
            Diag::new(
                Code::TooDeep,
                self.file,
                span,
                format!("`not`s, minus signs and brackets nested more than {limit} deep"),
                "nesting exceeds the limit here",
            )
            .help("`not not G` is `G` and `- -x` is `x`: drop them in pairs, and the brackets nothing needs")
        } else {
            Diag::new(
                Code::TooDeep,
                self.file,
                span,
                format!("brackets nested more than {limit} deep"),
                "nesting exceeds the limit here",
            )
            .help("no template needs this depth; look for unbalanced brackets")
        }
    }

    /// Names every NUL and every bidirectional control (see [`bidi_name`]) of a string or
    /// comment starting at `offset`.
    fn nuls(&mut self, text: &str, offset: usize) {
        for (at, c) in text.char_indices() {
            if c == '\0' || bidi_name(c).is_some() {
                self.character(c, offset + at);
            }
        }
    }

    /// Names a character the grammar cannot take, at byte `at`.
    fn character(&mut self, c: char, at: usize) {
        if self.diags.len() >= MAX_CHARACTER_DIAGS {
            return;
        }
        let (message, label, help) = describe(c);
        let diag = Diag::new(
            Code::UnexpectedCharacter,
            self.file,
            Span::new(at, at + c.len_utf8()),
            message,
            label,
        )
        .maybe_help(help);
        self.diags.push(diag);
    }
}

/// The Unicode name of a bidirectional embedding, override or isolate control: in a comment or
/// a string it makes an editor show the code around it in another order than it compiles in.
fn bidi_name(c: char) -> Option<&'static str> {
    Some(match c {
        '\u{202A}' => "LEFT-TO-RIGHT EMBEDDING",
        '\u{202B}' => "RIGHT-TO-LEFT EMBEDDING",
        '\u{202C}' => "POP DIRECTIONAL FORMATTING",
        '\u{202D}' => "LEFT-TO-RIGHT OVERRIDE",
        '\u{202E}' => "RIGHT-TO-LEFT OVERRIDE",
        '\u{2066}' => "LEFT-TO-RIGHT ISOLATE",
        '\u{2067}' => "RIGHT-TO-LEFT ISOLATE",
        '\u{2068}' => "FIRST STRONG ISOLATE",
        '\u{2069}' => "POP DIRECTIONAL ISOLATE",
        _ => return None,
    })
}

/// One past the closing quote of the string that opens at `start` (or the end of its line: a
/// string does not span lines), with the grammar's escapes (`\` and any character).
fn string_end(bytes: &[u8], start: usize) -> usize {
    let mut at = start + 1;
    while at < bytes.len() {
        match bytes[at] {
            b'"' => return at + 1,
            b'\n' => return at,
            b'\\' => at += 2,
            _ => at += 1,
        }
    }
    bytes.len()
}

/// What a character is and what to do about it: the message, the label, and a help line.
fn describe(c: char) -> (String, String, Option<String>) {
    let code = format!("U+{:04X}", u32::from(c));
    if c == '\0' {
        return (
            format!("{code} NUL is a zero byte, not text; delete it"),
            "a zero byte".to_string(),
            Some(
                "a file with a zero byte after every letter is UTF-16: save it as UTF-8 (most editors offer the \
                 encoding on save)"
                    .to_string(),
            ),
        );
    }
    if let Some(name) = bidi_name(c) {
        return (
            format!("{code} {name} changes the order in which the text is shown; delete it"),
            "a bidirectional control".to_string(),
            Some(
                "an editor shows the text around it reordered, so the file reads differently from how it compiles \
                 (CVE-2021-42574); rustc refuses these too"
                    .to_string(),
            ),
        );
    }
    if let Some(name) = space_name(c) {
        return (
            format!("{code} {name} looks like a space; replace it with a plain space"),
            "not a plain space".to_string(),
            None,
        );
    }
    if let Some(name) = invisible_name(c) {
        return (
            format!("{code} {name} is invisible; delete it"),
            "an invisible character".to_string(),
            Some("it often comes with text pasted from a web page or a word processor".to_string()),
        );
    }
    if let Some((name, ascii)) = lookalike(c) {
        let kind = if ascii.chars().all(|a| a.is_ascii_alphabetic()) {
            "the Latin letter"
        } else {
            "the ASCII"
        };
        return (
            format!("{code} {name} looks like `{ascii}`; replace it with {kind} `{ascii}`"),
            format!("not `{ascii}`"),
            None,
        );
    }
    if c == '\u{B0}' {
        return (
            format!("{code} DEGREE SIGN cannot write a unit; write `deg`"),
            "not a unit".to_string(),
            Some("angles are written `90 deg` or `1.57 rad`".to_string()),
        );
    }
    if c.is_control() {
        return (
            format!("{code} is a control character, not text; delete it"),
            "a control character".to_string(),
            None,
        );
    }
    (
        format!("{code} `{c}` cannot appear outside strings and comments"),
        "not ASCII".to_string(),
        Some("names, keywords, numbers and units are ASCII; other text belongs in a comment or a string".to_string()),
    )
}

/// The name of a character that looks like a space or a line break.
fn space_name(c: char) -> Option<&'static str> {
    Some(match c {
        '\u{85}' => "NEXT LINE",
        '\u{A0}' => "NO-BREAK SPACE",
        '\u{1680}' => "OGHAM SPACE MARK",
        '\u{2000}' => "EN QUAD",
        '\u{2001}' => "EM QUAD",
        '\u{2002}' => "EN SPACE",
        '\u{2003}' => "EM SPACE",
        '\u{2004}' => "THREE-PER-EM SPACE",
        '\u{2005}' => "FOUR-PER-EM SPACE",
        '\u{2006}' => "SIX-PER-EM SPACE",
        '\u{2007}' => "FIGURE SPACE",
        '\u{2008}' => "PUNCTUATION SPACE",
        '\u{2009}' => "THIN SPACE",
        '\u{200A}' => "HAIR SPACE",
        '\u{2028}' => "LINE SEPARATOR",
        '\u{2029}' => "PARAGRAPH SEPARATOR",
        '\u{202F}' => "NARROW NO-BREAK SPACE",
        '\u{205F}' => "MEDIUM MATHEMATICAL SPACE",
        '\u{3000}' => "IDEOGRAPHIC SPACE",
        _ => return None,
    })
}

/// The name of a character that shows as nothing (or changes the direction text shows in).
fn invisible_name(c: char) -> Option<&'static str> {
    Some(match c {
        '\u{AD}' => "SOFT HYPHEN",
        '\u{200B}' => "ZERO WIDTH SPACE",
        '\u{200C}' => "ZERO WIDTH NON-JOINER",
        '\u{200D}' => "ZERO WIDTH JOINER",
        '\u{200E}' => "LEFT-TO-RIGHT MARK",
        '\u{200F}' => "RIGHT-TO-LEFT MARK",
        '\u{202A}' => "LEFT-TO-RIGHT EMBEDDING",
        '\u{202B}' => "RIGHT-TO-LEFT EMBEDDING",
        '\u{202C}' => "POP DIRECTIONAL FORMATTING",
        '\u{202D}' => "LEFT-TO-RIGHT OVERRIDE",
        '\u{202E}' => "RIGHT-TO-LEFT OVERRIDE",
        '\u{2060}' => "WORD JOINER",
        '\u{2066}' => "LEFT-TO-RIGHT ISOLATE",
        '\u{2067}' => "RIGHT-TO-LEFT ISOLATE",
        '\u{2068}' => "FIRST STRONG ISOLATE",
        '\u{2069}' => "POP DIRECTIONAL ISOLATE",
        // At the very start it is a byte order mark, which `SourceFile::new` drops.
        '\u{FEFF}' => "ZERO WIDTH NO-BREAK SPACE (a byte order mark)",
        _ => return None,
    })
}

/// The name of a character that looks like ASCII, and that ASCII.
fn lookalike(c: char) -> Option<(String, &'static str)> {
    if let Some(found) = fullwidth(c) {
        return Some(found);
    }
    let (name, ascii) = match c {
        // Cyrillic.
        '\u{410}' => ("CYRILLIC CAPITAL LETTER A", "A"),
        '\u{412}' => ("CYRILLIC CAPITAL LETTER VE", "B"),
        '\u{415}' => ("CYRILLIC CAPITAL LETTER IE", "E"),
        '\u{41A}' => ("CYRILLIC CAPITAL LETTER KA", "K"),
        '\u{41C}' => ("CYRILLIC CAPITAL LETTER EM", "M"),
        '\u{41D}' => ("CYRILLIC CAPITAL LETTER EN", "H"),
        '\u{41E}' => ("CYRILLIC CAPITAL LETTER O", "O"),
        '\u{420}' => ("CYRILLIC CAPITAL LETTER ER", "P"),
        '\u{421}' => ("CYRILLIC CAPITAL LETTER ES", "C"),
        '\u{422}' => ("CYRILLIC CAPITAL LETTER TE", "T"),
        '\u{425}' => ("CYRILLIC CAPITAL LETTER HA", "X"),
        '\u{430}' => ("CYRILLIC SMALL LETTER A", "a"),
        '\u{435}' => ("CYRILLIC SMALL LETTER IE", "e"),
        '\u{43E}' => ("CYRILLIC SMALL LETTER O", "o"),
        '\u{440}' => ("CYRILLIC SMALL LETTER ER", "p"),
        '\u{441}' => ("CYRILLIC SMALL LETTER ES", "c"),
        '\u{443}' => ("CYRILLIC SMALL LETTER U", "y"),
        '\u{445}' => ("CYRILLIC SMALL LETTER HA", "x"),
        '\u{455}' => ("CYRILLIC SMALL LETTER DZE", "s"),
        '\u{456}' => ("CYRILLIC SMALL LETTER BYELORUSSIAN-UKRAINIAN I", "i"),
        '\u{458}' => ("CYRILLIC SMALL LETTER JE", "j"),
        // Greek.
        '\u{391}' => ("GREEK CAPITAL LETTER ALPHA", "A"),
        '\u{392}' => ("GREEK CAPITAL LETTER BETA", "B"),
        '\u{395}' => ("GREEK CAPITAL LETTER EPSILON", "E"),
        '\u{396}' => ("GREEK CAPITAL LETTER ZETA", "Z"),
        '\u{397}' => ("GREEK CAPITAL LETTER ETA", "H"),
        '\u{399}' => ("GREEK CAPITAL LETTER IOTA", "I"),
        '\u{39A}' => ("GREEK CAPITAL LETTER KAPPA", "K"),
        '\u{39C}' => ("GREEK CAPITAL LETTER MU", "M"),
        '\u{39D}' => ("GREEK CAPITAL LETTER NU", "N"),
        '\u{39F}' => ("GREEK CAPITAL LETTER OMICRON", "O"),
        '\u{3A1}' => ("GREEK CAPITAL LETTER RHO", "P"),
        '\u{3A4}' => ("GREEK CAPITAL LETTER TAU", "T"),
        '\u{3A5}' => ("GREEK CAPITAL LETTER UPSILON", "Y"),
        '\u{3A7}' => ("GREEK CAPITAL LETTER CHI", "X"),
        '\u{3BD}' => ("GREEK SMALL LETTER NU", "v"),
        '\u{3BF}' => ("GREEK SMALL LETTER OMICRON", "o"),
        // Punctuation word processors put in.
        '\u{2010}' => ("HYPHEN", "-"),
        '\u{2011}' => ("NON-BREAKING HYPHEN", "-"),
        '\u{2012}' => ("FIGURE DASH", "-"),
        '\u{2013}' => ("EN DASH", "-"),
        '\u{2014}' => ("EM DASH", "-"),
        '\u{2212}' => ("MINUS SIGN", "-"),
        '\u{2018}' => ("LEFT SINGLE QUOTATION MARK", "'"),
        '\u{2019}' => ("RIGHT SINGLE QUOTATION MARK", "'"),
        '\u{201C}' => ("LEFT DOUBLE QUOTATION MARK", "\""),
        '\u{201D}' => ("RIGHT DOUBLE QUOTATION MARK", "\""),
        '\u{201E}' => ("DOUBLE LOW-9 QUOTATION MARK", "\""),
        '\u{2044}' => ("FRACTION SLASH", "/"),
        '\u{2215}' => ("DIVISION SLASH", "/"),
        '\u{2192}' => ("RIGHTWARDS ARROW", "->"),
        '\u{2264}' => ("LESS-THAN OR EQUAL TO", "<="),
        '\u{2265}' => ("GREATER-THAN OR EQUAL TO", ">="),
        '\u{3002}' => ("IDEOGRAPHIC FULL STOP", "."),
        _ => return None,
    };
    Some((name.to_string(), ascii))
}

/// The fullwidth forms U+FF01 to U+FF5E of printable ASCII (`１`, `ａ`, `（`): name and ASCII.
fn fullwidth(c: char) -> Option<(String, &'static str)> {
    const ASCII: &str =
        "!\"#$%&'()*+,-./0123456789:;<=>?@ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_`abcdefghijklmnopqrstuvwxyz{|}~";
    const PUNCTUATION: [&str; 32] = [
        "EXCLAMATION MARK",
        "QUOTATION MARK",
        "NUMBER SIGN",
        "DOLLAR SIGN",
        "PERCENT SIGN",
        "AMPERSAND",
        "APOSTROPHE",
        "LEFT PARENTHESIS",
        "RIGHT PARENTHESIS",
        "ASTERISK",
        "PLUS SIGN",
        "COMMA",
        "HYPHEN-MINUS",
        "FULL STOP",
        "SOLIDUS",
        "COLON",
        "SEMICOLON",
        "LESS-THAN SIGN",
        "EQUALS SIGN",
        "GREATER-THAN SIGN",
        "QUESTION MARK",
        "COMMERCIAL AT",
        "LEFT SQUARE BRACKET",
        "REVERSE SOLIDUS",
        "RIGHT SQUARE BRACKET",
        "CIRCUMFLEX ACCENT",
        "LOW LINE",
        "GRAVE ACCENT",
        "LEFT CURLY BRACKET",
        "VERTICAL LINE",
        "RIGHT CURLY BRACKET",
        "TILDE",
    ];
    const DIGITS: [&str; 10] = [
        "ZERO", "ONE", "TWO", "THREE", "FOUR", "FIVE", "SIX", "SEVEN", "EIGHT", "NINE",
    ];
    let index = u32::from(c).checked_sub(0xFF01).filter(|index| *index < 94)? as usize;
    let ascii = &ASCII[index..index + 1];
    let byte = ascii.as_bytes()[0];
    let name = if byte.is_ascii_digit() {
        format!("FULLWIDTH DIGIT {}", DIGITS[usize::from(byte - b'0')])
    } else if byte.is_ascii_uppercase() {
        format!("FULLWIDTH LATIN CAPITAL LETTER {ascii}")
    } else if byte.is_ascii_lowercase() {
        format!("FULLWIDTH LATIN SMALL LETTER {}", ascii.to_ascii_uppercase())
    } else {
        // The punctuation, in ASCII order, skipping digits and letters.
        let rank = ASCII[..index].bytes().filter(|b| !b.is_ascii_alphanumeric()).count();
        format!("FULLWIDTH {}", PUNCTUATION[rank])
    };
    Some((name, ascii))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn messages(text: &str) -> Vec<(String, Span)> {
        prescan(text, 0)
            .into_iter()
            .map(|diag| (diag.message.clone(), diag.span()))
            .collect()
    }

    #[test]
    fn lookalikes_are_named_by_code_point_and_what_they_look_like() {
        let cases = [
            (
                "a\u{A0}b",
                "U+00A0 NO-BREAK SPACE looks like a space; replace it with a plain space",
            ),
            ("a\u{200B}b", "U+200B ZERO WIDTH SPACE is invisible; delete it"),
            (
                "st\u{430}te",
                "U+0430 CYRILLIC SMALL LETTER A looks like `a`; replace it with the Latin letter `a`",
            ),
            (
                "timeout \u{FF11} s",
                "U+FF11 FULLWIDTH DIGIT ONE looks like `1`; replace it with the ASCII `1`",
            ),
            ("a\0b", "U+0000 NUL is a zero byte, not text; delete it"),
            (
                "// x \u{202E} y",
                "U+202E RIGHT-TO-LEFT OVERRIDE changes the order in which the text is shown; delete it",
            ),
            (
                "f\u{FF08}",
                "U+FF08 FULLWIDTH LEFT PARENTHESIS looks like `(`; replace it with the ASCII `(`",
            ),
            (
                "\u{FF5A}",
                "U+FF5A FULLWIDTH LATIN SMALL LETTER Z looks like `z`; replace it with the Latin letter `z`",
            ),
            (
                "\u{FF5E}",
                "U+FF5E FULLWIDTH TILDE looks like `~`; replace it with the ASCII `~`",
            ),
            (
                "\u{2192}",
                "U+2192 RIGHTWARDS ARROW looks like `->`; replace it with the ASCII `->`",
            ),
            ("\u{1}", "U+0001 is a control character, not text; delete it"),
            ("\u{E9}", "U+00E9 `é` cannot appear outside strings and comments"),
        ];
        for (text, expected) in cases {
            let found = messages(text);
            assert_eq!(found.len(), 1, "{text:?}: {found:?}");
            assert_eq!(found[0].0, expected);
        }
        // Located at the character, whatever its length in bytes.
        assert_eq!(messages("on\u{A0}x")[0].1, Span::new(2, 4));
        assert_eq!(messages("ab\u{3000}")[0].1, Span::new(2, 5));
    }

    #[test]
    fn strings_and_comments_may_hold_any_character_but_nul() {
        assert!(messages("\"dém\u{A0}o.csv\" // naïve\u{200B}\n").is_empty());
        assert_eq!(messages("\"a\0\"").len(), 1);
        assert_eq!(messages("// a\0").len(), 1);
        // An escaped quote does not end the string; a line break does.
        assert!(messages("\"a\\\"\u{A0}\"").is_empty());
        assert_eq!(messages("\"a\n\u{A0}").len(), 1);
    }

    #[test]
    fn a_file_full_of_strange_characters_gets_a_bounded_number_of_diagnostics() {
        let text = "s\0".repeat(10_000);
        assert_eq!(messages(&text).len(), MAX_CHARACTER_DIAGS);
    }

    #[test]
    fn nots_count_towards_the_depth_until_their_operand_ends() {
        let at_bound = format!("{}x", "not ".repeat(crate::MAX_NESTING));
        assert!(messages(&at_bound).is_empty());
        let over = format!("{}x", "not ".repeat(crate::MAX_NESTING + 1));
        let found = messages(&over);
        assert_eq!(found.len(), 1);
        let at = 4 * crate::MAX_NESTING;
        assert_eq!(found[0].1, Span::new(at, at + 3), "at the first `not` too many");
        // Each `not (` is two levels; `not` after an operand starts again.
        let half = crate::MAX_NESTING / 2;
        let alternating = format!("{}x{}", "not (".repeat(half), ")".repeat(half));
        assert!(messages(&alternating).is_empty());
        let alternating = format!("{}x{}", "not (".repeat(half + 1), ")".repeat(half + 1));
        assert_eq!(messages(&alternating).len(), 1);
        let many = "not a and ".repeat(10_000);
        assert!(messages(&many).is_empty());
        // `not` inside a word, a string or a comment is not a `not`.
        let words = format!(
            "{} \"{}\" // {}",
            "knot nothing ".repeat(100),
            "not ".repeat(100),
            "not ".repeat(100)
        );
        assert!(messages(&words).is_empty());
    }
}

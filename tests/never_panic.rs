//! Malformed input of any kind gets diagnostics, never a panic or a stack overflow.

use proptest::prelude::*;
use skill_compiler::{Code, SourceFile};

const STDLIB: [&str; 4] = [
    include_str!("../stdlib-skills/touch.skill"),
    include_str!("../stdlib-skills/press.skill"),
    include_str!("../stdlib-skills/slide.skill"),
    include_str!("../stdlib-skills/contour.skill"),
];

/// Tokens that make mutations likely to stay near the grammar and reach the checker.
const TOKENS: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    "[",
    "]",
    ",",
    ":",
    "->",
    ".",
    "segment 1",
    "segment 9",
    "0",
    "-1",
    "5 N",
    "3 mm",
    "1e400",
    "and",
    "or",
    "not",
    "state x",
    "terminal",
    "on",
    "move",
    "control force z",
    "position all",
    "in base",
    "ü",
    "\"",
    "//",
    "///",
    "\n",
    " ",
    "N/m",
    "deg/s",
    "motion_done",
    "timeout",
    "force(",
    "extend along",
    "expect 0",
];

fn compile_bytes(bytes: Vec<u8>) {
    match skill_kit::frontend::decode("fuzz.skill", bytes) {
        Ok(source) => {
            let compilation = skill_compiler::compile(source, &mut |_| {
                Err(skill_compiler::LoadError {
                    reason: "no imports in this test".to_string(),
                })
            });
            // A program and errors never come together.
            assert_eq!(compilation.program.is_some(), !compilation.has_errors());
            // Every diagnostic points inside its file.
            for diag in &compilation.diags {
                let len = compilation.files[diag.file].text.len();
                for label in &diag.labels {
                    assert!(label.span.start <= label.span.end && label.span.end <= len, "{diag:?}");
                }
            }
            let _ = skill_kit::render::all_plain(&compilation, 80);
        }
        Err(invalid) => assert_eq!(invalid.1.code, Code::InvalidUtf8),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        compile_bytes(bytes);
    }

    #[test]
    fn mutated_stdlib_never_panics(
        which in 0..STDLIB.len(),
        edits in proptest::collection::vec((any::<prop::sample::Index>(), 0..4usize, any::<prop::sample::Index>(), 0..40usize), 1..8),
    ) {
        let mut text = STDLIB[which].as_bytes().to_vec();
        for (at, kind, token, len) in edits {
            let pos = at.index(text.len() + 1);
            match kind {
                0 => { let end = (pos + len).min(text.len()); text.drain(pos..end); }
                1 => { let token = TOKENS[token.index(TOKENS.len())]; text.splice(pos..pos, token.bytes()); }
                2 => { let end = (pos + len).min(text.len()); let copy = text[pos..end].to_vec(); text.splice(pos..pos, copy); }
                _ => { if pos < text.len() { text[pos] = text[pos].wrapping_add(len as u8); } }
            }
        }
        compile_bytes(text);
    }
}

#[test]
fn deep_nesting_is_refused_not_overflowed() {
    for open in ["(", "[", "{"] {
        let text = format!("skill s {{ learn {{ motion m = dmp({}) }} }}", open.repeat(100_000));
        let compilation = skill_compiler::compile_str("deep.skill", &text);
        assert_eq!(compilation.diags.len(), 1);
        assert_eq!(compilation.diags[0].code, Code::TooDeep);
    }
}

#[test]
fn ten_megabytes_of_anything_get_one_diagnostic() {
    let text = "skill s { state a { on motion_done -> a } }\n".repeat(10 * 1024 * 1024 / 44);
    let compilation = skill_compiler::compile_str("huge.skill", &text);
    assert_eq!(compilation.diags.len(), 1);
    assert_eq!(compilation.diags[0].code, Code::FileTooLarge);
}

#[test]
fn binary_input_is_reported_as_invalid_utf8_at_the_first_bad_byte() {
    let mut bytes = b"skill s {".to_vec();
    bytes.extend([0u8, 0xff, 0xfe, 0x00, 0x80]);
    let Err(invalid) = skill_kit::frontend::decode("bin.skill", bytes) else {
        panic!("binary is not UTF-8")
    };
    let (source, diag) = *invalid;
    assert_eq!(diag.code, Code::InvalidUtf8);
    assert_eq!(source.line_col(diag.span().start), (1, 11));
}

#[test]
fn long_but_valid_files_still_check() {
    // Many small skills in one file: every one is checked, and names clash across them only
    // when they really do.
    let mut text = String::new();
    for index in 0..300 {
        text.push_str(&format!(
            "skill s{index} {{\n learn {{\n motion p = dmp(segment 1)\n }}\n state a {{\n move p\n on motion_done -> d\n }}\n terminal d: success\n}}\n"
        ));
    }
    let compilation = skill_compiler::compile(SourceFile::new("many.skill", text), &mut |_| {
        Err(skill_compiler::LoadError {
            reason: "none".to_string(),
        })
    });
    assert!(compilation.diags.is_empty());
    assert_eq!(compilation.program.expect("compiles").skills.len(), 300);
}

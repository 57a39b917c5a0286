//! Fuzz target: any bytes through parse, check and lower must give diagnostics, never a panic.
//! Run with `cargo +nightly fuzz run parse_and_check` from the repository root.
//!
//! Random bytes seldom nest deeply, so each input is also run as a nesting of one of the
//! grammar's recursive rules (`not`, parentheses, `for` in parentheses, lists, calls, records),
//! up to well past `MAX_NESTING`, around the input's text: near the bound the whole pipeline
//! must still run, and past it give the located `too_deep` error, on any stack.
#![no_main]

/// Compiles `text`, renders the IR when there is one, and formats what parsed.
fn run(text: &str) {
    let compilation = skill_compiler::compile_str("fuzz.skill", text);
    assert_eq!(compilation.program.is_some(), !compilation.has_errors());
    if let Some(program) = &compilation.program {
        let _ = skill_compiler::graph::render(program, skill_compiler::graph::GraphFormat::Dot);
    }
    let _ = skill_compiler::fmt::format(&compilation.files[0], &compilation.ast);
    let _ = format!("{:?}", compilation.ast);
}

/// The input nested: its first byte picks the rule, its second how deep (0 to 2 × 255 levels),
/// the rest (as text) stands in the middle.
fn nested(data: &[u8]) -> Option<String> {
    let (&rule, rest) = data.split_first()?;
    let (&depth, rest) = rest.split_first()?;
    let middle = std::str::from_utf8(rest).ok()?;
    let levels = usize::from(depth) * 2;
    let (open, close, in_guard) = match rule % 6 {
        0 => ("not ", "", true),
        1 => ("(", ")", true),
        2 => ("not (", ")", true),
        3 => ("(", " for 1 ms)", true),
        4 => ("[", "]", false),
        _ => ("f(", ")", false),
    };
    let inner = format!("{}{middle}{}", open.repeat(levels), close.repeat(levels));
    Some(if in_guard {
        format!(
            "skill s {{ learn {{ motion p = dmp(segment 1) }} state a {{ move p on {inner} -> d on timeout 1 s -> d }} terminal d: success }}"
        )
    } else {
        format!("skill s {{ learn {{ motion p = dmp({inner}) }} }}")
    })
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        run(text);
    }
    if let Some(text) = nested(data) {
        let compilation = skill_compiler::compile_str("nested.skill", &text);
        let levels = usize::from(data[1]) * 2;
        if levels > skill_compiler::MAX_NESTING {
            assert!(
                compilation.diags.iter().any(|diag| diag.code == skill_compiler::Code::TooDeep),
                "{levels} levels are refused as too deep"
            );
        }
        run(&text);
    }
});

//! Fuzz target: any bytes through parse, check and lower must give diagnostics, never a panic.
//! Run with `cargo +nightly fuzz run parse_and_check` from the repository root.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let compilation = skill_compiler::compile_str("fuzz.skill", text);
        assert_eq!(compilation.program.is_some(), !compilation.has_errors());
        if let Some(program) = &compilation.program {
            let _ = skill_compiler::graph::render(program, skill_compiler::graph::GraphFormat::Dot);
        }
        let _ = skill_compiler::fmt::format(&compilation.files[0], &compilation.ast);
    }
});

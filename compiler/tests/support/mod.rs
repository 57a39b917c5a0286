//! Templates and compilation helpers shared by the `front_end_*.rs` tests.

// Each test crate that includes this module uses a part of it.
#![allow(dead_code)]

use skill_compiler::{Code, Compilation, LoadError};

/// The codes a template reports.
pub(crate) fn codes_of(text: &str) -> Vec<Code> {
    skill_compiler::compile_str("f.skill", text)
        .diags
        .iter()
        .map(|diag| diag.code)
        .collect()
}

/// A skill whose second state is `body`, with a motion `q`, a frame `c`, a force `f` and a
/// threshold `t`.
pub(crate) fn with_state(body: &str) -> String {
    format!(
        "skill s {{ learn {{ segments = max_force frame c = force_aligned(at: end(segment 1)) motion p = dmp(segment 1) motion q = dmp(segment 2) force f = force_at(end(segment 1), along: c.z) threshold t = 2 N }}\n\
         state a {{ move p on force(c.z) >= t -> b on force(c.z) >= f -> b on timeout 9 s -> d }}\n\
         state b {{ {body} }}\n terminal d: success }}\n"
    )
}

/// `text` (importing nothing) compiled with `--param` settings `params`.
pub(crate) fn compile_with(text: &str, params: &[&str]) -> Compilation {
    let params: Vec<String> = params.iter().map(|p| p.to_string()).collect();
    skill_compiler::compile_with_params(skill_compiler::SourceFile::new("s.skill", text), &params, &mut |_| {
        Err(LoadError {
            reason: "no imports here".into(),
        })
    })
}

//! Deep nesting of every recursive rule (`not`, parentheses, `for` in parentheses, lists,
//! records, calls, minus signs, grouped arithmetic): refused past `MAX_NESTING` with a located error before pest recurses, and
//! parsed, checked, formatted and printed at the bound on a 2 MiB stack (an unoptimised build's
//! pest takes about 55 KiB for each level of parentheses in a guard).

use skill_compiler::{Code, Compilation, SourceFile, MAX_NESTING};
use std::time::{Duration, Instant};

/// Runs `job` on a thread with `stack` bytes of stack; a stack overflow aborts the test binary,
/// which fails the test as loudly as an assertion.
fn on_stack<T: Send + 'static>(stack: usize, job: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(stack)
        .spawn(job)
        .expect("a thread starts")
        .join()
        .expect("the job does not panic")
}

/// The stack of a main thread on most systems (8 MiB), and the smallest common one (2 MiB:
/// Rust's spawned threads, some shells' limits).
const STACKS: [usize; 2] = [8 << 20, 2 << 20];

/// The nesting a guard starts at in [`with_guard`]: inside `skill {` and `state {`.
const GUARD_DEPTH: usize = 2;

/// A skill whose one active state leaves on `guard`.
fn with_guard(guard: &str) -> String {
    format!(
        "skill s {{\n    learn {{\n        motion p = dmp(segment 1)\n    }}\n\n    state a {{\n        move p from current\n        on {guard} -> d\n        on timeout 5 s -> d\n    }}\n\n    terminal d: success\n}}\n"
    )
}

/// Guards nested `levels` deep by each recursive rule of the guard grammar.
fn nested_guards(levels: usize) -> Vec<(&'static str, String)> {
    vec![
        ("not", format!("{}motion_done", "not ".repeat(levels))),
        (
            "parentheses",
            format!("{}motion_done{}", "(".repeat(levels), ")".repeat(levels)),
        ),
        (
            "not and parentheses",
            format!("{}motion_done{}", "not (".repeat(levels / 2), ")".repeat(levels / 2)),
        ),
        (
            "held in parentheses",
            format!("{}motion_done{}", "(".repeat(levels), " for 1 ms)".repeat(levels)),
        ),
        (
            "and, or in parentheses",
            format!(
                "{}motion_done{}",
                "(motion_done or not ".repeat(levels / 2),
                " and dwell 1 s)".repeat(levels / 2)
            ),
        ),
    ]
}

/// Values nested `levels` deep by each recursive rule of the value grammar, in a learn block
/// (three deep: `skill {`, `learn {`, `dmp(`).
fn nested_values(levels: usize) -> Vec<(&'static str, String)> {
    let learn = |value: String| format!("skill s {{ learn {{ motion p = dmp({value}) }} }}\n");
    vec![
        ("lists", learn(format!("{}1{}", "[".repeat(levels), "]".repeat(levels)))),
        (
            "calls",
            learn(format!("{}1{}", "f(".repeat(levels), ")".repeat(levels))),
        ),
        (
            "records",
            learn(format!("{}1{}", "{ a: ".repeat(levels), " }".repeat(levels))),
        ),
        // `- - - 1 mm`: each minus before the last negates (the last is the literal's sign).
        ("minus signs", learn(format!("{}1 mm", "- ".repeat(levels)))),
        (
            "grouped arithmetic",
            learn(format!("{}1 mm{}", "(".repeat(levels), " * 2)".repeat(levels))),
        ),
    ]
}

/// Parses, compiles, formats and prints (as `skillc dump --stage ast` does) `text`; the
/// compilation and how long it all took.
fn every_walk(text: String) -> (Compilation, Duration) {
    let start = Instant::now();
    let compilation = skill_compiler::compile_str("deep.skill", &text);
    let source = SourceFile::new("deep.skill", text.as_str());
    let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
    let formatted = skill_compiler::fmt::format(&source, &ast);
    let dump = format!("{ast:#?}");
    assert!(dump.starts_with("File {"), "the dump printed the tree");
    assert_eq!(diags.is_empty(), !formatted.is_empty(), "formatted exactly what parsed");
    if let Some(program) = &compilation.program {
        let _ = skill_compiler::graph::render(program, skill_compiler::graph::GraphFormat::Dot);
    }
    (compilation, start.elapsed())
}

fn codes(compilation: &Compilation) -> Vec<Code> {
    compilation.diags.iter().map(|diag| diag.code).collect()
}

#[test]
fn five_thousand_nots_are_refused_at_the_first_not_too_deep() {
    let text = with_guard(&format!("{}motion_done", "not ".repeat(5000)));
    for stack in STACKS {
        let text = text.clone();
        let (compilation, took) = on_stack(stack, move || every_walk(text));
        assert_eq!(codes(&compilation), [Code::TooDeep]);
        let diag = &compilation.diags[0];
        assert_eq!(
            diag.message,
            format!("`not`s, minus signs and brackets nested more than {MAX_NESTING} deep")
        );
        let first = compilation.files[0].text.find("not ").expect("a not");
        let at = first + 4 * (MAX_NESTING - GUARD_DEPTH);
        assert_eq!(
            diag.span(),
            skill_compiler::Span::new(at, at + 3),
            "the first `not` past the bound"
        );
        // A hang guard, not a benchmark: it takes milliseconds.
        assert!(took < Duration::from_secs(30), "took {took:?}");
    }
}

#[test]
fn every_recursive_rule_is_refused_one_past_the_bound() {
    let mut cases: Vec<(&str, String)> = nested_guards(10_000)
        .into_iter()
        .map(|(what, guard)| (what, with_guard(&guard)))
        .collect();
    cases.extend(nested_values(10_000));
    for (what, text) in cases {
        let (compilation, took) = on_stack(2 << 20, move || every_walk(text));
        assert_eq!(codes(&compilation), [Code::TooDeep], "{what}");
        assert!(took < Duration::from_secs(30), "{what} took {took:?}");
    }
}

#[test]
fn nesting_at_the_bound_is_parsed_checked_formatted_and_printed_on_a_small_stack() {
    let mut cases: Vec<(&str, String)> = nested_guards(MAX_NESTING - GUARD_DEPTH)
        .into_iter()
        .map(|(what, guard)| (what, with_guard(&guard)))
        .collect();
    cases.extend(nested_values(MAX_NESTING - 3));
    for (what, text) in cases {
        let (compilation, took) = on_stack(2 << 20, move || every_walk(text));
        assert!(
            !codes(&compilation).contains(&Code::TooDeep),
            "{what} at the bound is not too deep: {:?}",
            compilation.diags
        );
        assert!(took < Duration::from_secs(30), "{what} took {took:?}");
    }
    // The guards are legal templates: they compile, and format to text that parses again.
    for (what, guard) in nested_guards(MAX_NESTING - GUARD_DEPTH) {
        let text = with_guard(&guard);
        let compilation = skill_compiler::compile_str("deep.skill", &text);
        assert!(compilation.program.is_some(), "{what}: {:?}", compilation.diags);
        let formatted = skill_compiler::fmt::format(&compilation.files[0], &compilation.ast);
        let again = skill_compiler::compile_str("deep.skill", &formatted);
        assert!(again.program.is_some(), "{what} formatted: {:?}", again.diags);
    }
}

#[test]
fn a_parameter_setting_is_bounded_like_a_file() {
    let deep = format!("x={}1{}", "[".repeat(200), "]".repeat(200));
    let refused = on_stack(2 << 20, move || skill_compiler::syntax::parse_param_setting(&deep));
    assert_eq!(
        refused.map(|_| ()),
        Err(format!("brackets nested more than {MAX_NESTING} deep"))
    );
}

#[test]
fn a_long_sum_costs_no_depth() {
    // 100 000 terms in one chain: flat in the tree, so parsing, checking, formatting, printing
    // and dropping it stay within a small stack, and the sum is the value checked.
    let terms = 100_000;
    let sum = vec!["1 ms"; terms].join(" + ");
    let text = format!(
        "skill s {{\n    param t = {sum}\n    learn {{\n        segments = max_force\n        motion p = dmp(segment 1)\n    }}\n\n    state a {{\n        move p\n        on dwell t -> d\n    }}\n\n    terminal d: success\n}}\n"
    );
    assert!(text.len() < skill_compiler::MAX_SOURCE_BYTES);
    let (compilation, took) = on_stack(2 << 20, move || every_walk(text));
    assert!(compilation.program.is_some(), "{:?}", compilation.diags);
    let program = compilation.program.as_ref().expect("compiled");
    let param = &program.skills[0].params[0];
    assert!(
        (param.value_si - terms as f64 * 1e-3).abs() < 1e-9,
        "{}",
        param.value_si
    );
    assert!(took < Duration::from_secs(30), "took {took:?}");
}

//! End-to-end tests of the front end on the source text in and out: what the formatter prints
//! (comments, limits, arithmetic, holds), and byte order marks, invalid UTF-8, NULs and the columns
//! that diagnostics name.

mod support;

use serde_json::Value;
use skill_compiler::Code;
use support::with_state;

#[test]
fn formatting_keeps_every_comment() {
    let text = "// head\nskill s { learn { motion p = dmp(segment 1) // trailing\n }\n// before state\nstate a { move p // after move\n on motion_done -> d }\n terminal d: success // end\n}\n// tail\n";
    let source = skill_compiler::SourceFile::new("c.skill", text);
    let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
    assert!(diags.is_empty());
    let formatted = skill_compiler::fmt::format(&source, &ast);
    for comment in [
        "// head",
        "// trailing",
        "// before state",
        "// after move",
        "// end",
        "// tail",
    ] {
        assert_eq!(
            formatted.matches(comment).count(),
            1,
            "`{comment}` kept once in:\n{formatted}"
        );
    }
    assert!(
        formatted.contains("move p from current  // after move"),
        "trailing comments stay on their line:\n{formatted}"
    );
}

/// `text` parses without a problem, formats to exactly `expected`, and that compiles cleanly.
fn formats_to(text: &str, expected: &str) -> skill_compiler::Compilation {
    let source = skill_compiler::SourceFile::new("f.skill", text);
    let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
    assert!(diags.is_empty(), "{diags:?}");
    let formatted = skill_compiler::fmt::format(&source, &ast);
    assert_eq!(formatted, expected);
    let compiled = skill_compiler::compile_str("f.skill", &formatted);
    assert!(compiled.diags.is_empty(), "{:?}", compiled.diags);
    compiled
}

#[test]
fn formatting_prints_limits_approaches_and_step_limits() {
    let text = "skill s { learn { motion p = dmp(segment 1) threshold t = 2 N }\nlimits { /// Why.\n force: 40 N, speed : 100 mm/s tracking: inf }\nstate a { move p approach within 5 cm at 10 mm/s on force(tool.z) >= t -> d on timeout 5 s -> d }\n terminal d: success }\ntask k { step x = s(demo: \"d.csv\", limits: {force: 30 N speed: 5 cm/s}) }\n";
    let expected = r#"skill s {
    learn {
        motion p = dmp(segment 1)
        threshold t = 2 N
    }

    limits {
        /// Why.
        force: 40 N
        speed: 100 mm/s
        tracking: inf
    }

    state a {
        move p from current
        approach within 5 cm at 10 mm/s
        on force(tool.z) >= t -> d
        on timeout 5 s -> d
    }

    terminal d: success
}

task k {
    step x = s(demo: "d.csv", limits: { force: 30 N, speed: 5 cm/s })
}
"#;
    formats_to(text, expected);
}

#[test]
fn formatting_prints_arithmetic_with_the_parentheses_its_meaning_needs() {
    let text = "skill s { param a = (1 cm+2 mm)*3\n param b = 10 mm-(2 mm-1 mm)\n param n = 12/(2*3)\nlearn { motion p = dmp(segment 1) }\nlimits { force: -(-40 N) speed: ((2 * 50 mm/s)) }\nstate x { move p approach within a at 10 mm/s+(5 mm/s) on moved>=b+a/n -> d on force(tool.z) >= 2 * 1 N -> d on timeout -(-5 s)*n -> d }\n terminal d: success }\n";
    let expected = r#"skill s {
    param a = (1 cm + 2 mm) * 3
    param b = 10 mm - (2 mm - 1 mm)
    param n = 12 / (2 * 3)

    learn {
        motion p = dmp(segment 1)
    }

    limits {
        force: -(-40 N)
        speed: 2 * 50 mm/s
    }

    state x {
        move p from current
        approach within a at 10 mm/s + 5 mm/s
        on moved >= b + a / n -> d
        on force(tool.z) >= 2 * 1 N -> d
        on timeout -(-5 s) * n -> d
    }

    terminal d: success
}
"#;
    let compiled = formats_to(text, expected);
    let program = compiled.program.expect("compiles");
    let skill = &program.skills[0];
    let param = |name: &str| skill.params.iter().find(|p| p.name == name).expect("declared").value_si;
    assert!((param("a") - 0.036).abs() < 1e-12, "{}", param("a"));
    assert!((param("b") - 0.009).abs() < 1e-12);
    assert!((param("n") - 2.0).abs() < 1e-12);
    let ir: Value = serde_json::to_value(skill).expect("the IR serialises");
    // The folded values are what runs: 15 mm/s, 9 mm + 36 mm / 2 = 27 mm, 2 N, 10 s.
    let at = |pointer: &str| ir.pointer(pointer).and_then(Value::as_f64).unwrap_or(f64::NAN);
    assert!((at("/states/0/kind/approach/speed_mps") - 0.015).abs() < 1e-12, "{ir}");
    assert!((at("/transitions/0/guard/value_m") - 0.027).abs() < 1e-12, "{ir}");
    assert!((at("/transitions/1/guard/rhs/value") - 2.0).abs() < 1e-12, "{ir}");
    assert!((at("/transitions/2/guard/duration_s") - 10.0).abs() < 1e-12, "{ir}");
    assert!((at("/limits/1/value_si") - 0.1).abs() < 1e-12, "{ir}");
}

#[test]
fn formatting_prints_lift_offs_and_held_guards_with_the_fewest_parentheses() {
    let text = "skill s { learn { segments = max_force frame c = force_aligned(at: end(segment 1)) motion p = dmp(segment 1) motion q = dmp(segment 2) threshold t = 2 N }\nstate a { move p on force(c.z)>=t for 20 ms -> b on ( motion_done and force(c.z) < t ) for 50 ms or timeout 5 s -> d }\nstate b { move q lift off 2 cm at 10 mm/s on (not (motion_done for 10 ms)) for 100 ms -> e on timeout 5 s -> d }\nstate e { move q\n lift  off 0 mm on not force(c.z) >= t for 1 s -> d on timeout 5 s -> d }\n terminal d: success }\n";
    let expected = r#"skill s {
    learn {
        segments = max_force
        frame c = force_aligned(at: end(segment 1))
        motion p = dmp(segment 1)
        motion q = dmp(segment 2)
        threshold t = 2 N
    }

    state a {
        move p from current
        on force(c.z) >= t for 20 ms -> b
        on (motion_done and force(c.z) < t) for 50 ms or timeout 5 s -> d
    }

    state b {
        move q from current
        lift off 2 cm at 10 mm/s
        on not (motion_done for 10 ms) for 100 ms -> e
        on timeout 5 s -> d
    }

    state e {
        move q from current
        lift off 0 mm
        on not force(c.z) >= t for 1 s -> d
        on timeout 5 s -> d
    }

    terminal d: success
}
"#;
    let compiled = formats_to(text, expected);
    let skill = &compiled.program.expect("compiles").skills[0];
    // `for` binds tighter than `or` and looser than `not`.
    let guard = |index: usize| &skill.transitions[index].guard;
    assert!(matches!(guard(1), skill_ir::Guard::Or { any } if matches!(any[0], skill_ir::Guard::Held { .. })));
    let skill_ir::Guard::Held {
        guard: inner,
        duration_s,
    } = guard(4)
    else {
        panic!("`not A for D` is held: {:?}", guard(4))
    };
    assert_eq!(*duration_s, 1.0);
    assert!(matches!(**inner, skill_ir::Guard::Not { .. }));
    let skill_ir::StateKind::Active(e) = &skill.states[2].kind else {
        panic!("an active state")
    };
    assert_eq!(
        e.lift_off,
        Some(skill_ir::LiftOffSpec {
            distance_m: 0.0,
            speed_mps: 0.0
        })
    );
}

#[test]
fn a_byte_order_mark_is_dropped_and_positions_are_those_the_editor_shows() {
    // `nope` is at column 26 of the first line as an editor shows it (the mark is hidden).
    let text = "\u{feff}skill s { state a { move nope on motion_done -> d } terminal d: success }\n";
    let compilation = skill_compiler::compile_str("bom.skill", text);
    let diag = compilation.diags.first().expect("the unknown motion is reported");
    assert_eq!(diag.code, Code::UnknownName);
    let source = &compilation.files[0];
    assert!(!source.text.starts_with('\u{feff}'), "the mark is not part of the text");
    assert_eq!(source.slice(diag.span()), "nope");
    assert_eq!(source.line_col(diag.span().start), (1, 26));
    assert_eq!(
        text.find("nope"),
        Some(diag.span().start + '\u{feff}'.len_utf8()),
        "offsets count from after the mark"
    );
    let rendered = skill_compiler::render::all_plain(&compilation, 80);
    assert!(rendered.contains("bom.skill:1:26"), "{rendered}");
    // Formatting writes the text without the mark.
    let (ast, _) = skill_compiler::syntax::parse(source, 0);
    assert!(skill_compiler::fmt::format(source, &ast).starts_with("skill s {"));
}

#[test]
fn invalid_utf8_after_a_byte_order_mark_is_located_in_the_text_without_it() {
    let mut bytes = "\u{feff}skill s {".as_bytes().to_vec();
    bytes.push(0xff);
    let Err(invalid) = skill_compiler::decode("bin.skill", bytes) else {
        panic!("0xff is not UTF-8")
    };
    let (source, diag) = *invalid;
    assert_eq!(diag.code, Code::InvalidUtf8);
    assert_eq!(diag.span().start, "skill s {".len());
    assert_eq!(source.line_col(diag.span().start), (1, 10));
}

#[test]
fn a_nul_is_named_anywhere_and_a_utf16_file_is_recognised() {
    let with_nul = with_state("move q on motion_done -> d // a\0b");
    let compilation = skill_compiler::compile_str("nul.skill", &with_nul);
    assert_eq!(
        compilation.diags.iter().map(|d| d.code).collect::<Vec<_>>(),
        [Code::UnexpectedCharacter]
    );
    let diag = &compilation.diags[0];
    assert_eq!(diag.message, "U+0000 NUL is a zero byte, not text; delete it");
    assert_eq!(compilation.files[0].slice(diag.span()), "\0");
    // UTF-16 without a byte order mark is valid UTF-8 with a NUL after every ASCII letter.
    let utf16: String = "skill s { }".chars().flat_map(|c| [c, '\0']).collect();
    let compilation = skill_compiler::compile_str("utf16.skill", &utf16);
    assert!(compilation.diags.len() <= 20, "a bounded number of diagnostics");
    assert!(
        compilation.diags[0]
            .help
            .as_deref()
            .is_some_and(|help| help.contains("UTF-16")),
        "{:?}",
        compilation.diags[0]
    );
}

#[test]
fn rendered_columns_count_characters_like_the_json_and_the_editor() {
    let text = "skill s {\n    learn {\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m from current\n        on timeout \"é µ ° 🤖\" or dwell 5 mm -> d\n    }\n    terminal d: success\n}\n";
    let compilation = skill_compiler::compile_str("col.skill", text);
    let diag = compilation
        .diags
        .iter()
        .find(|d| d.code == Code::UnitMismatch)
        .expect("`dwell 5 mm` is refused");
    let (line, column) = compilation.files[0].line_col(diag.span().start);
    // Eight spaces, `on timeout "é µ ° 🤖" or dwell ` is 38 characters (44 bytes).
    assert_eq!((line, column), (7, 39));
    let rendered = skill_compiler::render::human(diag, &compilation, false, 100);
    assert!(rendered.contains("col.skill:7:39]"), "{rendered}");
}

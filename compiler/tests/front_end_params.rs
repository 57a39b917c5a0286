//! End-to-end tests of the front end on parameters and arithmetic: `--param` settings, defaults
//! that use other parameters, vector parameters, offsets from captures, and broken arithmetic.

mod support;

use serde_json::Value;
use skill_compiler::{Code, Compilation};
use support::compile_with;

/// A skill whose dwell is computed from its parameter: `hold - 3 s`.
const COMPUTED_DWELL: &str = "skill s {\n    param hold = 5 s\n    param passes = 2\n    learn {\n        segments = max_force\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m\n        repeat passes\n        on dwell hold - 3 s -> d\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";

fn with_params(params: &[&str]) -> Compilation {
    compile_with(COMPUTED_DWELL, params)
}

#[test]
fn arithmetic_in_a_param_flag_is_folded_and_an_error_it_causes_names_the_flag() {
    let compiled = with_params(&["hold=2 * 2 s + 500 ms"]);
    let program = compiled.program.unwrap_or_else(|| panic!("{:?}", compiled.diags));
    assert!((program.skills[0].params[0].value_si - 4.5).abs() < 1e-12);
    // 1 s - 3 s is a negative dwell: an error of the flag's, not of the file's defaults.
    let compiled = with_params(&["hold=1s"]);
    assert!(compiled.program.is_none());
    let diag = compiled
        .diags
        .iter()
        .find(|d| d.code == Code::OutOfRange)
        .expect("negative dwell");
    assert_eq!(diag.message, "the dwell time is negative");
    let help = diag.help.as_deref().unwrap_or("");
    assert!(help.contains("with `--param hold=1s` from the command line"), "{help}");
    // A count set to a duration names what it is.
    let compiled = with_params(&["passes=10"]);
    assert!(compiled.program.is_some(), "{:?}", compiled.diags);
    let text = COMPUTED_DWELL.replace("param passes = 2", "param passes = 10 s");
    let compiled = skill_compiler::compile_str("s.skill", &text);
    let diag = compiled
        .diags
        .iter()
        .find(|d| d.code == Code::BadArgument)
        .expect("not a count");
    assert_eq!(
        diag.message,
        "the repeat count must be a whole number, not a duration (`10 s`)"
    );
}

#[test]
fn an_offset_from_a_capture_is_three_lengths_in_a_known_frame() {
    let skill = |offset: &str| {
        format!(
            "skill s {{\n    learn {{\n        motion m = dmp(segment 1)\n    }}\n    state a {{\n        capture found\n        move m from current\n        on motion_done -> b\n    }}\n    state b {{\n        move m at found + {offset}\n        on motion_done -> d\n    }}\n    terminal d: success\n}}\n"
        )
    };
    let compiled = skill_compiler::compile_str("s.skill", &skill("[0 mm, 2 * 1 mm, -3 mm] in tool"));
    let program = compiled.program.unwrap_or_else(|| panic!("{:?}", compiled.diags));
    let skill_ir::StateKind::Active(active) = &program.skills[0].states[1].kind else {
        panic!("`b` is active")
    };
    let offset = active.motion_at_offset.as_ref().expect("an offset");
    assert_eq!(offset.frame, skill_ir::FrameRef::Tool);
    assert!((offset.offset_m[1] - 0.002).abs() < 1e-12 && (offset.offset_m[2] + 0.003).abs() < 1e-12);
    for (offset, code) in [
        ("[1 mm, 2 mm]", Code::BadArgument),
        ("[1 mm, 2 mm, 3 N]", Code::UnitMismatch),
        ("[0 mm, 0 mm, 1 mm] in nowhere", Code::UnknownName),
    ] {
        let compiled = skill_compiler::compile_str("s.skill", &skill(offset));
        assert!(compiled.program.is_none(), "{offset}");
        assert!(
            compiled.diags.iter().any(|d| d.code == code),
            "{offset}: {:?}",
            compiled.diags
        );
    }
}

#[test]
fn a_vector_parameter_is_an_offset_a_step_or_flag_may_set() {
    const TEXT: &str = "skill s {\n    /// Where to end, from the found point.\n    param lift = [0 mm, 0 mm, 5 mm]\n    learn {\n        motion m = dmp(segment 1)\n    }\n    state a {\n        capture found\n        move m from current\n        on motion_done -> b\n    }\n    state b {\n        move m at found + lift in tool\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";
    let compile = |params: &[&str]| compile_with(TEXT, params);
    let offset_of = |compiled: &Compilation| {
        let program = compiled
            .program
            .as_ref()
            .unwrap_or_else(|| panic!("{:?}", compiled.diags));
        let skill = &program.skills[0];
        let skill_ir::StateKind::Active(active) = &skill.states[1].kind else {
            panic!("`b` is active")
        };
        let offset = active.motion_at_offset.as_ref().expect("an offset").offset_m;
        (offset, skill.params[0].vector_si)
    };
    let (offset, listed) = offset_of(&compile(&[]));
    assert_eq!(offset, [0.0, 0.0, 0.005]);
    assert_eq!(listed, Some([0.0, 0.0, 0.005]));
    let (offset, _) = offset_of(&compile(&["lift=[1 mm, 2 * 1 mm, 1 cm]"]));
    assert!(
        (offset[1] - 0.002).abs() < 1e-12 && (offset[2] - 0.01).abs() < 1e-12,
        "{offset:?}"
    );
    let refused = compile(&["lift=[1 mm, 2 mm]"]);
    let diag = refused
        .diags
        .iter()
        .find(|d| d.code == Code::UnitMismatch)
        .expect("refused");
    assert!(
        diag.message.contains("is a list of three values, each a length"),
        "{}",
        diag.message
    );
}

#[test]
fn a_moved_since_guard_before_its_capture_is_warned_of() {
    let text = "skill s {\n    learn {\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m from current\n        on moved since found >= 1 cm -> b\n        on motion_done -> b\n    }\n    state b {\n        capture found\n        move m from current\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";
    let compiled = skill_compiler::compile_str("s.skill", text);
    let diag = compiled
        .diags
        .iter()
        .find(|d| d.code == Code::AtBeforeCapture)
        .unwrap_or_else(|| panic!("{:?}", compiled.diags));
    assert_eq!(diag.message, "state `a` can be reached before `found` is captured");
    assert!(diag
        .help
        .as_deref()
        .unwrap_or("")
        .contains("`moved since` is false on that path"));
    assert!(compiled.program.is_some(), "a warning, not an error");
}

/// Broken arithmetic in a default and in a guard, and two legal ones (whose guards the never-fires
/// analysis compares through the arithmetic: `p + 1 mm` after `p` would be shadowed).
#[test]
fn broken_arithmetic_is_an_error_never_a_panic() {
    let values = [
        "1 mm +",
        "+ 1 mm",
        "1 mm + * 2",
        "(1 mm",
        "1 mm)",
        "- - - -",
        "1 mm / 0",
        "1 mm / (1 - 1)",
        "1e308 m * 1e308",
        "-1e308 m - 1e308 m",
        "2 * [1 mm, 2 mm, 3 mm]",
        "\"a\" + 1",
        "1 mm + 1 mm/s",
        "1 / 3 * 3 mm",
        "1 mm //",
        "1 mm -> x",
        "((((((((1 mm))))))))",
        "1 mm * -",
    ];
    for value in values {
        let text = format!(
            "skill s {{\n    param p = {value}\n    learn {{\n        motion m = dmp(segment 1)\n    }}\n    state a {{\n        move m from current\n        on moved >= {value} + 1 mm -> d\n        on moved >= p -> d\n        on timeout 5 s -> d\n    }}\n    terminal d: success\n}}\n"
        );
        let compiled = std::panic::catch_unwind(|| skill_compiler::compile_str("s.skill", &text));
        let compiled = compiled.unwrap_or_else(|_| panic!("`{value}` panicked"));
        let legal = ["1 / 3 * 3 mm", "((((((((1 mm))))))))"].contains(&value);
        assert_eq!(compiled.program.is_some(), legal, "`{value}`: {:?}", compiled.diags);
        if !legal {
            assert!(compiled.has_errors(), "`{value}`: an error, not silence");
        }
        // Whatever parsed formats to text that parses again.
        let source = skill_compiler::SourceFile::new("s.skill", text.as_str());
        let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
        if diags.is_empty() {
            let formatted = skill_compiler::fmt::format(&source, &ast);
            let (_, again) =
                skill_compiler::syntax::parse(&skill_compiler::SourceFile::new("f.skill", formatted.as_str()), 0);
            assert!(again.is_empty(), "`{value}` formatted: {again:?}\n{formatted}");
        }
    }
}

/// A skill whose parameters' defaults use the parameters declared before them.
const DERIVED: &str = "skill s {\n    param hold = 4 s\n    param settle = hold / 4\n    param depth = 12 mm\n    param back = [0 mm, 0 mm, 5 mm]\n    param again = back\n    param rise = -(depth + 3 mm)\n    learn {\n        segments = max_force\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m\n        on moved >= -rise -> d\n        on dwell settle -> d\n        on motion_done -> b\n    }\n    state b {\n        capture found\n        move m at found + again in tool\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";

#[test]
fn a_default_uses_the_parameters_declared_before_it_and_follows_their_settings() {
    let value = |compiled: &Compilation, name: &str| {
        let program = compiled
            .program
            .as_ref()
            .unwrap_or_else(|| panic!("{:?}", compiled.diags));
        let skill = &program.skills[0];
        let param = skill.params.iter().find(|p| p.name == name).expect("declared");
        (param.value_si, param.vector_si)
    };
    let defaults = compile_with(DERIVED, &[]);
    assert!((value(&defaults, "settle").0 - 1.0).abs() < 1e-12);
    assert!((value(&defaults, "rise").0 + 0.015).abs() < 1e-12);
    assert_eq!(value(&defaults, "again").1, Some([0.0, 0.0, 0.005]));
    // `hold` and `back` are used only by other defaults: no "never used" warning for them.
    assert!(
        !defaults.diags.iter().any(|d| d.code == Code::Unused),
        "{:?}",
        defaults.diags
    );
    // Setting the parameter a default uses moves the default with it, unless it is set too.
    let set = compile_with(DERIVED, &["hold=10 s", "depth=2 cm"]);
    assert!((value(&set, "settle").0 - 2.5).abs() < 1e-12);
    assert!((value(&set, "rise").0 + 0.023).abs() < 1e-12);
    let both = compile_with(DERIVED, &["hold=10 s", "settle=1 s"]);
    assert!((value(&both, "settle").0 - 1.0).abs() < 1e-12);
    // The dwell and the guard take the derived values.
    let ir: Value = serde_json::to_value(&set.program.as_ref().expect("compiles").skills[0]).expect("serialises");
    let at = |pointer: &str| ir.pointer(pointer).and_then(Value::as_f64).unwrap_or(f64::NAN);
    assert!((at("/transitions/0/guard/value_m") - 0.023).abs() < 1e-12, "{ir}");
    assert!((at("/transitions/1/guard/duration_s") - 2.5).abs() < 1e-12, "{ir}");
}

#[test]
fn a_default_that_uses_itself_or_a_later_parameter_is_refused_naming_it() {
    for (text, message) in [
        (
            DERIVED.replace("param settle = hold / 4", "param settle = settle / 4"),
            "the default of `settle` uses itself",
        ),
        (
            DERIVED.replace("param settle = hold / 4", "param settle = depth / 1 mm * 1 s"),
            "the default of `settle` uses `depth`, which is declared after it",
        ),
    ] {
        let compiled = compile_with(&text, &[]);
        assert!(compiled.program.is_none());
        let diag = compiled
            .diags
            .iter()
            .find(|d| d.message == message)
            .unwrap_or_else(|| panic!("{message}: {:?}", compiled.diags));
        assert!(
            diag.help.as_deref().unwrap_or("").contains("declared above it"),
            "{diag:?}"
        );
    }
    // A default that uses an earlier parameter refused on its own says nothing more about it.
    let compiled = compile_with(&DERIVED.replace("param hold = 4 s", "param hold = \"4 s\""), &[]);
    assert!(compiled.program.is_none());
    let messages: Vec<&str> = compiled.diags.iter().map(|d| d.message.as_str()).collect();
    assert!(
        messages.iter().any(|m| m.contains("parameter `hold` needs a number")),
        "{messages:?}"
    );
    assert!(!messages.iter().any(|m| m.contains("declared after")), "{messages:?}");
    // A plain number for a length is refused.
    let compiled = compile_with(DERIVED, &["depth=3"]);
    assert!(compiled.program.is_none(), "a plain number for a length is refused");
}

#[test]
fn a_vector_parameter_is_negated_scaled_and_summed_where_an_offset_stands() {
    let text = "skill s {\n    param back = [0 mm, 0 mm, 5 mm]\n    param twice = 2 * -back + [1 mm, 0 mm, 0 mm]\n    learn {\n        segments = max_force\n        motion m = dmp(segment 1)\n    }\n    state a {\n        capture found\n        move m\n        on motion_done -> b\n    }\n    state b {\n        move m at found + -back / 2 in tool\n        on motion_done -> c\n    }\n    state c {\n        move m at found + twice\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";
    let compiled = compile_with(text, &["back=[0 mm, 1 cm, 0 mm]"]);
    let program = compiled.program.unwrap_or_else(|| panic!("{:?}", compiled.diags));
    let ir: Value = serde_json::to_value(&program.skills[0]).expect("serialises");
    let offset = |state: usize| -> Vec<f64> {
        let pointer = format!("/states/{state}/kind/motion_at_offset/offset_m");
        let items = ir
            .pointer(&pointer)
            .and_then(Value::as_array)
            .unwrap_or_else(|| panic!("{ir}"));
        items.iter().map(|v| v.as_f64().unwrap_or(f64::NAN)).collect()
    };
    // `2 in tool`: a number before `in` is no quantity of unit "in".
    assert_eq!(offset(1), [0.0, -0.005, 0.0]);
    // The derived default follows the setting: 2 · -[0, 10, 0] mm + [1, 0, 0] mm.
    assert_eq!(offset(2), [0.001, -0.02, 0.0]);
    // A list plus a length is refused, naming both.
    let compiled = compile_with(&text.replace("+ twice", "+ twice + 2 mm"), &[]);
    let diag = compiled
        .diags
        .iter()
        .find(|d| d.code == Code::BadArithmetic)
        .unwrap_or_else(|| panic!("{:?}", compiled.diags));
    assert_eq!(diag.message, "adds a list of 3 values and a length");
}

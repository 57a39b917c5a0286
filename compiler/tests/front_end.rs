//! End-to-end tests of the front end: the corpus, IR and diagnostic snapshots, and the formatter.
//!
//! The corpus is `tests/corpus/ok` and `tests/corpus/err/{syntax,check,lint}` (by the phase of
//! the code each file declares); the stdlib and example templates at the workspace root are
//! compiled too. Files are compiled under the names `skillc` shows for them when run from the
//! workspace root (`stdlib-skills/press.skill`), except that the corpus is named relative to
//! this crate and an error file without its phase directory (`tests/corpus/err/unused.skill`):
//! where a file is filed is not part of what its diagnostics say.

use serde_json::Value;
use skill_compiler::{Code, Compilation, LoadError, Severity};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// This crate's directory.
fn crate_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The workspace root, where the stdlib and the examples live.
fn workspace_root() -> PathBuf {
    crate_dir().join("..")
}

/// A file to compile: where it is, and the name it is compiled under.
struct Case {
    path: PathBuf,
    name: String,
}

impl Case {
    /// The directory names of this case's directory stand for (`tests/corpus/err` for an
    /// error file, the file's own directory otherwise).
    fn shown_dir(&self) -> &str {
        self.name.rsplit_once('/').map_or("", |(dir, _)| dir)
    }

    /// Reads a file by the name a compilation gives it: names in this case's shown
    /// directory are read from its real one, all others from the workspace root.
    fn read(&self, name: &str) -> std::io::Result<Vec<u8>> {
        let real_dir = self.path.parent().expect("a file has a directory");
        match name
            .strip_prefix(self.shown_dir())
            .and_then(|rest| rest.strip_prefix('/'))
        {
            Some(rest) if !self.shown_dir().is_empty() => std::fs::read(real_dir.join(rest)),
            _ => std::fs::read(workspace_root().join(name)),
        }
    }

    /// Compiles text under this case's name, reading imports the way `skillc` does.
    fn compile_bytes(&self, bytes: Vec<u8>) -> Compilation {
        let mut load = |import: &str| -> Result<String, LoadError> {
            let bytes = self.read(import).map_err(|err| LoadError {
                reason: err.to_string().to_lowercase(),
            })?;
            String::from_utf8(bytes).map_err(|_| LoadError {
                reason: "not valid UTF-8 text".to_string(),
            })
        };
        skill_compiler::compile_bytes(&self.name, bytes, &[], &mut load)
    }

    /// Compiles the file the way `skillc` does.
    fn compile(&self) -> Compilation {
        self.compile_bytes(std::fs::read(&self.path).expect("corpus files are readable"))
    }

    /// The file's name without `.skill`.
    fn stem(&self) -> String {
        self.path.file_stem().expect("file name").to_string_lossy().into_owned()
    }

    /// The name of the IR snapshot of a file that compiles: `ir__DIR__FILE`.
    fn ir_snapshot(&self) -> String {
        let dir = self.path.parent().and_then(Path::file_name).expect("parent dir");
        format!("ir__{}__{}", dir.to_string_lossy(), self.stem())
    }

    /// The name of the diagnostics snapshot of an error file: `diag__FILE`.
    fn diag_snapshot(&self) -> String {
        format!("diag__{}", self.stem())
    }
}

/// The `.skill` files of a directory, sorted.
fn skill_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|err| panic!("cannot list {}: {err}", dir.display()))
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "skill"))
        .collect();
    files.sort();
    files
}

/// The files of `dir` (relative to `base`), named relative to `base`.
fn cases_in(base: &Path, dir: &str) -> Vec<Case> {
    skill_files(&base.join(dir))
        .into_iter()
        .map(|path| {
            let file = path.file_name().expect("file name").to_string_lossy().into_owned();
            Case {
                name: format!("{dir}/{file}"),
                path,
            }
        })
        .collect()
}

/// The templates that must compile cleanly: the ok corpus, the stdlib and the examples.
fn ok_cases() -> Vec<Case> {
    let mut cases = cases_in(crate_dir(), "tests/corpus/ok");
    cases.extend(cases_in(&workspace_root(), "stdlib-skills"));
    cases.extend(cases_in(&workspace_root(), "examples/tasks"));
    cases
}

/// The phases of the diagnostic codes, each a directory of the error corpus.
const PHASES: [&str; 3] = ["syntax", "check", "lint"];

/// The error corpus, every phase, named without the phase directory.
fn err_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for phase in PHASES {
        for mut case in cases_in(crate_dir(), &format!("tests/corpus/err/{phase}")) {
            case.name = format!("tests/corpus/err/{}.skill", case.stem());
            cases.push(case);
        }
    }
    cases.sort_by(|a, b| a.name.cmp(&b.name));
    cases
}

/// The code an `err` corpus file declares on its first line: `// code: skill::check::x`.
fn declared_code(path: &Path) -> String {
    let bytes = std::fs::read(path).expect("corpus file is readable");
    let first_line = bytes.split(|b| *b == b'\n').next().unwrap_or_default();
    let first_line = String::from_utf8_lossy(first_line);
    first_line
        .strip_prefix("// code: ")
        .unwrap_or_else(|| panic!("{} must start with `// code: ...`", path.display()))
        .trim()
        .to_string()
}

#[test]
fn ok_corpus_compiles_without_diagnostics_and_matches_ir_snapshots() {
    let cases = ok_cases();
    assert!(cases.len() >= 8, "the ok corpus, stdlib and examples are all found");
    for case in cases {
        let path = &case.path;
        let compilation = case.compile();
        let rendered = skill_compiler::render::all_plain(&compilation, 80);
        assert!(
            compilation.diags.is_empty(),
            "{} has diagnostics:\n{rendered}",
            path.display()
        );
        let program = compilation.program.expect("no diagnostics means a program");
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false }, {
            insta::assert_yaml_snapshot!(case.ir_snapshot(), program);
        });
    }
}

#[test]
fn err_corpus_reports_the_declared_code_and_matches_diagnostic_snapshots() {
    for case in err_cases() {
        let path = &case.path;
        let compilation = case.compile();
        let code = declared_code(path);
        let phase = path.parent().and_then(Path::file_name).expect("phase directory");
        assert_eq!(
            code.split("::").nth(1),
            phase.to_str(),
            "{} belongs in the directory of its code's phase",
            path.display()
        );
        let codes: BTreeSet<&str> = compilation.diags.iter().map(|d| d.code.as_str()).collect();
        assert!(
            codes.contains(code.as_str()),
            "{} should report {code}, reported {codes:?}",
            path.display()
        );
        let severity = Code::ALL.iter().find(|c| c.as_str() == code).map(|c| c.severity());
        if severity == Some(Severity::Error) {
            assert!(
                compilation.program.is_none(),
                "{}: an error must withhold the IR",
                path.display()
            );
        }
        let source = String::from_utf8_lossy(&std::fs::read(path).expect("readable")).into_owned();
        let rendered = skill_compiler::render::all_plain(&compilation, 80);
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false }, {
            insta::assert_snapshot!(case.diag_snapshot(), format!("{source}\n----- diagnostics -----\n{rendered}"));
        });
    }
}

/// Codes whose trigger cannot be a small checked-in file; each has its own test below.
const GENERATED: &[Code] = &[Code::FileTooLarge];

#[test]
fn every_code_has_a_corpus_file() {
    let declared: BTreeSet<String> = err_cases().iter().map(|case| declared_code(&case.path)).collect();
    for code in Code::ALL {
        if GENERATED.contains(code) {
            continue;
        }
        assert!(
            declared.contains(code.as_str()),
            "no tests/corpus/err file declares `// code: {code}`"
        );
    }
}

#[test]
fn file_too_large_is_refused_before_parsing() {
    let text = "// padding\n".repeat(skill_compiler::MAX_SOURCE_BYTES / 10);
    let compilation = skill_compiler::compile_str("big.skill", &text);
    assert_eq!(compilation.diags.len(), 1);
    assert_eq!(compilation.diags[0].code, Code::FileTooLarge);
}

#[test]
fn all_problems_of_a_file_are_reported_in_one_run() {
    let case = err_cases()
        .into_iter()
        .find(|case| case.stem() == "many_problems")
        .expect("many_problems.skill is in the error corpus");
    let compilation = case.compile();
    let codes: BTreeSet<Code> = compilation.diags.iter().map(|d| d.code).collect();
    assert!(codes.len() >= 8, "expected many distinct problems, got {codes:?}");
}

/// The IR without source positions and guard texts, which formatting may change.
fn without_positions(mut value: Value) -> Value {
    fn strip(value: &mut Value) {
        match value {
            Value::Object(map) => {
                map.remove("span");
                map.remove("guard_text");
                map.remove("source");
                map.values_mut().for_each(strip);
            }
            Value::Array(items) => items.iter_mut().for_each(strip),
            _ => {}
        }
    }
    strip(&mut value);
    value
}

#[test]
fn formatting_is_idempotent_and_preserves_the_ir() {
    for case in ok_cases() {
        let path = &case.path;
        let text = std::fs::read_to_string(path).expect("readable");
        let name = path.to_string_lossy().into_owned();
        let source = skill_compiler::SourceFile::new(name.clone(), text.as_str());
        let (ast, diags) = skill_compiler::syntax::parse(&source, 0);
        assert!(diags.is_empty(), "{name} parses");
        let once = skill_compiler::fmt::format(&source, &ast);
        let source_once = skill_compiler::SourceFile::new(name.clone(), once.as_str());
        let (ast_once, diags) = skill_compiler::syntax::parse(&source_once, 0);
        assert!(diags.is_empty(), "formatted {name} parses:\n{once}");
        let twice = skill_compiler::fmt::format(&source_once, &ast_once);
        assert_eq!(once, twice, "formatting {name} twice changes it");

        // Compile both under the same name so that imports resolve alike.
        let original = case.compile();
        let reformatted = case.compile_bytes(once.into_bytes());
        let ir = |c: &Compilation| {
            without_positions(serde_json::to_value(c.program.as_ref().expect("compiles")).expect("serialises"))
        };
        assert_eq!(ir(&original), ir(&reformatted), "formatting {name} changes its IR");
    }
}

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

#[test]
fn ir_carries_its_version_and_source_positions() {
    let case = Case {
        path: workspace_root().join("stdlib-skills/press.skill"),
        name: "stdlib-skills/press.skill".to_string(),
    };
    let path = &case.path;
    let program = case.compile().program.expect("press compiles");
    assert_eq!(program.ir_version, skill_ir::IR_VERSION);
    let press = program.skill("press").expect("press skill");
    let approach = &press.states[press.initial.index()];
    assert_eq!(approach.name, "approach");
    assert_eq!(approach.span.file, "stdlib-skills/press.skill");
    let text = std::fs::read_to_string(path).expect("readable");
    let at = approach.span.start as usize;
    assert_eq!(
        &text[at..at + "approach".len()],
        "approach",
        "spans point at the state's name"
    );
    // The JSON round-trips.
    let json = serde_json::to_string(&program).expect("serialises");
    let back: skill_ir::Program = serde_json::from_str(&json).expect("deserialises");
    assert_eq!(back, program);
}

#[test]
fn every_snapshot_belongs_to_a_corpus_stdlib_or_example_file() {
    let expected: BTreeSet<String> = ok_cases()
        .iter()
        .map(Case::ir_snapshot)
        .chain(err_cases().iter().map(Case::diag_snapshot))
        .collect();
    let dir = crate_dir().join("tests/snapshots");
    let snapshots = std::fs::read_dir(&dir).unwrap_or_else(|err| panic!("cannot list {}: {err}", dir.display()));
    for entry in snapshots.filter_map(Result::ok) {
        let path = entry.path();
        if path.extension().is_some_and(|ext| ext == "snap") {
            let name = path.file_stem().expect("name").to_string_lossy().into_owned();
            assert!(
                expected.contains(&name),
                "orphaned snapshot {} (no corpus, stdlib or example file of that name)",
                path.display()
            );
        }
    }
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

/// The codes a template reports.
fn codes_of(text: &str) -> Vec<Code> {
    skill_compiler::compile_str("f.skill", text)
        .diags
        .iter()
        .map(|diag| diag.code)
        .collect()
}

/// A skill whose second state is `body`, with a motion `q`, a frame `c`, a force `f` and a
/// threshold `t`.
fn with_state(body: &str) -> String {
    format!(
        "skill s {{ learn {{ segments = max_force frame c = force_aligned(at: end(segment 1)) motion p = dmp(segment 1) motion q = dmp(segment 2) force f = force_at(end(segment 1), along: c.z) threshold t = 2 N }}\n\
         state a {{ move p on force(c.z) >= t -> b on force(c.z) >= f -> b on timeout 9 s -> d }}\n\
         state b {{ {body} }}\n terminal d: success }}\n"
    )
}

#[test]
fn lift_off_values_are_checked_by_dimension_and_sign() {
    let ok = with_state("control force z, position x y rx ry rz in c apply f on timeout 1 s -> e } state e { move q lift off 5 mm at 1 cm/s on motion_done -> d");
    assert_eq!(codes_of(&ok), Vec::<Code>::new());
    let lift = |stmt: &str| {
        with_state(&format!(
            "control force z, position x y rx ry rz in c apply f on timeout 1 s -> e }} state e {{ move q {stmt} on motion_done -> d"
        ))
    };
    assert_eq!(codes_of(&lift("lift off -1 cm at 10 mm/s")), [Code::OutOfRange]);
    assert_eq!(codes_of(&lift("lift off 2 cm at 0 mm/s")), [Code::OutOfRange]);
    assert_eq!(codes_of(&lift("lift off 2 cm")), [Code::BadArgument]);
    assert_eq!(codes_of(&lift("lift off 2 s at 10 mm/s")), [Code::UnitMismatch]);
    assert_eq!(codes_of(&lift("lift off 2 cm at 10 mm")), [Code::UnitMismatch]);
    assert_eq!(
        codes_of(&lift("lift off 2 cm at 10 mm/s lift off 0 mm")),
        [Code::DuplicateStatement]
    );
    // No lift, no lint: `lift off 0 mm` in a state that would not lift anyway.
    assert_eq!(
        codes_of(&with_state(
            "move q lift off 0 mm on force(c.z) >= t -> d on timeout 1 s -> d"
        )),
        Vec::<Code>::new()
    );
    // A force-controlled state never lifts off.
    assert_eq!(
        codes_of(&with_state(
            "move q control force z, position x y rx ry rz in c apply f lift off 1 cm at 5 mm/s on motion_done -> d"
        )),
        [Code::LiftOffIgnored]
    );
}

#[test]
fn hold_times_are_positive_durations_and_not_on_timed_guards() {
    let on = |guard: &str| with_state(&format!("move q on {guard} -> d on timeout 9 s -> d"));
    assert_eq!(codes_of(&on("force(c.z) < t for 100 ms")), Vec::<Code>::new());
    assert_eq!(codes_of(&on("force(c.z) < t for 0 ms")), [Code::OutOfRange]);
    assert_eq!(codes_of(&on("force(c.z) < t for 100")), [Code::MissingUnit]);
    assert_eq!(codes_of(&on("force(c.z) < t for 100 mm")), [Code::UnitMismatch]);
    assert_eq!(codes_of(&on("timeout 1 s for 500 ms")), [Code::ForOnTimedGuard]);
    assert_eq!(
        codes_of(&on("(dwell 1 s or timeout 2 s) for 500 ms")),
        [Code::ForOnTimedGuard]
    );
    // `not dwell 1 s for 50 ms` holds from 50 ms to 1 s: a meaning of its own.
    assert_eq!(codes_of(&on("not dwell 1 s for 50 ms")), Vec::<Code>::new());
    let compiled = skill_compiler::compile_str("f.skill", &on("timeout 1 s for 500 ms"));
    assert_eq!(compiled.diags[0].help.as_deref(), Some("write `timeout 1.5 s` instead"));
}

#[test]
fn a_hold_never_fires_after_an_earlier_timeout_or_beside_a_transition_on_its_guard() {
    let state = |transitions: &str| with_state(&format!("move q {transitions}"));
    assert_eq!(
        codes_of(&state("on timeout 1 s -> d on force(c.z) < t for 2 s -> d")),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t -> d on force(c.z) < t for 100 ms -> d on timeout 1 s -> d"
        )),
        [Code::NeverFires]
    );
    // The other way round the plain guard fires as soon as it holds, before it held 100 ms...
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms -> d on force(c.z) < t -> d on timeout 1 s -> d"
        )),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&state(
            "on (force(c.z) < t and motion_done) for 100 ms -> d on timeout 1 s -> d on force(c.z) < t -> d"
        )),
        [Code::NeverFires]
    );
    // ... unless it only starts a search, which keeps the state, or needs more than the held guard.
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms -> d on force(c.z) < t -> extend along c.z at 1 cm/s, up to 1 cm, then d on timeout 1 s -> d"
        )),
        Vec::<Code>::new()
    );
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms -> d on force(c.z) < t and motion_done -> d on timeout 1 s -> d"
        )),
        Vec::<Code>::new()
    );
    assert_eq!(
        codes_of(&state(
            "on force(c.z) < t for 100 ms and not force(c.z) < t -> d on timeout 1 s -> d"
        )),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&state("on motion_done -> d on force(c.z) >= t for 20 ms -> d")),
        Vec::<Code>::new(),
        "a held force guard still needs contact but has a way out"
    );
    assert_eq!(
        codes_of(&state("on force(c.z) >= t for 20 ms -> d")),
        [Code::ContactWaitWithoutTimeout]
    );
}

#[test]
fn graphs_print_hold_times_on_their_edges() {
    let program = skill_compiler::compile_str(
        "f.skill",
        &with_state("move q on force(c.z) < t for 100 ms -> d on timeout 1 s -> d"),
    )
    .program
    .expect("compiles");
    for format in [
        skill_compiler::graph::GraphFormat::Dot,
        skill_compiler::graph::GraphFormat::Mermaid,
    ] {
        let drawn = skill_compiler::graph::render(&program, format);
        assert!(drawn.contains("force(c.z) < t for 100 ms"), "{drawn}");
    }
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
fn a_hold_longer_than_a_later_timeout_is_refused_also_when_a_parameter_sets_it() {
    let text = with_state("move q on force(c.z) < t for hold -> d on timeout 4 s -> d")
        .replace("skill s {", "skill s { param hold = 2 s");
    let compile = |params: &[&str]| compile_with(&text, params);
    assert_eq!(compile(&[]).diags, Vec::new());
    let refused = compile(&["hold=5s"]);
    assert_eq!(
        refused.diags.iter().map(|d| d.code).collect::<Vec<_>>(),
        [Code::NeverFires]
    );
    assert!(refused.program.is_none());
    // Written the other way round, the hold after the timeout, it was refused already.
    assert_eq!(
        codes_of(&with_state("move q on force(c.z) < t for 5 s -> d on timeout 4 s -> d")),
        [Code::NeverFires]
    );
    assert_eq!(
        codes_of(&with_state("move q on force(c.z) < t for 4 s -> d on timeout 4 s -> d")),
        Vec::<Code>::new(),
        "a hold as long as the timeout fires if the force held from the entry"
    );
    // An `extend` before the timeout keeps the state, so the timeout may not come first.
    assert_eq!(
        codes_of(&with_state(
            "move q on force(c.z) < t for 5 s -> d on motion_done -> extend along c.z at 1 cm/s, up to 1 cm, then d on timeout 4 s -> d"
        )),
        Vec::<Code>::new()
    );
}

#[test]
fn a_zero_timeout_warns_only_where_a_motion_or_force_would_be_cut() {
    assert_eq!(
        codes_of(&with_state("move q on motion_done -> d on timeout 0 s -> d")),
        [Code::EndsOnEntry]
    );
    assert_eq!(
        codes_of(&with_state("move q on motion_done or dwell 0 ms -> d")),
        [Code::EndsOnEntry]
    );
    // A pass-through state, and a search started at once, are meant.
    let pass_through = codes_of(&with_state("capture here on dwell 0 s -> d"));
    assert!(
        !pass_through.is_empty() && !pass_through.contains(&Code::EndsOnEntry),
        "{pass_through:?}"
    );
    assert_eq!(
        codes_of(&with_state(
            "move q on force(c.z) >= t -> d on dwell 0 s -> extend along c.z at 1 cm/s, up to 1 cm, then d on timeout 5 s -> d"
        )),
        Vec::<Code>::new()
    );
}

/// A skill whose dwell is computed from its parameter: `hold - 3 s`.
const COMPUTED_DWELL: &str = "skill s {\n    param hold = 5 s\n    param passes = 2\n    learn {\n        segments = max_force\n        motion m = dmp(segment 1)\n    }\n    state a {\n        move m\n        repeat passes\n        on dwell hold - 3 s -> d\n        on motion_done -> d\n    }\n    terminal d: success\n}\n";

/// `text` (importing nothing) compiled with `--param` settings `params`.
fn compile_with(text: &str, params: &[&str]) -> Compilation {
    let params: Vec<String> = params.iter().map(|p| p.to_string()).collect();
    skill_compiler::compile_with_params(skill_compiler::SourceFile::new("s.skill", text), &params, &mut |_| {
        Err(LoadError {
            reason: "no imports here".into(),
        })
    })
}

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

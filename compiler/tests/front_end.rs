//! End-to-end tests of the front end: the corpus, IR and diagnostic snapshots, and the formatter.

use serde_json::Value;
use skill_compiler::{Code, Compilation, Severity};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Compiles a file the way `skillc` does, naming it relative to the package root so that
/// snapshots do not depend on where the repository is checked out.
fn compile(path: &Path) -> Compilation {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let relative = path.strip_prefix(root).unwrap_or(path);
    skillc::frontend::compile_path(relative).expect("corpus files are readable")
}

fn skill_files(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|err| panic!("cannot list {}: {err}", dir.display()))
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "skill"))
        .collect();
    files.sort();
    files
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
    let mut files = skill_files("tests/corpus/ok");
    files.extend(skill_files("stdlib-skills"));
    files.extend(skill_files("examples/tasks"));
    assert!(files.len() >= 8, "the ok corpus, stdlib and examples are all found");
    for path in files {
        let compilation = compile(&path);
        let rendered = skillc::render::all_plain(&compilation, 80);
        assert!(
            compilation.diags.is_empty(),
            "{} has diagnostics:\n{rendered}",
            path.display()
        );
        let program = compilation.program.expect("no diagnostics means a program");
        let name = path.file_stem().expect("file name").to_string_lossy().into_owned();
        let dir = path
            .parent()
            .and_then(|p| p.file_name())
            .expect("parent dir")
            .to_string_lossy()
            .into_owned();
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false }, {
            insta::assert_yaml_snapshot!(format!("ir__{dir}__{name}"), program);
        });
    }
}

#[test]
fn err_corpus_reports_the_declared_code_and_matches_diagnostic_snapshots() {
    for path in skill_files("tests/corpus/err") {
        let compilation = compile(&path);
        let code = declared_code(&path);
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
        let source = String::from_utf8_lossy(&std::fs::read(&path).expect("readable")).into_owned();
        let rendered = skillc::render::all_plain(&compilation, 80);
        let name = path.file_stem().expect("file name").to_string_lossy().into_owned();
        insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false }, {
            insta::assert_snapshot!(format!("diag__{name}"), format!("{source}\n----- diagnostics -----\n{rendered}"));
        });
    }
}

/// Codes whose trigger cannot be a small checked-in file; each has its own test below.
const GENERATED: &[Code] = &[Code::FileTooLarge];

#[test]
fn every_code_has_a_corpus_file() {
    let declared: BTreeSet<String> = skill_files("tests/corpus/err")
        .iter()
        .map(|p| declared_code(p))
        .collect();
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
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus/err/many_problems.skill");
    let compilation = compile(&path);
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
    let mut files = skill_files("tests/corpus/ok");
    files.extend(skill_files("stdlib-skills"));
    files.extend(skill_files("examples/tasks"));
    for path in files {
        let text = std::fs::read_to_string(&path).expect("readable");
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

        // Compile both in the original directory so that imports resolve alike.
        let original = compile(&path);
        let mut load = |import: &str| {
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(import)).map_err(|err| {
                skill_compiler::LoadError {
                    reason: err.to_string(),
                }
            })
        };
        let relative = path
            .strip_prefix(env!("CARGO_MANIFEST_DIR"))
            .unwrap_or(&path)
            .to_string_lossy()
            .into_owned();
        let reformatted = skill_compiler::compile(skill_compiler::SourceFile::new(relative, once.as_str()), &mut load);
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
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("stdlib-skills/press.skill");
    let program = compile(&path).program.expect("press compiles");
    assert_eq!(program.ir_version, skill_ir::IR_VERSION);
    let press = program.skill("press").expect("press skill");
    let approach = &press.states[press.initial.index()];
    assert_eq!(approach.name, "approach");
    assert_eq!(approach.span.file, "stdlib-skills/press.skill");
    let text = std::fs::read_to_string(&path).expect("readable");
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

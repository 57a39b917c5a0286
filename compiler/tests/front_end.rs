//! End-to-end tests of the front end on the corpus: IR and diagnostic snapshots, and the formatter.
//!
//! The corpus is `tests/corpus/ok` and `tests/corpus/err/{syntax,check,lint}` (by the phase of
//! the code each file declares); the stdlib and example templates at the workspace root are
//! compiled too. Files are compiled under the names `skillc` shows for them when run from the
//! workspace root (`stdlib-skills/press.skill`), except that the corpus is named relative to
//! this crate and an error file without its phase directory (`tests/corpus/err/unused.skill`):
//! where a file is filed is not part of what its diagnostics say.
//!
//! The `front_end_*.rs` files test the front end on templates written in the test: the source
//! text in and out (`front_end_text.rs`), holds, lift-offs and timeouts (`front_end_guards.rs`),
//! and parameters, arithmetic and captures (`front_end_params.rs`).

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

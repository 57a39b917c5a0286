//! The skillc front end: parse `.skill` templates, check them, and lower them to the IR.
//!
//! The stages are [`syntax::parse`] (text to [`ast`]), `check` (names, units, segments,
//! axes, the state machine) and lowering into [`skill_ir::Program`]. All of it is pure: the
//! caller supplies file contents, including those of imported files through a loader, so
//! this crate never touches the file system.

#![warn(missing_docs)]

pub mod ast;
mod check;
pub mod diag;
pub mod fmt;
pub mod graph;
pub mod source;
pub mod syntax;
pub mod units;

pub use check::{DEFAULT_FORCE_BASIS, DEFAULT_GAINS, DEFAULT_MOTION_BASIS, DEFAULT_STIFFNESS};
pub use diag::{Code, Diag, Severity};
pub use source::{SourceFile, Span};

use skill_ir as ir;
use std::collections::HashMap;

/// Largest source file accepted, in bytes. Templates are a few kilobytes; anything near this
/// is the wrong file, and refusing it keeps `check` fast on any input.
pub const MAX_SOURCE_BYTES: usize = 1 << 20;

/// Deepest bracket nesting accepted; keeps pest's recursion far from the stack limit.
pub const MAX_NESTING: usize = 64;

/// The result of compiling one root file and its imports.
#[derive(Debug)]
pub struct Compilation {
    /// Every file read: the root first, then imports in the order they were loaded.
    pub files: Vec<SourceFile>,
    /// Every diagnostic, errors and warnings, in file then position order.
    pub diags: Vec<Diag>,
    /// The parsed root file (empty when it did not parse).
    pub ast: ast::File,
    /// The IR, present exactly when there is no error.
    pub program: Option<ir::Program>,
}

impl Compilation {
    /// Whether any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diags.iter().any(|d| d.severity() == Severity::Error)
    }
}

/// Why an imported file could not be loaded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadError {
    /// A short reason, e.g. "no such file".
    pub reason: String,
}

/// Compiles a file that imports nothing (imports are reported as missing).
pub fn compile_str(name: &str, text: &str) -> Compilation {
    compile(SourceFile::new(name, text), &mut |_path: &str| {
        Err(LoadError {
            reason: "imports are not available here".to_string(),
        })
    })
}

/// Compiles `root`. `load` returns the text of an imported file given its path, which is
/// the import string joined lexically to the importing file's directory.
pub fn compile(root: SourceFile, load: &mut dyn FnMut(&str) -> Result<String, LoadError>) -> Compilation {
    let mut files = vec![root];
    let mut diags = Vec::new();
    let (root_ast, parse_diags) = syntax::parse(&files[0], 0);
    diags.extend(parse_diags);

    // Load imports depth-first, detecting cycles on the current import stack.
    let mut asts: Vec<ast::File> = vec![root_ast];
    let mut order: Vec<usize> = Vec::new();
    let mut stack: Vec<usize> = vec![0];
    load_imports(0, &mut files, &mut asts, &mut diags, &mut stack, &mut order, load);
    order.push(0);

    // Check every file's skills; tasks see all skills loaded.
    let mut skills: Vec<ir::Skill> = Vec::new();
    let mut skill_names: Vec<String> = Vec::new();
    let mut first_definition: HashMap<&str, (usize, Span)> = HashMap::new();
    let mut duplicates: Vec<Diag> = Vec::new();
    let mut to_check: Vec<(usize, &ast::Skill)> = Vec::new();
    for &file in &order {
        for skill in &asts[file].skills {
            match first_definition.get(skill.name.name.as_str()) {
                Some(&(earlier_file, earlier_span)) => {
                    let diag = Diag::new(
                        Code::DuplicateName,
                        file,
                        skill.name.span,
                        format!("skill `{}` is defined twice", skill.name.name),
                        "second definition",
                    );
                    duplicates.push(if earlier_file == file {
                        diag.label(earlier_span, "first defined here")
                            .help("rename one of them")
                    } else {
                        diag.help(format!(
                            "it is also defined in `{}`; rename one of them",
                            files[earlier_file].name
                        ))
                    });
                }
                None => {
                    first_definition.insert(&skill.name.name, (file, skill.name.span));
                    skill_names.push(skill.name.name.clone());
                    to_check.push((file, skill));
                }
            }
        }
    }
    diags.extend(duplicates);
    for (file, skill) in to_check {
        let mut checker = check::Checker::new(file, &files[file], &mut diags);
        if let Some(lowered) = checker.skill(skill) {
            skills.push(lowered);
        }
    }
    let mut tasks = Vec::new();
    {
        let source = files[0].clone();
        let base_dir = parent_dir(&source.name);
        let names: Vec<&str> = skill_names.iter().map(String::as_str).collect();
        let mut checker = check::Checker::new(0, &source, &mut diags);
        for task in &asts[0].tasks {
            if let Some(lowered) = checker.task(task, &names, &base_dir) {
                tasks.push(lowered);
            }
        }
    }

    diags.sort_by_key(|d| (d.file, d.span().start, d.code));
    let has_errors = diags.iter().any(|d| d.severity() == Severity::Error);
    let program = (!has_errors).then(|| ir::Program {
        ir_version: ir::IR_VERSION,
        source: files[0].name.clone(),
        skills,
        tasks,
    });
    let root_ast = asts.swap_remove(0);
    Compilation {
        files,
        diags,
        ast: root_ast,
        program,
    }
}

fn load_imports(
    file: usize,
    files: &mut Vec<SourceFile>,
    asts: &mut Vec<ast::File>,
    diags: &mut Vec<Diag>,
    stack: &mut Vec<usize>,
    order: &mut Vec<usize>,
    load: &mut dyn FnMut(&str) -> Result<String, LoadError>,
) {
    let base_dir = parent_dir(&files[file].name);
    let imports = asts[file].imports.clone();
    for import in imports {
        let path = check::join_path(&base_dir, &import.path);
        if let Some(existing) = files.iter().position(|f| f.name == path) {
            if stack.contains(&existing) {
                let chain: Vec<&str> = stack
                    .iter()
                    .skip_while(|&&f| f != existing)
                    .map(|&f| files[f].name.as_str())
                    .chain(std::iter::once(path.as_str()))
                    .collect();
                diags.push(
                    Diag::new(
                        Code::ImportCycle,
                        file,
                        import.span,
                        format!("import cycle: {}", chain.join(" -> ")),
                        "this import closes the cycle",
                    )
                    .help("move what both files need into a third file that imports neither"),
                );
            }
            continue;
        }
        let text = match load(&path) {
            Ok(text) => text,
            Err(err) => {
                diags.push(
                    Diag::new(
                        Code::MissingImport,
                        file,
                        import.span,
                        format!("cannot import `{path}`: {}", err.reason),
                        "imported here",
                    )
                    .help("import paths are relative to the importing file"),
                );
                continue;
            }
        };
        let index = files.len();
        files.push(SourceFile::new(path, text));
        let (parsed, parse_diags) = syntax::parse(&files[index], index);
        diags.extend(parse_diags);
        asts.push(parsed);
        stack.push(index);
        load_imports(index, files, asts, diags, stack, order, load);
        stack.pop();
        order.push(index);
    }
}

/// The directory part of a `/`-separated path (empty for a bare file name).
fn parent_dir(path: &str) -> String {
    match path.rfind('/') {
        Some(at) => path[..at].to_string(),
        None => String::new(),
    }
}

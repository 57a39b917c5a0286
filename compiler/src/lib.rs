//! The skillc front end: parse `.skill` templates, check them, and lower them to the IR.
//!
//! The stages are [`syntax::parse`] (text to [`ast`]), `check` (names, units, segments,
//! axes, the state machine) and lowering into [`skill_ir::Program`]. All of it is pure: the
//! caller supplies file contents, including those of imported files through a loader, so
//! this crate never touches the file system.

#![warn(missing_docs)]

mod allow;
pub mod ast;
mod check;
pub mod diag;
pub mod fmt;
pub mod graph;
mod import;
pub mod info;
pub mod render;
pub mod source;
pub mod syntax;
pub mod units;

pub use check::{ParamSetting, DEFAULT_FORCE_BASIS, DEFAULT_GAINS, DEFAULT_MOTION_BASIS, DEFAULT_STIFFNESS};
pub use diag::{Code, Diag, Severity};
pub use import::join_path;
pub use source::{SourceFile, Span};

use skill_ir as ir;

/// Largest source file accepted, in bytes. Templates are a few kilobytes; anything near this
/// is the wrong file, and refusing it keeps `check` fast on any input.
pub const MAX_SOURCE_BYTES: usize = 1 << 20;

/// Deepest nesting accepted, counting each open bracket and each `not` whose operand has not
/// ended (`not (not x)` is three deep at `x`). pest recurses for each level, and so does
/// everything that walks the syntax tree; the costliest level, a guard in parentheses, takes
/// about 55 KiB of stack in an unoptimised build, so a file at this depth parses, checks,
/// formats and prints on a 2 MiB thread (tested), with room to spare. Templates nest 5 deep.
pub const MAX_NESTING: usize = 32;

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
    /// How many warnings `// allow(LINT): REASON` comments silenced (left out of `diags`).
    pub allowed: usize,
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

/// Turns raw bytes into a source file, or a diagnostic pointing at the first invalid byte.
pub fn decode(name: &str, bytes: Vec<u8>) -> Result<SourceFile, Box<(SourceFile, Diag)>> {
    match String::from_utf8(bytes) {
        Ok(text) => Ok(SourceFile::new(name, text)),
        Err(err) => {
            let lossy = String::from_utf8_lossy(err.as_bytes()).into_owned();
            // Offsets in the lossy text match up to the first invalid byte, and the source's
            // text starts after a byte order mark.
            let bom = if lossy.starts_with(source::BYTE_ORDER_MARK) {
                source::BYTE_ORDER_MARK.len_utf8()
            } else {
                0
            };
            let valid_up_to = err.utf8_error().valid_up_to().saturating_sub(bom);
            let source = SourceFile::new(name, lossy);
            let diag = Diag::new(
                Code::InvalidUtf8,
                0,
                Span::new(valid_up_to, valid_up_to + 1),
                format!("`{name}` is not valid UTF-8 text"),
                "invalid byte here",
            )
            .help("skill templates are UTF-8 text; is this a binary file?");
            Err(Box::new((source, diag)))
        }
    }
}

/// Compiles a root file given as bytes, which may not be UTF-8 text; see [`compile_with_params`].
pub fn compile_bytes(
    name: &str,
    bytes: Vec<u8>,
    params: &[String],
    load: &mut dyn FnMut(&str) -> Result<String, LoadError>,
) -> Compilation {
    match decode(name, bytes) {
        Ok(root) => compile_with_params(root, params, load),
        Err(invalid) => {
            let (source, diag) = *invalid;
            Compilation {
                files: vec![source],
                diags: vec![diag],
                ast: Default::default(),
                program: None,
                allowed: 0,
            }
        }
    }
}

/// Compiles `root`. `load` returns the text of an imported file given its path, which is
/// the import string joined lexically to the importing file's directory.
pub fn compile(root: SourceFile, load: &mut dyn FnMut(&str) -> Result<String, LoadError>) -> Compilation {
    compile_with_params(root, &[], load)
}

/// The name under which `--param` settings appear in diagnostics, followed by the parameter's
/// name (`--param hold`); [`is_param_file`] tells such a file.
pub const PARAM_FILE: &str = "--param";

/// Whether a compilation's file named `name` holds a `--param` setting, not a `.skill` file.
pub fn is_param_file(name: &str) -> bool {
    name == PARAM_FILE || name.starts_with("--param ")
}

/// Compiles `root` with parameter settings from the command line (`NAME=VALUE`, as given to
/// `--param`): each sets the parameter of that name in every skill that declares one, before
/// a task step's own settings; a setting no skill declares is an error.
pub fn compile_with_params(
    root: SourceFile,
    params: &[String],
    load: &mut dyn FnMut(&str) -> Result<String, LoadError>,
) -> Compilation {
    let mut files = vec![root];
    let mut diags = Vec::new();
    let (root_ast, parse_diags) = syntax::parse(&files[0], 0);
    diags.extend(parse_diags);

    let mut asts: Vec<ast::File> = vec![root_ast];
    let order = import::load_all(&mut files, &mut asts, &mut diags, load);
    let command_line = command_line_settings(params, &mut files, &mut diags);

    // Check every file's skills; tasks see all skills loaded.
    let to_check = import::unique_skills(&order, &files, &asts, &mut diags);
    let skill_names: Vec<&str> = to_check.iter().map(|(_, skill)| skill.name.name.as_str()).collect();
    let facts: std::collections::HashMap<&str, check::SkillFacts<'_>> = to_check
        .iter()
        .map(|(_, skill)| (skill.name.name.as_str(), check::SkillFacts::of(skill)))
        .collect();
    for setting in &command_line {
        if !facts
            .values()
            .flat_map(|f| &f.params)
            .any(|name| *name == setting.name.name)
        {
            let mut all: Vec<&str> = facts.values().flat_map(|f| &f.params).copied().collect();
            all.sort_unstable();
            all.dedup();
            let help = diag::did_you_mean(&setting.name.name, all.iter().copied())
                .map(|found| format!("did you mean `{found}`?"))
                .unwrap_or_else(|| {
                    if all.is_empty() {
                        "no skill here declares a parameter (`param NAME = VALUE`)".to_string()
                    } else {
                        format!(
                            "parameters declared: {}",
                            all.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
                        )
                    }
                });
            diags.push(
                Diag::new(
                    Code::UnknownName,
                    setting.file,
                    setting.name.span,
                    format!(
                        "no skill in `{}` has a parameter `{}`",
                        files[0].name, setting.name.name
                    ),
                    "no such parameter",
                )
                .help(help),
            );
        }
    }
    let for_skill = |skill: &ast::Skill| -> Vec<ParamSetting> {
        command_line
            .iter()
            .filter(|setting| skill.params.iter().any(|p| p.name.name == setting.name.name))
            .cloned()
            .collect()
    };
    let mut skills: Vec<ir::Skill> = Vec::new();
    for &(file, skill) in &to_check {
        let settings = for_skill(skill);
        if settings.is_empty() {
            let mut checker = check::Checker::new(file, &files[file], &mut diags);
            if let Some(lowered) = checker.skill_with(skill, &settings, true) {
                skills.push(lowered);
            }
            continue;
        }
        let mut found = Vec::new();
        let lowered = check::Checker::new(file, &files[file], &mut found).skill_with(skill, &settings, true);
        if lowered.is_some() {
            // No error: nothing to attribute to the flags.
            diags.extend(found);
            skills.extend(lowered);
            continue;
        }
        // An error the defaults do not have is the command line's: say which flags.
        let mut with_defaults = Vec::new();
        check::Checker::new(file, &files[file], &mut with_defaults).skill_with(skill, &[], false);
        let flags = settings
            .iter()
            .map(|setting| format!("`--param {}`", files[setting.file].text))
            .collect::<Vec<_>>()
            .join(", ");
        for diag in found {
            let caused = diag.severity() == Severity::Error
                && diag.file == file
                && !with_defaults
                    .iter()
                    .any(|d| d.code == diag.code && d.span() == diag.span() && d.message == diag.message);
            diags.push(if caused {
                noted(diag, &format!("with {flags} from the command line"))
            } else {
                diag
            });
        }
    }
    let mut tasks = Vec::new();
    {
        let source = files[0].clone();
        let base_dir = import::parent_dir(&source.name);
        for task in &asts[0].tasks {
            let mut checker = check::Checker::new(0, &source, &mut diags);
            let (mut lowered, step_params) = checker.task(task, &skill_names, &facts, &base_dir);
            let mut ok = lowered.is_some();
            for step in step_params {
                let Some(&(file, skill)) = to_check.iter().find(|(_, s)| s.name.name == step.skill) else {
                    continue;
                };
                if !skills.iter().any(|s| s.name == step.skill) {
                    // The skill itself has errors, reported once already.
                    ok = false;
                    continue;
                }
                let step_name = step.step;
                let mut settings = for_skill(skill);
                settings.extend(step.settings);
                let mut scratch = Vec::new();
                let specialised =
                    check::Checker::new(file, &files[file], &mut scratch).skill_with(skill, &settings, false);
                // Warnings were given by the skill's own check; errors are this step's values'.
                for diag in scratch.into_iter().filter(|d| d.severity() == Severity::Error) {
                    diags.push(noted(diag, &format!("with the parameters step `{step_name}` sets")));
                }
                match (specialised, lowered.as_mut(), step.index) {
                    (Some(skill_ir), Some(task_ir), Some(index)) => {
                        let list = if step.fallback {
                            &mut task_ir.fallbacks
                        } else {
                            &mut task_ir.steps
                        };
                        list[index].specialised = Some(Box::new(skill_ir));
                    }
                    _ => ok = false,
                }
            }
            if let (true, Some(lowered)) = (ok, lowered) {
                tasks.push(lowered);
            }
        }
    }

    let mut allowed = 0;
    for (file, source) in files.iter().enumerate() {
        allowed += allow::apply(file, source, &mut diags);
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
        allowed,
    }
}

/// `diag` with `note` after its help, in parentheses (or as its help when it has none): what
/// caused it, when the cause is not in the file it points into.
fn noted(diag: Diag, note: &str) -> Diag {
    let help = match &diag.help {
        Some(help) => format!("{help} ({note})"),
        None => note.to_string(),
    };
    diag.help(help)
}

/// Parses `--param` settings, each into a file of its own named [`PARAM_FILE`] and the
/// parameter (`--param hold`; so that a
/// diagnostic can point into it); a setting that does not parse is reported there.
fn command_line_settings(params: &[String], files: &mut Vec<SourceFile>, diags: &mut Vec<Diag>) -> Vec<ParamSetting> {
    let mut settings = Vec::new();
    for text in params {
        let file = files.len();
        // Named after the parameter it sets (`--param hold`), so that a diagnostic's location
        // (`--param hold:1:6`) says which of several settings it is about.
        let name = match text.split_once('=') {
            Some((param, _)) if !param.trim().is_empty() => format!("{PARAM_FILE} {}", param.trim()),
            _ => PARAM_FILE.to_string(),
        };
        files.push(SourceFile::new(name, text.as_str()));
        match syntax::parse_param_setting(text) {
            Ok((name, value)) => settings.push(ParamSetting {
                name,
                value,
                file,
                source: ir::ParamSource::CommandLine,
            }),
            Err(message) => diags.push(
                Diag::new(
                    Code::Unexpected,
                    file,
                    Span::new(0, text.len()),
                    format!("cannot read `--param {text}`"),
                    "here",
                )
                .help(message),
            ),
        }
    }
    settings
}

//! Imports: loading imported files depth-first, import cycles, skills defined in two files
//! or twice in one, and joining paths written in a file to that file's directory.

use crate::diag::{Code, Diag};
use crate::source::{SourceFile, Span};
use crate::{ast, syntax, LoadError};
use std::collections::HashMap;

/// Loads the imports of the root file `files[0]` (parsed as `asts[0]`) and theirs,
/// depth-first, reporting cycles and files that cannot be loaded. Returns the files in the
/// order their skills are checked: every file after the files it imports, the root last.
pub(crate) fn load_all(
    files: &mut Vec<SourceFile>,
    asts: &mut Vec<ast::File>,
    diags: &mut Vec<Diag>,
    load: &mut dyn FnMut(&str) -> Result<String, LoadError>,
) -> Vec<usize> {
    let mut order: Vec<usize> = Vec::new();
    let mut stack: Vec<usize> = vec![0];
    load_imports(0, files, asts, diags, &mut stack, &mut order, load);
    order.push(0);
    order
}

/// The skills of the files in `order`, each name once with the file it is defined in. A
/// later definition of a name is reported and left out.
pub(crate) fn unique_skills<'a>(
    order: &[usize],
    files: &[SourceFile],
    asts: &'a [ast::File],
    diags: &mut Vec<Diag>,
) -> Vec<(usize, &'a ast::Skill)> {
    let mut first_definition: HashMap<&str, (usize, Span)> = HashMap::new();
    let mut duplicates: Vec<Diag> = Vec::new();
    let mut unique: Vec<(usize, &ast::Skill)> = Vec::new();
    for &file in order {
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
                    unique.push((file, skill));
                }
            }
        }
    }
    diags.extend(duplicates);
    unique
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
        let path = join_path(&base_dir, &import.path);
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
pub(crate) fn parent_dir(path: &str) -> String {
    match path.rfind('/') {
        Some(at) => path[..at].to_string(),
        None => String::new(),
    }
}

/// Joins a path written in a file to that file's directory, lexically (no IO).
pub fn join_path(base_dir: &str, path: &str) -> String {
    if path.starts_with('/') || base_dir.is_empty() {
        return path.to_string();
    }
    let mut parts: Vec<&str> = base_dir.split('/').filter(|p| !p.is_empty() && *p != ".").collect();
    let absolute = base_dir.starts_with('/');
    for part in path.split('/') {
        match part {
            "" | "." => {}
            ".." if parts.last().is_some_and(|last| *last != "..") => {
                parts.pop();
            }
            _ => parts.push(part),
        }
    }
    let joined = parts.join("/");
    if absolute {
        format!("/{joined}")
    } else if joined.is_empty() {
        ".".to_string()
    } else {
        joined
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn join_path_is_lexical() {
        assert_eq!(join_path("examples/tasks", "../demos/a.csv"), "examples/demos/a.csv");
        assert_eq!(join_path("", "a.csv"), "a.csv");
        assert_eq!(join_path("a", "/abs/b.csv"), "/abs/b.csv");
        assert_eq!(join_path("/x/y", "./z.skill"), "/x/y/z.skill");
        assert_eq!(join_path("..", "../a"), "../../a");
    }
}

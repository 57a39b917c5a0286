//! Repository hygiene: every Rust file says what it is for, none passes 1000 lines, and the
//! command line imports in no circle. (That no snapshot is orphaned is
//! checked next to the snapshots, in `compiler/tests/front_end.rs`.)

use std::path::{Path, PathBuf};

fn files_with_extension(dir: &Path, extension: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.filter_map(Result::ok) {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            if name != "target" && !name.starts_with('.') {
                files_with_extension(&path, extension, out);
            }
        } else if path.extension().is_some_and(|ext| ext == extension) {
            out.push(path);
        }
    }
}

#[test]
fn every_rust_file_starts_with_a_module_doc_line() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    files_with_extension(root, "rs", &mut files);
    assert!(files.len() > 10);
    let offenders: Vec<String> = files
        .iter()
        .filter(|path| {
            let text = std::fs::read_to_string(path).unwrap_or_default();
            !text.starts_with("//!")
        })
        .map(|path| path.strip_prefix(root).unwrap_or(path).display().to_string())
        .collect();
    assert!(
        offenders.is_empty(),
        "files without a leading `//!` line: {offenders:?}"
    );
}

/// Lines of every Rust file of the tree, by path.
fn rust_files() -> Vec<(PathBuf, usize)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    files_with_extension(root, "rs", &mut files);
    files
        .into_iter()
        .map(|path| {
            let lines = std::fs::read_to_string(&path).unwrap_or_default().lines().count();
            (path.strip_prefix(root).unwrap_or(&path).to_path_buf(), lines)
        })
        .collect()
}

#[test]
fn no_rust_file_passes_a_thousand_lines() {
    let files = rust_files();
    assert!(files.len() > 100, "{} files", files.len());
    let long: Vec<String> = files
        .iter()
        .filter(|(_, lines)| *lines > 1000)
        .map(|(path, lines)| format!("{} ({lines} lines)", path.display()))
        .collect();
    assert!(long.is_empty(), "split these by job: {long:?}");
}

/// The modules of a crate whose modules are the files of one flat folder, and the ones each
/// names (`crate::NAME`, `use crate::{A, B}`, and `super::NAME`, which in a top-level file is
/// the crate root).
fn module_imports(dir: &Path) -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    let mut graph = std::collections::BTreeMap::new();
    let entries = std::fs::read_dir(dir).unwrap_or_else(|err| panic!("{}: {err}", dir.display()));
    let files: Vec<PathBuf> = entries.filter_map(Result::ok).map(|entry| entry.path()).collect();
    let modules: std::collections::BTreeSet<String> = files
        .iter()
        .filter(|path| path.extension().is_some_and(|ext| ext == "rs"))
        .filter_map(|path| path.file_stem().map(|stem| stem.to_string_lossy().into_owned()))
        .filter(|stem| stem != "lib" && stem != "main")
        .collect();
    for module in &modules {
        let text = std::fs::read_to_string(dir.join(format!("{module}.rs"))).expect("module");
        let mut named = std::collections::BTreeSet::new();
        for prefix in ["crate::", "super::"] {
            for (at, _) in text.match_indices(prefix) {
                let rest = &text[at + prefix.len()..];
                let names: Vec<&str> = if let Some(group) = rest.strip_prefix('{') {
                    group.split('}').next().unwrap_or("").split(',').collect()
                } else {
                    vec![rest]
                };
                for name in names {
                    let name: String = name
                        .trim()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    if modules.contains(&name) && &name != module {
                        named.insert(name);
                    }
                }
            }
        }
        graph.insert(module.clone(), named);
    }
    graph
}

#[test]
fn the_command_line_and_its_kit_import_in_no_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for dir in ["src", "kit/src"] {
        let graph = module_imports(&root.join(dir));
        assert!(graph.len() >= 5, "{dir}: {graph:?}");
        // A module that reaches itself through the ones it names closes a circle.
        for start in graph.keys() {
            let mut seen = std::collections::BTreeSet::new();
            let mut todo: Vec<&String> = graph[start].iter().collect();
            while let Some(next) = todo.pop() {
                assert!(next != start, "{dir}: `{start}` imports itself through {seen:?}");
                if seen.insert(next.clone()) {
                    todo.extend(graph.get(next).into_iter().flatten());
                }
            }
        }
    }
}

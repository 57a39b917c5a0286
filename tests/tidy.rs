//! Repository hygiene: every Rust file says what it is for, and no snapshot is orphaned.

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

#[test]
fn every_snapshot_belongs_to_a_corpus_or_stdlib_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut snapshots = Vec::new();
    files_with_extension(&root.join("tests/snapshots"), "snap", &mut snapshots);
    for snapshot in snapshots {
        let name = snapshot.file_stem().expect("name").to_string_lossy().into_owned();
        let source = if let Some(rest) = name.strip_prefix("diag__") {
            root.join("tests/corpus/err").join(format!("{rest}.skill"))
        } else if let Some(rest) = name.strip_prefix("ir__") {
            let (dir, file) = rest.split_once("__").expect("ir__DIR__FILE");
            let dir = match dir {
                "ok" => root.join("tests/corpus/ok"),
                "stdlib-skills" => root.join("stdlib-skills"),
                "tasks" => root.join("examples/tasks"),
                other => panic!("snapshot {name} names an unknown directory {other}"),
            };
            dir.join(format!("{file}.skill"))
        } else {
            continue;
        };
        assert!(
            source.exists(),
            "orphaned snapshot {} (no {})",
            snapshot.display(),
            source.display()
        );
    }
}

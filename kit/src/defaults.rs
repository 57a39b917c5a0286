//! The built-in defaults `skillc eval` runs on from any folder: the standard skills, scenes,
//! robot and trials are compiled into the binary and the demonstrations are generated, written
//! once into the user's cache folder (`$XDG_CACHE_HOME/skillc/VERSION`, else
//! `~/.cache/skillc/VERSION`, else under the temporary directory).
//!
//! From the repository root (where `examples/eval/default.toml` is) the files there are used,
//! edits included; anywhere else (after `cargo install --locked --path .`) the built-in copies.

use std::path::{Path, PathBuf};

use skill_runtime::demogen::{generate, to_csv, StdSkill};

use crate::atomic;

/// Every built-in file, by its path relative to the repository root.
const FILES: &[(&str, &str)] = &[
    (
        "examples/eval/default.toml",
        include_str!("../../examples/eval/default.toml"),
    ),
    (
        "stdlib-skills/touch.skill",
        include_str!("../../stdlib-skills/touch.skill"),
    ),
    (
        "stdlib-skills/press.skill",
        include_str!("../../stdlib-skills/press.skill"),
    ),
    (
        "stdlib-skills/slide.skill",
        include_str!("../../stdlib-skills/slide.skill"),
    ),
    (
        "stdlib-skills/contour.skill",
        include_str!("../../stdlib-skills/contour.skill"),
    ),
    (
        "stdlib-skills/wipe.skill",
        include_str!("../../stdlib-skills/wipe.skill"),
    ),
    (
        "stdlib-skills/press_hold.skill",
        include_str!("../../stdlib-skills/press_hold.skill"),
    ),
    (
        "stdlib-skills/guarded_move.skill",
        include_str!("../../stdlib-skills/guarded_move.skill"),
    ),
    (
        "stdlib-skills/double_tap.skill",
        include_str!("../../stdlib-skills/double_tap.skill"),
    ),
    (
        "stdlib-skills/slide_then_press.skill",
        include_str!("../../stdlib-skills/slide_then_press.skill"),
    ),
    (
        "examples/scenes/table.toml",
        include_str!("../../examples/scenes/table.toml"),
    ),
    (
        "examples/scenes/button.toml",
        include_str!("../../examples/scenes/button.toml"),
    ),
    (
        "examples/scenes/cylinder.toml",
        include_str!("../../examples/scenes/cylinder.toml"),
    ),
    (
        "examples/scenes/workcell.toml",
        include_str!("../../examples/scenes/workcell.toml"),
    ),
    (
        "examples/tasks/find_wipe_hold.skill",
        include_str!("../../examples/tasks/find_wipe_hold.skill"),
    ),
    (
        "examples/tasks/inspect_and_press.skill",
        include_str!("../../examples/tasks/inspect_and_press.skill"),
    ),
    (
        "examples/robots/lwr4.urdf",
        include_str!("../../examples/robots/lwr4.urdf"),
    ),
    (
        "examples/robots/iiwa14.urdf",
        include_str!("../../examples/robots/iiwa14.urdf"),
    ),
    (
        "examples/robots/fr3.urdf",
        include_str!("../../examples/robots/fr3.urdf"),
    ),
];

/// The file whose presence marks a complete folder of defaults.
const COMPLETE: &str = ".complete";

/// The root the default trials' paths are relative to: the current folder when it is the
/// repository's root, else a folder of built-in copies (written on first use).
pub fn root() -> Result<PathBuf, String> {
    if Path::new("examples/eval/default.toml").is_file() && Path::new("stdlib-skills").is_dir() {
        return Ok(PathBuf::new());
    }
    let dir = cache_dir();
    if FILES.iter().all(|(path, text)| same(&dir.join(path), text)) && demos_as_marked(&dir) {
        return Ok(dir);
    }
    write_all(&dir).map_err(|err| format!("cannot write the built-in defaults to `{}`: {err}", dir.display()))?;
    Ok(dir)
}

/// Where the built-in copies go: the user's own cache (not a folder every user of the machine
/// can write into), else the temporary directory.
fn cache_dir() -> PathBuf {
    let version = format!("skillc/{}/defaults", env!("CARGO_PKG_VERSION"));
    let nonempty = |name: &str| {
        std::env::var_os(name)
            .filter(|value| !value.is_empty())
            .map(PathBuf::from)
    };
    if let Some(cache) = nonempty("XDG_CACHE_HOME") {
        return cache.join(version);
    }
    if let Some(home) = nonempty("HOME") {
        return home.join(".cache").join(version);
    }
    std::env::temp_dir().join(version)
}

/// Whether `path` holds exactly `text` (a copy from another version is rewritten).
fn same(path: &Path, text: &str) -> bool {
    std::fs::read_to_string(path).is_ok_and(|existing| existing == text)
}

/// The completion mark's text: one line `PATH HASH` per generated demonstration.
fn mark(demos: &[(String, Vec<u8>)]) -> String {
    demos
        .iter()
        .map(|(path, bytes)| format!("{path} {}\n", atomic::fnv(bytes)))
        .collect()
}

/// Whether the completion mark exists and every generated demonstration it lists still has the
/// bytes it had when written (a user's edit, a truncated or deleted file are regenerated; the
/// demonstrations are 9 MB, hashed in milliseconds).
fn demos_as_marked(dir: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(dir.join(COMPLETE)) else {
        return false;
    };
    let lines: Vec<(&str, &str)> = text.lines().filter_map(|line| line.split_once(' ')).collect();
    lines.len() == StdSkill::ALL.len()
        && lines
            .iter()
            .all(|(path, hash)| std::fs::read(dir.join(path)).is_ok_and(|bytes| atomic::fnv(&bytes) == *hash))
}

/// Writes every built-in file and the generated demonstrations into `dir`, each atomically,
/// then the completion mark with the demonstrations' hashes: a folder another process is
/// writing at the same time ends with the same bytes.
fn write_all(dir: &Path) -> std::io::Result<()> {
    for (path, text) in FILES {
        let target = dir.join(path);
        if let Some(parent) = target.parent() {
            std::fs::create_dir_all(parent)?;
        }
        atomic::write(&target, text.as_bytes())?;
    }
    std::fs::create_dir_all(dir.join("examples/demos"))?;
    let mut written = Vec::new();
    for skill in StdSkill::ALL {
        let path = format!("examples/demos/{}.csv", skill.name());
        let bytes = to_csv(&generate(skill, skill.default_seed())).into_bytes();
        atomic::write(&dir.join(&path), &bytes)?;
        written.push((path, bytes));
    }
    atomic::write(&dir.join(COMPLETE), mark(&written).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in copies are the repository's files: a stale `include_str!` cannot happen,
    /// but a file the defaults need and the list lacks would only fail outside the repository.
    #[test]
    fn the_defaults_hold_every_file_the_default_trials_name() {
        let trials: toml::Table = FILES[0].1.parse().expect("default trials");
        let skills = trials["skill"].as_array().expect("skills");
        let normal = |path: PathBuf| -> String {
            let normal: PathBuf = path.components().fold(PathBuf::new(), |mut acc, c| {
                match c {
                    std::path::Component::ParentDir => {
                        acc.pop();
                    }
                    other => acc.push(other),
                }
                acc
            });
            normal.to_string_lossy().replace('\\', "/")
        };
        let built_in = |name: &str| assert!(FILES.iter().any(|(p, _)| *p == name), "`{name}` is not built in");
        // A task's file, its imports and its steps' demonstrations, relative to the task file.
        for task in trials["task"].as_array().expect("tasks") {
            let file = normal(Path::new("examples/eval").join(task["file"].as_str().expect("file")));
            built_in(&file);
            built_in(&normal(
                Path::new("examples/eval").join(task["scene"].as_str().expect("scene")),
            ));
            let dir = Path::new(&file).parent().expect("folder").to_path_buf();
            let text = FILES.iter().find(|(p, _)| *p == file).expect("built in").1;
            for quoted in text.split('"').skip(1).step_by(2) {
                let name = normal(dir.join(quoted));
                if quoted.ends_with(".skill") {
                    built_in(&name);
                } else if let Some(stem) = quoted.strip_suffix(".csv") {
                    let stem = Path::new(stem).file_name().and_then(|s| s.to_str()).expect("stem");
                    assert!(
                        StdSkill::ALL.iter().any(|s| s.name() == stem),
                        "demo `{quoted}` is not generated"
                    );
                }
            }
        }
        for skill in skills {
            for key in ["file", "scene"] {
                let relative = skill[key].as_str().expect("path");
                built_in(&normal(Path::new("examples/eval").join(relative)));
            }
            let demo = skill["demo"].as_str().expect("demo");
            let stem = Path::new(demo).file_stem().and_then(|s| s.to_str()).expect("stem");
            assert!(
                StdSkill::ALL.iter().any(|s| s.name() == stem),
                "demo `{demo}` is not generated"
            );
        }
    }

    /// `skillc eval --robot NAME` from any folder needs every shipped robot's URDF.
    #[test]
    fn the_defaults_hold_every_shipped_robot() {
        for robot in skill_runtime::robot::BUILTIN_ROBOTS {
            let built_in = FILES.iter().find(|(path, _)| *path == robot.path);
            assert_eq!(built_in.map(|(_, text)| *text), Some(robot.urdf), "{}", robot.name);
        }
    }

    #[test]
    fn written_defaults_are_complete_and_match_the_repository() {
        let dir = std::env::temp_dir().join(format!("skillc-defaults-test-{}", std::process::id()));
        write_all(&dir).expect("writes");
        assert!(demos_as_marked(&dir));
        // An edited demonstration is noticed (and `root` would write the folder again).
        let press = dir.join("examples/demos/press.csv");
        let mut edited = std::fs::read(&press).expect("demo");
        edited.truncate(edited.len() / 2);
        std::fs::write(&press, edited).expect("edit");
        assert!(!demos_as_marked(&dir));
        write_all(&dir).expect("writes again");
        assert!(demos_as_marked(&dir));
        let repository = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for (path, text) in FILES {
            assert!(same(&dir.join(path), text), "{path}");
            let shipped = std::fs::read_to_string(repository.join(path)).expect("repository file");
            assert_eq!(shipped, *text, "{path}");
        }
        for name in StdSkill::ALL.map(StdSkill::name) {
            let generated = std::fs::read_to_string(dir.join(format!("examples/demos/{name}.csv"))).expect("demo");
            let shipped =
                std::fs::read_to_string(repository.join(format!("examples/demos/{name}.csv"))).expect("shipped demo");
            assert_eq!(generated, shipped, "{name}.csv");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

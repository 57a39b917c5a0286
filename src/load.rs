//! What the commands share: how a command fails ([`Failure`], exit 1 or 2), and loading their
//! inputs: a skill from a `.skill` file, a demonstration learned into features, a learned file,
//! a scene with `KEY=VALUE` overrides.

use std::fmt::Write as _;
use std::path::Path;

use skill_runtime::demo::{negate_wrench, read_csv, stores_applied_force, ReadOptions};
use skill_runtime::sim::Scene;
use skill_runtime::skill::{learn_skill, LearnOptions, Learned};

use crate::{frontend, render};

/// Why a command failed: a problem with the input (exit 1) or with usage or IO (exit 2).
#[derive(Debug)]
pub enum Failure {
    /// Exit 1.
    Input(String),
    /// Exit 2.
    Usage(String),
}

impl Failure {
    /// Prints the message and returns the exit code.
    pub fn report(self) -> u8 {
        match self {
            Failure::Input(message) => {
                eprintln!("error: {message}");
                1
            }
            Failure::Usage(message) => {
                eprintln!("error: {message}");
                2
            }
        }
    }
}

/// An error and its sources on one line: `a: b: c`.
pub fn error_chain(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(inner) = source {
        let _ = write!(text, ": {inner}");
        source = inner.source();
    }
    text
}

/// Compiles a `.skill` file and picks one skill of it (`name`, or the only one).
pub fn load_skill(path: &Path, name: Option<&str>) -> Result<(skill_ir::Program, skill_ir::Skill), Failure> {
    let compilation = frontend::compile_path(path).map_err(|err| Failure::Usage(err.to_string()))?;
    let Some(program) = compilation.program.clone() else {
        let mut text = String::new();
        for diag in &compilation.diags {
            text.push_str(&render::plain(diag, &compilation));
        }
        return Err(Failure::Input(format!(
            "`{}` does not compile:\n{}",
            path.display(),
            text.trim_end()
        )));
    };
    let skill = match name {
        Some(name) => program.skill(name).cloned().ok_or_else(|| {
            let names: Vec<&str> = program.skills.iter().map(|s| s.name.as_str()).collect();
            Failure::Usage(format!(
                "`{}` has no skill `{name}`; it has {}",
                path.display(),
                names.join(", ")
            ))
        })?,
        None => match program.skills.as_slice() {
            [only] => only.clone(),
            [] => return Err(Failure::Usage(format!("`{}` defines no skill", path.display()))),
            many => {
                let names: Vec<&str> = many.iter().map(|s| s.name.as_str()).collect();
                return Err(Failure::Usage(format!(
                    "`{}` defines {} skills ({}); pick one with --skill",
                    path.display(),
                    many.len(),
                    names.join(", ")
                )));
            }
        },
    };
    Ok((program, skill))
}

/// Learns a skill from a demonstration file; the library form of `skillc learn`.
pub fn learn_from_files(skill: &skill_ir::Skill, demo_path: &Path, options: &LearnOptions) -> Result<Learned, Failure> {
    learn_from_file(skill, demo_path, options, false)
}

/// Like [`learn_from_files`], optionally negating the file's wrench first (`applied_force`).
/// Warns when the forces look like the force the robot applies and were not negated.
pub fn learn_from_file(
    skill: &skill_ir::Skill,
    demo_path: &Path,
    options: &LearnOptions,
    applied_force: bool,
) -> Result<Learned, Failure> {
    let min_samples = (skill.learn.segments as usize * 5).max(10);
    let mut loaded =
        read_csv(demo_path, &ReadOptions { min_samples }).map_err(|err| Failure::Input(error_chain(&err)))?;
    let mut warnings: Vec<String> = loaded.warnings.iter().map(ToString::to_string).collect();
    if applied_force {
        negate_wrench(&mut loaded.demo);
    } else if stores_applied_force(&loaded.demo) {
        warnings.push(
            "in contact the force points into the surface: if the file stores the force the robot applies, pass --applied-force"
                .to_string(),
        );
    }
    learn_skill(skill, &loaded.demo, &warnings, options).map_err(|err| Failure::Input(error_chain(&err)))
}

/// Reads a learned file.
pub fn read_learned(path: &Path) -> Result<Learned, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|err| Failure::Usage(format!("cannot read `{}`: {err}", path.display())))?;
    serde_json::from_str(&text).map_err(|err| {
        Failure::Input(format!(
            "`{}` is not a learned file: {err} (line {}, column {})",
            path.display(),
            err.line(),
            err.column()
        ))
    })
}

/// Loads a scene and applies `KEY=VALUE` overrides.
pub fn load_scene(path: &Path, sets: &[String]) -> Result<Scene, Failure> {
    let mut scene = Scene::from_file(path).map_err(|err| Failure::Input(error_chain(&err)))?;
    for set in sets {
        let Some((key, value)) = set.split_once('=') else {
            return Err(Failure::Usage(format!(
                "`--set {set}` must look like KEY=VALUE, e.g. table.z=0.195"
            )));
        };
        scene
            .set(key.trim(), value.trim())
            .map_err(|err| Failure::Input(error_chain(&err)))?;
    }
    Ok(scene)
}

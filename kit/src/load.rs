//! What the commands share: how a command fails ([`Failure`], exit 1 or 2), and loading their
//! inputs: a skill from a `.skill` file, a demonstration learned into features, a learned file,
//! a scene with `KEY=VALUE` overrides.

use std::fmt::Write as _;
use std::path::Path;

use skill_runtime::demo::{read_csv_as, DemoError, Dialect, ForceSign, Loaded, ReadOptions};
use skill_runtime::sim::{Scene, SceneError};
use skill_runtime::skill::validate::InvalidLearned;
use skill_runtime::skill::{learn_skill, LearnOptions, Learned, LEARNED_VERSION};

use crate::{frontend, limits, render};
use skill_ros::bag::BagOptions;

/// Why a command failed: a problem with the input (exit 1) or with usage or IO (exit 2), or
/// standard output was closed by its reader (exit 0, nothing to say: `skillc ... | head`).
#[derive(Debug)]
pub enum Failure {
    /// Exit 1.
    Input(String),
    /// Exit 2.
    Usage(String),
    /// Exit 0, no message: the reader of standard output went away.
    Closed,
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
            Failure::Closed => 0,
        }
    }
}

/// An error and its sources on one line: `a: b: c`. A source whose text the message already
/// holds (thiserror messages that print their `source`) is not repeated.
pub fn error_chain(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(inner) = source {
        let part = inner.to_string();
        if !text.contains(&part) {
            let _ = write!(text, ": {part}");
        }
        source = inner.source();
    }
    text
}

/// Compiles a `.skill` file and picks one skill of it (`name`, or the only one).
pub fn load_skill(path: &Path, name: Option<&str>) -> Result<(skill_ir::Program, skill_ir::Skill), Failure> {
    load_skill_with(path, name, &[])
}

/// Compiles a `.skill` file (skills, tasks, imports) with `--param` settings; the compiler's
/// diagnostics as the error when it does not compile.
pub fn load_program_with(path: &Path, params: &[String]) -> Result<skill_ir::Program, Failure> {
    let compilation = frontend::compile_path_with(path, params).map_err(|err| Failure::Usage(err.to_string()))?;
    let Some(program) = compilation.program.clone() else {
        let mut text = String::new();
        for diag in &compilation.diags {
            text.push_str(&render::plain(diag, &compilation));
            if let Some(help) = &diag.help {
                let _ = writeln!(text, "  help: {help}");
            }
        }
        return Err(Failure::Input(format!(
            "`{}` does not compile:\n{}",
            path.display(),
            text.trim_end()
        )));
    };
    Ok(program)
}

/// [`load_skill`] with `--param NAME=VALUE` settings.
pub fn load_skill_with(
    path: &Path,
    name: Option<&str>,
    params: &[String],
) -> Result<(skill_ir::Program, skill_ir::Skill), Failure> {
    let program = load_program_with(path, params)?;
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

/// Like [`learn_from_files`], optionally declaring that the file stores the force the robot
/// applies (`applied_force`); otherwise the learner detects the sign (docs/method.md §1).
pub fn learn_from_file(
    skill: &skill_ir::Skill,
    demo_path: &Path,
    options: &LearnOptions,
    applied_force: bool,
) -> Result<Learned, Failure> {
    learn_from_demo(skill, demo_path, &Dialect::default(), options, applied_force)
}

/// Like [`learn_from_file`], reading the CSV in `dialect` (separator, column names).
pub fn learn_from_demo(
    skill: &skill_ir::Skill,
    demo_path: &Path,
    dialect: &Dialect,
    options: &LearnOptions,
    applied_force: bool,
) -> Result<Learned, Failure> {
    learn_from_source(
        skill,
        demo_path,
        dialect,
        &BagOptions::default(),
        options,
        applied_force,
    )
    .map(|(learned, _)| learned)
}

/// Reads a demonstration: a ROS 2 bag (an MCAP file, by the extension `.mcap`, or a rosbag2
/// folder; any folder is read as one, which says why it is not) through
/// [`skill_ros::bag::read_demo`] with the topics of `bag`, else CSV in `dialect`. A file named
/// otherwise whose content is a bag is refused by what it is ([`skill_ros::bag::misnamed_csv`];
/// the bag reader refuses a `.mcap` that is not MCAP). Returns it with the reader's notes (as
/// warnings) and, for a bag, where the pose and wrench came from.
pub fn read_demo(
    path: &Path,
    dialect: &Dialect,
    bag: &BagOptions,
) -> Result<(Loaded, Vec<String>, Option<String>), Failure> {
    crate::atomic::note_input(path);
    if skill_ros::bag::is_mcap(path) || path.is_dir() {
        return read_bag(path, bag);
    }
    if let Some(misnamed) = skill_ros::bag::misnamed_csv(path) {
        return Err(Failure::Input(misnamed));
    }
    let loaded = read_csv_as(path, &ReadOptions::default(), dialect).map_err(|err| match &err {
        // A file that cannot be read is an IO error; one that is not UTF-8 text is bad input.
        DemoError::Io { source, .. } if source.kind() != std::io::ErrorKind::InvalidData => {
            Failure::Usage(error_chain(&err))
        }
        _ => Failure::Input(error_chain(&err)),
    })?;
    Ok((loaded, Vec::new(), None))
}

#[cfg(feature = "mcap")]
fn read_bag(path: &Path, bag: &BagOptions) -> Result<(Loaded, Vec<String>, Option<String>), Failure> {
    use skill_ros::bag::BagError;
    let read = skill_ros::bag::read_demo(path, bag).map_err(|err| match &err {
        BagError::Io { .. } => Failure::Usage(error_chain(&err)),
        BagError::NotABag { .. } => Failure::Usage(error_chain(&err)),
        _ => Failure::Input(error_chain(&err)),
    })?;
    let provenance = format!(
        "pose from {}, wrench from topic `{}` interpolated onto the pose's times",
        read.pose_source, read.wrench_topic
    );
    Ok((read.loaded, read.notes, Some(provenance)))
}

#[cfg(not(feature = "mcap"))]
fn read_bag(path: &Path, _bag: &BagOptions) -> Result<(Loaded, Vec<String>, Option<String>), Failure> {
    Err(Failure::Usage(format!(
        "`{}` is a ROS 2 bag (MCAP), and this skillc was built without the `mcap` feature: build it with default features",
        path.display()
    )))
}

/// Like [`learn_from_demo`], reading an MCAP file's topics as `bag` says; also returns where a
/// bag's pose and wrench came from. Every number that sizes the work is bounded first (the
/// template's `resample`, `lowpass` and `expect`, the demonstration's duration and resampled
/// length), and the result is validated before it is returned, so nothing unusable is ever
/// written.
pub fn learn_from_source(
    skill: &skill_ir::Skill,
    demo_path: &Path,
    dialect: &Dialect,
    bag: &BagOptions,
    options: &LearnOptions,
    applied_force: bool,
) -> Result<(Learned, Option<String>), Failure> {
    let plan = &skill.learn;
    let name = &skill.name;
    if plan.segments > limits::SEGMENTS {
        return Err(Failure::Input(format!(
            "skill `{name}` expects {} segments (`expect {}`); at most {} are supported",
            plan.segments,
            plan.segments,
            limits::SEGMENTS
        )));
    }
    for (field, value) in [("resample", plan.resample_hz), ("lowpass", plan.lowpass_hz)] {
        if let Some(value) = value {
            limits::check(&format!("`{field}` of skill `{name}`"), value, limits::RATE_HZ, " Hz")
                .map_err(Failure::Input)?;
        }
    }
    for (flag, value) in [("--resample", options.resample_hz), ("--lowpass", options.lowpass_hz)] {
        if let Some(value) = value {
            limits::check(flag, value, limits::RATE_HZ, " Hz").map_err(Failure::Usage)?;
        }
    }
    let (loaded, notes, provenance) = read_demo(demo_path, dialect, bag)?;
    let file = demo_path.display();
    check_wrench_magnitudes(&loaded.demo, &file.to_string())?;
    let samples = loaded.demo.len();
    let needed = (plan.segments as usize * 5).max(10);
    if samples < needed {
        return Err(Failure::Input(format!(
            "skill `{name}` expects {} segment(s) (`expect {}`), which needs at least {needed} samples; `{file}` has {samples}",
            plan.segments, plan.segments
        )));
    }
    let duration = loaded.demo.duration_s();
    let min_length = match &plan.segmentation {
        skill_ir::Segmentation::Cluster { min_length_s, .. }
        | skill_ir::Segmentation::Changepoint { min_length_s, .. } => Some(*min_length_s),
        _ => None,
    };
    if let Some(min_length) = min_length.filter(|m| *m * f64::from(plan.segments) > duration) {
        return Err(Failure::Input(format!(
            "skill `{name}` expects {} segment(s) of at least {} s each (`min_length`), longer than `{file}` ({duration:.2} s) in all",
            plan.segments,
            limits::number(min_length)
        )));
    }
    if duration > limits::DEMO_S {
        return Err(Failure::Input(format!(
            "`{file}` lasts {duration:e} s, at most {} s are supported: is its `t` column in seconds?",
            limits::DEMO_S
        )));
    }
    if let Some(rate) = options.resample_hz.or(plan.resample_hz) {
        let resampled = duration * rate;
        if resampled > limits::SAMPLES {
            return Err(Failure::Input(format!(
                "resampling `{file}` ({duration:.1} s) at {rate} Hz would make {resampled:.0} samples, at most {:.0}",
                limits::SAMPLES
            )));
        }
    }
    let mut warnings: Vec<String> = loaded.warnings.iter().map(ToString::to_string).collect();
    warnings.extend(notes);
    // The wrench's frame and sign: the flags' declarations over the file's, the rest detected.
    let mut options = options.clone();
    if applied_force {
        options.wrench.sign = Some(ForceSign::Applied);
    }
    options.wrench = options.wrench.or(loaded.wrench);
    let learned = learn_skill(skill, &loaded.demo, &warnings, &options).map_err(|err| {
        let message = error_chain(&err);
        let file = file.to_string();
        if message.contains(&file) {
            Failure::Input(message)
        } else {
            Failure::Input(format!("learning skill `{name}` from `{file}`: {message}"))
        }
    })?;
    learned.validate().map_err(|err| {
        Failure::Input(format!(
            "what skill `{name}` learned from `{file}` is unusable, so nothing is written: {err} (are the demonstration's values in metres, newtons and seconds?)"
        ))
    })?;
    Ok((learned, provenance))
}

/// Refuses a demonstration whose force or moment components lie beyond any sensor's range
/// ([`limits::DEMO_FORCE_N`], [`limits::DEMO_MOMENT_NM`]), naming the first such sample: learning
/// would square them into infinities and report those instead.
fn check_wrench_magnitudes(demo: &skill_runtime::demo::Demo, file: &str) -> Result<(), Failure> {
    let channels = [
        (&demo.force_n, ["fx", "fy", "fz"], limits::DEMO_FORCE_N, "N"),
        (&demo.torque_nm, ["mx", "my", "mz"], limits::DEMO_MOMENT_NM, "N m"),
    ];
    for (values, names, bound, unit) in channels {
        for (index, value) in values.iter().enumerate() {
            if let Some(axis) = (0..3).find(|&axis| value[axis].abs() > bound) {
                let t = demo.t_s.get(index).copied().unwrap_or(f64::NAN);
                return Err(Failure::Input(format!(
                    "`{file}`, sample {} (t = {t} s): {} is {:e} {unit}, beyond any force sensor (at most {bound:e} {unit}): is the column in {}?",
                    index + 1,
                    names[axis],
                    value[axis],
                    if unit == "N" { "newtons" } else { "newton metres" }
                )));
            }
        }
    }
    Ok(())
}

/// Learned files larger than this are refused before reading, in bytes.
const MAX_LEARNED_BYTES: u64 = 256 << 20;

/// Reads a learned file and validates it ([`Learned::validate`]): the version first (a file of
/// another version says to learn it again), then every number and array.
pub fn read_learned(path: &Path) -> Result<Learned, Failure> {
    let file = path.display();
    let cannot_read = |err: std::io::Error| Failure::Usage(format!("cannot read `{file}`: {err}"));
    let meta = std::fs::metadata(path).map_err(cannot_read)?;
    if meta.is_file() && meta.len() > MAX_LEARNED_BYTES {
        return Err(Failure::Input(format!(
            "`{file}` is {} MB, larger than any learned file ({} MB at most)",
            meta.len() >> 20,
            MAX_LEARNED_BYTES >> 20
        )));
    }
    let text = std::fs::read_to_string(path).map_err(cannot_read)?;
    crate::atomic::note_input(path);
    let not_learned = |err: serde_json::Error| {
        Failure::Input(format!(
            "`{file}` is not a learned file: {err} (line {}, column {})",
            err.line(),
            err.column()
        ))
    };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(not_learned)?;
    match value.get("learned_version").map(serde_json::Value::as_u64) {
        None => {
            return Err(Failure::Input(format!(
                "`{file}` is not a learned file: it has no `learned_version` (write one with `skillc learn`)"
            )))
        }
        Some(Some(version)) if version == u64::from(LEARNED_VERSION) => {}
        Some(found) => {
            let err = InvalidLearned::Version {
                found: found.unwrap_or(u64::MAX),
                supported: LEARNED_VERSION,
            };
            return Err(Failure::Input(format!("`{file}`: {err}")));
        }
    }
    let learned: Learned = serde_json::from_value(value)
        .map_err(|err| Failure::Input(format!("`{file}` is not a learned file: {err}")))?;
    learned
        .validate()
        .map_err(|err| Failure::Input(format!("`{file}` is not a usable learned file: {err}")))?;
    Ok(learned)
}

/// Loads a scene and applies `KEY=VALUE` overrides.
pub fn load_scene(path: &Path, sets: &[String]) -> Result<Scene, Failure> {
    let mut scene = Scene::from_file(path).map_err(|err| match err {
        SceneError::Io { .. } => Failure::Usage(error_chain(&err)),
        _ => Failure::Input(error_chain(&err)),
    })?;
    crate::atomic::note_input(path);
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
    // The plant reads the scene's robot: it is an input too.
    crate::atomic::note_input(&scene.urdf_path());
    Ok(scene)
}

/// How a task step learns from its demonstration: the contact phase its `phase:` names, and
/// otherwise as `skillc learn` does with no flags.
pub fn step_learn_options(step: &skill_ir::Step) -> LearnOptions {
    LearnOptions {
        phase: step.phase.map(|phase| phase as usize),
        ..LearnOptions::default()
    }
}

//! Malformed URDF and scene files (tests/corpus/): each must give a clear error naming the problem, never a panic.

use std::path::{Path, PathBuf};

use skill_runtime::robot::Robot;
use skill_runtime::sim::{RapierPlant, Scene};

fn corpus(kind: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus").join(kind);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("corpus folder exists")
        .map(|entry| entry.expect("readable entry").path())
        .collect();
    files.sort();
    files
}

/// A clear message: one line, lowercase start, no trailing period.
fn assert_clear(file: &Path, message: &str) {
    assert!(
        !message.is_empty() && !message.contains('\n'),
        "{}: `{message}`",
        file.display()
    );
    assert!(
        message.starts_with(|c: char| c.is_lowercase()),
        "{}: `{message}`",
        file.display()
    );
    assert!(!message.ends_with('.'), "{}: `{message}`", file.display());
}

#[test]
fn malformed_urdfs_give_clear_errors() {
    let expected = [
        ("001", "malformed urdf"),
        ("002", "unknown link `zz`"),
        ("003", "several ends (`b`, `c`): name the tool link"),
        ("004", "needs an `<inertial>`"),
        ("005", "negative mass"),
        ("006", "not positive definite"),
        ("007", "unsupported type `floating`"),
        ("008", "zero or non-finite axis"),
        ("009", "invalid limits"),
        ("010", "exactly one root link"),
        (
            "011",
            "zero mass and an inertia tensor that is not positive semi-definite",
        ),
        ("012", "non-finite number in `joint j origin`"),
        ("013", "no movable joint"),
        ("014", "not a URDF"),
        (
            "015",
            "is a xacro file (macros and `${...}` expressions), not a URDF: expand it to plain URDF first",
        ),
        ("016", "is an SDF file, not a URDF"),
        ("017", "is a MuJoCo MJCF file, not a URDF"),
    ];
    let files = corpus("urdf");
    assert_eq!(files.len(), expected.len());
    for (file, (prefix, needle)) in files.iter().zip(expected) {
        assert!(file
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with(prefix)));
        let err = Robot::from_urdf_file(file, None).expect_err("corpus urdf must not load");
        let message = err.to_string();
        assert_clear(file, &message);
        assert!(
            message.contains(needle),
            "{}: `{message}` lacks `{needle}`",
            file.display()
        );
        let name = file.file_name().expect("a file").to_string_lossy();
        assert!(message.contains(name.as_ref()), "`{message}` does not name the file");
    }
}

#[test]
fn malformed_scenes_give_clear_errors_naming_the_file() {
    let expected = [
        ("001", "malformed scene"),
        ("002", "robot"),
        ("003", "colour"),
        ("004", "`table.size`"),
        ("005", "`drum.length`"),
        ("006", "sphere"),
        ("007", "`sim.dt`"),
        ("008", "`b.travel`"),
        ("009", "missing.urdf"),
        ("010", "`robot.q0`"),
        ("011", "`robot.q0.1`"),
        ("012", "unknown link `nope`"),
        ("013", "`sensor.noise_force_n` = `inf`: noise must be in [0, 100]"),
        ("014", "`robot.tool_start` = `xyz = [1.5, 0.0, 0.3]"),
        ("015", "arm link `lwr_3_link` starts"),
    ];
    let files = corpus("scene");
    assert_eq!(files.len(), expected.len());
    for (file, (prefix, needle)) in files.iter().zip(expected) {
        assert!(file
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with(prefix)));
        let message = match Scene::from_file(file) {
            Err(err) => err.to_string(),
            Ok(scene) => RapierPlant::from_scene(&scene)
                .expect_err("corpus scene must not build")
                .to_string(),
        };
        assert_clear(file, &message);
        assert!(
            message.contains(needle),
            "{}: `{message}` lacks `{needle}`",
            file.display()
        );
    }
}

#[test]
fn overrides_change_values_and_bad_overrides_name_key_and_value() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes/table.toml");
    let mut scene = Scene::from_file(&path).expect("example scene loads");
    scene.set("table.z", "0.195").expect("valid override");
    assert_eq!(scene.spec().objects["table"].xyz[2], 0.195);
    scene
        .set("objects.table.size.0", "1")
        .expect("integer accepted as float");
    assert_eq!(scene.spec().objects["table"].size, Some([1.0, 0.8, 0.05]));
    scene.set("sensor.cutoff_hz", "50").expect("valid override");
    assert_eq!(scene.spec().sensor.cutoff_hz, 50.0);
    scene.set("robot.tool", "probe").expect("strings need no quotes");
    assert_eq!(scene.spec().robot.tool.as_deref(), Some("probe"));
    for (key, value, needle) in [
        ("tabel.z", "0.1", "unknown section or object `tabel`"),
        ("table.size.7", "0.1", "out of range"),
        ("table.friction", "-1", "must be zero or positive"),
        ("table.z", "high", "invalid type"),
        ("sim.nope", "1", "unknown field"),
    ] {
        let before = scene.spec().clone();
        let message = scene.set(key, value).expect_err("bad override").to_string();
        assert!(message.contains("table.toml"), "`{message}` lacks the file");
        assert!(message.contains(needle), "`{message}` lacks `{needle}`");
        assert!(
            message.contains(key)
                || message.contains(&key.replace("table.", "objects.table."))
                || message.contains("friction"),
            "`{message}` lacks the key"
        );
        assert_eq!(
            &before,
            scene.spec(),
            "a failed override must leave the scene unchanged"
        );
    }
}

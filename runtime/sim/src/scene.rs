//! Scene files (TOML): the robot, simulation settings, the wrist sensor and the objects to touch,
//! with `--set key=value` overrides for experiments.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::Deserialize;

use super::SensorConfig;
use crate::robot::Robot;

/// Why a scene file could not be read, parsed or changed. Every variant names the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene `{file}`: {source}")]
    Io {
        /// The scene file.
        file: String,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// Not TOML, or a field of the wrong type or name.
    #[error("malformed scene `{file}`: {message}")]
    Syntax {
        /// The scene file.
        file: String,
        /// The parser's description.
        message: String,
    },
    /// A well-typed value that makes no physical sense.
    #[error("scene `{file}`: `{key}` = `{value}`: {reason}")]
    Invalid {
        /// The scene file.
        file: String,
        /// The key, as written in an override (`table.size`).
        key: String,
        /// The offending value.
        value: String,
        /// What is wrong.
        reason: String,
    },
    /// An override whose key does not exist in the scene.
    #[error("scene `{file}`: cannot set `{key}` = `{value}`: {reason}")]
    BadOverride {
        /// The scene file.
        file: String,
        /// The key given.
        key: String,
        /// The value given.
        value: String,
        /// What is wrong.
        reason: String,
    },
}

/// `[robot]`: which robot, which tool and sensor frame, where it starts.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// The URDF, relative to the scene file.
    pub urdf: PathBuf,
    /// The tool link (default: the last link of the chain).
    #[serde(default)]
    pub tool: Option<String>,
    /// The link the wrist sensor measures at (default `lwr_flange`).
    #[serde(default = "default_sensor_link")]
    pub sensor: String,
    /// Initial joint positions, rad (default: all zero). With [`RobotSpec::tool_start`] they are
    /// only the seed of its inverse kinematics.
    #[serde(default)]
    pub q0: Option<Vec<f64>>,
    /// The tool link's start pose instead of joint positions: `tool_start = { xyz = [x, y, z],
    /// rpy = [roll, pitch, yaw] }` (m, rad; the world frame, which is the robot's base frame;
    /// both keys required). The start configuration is found by inverse kinematics, from `q0`
    /// when given, else from [`crate::robot::Robot::inverse_kinematics_default_seed`]'s seeds; an
    /// unreachable pose is an error naming `robot.tool_start`.
    #[serde(default)]
    pub tool_start: Option<ToolStart>,
}

/// `robot.tool_start`: where the tool link starts, in the world (= robot base) frame.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolStart {
    /// Position, m.
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw, rad (URDF convention, as for objects).
    pub rpy: [f64; 3],
}

impl ToolStart {
    /// The pose as an isometry.
    pub fn pose(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.xyz[0], self.xyz[1], self.xyz[2]),
            UnitQuaternion::from_euler_angles(self.rpy[0], self.rpy[1], self.rpy[2]),
        )
    }
}

fn default_sensor_link() -> String {
    crate::robot::LWR4_FLANGE.to_owned()
}

/// `[sim]`: integration settings.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimSpec {
    /// Step, s (skillc runs at 1 kHz).
    pub dt: f64,
    /// Gravity in the world (= robot base) frame, m/s².
    pub gravity: [f64; 3],
    /// Stiffness of the tool's contact with fixed objects (tables, drums, end stops), N/m.
    ///
    /// The multibody is rigid, but a real arm is not: the LWR-IV's joints (harmonic drives with
    /// torque sensors, joint stiffness of order 1e4 N m/rad) put a tool-point stiffness of order
    /// 1e4-1e5 N/m in series with every contact, far softer than a steel probe on a table (Hertz
    /// contact, ~1e7 N/m). The series stiffness is the softest element's, so the default,
    /// 5e4 N/m, stands for the arm's own elasticity: a 10 N press sinks 0.2 mm. Left rigid, an
    /// impact's force is the momentum over one step (`m v / dt`), an artefact of the 1 ms step.
    pub contact_stiffness: f64,
    /// Damping ratio of the same contact (1 = critically damped: a probe held by an
    /// impedance-controlled arm does not bounce off a table).
    pub contact_damping_ratio: f64,
}

/// The largest object extent a scene accepts, m (the collision library's arithmetic is not
/// meant for kilometre boxes, and a work cell is a few metres across).
pub(crate) const MAX_OBJECT_EXTENT_M: f64 = 100.0;

/// The default [`SimSpec::contact_stiffness`], N/m.
pub(crate) const DEFAULT_CONTACT_STIFFNESS: f64 = 5e4;

impl Default for SimSpec {
    fn default() -> Self {
        SimSpec {
            dt: 1e-3,
            gravity: [0.0, 0.0, -9.81],
            contact_stiffness: DEFAULT_CONTACT_STIFFNESS,
            contact_damping_ratio: 1.0,
        }
    }
}

/// What an object is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum ObjectKind {
    /// A fixed box (`size`): tables, walls.
    Box,
    /// A fixed cylinder along its local z axis (`radius`, `length`): a curved surface to contour.
    Cylinder,
    /// A spring-loaded push button: a cylindrical cap (`radius`, `height`, `mass`) on a prismatic joint
    /// along its local z axis, pushed up by a spring (`stiffness`, `preload_n`, `damping`) against a
    /// stop, pressable down by `travel` onto a rigid lower stop (a fixed disc under the cap top, which
    /// the tool then rests on).
    Button,
}

/// `[objects.NAME]`: one object of the scene. Which fields apply depends on `kind`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Box, cylinder or button.
    pub kind: ObjectKind,
    /// Centre in the world frame, m (for a button: the cap's centre at rest).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw, rad (URDF convention).
    #[serde(default)]
    pub rpy: [f64; 3],
    /// Coulomb friction coefficient with the tool.
    #[serde(default = "default_friction")]
    pub friction: f64,
    /// Box extents along x, y, z, m.
    #[serde(default)]
    pub size: Option<[f64; 3]>,
    /// Cylinder or button-cap radius, m.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Cylinder length, m.
    #[serde(default)]
    pub length: Option<f64>,
    /// Button-cap height, m.
    #[serde(default)]
    pub height: Option<f64>,
    /// Button-cap mass, kg.
    #[serde(default)]
    pub mass: Option<f64>,
    /// Button spring stiffness, N/m.
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Button spring force at rest (against the upper stop), N.
    #[serde(default)]
    pub preload_n: Option<f64>,
    /// Button viscous damping, N s/m.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Button travel from rest to the lower stop, m.
    #[serde(default)]
    pub travel: Option<f64>,
}

fn default_friction() -> f64 {
    0.5
}

/// An object's shape with every default filled in, as the simulation builds it (in the object's
/// frame, [`ObjectSpec::pose`]; cylinders and button caps along its z axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ObjectShape {
    /// A box of full extents `size`, m (default 0.1 m each).
    Box {
        /// Full extents along x, y, z, m.
        size: [f64; 3],
    },
    /// A cylinder (default radius 0.1 m, length 0.1 m).
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Length, m.
        length: f64,
    },
    /// A button's cap at rest (default radius 0.02 m, height 0.02 m, travel 0.01 m).
    Button {
        /// Cap radius, m.
        radius: f64,
        /// Cap height, m.
        height: f64,
        /// Travel from rest to the lower stop, m.
        travel: f64,
    },
}

impl ObjectSpec {
    /// The object's shape, defaults filled in.
    pub fn shape(&self) -> ObjectShape {
        match self.kind {
            ObjectKind::Box => ObjectShape::Box {
                size: self.size.unwrap_or([0.1; 3]),
            },
            ObjectKind::Cylinder => ObjectShape::Cylinder {
                radius: self.radius.unwrap_or(0.1),
                length: self.length.unwrap_or(0.1),
            },
            ObjectKind::Button => ObjectShape::Button {
                radius: self.radius.unwrap_or(0.02),
                height: self.height.unwrap_or(0.02),
                travel: self.travel.unwrap_or(0.01),
            },
        }
    }

    /// The object's frame in the world (= robot base) frame: `xyz`, then `rpy` (URDF convention).
    pub fn pose(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.xyz[0], self.xyz[1], self.xyz[2]),
            UnitQuaternion::from_euler_angles(self.rpy[0], self.rpy[1], self.rpy[2]),
        )
    }
}

/// A whole scene file, typed.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// The robot.
    pub robot: RobotSpec,
    /// Integration settings.
    #[serde(default)]
    pub sim: SimSpec,
    /// The wrist sensor.
    #[serde(default)]
    pub sensor: SensorConfig,
    /// The objects, by name (sorted, so construction order is deterministic).
    #[serde(default)]
    pub objects: BTreeMap<String, ObjectSpec>,
}

/// A scene read from a file, possibly changed by [`Scene::set`].
#[derive(Debug, Clone)]
pub struct Scene {
    file: String,
    base_dir: PathBuf,
    raw: toml::Table,
    spec: SceneSpec,
}

const SECTIONS: [&str; 4] = ["robot", "sim", "sensor", "objects"];

/// The fields of `[objects.NAME]`: `objects.FIELD` sets one of them in every object.
const OBJECT_FIELDS: [&str; 13] = [
    "kind",
    "xyz",
    "rpy",
    "friction",
    "size",
    "radius",
    "length",
    "height",
    "mass",
    "stiffness",
    "preload_n",
    "damping",
    "travel",
];

impl Scene {
    /// Reads a scene file. Relative paths inside it (the URDF) are relative to the file.
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: file.clone(),
            source,
        })?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::from_toml(&text, &file, &base_dir)
    }

    /// Parses scene text; `file` names it in errors, `base_dir` resolves relative paths.
    pub fn from_toml(text: &str, file: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        let mut raw: toml::Table = text.parse().map_err(|err: toml::de::Error| SceneError::Syntax {
            file: file.to_owned(),
            message: one_line(&err.to_string()),
        })?;
        floats_everywhere(&mut raw);
        let spec = typed(&raw, file)?;
        Ok(Scene {
            file: file.to_owned(),
            base_dir: base_dir.to_path_buf(),
            raw,
            spec,
        })
    }

    /// The scene file's name, as used in errors.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The typed, validated scene.
    pub fn spec(&self) -> &SceneSpec {
        &self.spec
    }

    /// The robot URDF's path, resolved against the scene file's folder.
    pub fn urdf_path(&self) -> PathBuf {
        self.base_dir.join(&self.spec.robot.urdf)
    }

    /// The joint positions the robot starts at \[rad\]: found by inverse kinematics for
    /// `robot.tool_start` (seeded from `robot.q0` when the scene gives it too), else `robot.q0`,
    /// else all zero. The joint count and limits of a `q0` are checked when the simulation is
    /// built; a `tool_start` solution lies inside the limits.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming `robot.tool_start` when the pose is out of reach (the
    /// message says how close the solver came), or `robot.q0` when a seed has the wrong length.
    pub fn start_configuration(&self, robot: &Robot) -> Result<Vec<f64>, SceneError> {
        let spec = &self.spec.robot;
        let Some(tool_start) = &spec.tool_start else {
            return Ok(spec.q0.clone().unwrap_or_else(|| vec![0.0; robot.dof()]));
        };
        let invalid = |key: &str, value: String, reason: String| SceneError::Invalid {
            file: self.file.clone(),
            key: key.to_owned(),
            value,
            reason,
        };
        let target = tool_start.pose();
        let solved = match &spec.q0 {
            Some(seed) if seed.len() != robot.dof() => {
                return Err(invalid(
                    "robot.q0",
                    format!("{seed:?}"),
                    format!(
                        "robot `{}` has {} joints (q0 seeds `robot.tool_start`)",
                        robot.name(),
                        robot.dof()
                    ),
                ))
            }
            Some(seed) => robot.inverse_kinematics(&target, seed),
            None => robot.inverse_kinematics_default_seed(&target),
        };
        solved.map_err(|err| {
            invalid(
                "robot.tool_start",
                format!("xyz = {:?}, rpy = {:?}", tool_start.xyz, tool_start.rpy),
                err.to_string(),
            )
        })
    }

    /// Changes one value, as `skillc … --set key=value` does, and re-validates the scene.
    ///
    /// Keys are dotted paths into the file (`sensor.cutoff_hz`, `objects.table.xyz`); an object's name
    /// may stand for `objects.NAME`, `x`/`y`/`z` for the components of `xyz`, `roll`/`pitch`/`yaw` for
    /// `rpy`, and a number for an array index (`table.size.2`). Values are TOML (`0.1`, `[1, 2, 3]`,
    /// `true`); anything else is taken as a string. On error the scene is left unchanged.
    ///
    /// A key that ends in `+` or `-` changes a number (or each number of an array) by the value
    /// instead of replacing it: `--set table.z+=0.015` raises the table 1.5 cm,
    /// `--set table.xyz-=[0.02, 0, 0]` moves it 2 cm towards the robot (an `rpy` the file leaves
    /// out counts as zero). `objects.FIELD` without an object's name changes that field of every
    /// object: `--set objects.z+=0.03` raises the whole scene 3 cm, as one key.
    pub fn set(&mut self, key: &str, value: &str) -> Result<(), SceneError> {
        let bad = |reason: String| SceneError::BadOverride {
            file: self.file.clone(),
            key: key.to_owned(),
            value: value.to_owned(),
            reason,
        };
        let (plain_key, sign) = match (key.strip_suffix('+'), key.strip_suffix('-')) {
            (Some(k), _) => (k.trim_end(), Some(1.0)),
            (_, Some(k)) => (k.trim_end(), Some(-1.0)),
            _ => (key, None),
        };
        let mut path: Vec<String> = plain_key.split('.').map(str::to_owned).collect();
        if path.iter().any(String::is_empty) {
            return Err(bad("empty key segment".to_owned()));
        }
        let object_names: Vec<String> = self.spec.objects.keys().cloned().collect();
        if !SECTIONS.contains(&path[0].as_str()) {
            if object_names.contains(&path[0]) {
                path.insert(0, "objects".to_owned());
            } else {
                return Err(bad(format!(
                    "unknown section or object `{}` (sections: robot, sim, sensor, objects; objects: {})",
                    path[0],
                    object_names.join(", ")
                )));
            }
        }
        let last = path.len() - 1;
        let alias = match path[last].as_str() {
            "x" => Some(("xyz", 0)),
            "y" => Some(("xyz", 1)),
            "z" => Some(("xyz", 2)),
            "roll" => Some(("rpy", 0)),
            "pitch" => Some(("rpy", 1)),
            "yaw" => Some(("rpy", 2)),
            _ => None,
        };
        if let Some((field, idx)) = alias {
            path[last] = field.to_owned();
            path.push(idx.to_string());
        }
        let mut new_value = parse_value(value);
        if path.last().is_none_or(|seg| seg != "seed") {
            floats_in_value(&mut new_value);
        }
        // `objects.FIELD`: the field of every object.
        let every_object = path[0] == "objects"
            && path
                .get(1)
                .is_some_and(|field| OBJECT_FIELDS.contains(&field.as_str()) && !object_names.contains(field));
        let paths: Vec<Vec<String>> = if every_object {
            if object_names.is_empty() {
                return Err(bad("the scene has no objects".to_owned()));
            }
            object_names
                .iter()
                .map(|object| {
                    let mut each = path.clone();
                    each.insert(1, object.clone());
                    each
                })
                .collect()
        } else {
            vec![path]
        };
        let mut raw = self.raw.clone();
        for path in &paths {
            // An `rpy` the file leaves out is zero: set one of its angles in the zeros.
            if path.len() == 4 && get_path(&raw, &path[..3]).is_none() {
                if let Some(zeros) = default_of(&path[..3]) {
                    set_path(&mut raw, &path[..3], zeros).map_err(bad)?;
                }
            }
            let value = match sign {
                None => new_value.clone(),
                Some(sign) => {
                    let old = get_path(&raw, path).or_else(|| default_of(path));
                    let old = old.ok_or_else(|| bad(format!("`{}` has no value to change", path.join("."))))?;
                    add_scaled(&old, &new_value, sign)
                        .map_err(|reason| bad(format!("`{}`: {reason}", path.join("."))))?
                }
            };
            set_path(&mut raw, path, value).map_err(bad)?;
        }
        let spec = typed(&raw, &self.file).map_err(|err| match err {
            SceneError::Syntax { message, .. } => bad(message),
            other => other,
        })?;
        self.raw = raw;
        self.spec = spec;
        Ok(())
    }
}

fn one_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .filter(|line| !line.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

fn parse_value(text: &str) -> toml::Value {
    format!("v = {text}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut table| table.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.to_owned()))
}

/// Physical quantities are f64: accept `1` where `1.0` is meant (except seeds, which stay integers).
fn floats_everywhere(table: &mut toml::Table) {
    for (key, value) in table.iter_mut() {
        if key != "seed" {
            floats_in_value(value);
        }
    }
}

fn floats_in_value(value: &mut toml::Value) {
    match value {
        toml::Value::Integer(int) => *value = toml::Value::Float(*int as f64),
        toml::Value::Array(items) => items.iter_mut().for_each(floats_in_value),
        toml::Value::Table(table) => floats_everywhere(table),
        _ => {}
    }
}

/// The value at `path` in `table`, if there is one.
fn get_path(table: &toml::Table, path: &[String]) -> Option<toml::Value> {
    let (head, rest) = path.split_first()?;
    let mut value = table.get(head)?;
    for segment in rest {
        value = match value {
            toml::Value::Table(inner) => inner.get(segment)?,
            toml::Value::Array(items) => items.get(segment.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(value.clone())
}

/// The value a file may leave out that a relative change starts from: an object's `rpy` (or
/// one of its angles) is zero.
fn default_of(path: &[String]) -> Option<toml::Value> {
    match path {
        [objects, _, field] if objects == "objects" && field == "rpy" => {
            Some(toml::Value::Array(vec![toml::Value::Float(0.0); 3]))
        }
        [objects, _, field, _] if objects == "objects" && field == "rpy" => Some(toml::Value::Float(0.0)),
        _ => None,
    }
}

/// `old + sign × delta` for a number, or element by element for arrays of numbers of one length.
fn add_scaled(old: &toml::Value, delta: &toml::Value, sign: f64) -> Result<toml::Value, String> {
    let number = |value: &toml::Value| match value {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    match (old, delta) {
        (toml::Value::Array(olds), toml::Value::Array(deltas)) => {
            if olds.len() != deltas.len() {
                return Err(format!(
                    "{} values to change by {} (give one change per value)",
                    olds.len(),
                    deltas.len()
                ));
            }
            olds.iter()
                .zip(deltas)
                .map(|(o, d)| add_scaled(o, d, sign))
                .collect::<Result<Vec<_>, _>>()
                .map(toml::Value::Array)
        }
        (toml::Value::Array(_), _) => Err("an array changes by an array of the same length".to_owned()),
        _ => match (number(old), number(delta)) {
            (Some(o), Some(d)) => Ok(toml::Value::Float(o + sign * d)),
            (None, _) => Err(format!("`{old}` is not a number to change")),
            (_, None) => Err(format!("`{delta}` is not a number to change by")),
        },
    }
}

fn set_path(table: &mut toml::Table, path: &[String], value: toml::Value) -> Result<(), String> {
    let (head, rest) = path.split_first().ok_or_else(|| "empty key".to_owned())?;
    if rest.is_empty() {
        table.insert(head.clone(), value);
        return Ok(());
    }
    let entry = table
        .entry(head.clone())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    set_in_value(entry, rest, value)
}

fn set_in_value(target: &mut toml::Value, path: &[String], value: toml::Value) -> Result<(), String> {
    match target {
        toml::Value::Table(table) => set_path(table, path, value),
        toml::Value::Array(items) => {
            let idx: usize = path[0]
                .parse()
                .map_err(|_| format!("`{}` is not an index into an array", path[0]))?;
            let len = items.len();
            let slot = items
                .get_mut(idx)
                .ok_or_else(|| format!("index {idx} is out of range for an array of {len}"))?;
            if path.len() == 1 {
                *slot = value;
                Ok(())
            } else {
                set_in_value(slot, &path[1..], value)
            }
        }
        _ => Err(format!("`{}` is inside a value that is not a table or array", path[0])),
    }
}

fn typed(raw: &toml::Table, file: &str) -> Result<SceneSpec, SceneError> {
    let spec: SceneSpec = raw
        .clone()
        .try_into()
        .map_err(|err: toml::de::Error| SceneError::Syntax {
            file: file.to_owned(),
            message: one_line(&err.to_string()),
        })?;
    validate(&spec, file)?;
    Ok(spec)
}

fn validate(spec: &SceneSpec, file: &str) -> Result<(), SceneError> {
    let invalid = |key: String, value: String, reason: &str| SceneError::Invalid {
        file: file.to_owned(),
        key,
        value,
        reason: reason.to_owned(),
    };
    if !(spec.sim.dt > 0.0 && spec.sim.dt <= 0.01) {
        return Err(invalid(
            "sim.dt".into(),
            spec.sim.dt.to_string(),
            "the step must be in (0, 0.01] s",
        ));
    }
    if !(spec.sim.contact_stiffness >= 1e2 && spec.sim.contact_stiffness <= 1e9) {
        return Err(invalid(
            "sim.contact_stiffness".into(),
            spec.sim.contact_stiffness.to_string(),
            "the contact stiffness must be in [1e2, 1e9] N/m",
        ));
    }
    if !(spec.sim.contact_damping_ratio > 0.0 && spec.sim.contact_damping_ratio <= 100.0) {
        return Err(invalid(
            "sim.contact_damping_ratio".into(),
            spec.sim.contact_damping_ratio.to_string(),
            "the damping ratio must be in (0, 100]",
        ));
    }
    if spec.sim.gravity.iter().any(|g| !g.is_finite()) {
        return Err(invalid(
            "sim.gravity".into(),
            format!("{:?}", spec.sim.gravity),
            "must be finite",
        ));
    }
    let sensor = &spec.sensor;
    // A wrist sensor's noise is a fraction of a newton; 100 N of noise is a broken sensor, and an
    // infinite one turned every reading into NaN.
    for (field, value, bound) in [
        ("sensor.noise_force_n", sensor.noise_force_n, 100.0),
        ("sensor.noise_torque_nm", sensor.noise_torque_nm, 10.0),
    ] {
        if !(0.0..=bound).contains(&value) {
            return Err(invalid(
                field.into(),
                value.to_string(),
                &format!("noise must be in [0, {bound}]"),
            ));
        }
    }
    if !sensor.cutoff_hz.is_finite() || sensor.bias.iter().any(|b| !b.is_finite()) {
        return Err(invalid(
            "sensor".into(),
            format!("{sensor:?}"),
            "cutoff and bias must be finite",
        ));
    }
    if let Some(q0) = &spec.robot.q0 {
        if q0.iter().any(|q| !q.is_finite()) {
            return Err(invalid("robot.q0".into(), format!("{q0:?}"), "must be finite"));
        }
    }
    if let Some(start) = &spec.robot.tool_start {
        if start.xyz.iter().chain(&start.rpy).any(|v| !v.is_finite()) {
            return Err(invalid(
                "robot.tool_start".into(),
                format!("xyz = {:?}, rpy = {:?}", start.xyz, start.rpy),
                "must be finite",
            ));
        }
    }
    for (name, object) in &spec.objects {
        let key = |field: &str| format!("{name}.{field}");
        if object.xyz.iter().chain(&object.rpy).any(|v| !v.is_finite()) {
            return Err(invalid(
                key("xyz"),
                format!("{:?} {:?}", object.xyz, object.rpy),
                "pose must be finite",
            ));
        }
        if !(object.friction >= 0.0 && object.friction.is_finite()) {
            return Err(invalid(
                key("friction"),
                object.friction.to_string(),
                "must be zero or positive",
            ));
        }
        let positive = |field: &str, value: Option<f64>| -> Result<f64, SceneError> {
            match value {
                None => Err(invalid(
                    key(field),
                    "(missing)".into(),
                    &format!("a {:?} needs `{field}`", object.kind).to_lowercase(),
                )),
                Some(v) if v > MAX_OBJECT_EXTENT_M && ["radius", "length", "height", "travel"].contains(&field) => {
                    Err(invalid(
                        key(field),
                        v.to_string(),
                        &format!("larger than {MAX_OBJECT_EXTENT_M} m: a work cell is a few metres across"),
                    ))
                }
                Some(v) if v > 0.0 && v.is_finite() => Ok(v),
                Some(v) => Err(invalid(key(field), v.to_string(), "must be positive")),
            }
        };
        match object.kind {
            ObjectKind::Box => {
                let size = object
                    .size
                    .ok_or_else(|| invalid(key("size"), "(missing)".into(), "a box needs `size`"))?;
                if size.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
                    return Err(invalid(key("size"), format!("{size:?}"), "extents must be positive"));
                }
                if size.iter().any(|s| *s > MAX_OBJECT_EXTENT_M) {
                    return Err(invalid(
                        key("size"),
                        format!("{size:?}"),
                        &format!("larger than {MAX_OBJECT_EXTENT_M} m: a work cell is a few metres across"),
                    ));
                }
            }
            ObjectKind::Cylinder => {
                positive("radius", object.radius)?;
                positive("length", object.length)?;
            }
            ObjectKind::Button => {
                positive("radius", object.radius)?;
                positive("height", object.height)?;
                positive("mass", object.mass)?;
                positive("stiffness", object.stiffness)?;
                positive("travel", object.travel)?;
                let preload = object.preload_n.unwrap_or(0.0);
                let damping = object.damping.unwrap_or(0.0);
                if !(preload >= 0.0 && damping >= 0.0) {
                    return Err(invalid(
                        key("preload_n"),
                        format!("{preload} / {damping}"),
                        "preload and damping must be zero or positive",
                    ));
                }
            }
        }
    }
    Ok(())
}

//! `skillc eval --robot NAME`: the same trials on another shipped arm. Each trial's scene is
//! loaded as written (with its variant's overrides), the tool's start pose is taken from the
//! scene's own robot (forward kinematics of its start configuration: for the shipped scenes the
//! LWR-IV's `q0`, the demonstrated start), and the named robot replaces it, starting with its
//! tool at that same pose (inverse kinematics from its elbow-up seed). Objects, sensor and
//! simulation settings stay; the skills are the ones learned from the LWR-IV's demonstrations.

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use skill_runtime::robot::{BuiltinRobot, Robot};

use skill_kit::load::{error_chain, load_scene, Failure};

/// A robot to swap into every trial's scene.
#[derive(Debug, Clone)]
pub struct Swap {
    /// The shipped robot.
    pub robot: BuiltinRobot,
    /// Its URDF file, absolute (scenes resolve relative paths against their own folder).
    pub urdf: PathBuf,
    /// The model, for the inverse kinematics.
    model: Robot,
}

impl Swap {
    /// The shipped robot called `name`, its URDF found under `root` (the defaults' root).
    ///
    /// # Errors
    /// A usage error naming the shipped robots when there is none of that name.
    pub fn new(name: &str, root: &Path) -> Result<Swap, Failure> {
        let robot = BuiltinRobot::find(name).ok_or_else(|| {
            Failure::Usage(format!(
                "unknown robot `{name}` for --robot (shipped: {})",
                BuiltinRobot::names()
            ))
        })?;
        let mut urdf = root.join(robot.path);
        if urdf.is_relative() {
            let here = std::env::current_dir()
                .map_err(|err| Failure::Usage(format!("cannot read the current folder: {err}")))?;
            urdf = here.join(urdf);
        }
        let model = Robot::from_urdf_file(&urdf, Some(robot.tool)).map_err(|err| Failure::Input(error_chain(&err)))?;
        Ok(Swap { robot, urdf, model })
    }

    /// The overrides that put this robot into the scene at `scene_path` with `sets` applied,
    /// its tool where the scene's own robot starts its tool; none when the scene already holds
    /// this robot.
    ///
    /// # Errors
    /// The scene's errors, or the pose out of this robot's reach (named).
    pub fn sets(&self, scene_path: &Path, sets: &[String]) -> Result<Vec<String>, String> {
        let message = |failure: Failure| match failure {
            Failure::Input(message) | Failure::Usage(message) => message,
            Failure::Closed => "standard output closed".to_string(),
        };
        let scene = load_scene(scene_path, sets).map_err(message)?;
        let own = Robot::from_urdf_file(&scene.urdf_path(), scene.spec().robot.tool.as_deref())
            .map_err(|err| error_chain(&err))?;
        if own.name() == self.model.name() {
            return Ok(Vec::new());
        }
        let start = scene.start_configuration(&own).map_err(|err| error_chain(&err))?;
        let (tool, _, _) = own.evaluate(&start);
        let q0 = self.start(&tool).map_err(|err| {
            format!(
                "`{}` cannot start its tool where `{}` does in `{}`: {err}",
                self.robot.name,
                own.name(),
                scene.file()
            )
        })?;
        let q0: Vec<String> = q0.iter().map(|q| format!("{q:?}")).collect();
        Ok(vec![
            format!("robot.urdf={}", toml_string(&self.urdf.display().to_string())),
            format!("robot.tool={}", self.robot.tool),
            format!("robot.sensor={}", self.robot.sensor),
            format!("robot.q0=[{}]", q0.join(", ")),
        ])
    }

    /// This robot's joint angles with its tool at `tool` (base frame).
    fn start(&self, tool: &Isometry3<f64>) -> Result<Vec<f64>, String> {
        self.model
            .inverse_kinematics_default_seed(tool)
            .map_err(|err| err.to_string())
    }
}

/// A TOML basic string (a path with backslashes or quotes stays one value).
fn toml_string(text: &str) -> String {
    toml::Value::String(text.to_owned()).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
    }

    /// The iiwa takes the LWR-IV's place with its tool where the LWR-IV's `q0` puts it, also
    /// for a variant that raises the start with its own `q0`.
    #[test]
    fn the_swapped_robot_starts_its_tool_where_the_scene_robot_does() {
        let swap = Swap::new("iiwa14", &root()).expect("shipped");
        let scene = root().join("examples/scenes/table.toml");
        let raised = "robot.q0=[0.0, -0.454318493, 0.0, 1.431100155, 0.0, -1.256174005, 0.0]".to_string();
        for variant in [vec![], vec!["table.z=0.305".to_string(), raised]] {
            let extra = swap.sets(&scene, &variant).expect("reachable");
            assert_eq!(extra.len(), 4, "{extra:?}");
            let lwr_scene = load_scene(&scene, &variant).expect("scene");
            let lwr = Robot::from_urdf_file(&lwr_scene.urdf_path(), Some("probe_tip")).expect("lwr");
            let (lwr_tool, _, _) = lwr.evaluate(&lwr_scene.start_configuration(&lwr).expect("q0"));
            let all: Vec<String> = variant.iter().chain(&extra).cloned().collect();
            let iiwa_scene = load_scene(&scene, &all).expect("swapped scene");
            assert_eq!(iiwa_scene.urdf_path(), swap.urdf);
            assert_eq!(iiwa_scene.spec().robot.sensor, "iiwa_flange");
            let q = iiwa_scene.start_configuration(&swap.model).expect("q0");
            let (iiwa_tool, _, _) = swap.model.evaluate(&q);
            let miss = (iiwa_tool.translation.vector - lwr_tool.translation.vector).norm();
            assert!(miss < 1e-6, "{miss} m");
            assert!(iiwa_tool.rotation.angle_to(&lwr_tool.rotation) < 1e-5);
        }
    }

    #[test]
    fn a_scene_that_already_holds_the_robot_is_left_as_it_is() {
        let swap = Swap::new("iiwa14", &root()).expect("shipped");
        let scene = root().join("examples/scenes/iiwa14/button.toml");
        assert_eq!(swap.sets(&scene, &[]), Ok(Vec::new()));
        let lwr = Swap::new("lwr4", &root()).expect("shipped");
        assert_eq!(
            lwr.sets(&root().join("examples/scenes/button.toml"), &[]),
            Ok(Vec::new())
        );
        assert_eq!(lwr.sets(&scene, &[]).map(|sets| sets.len()), Ok(4));
    }

    #[test]
    fn an_unknown_robot_names_the_shipped_ones() {
        match Swap::new("panda", &root()) {
            Err(Failure::Usage(message)) => {
                assert_eq!(
                    message,
                    "unknown robot `panda` for --robot (shipped: lwr4, iiwa14, fr3)"
                )
            }
            other => panic!("expected a usage error, got {:?}", other.map(|swap| swap.robot)),
        }
    }
}

//! The robots shipped with skillc (`examples/robots/*.urdf`, each written by its generator there):
//! their URDF compiled in, the tool link the skills act with and the link the wrist sensor
//! measures at, by a short name (`lwr4`, `iiwa14`, `fr3`) that `skillc eval --robot` takes.

use super::{Robot, RobotError};

/// A robot shipped with skillc.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuiltinRobot {
    /// The short name (`skillc eval --robot NAME`).
    pub name: &'static str,
    /// What it is, in words.
    pub title: &'static str,
    /// The URDF's path relative to the repository root.
    pub path: &'static str,
    /// The URDF's text.
    pub urdf: &'static str,
    /// The tool link: the centre of the probe's spherical tip.
    pub tool: &'static str,
    /// The flange link, where the wrist force/torque sensor sits.
    pub sensor: &'static str,
}

/// The KUKA LWR IV with the probe (`examples/robots/lwr4.urdf`): the arm the standard skills
/// were demonstrated on and the shipped scenes place.
pub const LWR4: BuiltinRobot = BuiltinRobot {
    name: "lwr4",
    title: "KUKA LWR IV with a probe",
    path: "examples/robots/lwr4.urdf",
    urdf: super::LWR4_URDF,
    tool: super::LWR4_TOOL,
    sensor: super::LWR4_FLANGE,
};

/// The KUKA LBR iiwa 14 R820 with the same probe (`examples/robots/iiwa14.urdf`).
pub const IIWA14: BuiltinRobot = BuiltinRobot {
    name: "iiwa14",
    title: "KUKA LBR iiwa 14 R820 with the same probe",
    path: "examples/robots/iiwa14.urdf",
    urdf: include_str!("../../../examples/robots/iiwa14.urdf"),
    tool: "probe_tip",
    sensor: "iiwa_flange",
};

/// The Franka Research 3 with the same probe on its flange (`examples/robots/fr3.urdf`).
pub const FR3: BuiltinRobot = BuiltinRobot {
    name: "fr3",
    title: "Franka Research 3 with the same probe",
    path: "examples/robots/fr3.urdf",
    urdf: include_str!("../../../examples/robots/fr3.urdf"),
    tool: "probe_tip",
    sensor: "fr3_wrist_sensor",
};

/// Every shipped robot.
pub const BUILTIN_ROBOTS: [BuiltinRobot; 3] = [LWR4, IIWA14, FR3];

impl BuiltinRobot {
    /// The shipped robot called `name`, if any.
    pub fn find(name: &str) -> Option<BuiltinRobot> {
        BUILTIN_ROBOTS.into_iter().find(|robot| robot.name == name)
    }

    /// The shipped robots' names, comma separated (for messages).
    pub fn names() -> String {
        BUILTIN_ROBOTS.map(|robot| robot.name).join(", ")
    }

    /// The robot model with its tool link.
    ///
    /// # Errors
    /// Only if the compiled-in URDF were broken (a test loads each).
    pub fn load(&self) -> Result<Robot, RobotError> {
        Robot::from_urdf_str(self.urdf, Some(self.tool))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_robot_loads_with_its_tool_and_sensor_links() {
        for builtin in BUILTIN_ROBOTS {
            let robot = builtin.load().expect("shipped urdf loads");
            assert_eq!(robot.dof(), 7, "{}", builtin.name);
            robot.require_link(builtin.sensor).expect("sensor link");
            assert_eq!(BuiltinRobot::find(builtin.name), Some(builtin));
        }
        assert_eq!(BuiltinRobot::find("ur5"), None);
        assert_eq!(BuiltinRobot::names(), "lwr4, iiwa14, fr3");
    }

    /// The elbow-up seed follows each arm's axis directions: the same physical pose (probe down,
    /// 0.55 m in front of the base) on both shipped arms.
    #[test]
    fn the_elbow_up_seed_is_the_same_pose_on_both_arms() {
        let lwr = LWR4.load().expect("lwr4");
        let iiwa = IIWA14.load().expect("iiwa14");
        let lwr_seed = lwr.elbow_up_seed().expect("7 joints");
        let iiwa_seed = iiwa.elbow_up_seed().expect("7 joints");
        assert_eq!(lwr_seed, super::super::LWR4_ELBOW_UP);
        assert_eq!(iiwa_seed[1], -lwr_seed[1]);
        assert_eq!(iiwa_seed[3], -lwr_seed[3]);
        assert_eq!(iiwa_seed[5], -lwr_seed[5]);
        let (iiwa_tool, _, _) = iiwa.evaluate(&iiwa_seed);
        let down = iiwa_tool.rotation * nalgebra::Vector3::z();
        assert!(down.z < -0.999, "iiwa tool z axis {down:?}");
        assert!(iiwa_tool.translation.vector.x > 0.4, "{:?}", iiwa_tool.translation);
    }

    /// On the FR3 (joint 2 turning the other way round, joint 6 folded by π at zero: the flange
    /// points down at q = 0) the seed is the same elbow-up pose too, every joint inside its range.
    #[test]
    fn the_fr3_elbow_up_seed_unfolds_its_wrist() {
        let fr3 = FR3.load().expect("fr3");
        let seed = fr3.elbow_up_seed().expect("7 joints");
        let lwr = super::super::LWR4_ELBOW_UP;
        assert_eq!(seed[1], -lwr[1]);
        assert_eq!(seed[3], -lwr[3]);
        assert_eq!(seed[5], lwr[5] + std::f64::consts::PI);
        for (value, (lower, upper)) in seed.iter().zip(fr3.position_limits()) {
            assert!(lower < *value && *value < upper, "{seed:?}");
        }
        let (tool, _, _) = fr3.evaluate(&seed);
        let down = tool.rotation * nalgebra::Vector3::z();
        assert!(down.z < -0.999, "fr3 tool z axis {down:?}");
        assert!(tool.translation.vector.x > 0.4, "{:?}", tool.translation);
    }
}

//! A summary of a robot at one configuration, for `skillc robot` (JSON keys fixed by issue 3).

use std::fmt::Write as _;

use serde::Serialize;

use super::{Robot, RobotError};

/// One joint of an [`Inspection`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointSummary {
    /// URDF joint name.
    pub name: String,
    /// Unit axis in the joint frame.
    pub axis: [f64; 3],
    /// Lower limit, rad (null in JSON when unlimited).
    pub lower: f64,
    /// Upper limit, rad (null in JSON when unlimited).
    pub upper: f64,
    /// Velocity limit, rad/s.
    pub velocity: f64,
    /// Torque limit, N m.
    pub effort: f64,
}

/// The chain and, at `q`, the tool pose, tool Jacobian and gravity torques.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Inspection {
    /// Robot name.
    pub robot: String,
    /// Tool link name.
    pub tool_link: String,
    /// Number of joints.
    pub dof: usize,
    /// The movable joints, base to tip.
    pub joints: Vec<JointSummary>,
    /// The configuration, rad.
    pub q: Vec<f64>,
    /// Tool link origin in the base frame, m.
    pub tool_position: [f64; 3],
    /// Tool orientation in the base frame, unit quaternion `[w, x, y, z]`.
    pub tool_quaternion_wxyz: [f64; 4],
    /// Geometric Jacobian at the tool link origin, base frame: 6 rows (vx vy vz wx wy wz) of `dof`.
    pub jacobian: Vec<Vec<f64>>,
    /// Gravity torques g(q), N m: the torques that hold the arm still.
    pub gravity_torque: Vec<f64>,
    /// Mass moved by each joint (its body), kg (text output only).
    #[serde(skip)]
    pub body_masses: Vec<f64>,
    /// What loading decided on the user's behalf (held branches, ignored base inertia, default
    /// limits); lines starting with `warning:` deserve a look.
    pub notes: Vec<String>,
}

impl Robot {
    /// Summarises the robot at `q` (all zero when `None`).
    pub fn inspect(&self, q: Option<&[f64]>) -> Result<Inspection, RobotError> {
        let zeros = vec![0.0; self.dof()];
        let q = q.unwrap_or(&zeros);
        self.check_dof(q.len())?;
        if let Some(idx) = q.iter().position(|v| !v.is_finite()) {
            return Err(RobotError::NonFinite {
                item: format!("q{}", idx + 1),
            });
        }
        let (tool, jacobian, gravity) = self.evaluate(q);
        let rot = tool.rotation;
        Ok(Inspection {
            robot: self.name.clone(),
            tool_link: self.links[self.tool_link].name.clone(),
            dof: self.dof(),
            joints: self
                .joints
                .iter()
                .map(|joint| JointSummary {
                    name: joint.name.clone(),
                    axis: [joint.axis.x, joint.axis.y, joint.axis.z],
                    lower: joint.lower,
                    upper: joint.upper,
                    velocity: joint.velocity,
                    effort: joint.effort,
                })
                .collect(),
            q: q.to_vec(),
            tool_position: tool.translation.vector.into(),
            tool_quaternion_wxyz: [rot.w, rot.i, rot.j, rot.k],
            jacobian: jacobian.row_iter().map(|row| row.iter().copied().collect()).collect(),
            gravity_torque: gravity.iter().copied().collect(),
            body_masses: self.bodies.iter().map(|body| body.mass).collect(),
            notes: self.notes.clone(),
        })
    }
}

impl Inspection {
    /// A human-readable table.
    pub fn to_text(&self) -> String {
        let mut out = String::new();
        // Writing to a String cannot fail.
        let _ = writeln!(
            out,
            "robot `{}`: {} joints, tool link `{}`",
            self.robot, self.dof, self.tool_link
        );
        let _ = writeln!(
            out,
            "{:<16} {:>18} {:>9} {:>9} {:>9} {:>8} {:>9}",
            "joint", "axis", "lower", "upper", "vel", "effort", "mass kg"
        );
        for (joint, mass) in self.joints.iter().zip(&self.body_masses) {
            let axis = format!("[{:.3} {:.3} {:.3}]", joint.axis[0], joint.axis[1], joint.axis[2]);
            let _ = writeln!(
                out,
                "{:<16} {:>18} {:>9.4} {:>9.4} {:>9.4} {:>8.1} {:>9.3}",
                joint.name, axis, joint.lower, joint.upper, joint.velocity, joint.effort, mass
            );
        }
        let _ = writeln!(out, "q [rad]            {:?}", self.q);
        let p = self.tool_position;
        let _ = writeln!(out, "tool position [m]  [{:.6} {:.6} {:.6}]", p[0], p[1], p[2]);
        let w = self.tool_quaternion_wxyz;
        let _ = writeln!(
            out,
            "tool quat (wxyz)   [{:.6} {:.6} {:.6} {:.6}]",
            w[0], w[1], w[2], w[3]
        );
        let _ = writeln!(out, "jacobian (base frame, rows vx vy vz wx wy wz):");
        for row in &self.jacobian {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:>9.4}")).collect();
            let _ = writeln!(out, "  {}", cells.join(" "));
        }
        let cells: Vec<String> = self.gravity_torque.iter().map(|v| format!("{v:.4}")).collect();
        let _ = writeln!(out, "gravity torque [N m] [{}]", cells.join(", "));
        for note in &self.notes {
            let _ = writeln!(out, "note: {note}");
        }
        out
    }
}

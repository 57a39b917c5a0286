//! The limits the safety supervisor enforces, their documented defaults, and how a skill, a task
//! step or the command line tightens or loosens them.

use std::fmt;

/// An axis-aligned box in the base frame \[m\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Workspace {
    /// Lower corner `[x, y, z]` \[m\].
    pub min: [f64; 3],
    /// Upper corner `[x, y, z]` \[m\].
    pub max: [f64; 3],
}

impl Workspace {
    /// The smallest box holding every point, grown by `margin_m` on every side; `None` for no points.
    pub fn around<'p>(points: impl IntoIterator<Item = &'p [f64; 3]>, margin_m: f64) -> Option<Self> {
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        let mut any = false;
        for point in points {
            if point.iter().any(|v| !v.is_finite()) {
                continue;
            }
            any = true;
            for axis in 0..3 {
                min[axis] = min[axis].min(point[axis]);
                max[axis] = max[axis].max(point[axis]);
            }
        }
        any.then(|| Workspace {
            min: min.map(|v| v - margin_m),
            max: max.map(|v| v + margin_m),
        })
    }

    /// How far `p` lies outside the box \[m\] (0 inside).
    pub fn outside_by(&self, p: [f64; 3]) -> f64 {
        let squared: f64 = (0..3)
            .map(|axis| {
                let d = (self.min[axis] - p[axis]).max(p[axis] - self.max[axis]).max(0.0);
                d * d
            })
            .sum();
        squared.sqrt()
    }
}

/// What the supervisor checks every tick. A value of `f64::INFINITY` switches a check off; the
/// non-finite check cannot be switched off.
///
/// The defaults ([`Limits::for_skill`]) follow what collaborative arms promise: a collision
/// threshold on the contact wrench above the task's own forces (libfranka's collision behaviour),
/// Cartesian and joint speed monitoring (KUKA's safety configuration; 250 mm/s is the reduced
/// speed of ISO 10218-1 for hand guiding and collaborative operation), joint-limit margins, drive
/// saturation, a tracking-error monitor on position-controlled axes, and a workspace box.
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// Largest magnitude of the force the tool applies \[N\].
    pub force_n: f64,
    /// Largest magnitude of the moment the tool applies about the tool point \[N m\].
    pub moment_nm: f64,
    /// Largest tool-point linear speed \[m/s\].
    pub tool_speed_mps: f64,
    /// Largest tool angular speed \[rad/s\].
    pub tool_angular_speed_radps: f64,
    /// Smallest distance of any joint from its position limits \[rad or m\].
    pub joint_margin: f64,
    /// Largest joint speed as a fraction of the robot file's velocity limit.
    pub joint_speed_fraction: f64,
    /// Longest time any joint torque may stay at its effort limit \[s\].
    pub torque_saturation_s: f64,
    /// Largest position error along the position-controlled axes of the compliant frame \[m\].
    pub tracking_error_m: f64,
    /// Largest orientation error about the position-controlled rotation axes \[rad\].
    pub tracking_error_rad: f64,
    /// Largest contact force on an arm link other than the tool \[N\]
    /// ([`crate::plant::Observation::arm_contact_n`]).
    pub arm_contact_n: f64,
    /// Where the tool point may go (base frame); `None` for anywhere.
    pub workspace: Option<Workspace>,
}

/// The margin around the learned motions that makes the default workspace \[m\]: scene changes
/// of ±10 cm and searches of a few centimetres stay well inside it.
pub const WORKSPACE_MARGIN_M: f64 = 0.3;

/// The reduced Cartesian speed of ISO 10218-1 \[m/s\], the default tool speed limit.
pub const REDUCED_SPEED_MPS: f64 = 0.25;

/// A torque counts as saturated at this fraction of the joint's effort limit.
pub const SATURATION_FRACTION: f64 = 0.99;

/// The default limit on the contact force on an arm link other than the tool \[N\]. Skills
/// touch the world with the tool only, so this is not a tolerance for pushing but the smallest
/// force that is clearly a contact: the force that stops pre-positioning (5 N, well above a wrist
/// sensor's noise). In the simulation the value is noise-free and a link moving at 0.1 m/s into
/// a 5e4 N/m contact passes it within about a millisecond (0.1 mm of penetration); a real arm's
/// estimate from its joint torques is noisier (a few newtons at the links for the LWR-IV), which
/// is what the limit's name (`arm_contact`) is there to loosen.
pub const ARM_CONTACT_N: f64 = 5.0;

impl Limits {
    /// The default limits for a skill whose learned forces and thresholds peak at
    /// `learned_peak_force_n` and whose learned motions stay inside `workspace`:
    ///
    /// - contact force: `max(3 f, f + 30 N)` for the learned peak `f`, so a skill can press what
    ///   it learned with room for transients, while an impact several times that is a collision;
    /// - moment: the force limit on a 10 cm lever, at least 10 N m;
    /// - tool speed 0.25 m/s ([`REDUCED_SPEED_MPS`]), angular speed 2 rad/s;
    /// - joints: 1° from a position limit, the robot file's velocity limit, effort limits held
    ///   for at most 100 ms;
    /// - tracking: 5 cm and 0.35 rad (20°) on position-controlled axes (at the default 2000 N/m
    ///   a 5 cm error is 100 N of push: something the arm did not expect is in the way);
    /// - arm contact: 5 N on any link other than the tool ([`ARM_CONTACT_N`]);
    /// - workspace: the learned motions' box grown by [`WORKSPACE_MARGIN_M`].
    pub fn for_skill(learned_peak_force_n: f64, workspace: Option<Workspace>) -> Self {
        let peak = if learned_peak_force_n.is_finite() {
            learned_peak_force_n.max(0.0)
        } else {
            0.0
        };
        let force_n = (3.0 * peak).max(peak + 30.0);
        Limits {
            force_n,
            moment_nm: (0.1 * force_n).max(10.0),
            tool_speed_mps: REDUCED_SPEED_MPS,
            tool_angular_speed_radps: 2.0,
            joint_margin: 1f64.to_radians(),
            joint_speed_fraction: 1.0,
            torque_saturation_s: 0.1,
            tracking_error_m: 0.05,
            tracking_error_rad: 0.35,
            arm_contact_n: ARM_CONTACT_N,
            workspace,
        }
    }

    /// Sets one limit by its name in the language and on the command line (one of
    /// [`LIMIT_NAMES`]: `force`, `moment`, `speed`, `angular_speed`, `joint_margin`,
    /// `joint_speed`, `saturation`, `tracking`, `tracking_angle`, `arm_contact`), in SI units.
    /// `inf` switches a check off.
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), LimitError> {
        if value.is_nan() || value <= 0.0 {
            return Err(LimitError::NotPositive {
                name: name.to_string(),
                value,
            });
        }
        // Only the table's names: a name below that it lacks cannot be set.
        if skill_ir::limit_spec(name).is_none() {
            return Err(LimitError::Unknown { name: name.to_string() });
        }
        let slot = match name {
            "force" => &mut self.force_n,
            "moment" => &mut self.moment_nm,
            "speed" => &mut self.tool_speed_mps,
            "angular_speed" => &mut self.tool_angular_speed_radps,
            "joint_margin" => &mut self.joint_margin,
            "joint_speed" => &mut self.joint_speed_fraction,
            "saturation" => &mut self.torque_saturation_s,
            "tracking" => &mut self.tracking_error_m,
            "tracking_angle" => &mut self.tracking_error_rad,
            "arm_contact" => &mut self.arm_contact_n,
            _ => return Err(LimitError::Unknown { name: name.to_string() }),
        };
        // `inf` switches a check off; the joint margin is a smallest distance, so off is 0.
        *slot = if name == "joint_margin" && value.is_infinite() {
            0.0
        } else {
            value
        };
        Ok(())
    }

    /// Scales the force and moment limits up by a task step's force scale (it pushes harder on
    /// purpose); a scale below 1 keeps the defaults, which already bound the learned forces.
    pub fn scale_force(&mut self, factor: f64) {
        if factor.is_finite() && factor > 1.0 {
            self.force_n *= factor;
            self.moment_nm *= factor;
        }
    }
}

/// The names [`Limits::set`] accepts, with their dimensions (SI units) and what they bound: the
/// IR's one table, which the compiler checks `limits { }` blocks against
/// (`limit_table_and_set_agree` checks that `set` takes exactly these).
pub const LIMIT_NAMES: &[skill_ir::LimitSpec] = skill_ir::LIMITS;

/// A limit that cannot be set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LimitError {
    /// Not one of [`LIMIT_NAMES`].
    #[error("unknown limit `{name}` (known: {})", known_names())]
    Unknown {
        /// The name given.
        name: String,
    },
    /// Zero, negative or NaN.
    #[error("limit `{name}` must be a positive number (or inf to switch it off), got {value}")]
    NotPositive {
        /// The limit's name.
        name: String,
        /// The value given.
        value: f64,
    },
}

fn known_names() -> String {
    LIMIT_NAMES
        .iter()
        .map(|spec| format!("`{}`", spec.name))
        .collect::<Vec<_>>()
        .join(", ")
}

impl fmt::Display for Workspace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "x {:.3}..{:.3}, y {:.3}..{:.3}, z {:.3}..{:.3} m",
            self.min[0], self.max[0], self.min[1], self.max[1], self.min[2], self.max[2]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::safety::Quantity;

    #[test]
    fn force_limit_keeps_room_above_the_learned_peak() {
        assert_eq!(Limits::for_skill(4.0, None).force_n, 34.0);
        assert_eq!(Limits::for_skill(20.0, None).force_n, 60.0);
        // Nothing learned: a collision threshold of 30 N.
        assert_eq!(Limits::for_skill(f64::NAN, None).force_n, 30.0);
    }

    #[test]
    fn workspace_grows_by_the_margin_and_measures_distance_outside() {
        let points = [[0.0, 0.0, 0.5], [0.2, 0.1, 0.3]];
        let box_ = Workspace::around(points.iter(), 0.1).expect("points");
        for (got, want) in box_.min.iter().zip([-0.1, -0.1, 0.2]) {
            assert!((got - want).abs() < 1e-12);
        }
        assert!((box_.max[0] - 0.3).abs() < 1e-12);
        assert_eq!(box_.outside_by([0.0, 0.0, 0.4]), 0.0);
        assert!((box_.outside_by([0.0, 0.0, 0.1]) - 0.1).abs() < 1e-12);
        assert!(Workspace::around([].iter(), 0.1).is_none());
    }

    #[test]
    fn inf_switches_every_check_off() {
        let mut limits = Limits::for_skill(10.0, None);
        for spec in LIMIT_NAMES {
            limits
                .set(spec.name, f64::INFINITY)
                .unwrap_or_else(|err| panic!("{}: {err}", spec.name));
        }
        // The one smallest-distance limit is off at 0, every largest-value limit at inf.
        assert_eq!(limits.joint_margin, 0.0);
        assert!(limits.force_n.is_infinite() && limits.tool_speed_mps.is_infinite());
        assert!(limits.tracking_error_m.is_infinite() && limits.torque_saturation_s.is_infinite());
    }

    #[test]
    fn limit_table_and_set_agree() {
        // Every name of the table sets exactly one field, each a different one.
        let base = Limits::for_skill(10.0, None);
        let mut changed = Vec::new();
        for spec in LIMIT_NAMES {
            let mut limits = base.clone();
            limits
                .set(spec.name, 1234.5)
                .unwrap_or_else(|err| panic!("{}: {err}", spec.name));
            let fields = [
                limits.force_n,
                limits.moment_nm,
                limits.tool_speed_mps,
                limits.tool_angular_speed_radps,
                limits.joint_margin,
                limits.joint_speed_fraction,
                limits.torque_saturation_s,
                limits.tracking_error_m,
                limits.tracking_error_rad,
                limits.arm_contact_n,
            ];
            let set: Vec<usize> = (0..fields.len()).filter(|&i| fields[i] == 1234.5).collect();
            assert_eq!(set.len(), 1, "`{}` sets {set:?}", spec.name);
            assert!(
                !changed.contains(&set[0]),
                "`{}` sets a field another name sets",
                spec.name
            );
            changed.push(set[0]);
        }
        // Every field is reached by a name of the table (and `set` refuses names outside it).
        assert_eq!(changed.len(), 10, "every settable field has a name in the table");
        // Each quantity a reflex names as loosenable is in the table.
        for quantity in [
            Quantity::ContactForce,
            Quantity::ContactMoment,
            Quantity::ToolSpeed,
            Quantity::ToolAngularSpeed,
            Quantity::JointMargin,
            Quantity::JointSpeed,
            Quantity::TorqueSaturation,
            Quantity::TrackingError,
            Quantity::TrackingAngle,
            Quantity::ArmContact,
        ] {
            let name = quantity.limit_name().expect("a limit name");
            assert!(skill_ir::limit_spec(name).is_some(), "`{name}`");
        }
    }

    #[test]
    fn set_rejects_unknown_names_and_non_positive_values() {
        let mut limits = Limits::for_skill(10.0, None);
        limits.set("speed", 0.1).expect("known");
        assert_eq!(limits.tool_speed_mps, 0.1);
        limits.set("force", f64::INFINITY).expect("inf switches off");
        assert!(matches!(limits.set("sped", 1.0), Err(LimitError::Unknown { .. })));
        assert!(matches!(limits.set("force", -1.0), Err(LimitError::NotPositive { .. })));
        assert!(matches!(
            limits.set("force", f64::NAN),
            Err(LimitError::NotPositive { .. })
        ));
    }
}

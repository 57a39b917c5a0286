//! The wrench's conventions as data: the axes, the sign and the bias a demonstration's force
//! columns were found to have, and the evidence ([`WrenchReport`], stored in the learned file).

use std::fmt;

use serde::{Deserialize, Serialize};

/// The axes a file's force and moment columns are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WrenchFrame {
    /// The robot base frame, like the pose (skillc's own files, the simulated sensor).
    Base,
    /// The sensor's axes, taken to be the flange's: a wrist sensor's raw reading. Rotated into
    /// the base frame by the flange orientation of each sample.
    Sensor,
}

impl WrenchFrame {
    /// `base` or `sensor`, as the flag and the file header write it.
    pub fn name(self) -> &'static str {
        match self {
            WrenchFrame::Base => "base",
            WrenchFrame::Sensor => "sensor",
        }
    }
}

impl std::str::FromStr for WrenchFrame {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "base" | "world" => Ok(WrenchFrame::Base),
            "sensor" | "flange" | "tool" => Ok(WrenchFrame::Sensor),
            other => Err(format!("`{other}` is not a wrench frame: write `base` or `sensor`")),
        }
    }
}

/// Which of the two opposite wrenches a file stores.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceSign {
    /// The wrench the environment exerts on the tool, what a wrist sensor reports (skillc's
    /// convention).
    OnTool,
    /// The wrench the robot applies to the environment; negated on reading.
    Applied,
}

impl ForceSign {
    /// `on-tool` or `applied`, as the flag and the file header write it.
    pub fn name(self) -> &'static str {
        match self {
            ForceSign::OnTool => "on-tool",
            ForceSign::Applied => "applied",
        }
    }
}

impl std::str::FromStr for ForceSign {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        match text.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "on-tool" | "measured" | "sensor" => Ok(ForceSign::OnTool),
            "applied" => Ok(ForceSign::Applied),
            other => Err(format!("`{other}` is not a force sign: write `on-tool` or `applied`")),
        }
    }
}

/// What is known about a file's wrench before looking at it; `None` is detected.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WrenchDeclaration {
    /// The axes of the force and moment columns.
    pub frame: Option<WrenchFrame>,
    /// Which wrench the columns hold.
    pub sign: Option<ForceSign>,
    /// For a sensor-frame wrench: the angle the sensor's axes are turned from the flange's about
    /// the flange z, the tool axis \[°\] (a sensor mounted with its x between two bolts of
    /// the flange pattern, or the other way round).
    pub sensor_turn_deg: Option<f64>,
}

impl WrenchDeclaration {
    /// Each field of `self`, or else `other`'s: the caller's declaration over the file's.
    pub fn or(self, other: WrenchDeclaration) -> WrenchDeclaration {
        WrenchDeclaration {
            frame: self.frame.or(other.frame),
            sign: self.sign.or(other.sign),
            sensor_turn_deg: self.sensor_turn_deg.or(other.sensor_turn_deg),
        }
    }
}

/// How a decision was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Origin {
    /// The file or the caller said so.
    Declared,
    /// The data decided it (the evidence is reported).
    Detected,
    /// The data could not decide; skillc's default was taken.
    Assumed,
}

impl Origin {
    /// `declared` or `detected`, as `skillc learn` prints it.
    pub fn name(self) -> &'static str {
        match self {
            Origin::Declared => "declared",
            Origin::Detected => "detected",
            Origin::Assumed => "assumed",
        }
    }
}

/// The statistic the frame was judged by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameStatistic {
    /// Samples in moving contact: the spread (1.4826 × median absolute deviation) of the angle
    /// by which the force leans along the direction of travel, `asin(f̂ · v̂)`.
    LeanSpread,
    /// Samples in contact without motion: the median angle of the force from its mean direction.
    DirectionSpread,
}

/// The sensor turns detection tries \[°\]: a sensor's axes are usually the flange's, or
/// turned by a quarter or half turn about the tool axis by the way it is bolted on.
pub const SENSOR_TURNS_DEG: [f64; 4] = [0.0, 90.0, 180.0, 270.0];

/// The evidence for a detected (or undecidable) wrench frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameEvidence {
    /// What was measured.
    pub statistic: FrameStatistic,
    /// Samples it was measured on.
    pub samples: usize,
    /// The statistic with the columns read as base-frame axes \[°\].
    pub base_deg: f64,
    /// The statistic with the columns read as sensor axes turned by each of
    /// [`SENSOR_TURNS_DEG`] from the flange's and rotated into the base frame \[°\].
    pub sensor_deg: [f64; 4],
}

/// The decision about the wrench's axes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameFinding {
    /// The axes the file's wrench was read in.
    pub frame: WrenchFrame,
    /// How it was decided.
    pub origin: Origin,
    /// For [`WrenchFrame::Sensor`]: the sensor's axes are the flange's turned by this angle
    /// about the flange z \[°\] (0 for base-frame wrenches).
    pub turn_deg: f64,
    /// How the turn was decided.
    pub turn_origin: Origin,
    /// The figures detection compared (`None` when no sample was in contact, or when nothing
    /// was left to detect).
    pub evidence: Option<FrameEvidence>,
}

/// The decision about the wrench's sign.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SignFinding {
    /// Which wrench the file stores.
    pub sign: ForceSign,
    /// How it was decided.
    pub origin: Origin,
    /// The figures detection looked at, in the base frame before any negation.
    pub evidence: Option<SignEvidence>,
}

/// What was done about the sensor's bias.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
#[non_exhaustive]
pub enum BiasFinding {
    /// The mean wrench of a still, contact-free period was removed from every sample.
    Removed {
        /// The force bias in the sensor's axes (the flange's) \[N\].
        force_n: [f64; 3],
        /// The moment bias in the sensor's axes \[N m\].
        torque_nm: [f64; 3],
        /// First sample of the period (0-based).
        first: usize,
        /// Last sample of the period (0-based, inclusive).
        last: usize,
        /// Its times \[s\].
        t_s: [f64; 2],
    },
    /// Nothing was removed, for the reason given.
    NotRemoved {
        /// Why (no still period, a frozen signal, a contact).
        reason: String,
    },
    /// The caller asked to keep the bias.
    Kept,
}

/// The three decisions of the learner's `prepare_wrench`, stored in the learned file and printed by
/// `skillc learn`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrenchReport {
    /// The axes.
    pub frame: FrameFinding,
    /// The bias.
    pub bias: BiasFinding,
    /// The sign.
    pub sign: SignFinding,
}

/// What the sign check looks at (docs/method.md §1), in the base frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SignEvidence {
    /// Distance from the sample of largest force back to the first sample \[m\].
    pub back_m: f64,
    /// Cosine between the mean force of the samples above half the peak and the way back to
    /// the first sample: near +1 for the force on the tool, negative for the applied force.
    pub cos_back: f64,
}

impl SignEvidence {
    /// Whether the figures decide the sign: the tool came from at least 1 cm away and the
    /// force points clearly to one side of the way back (more than 11.5° off perpendicular).
    pub fn decisive(&self) -> bool {
        self.back_m > 0.01 && self.cos_back.abs() >= 0.2
    }
}

impl fmt::Display for FrameFinding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} frame ({})", self.frame.name(), self.origin.name())?;
        if self.frame == WrenchFrame::Sensor {
            write!(
                f,
                ", its axes turned {}° from the flange's about the tool axis ({})",
                self.turn_deg,
                self.turn_origin.name()
            )?;
        }
        if let Some(e) = &self.evidence {
            let (what, samples) = match e.statistic {
                FrameStatistic::LeanSpread => ("the force's lean along the motion scatters", "moving contact"),
                FrameStatistic::DirectionSpread => ("the force's direction scatters", "contact"),
            };
            write!(
                f,
                ": {what} {:.1}° read as base axes, {:.1}° / {:.1}° / {:.1}° / {:.1}° read as sensor axes turned 0° / 90° / 180° / 270°, over {} samples in {samples}",
                e.base_deg, e.sensor_deg[0], e.sensor_deg[1], e.sensor_deg[2], e.sensor_deg[3], e.samples
            )?;
            if self.origin == Origin::Assumed {
                write!(f, " (too close to tell)")?;
            }
        } else if self.origin == Origin::Assumed {
            write!(f, ": too few samples in contact to tell")?;
        }
        if self.frame == WrenchFrame::Sensor {
            write!(f, "; rotated into the base frame by the flange orientation")?;
        }
        Ok(())
    }
}

impl fmt::Display for BiasFinding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BiasFinding::Removed {
                force_n,
                torque_nm,
                first,
                last,
                t_s,
            } => write!(
                f,
                "removed [{:+.2}, {:+.2}, {:+.2}] N, [{:+.3}, {:+.3}, {:+.3}] N m (sensor axes), the mean of samples {first}..{last} ({:.2}..{:.2} s, still and contact-free)",
                force_n[0], force_n[1], force_n[2], torque_nm[0], torque_nm[1], torque_nm[2], t_s[0], t_s[1]
            ),
            BiasFinding::NotRemoved { reason } => write!(f, "not removed: {reason}"),
            BiasFinding::Kept => f.write_str("kept as asked"),
        }
    }
}

impl fmt::Display for SignFinding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.sign {
            ForceSign::OnTool => "the force on the tool",
            ForceSign::Applied => "the force the robot applies, negated",
        };
        write!(f, "{what} ({}", self.origin.name())?;
        if let Some(e) = &self.evidence {
            write!(
                f,
                ": in contact the force points {} the start (cosine {:+.2}, the start {:.0} mm from the peak)",
                if e.cos_back >= 0.0 { "back towards" } else { "away from" },
                e.cos_back,
                e.back_m * 1e3
            )?;
        }
        write!(f, ")")
    }
}

impl fmt::Display for WrenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "wrench: {}; bias {}; sign: {}", self.frame, self.bias, self.sign)
    }
}

//! One kinesthetic demonstration: reading it from CSV, validating it, resampling and filtering it.
//!
//! **Sign convention:** `force_n` and `torque_nm` hold the wrench the wrist force/torque sensor
//! measures, that is the wrench the *environment exerts on the tool*, in the robot base frame.
//! The wrench the robot applies to the environment is its negative. Every module of the runtime
//! keeps this convention; functions that need the applied force negate explicitly and say so.
//! A file may store its wrench in the sensor's axes or with the other sign: [`prepare_wrench`]
//! (run first by every learning run) settles both and removes the sensor's bias.
//!
//! Units are SI throughout: seconds, metres, newtons, newton-metres. Poses are the tool (flange)
//! pose in the robot base frame.

pub mod air;
mod csv;
mod filter;
mod noise;
mod prepare;
mod quat;
pub use self::quat::{orientation_warnings, Normalised};
mod resample;
mod sign;
mod timing;
mod wrench;

pub use self::csv::{parse_csv, parse_csv_as, read_csv, read_csv_as, Dialect, ReadOptions, COLUMNS, MAX_COLUMNS};
pub use self::filter::{low_pass, low_pass_motion, FilterOrder};
pub use self::noise::{noise_std, position_noise_m};
pub use self::prepare::{
    default_motion_cutoff_hz, prepare, Prepared, Smoothing, DEFAULT_MOTION_CUTOFF_HZ, MOTION_BAND_HZ,
};
pub use self::resample::resample;
pub use self::sign::{negate_wrench, sign_evidence, stores_applied_force, SignEvidence};
pub use self::timing::{check_timing, median_step_s, GAP_ERROR_S, GAP_FACTOR, MAX_RATE_HZ, MIN_RATE_HZ};
pub use self::wrench::{
    prepare_wrench, BiasFinding, ForceSign, FrameEvidence, FrameFinding, FrameStatistic, Origin, SignFinding,
    WrenchDeclaration, WrenchFrame, WrenchOptions, WrenchReport, SENSOR_TURNS_DEG,
};

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// A demonstration as parallel per-sample arrays (all of length [`Demo::len`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Demo {
    /// Name of the source (file path), used in messages.
    pub source: String,
    /// Sample times (s), strictly increasing, not necessarily evenly spaced.
    pub t_s: Vec<f64>,
    /// Tool position in the base frame (m).
    pub position_m: Vec<Vector3<f64>>,
    /// Tool orientation in the base frame, unit and sign-continuous (`q[k]·q[k-1] ≥ 0`).
    pub orientation: Vec<UnitQuaternion<f64>>,
    /// Measured force in the base frame (N): the force the environment exerts on the tool.
    pub force_n: Vec<Vector3<f64>>,
    /// Measured torque in the base frame (Nm): the torque the environment exerts on the tool.
    pub torque_nm: Vec<Vector3<f64>>,
}

impl Demo {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// True when the demonstration has no samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Duration from the first to the last sample (s) (0 for fewer than two samples).
    pub fn duration_s(&self) -> f64 {
        match (self.t_s.first(), self.t_s.last()) {
            (Some(first), Some(last)) => last - first,
            _ => 0.0,
        }
    }

    /// Mean sampling period (s) (0 for fewer than two samples).
    pub fn mean_dt_s(&self) -> f64 {
        if self.len() < 2 {
            0.0
        } else {
            self.duration_s() / (self.len() - 1) as f64
        }
    }

    /// The samples `range` as a new demonstration (times kept as they are); the range is
    /// clipped to the samples present.
    pub fn slice(&self, range: std::ops::Range<usize>) -> Demo {
        let end = range.end.min(self.len());
        let range = range.start.min(end)..end;
        Demo {
            source: self.source.clone(),
            t_s: self.t_s[range.clone()].to_vec(),
            position_m: self.position_m[range.clone()].to_vec(),
            orientation: self.orientation[range.clone()].to_vec(),
            force_n: self.force_n[range.clone()].to_vec(),
            torque_nm: self.torque_nm[range].to_vec(),
        }
    }
}

/// Something the reader fixed and the user should know about; the data is still usable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum DemoWarning {
    /// Quaternions whose norm differed from 1 by more than `1e-6` were normalised.
    Renormalised {
        /// Source file.
        file: String,
        /// How many rows were normalised.
        count: usize,
        /// First such row (1-based line number in the file).
        first_row: usize,
        /// Largest `| |q| - 1 |` seen.
        max_deviation: f64,
    },
    /// Quaternions were negated so that consecutive samples lie in the same hemisphere.
    SignFlipped {
        /// Source file.
        file: String,
        /// How many rows were negated.
        count: usize,
        /// First such row (1-based line number in the file).
        first_row: usize,
    },
    /// Steps of more than ten median steps (dropped samples), short enough to interpolate.
    TimeSteps {
        /// Source file.
        file: String,
        /// How many such steps.
        count: usize,
        /// Data row (1-based, header not counted) before the first one.
        first_row: usize,
        /// The longest of them \[s\].
        largest_step_s: f64,
        /// The median step \[s\].
        median_step_s: f64,
    },
    /// The positions are noisy and were not smoothed.
    NoisyPositions {
        /// Source file.
        file: String,
        /// Estimated noise per axis \[m\].
        noise_m: f64,
    },
    /// The force repeats exactly between most consecutive samples: the sensor was not
    /// streaming, and nothing learned from the force (segments by force, contact frames, forces,
    /// thresholds) describes the demonstration.
    FrozenForce {
        /// Source file.
        file: String,
        /// The share of consecutive samples with the same force, 0 to 1.
        share: f64,
    },
    /// The recording holds a load while the tool is in the air (a hand's grip, a wandering
    /// bias), found from its own levels and removed from every sample ([`air`]).
    AirLoad {
        /// Source file.
        file: String,
        /// The largest load \[N\].
        largest_n: f64,
        /// How far it moved over the recording \[N\].
        drift_n: f64,
    },
}

/// The share of consecutive samples whose force is exactly the same (0 for fewer than three
/// samples). A streaming sensor's noise changes the last digits at every sample; a share above
/// [`FROZEN_FORCE_SHARE`] means the stream repeated its last value.
pub fn frozen_force_share(force: &[Vector3<f64>]) -> f64 {
    if force.len() < 3 {
        return 0.0;
    }
    let unchanged = force.windows(2).filter(|w| w[1] == w[0]).count();
    unchanged as f64 / (force.len() - 1) as f64
}

/// The share of repeated force samples above which a force signal counts as frozen.
pub const FROZEN_FORCE_SHARE: f64 = 0.5;

impl std::fmt::Display for DemoWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DemoWarning::Renormalised { file, count, first_row, max_deviation } => write!(
                f,
                "normalised {count} non-unit quaternion(s) in `{file}` (first at row {first_row}, largest norm error {max_deviation:.3e})"
            ),
            DemoWarning::SignFlipped { file, count, first_row } => write!(
                f,
                "negated {count} quaternion(s) in `{file}` to make them sign-continuous (first at row {first_row})"
            ),
            DemoWarning::TimeSteps { file, count, first_row, largest_step_s, median_step_s } => write!(
                f,
                "{count} step(s) in the time column of `{file}` exceed ten median steps ({:.2} ms), the first after data row {first_row}, the longest {:.1} ms: samples were dropped; they are interpolated",
                median_step_s * 1e3,
                largest_step_s * 1e3
            ),
            DemoWarning::NoisyPositions { file, noise_m } => write!(
                f,
                "the positions in `{file}` carry {:.3} mm of noise and are not smoothed: learned motions will be rough; set `lowpass` (e.g. --lowpass 20) or record faster",
                noise_m * 1e3
            ),
            DemoWarning::FrozenForce { file, share } => write!(
                f,
                "the force in `{file}` repeats exactly between {:.0} % of consecutive samples: the force sensor was not streaming (or streamed far slower than the pose was logged), so segments, frames and forces learned from the force may not describe the demonstration; check the recording, or learn only motions (`segments = none`)",
                share * 100.0
            ),
            DemoWarning::AirLoad { file, largest_n, drift_n } => write!(
                f,
                "`{file}` holds up to {largest_n:.1} N on the sensor while the tool is in the air (moving by {drift_n:.1} N over the recording): followed between the contacts and removed from every sample, so contact forces are read against the air around them; `--keep-bias` keeps it"
            ),
        }
    }
}

/// A demonstration with the warnings produced while loading or preprocessing it.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The demonstration.
    pub demo: Demo,
    /// What was fixed on the way.
    pub warnings: Vec<DemoWarning>,
    /// What the file's `# wrench_frame:`, `# force_sign:` and `# sensor_turn:` lines declare.
    pub wrench: WrenchDeclaration,
}

/// Optional preprocessing applied after reading: first resampling, then low-pass filtering.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PreprocessConfig {
    /// Resample to this fixed rate (Hz) (linear interpolation, slerp for orientation).
    pub resample_hz: Option<f64>,
    /// Zero-phase low-pass cut-off (Hz); needs evenly spaced samples (set `resample_hz` for
    /// irregular data, or the mean rate is used when the spacing varies by less than 1 %).
    pub lowpass_cutoff_hz: Option<f64>,
    /// Order of the low-pass (applied forwards and backwards, so the effective order doubles).
    pub lowpass_order: FilterOrder,
}

/// Applies `config` to `demo`: resampling first, then filtering.
pub fn preprocess(demo: &Demo, config: &PreprocessConfig) -> Result<Demo, DemoError> {
    let mut out = match config.resample_hz {
        Some(rate_hz) => resample(demo, rate_hz)?,
        None => demo.clone(),
    };
    if let Some(cutoff_hz) = config.lowpass_cutoff_hz {
        out = low_pass(&out, cutoff_hz, config.lowpass_order)?;
    }
    Ok(out)
}

/// Problems with a demonstration file or with the parameters used to preprocess it.
///
/// Rows are 1-based line numbers in the file (the header is row 1).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DemoError {
    /// The file could not be read.
    #[error("cannot read demonstration `{file}`")]
    Io {
        /// Path of the file.
        file: String,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file holds nothing, not even a header.
    #[error("demonstration `{file}` is empty")]
    Empty {
        /// Path of the file.
        file: String,
    },
    /// The file holds a header but no data rows.
    #[error("demonstration `{file}` has a header but no data rows")]
    HeaderOnly {
        /// Path of the file.
        file: String,
    },
    /// Required columns are absent from the header.
    #[error("demonstration `{file}` lacks column(s) {}", list_columns(.columns))]
    MissingColumns {
        /// Path of the file.
        file: String,
        /// The absent column names.
        columns: Vec<String>,
    },
    /// The header has more columns than [`MAX_COLUMNS`].
    #[error(
        "the header of `{file}` has {columns} columns, more than the {limit} a demonstration may have \
         (skillc reads 14: t, px, py, pz, qw, qx, qy, qz, fx, fy, fz, mx, my, mz); drop the others"
    )]
    TooManyColumns {
        /// Path of the file.
        file: String,
        /// Columns in its header.
        columns: usize,
        /// [`MAX_COLUMNS`].
        limit: usize,
    },
    /// A column name appears twice in the header.
    #[error("column `{column}` appears twice in the header of `{file}`")]
    DuplicateColumn {
        /// Path of the file.
        file: String,
        /// The repeated name.
        column: String,
    },
    /// A row has a different number of fields than the header.
    #[error("row {row} of `{file}` has {found} field(s), the header has {expected}")]
    Ragged {
        /// Path of the file.
        file: String,
        /// 1-based line number.
        row: usize,
        /// Fields in the header.
        expected: usize,
        /// Fields in this row.
        found: usize,
    },
    /// A field is not a number.
    #[error("row {row}, column `{column}` of `{file}`: `{text}` is not a number")]
    NotANumber {
        /// Path of the file.
        file: String,
        /// 1-based line number.
        row: usize,
        /// Column name.
        column: String,
        /// The offending text.
        text: String,
    },
    /// A field is NaN or infinite.
    #[error("row {row}, column `{column}` of `{file}` is not finite (`{text}`)")]
    NonFinite {
        /// Path of the file.
        file: String,
        /// 1-based line number.
        row: usize,
        /// Column name.
        column: String,
        /// The offending text.
        text: String,
    },
    /// Time does not strictly increase.
    #[error("row {row}, column `t` of `{file}`: time {t_s} s does not exceed the previous {previous_s} s")]
    TimeNotIncreasing {
        /// Path of the file.
        file: String,
        /// 1-based line number.
        row: usize,
        /// This row's time (s).
        t_s: f64,
        /// Previous row's time (s).
        previous_s: f64,
    },
    /// A quaternion is (nearly) zero and cannot be normalised.
    #[error("row {row} of `{file}`: quaternion (`qw`, `qx`, `qy`, `qz`) has zero norm")]
    ZeroQuaternion {
        /// Path of the file.
        file: String,
        /// 1-based line number.
        row: usize,
    },
    /// Fewer samples than required.
    #[error("demonstration `{file}` has {found} sample(s), at least {required} are needed")]
    TooFewSamples {
        /// Path of the file.
        file: String,
        /// Samples present.
        found: usize,
        /// Samples required.
        required: usize,
    },
    /// A preprocessing parameter is out of range.
    #[error("invalid `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Why it is rejected.
        reason: String,
    },
    /// The median sample rate is implausible: the time column is not in seconds.
    #[error("the time column of `{file}` looks like it is in the wrong unit: its median step is {median_step} (read as seconds: {:.3e} Hz, a recorder runs at 10 Hz .. 100 kHz); {hint}", 1.0 / .median_step)]
    TimeUnit {
        /// Path of the file.
        file: String,
        /// The median step between samples, in the file's unit.
        median_step: f64,
        /// What the unit probably is and what to do.
        hint: String,
    },
    /// Time jumps by far more than the median step: samples are missing.
    #[error("`{file}` has a gap in its time column: {step_s:.3} s between data rows {row} and {} (t = {from_s:.3} s and {to_s:.3} s; the median step is {:.2} ms){}; cut the file at the gap or record again", .row + 1, .median_step_s * 1e3, if *.count > 1 { format!(", and {} more gap(s) longer than 0.1 s", .count - 1) } else { String::new() })]
    TimeGap {
        /// Path of the file.
        file: String,
        /// 1-based data row (header not counted) of the sample before the gap.
        row: usize,
        /// Time before the gap \[s\].
        from_s: f64,
        /// Time after the gap \[s\].
        to_s: f64,
        /// The step \[s\].
        step_s: f64,
        /// The median step \[s\].
        median_step_s: f64,
        /// How many such gaps the file has.
        count: usize,
    },
    /// A `# wrench_frame:`, `# force_sign:` or `# sensor_turn:` line with a value skillc does not know.
    #[error("row {row} of `{file}`: {reason}")]
    BadDeclaration {
        /// Path of the file.
        file: String,
        /// 1-based line number.
        row: usize,
        /// What is wrong.
        reason: String,
    },
    /// Filtering needs evenly spaced samples.
    #[error("demonstration `{file}` is irregularly sampled (period {min_dt_s:.3e}..{max_dt_s:.3e} s): resample it before filtering")]
    IrregularSampling {
        /// Path of the file.
        file: String,
        /// Smallest period (s).
        min_dt_s: f64,
        /// Largest period (s).
        max_dt_s: f64,
    },
}

fn list_columns(columns: &[String]) -> String {
    columns.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(", ")
}

//! Reading a demonstration CSV by column name, through the `csv` crate.
//!
//! A header row names the columns, then one row per sample. The `csv` crate handles what
//! spreadsheets, pandas and loggers write: quoted fields (`"0.0000"`), a UTF-8 BOM, `\r\n` line
//! ends, and other separators: `;` (with a decimal comma, as European spreadsheets write), tab
//! and `|` are detected from the header line, or set with [`Dialect::delimiter`]. Blank lines
//! and lines starting with `#` are skipped; spaces around fields are ignored. Every error names
//! the 1-based line number of the row in the file.
//!
//! Columns are found by name, in any order, extra columns ignored: first the exact name, then
//! the name [`Dialect::columns`] maps it to (`t` → `time`), then common spellings of other
//! tools, compared without case or punctuation (`time`/`timestamp`, `x`/`pos_x`/`position.x`,
//! `orientation.w`, `force_x`/`wrench.force.x`, `torque_x`/`tx`).
//!
//! Three comment lines declare the wrench's conventions (docs/method.md §1), anywhere in the file,
//! `:` or `=` between key and value, case ignored: `# wrench_frame: base|sensor` (the axes the
//! force and moment columns are written in), `# force_sign: on-tool|applied` (which of the two
//! opposite wrenches they hold) and `# sensor_turn: DEG` (a sensor-frame wrench's axes turned
//! from the flange's about the tool axis). Undeclared, all three are detected when learning.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::quat::{orientation_warnings, Normalised};
use super::wrench::{ForceSign, WrenchDeclaration, WrenchFrame};
use super::{Demo, DemoError, Loaded};

/// The required columns, in the order the reader stores them.
pub const COLUMNS: [&str; 14] = [
    "t", "px", "py", "pz", "qw", "qx", "qy", "qz", "fx", "fy", "fz", "mx", "my", "mz",
];

/// Separators tried when none is given, in order of preference on a tie.
const DELIMITERS: [u8; 4] = [b',', b';', b'\t', b'|'];

/// Options for reading a demonstration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReadOptions {
    /// Fewest samples accepted (the template may ask for more, e.g. several segments of a
    /// minimum length). At least 2.
    pub min_samples: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self { min_samples: 2 }
    }
}

/// How a CSV file is written, where it departs from skillc's own: the separator and the
/// names of the columns. The default detects the separator and finds columns by name.
///
/// (A type of its own rather than fields of [`ReadOptions`], so that code building
/// `ReadOptions { min_samples }` keeps compiling.)
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Dialect {
    /// The field separator; `None` detects it from the header line (`,`, `;`, tab or `|`,
    /// whichever occurs most outside quotes; `,` when none does).
    pub delimiter: Option<u8>,
    /// The file's names for skillc's columns: `"t" → "time"` reads `t` from the column `time`.
    /// Columns not named here are found by their own name or a common spelling.
    pub columns: BTreeMap<String, String>,
}

/// Reads and validates the demonstration at `path`.
pub fn read_csv(path: &Path, options: &ReadOptions) -> Result<Loaded, DemoError> {
    read_csv_as(path, options, &Dialect::default())
}

/// Reads and validates the demonstration at `path`, written in `dialect`.
pub fn read_csv_as(path: &Path, options: &ReadOptions, dialect: &Dialect) -> Result<Loaded, DemoError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| DemoError::Io {
        file: file.clone(),
        source,
    })?;
    parse_csv_as(&file, &text, options, dialect)
}

/// The separator of `header`: the candidate that occurs most often outside double quotes.
fn detect_delimiter(header: &str) -> u8 {
    let mut counts = [0usize; DELIMITERS.len()];
    let mut quoted = false;
    for byte in header.bytes() {
        if byte == b'"' {
            quoted = !quoted;
        } else if !quoted {
            if let Some(index) = DELIMITERS.iter().position(|d| *d == byte) {
                counts[index] += 1;
            }
        }
    }
    let best = (0..DELIMITERS.len()).fold(0, |best, i| if counts[i] > counts[best] { i } else { best });
    DELIMITERS[best]
}

/// Lower case, letters and digits only: `Position.X` and `position_x` compare equal.
fn normalise(name: &str) -> String {
    name.chars()
        .filter(char::is_ascii_alphanumeric)
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// Whether `name` (normalised) is another tool's spelling of `column`.
fn is_alias(column: &str, name: &str) -> bool {
    let axis = column.chars().last().unwrap_or(' ');
    match column {
        "t" => ["time", "times", "timestamp", "stamp", "ts", "sec", "seconds"].contains(&name),
        "px" | "py" | "pz" => {
            name == axis.to_string()
                || name.ends_with(&format!("position{axis}"))
                || name.ends_with(&format!("pos{axis}"))
                || name == format!("{axis}m")
        }
        "qw" | "qx" | "qy" | "qz" => {
            name.ends_with(&format!("orientation{axis}"))
                || name.ends_with(&format!("quaternion{axis}"))
                || name.ends_with(&format!("quat{axis}"))
                || name.ends_with(&format!("rotation{axis}"))
        }
        "fx" | "fy" | "fz" => name.ends_with(&format!("force{axis}")) || name == format!("f{axis}n"),
        "mx" | "my" | "mz" => {
            name.ends_with(&format!("torque{axis}")) || name == format!("t{axis}") || name == format!("m{axis}nm")
        }
        _ => false,
    }
}

/// The index of each of [`COLUMNS`] in `names`, or the names that could not be found.
fn find_columns(names: &[String], dialect: &Dialect) -> Result<[usize; 14], Vec<String>> {
    let normalised: Vec<String> = names.iter().map(|n| normalise(n)).collect();
    let mut col_idx = [0usize; 14];
    let mut missing = Vec::new();
    for (slot, wanted) in col_idx.iter_mut().zip(COLUMNS) {
        if let Some(theirs) = dialect.columns.get(wanted) {
            match names.iter().position(|name| name == theirs) {
                Some(idx) => *slot = idx,
                None => missing.push(theirs.clone()),
            }
            continue;
        }
        if let Some(idx) = names.iter().position(|name| name == wanted) {
            *slot = idx;
            continue;
        }
        let exact: Vec<usize> = (0..names.len()).filter(|&i| normalised[i] == wanted).collect();
        let aliases: Vec<usize> = (0..names.len()).filter(|&i| is_alias(wanted, &normalised[i])).collect();
        match (exact.as_slice(), aliases.as_slice()) {
            ([only], _) | ([], [only]) => *slot = *only,
            _ => missing.push(wanted.to_owned()),
        }
    }
    if missing.is_empty() {
        Ok(col_idx)
    } else {
        Err(missing)
    }
}

/// The 1-based lines of the records the reader reports, counted from the reader's own position:
/// each call counts the newlines since the previous record only, so reading a file is linear in
/// its size (counting from the start of the file for every row made a 50 s demonstration at
/// 1 kHz take over a minute). The crate's own line count and offset do not account for the
/// comment and blank lines it skips before a record, so those are skipped here.
struct LineCounter<'t> {
    text: &'t str,
    /// The byte up to which newlines have been counted.
    byte: usize,
    /// Newlines in `text[..byte]`.
    newlines: usize,
}

impl<'t> LineCounter<'t> {
    fn new(text: &'t str) -> Self {
        Self {
            text,
            byte: 0,
            newlines: 0,
        }
    }

    /// The line of the record the reader reports at `byte`; bytes must not decrease from call
    /// to call (a reader's records do not go back).
    fn line_of(&mut self, byte: usize) -> usize {
        let byte = byte.min(self.text.len()).max(self.byte);
        self.newlines += self.text.as_bytes()[self.byte..byte]
            .iter()
            .filter(|b| **b == b'\n')
            .count();
        self.byte = byte;
        let skipped = self.text[byte..]
            .lines()
            .take_while(|line| {
                let line = line.trim();
                line.is_empty() || line.starts_with('#')
            })
            .count();
        1 + self.newlines + skipped
    }
}

/// The declarations in the comment lines of `text` (see the module docs).
fn declarations(file: &str, text: &str) -> Result<WrenchDeclaration, DemoError> {
    let mut declared = WrenchDeclaration::default();
    for (index, line) in text.lines().enumerate() {
        let Some(comment) = line.trim().strip_prefix('#') else {
            continue;
        };
        let Some((key, value)) = comment.split_once([':', '=']) else {
            continue;
        };
        let key = key.trim().to_ascii_lowercase().replace(['-', ' '], "_");
        let bad = |reason: String| DemoError::BadDeclaration {
            file: file.to_owned(),
            row: index + 1,
            reason,
        };
        match key.as_str() {
            "wrench_frame" => declared.frame = Some(value.parse::<WrenchFrame>().map_err(bad)?),
            "force_sign" => declared.sign = Some(value.parse::<ForceSign>().map_err(bad)?),
            "sensor_turn" => {
                let deg = value
                    .trim()
                    .trim_end_matches("deg")
                    .trim_end_matches('°')
                    .trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|deg| (-360.0..=360.0).contains(deg))
                    .ok_or_else(|| bad(format!("`{}` is not a turn in degrees (-360 to 360)", value.trim())))?;
                declared.sensor_turn_deg = Some(deg);
            }
            _ => {}
        }
    }
    Ok(declared)
}

/// Parses one field: a number, with a decimal comma accepted when `,` is not the separator.
fn number(text: &str, delimiter: u8) -> Option<f64> {
    text.parse().ok().or_else(|| {
        (delimiter != b',' && text.matches(',').count() == 1 && !text.contains('.'))
            .then(|| text.replace(',', ".").parse().ok())
            .flatten()
    })
}

/// Parses and validates demonstration CSV `text`; `file` names it in messages.
pub fn parse_csv(file: &str, text: &str, options: &ReadOptions) -> Result<Loaded, DemoError> {
    parse_csv_as(file, text, options, &Dialect::default())
}

/// Parses and validates demonstration CSV `text` written in `dialect`; `file` names it in
/// messages.
pub fn parse_csv_as(file: &str, text: &str, options: &ReadOptions, dialect: &Dialect) -> Result<Loaded, DemoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let wrench = declarations(file, text)?;
    let header_line = text
        .lines()
        .map(str::trim)
        .find(|line| !line.is_empty() && !line.starts_with('#'));
    let Some(header_line) = header_line else {
        return Err(DemoError::Empty { file: file.to_owned() });
    };
    let delimiter = dialect.delimiter.unwrap_or_else(|| detect_delimiter(header_line));
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delimiter)
        .comment(Some(b'#'))
        .trim(::csv::Trim::All)
        .from_reader(text.as_bytes());
    let malformed = |err: ::csv::Error| {
        let line = err.position().map_or(0, ::csv::Position::line);
        DemoError::Io {
            file: file.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("line {line}: {err}")),
        }
    };
    let mut records = reader.records();
    let mut lines = LineCounter::new(text);
    // Rows of spaces only are blank lines too.
    let mut next_row = || -> Result<Option<(usize, ::csv::StringRecord)>, DemoError> {
        for record in records.by_ref() {
            let record = record.map_err(&malformed)?;
            if record.iter().all(str::is_empty) {
                continue;
            }
            let byte = record.position().map_or(0, |p| p.byte() as usize);
            return Ok(Some((lines.line_of(byte), record)));
        }
        Ok(None)
    };
    let Some((_, header)) = next_row()? else {
        return Err(DemoError::Empty { file: file.to_owned() });
    };
    let names: Vec<String> = header.iter().map(|name| name.trim().to_owned()).collect();
    for (idx, name) in names.iter().enumerate() {
        if names[..idx].contains(name) && COLUMNS.contains(&name.as_str()) {
            return Err(DemoError::DuplicateColumn {
                file: file.to_owned(),
                column: name.clone(),
            });
        }
    }
    let col_idx = find_columns(&names, dialect).map_err(|columns| DemoError::MissingColumns {
        file: file.to_owned(),
        columns,
    })?;

    let mut demo = Demo {
        source: file.to_owned(),
        t_s: Vec::new(),
        position_m: Vec::new(),
        orientation: Vec::new(),
        force_n: Vec::new(),
        torque_nm: Vec::new(),
    };
    let mut rows = Vec::new();
    let mut values = [0.0f64; 14];
    let mut normalised = Normalised::default();
    while let Some((row, fields)) = next_row()? {
        if fields.len() != names.len() {
            return Err(DemoError::Ragged {
                file: file.to_owned(),
                row,
                expected: names.len(),
                found: fields.len(),
            });
        }
        for ((value, &idx), column) in values.iter_mut().zip(&col_idx).zip(COLUMNS) {
            let text = fields.get(idx).unwrap_or_default().trim();
            let parsed = number(text, delimiter).ok_or_else(|| DemoError::NotANumber {
                file: file.to_owned(),
                row,
                column: column.to_owned(),
                text: text.to_owned(),
            })?;
            if !parsed.is_finite() {
                return Err(DemoError::NonFinite {
                    file: file.to_owned(),
                    row,
                    column: column.to_owned(),
                    text: text.to_owned(),
                });
            }
            *value = parsed;
        }
        let [t, px, py, pz, qw, qx, qy, qz, fx, fy, fz, mx, my, mz] = values;
        if let Some(&previous_s) = demo.t_s.last() {
            if t <= previous_s {
                return Err(DemoError::TimeNotIncreasing {
                    file: file.to_owned(),
                    row,
                    t_s: t,
                    previous_s,
                });
            }
        }
        let raw = Quaternion::new(qw, qx, qy, qz);
        let norm = raw.norm();
        if norm < 1e-9 {
            return Err(DemoError::ZeroQuaternion {
                file: file.to_owned(),
                row,
            });
        }
        normalised.note(norm, row);
        demo.t_s.push(t);
        demo.position_m.push(Vector3::new(px, py, pz));
        demo.orientation.push(UnitQuaternion::from_quaternion(raw));
        demo.force_n.push(Vector3::new(fx, fy, fz));
        demo.torque_nm.push(Vector3::new(mx, my, mz));
        rows.push(row);
    }
    if demo.is_empty() {
        return Err(DemoError::HeaderOnly { file: file.to_owned() });
    }
    let required = options.min_samples.max(2);
    if demo.len() < required {
        return Err(DemoError::TooFewSamples {
            file: file.to_owned(),
            found: demo.len(),
            required,
        });
    }
    let warnings = orientation_warnings(file, &mut demo.orientation, &normalised, |k| rows[k]);
    Ok(Loaded { demo, warnings, wrench })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::DemoWarning;

    const HEADER: &str = "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz";

    fn row(t: f64) -> String {
        format!("{t},0.1,0.2,0.3,1,0,0,0,0,0,-5,0,0,0")
    }

    fn parse(text: &str) -> Result<Loaded, DemoError> {
        parse_csv("demo.csv", text, &ReadOptions::default())
    }

    #[test]
    fn reads_columns_by_name_and_ignores_extra_columns() {
        let text = "q1,mz,my,mx,fz,fy,fx,qz,qy,qx,qw,pz,py,px,t,extra\n9,6,5,4,3,2,1,0,0,0,1,0.3,0.2,0.1,0.0,7\n9,6,5,4,3,2,1,0,0,0,1,0.3,0.2,0.1,0.01,7\n";
        let loaded = parse(text).expect("valid file");
        assert_eq!(loaded.demo.len(), 2);
        assert_eq!(loaded.demo.position_m[0], Vector3::new(0.1, 0.2, 0.3));
        assert_eq!(loaded.demo.force_n[1], Vector3::new(1.0, 2.0, 3.0));
        assert_eq!(loaded.demo.torque_nm[1], Vector3::new(4.0, 5.0, 6.0));
        assert!(loaded.warnings.is_empty());
    }

    #[test]
    fn empty_and_header_only_files_are_rejected() {
        assert!(matches!(parse(""), Err(DemoError::Empty { .. })));
        assert!(matches!(parse("\n\n"), Err(DemoError::Empty { .. })));
        assert!(matches!(
            parse(&format!("{HEADER}\n")),
            Err(DemoError::HeaderOnly { .. })
        ));
    }

    #[test]
    fn missing_columns_are_all_named() {
        let err = parse("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz\n0,0,0,0,1,0,0,0,0,0,0\n").expect_err("lacks torques");
        assert_eq!(
            err.to_string(),
            "demonstration `demo.csv` lacks column(s) `mx`, `my`, `mz`"
        );
    }

    #[test]
    fn ragged_row_names_the_row() {
        let text = format!("{HEADER}\n{}\n0.01,1,2\n", row(0.0));
        let err = parse(&text).expect_err("ragged");
        assert!(
            matches!(
                err,
                DemoError::Ragged {
                    row: 3,
                    expected: 14,
                    found: 3,
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn nan_and_infinity_name_row_and_column() {
        let text = format!("{HEADER}\n{}\n0.01,0.1,NaN,0.3,1,0,0,0,0,0,0,0,0,0\n", row(0.0));
        let err = parse(&text).expect_err("nan");
        assert_eq!(
            err.to_string(),
            "row 3, column `py` of `demo.csv` is not finite (`NaN`)"
        );
        let text = format!("{HEADER}\n{}\n0.01,0.1,0.2,0.3,1,0,0,0,0,0,inf,0,0,0\n", row(0.0));
        assert!(matches!(parse(&text), Err(DemoError::NonFinite { row: 3, .. })));
        let text = format!("{HEADER}\n{}\n0.01,0.1,abc,0.3,1,0,0,0,0,0,0,0,0,0\n", row(0.0));
        assert!(matches!(parse(&text), Err(DemoError::NotANumber { row: 3, .. })));
    }

    #[test]
    fn time_must_strictly_increase() {
        let text = format!("{HEADER}\n{}\n{}\n{}\n", row(0.0), row(0.01), row(0.01));
        let err = parse(&text).expect_err("repeated time");
        assert!(matches!(err, DemoError::TimeNotIncreasing { row: 4, .. }), "{err}");
    }

    #[test]
    fn too_few_samples_is_an_error() {
        let text = format!("{HEADER}\n{}\n{}\n", row(0.0), row(0.01));
        let err = parse_csv("demo.csv", &text, &ReadOptions { min_samples: 10 }).expect_err("too few");
        assert!(matches!(
            err,
            DemoError::TooFewSamples {
                found: 2,
                required: 10,
                ..
            }
        ));
    }

    #[test]
    fn quaternions_are_normalised_and_made_continuous_with_warnings() {
        let text = format!(
            "{HEADER}\n0,0,0,0,2,0,0,0,0,0,0,0,0,0\n0.01,0,0,0,-1,0,0,0,0,0,0,0,0,0\n0.02,0,0,0,-0.99,-0.01,0,0,0,0,0,0,0,0\n"
        );
        let loaded = parse(&text).expect("valid");
        assert_eq!(loaded.warnings.len(), 2);
        assert!(matches!(
            loaded.warnings[0],
            DemoWarning::Renormalised {
                count: 2,
                first_row: 2,
                ..
            }
        ));
        assert!(matches!(
            loaded.warnings[1],
            DemoWarning::SignFlipped {
                count: 2,
                first_row: 3,
                ..
            }
        ));
        for q in &loaded.demo.orientation {
            assert!((q.as_ref().norm() - 1.0).abs() < 1e-12);
            assert!(q.w > 0.0);
        }
    }

    #[test]
    fn irregular_sampling_is_accepted() {
        let text = format!("{HEADER}\n{}\n{}\n{}\n", row(0.0), row(0.001), row(0.0125));
        let loaded = parse(&text).expect("irregular is fine");
        assert_eq!(loaded.demo.t_s, vec![0.0, 0.001, 0.0125]);
    }

    #[test]
    fn quoted_fields_bom_and_crlf_are_read() {
        let quoted: Vec<String> = HEADER.split(',').map(|c| format!("\"{c}\"")).collect();
        let text = format!(
            "\u{feff}{}\r\n\"0.0000\",\"0.1\",0.2,0.3,1,0,0,0,0,0,-5,0,0,0\r\n{}\r\n",
            quoted.join(","),
            row(0.01)
        );
        let loaded = parse(&text).expect("pandas-style file");
        assert_eq!(loaded.demo.t_s, vec![0.0, 0.01]);
        assert_eq!(loaded.demo.position_m[0], Vector3::new(0.1, 0.2, 0.3));
    }

    #[test]
    fn semicolons_with_decimal_commas_and_tabs_are_detected() {
        let semi = format!(
            "{}\n0;0,1;0,2;0,3;1;0;0;0;0;0;-5;0;0;0\n0,01;0,1;0,2;0,3;1;0;0;0;0;0;-5;0;0;0\n",
            HEADER.replace(',', ";")
        );
        let loaded = parse(&semi).expect("semicolons");
        assert_eq!(loaded.demo.t_s, vec![0.0, 0.01]);
        assert_eq!(loaded.demo.position_m[1], Vector3::new(0.1, 0.2, 0.3));
        let tabs = format!(
            "{}\n{}\n{}\n",
            HEADER.replace(',', "\t"),
            row(0.0).replace(',', "\t"),
            row(0.01).replace(',', "\t")
        );
        assert_eq!(parse(&tabs).expect("tabs").demo.len(), 2);
        // A separator given explicitly wins over detection.
        let dialect = Dialect {
            delimiter: Some(b','),
            ..Dialect::default()
        };
        let err = parse_csv_as("demo.csv", &semi, &ReadOptions::default(), &dialect).expect_err("not commas");
        assert!(matches!(err, DemoError::MissingColumns { .. }), "{err}");
    }

    #[test]
    fn other_tools_column_names_are_mapped() {
        let header = "Time,position.x,position.y,position.z,orientation.w,orientation.x,orientation.y,orientation.z,force_x,force_y,force_z,torque_x,torque_y,torque_z";
        let text = format!("{header}\n{}\n{}\n", row(0.0), row(0.01));
        let loaded = parse(&text).expect("ROS-style names");
        assert_eq!(loaded.demo.force_n[0], Vector3::new(0.0, 0.0, -5.0));
        let header = "stamp,a,b,c,qw,qx,qy,qz,fx,fy,fz,mx,my,mz";
        let text = format!("{header}\n{}\n{}\n", row(0.0), row(0.01));
        assert!(matches!(parse(&text), Err(DemoError::MissingColumns { .. })));
        let columns = [("px", "a"), ("py", "b"), ("pz", "c")]
            .into_iter()
            .map(|(ours, theirs)| (ours.to_owned(), theirs.to_owned()))
            .collect();
        let dialect = Dialect {
            columns,
            ..Dialect::default()
        };
        let loaded = parse_csv_as("demo.csv", &text, &ReadOptions::default(), &dialect).expect("mapped by the user");
        assert_eq!(loaded.demo.position_m[1], Vector3::new(0.1, 0.2, 0.3));
    }

    #[test]
    fn errors_name_the_line_past_comments_and_blank_lines() {
        let text = format!(
            "# recorded today\n{HEADER}\n\n{}\n   \n# pause\n0.01,0.1,x,0.3,1,0,0,0,0,0,0,0,0,0\n",
            row(0.0)
        );
        let err = parse(&text).expect_err("not a number");
        assert!(matches!(err, DemoError::NotANumber { row: 7, .. }), "{err}");
    }

    #[test]
    fn comment_lines_declare_the_wrench_frame_sign_and_turn() {
        let text = format!(
            "# recorded: 2019-02-14\n# Wrench-Frame: sensor\n# force_sign = applied\n# sensor_turn: 180 deg\n{HEADER}\n{}\n{}\n",
            row(0.0),
            row(0.01)
        );
        let loaded = parse(&text).expect("declarations are comments");
        assert_eq!(
            loaded.wrench,
            WrenchDeclaration {
                frame: Some(WrenchFrame::Sensor),
                sign: Some(ForceSign::Applied),
                sensor_turn_deg: Some(180.0),
            }
        );
        let plain = parse(&format!("{HEADER}\n{}\n{}\n", row(0.0), row(0.01))).expect("valid");
        assert_eq!(plain.wrench, WrenchDeclaration::default());
        let text = format!("{HEADER}\n# wrench_frame: tool0\n{}\n{}\n", row(0.0), row(0.01));
        let err = parse(&text).expect_err("unknown frame");
        assert!(matches!(err, DemoError::BadDeclaration { row: 2, .. }), "{err}");
        assert!(err.to_string().contains("`base` or `sensor`"), "{err}");
    }
}

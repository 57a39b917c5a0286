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
/// The most columns a demonstration's header may have: the 14 skillc reads and a recorder's
/// others (joint angles, velocities, torques, labels) fit many times over. Checked before the
/// header's names size any work.
pub const MAX_COLUMNS: usize = 1024;

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
    /// Lines of the file before `text`, plus newlines in `text[..byte]`.
    newlines: usize,
}

impl<'t> LineCounter<'t> {
    /// Counts the lines of `text`, whose first line is the file's line `first_line`.
    fn new(text: &'t str, first_line: usize) -> Self {
        Self {
            text,
            byte: 0,
            newlines: first_line - 1,
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

/// Pieces of at least this many bytes are read side by side (a minute at 1 kHz is about 5 MB).
const PIECE_MIN_BYTES: usize = 1 << 20;

/// At most this many pieces.
const MAX_PIECES: usize = 4;

/// How a file's rows are laid out: its name for messages, its separator, where each of
/// [`COLUMNS`] is and how many fields a row has.
struct Layout<'a> {
    file: &'a str,
    delimiter: u8,
    columns: &'a [usize; 14],
    fields: usize,
}

/// The samples read from a piece of a file's body, with the line each came from.
struct Rows {
    demo: Demo,
    lines: Vec<usize>,
    normalised: Normalised,
}

impl Rows {
    fn with_capacity(file: &str, capacity: usize) -> Self {
        Self {
            demo: Demo {
                source: file.to_owned(),
                t_s: Vec::with_capacity(capacity),
                position_m: Vec::with_capacity(capacity),
                orientation: Vec::with_capacity(capacity),
                force_n: Vec::with_capacity(capacity),
                torque_nm: Vec::with_capacity(capacity),
            },
            lines: Vec::with_capacity(capacity),
            normalised: Normalised::default(),
        }
    }

    /// Reads the rows of `text`, the file from line `first_line` on, through `reader`, stopping
    /// at the first bad row.
    fn read(
        &mut self,
        reader: &mut ::csv::Reader<&[u8]>,
        text: &str,
        first_line: usize,
        layout: &Layout<'_>,
    ) -> Result<(), DemoError> {
        let file = layout.file;
        let mut lines = LineCounter::new(text, first_line);
        let mut record = ::csv::ByteRecord::new();
        let mut values = [0.0f64; 14];
        while reader
            .read_byte_record(&mut record)
            .map_err(|err| malformed(file, first_line - 1, &err))?
        {
            if is_blank(&record) {
                continue;
            }
            let row = lines.line_of(record.position().map_or(0, |p| p.byte() as usize));
            if record.len() != layout.fields {
                return Err(DemoError::Ragged {
                    file: file.to_owned(),
                    row,
                    expected: layout.fields,
                    found: record.len(),
                });
            }
            for ((value, &idx), column) in values.iter_mut().zip(layout.columns).zip(COLUMNS) {
                // Fields cut from a `str` at ASCII separators are UTF-8.
                let text = std::str::from_utf8(record.get(idx).unwrap_or_default())
                    .unwrap_or_default()
                    .trim();
                let parsed = number(text, layout.delimiter).ok_or_else(|| DemoError::NotANumber {
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
            self.push(values, row)?;
        }
        Ok(())
    }

    /// Adds the sample of one row, read from line `row`.
    fn push(&mut self, values: [f64; 14], row: usize) -> Result<(), DemoError> {
        let [t, px, py, pz, qw, qx, qy, qz, fx, fy, fz, mx, my, mz] = values;
        if let Some(&previous_s) = self.demo.t_s.last() {
            if t <= previous_s {
                return Err(DemoError::TimeNotIncreasing {
                    file: self.demo.source.clone(),
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
                file: self.demo.source.clone(),
                row,
            });
        }
        self.normalised.note(norm, row);
        self.demo.t_s.push(t);
        self.demo.position_m.push(Vector3::new(px, py, pz));
        self.demo.orientation.push(UnitQuaternion::from_quaternion(raw));
        self.demo.force_n.push(Vector3::new(fx, fy, fz));
        self.demo.torque_nm.push(Vector3::new(mx, my, mz));
        self.lines.push(row);
        Ok(())
    }

    /// Appends the rows of the piece after this one: the error of the first bad row, in the
    /// file's order (a later piece's first time must still follow this piece's last).
    fn append(&mut self, later: Piece) -> Result<(), DemoError> {
        let Piece { rows, error } = later;
        if let (Some(&previous_s), Some(&t_s)) = (self.demo.t_s.last(), rows.demo.t_s.first()) {
            if t_s <= previous_s {
                return Err(DemoError::TimeNotIncreasing {
                    file: self.demo.source.clone(),
                    row: rows.lines[0],
                    t_s,
                    previous_s,
                });
            }
        }
        if let Some(error) = error {
            return Err(error);
        }
        let Rows {
            demo,
            lines,
            normalised,
        } = rows;
        self.demo.t_s.extend(demo.t_s);
        self.demo.position_m.extend(demo.position_m);
        self.demo.orientation.extend(demo.orientation);
        self.demo.force_n.extend(demo.force_n);
        self.demo.torque_nm.extend(demo.torque_nm);
        self.lines.extend(lines);
        self.normalised.merge(&normalised);
        Ok(())
    }
}

/// What reading one piece of a body gave: its rows up to the first bad one, and that row's error.
struct Piece {
    rows: Rows,
    error: Option<DemoError>,
}

/// Reads the rows of `text`, the file from line `first_line` on, holding `lines` newlines.
fn read_piece(
    mut reader: ::csv::Reader<&[u8]>,
    text: &str,
    first_line: usize,
    lines: usize,
    layout: &Layout<'_>,
) -> Piece {
    let mut rows = Rows::with_capacity(layout.file, lines + 1);
    let error = rows.read(&mut reader, text, first_line, layout).err();
    Piece { rows, error }
}

/// How many pieces to read a body of `bytes` in: one per core, at most [`MAX_PIECES`], each at
/// least [`PIECE_MIN_BYTES`].
fn piece_count(bytes: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    cores.min(MAX_PIECES).min(bytes / PIECE_MIN_BYTES).max(1)
}

/// `body` cut into at most `count` pieces, each but the last ending with a newline. A body
/// with a double quote stays whole: a quoted field may hold a newline, and a cut there would
/// split a row.
fn pieces_of(body: &str, count: usize) -> Vec<&str> {
    if count <= 1 || body.as_bytes().contains(&b'"') {
        return vec![body];
    }
    let bytes = body.as_bytes();
    let mut pieces = Vec::with_capacity(count);
    let mut start = 0;
    for k in 1..count {
        let target = (bytes.len() * k / count).max(start);
        let Some(offset) = bytes[target..].iter().position(|&b| b == b'\n') else {
            break;
        };
        let end = target + offset + 1;
        pieces.push(&body[start..end]);
        start = end;
    }
    pieces.push(&body[start..]);
    pieces
}

/// Newlines in `bytes`.
fn newlines(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b == b'\n').count()
}

/// Whether a row is blank: no fields but spaces.
fn is_blank(record: &::csv::ByteRecord) -> bool {
    record.iter().all(|field| field.trim_ascii().is_empty())
}

/// The error of a row the `csv` crate could not read, its line counted on from `lines_before`.
fn malformed(file: &str, lines_before: usize, err: &::csv::Error) -> DemoError {
    let line = err.position().map_or(0, |p| lines_before + p.line() as usize);
    DemoError::Io {
        file: file.to_owned(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("line {line}: {err}")),
    }
}

/// Parses and validates demonstration CSV `text`; `file` names it in messages.
pub fn parse_csv(file: &str, text: &str, options: &ReadOptions) -> Result<Loaded, DemoError> {
    parse_csv_as(file, text, options, &Dialect::default())
}

/// Parses and validates demonstration CSV `text` written in `dialect`; `file` names it in
/// messages.
pub fn parse_csv_as(file: &str, text: &str, options: &ReadOptions, dialect: &Dialect) -> Result<Loaded, DemoError> {
    parse_in_pieces(file, text, options, dialect, piece_count(text.len()))
}

/// [`parse_csv_as`], the body read in at most `pieces` pieces side by side.
fn parse_in_pieces<'t>(
    file: &str,
    text: &'t str,
    options: &ReadOptions,
    dialect: &Dialect,
    pieces: usize,
) -> Result<Loaded, DemoError> {
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
    let reader = |text: &'t str| {
        ::csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .delimiter(delimiter)
            .comment(Some(b'#'))
            .from_reader(text.as_bytes())
    };
    // The header is the first row that is not blank; the body starts on the line after it.
    let mut head = reader(text);
    let mut record = ::csv::ByteRecord::new();
    let header = loop {
        if !head
            .read_byte_record(&mut record)
            .map_err(|err| malformed(file, 0, &err))?
        {
            return Err(DemoError::Empty { file: file.to_owned() });
        }
        if !is_blank(&record) {
            break record.clone();
        }
    };
    let body_start = (head.position().byte() as usize).min(text.len());
    if header.len() > MAX_COLUMNS {
        return Err(DemoError::TooManyColumns {
            file: file.to_owned(),
            columns: header.len(),
            limit: MAX_COLUMNS,
        });
    }
    let names: Vec<String> = header
        .iter()
        .map(|name| String::from_utf8_lossy(name).trim().to_owned())
        .collect();
    for (idx, name) in names.iter().enumerate() {
        if COLUMNS.contains(&name.as_str()) && names[..idx].contains(name) {
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
    let layout = Layout {
        file,
        delimiter,
        columns: &col_idx,
        fields: names.len(),
    };
    // The body in pieces that start at line starts, read side by side; a quote may hold a
    // newline, so a file with quotes is read in one piece.
    let body = &text[body_start..];
    let first_line = 1 + newlines(&text.as_bytes()[..body_start]);
    let pieces = pieces_of(body, pieces);
    // Each piece's newlines, counted once: its first line in the file, and its rows at most.
    let lines: Vec<usize> = pieces.iter().map(|piece| newlines(piece.as_bytes())).collect();
    let mut first_lines = Vec::with_capacity(pieces.len());
    let mut line = first_line;
    for count in &lines {
        first_lines.push(line);
        line += count;
    }
    let read: Vec<Piece> = if pieces.len() == 1 {
        vec![read_piece(reader(body), body, first_line, lines[0], &layout)]
    } else {
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..pieces.len())
                .map(|k| {
                    let (piece, from, count, layout) = (pieces[k], first_lines[k], lines[k], &layout);
                    scope.spawn(move || read_piece(reader(piece), piece, from, count, layout))
                })
                .collect();
            handles
                .into_iter()
                .map(|handle| handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
                .collect()
        })
    };
    let total = read.iter().map(|piece| piece.rows.lines.len()).sum();
    let mut rows = Rows::with_capacity(file, total);
    for piece in read {
        rows.append(piece)?;
    }
    let Rows {
        mut demo,
        lines,
        normalised,
    } = rows;
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
    let warnings = orientation_warnings(file, &mut demo.orientation, &normalised, |k| lines[k]);
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

    /// A body of `n` rows with comment and blank lines among them and some quaternions off
    /// unit norm, for reading in pieces.
    fn varied_body(n: usize) -> String {
        let mut text = format!("# a note\n{HEADER}\n");
        for k in 0..n {
            if k % 97 == 13 {
                text.push_str("# pause\n\n   \n");
            }
            let w = if k % 53 == 7 { 1.01 } else { 1.0 };
            text.push_str(&format!(
                "{:.3}, {:.4},0.2,0.3,{w},0,0,0,0,0,{:.2},0,0,0\n",
                k as f64 * 1e-3,
                0.1 + k as f64 * 1e-4,
                -((k % 11) as f64)
            ));
        }
        text
    }

    fn parse_pieces(text: &str, pieces: usize) -> Result<Loaded, DemoError> {
        parse_in_pieces("demo.csv", text, &ReadOptions::default(), &Dialect::default(), pieces)
    }

    #[test]
    fn a_body_read_in_pieces_reads_as_it_does_whole() {
        let text = varied_body(1000);
        let whole = parse_pieces(&text, 1).expect("valid");
        assert_eq!(whole.demo.len(), 1000);
        for pieces in 2..=4 {
            assert_eq!(pieces_of(&text, pieces).len(), pieces);
            let read = parse_pieces(&text, pieces).expect("valid");
            assert_eq!(read.demo.t_s, whole.demo.t_s, "{pieces} pieces");
            assert_eq!(read.demo.position_m, whole.demo.position_m);
            assert_eq!(read.demo.orientation, whole.demo.orientation);
            assert_eq!(read.demo.force_n, whole.demo.force_n);
            assert_eq!(read.warnings, whole.warnings, "renormalised count and first row");
        }
        assert!(
            matches!(
                whole.warnings.first(),
                Some(DemoWarning::Renormalised {
                    count: 19,
                    first_row: 10,
                    ..
                })
            ),
            "{:?}",
            whole.warnings
        );
    }

    #[test]
    fn an_error_in_a_later_piece_names_its_line_in_the_file() {
        let good = varied_body(1000);
        let line = good.lines().count() - 10;
        let mut lines: Vec<String> = good.lines().map(str::to_owned).collect();
        lines[line - 1] = lines[line - 1].replacen("0.2", "nan", 1);
        let text = lines.join("\n") + "\n";
        for pieces in 1..=4 {
            let err = parse_pieces(&text, pieces).expect_err("NaN");
            assert!(
                matches!(&err, DemoError::NonFinite { row, .. } if *row == line),
                "{pieces} pieces: {err}"
            );
        }
        // A time that goes back right where a piece starts is still caught, at its line.
        let cut = pieces_of(&good, 2)[0];
        let line = cut.lines().count() + 1;
        let mut lines: Vec<String> = good.lines().map(str::to_owned).collect();
        let (t, rest) = lines[line - 1].split_once(',').expect("a row");
        assert!(t.parse::<f64>().is_ok(), "line {line} is a row: {}", lines[line - 1]);
        lines[line - 1] = format!("0.0,{rest}");
        let text = lines.join("\n") + "\n";
        for pieces in 1..=2 {
            let err = parse_pieces(&text, pieces).expect_err("time goes back");
            assert!(
                matches!(&err, DemoError::TimeNotIncreasing { row, .. } if *row == line),
                "{pieces} pieces: {err}"
            );
        }
    }

    #[test]
    fn a_body_with_quotes_is_read_whole() {
        let text = format!(
            "{HEADER}\n\"0.0\",0.1,0.2,0.3,1,0,0,0,0,0,0,0,0,0\n{}\n{}\n",
            row(0.01),
            row(0.02)
        );
        assert_eq!(pieces_of(&text, 4).len(), 1);
        assert_eq!(parse_pieces(&text, 4).expect("valid").demo.len(), 3);
    }
}

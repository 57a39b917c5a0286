//! Reading a demonstration CSV by column name.
//!
//! The format is plain numeric CSV: a header row naming the columns, then one row per sample,
//! fields separated by commas. Blank lines and lines starting with `#` are skipped; a UTF-8 BOM,
//! `\r\n` line ends, surrounding spaces and double quotes around header names are tolerated. The
//! parser is written by hand rather than with the `csv` crate because every field is a number,
//! and hand parsing gives exact 1-based line numbers for every error at no extra cost.

use std::path::Path;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::quat::make_continuous;
use super::{Demo, DemoError, DemoWarning, Loaded};

/// The required columns, in the order the reader stores them.
pub const COLUMNS: [&str; 14] = [
    "t", "px", "py", "pz", "qw", "qx", "qy", "qz", "fx", "fy", "fz", "mx", "my", "mz",
];

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

/// Reads and validates the demonstration at `path`.
pub fn read_csv(path: &Path, options: &ReadOptions) -> Result<Loaded, DemoError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| DemoError::Io {
        file: file.clone(),
        source,
    })?;
    parse_csv(&file, &text, options)
}

/// Parses and validates demonstration CSV `text`; `file` names it in messages.
pub fn parse_csv(file: &str, text: &str, options: &ReadOptions) -> Result<Loaded, DemoError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(idx, line)| (idx + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(DemoError::Empty { file: file.to_owned() });
    };
    let names: Vec<&str> = header
        .split(',')
        .map(|name| name.trim().trim_matches('"').trim())
        .collect();
    for (idx, name) in names.iter().enumerate() {
        if names[..idx].contains(name) && COLUMNS.contains(name) {
            return Err(DemoError::DuplicateColumn {
                file: file.to_owned(),
                column: (*name).to_owned(),
            });
        }
    }
    let mut col_idx = [0usize; 14];
    let mut missing = Vec::new();
    for (slot, wanted) in col_idx.iter_mut().zip(COLUMNS) {
        match names.iter().position(|name| *name == wanted) {
            Some(idx) => *slot = idx,
            None => missing.push(wanted.to_owned()),
        }
    }
    if !missing.is_empty() {
        return Err(DemoError::MissingColumns {
            file: file.to_owned(),
            columns: missing,
        });
    }

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
    let mut fields: Vec<&str> = Vec::with_capacity(names.len());
    let mut renormalised = (0usize, 0usize, 0.0f64);
    for (row, line) in lines {
        fields.clear();
        fields.extend(line.split(','));
        if fields.len() != names.len() {
            return Err(DemoError::Ragged {
                file: file.to_owned(),
                row,
                expected: names.len(),
                found: fields.len(),
            });
        }
        for ((value, &idx), column) in values.iter_mut().zip(&col_idx).zip(COLUMNS) {
            let text = fields[idx].trim();
            let parsed: f64 = text.parse().map_err(|_| DemoError::NotANumber {
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
        let deviation = (norm - 1.0).abs();
        if deviation > 1e-6 {
            if renormalised.0 == 0 {
                renormalised.1 = row;
            }
            renormalised.0 += 1;
            renormalised.2 = renormalised.2.max(deviation);
        }
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
    let mut warnings = Vec::new();
    if renormalised.0 > 0 {
        warnings.push(DemoWarning::Renormalised {
            file: file.to_owned(),
            count: renormalised.0,
            first_row: renormalised.1,
            max_deviation: renormalised.2,
        });
    }
    let flipped = make_continuous(&mut demo.orientation);
    if let Some(&first) = flipped.first() {
        warnings.push(DemoWarning::SignFlipped {
            file: file.to_owned(),
            count: flipped.len(),
            first_row: rows[first],
        });
    }
    Ok(Loaded { demo, warnings })
}

#[cfg(test)]
mod tests {
    use super::*;

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
}

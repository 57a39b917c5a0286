//! Physical units of `.skill` literals and their dimensions, converted to SI at check time.

use std::f64::consts::PI;
use std::fmt;

/// The physical dimension a literal must have where it is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dim {
    /// Metres.
    Length,
    /// Radians.
    Angle,
    /// Seconds.
    Time,
    /// Newtons.
    Force,
    /// Newton-metres.
    Torque,
    /// N/m.
    Stiffness,
    /// Nm/rad.
    RotStiffness,
    /// m/s.
    Speed,
    /// rad/s.
    AngularSpeed,
    /// Hz.
    Frequency,
}

impl Dim {
    /// What to call it in messages.
    pub fn describe(self) -> &'static str {
        match self {
            Dim::Length => "a length",
            Dim::Angle => "an angle",
            Dim::Time => "a duration",
            Dim::Force => "a force",
            Dim::Torque => "a torque",
            Dim::Stiffness => "a translational stiffness",
            Dim::RotStiffness => "a rotational stiffness",
            Dim::Speed => "a speed",
            Dim::AngularSpeed => "an angular speed",
            Dim::Frequency => "a frequency",
        }
    }

    /// A unit to suggest for this dimension.
    pub fn example_unit(self) -> &'static str {
        match self {
            Dim::Length => "mm",
            Dim::Angle => "deg",
            Dim::Time => "s",
            Dim::Force => "N",
            Dim::Torque => "Nm",
            Dim::Stiffness => "N/m",
            Dim::RotStiffness => "Nm/rad",
            Dim::Speed => "mm/s",
            Dim::AngularSpeed => "deg/s",
            Dim::Frequency => "Hz",
        }
    }
}

impl fmt::Display for Dim {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.describe())
    }
}

/// Every unit a literal may carry: name, dimension, factor to SI.
pub const UNITS: &[(&str, Dim, f64)] = &[
    ("N", Dim::Force, 1.0),
    ("kN", Dim::Force, 1000.0),
    ("Nm", Dim::Torque, 1.0),
    ("m", Dim::Length, 1.0),
    ("cm", Dim::Length, 0.01),
    ("mm", Dim::Length, 0.001),
    ("s", Dim::Time, 1.0),
    ("ms", Dim::Time, 0.001),
    ("deg", Dim::Angle, PI / 180.0),
    ("rad", Dim::Angle, 1.0),
    ("N/m", Dim::Stiffness, 1.0),
    ("N/mm", Dim::Stiffness, 1000.0),
    ("Nm/rad", Dim::RotStiffness, 1.0),
    ("Nm/deg", Dim::RotStiffness, 180.0 / PI),
    ("m/s", Dim::Speed, 1.0),
    ("cm/s", Dim::Speed, 0.01),
    ("mm/s", Dim::Speed, 0.001),
    ("rad/s", Dim::AngularSpeed, 1.0),
    ("deg/s", Dim::AngularSpeed, PI / 180.0),
    ("Hz", Dim::Frequency, 1.0),
    ("kHz", Dim::Frequency, 1000.0),
];

/// The dimension and SI factor of a unit name.
pub fn lookup(unit: &str) -> Option<(Dim, f64)> {
    UNITS
        .iter()
        .find(|(name, _, _)| *name == unit)
        .map(|&(_, dim, factor)| (dim, factor))
}

/// The units of one dimension, for help lines.
pub fn units_of(dim: Dim) -> Vec<&'static str> {
    UNITS
        .iter()
        .filter(|(_, d, _)| *d == dim)
        .map(|(name, _, _)| *name)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn converts_to_si() {
        assert_eq!(lookup("mm"), Some((Dim::Length, 0.001)));
        let (dim, factor) = lookup("deg").expect("deg is a unit");
        assert_eq!(dim, Dim::Angle);
        assert!((90.0 * factor - PI / 2.0).abs() < 1e-15);
        assert_eq!(lookup("lbs"), None);
    }

    #[test]
    fn every_dimension_has_its_example_unit() {
        for &(_, dim, _) in UNITS {
            assert!(units_of(dim).contains(&dim.example_unit()), "{dim}");
        }
    }
}

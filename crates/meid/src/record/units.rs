//! Units of measured records and their conversion to SI.
//!
//! A measured value `v` in a unit `u` is `v · factor(u)` in the SI unit of its quantity:
//!
//! | quantity | SI unit | accepted units (factor to SI) |
//! |---|---|---|
//! | time | s | s, ms (1e-3), us/µs (1e-6) |
//! | acceleration | m/s² | m/s^2, m/s2, m/s**2, m/s² (1); mm/s^2 (1e-3); cm/s^2 (1e-2); g, G, gn (9.80665, standard gravity, CGPM 1901); mg (9.80665e-3); in/s^2 (0.0254); ft/s^2 (0.3048) |
//! | velocity | m/s | m/s (1), mm/s (1e-3), cm/s (1e-2), in/s (0.0254) |
//! | displacement | m | m (1), mm (1e-3), um/µm (1e-6), in (0.0254) |
//! | force | N | N (1), kN (1e3), mN (1e-3), lbf (4.4482216152605), kgf (9.80665) |
//!
//! The inch is 0.0254 m and the pound-force 4.4482216152605 N exactly (NIST SP 811, 2008,
//! appendix B). Spellings are matched exactly after trimming (`g` and `G` both mean standard
//! gravity; `mN` and `MN` are not confused). Anything else is refused by the readers with the
//! file, dataset, record and line of the unit.

use serde::Serialize;

/// The physical quantity of a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    Time,
    Acceleration,
    Velocity,
    Displacement,
    Force,
}

impl Quantity {
    /// The SI unit, as printed and written (`m/s^2` in ASCII, the UFF convention).
    pub fn si_unit(self) -> &'static str {
        match self {
            Quantity::Time => "s",
            Quantity::Acceleration => "m/s^2",
            Quantity::Velocity => "m/s",
            Quantity::Displacement => "m",
            Quantity::Force => "N",
        }
    }

    /// A name for messages.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Time => "time",
            Quantity::Acceleration => "acceleration",
            Quantity::Velocity => "velocity",
            Quantity::Displacement => "displacement",
            Quantity::Force => "force",
        }
    }

    /// The UFF "specific data type" of records 8-11 (dataset 58): 17 time, 12 acceleration,
    /// 11 velocity, 8 displacement, 13 excitation force (9 reaction force reads as force too).
    pub fn uff_data_type(self) -> i64 {
        match self {
            Quantity::Time => 17,
            Quantity::Acceleration => 12,
            Quantity::Velocity => 11,
            Quantity::Displacement => 8,
            Quantity::Force => 13,
        }
    }

    /// The quantity of a UFF specific data type, when it is one of ours.
    pub fn from_uff_data_type(t: i64) -> Option<Quantity> {
        Some(match t {
            17 => Quantity::Time,
            12 => Quantity::Acceleration,
            11 => Quantity::Velocity,
            8 => Quantity::Displacement,
            9 | 13 => Quantity::Force,
            _ => return None,
        })
    }

    /// UFF unit exponents (length, force, temperature) of the SI unit in a consistent
    /// system: acceleration and velocity are length/time (1, 0, 0), displacement (1, 0, 0),
    /// force (0, 1, 0), time (0, 0, 0).
    pub fn uff_exponents(self) -> (i64, i64, i64) {
        match self {
            Quantity::Time => (0, 0, 0),
            Quantity::Acceleration | Quantity::Velocity | Quantity::Displacement => (1, 0, 0),
            Quantity::Force => (0, 1, 0),
        }
    }
}

/// Standard gravity g_n (m/s²), exact by definition (3rd CGPM, 1901).
pub const STANDARD_GRAVITY_M_PER_S2: f64 = 9.80665;
/// The inch (m), exact.
pub const INCH_M: f64 = 0.0254;
/// The pound-force (N), exact (NIST SP 811).
pub const POUND_FORCE_N: f64 = 4.448_221_615_260_5;

/// The quantity and the factor to SI of a unit label (module table), or `None`.
pub fn parse_unit(label: &str) -> Option<(Quantity, f64)> {
    use Quantity::*;
    let u = label.trim();
    let g = STANDARD_GRAVITY_M_PER_S2;
    Some(match u {
        "s" | "sec" => (Time, 1.0),
        "ms" => (Time, 1e-3),
        "us" | "µs" | "μs" => (Time, 1e-6),
        "m/s^2" | "m/s2" | "m/s**2" | "m/s²" | "m s^-2" | "m*s^-2" => (Acceleration, 1.0),
        "mm/s^2" | "mm/s2" | "mm/s**2" | "mm/s²" => (Acceleration, 1e-3),
        "cm/s^2" | "cm/s2" | "cm/s²" => (Acceleration, 1e-2),
        "g" | "G" | "gn" | "g_n" => (Acceleration, g),
        "mg" => (Acceleration, 1e-3 * g),
        "in/s^2" | "in/s2" | "in/s²" => (Acceleration, INCH_M),
        "ft/s^2" | "ft/s2" | "ft/s²" => (Acceleration, 0.3048),
        "m/s" => (Velocity, 1.0),
        "mm/s" => (Velocity, 1e-3),
        "cm/s" => (Velocity, 1e-2),
        "in/s" => (Velocity, INCH_M),
        "m" => (Displacement, 1.0),
        "mm" => (Displacement, 1e-3),
        "um" | "µm" | "μm" => (Displacement, 1e-6),
        "in" => (Displacement, INCH_M),
        "N" | "n" => (Force, 1.0),
        "kN" | "kn" => (Force, 1e3),
        "mN" => (Force, 1e-3),
        "lbf" => (Force, POUND_FORCE_N),
        "kgf" => (Force, g),
        _ => return None,
    })
}

/// The units [`parse_unit`] accepts, for messages.
pub const ACCEPTED_UNITS: &str = "s, ms, us; m/s^2, mm/s^2, cm/s^2, g, mg, in/s^2, ft/s^2; \
m/s, mm/s, in/s; m, mm, um, in; N, kN, mN, lbf, kgf";

/// Unit suffixes of CSV column names (`accel_B_m_per_s2`, `force_floor_n`, `time_s`,
/// `accel_B_g`), longest first so that `_mm_per_s2` wins over `_s2`... and `_m_per_s` over `_s`.
pub const CSV_SUFFIXES: [(&str, Quantity, f64); 16] = [
    ("_mm_per_s2", Quantity::Acceleration, 1e-3),
    ("_m_per_s2", Quantity::Acceleration, 1.0),
    ("_mm_per_s", Quantity::Velocity, 1e-3),
    ("_m_per_s", Quantity::Velocity, 1.0),
    ("_ms", Quantity::Time, 1e-3),
    ("_us", Quantity::Time, 1e-6),
    ("_s", Quantity::Time, 1.0),
    (
        "_mg",
        Quantity::Acceleration,
        1e-3 * STANDARD_GRAVITY_M_PER_S2,
    ),
    ("_g", Quantity::Acceleration, STANDARD_GRAVITY_M_PER_S2),
    ("_kn", Quantity::Force, 1e3),
    ("_n", Quantity::Force, 1.0),
    ("_lbf", Quantity::Force, POUND_FORCE_N),
    ("_mm", Quantity::Displacement, 1e-3),
    ("_um", Quantity::Displacement, 1e-6),
    ("_m", Quantity::Displacement, 1.0),
    ("_in", Quantity::Displacement, INCH_M),
];

/// Splits a CSV column name into (channel name, quantity, factor to SI) by its unit suffix
/// (case-insensitive), or `None` when it carries none of [`CSV_SUFFIXES`].
pub fn split_csv_name(name: &str) -> Option<(String, Quantity, f64)> {
    let n = name.trim();
    let lower = n.to_ascii_lowercase();
    // Longest suffix first.
    let mut best: Option<(usize, Quantity, f64)> = None;
    for (suffix, q, f) in CSV_SUFFIXES {
        if lower.ends_with(suffix)
            && lower.len() > suffix.len()
            && best.is_none_or(|b| suffix.len() > b.0)
        {
            best = Some((suffix.len(), q, f));
        }
    }
    let (len, q, f) = best?;
    Some((n[..n.len() - len].to_string(), q, f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_convert_to_si() {
        assert_eq!(parse_unit("g"), Some((Quantity::Acceleration, 9.80665)));
        assert_eq!(parse_unit(" mm/s^2 "), Some((Quantity::Acceleration, 1e-3)));
        assert_eq!(parse_unit("kN"), Some((Quantity::Force, 1e3)));
        assert_eq!(parse_unit("MN"), None);
        assert_eq!(parse_unit("furlong"), None);
        assert_eq!(parse_unit("ft/s^2").unwrap().1, 0.3048);
    }

    #[test]
    fn csv_names_split_on_the_longest_suffix() {
        let (n, q, f) = split_csv_name("accel_B_m_per_s2").unwrap();
        assert_eq!((n.as_str(), q, f), ("accel_B", Quantity::Acceleration, 1.0));
        let (n, q, _) = split_csv_name("force_floor_n").unwrap();
        assert_eq!((n.as_str(), q), ("force_floor", Quantity::Force));
        let (n, q, f) = split_csv_name("accel_B_g").unwrap();
        assert_eq!(
            (n.as_str(), q, f),
            ("accel_B", Quantity::Acceleration, 9.80665)
        );
        let (n, q, _) = split_csv_name("time_s").unwrap();
        assert_eq!((n.as_str(), q), ("time", Quantity::Time));
        let (n, q, _) = split_csv_name("bed_velocity_m_per_s").unwrap();
        assert_eq!((n.as_str(), q), ("bed_velocity", Quantity::Velocity));
        let (n, q, f) = split_csv_name("accel_mm_per_s2").unwrap();
        assert_eq!((n.as_str(), q, f), ("accel", Quantity::Acceleration, 1e-3));
        assert!(split_csv_name("ke_slider_j").is_none());
        assert!(split_csv_name("_s").is_none());
    }
}

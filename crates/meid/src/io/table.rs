//! Typed result tables (a sweep's points, a Monte Carlo's samples) for columnar output.
//!
//! A [`Table`] is the same rows as the study's CSV, with a type and an SI unit per column and
//! the file-level facts (meid version, model hash, seed, ...) that make the table
//! self-describing. [`crate::io::parquet`] (cargo feature `parquet`) writes it as Parquet.
//! This module knows the format only: the studies build their tables
//! ([`crate::analysis::table`]).

/// The values of one column.
#[derive(Debug, Clone, PartialEq)]
pub enum ColumnData {
    /// Row numbers (a sweep's grid index, a Monte Carlo sample index).
    U64(Vec<u64>),
    /// Measured or computed quantities; `None` is a value not defined for that row (null),
    /// NaN a row that failed, as in the CSV.
    F64(Vec<Option<f64>>),
    /// Text (an error message); `None` is null (no error).
    Str(Vec<Option<String>>),
}

impl ColumnData {
    /// Number of rows.
    pub fn len(&self) -> usize {
        match self {
            ColumnData::U64(v) => v.len(),
            ColumnData::F64(v) => v.len(),
            ColumnData::Str(v) => v.len(),
        }
    }

    /// No rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One named column with its unit (`"1"` for ratios and counts, `None` for text or a model
/// field whose unit is not known).
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    pub name: String,
    pub unit: Option<String>,
    pub data: ColumnData,
}

/// Columns of equal length and file-level metadata (key, value), in order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    pub columns: Vec<Column>,
    pub metadata: Vec<(String, String)>,
}

impl Table {
    /// Number of rows (0 without columns).
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |c| c.data.len())
    }
}

/// The SI unit of a result column from its name's suffix (`_j` → J, `_n_per_m` → N/m,
/// `_m_per_s2` → m/s^2, ...); `"1"` for ratios, counts and other unsuffixed names. The
/// METRIC:CASE columns of a sweep with cases take the unit of METRIC.
pub fn unit_of_column(name: &str) -> &'static str {
    const UNITS: [(&str, &str); 8] = [
        ("_m_per_s2", "m/s^2"),
        ("_m_per_s", "m/s"),
        ("_n_per_m", "N/m"),
        ("_kg", "kg"),
        ("_j", "J"),
        ("_n", "N"),
        ("_s", "s"),
        ("_m", "m"),
    ];
    let stem = name.split_once(':').map_or(name, |(m, _)| m);
    UNITS
        .iter()
        .find_map(|(suffix, u)| stem.ends_with(suffix).then_some(*u))
        .unwrap_or("1")
}

/// FNV-1a 64 of `bytes` as 16 hex digits (a content hash for identification, not security).
pub fn fnv1a_hex(bytes: &[u8]) -> String {
    crate::input::fnv1a_hex(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_from_suffixes() {
        assert_eq!(unit_of_column("peak_bed_acceleration_m_per_s2"), "m/s^2");
        assert_eq!(unit_of_column("slider_rebound_velocity_m_per_s"), "m/s");
        assert_eq!(unit_of_column("slider_contact_stiffness_n_per_m"), "N/m");
        assert_eq!(unit_of_column("damper_mass_kg"), "kg");
        assert_eq!(unit_of_column("peak_floor_force_n"), "N");
        assert_eq!(unit_of_column("collision_end_s"), "s");
        assert_eq!(unit_of_column("slider_energy_before_j:damper"), "J");
        assert_eq!(unit_of_column("energy_ratio"), "1");
        assert_eq!(unit_of_column("steps"), "1");
    }

    #[test]
    fn fnv1a_reference_values() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a_hex(b""), "cbf29ce484222325");
        assert_eq!(fnv1a_hex(b"a"), "af63dc4c8601ec8c");
        assert_eq!(fnv1a_hex(b"foobar"), "85944171f73967e8");
    }
}

//! Typed result tables (a sweep's points, a Monte Carlo's samples) for columnar output.
//!
//! A [`Table`] is the same rows as the study's CSV, with a type and an SI unit per column and
//! the file-level facts (meid version, model hash, seed, ...) that make the table
//! self-describing. [`crate::io::parquet`] (cargo feature `parquet`) writes it as Parquet.

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

/// The model facts every table carries: `meid_version`, `model` (the file as given),
/// `model_hash` ([`fnv1a_hex`] of the model file's text), `overrides` (`--set`, JSON list).
pub fn model_metadata(model: &crate::model::Model) -> Vec<(String, String)> {
    let overrides: Vec<String> = model
        .source
        .overrides
        .iter()
        .map(|(p, v)| format!("{p}={v}"))
        .collect();
    vec![
        ("meid_version".into(), env!("CARGO_PKG_VERSION").to_string()),
        ("model".into(), model.source.name.clone()),
        ("model_hash".into(), fnv1a_hex(model.source.text.as_bytes())),
        (
            "overrides".into(),
            serde_json::to_string(&overrides).unwrap_or_else(|_| "[]".into()),
        ),
    ]
}

impl crate::analysis::sweep::Sweep {
    /// `result` (this sweep's) as a [`Table`]: the columns of `sweep.csv` — `index` (u64), the
    /// varied values, K_s, K_d, m_d, m_s and every metric (f64; null where the CSV field is
    /// empty, NaN for a failed point), `error` (text, null when the point ran) — with units,
    /// and the metadata of [`model_metadata`] plus `command` = `sweep`, `fingerprint` (the
    /// shards' study fingerprint) and `sweep` (`sweep.json`'s spec as JSON).
    pub fn table(&self, result: &crate::analysis::sweep::SweepResult) -> Table {
        let points = &result.points;
        let mut columns = vec![Column {
            name: "index".into(),
            unit: Some("1".into()),
            data: ColumnData::U64(points.iter().map(|p| p.index as u64).collect()),
        }];
        for (k, v) in self.vary.iter().enumerate() {
            columns.push(Column {
                name: v.quantity.name(),
                unit: v.quantity.unit().map(str::to_string),
                data: ColumnData::F64(points.iter().map(|p| p.values.get(k).copied()).collect()),
            });
        }
        for (k, name) in crate::analysis::sweep::DERIVED.iter().enumerate() {
            columns.push(Column {
                name: name.to_string(),
                unit: Some(unit_of_column(name).into()),
                data: ColumnData::F64(points.iter().map(|p| p.derived.get(k).copied()).collect()),
            });
        }
        let names = self.columns();
        let first_metric = 1 + self.vary.len() + crate::analysis::sweep::DERIVED.len();
        let metric_names = &names[first_metric..names.len() - 1];
        for (k, name) in metric_names.iter().enumerate() {
            columns.push(Column {
                name: name.clone(),
                unit: Some(unit_of_column(name).into()),
                data: ColumnData::F64(
                    points
                        .iter()
                        .map(|p| p.metrics.get(k).copied().flatten())
                        .collect(),
                ),
            });
        }
        columns.push(Column {
            name: "error".into(),
            unit: None,
            data: ColumnData::Str(points.iter().map(|p| p.error.clone()).collect()),
        });
        let mut metadata = model_metadata(&self.model);
        metadata.push(("command".into(), "sweep".into()));
        metadata.push(("fingerprint".into(), self.fingerprint_text()));
        metadata.push((
            "sweep".into(),
            serde_json::to_string(&result.spec).unwrap_or_default(),
        ));
        Table { columns, metadata }
    }
}

impl crate::analysis::montecarlo::MonteCarlo {
    /// `result` (this study's) as a [`Table`]: the columns of `samples.csv` — `sample` (u64),
    /// the drawn inputs, the metrics (f64, null for a failed sample), `error` (text, null when
    /// the sample ran) — with units, and the metadata of [`model_metadata`] plus `command` =
    /// `montecarlo`, `seed`, `samples`, `inputs` (JSON) and `fingerprint`. The values are the
    /// exact f64 (`samples.csv` prints 13 significant digits).
    pub fn table(&self, result: &crate::analysis::montecarlo::MonteCarloResult) -> Table {
        use crate::analysis::montecarlo::METRICS;
        let s = &result.samples;
        let mut columns = vec![Column {
            name: "sample".into(),
            unit: Some("1".into()),
            data: ColumnData::U64(s.iter().map(|x| x.index as u64).collect()),
        }];
        for (k, u) in result.inputs.iter().enumerate() {
            columns.push(Column {
                name: u.path.clone(),
                unit: crate::analysis::sweep::Quantity::Field(u.path.clone())
                    .unit()
                    .map(str::to_string),
                data: ColumnData::F64(s.iter().map(|x| x.inputs.get(k).copied()).collect()),
            });
        }
        for (k, name) in METRICS.iter().enumerate() {
            columns.push(Column {
                name: name.to_string(),
                unit: Some(unit_of_column(name).into()),
                data: ColumnData::F64(s.iter().map(|x| x.metrics.map(|m| m[k])).collect()),
            });
        }
        columns.push(Column {
            name: "error".into(),
            unit: None,
            data: ColumnData::Str(s.iter().map(|x| x.error.clone()).collect()),
        });
        let mut metadata = model_metadata(&self.model);
        metadata.push(("command".into(), "montecarlo".into()));
        metadata.push(("seed".into(), result.seed.to_string()));
        metadata.push(("samples".into(), s.len().to_string()));
        metadata.push((
            "inputs".into(),
            serde_json::to_string(&result.inputs).unwrap_or_default(),
        ));
        metadata.push(("fingerprint".into(), self.fingerprint()));
        Table { columns, metadata }
    }
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

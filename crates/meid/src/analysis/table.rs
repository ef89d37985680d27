//! The studies' results as typed tables ([`Table`]) for columnar output: a sweep's points
//! ([`Sweep::table`]) and a Monte Carlo's samples ([`MonteCarlo::table`]), each with the model
//! facts of [`model_metadata`]. The format (columns, units, Parquet) is [`crate::io::table`]'s.

use super::montecarlo::{MonteCarlo, MonteCarloResult, METRICS};
use super::sweep::{Quantity, Sweep, SweepResult, DERIVED};
use crate::io::table::{fnv1a_hex, unit_of_column, Column, ColumnData, Table};
use crate::model::Model;

/// The model facts every table carries: `meid_version`, `model` (the file as given),
/// `model_hash` ([`fnv1a_hex`] of the model file's text), `overrides` (`--set`, JSON list).
pub fn model_metadata(model: &Model) -> Vec<(String, String)> {
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

impl Sweep {
    /// `result` (this sweep's) as a [`Table`]: the columns of `sweep.csv` — `index` (u64), the
    /// varied values, K_s, K_d, m_d, m_s and every metric (f64; null where the CSV field is
    /// empty, NaN for a failed point), `error` (text, null when the point ran) — with units,
    /// and the metadata of [`model_metadata`] plus `command` = `sweep`, `fingerprint` (the
    /// shards' study fingerprint) and `sweep` (`sweep.json`'s spec as JSON).
    pub fn table(&self, result: &SweepResult) -> Table {
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
        for (k, name) in DERIVED.iter().enumerate() {
            columns.push(Column {
                name: name.to_string(),
                unit: Some(unit_of_column(name).into()),
                data: ColumnData::F64(points.iter().map(|p| p.derived.get(k).copied()).collect()),
            });
        }
        let names = self.columns();
        let first_metric = 1 + self.vary.len() + DERIVED.len();
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

impl MonteCarlo {
    /// `result` (this study's) as a [`Table`]: the columns of `samples.csv` — `sample` (u64),
    /// the drawn inputs, the metrics (f64, null for a failed sample), `error` (text, null when
    /// the sample ran) — with units, and the metadata of [`model_metadata`] plus `command` =
    /// `montecarlo`, `seed`, `samples`, `inputs` (JSON) and `fingerprint`. The values are the
    /// exact f64 (`samples.csv` prints 13 significant digits).
    pub fn table(&self, result: &MonteCarloResult) -> Table {
        let s = &result.samples;
        let mut columns = vec![Column {
            name: "sample".into(),
            unit: Some("1".into()),
            data: ColumnData::U64(s.iter().map(|x| x.index as u64).collect()),
        }];
        for (k, u) in result.inputs.iter().enumerate() {
            columns.push(Column {
                name: u.path.clone(),
                unit: Quantity::Field(u.path.clone()).unit().map(str::to_string),
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

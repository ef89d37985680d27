//! Sweeps over a general machine's fields ([`crate::model::network`]) and the quantities a
//! designer reads on one: `meid sweep GENERAL.toml --vary PATH=VALUES`.
//!
//! A varied path is any `--set` path of the machine, its arrays' entries named by name
//! ([`crate::model::network_fields`]): `damper.damper1.mass=0.5..2:7`,
//! `contact.bed_damper1.gap=0,1e-4,2e-4`, `impactor.slider.velocity=0.6..1.8:5`, or a list of
//! structure points for a damper's place, `damper.damper1.point=[D1,D2,S]`. One or two paths;
//! the grid is their Cartesian product, the last fastest. Every point is the model the file
//! gives with the base's `--set` overrides followed by the point's `PATH=VALUE`s (so a point
//! equals `meid simulate FILE --set …` of the same values, bit for bit), its structure reused
//! when the point leaves the structure's key unchanged
//! ([`crate::model::network_fields::NetKey`]).
//!
//! The metrics of a point ([`metrics`]), all from its exact run
//! ([`crate::analysis::network::summary`]): `energy_ratio` (the share of the blows' energy
//! `KE_b(0) + W+` kept by the structure at the end of the collision), `collision_end_s`,
//! `dissipated_energy_j`, `floor_force_n` (the peak force to the floor, when something carries
//! force to it), `peak_force_n:CONTACT` (each contact's largest compressive force) and
//! `peak_acceleration_m_per_s2:POINT` (each named point's largest |acceleration|).
//!
//! With a stroke rate ([`NetSweep::at_rate`]: `--rate-bpm R`, or the file's `[production]
//! rate_bpm`) every point is judged on its **steady blow** at that rate instead
//! ([`super::network_blows::steady_state`]): the same columns from the steady blow
//! (`collision_end_s` of its first blow; `dissipated_energy_j` has no value), and
//! `dampers_return` (1 when the train settled and every damper touches its point before each
//! strike, 0 otherwise).

use rayon::prelude::*;
use serde::Serialize;

use super::network::{summary, NetSummary};
use super::network_blows::settled_steady_state;
use super::sweep::parse_values;
use crate::model::network::NetworkModel;
use crate::model::network_fields::NetCache;
use crate::{Error, Result};

/// A varied value: a number, or a name (a structure point for `damper.NAME.point`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum NetValue {
    Number(f64),
    Name(String),
}

impl NetValue {
    /// The TOML value of an override: a number in Rust's shortest round-trip form, a name as
    /// a TOML string.
    pub fn toml(&self) -> String {
        match self {
            NetValue::Number(v) => format!("{v:e}"),
            NetValue::Name(n) => toml::Value::String(n.clone()).to_string(),
        }
    }

    /// The value as shown in tables (a number plain, a name as is).
    pub fn label(&self) -> String {
        match self {
            NetValue::Number(v) => format!("{v}"),
            NetValue::Name(n) => n.clone(),
        }
    }
}

/// One varied path and its values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetVary {
    /// The SPEC as given.
    pub spec: String,
    pub path: String,
    pub values: Vec<NetValue>,
}

impl NetVary {
    /// Parses `PATH=LIST`, `PATH=A..B:N`, `PATH=A..B:N:log` or `PATH=[NAME,NAME,…]`.
    pub fn parse(spec: &str) -> Result<Self> {
        let usage = "expected PATH=LIST (damper.damper1.mass=0.5,1,2), PATH=A..B:N (linear), PATH=A..B:N:log or PATH=[NAME,...] (damper.damper1.point=[D1,D2,S])";
        let (path, rhs) = spec
            .split_once('=')
            .ok_or_else(|| Error::invalid("--vary", format!("`{spec}`: {usage}")))?;
        let (path, rhs) = (path.trim(), rhs.trim());
        if path.is_empty() || rhs.is_empty() {
            return Err(Error::invalid("--vary", format!("`{spec}`: {usage}")));
        }
        let values = match rhs.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            Some(list) => {
                let items: Vec<&str> = list
                    .split(',')
                    .map(|s| s.trim().trim_matches('"').trim_matches('\''))
                    .collect();
                if items.iter().any(|s| s.is_empty()) {
                    return Err(Error::invalid(
                        "--vary",
                        format!("`{spec}`: an empty name in the list; {usage}"),
                    ));
                }
                items
                    .iter()
                    .map(|s| match s.parse::<f64>() {
                        Ok(v) => NetValue::Number(v),
                        Err(_) => NetValue::Name(s.to_string()),
                    })
                    .collect()
            }
            None => parse_values(rhs, spec, "--vary")?
                .1
                .into_iter()
                .map(NetValue::Number)
                .collect(),
        };
        Ok(Self {
            spec: spec.to_string(),
            path: path.to_string(),
            values,
        })
    }
}

/// The metrics of a general machine's run (module docs), `(column, value)` in a fixed order;
/// `None` where the run has no value (no energy ratio when the collision did not end).
pub fn metrics(s: &NetSummary) -> Vec<(String, Option<f64>)> {
    let mut out = vec![
        ("energy_ratio".to_string(), s.energy_ratio),
        ("collision_end_s".to_string(), s.collision_end_s),
        (
            "dissipated_energy_j".to_string(),
            Some(s.dissipated_energy_j),
        ),
    ];
    if let Some(f) = &s.floor_force_n {
        out.push(("floor_force_n".into(), Some(f.peak.abs())));
    }
    for c in &s.contacts {
        out.push((
            format!("peak_force_n:{}", c.name),
            Some(c.peak_force_n.peak),
        ));
    }
    for p in &s.points {
        out.push((
            format!("peak_acceleration_m_per_s2:{}", p.name),
            Some(p.acceleration_m_per_s2.peak.abs()),
        ));
    }
    out
}

/// One grid point's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetPoint {
    pub index: usize,
    pub values: Vec<NetValue>,
    /// The metrics in [`NetSweepResult::columns`]' order (`None`: no value, or the run failed).
    pub metrics: Vec<Option<f64>>,
    /// Why the point has no result (a bad value, a failed run).
    pub error: Option<String>,
}

/// The result of a sweep over a general machine.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetSweepResult {
    pub machine: &'static str,
    pub vary: Vec<NetVary>,
    pub columns: Vec<String>,
    pub points: Vec<NetPoint>,
    /// Structures built beyond the base's (the rest reused it).
    pub structures_built: usize,
}

/// A sweep over a general machine's fields (module docs).
#[derive(Debug)]
pub struct NetSweep {
    pub model: NetworkModel,
    pub vary: Vec<NetVary>,
    columns: Vec<String>,
    /// The stroke rate at which every point is judged on its steady blow (module docs).
    rate_bpm: Option<f64>,
}

impl NetSweep {
    /// The sweep of `model` over `vary` (one or two paths). Every path and value is checked
    /// on the grid's first point of each value before any run.
    pub fn new(model: NetworkModel, vary: Vec<NetVary>) -> Result<Self> {
        if vary.is_empty() || vary.len() > 2 {
            return Err(Error::invalid(
                "--vary",
                format!(
                    "a general machine's sweep takes one or two --vary (got {})",
                    vary.len()
                ),
            ));
        }
        for (i, v) in vary.iter().enumerate() {
            if vary[..i].iter().any(|w| w.path == v.path) {
                return Err(Error::invalid(
                    "--vary",
                    format!("{} is varied twice", v.path),
                ));
            }
        }
        model.options()?;
        for v in &vary {
            check_values(&model, v)?;
        }
        let columns = columns_of(&model);
        Ok(Self {
            model,
            vary,
            columns,
            rate_bpm: None,
        })
    }

    /// Every point judged on its steady blow at `rate_bpm` (module docs); `None` keeps the
    /// first blow. Adds the `dampers_return` column.
    pub fn at_rate(mut self, rate_bpm: Option<f64>) -> Result<Self> {
        if let Some(r) = rate_bpm {
            super::network_blows::check_rate(r)?;
            if self.rate_bpm.is_none() {
                self.columns.push("dampers_return".into());
            }
        }
        self.rate_bpm = rate_bpm;
        Ok(self)
    }

    /// The metric columns, in order.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// Grid points.
    pub fn len(&self) -> usize {
        self.vary.iter().map(|v| v.values.len()).product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values of grid point `index` (last path fastest).
    pub fn values_at(&self, index: usize) -> Vec<NetValue> {
        let mut rest = index;
        let mut out = vec![NetValue::Number(0.0); self.vary.len()];
        for (k, v) in self.vary.iter().enumerate().rev() {
            let n = v.values.len();
            out[k] = v.values[rest % n].clone();
            rest /= n;
        }
        out
    }

    /// The overrides of grid point `index`: `PATH=VALUE` per varied path.
    pub fn fields_at(&self, index: usize) -> Vec<String> {
        self.vary
            .iter()
            .zip(self.values_at(index))
            .map(|(v, x)| format!("{}={}", v.path, x.toml()))
            .collect()
    }

    /// The model of grid point `index` (structure reused through `cache`).
    pub fn model_at(&self, index: usize, cache: &NetCache) -> Result<NetworkModel> {
        self.model.with_fields(&self.fields_at(index), Some(cache))
    }

    /// Runs every point (in parallel, collected in grid order); `progress` is called with the
    /// count of finished points. A point that fails keeps its error and no metrics.
    pub fn run(&self, progress: &(dyn Fn(usize) + Sync)) -> NetSweepResult {
        self.run_unless(progress, &std::sync::atomic::AtomicBool::new(false))
    }

    /// [`Self::run`], except that once `cancel` is set the points not yet started are not run
    /// (their rows carry the error "interrupted"); a point's result does not depend on it.
    pub fn run_unless(
        &self,
        progress: &(dyn Fn(usize) + Sync),
        cancel: &std::sync::atomic::AtomicBool,
    ) -> NetSweepResult {
        use std::sync::atomic::Ordering;
        let cache = NetCache::new();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let points = (0..self.len())
            .into_par_iter()
            .map(|i| {
                if cancel.load(Ordering::Relaxed) {
                    return NetPoint {
                        index: i,
                        values: self.values_at(i),
                        metrics: vec![None; self.columns.len()],
                        error: Some("interrupted".into()),
                    };
                }
                let r = self.point(i, &cache);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                r
            })
            .collect();
        NetSweepResult {
            machine: "general",
            vary: self.vary.clone(),
            columns: self.columns.clone(),
            points,
            structures_built: cache.builds(),
        }
    }

    /// The metrics of grid point `index`'s steady blow at `rate_bpm` (module docs).
    fn steady_point(
        &self,
        index: usize,
        cache: &NetCache,
        rate_bpm: f64,
    ) -> Result<Vec<Option<f64>>> {
        let m = self.model_at(index, cache)?;
        let s = settled_steady_state(&m, rate_bpm)?;
        Ok(self
            .columns
            .iter()
            .map(|c| match c.as_str() {
                "dampers_return" => Some(if s.dampers_return() { 1.0 } else { 0.0 }),
                "collision_end_s" => s.blows.first().and_then(|b| b.collision_end_s),
                "dissipated_energy_j" => None,
                c => s.metric(c),
            })
            .collect())
    }

    fn point(&self, index: usize, cache: &NetCache) -> NetPoint {
        let values = self.values_at(index);
        let got = match self.rate_bpm {
            Some(rate) => self.steady_point(index, cache, rate),
            None => self.first_blow_point(index, cache),
        };
        match got {
            Ok(metrics) => NetPoint {
                index,
                values,
                metrics,
                error: None,
            },
            Err(e) => NetPoint {
                index,
                values,
                metrics: vec![None; self.columns.len()],
                error: Some(e.to_string()),
            },
        }
    }

    /// The metrics of grid point `index`'s first blow, in column order.
    fn first_blow_point(&self, index: usize, cache: &NetCache) -> Result<Vec<Option<f64>>> {
        let m = self.model_at(index, cache)?;
        let sol = m.solve(&m.options()?)?;
        let got = metrics(&summary(&m, &sol));
        Ok(self
            .columns
            .iter()
            .map(|c| got.iter().find(|(n, _)| n == c).and_then(|(_, v)| *v))
            .collect())
    }
}

/// The metric columns of `model`'s runs: fixed by its contacts, points and floor.
fn columns_of(model: &NetworkModel) -> Vec<String> {
    let net = &model.network;
    let mut out: Vec<String> = ["energy_ratio", "collision_end_s", "dissipated_energy_j"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    if net.has_floor_force() {
        out.push("floor_force_n".into());
    }
    out.extend(
        net.contacts
            .iter()
            .map(|c| format!("peak_force_n:{}", c.name)),
    );
    out.extend(
        net.structure
            .points
            .keys()
            .map(|p| format!("peak_acceleration_m_per_s2:{p}")),
    );
    out
}

/// Checks every value of `v` before any run: the path (named entries, fields) as the file
/// would take it, and a point or anchor name against the structure's points.
fn check_values(model: &NetworkModel, v: &NetVary) -> Result<()> {
    let base: Vec<String> = model
        .source
        .overrides
        .iter()
        .map(|(p, x)| format!("{p}={x}"))
        .collect();
    let is_place = v.path.ends_with(".point") || v.path.ends_with(".anchor");
    for x in &v.values {
        let mut fields = base.clone();
        fields.push(format!("{}={}", v.path, x.toml()));
        crate::model::network::read_spec(&model.source.name, model.source.text.clone(), &fields)
            .map_err(|e| Error::invalid("--vary", format!("`{}`: {e}", v.spec)))?;
        match x {
            NetValue::Name(n) if is_place => {
                let ground = v.path.ends_with(".anchor") && n == "ground";
                if !ground && !model.structure.points.contains_key(n) {
                    let known: Vec<&str> =
                        model.structure.points.keys().map(|s| s.as_str()).collect();
                    return Err(Error::invalid(
                        "--vary",
                        format!(
                            "`{}`: '{n}' is not a structure point{} (valid: {})",
                            v.spec,
                            crate::model::network_paths::did_you_mean(n, &known),
                            known.join(", ")
                        ),
                    ));
                }
            }
            NetValue::Name(n) => {
                return Err(Error::invalid(
                    "--vary",
                    format!("`{}`: '{n}' is not a number (names are values of damper.NAME.point or .anchor only)", v.spec),
                ))
            }
            NetValue::Number(_) if is_place => {
                return Err(Error::invalid(
                    "--vary",
                    format!("`{}`: a damper's point is a structure point's name: give a list of names, e.g. {}=[D1,D2]", v.spec, v.path),
                ))
            }
            NetValue::Number(_) => {}
        }
    }
    Ok(())
}

impl NetSweepResult {
    /// The table as CSV: `index`, the varied paths, the metric columns, `error`.
    pub fn to_csv(&self) -> String {
        let q = |s: &str| {
            if s.contains([',', '"', '\n']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.to_string()
            }
        };
        let mut s = String::from("index");
        for v in &self.vary {
            s += &format!(",{}", q(&v.path));
        }
        for c in &self.columns {
            s += &format!(",{}", q(c));
        }
        s += ",error\n";
        for p in &self.points {
            s += &p.index.to_string();
            for v in &p.values {
                s += &format!(",{}", q(&v.label()));
            }
            for m in &p.metrics {
                s += &m.map_or(",".to_string(), |x| format!(",{x:e}"));
            }
            s += &format!(",{}\n", q(p.error.as_deref().unwrap_or("")));
        }
        s
    }

    /// The index of column `metric`, or an error listing the valid ones.
    pub fn column(&self, metric: &str) -> Result<usize> {
        self.columns
            .iter()
            .position(|c| c == metric)
            .ok_or_else(|| {
                let known: Vec<&str> = self.columns.iter().map(|s| s.as_str()).collect();
                Error::invalid(
                    "--metric",
                    format!(
                        "unknown metric `{metric}` for this machine{} (valid: {})",
                        crate::model::network_paths::did_you_mean(metric, &known),
                        known.join(", ")
                    ),
                )
            })
    }
}

//! A general impact machine in Python (`meid.Machine`): a model file with `[[impactor]]`,
//! `[[damper]]` and `[[contact]]` arrays ([`meid::model::network`]), run by the exact network
//! engine. The same problem → solve → solution shape as `meid.Model`: `Machine.from_file` /
//! `from_toml`, `with_values` (named array paths such as `damper.damper1.mass`), `simulate` →
//! `Run` (the summary of `meid simulate --json` on that file, with its per-impact table), and
//! the sweep (`meid.sweep(machine, vary=...)`) over any of its fields, points included.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use meid::analysis::network::summary;
use meid::analysis::network_study::{NetSweep, NetVary};
use meid::model::network::NetworkModel;

use crate::{err, field_list, interruptible, override_list, pool, toml_real};
use crate::{MeidError, MeidWarning, Run};

/// A validated general impact machine: impactors, dampers and contacts on a structure reduced
/// to its modes. Build it with `Machine.from_file` or `Machine.from_toml` (or `meid.load`,
/// which reads either kind of model file).
#[pyclass(module = "meid", frozen)]
#[derive(Clone)]
pub struct Machine {
    pub(crate) inner: NetworkModel,
}

#[pymethods]
impl Machine {
    /// Reads and validates a general machine's file (TOML), applying `overrides`
    /// ("PATH=VALUE", as the CLI's `--set`; named paths such as `damper.damper1.mass`).
    #[staticmethod]
    #[pyo3(signature = (path, overrides=None))]
    fn from_file(
        py: Python<'_>,
        path: std::path::PathBuf,
        overrides: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let ov = override_list(overrides)?;
        py.detach(|| NetworkModel::from_file(&path, &ov))
            .map(|inner| Machine { inner })
            .map_err(err)
    }

    /// Parses and validates a general machine's text; `name` is what error messages call it.
    #[staticmethod]
    #[pyo3(signature = (text, name="<string>".to_string(), overrides=None))]
    fn from_toml(
        py: Python<'_>,
        text: String,
        name: String,
        overrides: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let ov = override_list(overrides)?;
        py.detach(|| NetworkModel::from_text(&name, text, &ov))
            .map(|inner| Machine { inner })
            .map_err(err)
    }

    /// This machine with fields set, as `--set PATH=VALUE` would:
    /// `{"damper.damper1.mass": 1.2, "damper.damper1.point": "D2"}`.
    fn with_values(&self, py: Python<'_>, values: &Bound<'_, PyDict>) -> PyResult<Self> {
        let fields = field_list(values, "damper.damper1.mass")?;
        py.detach(|| self.inner.with_fields(&fields, None))
            .map(|inner| Machine { inner })
            .map_err(err)
    }

    /// One run of the machine (exact engine) for `duration` s (default: its `[simulation]`):
    /// a `Run` whose `summary` is `meid simulate --json`'s object (energy ratio, per contact,
    /// damper, impactor and point, the floor force, `impacts`: one row per closing of a
    /// contact). A general machine keeps no sampled history (`Run.history` is `None`).
    #[pyo3(signature = (duration=None))]
    fn simulate(&self, py: Python<'_>, duration: Option<f64>) -> PyResult<Run> {
        let s = py
            .detach(|| -> meid::Result<_> {
                let m = match duration {
                    None => self.inner.clone(),
                    Some(d) => self
                        .inner
                        .with_fields(&[format!("simulation.duration={}", toml_real(d))], None)?,
                };
                let sol = m.solve(&m.options()?)?;
                Ok(summary(&m, &sol))
            })
            .map_err(err)?;
        let json = serde_json::to_string(&s).map_err(|e| MeidError::new_err(e.to_string()))?;
        let warn = py.import("warnings")?;
        let category = py.get_type::<MeidWarning>();
        for w in &s.warnings {
            warn.call_method1("warn", (w.as_str(), &category, 1))?;
        }
        Ok(Run::from_summary(json))
    }

    /// The file name (or the name given) the machine was read from.
    #[getter]
    fn name(&self) -> String {
        self.inner.source.name.clone()
    }

    /// The overrides applied to the file's text, as "PATH=VALUE" strings.
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.inner
            .source
            .overrides
            .iter()
            .map(|(p, v)| format!("{p}={v}"))
            .collect()
    }

    /// The names of the machine's impactors, dampers, contacts and structure points.
    fn names<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner.spec;
        let d = PyDict::new(py);
        d.set_item(
            "impactor",
            s.impactor
                .iter()
                .map(|b| b.name.clone())
                .collect::<Vec<_>>(),
        )?;
        d.set_item(
            "damper",
            s.damper.iter().map(|b| b.name.clone()).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "contact",
            s.contact.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        )?;
        d.set_item(
            "point",
            self.inner
                .structure
                .points
                .keys()
                .cloned()
                .collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let s = &self.inner.spec;
        format!(
            "meid.Machine({:?}: {} impactor(s), {} damper(s), {} contact(s))",
            self.name(),
            s.impactor.len(),
            s.damper.len(),
            s.contact.len()
        )
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::Reduce<'py>> {
        // Pickled as its text and overrides (dask ships models to workers this way).
        let f = py
            .import("meid")?
            .getattr("Machine")?
            .getattr("from_toml")?;
        Ok((
            f,
            (
                self.inner.source.text.clone(),
                self.inner.source.name.clone(),
                self.overrides(),
            ),
        ))
    }
}

/// A sweep of a general machine over `specs` ("PATH=LIST", "PATH=A..B:N[:log]", a list of
/// names for a point field: "damper.damper1.point=[D1,D2]"), one or two paths: `meid sweep
/// GENERAL.toml --vary ...`'s result as JSON text (`columns`, `vary`, `points` with their
/// `values`, `metrics` in column order and `error`).
#[pyfunction]
#[pyo3(signature = (machine, specs, threads=None))]
pub(crate) fn machine_sweep_json(
    py: Python<'_>,
    machine: &Machine,
    specs: Vec<String>,
    threads: Option<i64>,
) -> PyResult<String> {
    let vary = specs
        .iter()
        .map(|s| NetVary::parse(s))
        .collect::<meid::Result<Vec<_>>>()
        .map_err(err)?;
    let sweep = NetSweep::new(machine.inner.clone(), vary).map_err(err)?;
    // A row holds its values, metrics and error text: bounded before anything runs.
    let row_bytes = 64.0 * (sweep.columns().len() + specs.len() + 4) as f64;
    meid::limits::check_memory(
        &format!("the sweep's {} rows", sweep.len()),
        sweep.len() as f64 * row_bytes,
        "vary",
        "fewer grid points (split the grid into several calls)",
    )
    .map_err(err)?;
    let pool = pool(threads)?;
    let (result, interrupted) =
        py.detach(|| interruptible(&pool, |cancel| sweep.run_unless(&|_| {}, cancel)));
    if let Some(e) = interrupted {
        return Err(e);
    }
    serde_json::to_string(&result).map_err(|e| MeidError::new_err(e.to_string()))
}

/// A general machine in production at `rate_bpm` blows/min (`None`: its `[production]
/// rate_bpm`, else 60): `meid blows GENERAL.toml --json`'s object as JSON text. With `steady`,
/// the verdict and the periodic steady state found directly (`--steady`); without, the march
/// of `blows` blows from rest.
#[pyfunction]
#[pyo3(signature = (machine, rate_bpm=None, steady=true, blows=10))]
pub(crate) fn machine_blows_json(
    py: Python<'_>,
    machine: &Machine,
    rate_bpm: Option<f64>,
    steady: bool,
    blows: i64,
) -> PyResult<String> {
    use meid::analysis::blows::BlowOptions;
    use meid::analysis::network_blows::{run_blows, steady_object, steady_state, stroke_rate};
    use meid::analysis::steady::SteadyOptions;
    let blows = crate::count("blows", blows, 1)?;
    let out = py
        .detach(|| -> meid::Result<serde_json::Value> {
            let m = &machine.inner;
            let rate_bpm = stroke_rate(m, rate_bpm)?;
            let je = |e: serde_json::Error| meid::Error::numerical("blows", e.to_string());
            if steady {
                let so = SteadyOptions {
                    rate_bpm,
                    ..SteadyOptions::default()
                };
                Ok(steady_object(&steady_state(m, &so)?))
            } else {
                let b = BlowOptions {
                    blows,
                    rate_bpm,
                    ..BlowOptions::default()
                };
                serde_json::to_value(run_blows(m, &b)?).map_err(je)
            }
        })
        .map_err(err)?;
    // `warnings` and `notes` as every JSON object of the CLI carries them.
    let mut out = out;
    if let serde_json::Value::Object(o) = &mut out {
        for key in ["warnings", "notes"] {
            o.entry(key)
                .or_insert_with(|| serde_json::Value::Array(Vec::new()));
        }
    }
    serde_json::to_string(&out).map_err(|e| MeidError::new_err(e.to_string()))
}

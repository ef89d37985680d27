//! Python bindings of meid: the extension module `meid._meid`, wrapped by the pure-Python
//! package `meid` (crates/meid-py/python/meid). Problem → solve → solution:
//! [`Model`] (from a file, TOML text or a dict; `with_values`), `Model.simulate` → [`Run`]
//! (summary dict, history as numpy arrays), `Model.modes`, and the studies `sweep`,
//! `montecarlo`, `evaluate` as columns of numpy arrays (the package turns them into a pyarrow
//! Table or a pandas DataFrame). Every study releases the GIL and runs on rayon's threads.
//! meid's errors become `meid.InputError` (bad input: the message names the file:line:column or
//! the `--set`/field) or `meid.MeidError`, with meid's own message.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use meid::analysis::montecarlo::{self, MonteCarlo, Uncertain};
use meid::analysis::sweep::{self, Quantity, Sweep, Vary};
use meid::model::{Case, StructureCache};

create_exception!(
    meid,
    MeidError,
    PyException,
    "An error of meid (numerical, I/O)."
);
create_exception!(
    meid,
    InputError,
    MeidError,
    "Bad input: the message names the file:line:column, the field or the override, and what would be valid."
);

fn err(e: meid::Error) -> PyErr {
    match e {
        meid::Error::Input { .. } | meid::Error::InvalidValue { .. } => {
            InputError::new_err(e.to_string())
        }
        _ => MeidError::new_err(e.to_string()),
    }
}

fn pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err(InputError::new_err("threads: needs at least 1"));
        }
        b = b.num_threads(n);
    }
    b.build()
        .map_err(|e| MeidError::new_err(format!("cannot start the worker threads: {e}")))
}

/// The TOML literal of a Python value for a field (`with_values`): int → integer, float →
/// shortest round-trip real, bool, str → TOML string.
fn literal(path: &str, v: &Bound<'_, PyAny>) -> PyResult<String> {
    if v.is_instance_of::<PyBool>() {
        return Ok(v.extract::<bool>()?.to_string());
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(v.extract::<i64>()?.to_string());
    }
    if let Ok(x) = v.extract::<f64>() {
        if !v.is_instance_of::<PyString>() {
            return Ok(format!("{x:e}"));
        }
    }
    if let Ok(s) = v.extract::<String>() {
        return Ok(toml::Value::String(s).to_string());
    }
    Err(InputError::new_err(format!(
        "{path}: a value must be a number, a bool or a string (got {})",
        v.get_type().name()?
    )))
}

/// A Python dict/list/scalar as a TOML value (`Model.from_dict`).
fn to_toml(path: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            if x.is_none() {
                continue; // TOML has no null: an absent key (what `to_dict` writes as None).
            }
            let k: String = k.extract().map_err(|_| {
                InputError::new_err(format!("{path}: dictionary keys must be strings"))
            })?;
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            t.insert(k, to_toml(&p, &x)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for (i, x) in v.try_iter()?.enumerate() {
            a.push(to_toml(&format!("{path}[{i}]"), &x?)?);
        }
        return Ok(toml::Value::Array(a));
    }
    Err(InputError::new_err(format!(
        "{path}: cannot be written as TOML (got {}); use dicts, lists, str, int, float, bool",
        v.get_type().name()?
    )))
}

fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// A validated meid model: the structure reduced to its modes, the contacts, the damper and
/// the simulation settings. Build it with `Model.from_file`, `Model.from_toml` or
/// `Model.from_dict`.
#[pyclass(module = "meid", frozen)]
#[derive(Clone)]
pub struct Model {
    inner: meid::model::Model,
}

#[pymethods]
impl Model {
    /// Reads and validates a model file (TOML), applying `overrides` ("PATH=VALUE", as the
    /// CLI's `--set`) in order.
    #[staticmethod]
    #[pyo3(signature = (path, overrides=None))]
    fn from_file(
        py: Python<'_>,
        path: std::path::PathBuf,
        overrides: Option<Vec<String>>,
    ) -> PyResult<Self> {
        let ov = overrides.unwrap_or_default();
        py.detach(|| meid::model::Model::from_file(&path, &ov))
            .map(|inner| Model { inner })
            .map_err(err)
    }

    /// Parses and validates model text; `name` is what error messages call it.
    #[staticmethod]
    #[pyo3(signature = (text, name="<string>".to_string(), overrides=None))]
    fn from_toml(
        py: Python<'_>,
        text: String,
        name: String,
        overrides: Option<Vec<String>>,
    ) -> PyResult<Self> {
        let ov = overrides.unwrap_or_default();
        py.detach(|| meid::model::Model::from_text(&name, text, &ov))
            .map(|inner| Model { inner })
            .map_err(err)
    }

    /// A model from a dict with the layout of a model file (nested tables as dicts); errors
    /// name the field and the line of the TOML text it becomes.
    #[staticmethod]
    #[pyo3(signature = (d, name="<dict>".to_string()))]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyDict>, name: String) -> PyResult<Self> {
        let toml::Value::Table(t) = to_toml("", d.as_any())? else {
            return Err(InputError::new_err("from_dict needs a dict"));
        };
        let text = toml::to_string(&t)
            .map_err(|e| InputError::new_err(format!("{name}: cannot write TOML: {e}")))?;
        py.detach(|| meid::model::Model::from_text(&name, text, &[]))
            .map(|inner| Model { inner })
            .map_err(err)
    }

    /// This model with fields set, as `--set PATH=VALUE` would: `{"contact.slider_bed.stiffness":
    /// 4.3e7}`. The structure's modes are reused unless a value changes the structure.
    fn with_values(&self, py: Python<'_>, values: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut fields = Vec::new();
        for (k, v) in values.iter() {
            let k: String = k.extract()?;
            fields.push(format!("{k}={}", literal(&k, &v)?));
        }
        py.detach(|| self.inner.with_fields(&fields, None))
            .map(|inner| Model { inner })
            .map_err(err)
    }

    /// One blow: `method` "exact" or "dopri5", `duration` (s) and `rate` (Hz) override the
    /// model's `[simulation]`; `case` is "as-specified", "none", "damper" or "added-mass".
    /// With `history`, the sampled time histories are kept (`Run.history`).
    #[pyo3(signature = (method=None, duration=None, rate=None, case="as-specified".to_string(), history=true))]
    fn simulate(
        &self,
        py: Python<'_>,
        method: Option<String>,
        duration: Option<f64>,
        rate: Option<f64>,
        case: String,
        history: bool,
    ) -> PyResult<Run> {
        let mut fields = Vec::new();
        if let Some(m) = method {
            fields.push(format!("simulation.method={}", toml::Value::String(m)));
        }
        if let Some(d) = duration {
            fields.push(format!("simulation.duration={d:e}"));
        }
        if let Some(r) = rate {
            fields.push(format!("simulation.sample_rate={r:e}"));
        }
        let case: Case = case.parse().map_err(err)?;
        let run = py
            .detach(|| -> meid::Result<_> {
                let m = if fields.is_empty() {
                    self.inner.clone()
                } else {
                    self.inner.with_fields(&fields, None)?
                };
                let sys = m.impact_system(case)?;
                meid::analysis::simulate(&sys, &m.options(), history)
            })
            .map_err(err)?;
        let summary =
            serde_json::to_string(&run.summary).map_err(|e| MeidError::new_err(e.to_string()))?;
        let columns = run.history.map(|h| {
            let n = h.time_s.len();
            let mut cols: Vec<Vec<f64>> =
                vec![Vec::with_capacity(n); meid::io::HISTORY_COLUMNS.len()];
            for i in 0..n {
                for (c, v) in cols.iter_mut().zip(h.row(i)) {
                    c.push(v);
                }
            }
            cols
        });
        Ok(Run {
            summary_json: summary,
            columns,
        })
    }

    /// The retained modes: `{"frequencies_hz": (n,), "points": [names], "shapes": (points, n)}`
    /// (signed mass-normalised ψ along the impact axis at the named points, 1/√kg; points in
    /// name order, as the ψ columns of `meid modes`' modes.csv), the first `count` when given.
    #[pyo3(signature = (count=None))]
    fn modes<'py>(&self, py: Python<'py>, count: Option<usize>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner.structure;
        let n = count.unwrap_or(s.len()).min(s.len());
        let f: Vec<f64> = s.omega_rad_per_s[..n]
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect();
        let names: Vec<String> = s.points.keys().cloned().collect();
        let mut flat = Vec::with_capacity(names.len() * n);
        for p in &names {
            flat.extend_from_slice(&s.points[p][..n]);
        }
        let d = PyDict::new(py);
        d.set_item("frequencies_hz", PyArray1::from_vec(py, f))?;
        d.set_item("points", names.clone())?;
        d.set_item(
            "shapes",
            PyArray1::from_vec(py, flat).reshape([names.len(), n])?,
        )?;
        d.set_item("labels", s.labels[..n.min(s.labels.len())].to_vec())?;
        Ok(d)
    }

    /// The file name (or the name given) the model was read from.
    #[getter]
    fn name(&self) -> String {
        self.inner.source.name.clone()
    }

    /// The overrides applied, as "PATH=VALUE".
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.inner
            .source
            .overrides
            .iter()
            .map(|(p, v)| format!("{p}={v}"))
            .collect()
    }

    /// The model's values (after overrides) as a dict with the layout of a model file.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = serde_json::to_string(&self.inner.spec)
            .map_err(|e| MeidError::new_err(e.to_string()))?;
        json_to_py(py, &s)
    }

    fn __repr__(&self) -> String {
        format!(
            "meid.Model({:?}, {} modes{})",
            self.inner.source.name,
            self.inner.structure.len(),
            if self.inner.source.overrides.is_empty() {
                String::new()
            } else {
                format!(", overrides={:?}", self.overrides())
            }
        )
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Reduce<'py>> {
        // Pickled as its text and overrides (dask ships models to workers this way).
        let f = py.import("meid")?.getattr("Model")?.getattr("from_toml")?;
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

/// The result of `Model.simulate`.
#[pyclass(module = "meid", frozen)]
pub struct Run {
    summary_json: String,
    columns: Option<Vec<Vec<f64>>>,
}

#[pymethods]
impl Run {
    /// Energy ratio E_p+/E_s−, contact forces, exact peaks, ... (names carry their SI units).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.summary_json)
    }

    /// The sampled histories, `{column: numpy array}` (columns as in `history.csv`, units in
    /// the names); `None` when simulated with `history=False`.
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(cols) = &self.columns else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        for (name, c) in meid::io::HISTORY_COLUMNS.iter().zip(cols) {
            d.set_item(name, PyArray1::from_slice(py, c))?;
        }
        Ok(Some(d))
    }

    /// The history as a pandas DataFrame (needs pandas).
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pd = py.import("pandas").map_err(|_| {
            pyo3::exceptions::PyImportError::new_err(
                "Run.to_pandas needs pandas: pip install pandas",
            )
        })?;
        let h = self
            .history(py)?
            .ok_or_else(|| MeidError::new_err("no history: simulate(history=True)"))?;
        pd.call_method1("DataFrame", (h,))
    }

    fn __repr__(&self) -> String {
        format!(
            "meid.Run({} samples)",
            self.columns.as_ref().map_or(0, |c| c[0].len())
        )
    }
}

/// Columns of a study as Python sees them: names, numpy columns, the error column.
type PyColumns<'py> = (
    Vec<String>,
    Vec<Bound<'py, PyArray1<f64>>>,
    Vec<Option<String>>,
);

/// Pickling: the constructor and its arguments (text, name, overrides).
type Reduce<'py> = (Bound<'py, PyAny>, (String, String, Vec<String>));

/// Columns of a study: names, float columns, the error column.
type Columns = (Vec<String>, Vec<Vec<f64>>, Vec<Option<String>>);

fn columns_py<'py>(py: Python<'py>, c: Columns) -> PyResult<PyColumns<'py>> {
    let arrays = c.1.into_iter().map(|v| PyArray1::from_vec(py, v)).collect();
    Ok((c.0, arrays, c.2))
}

/// A sweep over `specs` ("NAME=LIST", "NAME=A..B:N[:log]"): (column names, float columns,
/// errors), one row per grid point in grid order.
#[pyfunction]
#[pyo3(signature = (model, specs, bed_mass_kg=None, threads=None))]
fn sweep_columns<'py>(
    py: Python<'py>,
    model: &Model,
    specs: Vec<String>,
    bed_mass_kg: Option<f64>,
    threads: Option<usize>,
) -> PyResult<PyColumns<'py>> {
    let pool = pool(threads)?;
    let m = model.inner.clone();
    let c = py
        .detach(|| -> meid::Result<Columns> {
            let vary = specs
                .iter()
                .map(|s| Vary::parse(s))
                .collect::<meid::Result<Vec<_>>>()?;
            let s = Sweep::with_bed_mass(m, vary, bed_mass_kg)?;
            let r = pool.install(|| s.run(&|_, _| {}));
            if let Some(e) = s.all_failed_error(&r) {
                return Err(e);
            }
            let names = s.columns();
            let ncol = names.len() - 1;
            let mut cols = vec![Vec::with_capacity(r.points.len()); ncol];
            let mut errors = Vec::with_capacity(r.points.len());
            for p in &r.points {
                let row = std::iter::once(p.index as f64)
                    .chain(p.values.iter().copied())
                    .chain(p.derived.iter().copied())
                    .chain(p.metrics.iter().map(|m| m.unwrap_or(f64::NAN)));
                for (c, v) in cols.iter_mut().zip(row) {
                    c.push(v);
                }
                errors.push(p.error.clone());
            }
            Ok((names[..ncol].to_vec(), cols, errors))
        })
        .map_err(err)?;
    columns_py(py, c)
}

/// Monte Carlo samples `first..end` (default all) of `samples` over `specs`
/// ("PATH=DIST(a,b)"): (column names, float columns, errors) in sample order; sample i
/// depends only on (seed, i).
#[pyfunction]
#[pyo3(signature = (model, specs, samples, seed=1, first=0, end=None, threads=None))]
#[allow(clippy::too_many_arguments)]
fn montecarlo_columns<'py>(
    py: Python<'py>,
    model: &Model,
    specs: Vec<String>,
    samples: usize,
    seed: u64,
    first: usize,
    end: Option<usize>,
    threads: Option<usize>,
) -> PyResult<PyColumns<'py>> {
    let pool = pool(threads)?;
    let m = model.inner.clone();
    let end = end.unwrap_or(samples);
    let c = py
        .detach(|| -> meid::Result<Columns> {
            let inputs = specs
                .iter()
                .map(|s| Uncertain::parse(s))
                .collect::<meid::Result<Vec<_>>>()?;
            let study = MonteCarlo {
                model: m,
                inputs,
                samples,
                seed,
            };
            if first > end || end > samples {
                return Err(meid::Error::invalid(
                    "range",
                    format!("samples {first}..{end} are outside 0..{samples}"),
                ));
            }
            study.check(end - first)?;
            let s = pool.install(|| study.run_range(first..end, &|_, _| {}));
            let mut names = vec!["sample".to_string()];
            names.extend(study.inputs.iter().map(|u| u.path.clone()));
            names.extend(montecarlo::METRICS.iter().map(|m| m.to_string()));
            let mut cols = vec![Vec::with_capacity(s.len()); names.len()];
            let mut errors = Vec::with_capacity(s.len());
            for x in &s {
                let nan = [f64::NAN; 5];
                let row = std::iter::once(x.index as f64)
                    .chain(x.inputs.iter().copied())
                    .chain(x.metrics.unwrap_or(nan));
                for (c, v) in cols.iter_mut().zip(row) {
                    c.push(v);
                }
                errors.push(x.error.clone());
            }
            Ok((names, cols, errors))
        })
        .map_err(err)?;
    columns_py(py, c)
}

/// Where `evaluate` finds a requested metric in a point's result.
#[derive(Clone, Copy)]
enum Pick {
    Metric(usize),
    Derived(usize),
}

/// The metric names `evaluate` returns by default (the sweep's, in order).
#[pyfunction]
fn metric_names() -> Vec<String> {
    sweep::METRICS.iter().map(|s| s.to_string()).collect()
}

/// `values` (N, k): N parameter sets of the k quantities `names` (sweep names: ratios such as
/// "wd/ws" or field paths); returns (N, m) metrics (`metrics`, default all of
/// `metric_names()`), NaN where a point failed or a metric is undefined. Releases the GIL;
/// points run in parallel (rayon) and each is the single run of its values.
#[pyfunction]
#[pyo3(signature = (model, names, values, metrics=None, bed_mass_kg=None, threads=None))]
fn evaluate<'py>(
    py: Python<'py>,
    model: &Model,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    metrics: Option<Vec<String>>,
    bed_mass_kg: Option<f64>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let shape = values.shape().to_vec();
    let (n, k) = (shape[0], shape[1]);
    if k != names.len() {
        return Err(InputError::new_err(format!(
            "values has {k} columns for {} names",
            names.len()
        )));
    }
    if k == 0 {
        return Err(InputError::new_err(
            "names is empty: give at least one quantity (a ratio such as \"wd/ws\" or a field path)",
        ));
    }
    let v = values.as_array();
    // Row-major (N, k) values, and for each requested metric where a point keeps it.
    let xs: Vec<f64> = (0..n)
        .flat_map(|i| (0..k).map(move |j| v[[i, j]]))
        .collect();
    let metrics = metrics.unwrap_or_else(metric_names);
    if metrics.is_empty() {
        return Err(InputError::new_err(format!(
            "metrics is empty; valid: {}",
            sweep::METRICS.join(", ")
        )));
    }
    let mut picks = Vec::with_capacity(metrics.len());
    for m in &metrics {
        if let Some(i) = sweep::METRICS.iter().position(|x| *x == m.as_str()) {
            picks.push(Pick::Metric(i));
        } else if let Some(i) = sweep::DERIVED.iter().position(|x| *x == m.as_str()) {
            picks.push(Pick::Derived(i));
        } else {
            return Err(InputError::new_err(format!(
                "unknown metric '{m}'; valid: {}, {}",
                sweep::METRICS.join(", "),
                sweep::DERIVED.join(", ")
            )));
        }
    }
    let m = picks.len();
    let pool = pool(threads)?;
    let base = model.inner.clone();
    let flat = py
        .detach(|| -> meid::Result<Vec<f64>> {
            use rayon::prelude::*;
            let qs = names
                .iter()
                .map(|s| Quantity::parse(s))
                .collect::<meid::Result<Vec<_>>>()?;
            let qr: Vec<&Quantity> = qs.iter().collect();
            let bed = bed_mass_kg.or_else(|| base.bed_mass());
            sweep::check_quantities(&base, &qr, bed)?;
            // The names checked as `meid sweep --vary` checks them: an unknown or non-numeric
            // field is an InputError naming it (it used to give rows of NaN).
            let vary = names
                .iter()
                .enumerate()
                .map(|(j, name)| {
                    let v = xs.get(j).copied().unwrap_or(1.0);
                    Vary::parse(&format!("{name}={:e}", if v.is_finite() { v } else { 1.0 }))
                })
                .collect::<meid::Result<Vec<_>>>()?;
            Sweep::with_bed_mass(base.clone(), vary, bed_mass_kg)?;
            let mut options = base.options();
            options.stop_at_collision_end = true;
            let cache = StructureCache::new();
            // Each row is written in place: no per-row vectors, no lookups by name.
            let mut out = vec![f64::NAN; n * m];
            pool.install(|| {
                out.par_chunks_mut(m)
                    .zip(xs.par_chunks(k))
                    .enumerate()
                    .for_each(|(i, (row, x))| {
                        let p = sweep::evaluate_cached(
                            &base,
                            &qr,
                            x,
                            bed_mass_kg,
                            &options,
                            i,
                            Some(&cache),
                        );
                        for (o, pick) in row.iter_mut().zip(&picks) {
                            *o = match *pick {
                                Pick::Metric(j) => p.metrics.get(j).copied().flatten(),
                                Pick::Derived(j) => p.derived.get(j).copied(),
                            }
                            .unwrap_or(f64::NAN);
                        }
                    })
            });
            Ok(out)
        })
        .map_err(err)?;
    Ok(PyArray1::from_vec(py, flat).reshape([n, m])?.into_any())
}

#[pymodule]
fn _meid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_class::<Run>()?;
    m.add_function(wrap_pyfunction!(sweep_columns, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_columns, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(metric_names, m)?)?;
    m.add("MeidError", m.py().get_type::<MeidError>())?;
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

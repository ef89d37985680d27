//! Python bindings of meid: the extension module `meid._meid`, wrapped by the pure-Python
//! package `meid` (crates/meid-py/python/meid). Problem → solve → solution:
//! [`Model`] (from a file, TOML text or a dict; `with_values`), `Model.simulate` → [`Run`]
//! (summary dict, history as numpy arrays), `Model.modes`, and the studies `sweep`,
//! `montecarlo`, `evaluate` as columns of numpy arrays (the package turns them into a pyarrow
//! Table or a pandas DataFrame). Every study releases the GIL and runs on rayon's threads.
//! meid's errors become `meid.InputError` (bad input: the message names the file:line:column or
//! the `--set`/field), `meid.FileNotFound`/`meid.FileError` (also FileNotFoundError/OSError) or
//! `meid.MeidError`, with meid's own message; the warnings `meid simulate` prints become
//! `meid.MeidWarning`s. Every allocation that grows with an input is checked against
//! `meid.max_memory()` before it is made.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use std::sync::atomic::{AtomicBool, Ordering};

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

mod machine;

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

create_exception!(
    meid,
    MeidWarning,
    pyo3::exceptions::PyUserWarning,
    "A finding of meid about a model or a run that does not stop it (e.g. retained modes that \
     carry too little of the static flexibility at a point): the same text as the CLI's \
     `warning:` lines and the `warnings` of `Run.summary`."
);

/// `meid.FileNotFound` (MeidError and FileNotFoundError) and `meid.FileError` (MeidError and
/// OSError): a file meid could not read or write, caught by `except FileNotFoundError` /
/// `except OSError` as a Python user writes it, and by `except MeidError`.
static FILE_NOT_FOUND: pyo3::sync::PyOnceLock<Py<pyo3::types::PyType>> =
    pyo3::sync::PyOnceLock::new();
static FILE_ERROR: pyo3::sync::PyOnceLock<Py<pyo3::types::PyType>> = pyo3::sync::PyOnceLock::new();

/// An I/O error as `meid.FileNotFound` / `meid.FileError` with meid's message, and `errno`,
/// `strerror`, `filename` set as on Python's own OSError.
fn io_err(text: &str, path: &std::path::Path, source: &std::io::Error) -> PyErr {
    Python::attach(|py| {
        let cell = if source.kind() == std::io::ErrorKind::NotFound {
            &FILE_NOT_FOUND
        } else {
            &FILE_ERROR
        };
        let Some(cls) = cell.get(py) else {
            return MeidError::new_err(text.to_string());
        };
        let make = || -> PyResult<PyErr> {
            let e = cls.bind(py).call1((text,))?;
            e.setattr("errno", source.raw_os_error())?;
            e.setattr("strerror", source.to_string())?;
            e.setattr("filename", path.to_string_lossy().to_string())?;
            Ok(PyErr::from_value(e))
        };
        make().unwrap_or_else(|e| e)
    })
}

fn err(e: meid::Error) -> PyErr {
    let mut text = e.to_string();
    if text.contains("--max-memory") {
        // The limit is the CLI's --max-memory; from Python it is meid.set_max_memory.
        text.push_str(" (from Python: meid.set_max_memory(BYTES))");
    }
    if let meid::Error::Io { path, source } = &e {
        return io_err(&text, path, source);
    }
    match e {
        meid::Error::Input { .. } | meid::Error::InvalidValue { .. } => InputError::new_err(text),
        _ => MeidError::new_err(text),
    }
}

/// A count argument (`threads`, `samples`, `first`, `end`, `count`): an integer >= `min`, or an
/// `InputError` naming the argument (a negative Python int used to give a bare OverflowError).
fn count(name: &str, v: i64, min: i64) -> PyResult<usize> {
    if v < min {
        return Err(InputError::new_err(format!(
            "{name}: must be an integer >= {min} (got {v})"
        )));
    }
    usize::try_from(v).map_err(|_| InputError::new_err(format!("{name}: {v} is too large")))
}

/// A real as a TOML literal that reads back as the same double: the shortest round-trip
/// decimal (`0.05`, `-1.0`, `1e-7`), or `nan`, `inf`, `-inf` (TOML's spellings, which meid's
/// checks then name: "must be a finite number"; Rust's `NaN` used to read as a string).
fn toml_real(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

/// True for numpy's bool scalar (`numpy.bool_`), which is not a Python bool.
fn is_numpy_bool(v: &Bound<'_, PyAny>) -> bool {
    v.get_type()
        .name()
        .map(|n| n == "bool_" || n == "bool")
        .unwrap_or(false)
        && !v.is_instance_of::<PyBool>()
        && v.hasattr("dtype").unwrap_or(false)
}

/// A Python scalar (bool, int, float, str, or a numpy scalar of those kinds) as a TOML
/// value; `None` when `v` is not a scalar.
fn scalar_toml(path: &str, v: &Bound<'_, PyAny>) -> PyResult<Option<toml::Value>> {
    // numpy arrays (and pandas Series) have `__index__`/`__float__` too: only 0-d ones are
    // scalars.
    if let Ok(ndim) = v.getattr("ndim").and_then(|n| n.extract::<i64>()) {
        if ndim != 0 {
            return Ok(None);
        }
    }
    if v.is_instance_of::<PyBool>() || is_numpy_bool(v) {
        return Ok(Some(toml::Value::Boolean(v.is_truthy()?)));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Some(toml::Value::String(v.extract()?)));
    }
    // int, numpy integers (anything with __index__): an integer if it fits TOML's i64, else
    // the nearest real.
    if v.is_instance_of::<PyInt>() || (!v.is_instance_of::<PyFloat>() && v.hasattr("__index__")?) {
        if let Ok(i) = v.extract::<i64>() {
            return Ok(Some(toml::Value::Integer(i)));
        }
        let x: f64 = v.extract().map_err(|_| {
            InputError::new_err(format!(
                "{path}: the integer is too large for a real number"
            ))
        })?;
        return Ok(Some(toml::Value::Float(x)));
    }
    // float, numpy floats (anything with __float__ that is not a container).
    if v.is_instance_of::<PyFloat>() || v.hasattr("__float__")? {
        if let Ok(x) = v.extract::<f64>() {
            return Ok(Some(toml::Value::Float(x)));
        }
    }
    Ok(None)
}

/// `overrides` as a list of "PATH=VALUE": a list/tuple of str, or one str (it used to be
/// refused with pyo3's "Can't extract `str` to `Vec`").
fn override_list(overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(o) = overrides else {
        return Ok(Vec::new());
    };
    if o.is_none() {
        return Ok(Vec::new());
    }
    if let Ok(s) = o.extract::<String>() {
        return Ok(vec![s]);
    }
    o.extract::<Vec<String>>().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "overrides: a list of \"PATH=VALUE\" strings, e.g. [\"damper.mass=3.5\"] (got {})",
            type_name(o)
        ))
    })
}

/// The type name of `v` for messages.
fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

fn pool(threads: Option<i64>) -> PyResult<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        b = b.num_threads(count("threads", n, 1)?);
    }
    b.build()
        .map_err(|e| MeidError::new_err(format!("cannot start the worker threads: {e}")))
}

/// Runs `work` on `pool` while this (the calling) thread checks Python's signals every 50 ms:
/// on Ctrl-C (a KeyboardInterrupt from the signal handler) `cancel` is set, `work` stops what it
/// has not started, and the KeyboardInterrupt is returned beside its result. Without this a long
/// study ignored Ctrl-C until it ended: the GIL is released, and only the main thread runs
/// Python's signal handlers. Call it without the GIL (inside `py.detach`).
fn interruptible<R: Send>(
    pool: &rayon::ThreadPool,
    work: impl FnOnce(&AtomicBool) -> R + Send,
) -> (R, Option<PyErr>) {
    let cancel = AtomicBool::new(false);
    let done = AtomicBool::new(false);
    let caller = std::thread::current();
    std::thread::scope(|sc| {
        let h = sc.spawn(|| {
            // Set even when `work` panics, so that the loop below ends and the panic is
            // resumed here.
            struct Done<'a>(&'a AtomicBool, std::thread::Thread);
            impl Drop for Done<'_> {
                fn drop(&mut self) {
                    self.0.store(true, Ordering::Release);
                    self.1.unpark();
                }
            }
            let _done = Done(&done, caller);
            pool.install(|| work(&cancel))
        });
        let mut interrupted = None;
        while !done.load(Ordering::Acquire) {
            std::thread::park_timeout(std::time::Duration::from_millis(50));
            if interrupted.is_none() && !done.load(Ordering::Acquire) {
                if let Err(e) = Python::attach(|py| py.check_signals()) {
                    cancel.store(true, Ordering::Relaxed);
                    interrupted = Some(e);
                }
            }
        }
        match h.join() {
            Ok(r) => (r, interrupted),
            Err(p) => std::panic::resume_unwind(p),
        }
    })
}

/// Points a study runs between two looks at `cancel` (sweep and Monte Carlo run index ranges
/// one after the other; a point depends only on its index, so the rows are the same).
const CANCEL_CHUNK: usize = 1024;

/// `with_values`' dict as `PATH=VALUE` overrides; a key that is not a str is a TypeError
/// naming `example`, a path of the model's kind.
fn field_list(values: &Bound<'_, PyDict>, example: &str) -> PyResult<Vec<String>> {
    let mut fields = Vec::new();
    for (k, v) in values.iter() {
        let k: String = k.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "with_values: keys are field paths such as \"{example}\" (str); got {} {}",
                type_name(&k),
                k.repr().map(|r| r.to_string()).unwrap_or_default()
            ))
        })?;
        fields.push(format!("{k}={}", literal(&k, &v)?));
    }
    Ok(fields)
}

/// The TOML literal of a Python value for a field (`with_values`): bool (numpy's too) →
/// boolean, int (numpy integers too) → integer, float (numpy floats too) → shortest
/// round-trip real (`nan`/`inf` as TOML spells them), str → TOML string.
fn literal(path: &str, v: &Bound<'_, PyAny>) -> PyResult<String> {
    match scalar_toml(path, v)? {
        Some(toml::Value::Float(x)) => Ok(toml_real(x)),
        Some(t) => Ok(t.to_string()),
        None => Err(InputError::new_err(format!(
            "{path}: a value must be a number, a bool or a string (got {})",
            type_name(v)
        ))),
    }
}

/// A Python dict/list/scalar as a TOML value (`Model.from_dict`).
fn to_toml(path: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if let Some(t) = scalar_toml(path, v)? {
        return Ok(t);
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            if x.is_none() {
                continue; // TOML has no null: an absent key (what `to_dict` writes as None).
            }
            let k: String = k.extract().map_err(|_| {
                let at = if path.is_empty() { "from_dict" } else { path };
                InputError::new_err(format!(
                    "{at}: dictionary keys must be strings (field names); got {} {}",
                    type_name(&k),
                    k.repr().map(|r| r.to_string()).unwrap_or_default()
                ))
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
    // A numpy array (or anything with `tolist`, e.g. a pandas Series): its nested lists.
    if v.hasattr("tolist")? && v.hasattr("ndim")? {
        return to_toml(path, &v.call_method0("tolist")?);
    }
    Err(InputError::new_err(format!(
        "{path}: cannot be written as TOML (got {}); use dicts, lists, str, int, float, bool \
         (numpy scalars and arrays too)",
        type_name(v)
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
        overrides: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let ov = override_list(overrides)?;
        if meid::model::network::is_general_file(&path) {
            return Err(InputError::new_err(format!(
                "{}: this is a general machine ([[impactor]], [[damper]] or [[contact]] arrays): \
                 read it with meid.Machine.from_file (or meid.load, which reads either kind)",
                path.display()
            )));
        }
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
        overrides: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let ov = override_list(overrides)?;
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
        let fields = field_list(values, "damper.mass")?;
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
            fields.push(format!("simulation.duration={}", toml_real(d)));
        }
        if let Some(r) = rate {
            fields.push(format!("simulation.sample_rate={}", toml_real(r)));
        }
        let case: Case = case.parse().map_err(err)?;
        let (run_summary, columns, diag, (impacts, totals)) = py
            .detach(|| -> meid::Result<_> {
                let m = if fields.is_empty() {
                    self.inner.clone()
                } else {
                    self.inner.with_fields(&fields, None)?
                };
                let opts = m.options();
                if history {
                    // In Python the history is held three times over: meid's record (160 B a
                    // sample), the Run's columns and the numpy copy `Run.history` hands out
                    // (21 × 8 B each). meid's own check counts the first only.
                    let n = meid::analysis::energy::sample_count(opts.duration, opts.sample_rate);
                    meid::limits::check_memory(
                        &format!("the history in Python ({n:.3e} samples × {PY_HISTORY_SAMPLE_BYTES} B: meid's record, the Run's columns and one numpy copy)"),
                        n * PY_HISTORY_SAMPLE_BYTES,
                        "simulation.duration",
                        "duration or rate, or simulate(history=False) (the summary's peaks are exact without samples)",
                    )?;
                }
                let sys = m.impact_system(case)?;
                let run = meid::analysis::simulate(&sys, &opts, history)?;
                // The columns are built here too, without the GIL (a 10^6-sample history
                // held it for 0.3 s when built after).
                let columns = run.history.as_ref().map(|h| {
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
                let impacts = meid::analysis::impacts::impacts(&sys, &run.solution)?;
                let totals = meid::analysis::impacts::totals(&sys, &impacts);
                Ok((run.summary, columns, m.diagnostics(), (impacts, totals)))
            })
            .map_err(err)?;
        // The summary's fields, then `truncation`, `notes` and `warnings`: `meid simulate
        // --json`'s object.
        let mut out =
            serde_json::to_value(&run_summary).map_err(|e| MeidError::new_err(e.to_string()))?;
        if let (serde_json::Value::Object(o), Ok(serde_json::Value::Object(d))) =
            (&mut out, serde_json::to_value(&diag))
        {
            o.extend(d);
        }
        // The per-impact table and its totals per contact (`meid simulate --json`'s).
        if let serde_json::Value::Object(o) = &mut out {
            let je = |e: serde_json::Error| MeidError::new_err(e.to_string());
            o.insert(
                "impacts".into(),
                serde_json::to_value(&impacts).map_err(je)?,
            );
            o.insert(
                "impact_totals".into(),
                serde_json::to_value(&totals).map_err(je)?,
            );
        }
        let summary = out.to_string();
        let warn = py.import("warnings")?;
        let category = py.get_type::<MeidWarning>();
        for w in &diag.warnings {
            warn.call_method1("warn", (w.as_str(), &category, 1))?;
        }
        Ok(Run {
            summary_json: summary,
            columns,
        })
    }

    /// The retained modes: `{"frequencies_hz": (n,), "points": [names], "shapes": (points, n),
    /// "labels": [n names]}`
    /// (signed mass-normalised ψ along the impact axis at the named points, 1/√kg; points in
    /// name order, as the ψ columns of `meid modes`' modes.csv), the first `count` when given.
    #[pyo3(signature = (count=None))]
    fn modes<'py>(&self, py: Python<'py>, count: Option<i64>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner.structure;
        let n = match count {
            Some(c) => self::count("count", c, 0)?.min(s.len()),
            None => s.len(),
        };
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

    /// What `meid simulate` prints beside its results: `{"truncation": [{"point", "roles",
    /// "static_flexibility_m_per_n", "modal_flexibility_m_per_n", "captured_share"}, ...],
    /// "notes": [str], "warnings": [str]}` (captured share = modal / static flexibility at
    /// each role point; a share below 0.95 is a warning).
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let d = py.detach(|| self.inner.diagnostics());
        let s = serde_json::to_string(&d).map_err(|e| MeidError::new_err(e.to_string()))?;
        json_to_py(py, &s)
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

/// Bytes a sample of a history costs in Python: meid's record
/// ([`meid::analysis::energy::HISTORY_SAMPLE_BYTES`]), the Run's 21 columns and one numpy copy
/// of them.
const PY_HISTORY_SAMPLE_BYTES: f64 = meid::analysis::energy::HISTORY_SAMPLE_BYTES
    + 2.0 * 8.0 * meid::io::HISTORY_COLUMNS.len() as f64;

/// The result of `Model.simulate`.
#[pyclass(module = "meid", frozen)]
pub struct Run {
    summary_json: String,
    columns: Option<Vec<Vec<f64>>>,
}

impl Run {
    /// A run without a sampled history (a general machine's, [`machine::Machine`]).
    fn from_summary(summary_json: String) -> Self {
        Run {
            summary_json,
            columns: None,
        }
    }
}

/// Whether the model file at `path` is a general machine (`[[impactor]]`, `[[damper]]` or
/// `[[contact]]` arrays), which `meid.Machine` reads, rather than the paper's machine
/// (`meid.Model`). A file that cannot be read or parsed is not one.
#[pyfunction]
fn is_general_file(path: std::path::PathBuf) -> bool {
    meid::model::network::is_general_file(&path)
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
        match &self.columns {
            Some(c) => format!("meid.Run({} samples)", c.first().map_or(0, Vec::len)),
            None => "meid.Run(no history)".into(),
        }
    }

    /// Pickling (Dask ships a Run from a worker process back to the client this way): the
    /// summary's JSON and the columns as little-endian f64 bytes, column after column.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<RunReduce<'py>> {
        let f = py.import("meid")?.getattr("Run")?.getattr("_from_state")?;
        let bytes = self.columns.as_ref().map(|cols| {
            let b: Vec<u8> = cols
                .iter()
                .flat_map(|c| c.iter().flat_map(|x| x.to_le_bytes()))
                .collect();
            PyBytes::new(py, &b)
        });
        Ok((f, (self.summary_json.clone(), bytes)))
    }

    /// The inverse of `__reduce__`.
    #[staticmethod]
    #[pyo3(signature = (summary_json, columns))]
    fn _from_state(summary_json: String, columns: Option<&[u8]>) -> PyResult<Run> {
        let ncol = meid::io::HISTORY_COLUMNS.len();
        let columns = match columns {
            None => None,
            Some(b) => {
                if b.len() % (8 * ncol) != 0 {
                    return Err(MeidError::new_err(format!(
                        "Run._from_state: {} bytes are not {ncol} columns of f64",
                        b.len()
                    )));
                }
                let n = b.len() / (8 * ncol);
                let xs: Vec<f64> = b
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
                    .collect();
                Some((0..ncol).map(|j| xs[j * n..(j + 1) * n].to_vec()).collect())
            }
        };
        Ok(Run {
            summary_json,
            columns,
        })
    }
}

/// Columns of a study as Python sees them: names, numpy columns, the error column.
type PyColumns<'py> = (
    Vec<String>,
    Vec<Bound<'py, PyArray1<f64>>>,
    Vec<Option<String>>,
);

/// Pickling a Run: `Run._from_state` and (summary JSON, the columns' bytes).
type RunReduce<'py> = (Bound<'py, PyAny>, (String, Option<Bound<'py, PyBytes>>));

/// Pickling: the constructor and its arguments (text, name, overrides).
type Reduce<'py> = (Bound<'py, PyAny>, (String, String, Vec<String>));

/// Columns of a study: names, float columns, the error column.
type Columns = (Vec<String>, Vec<Vec<f64>>, Vec<Option<String>>);

fn columns_py<'py>(py: Python<'py>, c: Columns) -> PyResult<PyColumns<'py>> {
    let arrays = c.1.into_iter().map(|v| PyArray1::from_vec(py, v)).collect();
    Ok((c.0, arrays, c.2))
}

/// A sweep over `specs` ("NAME=LIST", "NAME=A..B:N[:log]"): (column names, float columns,
/// errors), one row per grid point in grid order. Each point stops at the end of the
/// collision; with `duration` (s) it runs that long instead (`meid sweep --duration`).
#[pyfunction]
#[pyo3(signature = (model, specs, bed_mass_kg=None, threads=None, duration=None))]
fn sweep_columns<'py>(
    py: Python<'py>,
    model: &Model,
    specs: Vec<String>,
    bed_mass_kg: Option<f64>,
    threads: Option<i64>,
    duration: Option<f64>,
) -> PyResult<PyColumns<'py>> {
    let pool = pool(threads)?;
    let base = &model.inner;
    let c = py
        .detach(|| -> meid::Result<PyResult<Columns>> {
            let m = match duration {
                Some(d) => {
                    base.with_fields(&[format!("simulation.duration={}", toml_real(d))], None)?
                }
                None => base.clone(),
            };
            let vary = specs
                .iter()
                .map(|s| Vary::parse(s))
                .collect::<meid::Result<Vec<_>>>()?;
            let mut s = Sweep::with_bed_mass(m, vary, bed_mass_kg)?;
            if duration.is_some() {
                s.options.stop_at_collision_end = false;
            }
            let (points, interrupted) = interruptible(&pool, |cancel| {
                let mut points = Vec::with_capacity(s.len());
                for a in (0..s.len()).step_by(CANCEL_CHUNK) {
                    if cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    points.extend(s.run_range(a..(a + CANCEL_CHUNK).min(s.len()), &|_, _| {})?);
                }
                Ok::<_, meid::Error>(points)
            });
            if let Some(e) = interrupted {
                return Ok(Err(e));
            }
            let r = s.result_from(points?)?;
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
            Ok(Ok((names[..ncol].to_vec(), cols, errors)))
        })
        .map_err(err)??;
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
    samples: i64,
    seed: i128,
    first: i64,
    end: Option<i64>,
    threads: Option<i64>,
) -> PyResult<PyColumns<'py>> {
    let pool = pool(threads)?;
    let m = model.inner.clone();
    let samples = count("samples", samples, 0)?;
    let seed = u64::try_from(seed).map_err(|_| {
        InputError::new_err(format!("seed: must be an integer in 0..2^64 (got {seed})"))
    })?;
    let first = count("first", first, 0)?;
    let end = match end {
        Some(e) => count("end", e, 0)?,
        None => samples,
    };
    let c = py
        .detach(|| -> meid::Result<PyResult<Columns>> {
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
            let (s, interrupted) = interruptible(&pool, |cancel| {
                let mut s = Vec::with_capacity(end - first);
                for a in (first..end).step_by(CANCEL_CHUNK) {
                    if cancel.load(Ordering::Relaxed) {
                        break;
                    }
                    s.extend(study.run_range(a..(a + CANCEL_CHUNK).min(end), &|_, _| {}));
                }
                s
            });
            if let Some(e) = interrupted {
                return Ok(Err(e));
            }
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
            Ok(Ok((names, cols, errors)))
        })
        .map_err(err)??;
    columns_py(py, c)
}

/// What `evaluate`'s rows give: the (N, m) metrics row-major, the errors (when asked for),
/// and a KeyboardInterrupt that stopped them.
type Evaluated = (Vec<f64>, Vec<Option<String>>, Option<PyErr>);

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
/// points run in parallel (rayon) and each is the single run of its values. With `errors`,
/// returns `(metrics, errors)`: `errors[i]` says why row i failed (`None` when it ran).
#[pyfunction]
#[pyo3(signature = (model, names, values, metrics=None, bed_mass_kg=None, threads=None, errors=false))]
#[allow(clippy::too_many_arguments)]
fn evaluate<'py>(
    py: Python<'py>,
    model: &Model,
    names: Vec<String>,
    values: PyReadonlyArray2<'py, f64>,
    metrics: Option<Vec<String>>,
    bed_mass_kg: Option<f64>,
    threads: Option<i64>,
    errors: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let shape = values.shape().to_vec();
    let (n, k) = (shape[0], shape[1]);
    let m = metrics.as_ref().map_or(sweep::METRICS.len(), Vec::len);
    // The (N, k) copy of the values and the (N, m) result, before either is allocated (a
    // huge N used to abort the interpreter: "memory allocation of … bytes failed").
    meid::limits::check_memory(
        &format!("evaluate's {n} rows ({k} values and {m} metrics, 8 B each)"),
        8.0 * n as f64 * (k + m) as f64,
        "values",
        "the number of rows of values (evaluate them in parts)",
    )
    .map_err(err)?;
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
    let (flat, why, interrupted) = py
        .detach(|| -> meid::Result<Evaluated> {
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
            let mut why: Vec<Option<String>> = vec![None; if errors { n } else { 0 }];
            // Ctrl-C stops the rows not yet started (see `interruptible`).
            let work = |cancel: &AtomicBool| {
                let rows = out.par_chunks_mut(m).zip(xs.par_chunks(k)).enumerate();
                let each = |(i, (row, x)): (usize, (&mut [f64], &[f64])),
                            e: Option<&mut Option<String>>| {
                    if cancel.load(Ordering::Relaxed) {
                        return;
                    }
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
                    if let Some(e) = e {
                        *e = p.error;
                    }
                };
                if errors {
                    rows.zip(why.par_iter_mut())
                        .for_each(|(r, e)| each(r, Some(e)));
                } else {
                    rows.for_each(|r| each(r, None));
                }
            };
            let ((), interrupted) = interruptible(&pool, work);
            Ok((out, why, interrupted))
        })
        .map_err(err)?;
    let (flat, why) = match interrupted {
        Some(e) => return Err(e),
        None => (flat, why),
    };
    let y = PyArray1::from_vec(py, flat).reshape([n, m])?.into_any();
    if errors {
        return Ok((y, why).into_pyobject(py)?.into_any());
    }
    Ok(y)
}

/// The machine in production at `rate_bpm` (`None`: the model's `[production] rate_bpm`, else
/// 60) (`meid blows --json`'s object, as JSON text): the
/// verdict, the periodic steady state of `case` (`steady_state`) and of every case
/// (`production`); without `steady`, also the march of `blows` blows from rest.
#[pyfunction]
#[pyo3(signature = (model, rate_bpm=None, steady=true, case="as-specified".to_string(), blows=10))]
fn blows_json(
    py: Python<'_>,
    model: &Model,
    rate_bpm: Option<f64>,
    steady: bool,
    case: String,
    blows: usize,
) -> PyResult<String> {
    use meid::analysis::production;
    use meid::analysis::steady::{steady_state, SteadyOptions};
    let case: Case = case.parse().map_err(err)?;
    py.detach(|| -> meid::Result<String> {
        let m = &model.inner;
        let (rate_bpm, _) = production::stroke_rate(m, rate_bpm)?;
        let so = SteadyOptions::default();
        let p = production::production(m, rate_bpm, &so, true)?;
        let sys = m.impact_system(case)?;
        let selected = steady_state(&sys, &m.options(), &SteadyOptions { rate_bpm, ..so })?;
        let mut out = serde_json::json!({
            "rate_bpm": rate_bpm,
            "interval_s": p.interval_s,
            "verdict": p.verdict,
            "steady_state": selected,
            "production": p,
        });
        if !steady {
            let b = meid::analysis::blows::BlowOptions {
                blows,
                rate_bpm,
                ..Default::default()
            };
            let r = meid::analysis::blows::run_blows(&sys, &m.options(), &b, false)?;
            out["blows"] = serde_json::to_value(&r.blows)
                .map_err(|e| meid::Error::numerical("blows", e.to_string()))?;
            out["steady"] = serde_json::to_value(&r.steady)
                .map_err(|e| meid::Error::numerical("blows", e.to_string()))?;
            out["damper_gap_at_next_strike_m"] = r.damper_gap_at_next_strike_m.into();
            let mut impacts = Vec::new();
            for (b, sol) in r.blows.iter().zip(&r.solutions) {
                impacts.extend(meid::analysis::impacts::blow_impacts(
                    &sys, sol, b.blow, b.start_s,
                )?);
            }
            out["impacts"] = serde_json::to_value(&impacts)
                .map_err(|e| meid::Error::numerical("blows", e.to_string()))?;
        }
        serde_json::to_string(&out).map_err(|e| meid::Error::numerical("blows", e.to_string()))
    })
    .map_err(err)
}

/// The memory limit (bytes) every run checks its estimate against before it allocates: by
/// default half the physical memory; `set_max_memory` changes it for this process.
#[pyfunction]
fn max_memory() -> u64 {
    meid::limits::max_memory()
}

/// Sets the memory limit of this process (the CLI's `--max-memory`): an int of bytes
/// (`8 * 2**30`) or a size text ("8GiB", "512MiB", "3GB").
#[pyfunction]
fn set_max_memory(size: &Bound<'_, PyAny>) -> PyResult<()> {
    let bytes = if size.is_instance_of::<PyString>() {
        meid::limits::parse_bytes(&size.extract::<String>()?)
            .map_err(|e| InputError::new_err(e.to_string().replace("--max-memory", "max_memory")))?
    } else {
        let b: i128 = size.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "set_max_memory: give bytes as an int or a size text such as \"8GiB\" (got {})",
                type_name(size)
            ))
        })?;
        u64::try_from(b).ok().filter(|b| *b >= 1).ok_or_else(|| {
            InputError::new_err(format!(
                "max_memory: {b} bytes; give at least 1 byte and less than 2^64"
            ))
        })?
    };
    meid::limits::set_max_memory(bytes);
    Ok(())
}

/// The SI unit of a column of meid's results or of a varied quantity, as the Parquet files
/// of `meid sweep`/`meid montecarlo` give it: by the name's suffix for result columns
/// (`_j` J, `_n` N, `_m` m, `_s` s, `_m_per_s2` m/s^2, ...; "1" otherwise), "1" for the ratios
/// (`wd/ws`), by the field's last name for a field path (`…stiffness` N/m, `…mass` kg,
/// `…damping` N·s/m, `…velocity` m/s); `None` for a field path of unknown unit.
#[pyfunction]
fn column_unit(name: &str) -> Option<&'static str> {
    if name.contains('.') || name.contains('/') {
        // A field path or a ratio: the unit the sweep's and Monte Carlo's tables give it.
        Quantity::parse(name).ok().and_then(|q| q.unit())
    } else {
        Some(meid::io::table::unit_of_column(name))
    }
}

#[pymodule]
fn _meid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_class::<Run>()?;
    m.add_class::<machine::Machine>()?;
    m.add_function(wrap_pyfunction!(machine::machine_sweep_json, m)?)?;
    m.add_function(wrap_pyfunction!(machine::machine_blows_json, m)?)?;
    m.add_function(wrap_pyfunction!(is_general_file, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_columns, m)?)?;
    m.add_function(wrap_pyfunction!(montecarlo_columns, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(blows_json, m)?)?;
    m.add_function(wrap_pyfunction!(metric_names, m)?)?;
    m.add_function(wrap_pyfunction!(max_memory, m)?)?;
    m.add_function(wrap_pyfunction!(set_max_memory, m)?)?;
    m.add_function(wrap_pyfunction!(column_unit, m)?)?;
    m.add("MeidWarning", m.py().get_type::<MeidWarning>())?;
    // Two bases each: a class `create_exception!` cannot make.
    let py = m.py();
    let builtins = py.import("builtins")?;
    let make = |name: &str, os_base: &str, doc: &str| -> PyResult<Py<pyo3::types::PyType>> {
        let bases = (py.get_type::<MeidError>(), builtins.getattr(os_base)?);
        let ns = PyDict::new(py);
        ns.set_item("__module__", "meid")?;
        ns.set_item("__doc__", doc)?;
        let t = builtins.getattr("type")?.call1((name, bases, ns))?;
        Ok(t.cast_into::<pyo3::types::PyType>()?.unbind())
    };
    let nf = FILE_NOT_FOUND.get_or_try_init(py, || {
        make(
            "FileNotFound",
            "FileNotFoundError",
            "A file meid was asked to read does not exist (a MeidError and a FileNotFoundError).",
        )
    })?;
    m.add("FileNotFound", nf.bind(py))?;
    let fe = FILE_ERROR.get_or_try_init(py, || {
        make(
            "FileError",
            "OSError",
            "A file meid could not read or write (a MeidError and an OSError).",
        )
    })?;
    m.add("FileError", fe.bind(py))?;
    m.add("MeidError", m.py().get_type::<MeidError>())?;
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

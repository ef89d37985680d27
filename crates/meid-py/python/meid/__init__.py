"""meid: momentum-exchange impact dampers for impact machines (forging presses, hammers).

Problem -> solve -> solution::

    import meid
    model = meid.Model.from_file("examples/paper-lumped.toml")
    stiff = model.with_values({"contact.slider_bed.stiffness": 4.3e7})
    run = stiff.simulate(duration=0.5)
    run.summary["energy_ratio"]           # E_p+/E_s- (paper Eq. 10)
    run.history["bed_acceleration_m_per_s2"]   # numpy array
    df = run.to_pandas()                  # needs pandas

    press = meid.load("examples/press-off-centre-4-dampers.toml")   # a general machine
    press.simulate().summary["impacts"]   # one row per closing of a contact
    meid.sweep(press, vary={"damper.damper1.point": ["D1", "D2"]})

    table = meid.sweep(model, vary={"wd/ws": "0.3..3:41:log"})             # pyarrow Table
    mc = meid.montecarlo(model, vary={"contact.slider_bed.stiffness": "lognormal(4.3e7,0.3)"},
                         samples=1000, seed=1, output="pandas")
    y = meid.evaluate(model, ["wd/ws", "damper.mass"], x)                  # (N, 2) -> (N, 24)

Studies release the GIL and run in parallel (rayon). Errors raise :class:`InputError` (bad
input: the message names the file:line:column, field or override, and what would be valid) or
:class:`MeidError`, with meid's own messages; a file that does not exist raises
:class:`FileNotFound` (both a ``MeidError`` and a ``FileNotFoundError``), another I/O failure
:class:`FileError` (``MeidError`` and ``OSError``); a wrong Python type raises ``TypeError``.
What ``meid simulate`` prints as ``warning:`` comes as a :class:`MeidWarning` (and in
``Run.summary["warnings"]``). Every run estimates its memory before it allocates and refuses
one over :func:`max_memory` (default half the physical memory; :func:`set_max_memory`).
See also :mod:`meid.dask` for clusters.
"""

from __future__ import annotations

from typing import Any, Dict, Mapping, Optional, Sequence, Union

import numpy as np

from ._meid import (  # noqa: F401
    FileError,
    FileNotFound,
    InputError,
    Machine,
    MeidError,
    MeidWarning,
    Model,
    Run,
    __version__,
    blows_json,
    column_unit,
    evaluate as _evaluate,
    is_general_file,
    machine_blows_json,
    machine_sweep_json,
    max_memory,
    metric_names,
    montecarlo_columns,
    set_max_memory,
    sweep_columns,
)

__all__ = [
    "Model",
    "Machine",
    "load",
    "Run",
    "MeidError",
    "InputError",
    "MeidWarning",
    "FileNotFound",
    "FileError",
    "blows",
    "sweep",
    "montecarlo",
    "evaluate",
    "metric_names",
    "units",
    "max_memory",
    "set_max_memory",
    "__version__",
]

def units(column: str) -> Optional[str]:
    """The SI unit of a result column or a varied quantity, as meid's Parquet files give it:
    by the name's suffix for result columns (``_j`` J, ``_n`` N, ``_m`` m, ``_s`` s,
    ``_m_per_s2`` m/s^2, ...; "1" for ratios and counts), "1" for the ratios (``wd/ws``), by
    the field's last name for a field path (``...stiffness`` N/m, ``...mass`` kg, ``...damping``
    N·s/m, ``...velocity`` m/s); ``None`` for a field path of unknown unit."""
    return column_unit(column)


def load(path: str, overrides: Optional[Sequence[str]] = None) -> Union[Model, Machine]:
    """Reads a model file of either kind: the paper's machine (``[slider]``, ``[damper]``,
    ``[contact.slider_bed]``) as a :class:`Model`, a general machine (``[[impactor]]``,
    ``[[damper]]``, ``[[contact]]`` arrays) as a :class:`Machine`. ``overrides`` are
    "PATH=VALUE" strings, as the CLI's ``--set``."""
    if is_general_file(str(path)):
        return Machine.from_file(path, overrides)
    return Model.from_file(path, overrides)


def _spec(name: str, values: Any) -> str:
    if not isinstance(name, str):
        raise TypeError(f"vary: keys are quantities or field paths (str), got {name!r}")
    if isinstance(values, str):
        return f"{name}={values}"
    try:
        vals = np.asarray(values, dtype=float).ravel()
    except (TypeError, ValueError) as e:
        raise TypeError(
            f"vary[{name!r}]: give a list or array of numbers or a range text \"A..B:N\" ({e})"
        ) from None
    return f"{name}=" + ",".join(repr(float(v)) for v in vals)


def _table(names, columns, errors, output: str, index: str):
    """Columns -> pyarrow Table (units in the field metadata) or pandas DataFrame."""
    if output == "numpy":
        out: Dict[str, Any] = dict(zip(names, columns))
        out["error"] = errors
        return out
    if output == "pandas":
        import pandas as pd

        df = pd.DataFrame(dict(zip(names, columns)))
        df[index] = df[index].astype("int64")
        df["error"] = pd.Series(errors, dtype="object")
        return df
    if output != "pyarrow":
        raise ValueError(f"output must be 'pyarrow', 'pandas' or 'numpy' (got {output!r})")
    import pyarrow as pa

    fields = []
    arrays = []
    for n, c in zip(names, columns):
        if n == index:
            # uint64, as in the Parquet files of `meid sweep`/`meid montecarlo -o`.
            arrays.append(pa.array(c.astype("uint64")))
            fields.append(pa.field(n, pa.uint64(), metadata={"unit": "1"}))
        elif c.dtype == object:
            # Names (a general machine's varied point), as text.
            arrays.append(pa.array(list(c), type=pa.string()))
            fields.append(pa.field(n, pa.string()))
        else:
            u = units(n)
            arrays.append(pa.array(c, type=pa.float64()))
            fields.append(pa.field(n, pa.float64(), metadata=None if u is None else {"unit": u}))
    arrays.append(pa.array(errors, type=pa.string()))
    fields.append(pa.field("error", pa.string()))
    return pa.Table.from_arrays(arrays, schema=pa.schema(fields))


def blows(
    model: Union[Model, Machine],
    rate_bpm: Optional[float] = None,
    *,
    steady: bool = True,
    case: str = "as-specified",
    blows: int = 10,
) -> Dict[str, Any]:
    """The machine in production at ``rate_bpm`` blows/min (default: the model's
    ``[production] rate_bpm``, else 60): ``meid blows --json``'s object as a dict. ``verdict`` (sentences), ``steady_state`` (the periodic steady state of ``case``:
    ``converged``, ``residual``, ``map_evaluations``, ``regime``, ``period_blows``,
    ``energy_ratio``, ``peak_floor_force_n``, ``peak_bed_acceleration_m_per_s2``,
    ``damper_gap_at_strike_m``, ``damper_touches_bed``, ``multipliers_abs``, ...) and
    ``production`` (every case and the damper's return rate). With ``steady=False``, also the
    march of ``blows`` blows from rest (``blows``, ``steady``).

    A general machine (:class:`Machine`) gives ``meid blows GENERAL.toml --json``'s object: with
    ``steady``, ``verdict`` and ``steady_state`` (the same fields, with ``dampers_touch`` per
    damper); without, the march of ``blows`` blows from rest. Its ``case`` is as its file says."""
    import json

    if isinstance(model, Machine):
        if case != "as-specified":
            raise ValueError(
                "blows of a Machine: case is for the paper's Model (a general machine's "
                "[[damper]] entries are its dampers)"
            )
        return json.loads(machine_blows_json(model, rate_bpm, steady, blows))
    return json.loads(blows_json(model, rate_bpm, steady, case, blows))


def sweep(
    model: Model,
    vary: Mapping[str, Union[str, Sequence[float]]],
    *,
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = None,
    duration: Optional[float] = None,
    output: str = "pyarrow",
):
    """Simulates one blow at every point of the Cartesian grid of ``vary`` (last fastest).

    ``vary`` maps a quantity -- a ratio ``ws/w_ref``, ``wd/w_ref``, ``wd/ws``, ``md/mb`` or a
    model field path -- to a list of values or a range ``"A..B:N"`` / ``"A..B:N:log"``. Each
    point stops at the end of the collision, as ``meid sweep`` (so ``peak_floor_force_n`` is
    the peak during the collision); with ``duration`` (s) every point runs that long instead,
    as ``meid sweep --duration``. Returns a pyarrow Table (units
    in each field's metadata ``unit``), a pandas DataFrame (``output="pandas"``) or a dict of
    numpy arrays (``output="numpy"``), one row per point: ``index``, the varied values, K_s,
    K_d, m_d, m_s and every metric; ``error`` says why a point failed (NaN metrics).
    """
    if isinstance(model, Machine):
        if bed_mass_kg is not None or duration is not None:
            raise ValueError(
                "sweep of a Machine: bed_mass_kg and duration are for the paper's Model (set a "
                "general machine's duration with machine.with_values({'simulation.duration': T}))"
            )
        return _machine_sweep(model, vary, threads, output)
    specs = [_spec(k, v) for k, v in vary.items()]
    names, columns, errors = sweep_columns(model, specs, bed_mass_kg, threads, duration)
    return _table(names, columns, errors, output, "index")


def _machine_spec(name: str, values: Any) -> str:
    """A general machine's ``--vary``: a range text, or a list of numbers or point names."""
    if isinstance(values, str):
        return f"{name}={values}"
    vals = list(np.asarray(values, dtype=object).ravel())
    if vals and all(isinstance(v, str) for v in vals):
        return f"{name}=[" + ",".join(vals) + "]"
    return _spec(name, values)


def _machine_sweep(machine: Machine, vary, threads, output: str):
    """A general machine's sweep (``meid sweep GENERAL.toml --vary``) as a table: ``index``, the
    varied fields (numbers, or point names as text), the metric columns, ``error``."""
    import json

    specs = [_machine_spec(k, v) for k, v in vary.items()]
    r = json.loads(machine_sweep_json(machine, specs, threads))
    points = r["points"]
    index = np.array([p["index"] for p in points], dtype=np.float64)
    names = ["index"]
    columns: list = [index]
    for k, v in enumerate(r["vary"]):
        vals = [p["values"][k] for p in points]
        names.append(v["path"])
        if all(isinstance(x, (int, float)) for x in vals):
            columns.append(np.array(vals, dtype=np.float64))
        else:
            columns.append(np.array([str(x) for x in vals], dtype=object))
    for j, c in enumerate(r["columns"]):
        names.append(c)
        columns.append(
            np.array([np.nan if p["metrics"][j] is None else p["metrics"][j] for p in points])
        )
    errors = [p["error"] for p in points]
    return _table(names, columns, errors, output, "index")


def montecarlo(
    model: Model,
    vary: Mapping[str, str],
    *,
    samples: int = 200,
    seed: int = 1,
    first: int = 0,
    end: Optional[int] = None,
    threads: Optional[int] = None,
    output: str = "pyarrow",
):
    """Monte Carlo over uncertain inputs ``{path: "normal(m,s)" | "lognormal(mean,cov)" |
    "uniform(a,b)"}``: samples ``first..end`` (default all) of ``samples``, each the whole run of
    the model's ``[simulation]``. Sample i depends only on ``(seed, i)`` (counter-based), so any
    split gives the same rows. Columns: ``sample``, the inputs, ``energy_ratio``,
    ``peak_bed_acceleration_m_per_s2``, ``peak_floor_force_n``, the peak contact forces,
    ``error``.
    """
    specs = [f"{k}={v}" for k, v in vary.items()]
    names, columns, errors = montecarlo_columns(model, specs, samples, seed, first, end, threads)
    return _table(names, columns, errors, output, "sample")


def evaluate(
    model: Model,
    names: Sequence[str],
    values: Any,
    *,
    metrics: Optional[Sequence[str]] = None,
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = None,
    errors: bool = False,
):
    """``values`` (N, k): N parameter sets of the quantities ``names``; returns the (N, m)
    metrics (``metrics``, default :func:`metric_names`), NaN where undefined or failed. Each row
    is the sweep point of those values (one blow, stopped at the end of the collision). With
    ``errors=True``, returns ``(metrics, errors)``: ``errors[i]`` is meid's message for a row
    that failed (e.g. a negative mass), ``None`` for a row that ran.
    Releases the GIL and runs the rows in parallel. ``values`` may be any array-like of
    numbers (any dtype, any memory layout; read as float64); a 1-d array is N
    rows of one quantity. A single name or metric may be given as a str."""
    if isinstance(names, str):
        names = [names]
    if isinstance(metrics, str):
        metrics = [metrics]
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise TypeError(f"values: needs an (N, k) array of numbers ({e})") from None
    if arr.ndim == 1 and len(names) == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2:
        raise ValueError(
            f"values: needs shape (N, {len(names)}) -- N rows of the {len(names)} quantities "
            f"{list(names)} -- (got shape {arr.shape})"
        )
    # Not copied: the extension reads any strides (a transposed, sliced or broadcast array
    # too), and refuses a request over max_memory() before it allocates anything.
    return _evaluate(
        model, list(names), arr, None if metrics is None else list(metrics), bed_mass_kg, threads,
        errors,
    )

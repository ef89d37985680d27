"""meid: momentum-exchange impact dampers for impact machines (forging presses, hammers).

Problem -> solve -> solution::

    import meid
    model = meid.Model.from_file("examples/paper-lumped.toml")
    stiff = model.with_values({"contact.slider_bed.stiffness": 4.3e7})
    run = stiff.simulate(duration=0.5)
    run.summary["energy_ratio"]           # E_p+/E_s- (paper Eq. 10)
    run.history["bed_acceleration_m_per_s2"]   # numpy array
    df = run.to_pandas()                  # needs pandas

    table = meid.sweep(model, vary={"wd/ws": "0.3..3:41:log"})             # pyarrow Table
    mc = meid.montecarlo(model, vary={"contact.slider_bed.stiffness": "lognormal(4.3e7,0.3)"},
                         samples=1000, seed=1, output="pandas")
    y = meid.evaluate(model, ["wd/ws", "damper.mass"], x)                  # (N, 2) -> (N, 24)

Studies release the GIL and run in parallel (rayon). Errors raise :class:`InputError` (bad
input: the message names the file:line:column, field or override, and what would be valid) or
:class:`MeidError`, with meid's own messages. See also :mod:`meid.dask` for clusters.
"""

from __future__ import annotations

from typing import Any, Dict, Mapping, Optional, Sequence, Union

import numpy as np

from ._meid import (  # noqa: F401
    InputError,
    MeidError,
    Model,
    Run,
    __version__,
    evaluate as _evaluate,
    metric_names,
    montecarlo_columns,
    sweep_columns,
)

__all__ = [
    "Model",
    "Run",
    "MeidError",
    "InputError",
    "sweep",
    "montecarlo",
    "evaluate",
    "metric_names",
    "units",
    "__version__",
]

_UNITS = [
    ("_m_per_s2", "m/s^2"),
    ("_m_per_s", "m/s"),
    ("_n_per_m", "N/m"),
    ("_kg", "kg"),
    ("_j", "J"),
    ("_n", "N"),
    ("_s", "s"),
]


def units(column: str) -> str:
    """The SI unit of a result column, from its name's suffix ("1" for ratios and counts)."""
    for suffix, unit in _UNITS:
        if column.endswith(suffix):
            return unit
    if column.endswith("stiffness"):
        return "N/m"
    if column.endswith("mass"):
        return "kg"
    if column.endswith("damping"):
        return "N s/m"
    if column.endswith("velocity"):
        return "m/s"
    return "1"


def _spec(name: str, values: Any) -> str:
    if isinstance(values, str):
        return f"{name}={values}"
    vals = np.asarray(values, dtype=float).ravel()
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
            arrays.append(pa.array(c.astype("int64")))
            fields.append(pa.field(n, pa.int64(), metadata={"unit": "1"}))
        else:
            arrays.append(pa.array(c, type=pa.float64()))
            fields.append(pa.field(n, pa.float64(), metadata={"unit": units(n)}))
    arrays.append(pa.array(errors, type=pa.string()))
    fields.append(pa.field("error", pa.string()))
    return pa.Table.from_arrays(arrays, schema=pa.schema(fields))


def sweep(
    model: Model,
    vary: Mapping[str, Union[str, Sequence[float]]],
    *,
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = None,
    output: str = "pyarrow",
):
    """Simulates one blow at every point of the Cartesian grid of ``vary`` (last fastest).

    ``vary`` maps a quantity -- a ratio ``ws/w_ref``, ``wd/w_ref``, ``wd/ws``, ``md/mb`` or a
    model field path -- to a list of values or a range ``"A..B:N"`` / ``"A..B:N:log"``. Each
    point stops at the end of the collision, as ``meid sweep``. Returns a pyarrow Table (units
    in each field's metadata ``unit``), a pandas DataFrame (``output="pandas"``) or a dict of
    numpy arrays (``output="numpy"``), one row per point: ``index``, the varied values, K_s,
    K_d, m_d, m_s and every metric; ``error`` says why a point failed (NaN metrics).
    """
    specs = [_spec(k, v) for k, v in vary.items()]
    names, columns, errors = sweep_columns(model, specs, bed_mass_kg, threads)
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
) -> np.ndarray:
    """``values`` (N, k): N parameter sets of the quantities ``names``; returns the (N, m)
    metrics (``metrics``, default :func:`metric_names`), NaN where undefined or failed. Each row
    is the sweep point of those values (one blow, stopped at the end of the collision).
    Releases the GIL and runs the rows in parallel."""
    arr = np.ascontiguousarray(np.asarray(values, dtype=np.float64))
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    return _evaluate(
        model, list(names), arr, None if metrics is None else list(metrics), bed_mass_kg, threads
    )

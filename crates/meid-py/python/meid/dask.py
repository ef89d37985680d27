"""Sweeps and Monte Carlo on a Dask cluster (``dask.distributed``).

A study is cut into chunks of ``chunk`` points (default 2000: 10^3-10^4 per task, not one
point per task, so the scheduler's ~1 ms per task is negligible against ~1-10 ms per point).
Each task computes its index range with the same code as the single-process run -- a sweep
point depends only on its grid index, a Monte Carlo sample only on ``(seed, index)`` -- so the
gathered table equals the single-process one row for row, whatever the number of workers.
A worker that dies mid-study loses its running tasks; Dask reschedules them on the other
workers (``allowed_failures``, default 3), and since a task is a pure function of its range,
the retry gives the same rows: nothing is lost or duplicated (checked: ranges must tile the
study exactly once before the table is built).

The same code runs on a laptop (``LocalCluster``), or a Slurm/PBS cluster through
dask-jobqueue::

    from dask_jobqueue import SLURMCluster
    from dask.distributed import Client
    cluster = SLURMCluster(cores=32, processes=8, memory="64GB", walltime="02:00:00")
    cluster.scale(jobs=20)                    # 160 worker processes
    client = Client(cluster)
    table = meid.dask.montecarlo(client, "examples/paper-soft-base.toml",
                                 {"contact.slider_bed.stiffness": "lognormal(4.3e7,0.3)"},
                                 samples=10**8, chunk=10_000)

Models travel to the workers as their file text, name and overrides (a few kB in each task's
arguments, no scattered data that a dying worker could take with it); each worker process
builds a model once and keeps the last few it built, so an FE model's eigenproblem is solved
once per worker, not once per task. Workers need meid installed but not the model file.
"""

from __future__ import annotations

import os
from collections import OrderedDict
from typing import List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

import meid

__all__ = ["sweep", "montecarlo", "chunks"]

_ModelArgs = Tuple[str, str, Tuple[str, ...]]

#: Models built in this (worker) process, by (text, name, overrides); the last few are kept.
_MODELS: "OrderedDict[_ModelArgs, meid.Model]" = OrderedDict()
_MODELS_KEPT = 4


def chunks(total: int, chunk: int) -> List[Tuple[int, int]]:
    """The index ranges ``[(a, b), ...]`` that tile ``0..total`` in pieces of ``chunk``."""
    if chunk < 1:
        raise ValueError(f"chunk must be >= 1 (got {chunk})")
    if total < 0:
        raise ValueError(f"total must be >= 0 (got {total})")
    return [(a, min(a + chunk, total)) for a in range(0, total, chunk)]


def _model_args(model: Union["meid.Model", str, "os.PathLike[str]"]) -> _ModelArgs:
    """The (text, name, overrides) a model is rebuilt from (its pickle's arguments)."""
    if isinstance(model, (str, os.PathLike)):
        model = meid.Model.from_file(model)
    if not isinstance(model, meid.Model):
        raise TypeError(f"model must be a meid.Model or a path (got {type(model).__name__})")
    _, (text, name, overrides) = model.__reduce__()
    return text, name, tuple(overrides)


def _model(args: _ModelArgs) -> "meid.Model":
    m = _MODELS.get(args)
    if m is None:
        text, name, overrides = args
        m = meid.Model.from_toml(text, name, list(overrides))
        _MODELS[args] = m
        while len(_MODELS) > _MODELS_KEPT:
            _MODELS.popitem(last=False)
    else:
        _MODELS.move_to_end(args)
    return m


def _mc_task(margs, specs, samples, seed, a, b, threads):
    names, cols, errors = meid.montecarlo_columns(_model(margs), specs, samples, seed, a, b, threads)
    return a, b, names, cols, errors


def _grid_rows(grids: Sequence[np.ndarray], a: int, b: int) -> np.ndarray:
    """Rows ``a..b`` of the Cartesian grid of ``grids`` (last fastest), shape (b - a, k)."""
    shape = [len(g) for g in grids]
    if b <= a:
        return np.zeros((0, len(grids)))
    idx = np.unravel_index(np.arange(a, b), shape)
    return np.stack([g[i] for g, i in zip(grids, idx)], axis=1)


def _sweep_task(margs, vary_items, a, b, bed_mass_kg, threads):
    # The rows a..b of the grid, evaluated: the metrics of meid.sweep at those points.
    names = [k for k, _ in vary_items]
    x = _grid_rows([np.asarray(v, dtype=float) for _, v in vary_items], a, b)
    y = meid.evaluate(_model(margs), names, x, bed_mass_kg=bed_mass_kg, threads=threads)
    return a, b, x, y


def _format_bytes(b: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if b < 1024 or unit == "PiB":
            return f"{b:.0f} B" if unit == "B" else f"{b:.2f} {unit}"
        b /= 1024
    return f"{b:.2e} B"


def _check_gather(rows: int, columns: int, what: str, reduce: str) -> None:
    """Refuses, before any task is sent, a result the client could not hold: ``rows`` of
    ``columns`` float64 values, held twice while the parts are concatenated (16 B a value),
    plus 8 B a row for the error column, against :func:`meid.max_memory`."""
    need = rows * (16.0 * columns + 8.0)
    limit = meid.max_memory()
    if need > limit:
        raise meid.InputError(
            f"{what}: {rows:.3e} rows of {columns} columns gathered on the client "
            f"({16 * columns + 8} B a row) would need about {_format_bytes(need)} of memory, "
            f"over the limit of {_format_bytes(limit)} (meid.max_memory(); "
            f"meid.set_max_memory raises it). Reduce {reduce}"
        )


def _gather(client, futures, total: int, first: int = 0):
    """The tasks' results in index order, checked to tile ``first..total`` exactly once."""
    parts = client.gather(futures)
    parts.sort(key=lambda p: (p[0], p[1]))
    at = first
    for p in parts:
        if p[0] != at:
            what = "duplicated" if p[0] < at else "missing"
            raise RuntimeError(f"rows {min(at, p[0])}..{max(at, p[0])} {what} after gathering")
        at = p[1]
    if at != total:
        raise RuntimeError(f"rows {at}..{total} missing after gathering")
    return parts


def montecarlo(
    client,
    model: Union["meid.Model", str, "os.PathLike[str]"],
    vary: Mapping[str, str],
    *,
    samples: int,
    seed: int = 1,
    first: int = 0,
    end: Optional[int] = None,
    chunk: int = 2000,
    threads: Optional[int] = 1,
    output: str = "pyarrow",
):
    """:func:`meid.montecarlo` on ``client``'s workers, ``chunk`` samples per task: the same
    table (pyarrow, ``output="pandas"`` or ``"numpy"``) as the single-process run, row for row.
    Samples ``first..end`` (default all) of the study: a study too large for the client's
    memory is gathered in parts. ``threads`` rayon threads per task (1: one task per worker
    thread; give each worker as many Dask threads as cores)."""
    if samples < 1:
        raise ValueError(f"samples must be >= 1 (got {samples})")
    end = samples if end is None else end
    if not 0 <= first <= end <= samples:
        raise ValueError(f"samples {first}..{end} are outside 0..{samples}")
    margs = _model_args(model)
    specs = [f"{k}={v}" for k, v in vary.items()]
    # Checks the specification here, where the error is readable, before any task is sent.
    names = meid.montecarlo_columns(_model(margs), specs, samples, seed, 0, 0, 1)[0]
    # ... and what the client will hold (10^12 samples used to queue 5 * 10^8 tasks).
    _check_gather(end - first, len(names), f"samples {first}..{end}",
                  "the range first..end (gather the study in parts)")
    futures = [
        client.submit(_mc_task, margs, specs, samples, seed, first + a, first + b, threads,
                      pure=True)
        for a, b in chunks(end - first, chunk)
    ]
    parts = _gather(client, futures, end, first)
    if not parts:
        return meid.montecarlo(_model(margs), vary, samples=samples, seed=seed, first=first,
                               end=end, threads=1, output=output)
    names = parts[0][2]
    cols = [np.concatenate([p[3][k] for p in parts]) for k in range(len(names))]
    errors = [e for p in parts for e in p[4]]
    return meid._table(names, cols, errors, output, "sample")


def sweep(
    client,
    model: Union["meid.Model", str, "os.PathLike[str]"],
    vary: Mapping[str, Sequence[float]],
    *,
    chunk: int = 2000,
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = 1,
) -> Tuple[np.ndarray, np.ndarray]:
    """A sweep over the Cartesian grid of ``vary`` (explicit value lists, e.g.
    ``np.geomspace(0.3, 3, 41)``; last fastest) on ``client``'s workers, ``chunk`` points per
    task. Returns ``(x, y)``: the (N, k) grid values in grid order and the (N, m) metrics of
    :func:`meid.metric_names`, equal to ``meid.evaluate`` of the whole grid in one process
    (and to the metric columns of :func:`meid.sweep`)."""
    margs = _model_args(model)
    items = []
    for k, v in vary.items():
        if isinstance(v, str):
            raise TypeError(
                f"vary[{k!r}]: give the values as a list or array (e.g. np.linspace), not {v!r}"
            )
        items.append((k, [float(x) for x in np.asarray(v, dtype=float).ravel()]))
    total = 1
    for _, v in items:
        total *= len(v)  # Python ints: no overflow of a huge grid's count
    total = total if items else 0
    # Checks names and values here, where the error is readable, before any task is sent.
    meid.evaluate(_model(margs), [k for k, _ in items], np.zeros((0, len(items))),
                  bed_mass_kg=bed_mass_kg, threads=1)
    _check_gather(total, len(items) + len(meid.metric_names()), "the grid",
                  "the number of values in vary")
    futures = [
        client.submit(_sweep_task, margs, items, a, b, bed_mass_kg, threads, pure=True)
        for a, b in chunks(total, chunk)
    ]
    parts = _gather(client, futures, total)
    m = len(meid.metric_names())
    x = np.concatenate([p[2] for p in parts]) if parts else np.zeros((0, len(items)))
    y = np.concatenate([p[3] for p in parts]) if parts else np.zeros((0, m))
    return x, y

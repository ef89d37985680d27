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

Models travel to the workers as their file text and overrides (a model pickles that way), so
workers need meid installed but not the model file.
"""

from __future__ import annotations

from typing import Any, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

import meid

__all__ = ["sweep", "montecarlo", "chunks"]


def chunks(total: int, chunk: int) -> List[Tuple[int, int]]:
    """The index ranges ``[(a, b), ...]`` that tile ``0..total`` in pieces of ``chunk``."""
    if chunk < 1:
        raise ValueError("chunk must be >= 1")
    return [(a, min(a + chunk, total)) for a in range(0, total, chunk)]


def _model(model: Union["meid.Model", str]) -> "meid.Model":
    return meid.Model.from_file(model) if isinstance(model, str) else model


def _mc_task(model, specs, samples, seed, a, b, threads):
    names, cols, errors = meid.montecarlo_columns(model, specs, samples, seed, a, b, threads)
    return a, b, names, cols, errors


def _sweep_task(model, vary_items, a, b, bed_mass_kg, threads):
    # The rows a..b of the grid, by evaluating their values; columns as meid.sweep.
    names = [k for k, _ in vary_items]
    grids = [np.asarray(v, dtype=float) for _, v in vary_items]
    shape = [len(g) for g in grids]
    idx = np.unravel_index(np.arange(a, b), shape)
    x = np.stack([g[i] for g, i in zip(grids, idx)], axis=1) if b > a else np.zeros((0, len(names)))
    y = meid.evaluate(model, names, x, bed_mass_kg=bed_mass_kg, threads=threads)
    return a, b, names, x, y


def _gather(client, futures, total: int):
    parts = client.gather(futures)
    parts.sort(key=lambda p: p[0])
    at = 0
    for p in parts:
        if p[0] != at:
            raise RuntimeError(f"rows {at}..{p[0]} missing or duplicated after gathering")
        at = p[1]
    if at != total:
        raise RuntimeError(f"rows {at}..{total} missing after gathering")
    return parts


def montecarlo(
    client,
    model: Union["meid.Model", str],
    vary: Mapping[str, str],
    *,
    samples: int,
    seed: int = 1,
    chunk: int = 2000,
    threads: Optional[int] = 1,
    output: str = "pyarrow",
):
    """:func:`meid.montecarlo` on ``client``'s workers, ``chunk`` samples per task; the same
    table as the single-process run. ``threads`` per task (1: one task per worker core)."""
    m = _model(model)
    specs = [f"{k}={v}" for k, v in vary.items()]
    mf = client.scatter(m, broadcast=True)
    futures = [
        client.submit(_mc_task, mf, specs, samples, seed, a, b, threads, pure=True)
        for a, b in chunks(samples, chunk)
    ]
    parts = _gather(client, futures, samples)
    names = parts[0][2]
    cols = [np.concatenate([p[3][k] for p in parts]) for k in range(len(names))]
    errors = [e for p in parts for e in p[4]]
    return meid._table(names, cols, errors, output, "sample")


def sweep(
    client,
    model: Union["meid.Model", str],
    vary: Mapping[str, Sequence[float]],
    *,
    chunk: int = 2000,
    bed_mass_kg: Optional[float] = None,
    threads: Optional[int] = 1,
):
    """A sweep over the Cartesian grid of ``vary`` (explicit value lists, last fastest) on
    ``client``'s workers, ``chunk`` points per task. Returns ``(x, y)``: the (N, k) grid values
    in grid order and the (N, m) metrics of :func:`meid.metric_names`, equal to
    ``meid.evaluate`` of the whole grid in one process."""
    m = _model(model)
    items = [(k, list(np.asarray(v, dtype=float).ravel())) for k, v in vary.items()]
    total = int(np.prod([len(v) for _, v in items]))
    mf = client.scatter(m, broadcast=True)
    futures = [
        client.submit(_sweep_task, mf, items, a, b, bed_mass_kg, threads, pure=True)
        for a, b in chunks(total, chunk)
    ]
    parts = _gather(client, futures, total)
    x = np.concatenate([p[3] for p in parts])
    y = np.concatenate([p[4] for p in parts])
    return x, y

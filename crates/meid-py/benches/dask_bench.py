"""meid.dask on a LocalCluster: 2 worker processes against 1 (docs/performance.md, issue 14).

Method: the lumped example (examples/paper-lumped.toml); a sweep of N collisions (default 10^6:
a 1000 x 1000 grid of wd/ws 0.3..3 geometric and md/mb 0.05..0.6 linear), each point one
collision to its end, through `meid.dask.sweep(client, ..., chunk=10_000, threads=1)`.
For W in (1, 2): start `LocalCluster(n_workers=W, processes=True, threads_per_worker=1)`,
warm it up with a 2-chunk study (imports, model build), then time the whole study (submit,
compute, gather) once; the two results are checked to be bit-identical. Prints wall times,
the ratio and the per-point cost (wall time x workers / N), and `uptime` before and after:
the machine may be shared, so the load goes beside the figures.

usage: python dask_bench.py [N_SIDE] [--chunk C]
"""

import argparse
import os
import pathlib
import subprocess
import time

import numpy as np

import meid
import meid.dask
from dask.distributed import Client, LocalCluster

ROOT = pathlib.Path(__file__).resolve().parents[3]
MODEL = ROOT / "examples" / "paper-lumped.toml"


def run(workers, vary, chunk, n_points):
    with LocalCluster(n_workers=workers, processes=True, threads_per_worker=1,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        small = {k: v[: 2 if i == 0 else len(v)] for i, (k, v) in enumerate(vary.items())}
        meid.dask.sweep(client, MODEL, small, chunk=chunk // 2 or 1)  # warm-up
        t0 = time.perf_counter()
        x, y = meid.dask.sweep(client, MODEL, vary, chunk=chunk, threads=1)
        dt = time.perf_counter() - t0
    assert len(x) == n_points
    return dt, y


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("side", nargs="?", type=int, default=1000)
    ap.add_argument("--chunk", type=int, default=10_000)
    a = ap.parse_args()
    n = a.side
    vary = {"wd/ws": np.geomspace(0.3, 3.0, n), "md/mb": np.linspace(0.05, 0.6, n)}
    N = n * n
    print("uptime before:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    t1, y1 = run(1, vary, a.chunk, N)
    print(f"1 worker : {N} collisions in {t1:.1f} s ({t1 / N * 1e6:.1f} us/point)", flush=True)
    print("uptime between:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    t2, y2 = run(2, vary, a.chunk, N)
    print(f"2 workers: {N} collisions in {t2:.1f} s ({2 * t2 / N * 1e6:.1f} us/point per worker)")
    print("uptime after:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    assert np.array_equal(y1, y2, equal_nan=True)
    print(f"speed-up 2 workers / 1 worker: {t1 / t2:.2f}x (results bit-identical)")


if __name__ == "__main__":
    main()

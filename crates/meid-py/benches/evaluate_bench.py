"""meid.evaluate from Python against the Rust sweep (docs/performance.md, issue 14).

Method: the lumped example (examples/paper-lumped.toml), an n x n grid of (wd/ws, md/mb)
(numpy geomspace 0.3..3, linspace 0.05..0.6, given to the CLI as value lists), each point one collision to its end (a sweep point). Alternates, `reps`
times: (a) the Rust sweep, `meid sweep MODEL --vary ... --threads T -q` (whole process: start,
model read, grid, no output files), wall time and child CPU time; (b) `meid.evaluate(model,
names, x, threads=T)` on the same (N, 2) grid in this process (model loaded before timing; the
GIL is released during the run), wall and CPU time; checks that (b) equals meid.sweep's metric
columns bit for bit. Prints medians and minima; the overhead is (b)/(a) - 1.

usage: python evaluate_bench.py [N_SIDE ...] [--reps R] [--threads T]
"""

import argparse
import os
import pathlib
import resource
import statistics
import subprocess
import time

import numpy as np

import meid

ROOT = pathlib.Path(__file__).resolve().parents[3]
MODEL = ROOT / "examples" / "paper-lumped.toml"
MEID = os.environ.get("MEID_BIN", str(ROOT / "target" / "release" / "meid"))


def cpu_children():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def cpu_self():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sides", nargs="*", type=int, default=[100, 317])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    model = meid.Model.from_file(MODEL)
    for n in a.sides:
        ws = np.geomspace(0.3, 3.0, n)
        md = np.linspace(0.05, 0.6, n)
        x = np.stack(np.meshgrid(ws, md, indexing="ij"), axis=-1).reshape(-1, 2)
        # Explicit value lists: the CLI reads the same doubles (shortest round-trip text).
        spec = ["wd/ws=" + ",".join(repr(float(v)) for v in ws),
                "md/mb=" + ",".join(repr(float(v)) for v in md)]
        cli_wall, cli_cpu, py_wall, py_cpu = [], [], [], []
        for r in range(a.reps):
            c0, t0 = cpu_children(), time.perf_counter()
            subprocess.run([MEID, "sweep", str(MODEL), "--vary", spec[0], "--vary", spec[1],
                            "--threads", str(a.threads), "-q"], check=True,
                           stdout=subprocess.DEVNULL)
            cli_wall.append(time.perf_counter() - t0)
            cli_cpu.append(cpu_children() - c0)
            c0, t0 = cpu_self(), time.perf_counter()
            y = meid.evaluate(model, ["wd/ws", "md/mb"], x, threads=a.threads)
            py_wall.append(time.perf_counter() - t0)
            py_cpu.append(cpu_self() - c0)
            if r == 0 and n <= 100:
                t = meid.sweep(model, vary={"wd/ws": ws, "md/mb": md}, threads=a.threads,
                               output="numpy")
                assert np.array_equal(t["wd/ws"], x[:, 0]) and np.array_equal(t["md/mb"], x[:, 1])
                for k, name in enumerate(meid.metric_names()):
                    assert np.array_equal(y[:, k], t[name], equal_nan=True), name
        N = n * n
        med = statistics.median
        print(f"N = {N}: Rust sweep (CLI) wall median {med(cli_wall):.3f} s min {min(cli_wall):.3f} s, "
              f"CPU median {med(cli_cpu):.3f} s | meid.evaluate wall median {med(py_wall):.3f} s "
              f"min {min(py_wall):.3f} s, CPU median {med(py_cpu):.3f} s | overhead wall "
              f"median {med(py_wall) / med(cli_wall) - 1:+.1%}, min {min(py_wall) / min(cli_wall) - 1:+.1%}, "
              f"CPU {med(py_cpu) / med(cli_cpu) - 1:+.1%} | per point {med(py_wall) / N * 1e6:.1f} us wall")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Peer for meid's sparse Lanczos: SciPy eigsh (ARPACK) in shift-invert mode.

usage: eigsh_peer.py K.mtx M.mtx [COUNT=20] [SIGMA] [--meid modes.json]

Reads the stiffness and mass matrices (Matrix Market), solves K x = lam M x for the COUNT
eigenvalues nearest SIGMA with eigsh(K, k, M, sigma=SIGMA, which='LM') (shift-invert:
(K - sigma M)^-1 M, SuperLU factorisation), and prints one JSON line with the wall and CPU
time of the solve (s; CPU: user + system of all the process's threads; file reading
excluded), eigenvalues, frequencies (Hz, rigid-body modes clamped to 0 as meid does) and
max relative residual. SIGMA defaults to -1e-6 * max(K_ii / M_ii), meid's automatic shift.

With --meid modes.json (written by `meid modes MODEL -o DIR --export-matrices`, same model),
the JSON line also carries meid's frequencies and the relative difference per mode,
|f_meid - f_eigsh| / f_eigsh (absolute difference in Hz for modes eigsh finds at 0 Hz), and
the largest of them. Example (the paper machine refined to 106,968 DOFs):

    meid modes examples/paper-soft-base.toml --count 20 -o out --export-matrices \
        --set structure.fem.machine.elements_per_side=115
    python3 bench/peer/eigsh_peer.py out/K.mtx out/M.mtx 20 --meid out/modes.json
"""
import json
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse
from scipy.sparse.linalg import eigsh


def main():
    args = sys.argv[1:]
    meid_json = None
    if "--meid" in args:
        i = args.index("--meid")
        if i + 1 >= len(args):
            sys.exit("--meid needs a modes.json file")
        meid_json = args[i + 1]
        del args[i:i + 2]
    if len(args) < 2:
        sys.exit(__doc__)
    k = scipy.sparse.csc_matrix(scipy.io.mmread(args[0]))
    m = scipy.sparse.csc_matrix(scipy.io.mmread(args[1]))
    count = int(args[2]) if len(args) > 2 else 20
    scale = float(np.max(k.diagonal() / m.diagonal()))
    sigma = float(args[3]) if len(args) > 3 else -1e-6 * scale
    t0, c0 = time.perf_counter(), time.process_time()
    lam, phi = eigsh(k, k=count, M=m, sigma=sigma, which="LM", tol=1e-12)
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    kx, mx = k @ phi, m @ phi
    res = np.linalg.norm(kx - mx * lam, axis=0) / (
        np.linalg.norm(kx, axis=0) + np.maximum(np.abs(lam), 1e-10 * scale) * np.linalg.norm(mx, axis=0))
    # Rigid-body modes (omega = 0) as meid reports them: -1e-10 s <= lam <= 1e-12 s.
    rigid = np.where(lam > 0, lam <= 1e-12 * scale, -lam <= 1e-10 * scale)
    omega = np.where(rigid, 0.0, np.sqrt(np.abs(lam)))
    freq = omega / (2 * np.pi)
    out = {
        "solver": "scipy.eigsh",
        "dof": k.shape[0],
        "count": count,
        "sigma": sigma,
        "time_s": elapsed,
        "cpu_s": cpu,
        "eigenvalues": lam.tolist(),
        "frequencies_hz": freq.tolist(),
        "max_residual": float(res.max()),
    }
    if meid_json is not None:
        with open(meid_json) as f:
            rows = json.load(f)["modes"]
        f_meid = np.array([r["frequency_hz"] for r in rows][:count])
        n = min(len(f_meid), len(freq))
        diff = [
            abs(a - b) / b if b > 0 else abs(a - b)
            for a, b in zip(f_meid[:n], freq[:n])
        ]
        out["meid_frequencies_hz"] = f_meid[:n].tolist()
        out["relative_difference"] = diff
        out["max_relative_difference"] = float(max(diff)) if diff else None
    print(json.dumps(out))


if __name__ == "__main__":
    main()

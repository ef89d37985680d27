#!/usr/bin/env python3
"""Peer for meid's sparse Lanczos: SciPy eigsh (ARPACK) in shift-invert mode.

usage: eigsh_peer.py K.mtx M.mtx [COUNT=20] [SIGMA]

Reads the stiffness and mass matrices (Matrix Market), solves K x = lam M x for the COUNT
eigenvalues nearest SIGMA with eigsh(K, k, M, sigma=SIGMA, which='LM') (shift-invert:
(K - sigma M)^-1 M, SuperLU factorisation), and prints one JSON line with the time (s,
excluding file reading), eigenvalues, frequencies (Hz, rigid-body modes clamped to 0) and
max relative residual. SIGMA defaults to -1e-6 * max(K_ii / M_ii), meid's automatic shift.
"""
import json
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse
from scipy.sparse.linalg import eigsh


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    k = scipy.sparse.csc_matrix(scipy.io.mmread(sys.argv[1]))
    m = scipy.sparse.csc_matrix(scipy.io.mmread(sys.argv[2]))
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    scale = float(np.max(k.diagonal() / m.diagonal()))
    sigma = float(sys.argv[4]) if len(sys.argv) > 4 else -1e-6 * scale
    t0 = time.perf_counter()
    lam, phi = eigsh(k, k=count, M=m, sigma=sigma, which="LM", tol=1e-12)
    elapsed = time.perf_counter() - t0
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    kx, mx = k @ phi, m @ phi
    res = np.linalg.norm(kx - mx * lam, axis=0) / (
        np.linalg.norm(kx, axis=0) + np.maximum(np.abs(lam), 1e-10 * scale) * np.linalg.norm(mx, axis=0))
    omega = np.where(np.abs(lam) <= 1e-10 * scale, 0.0, np.sqrt(np.abs(lam)))
    print(json.dumps({
        "solver": "scipy.eigsh",
        "dof": k.shape[0],
        "count": count,
        "sigma": sigma,
        "time_s": elapsed,
        "eigenvalues": lam.tolist(),
        "frequencies_hz": (omega / (2 * np.pi)).tolist(),
        "max_residual": float(res.max()),
    }))


if __name__ == "__main__":
    main()

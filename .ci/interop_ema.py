"""Cross-check of meid's modal identification against sdypy-EMA (PyPI; its LSCF poles and
stabilisation): crates/meid/tests/ema_interop.rs writes FRFs as CSV (frequency_hz, then the real
and imaginary parts of each output) and meid's identified frequencies; this script identifies
the same FRFs with sdypy-EMA, picking the stable poles closest to those frequencies, and prints
{"frequency_hz": [...], "damping_ratio": [...]} as JSON.

usage: interop_ema.py FRF.csv LOWER_HZ UPPER_HZ ORDER F1 [F2 ...]
"""
import json
import sys

import numpy as np
from sdypy import EMA


def main():
    path, lower, upper, order = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    approx = [float(v) for v in sys.argv[5:]]
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    freq = data[:, 0]
    frf = (data[:, 1::2] + 1j * data[:, 2::2]).T
    m = EMA.Model(frf=frf, freq=freq, lower=lower, upper=upper, pol_order_high=order,
                  frf_form="accelerance")
    m.get_poles(method="lscf", show_progress=False)
    m.select_closest_poles(approx, f_window=5)
    print(json.dumps({"frequency_hz": [float(v) for v in m.nat_freq],
                      "damping_ratio": [float(v) for v in m.nat_xi]}))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""SciPy peer for meid's impact benchmark: one blow of the lumped paper example with
solve_ivp RK45 (rtol 1e-8), the way the paper used MATLAB's ode45.

Reads the system written by `cargo run --release -p meid --example impact_bench`
(JSON: modal frequencies, damping matrix, mode-shape values at O_b and O_f, masses,
contact and damper data), integrates from first contact to the end of the collision
(first instant after the slider has left at which both contacts are open: a terminal
event on max(overlap_s, overlap_d) falling through zero after the slider-bed overlap has
become negative), and prints JSON: per-run wall times (each, their median and minimum over N runs)
and the energy ratio
E_p+/E_s- = 1 - (E_s+ + E_d+)/E_s-.

The right-hand side evaluates the contact laws from the state (f = K*overlap while the
overlap is positive; the one-way dashpot acts while the damper moves back, Eq. 7), as an
ode45 user would write it.
"""
import json
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp


def main():
    spec = json.load(open(sys.argv[1]))
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 20
    w = np.array(spec["omega"])
    n = len(w)
    D = np.array(spec["damping"]).reshape(n, n)
    pb = np.array(spec["phi_b"])
    pf = np.array(spec["phi_f"])
    ms, vs, md = spec["m_s"], spec["v_s"], spec["m_d"]
    Ks, Kd, kd, cd = spec["K_s"], spec["K_d"], spec["k_d"], spec["c_d"]
    w2 = w * w

    def rhs(t, y):
        q, zs, zd = y[:n], y[n], y[n + 1]
        qd, vs_, vd = y[n + 2:2 * n + 2], y[2 * n + 2], y[2 * n + 3]
        ub, uf = pb @ q, pf @ q
        dub, duf = pb @ qd, pf @ qd
        ds = zs - ub
        dd = ub - zd
        fbs = Ks * ds if ds > 0 else 0.0
        fbd = Kd * dd if dd > 0 else 0.0
        r = vd - duf
        ffd = kd * (zd - uf) + (cd * r if r < 0 else 0.0)
        qdd = -w2 * q - D @ qd + pb * (fbs - fbd) + pf * ffd
        return np.concatenate([qd, [vs_, vd], qdd, [-fbs / ms, (fbd - ffd) / md]])

    def slider_left(t, y):
        return y[n] - pb @ y[:n]
    slider_left.direction = -1
    slider_left.terminal = True

    def end(t, y):
        q = y[:n]
        ub = pb @ q
        return max(y[n] - ub, ub - y[n + 1])
    end.direction = -1

    y0 = np.zeros(2 * n + 4)
    y0[2 * n + 2] = vs
    es = 0.5 * ms * vs * vs
    times = []
    ratio = None
    # One untimed run first (imports, caches), as the Rust side warms up too.
    for i in range(runs + 1):
        t0 = time.perf_counter()
        # Stage 1: until the slider leaves (skip the start, where both overlaps are zero).
        s1 = solve_ivp(rhs, (0.0, 0.05), y0, method="RK45", rtol=1e-8, atol=1e-14,
                       events=[slider_left], first_step=1e-7)
        ye = s1.y_events[0][0] if s1.t_events[0].size else s1.y[:, -1]
        te = s1.t_events[0][0] if s1.t_events[0].size else s1.t[-1]
        # Stage 2: until both contacts are open.
        if end(te, ye) > 0:
            end.terminal = True
            s2 = solve_ivp(rhs, (te, te + 0.05), ye, method="RK45", rtol=1e-8, atol=1e-14,
                           events=[end])
            ye = s2.y_events[0][0] if s2.t_events[0].size else s2.y[:, -1]
        if i > 0:
            times.append(time.perf_counter() - t0)
        q = ye[:n]
        v_s, v_d = ye[2 * n + 2], ye[2 * n + 3]
        e_s = 0.5 * ms * v_s ** 2
        e_d = 0.5 * md * v_d ** 2 + 0.5 * kd * (ye[n + 1] - pf @ q) ** 2
        ratio = (es - e_s - e_d) / es
    print(json.dumps({"median_s": float(np.median(times)), "min_s": float(np.min(times)),
                      "times_s": [float(t) for t in times], "runs": runs, "energy_ratio": ratio,
                      "scipy": __import__("scipy").__version__}))


if __name__ == "__main__":
    main()

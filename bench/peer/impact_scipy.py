#!/usr/bin/env python3
"""SciPy peers for meid's collision: one blow of the lumped paper example with every switch
located as an event, by `solve_ivp` RK45 or by `ode('dopri5')` (Hairer's DOPRI5, Fortran).

usage: impact_scipy.py SPEC.json [--method rk45|dopri5] [--rtol 1e-8] [--atol 1e-14]
                       [--runs N]

SPEC.json is written by `target/release/examples/impact_bench --spec SPEC.json` (the system
meid integrates: modal frequencies, modal damping matrix, mode-shape values at O_b and O_f,
slider, damper and contact data, and meid's exact energy ratio and collision end).

The model (docs/explanations/paper-machine.md, the impact damper of docs/reference/model-file.md), modal
coordinates q (mass-normalised), slider z_s, damper z_d:

    q'' = -w^2 q - D q' + phi_b (f_s - f_d) + phi_f f_a
    m_s z_s'' = -f_s,    m_d z_d'' = f_d - f_a
    f_s = K_s (z_s - u_b) while the slider-bed contact is closed, else 0
    f_d = K_d (u_b - z_d) while the bed-damper contact is closed, else 0
    f_a = k_d (z_d - u_f) + c_d r while the one-way dashpot acts, r = z_d' - u_f', else k_d (z_d - u_f)

with u_b = phi_b.q, u_f = phi_f.q. The discrete state (which contacts are closed, whether the
dashpot acts) is held fixed between events, so that each stretch is smooth and the error
control sees a smooth right-hand side; the switches are events: a contact closes (overlap rising
through 0) or opens (falling through 0; with C = 0 the force and the overlap vanish together),
the dashpot starts (r falling through 0) or stops (r rising through 0). At an event the switch's
state flips and the integration restarts from the located point. The start (every contact at
zero overlap, the dashpot at r = 0) is decided by the sign of each indicator's first non-zero
derivative in the candidate state, a derivative within round-off of zero counting as zero (the
lexicographic rule meid uses; the right-hand side of a fixed state is linear and homogeneous,
so the derivatives are repeated evaluations of it). Here it starts with both contacts closed
and the dashpot acting, which stops 0.78 us later, as in meid.
The collision ends at the first instant after the slider has left at which both contacts are
open; the energy ratio is meid's, E_p+/E_s- = 1 - (E_s+ + E_d+)/E_s-, with
E_d = m_d z_d'^2/2 + k_d (z_d - u_f)^2/2.

Events: solve_ivp locates them on its dense output (events=..., terminal); ode('dopri5') has no
events, so a `solout` callback stops the integration after the step on which an indicator
changes sign, and the crossing is found by Brent's method (scipy.optimize.brentq, xtol 1e-17 s)
on re-integrations from the step's start; the integration restarts from there.

Prints one JSON line: the peer, tolerances, runs, energy ratio and its error against meid's,
collision end and its error, right-hand-side evaluations per collision, and the CPU time
(time.process_time, user + system of this process) per collision over the N timed runs
(after one untimed run). Whole-process CPU time, alternated with meid's, is the comparison
(bench/peer/README.md).
"""
import argparse
import json
import time

import numpy as np
import scipy
from scipy.integrate import ode, solve_ivp
from scipy.optimize import brentq

SLIDER, DAMPER, DASHPOT = 1, 2, 4
NOISE, TINY = 1e3 * np.finfo(float).eps, np.finfo(float).tiny


class Blow:
    def __init__(self, spec):
        self.w2 = np.array(spec["omega"]) ** 2
        self.n = n = len(self.w2)
        self.D = np.array(spec["damping"]).reshape(n, n)
        self.pb = np.array(spec["phi_b"])
        self.pf = np.array(spec["phi_f"])
        self.ms, self.vs, self.md = spec["m_s"], spec["v_s"], spec["m_d"]
        self.Ks, self.Kd, self.kd, self.cd = spec["K_s"], spec["K_d"], spec["k_d"], spec["c_d"]
        self.abs_pb, self.abs_pf = np.abs(self.pb), np.abs(self.pf)
        self.rhs = [self.make_rhs(mode) for mode in range(8)]
        self.nfev = 0

    def make_rhs(self, mode):
        n, w2, D, pb, pf = self.n, self.w2, self.D, self.pb, self.pf
        ms, md, Ks, Kd, kd, cd = self.ms, self.md, self.Ks, self.Kd, self.kd, self.cd
        slider, damper, dashpot = mode & SLIDER, mode & DAMPER, mode & DASHPOT

        def rhs(t, y):
            self.nfev += 1
            q, zs, zd = y[:n], y[n], y[n + 1]
            qd, vd = y[n + 2:2 * n + 2], y[2 * n + 3]
            ub, uf = pb @ q, pf @ q
            fs = Ks * (zs - ub) if slider else 0.0
            fd = Kd * (ub - zd) if damper else 0.0
            fa = kd * (zd - uf) + (cd * (vd - pf @ qd) if dashpot else 0.0)
            qdd = -w2 * q - D @ qd + pb * (fs - fd) + pf * fa
            return np.concatenate([qd, y[2 * n + 2:], qdd, [-fs / ms, (fd - fa) / md]])

        return rhs

    def indicator(self, y, k):
        """Indicator k at y (slider overlap, damper overlap, dashpot relative velocity r) and
        the size of its terms."""
        n = self.n
        if k == 2:
            qd = y[n + 2:2 * n + 2]
            return y[2 * n + 3] - self.pf @ qd, abs(y[2 * n + 3]) + self.abs_pf @ np.abs(qd)
        q = y[:n]
        ub, size = self.pb @ q, abs(y[n + k]) + self.abs_pb @ np.abs(q)
        return (y[n] - ub if k == 0 else ub - y[n + 1]), size

    def event_value(self, y, mode, k):
        """Indicator k as an event function in `mode`: a value within round-off of zero (1000
        eps of its terms' size; as at the start, where every indicator is 0) counts as the side
        the state is on, so that it is not a crossing."""
        g, size = self.indicator(y, k)
        return g if abs(g) > NOISE * size else -self.wants(mode, k) * TINY

    @staticmethod
    def wants(mode, k):
        """The crossing direction that flips switch k in `mode`: +1 rising, -1 falling."""
        on = mode & (1 << k)
        if k < 2:
            return -1 if on else 1  # a closed contact opens, an open one closes
        return 1 if on else -1  # the dashpot stops when r rises through 0, starts when it falls

    def start_mode(self, y):
        """The state consistent with the lexicographic signs of the indicators at y: from all
        switches off, take the state the signs under the current one ask for, until they agree
        (then every state in turn, if that does not settle)."""
        mode = 0
        for _ in range(8):
            wanted = self.lex_state(y, mode)
            if wanted == mode:
                return mode
            mode = wanted
        for mode in range(8):
            if self.lex_state(y, mode) == mode:
                return mode
        raise RuntimeError("no consistent start state")

    def lex_state(self, y, mode):
        """The switch states the indicators' first non-zero derivatives at y ask for, the
        derivatives taken in `mode`."""
        chain, signs = y, [0, 0, 0]
        for _ in range(2 * self.n + 6):
            for k in range(3):
                g = self.event_value(chain, mode, k)
                if signs[k] == 0 and abs(g) > TINY:
                    signs[k] = 1 if g > 0 else -1
            if all(signs):
                break
            chain = self.rhs[mode](0.0, chain)
        return (signs[0] > 0) * SLIDER | (signs[1] > 0) * DAMPER | (signs[2] < 0) * DASHPOT

    def y0(self):
        y = np.zeros(2 * self.n + 4)
        y[2 * self.n + 2] = self.vs
        return y

    def energy_ratio(self, y):
        n = self.n
        es = 0.5 * self.ms * self.vs ** 2
        e_s = 0.5 * self.ms * y[2 * n + 2] ** 2
        e_d = 0.5 * self.md * y[2 * n + 3] ** 2 + 0.5 * self.kd * (y[n + 1] - self.pf @ y[:n]) ** 2
        return (es - e_s - e_d) / es

    def run(self, stretch):
        """One blow; `stretch(mode, t, y)` integrates in `mode` to its first switch and returns
        (t, y, k) at the switch k."""
        t, y = 0.0, self.y0()
        mode = self.start_mode(y)
        left = False
        while True:
            t, y, k = stretch(mode, t, y)
            mode ^= 1 << k
            left = left or (k == 0 and not mode & SLIDER)
            if left and not mode & (SLIDER | DAMPER):
                return t, y


def rk45_stretcher(blow, rtol, atol, t_max):
    events = []
    for mode in range(8):
        evs = []
        for k in range(3):
            def ev(t, y, k=k, mode=mode):
                return blow.event_value(y, mode, k)
            ev.terminal = True
            ev.direction = Blow.wants(mode, k)
            evs.append(ev)
        events.append(evs)

    def stretch(mode, t, y):
        s = solve_ivp(blow.rhs[mode], (t, t + t_max), y, method="RK45", rtol=rtol, atol=atol,
                      events=events[mode])
        if s.status != 1:
            raise RuntimeError(f"no switch within {t_max} s from t = {t}: {s.message}")
        k = min((k for k in range(3) if s.t_events[k].size), key=lambda k: s.t_events[k][0])
        return s.t_events[k][0], s.y_events[k][0], k

    return stretch


def dopri5_stretcher(blow, rtol, atol, t_max):
    state = {"mode": 0, "watch": True, "hit": None, "prev": None}

    def solout(t, y):
        if not state["watch"]:
            return 0
        mode = state["mode"]
        g = [blow.event_value(y, mode, k) for k in range(3)]
        prev = state["prev"]
        if prev is not None:
            for k in range(3):
                d = Blow.wants(mode, k)
                if (d > 0 and prev[1][k] <= 0 < g[k]) or (d < 0 and prev[1][k] >= 0 > g[k]):
                    state["hit"] = (k, prev[0], t)
                    return -1
        state["prev"] = (t, g, y.copy())
        return 0

    solvers = []
    for mode in range(8):
        r = ode(blow.rhs[mode]).set_integrator("dopri5", rtol=rtol, atol=atol, nsteps=10 ** 6)
        r.set_solout(solout)
        solvers.append(r)

    def stretch(mode, t, y):
        r = solvers[mode]
        state.update(mode=mode, watch=True, hit=None, prev=None)
        r.set_initial_value(y, t)
        r.integrate(t + t_max)
        if state["hit"] is None:
            raise RuntimeError(f"no switch within {t_max} s from t = {t}")
        k, ta, tb = state["hit"]
        ya = state["prev"][2]
        state["watch"] = False

        def at(tt):
            if tt == ta:
                return ya
            r.set_initial_value(ya, ta)
            return r.integrate(tt)

        # Every indicator that changed sign in the wanted direction on the step is located;
        # the earliest crossing is the switch.
        best = None
        yb = at(tb).copy()
        for j in range(3):
            d, ga, gb = Blow.wants(mode, j), blow.event_value(ya, mode, j), blow.event_value(yb, mode, j)
            if (d > 0 and ga <= 0 < gb) or (d < 0 and ga >= 0 > gb):
                def g(tt, j=j, ga=ga):
                    return ga if tt == ta else blow.indicator(at(tt), j)[0]
                tj = brentq(g, ta, tb, xtol=1e-17, rtol=4 * np.finfo(float).eps)
                if best is None or tj < best[0]:
                    best = (tj, j)
        te, k = best
        return te, at(te).copy(), k

    return stretch


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("spec")
    ap.add_argument("--method", choices=["rk45", "dopri5"], default="rk45")
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--atol", type=float, default=1e-14)
    ap.add_argument("--runs", type=int, default=20)
    a = ap.parse_args()
    spec = json.load(open(a.spec))
    blow = Blow(spec)
    make = rk45_stretcher if a.method == "rk45" else dopri5_stretcher
    stretch = make(blow, a.rtol, a.atol, 0.05)
    t_end, y = blow.run(stretch)  # untimed: imports and caches
    blow.nfev = 0
    c0 = time.process_time()
    for _ in range(a.runs):
        t_end, y = blow.run(stretch)
    cpu = time.process_time() - c0
    ratio = blow.energy_ratio(y)
    print(json.dumps({
        "peer": "SciPy solve_ivp RK45" if a.method == "rk45" else "SciPy ode dopri5 (Fortran)",
        "scipy": scipy.__version__, "rtol": a.rtol, "atol": a.atol, "runs": a.runs,
        "energy_ratio": ratio, "energy_ratio_error": ratio - spec["meid_energy_ratio"],
        "collision_end_s": t_end, "collision_end_error_s": t_end - spec["meid_collision_end_s"],
        "rhs_evaluations_per_collision": blow.nfev / max(a.runs, 1),
        "cpu_per_collision_s": cpu / max(a.runs, 1)}))


if __name__ == "__main__":
    main()

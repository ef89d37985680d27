#!/usr/bin/env python3
"""Exudyn peer for meid's collision: one blow of the lumped paper example with Exudyn's
explicit DOPRI5 (adaptive steps, C++), contacts and the one-way dashpot as symbolic user
functions.

usage: impact_exudyn.py SPEC.json [--rtol 1e-8] [--atol 1e-14] [--runs N]

SPEC.json is written by `target/release/examples/impact_bench --spec SPEC.json` (the system
meid integrates and meid's exact energy ratio and collision end).

Model (the same equations as bench/peer/impact_scipy.py, in physical coordinates): the bed
(O_b) and the floating base (O_f) are two `Node1D` coordinates x = Phi q of an
`ObjectGenericODE2` with M = Phi^-T Phi^-1, K = Phi^-T W Phi^-1 and C = Phi^-T D Phi^-1, where
the rows of Phi are the mass-normalised mode shapes at O_b and O_f (the columns and support
springs and the 1 % modal damping of examples/paper-lumped.toml, exactly); the slider and the
damper are `Mass1D`. Three `ObjectConnectorCoordinateSpringDamper` carry the switching forces,
each with a symbolic user function (exudyn.advancedUtilities.CreateSymbolicUserFunction, run
in C++ without calling Python):

    slider-bed:  K_s d if d > 0 else 0,            d = z_s - u_b
    bed-damper:  K_d d if d > 0 else 0,            d = u_b - z_d
    damper-base: k_d d + (c_d r if r < 0 else 0),  d = z_d - u_f, r = z_d' - u_f'

Exudyn's explicit solvers have no event location: the switches are kinks and jumps in the
right-hand side that DOPRI5's error control crosses by rejecting and shrinking steps (what an
Exudyn user writing these user functions gets). The run ends at meid's collision end (the
first instant after the slider has left at which both contacts are open; in meid's exact
solution 6.781e-4 s), where the energy ratio E_p+/E_s- = 1 - (E_s+ + E_d+)/E_s- is taken, with
E_d = m_d z_d'^2/2 + k_d (z_d - u_f)^2/2.

Prints one JSON line: tolerances, runs, energy ratio and its error against meid's, steps, and
the CPU time (time.process_time, user + system) per collision over the N timed runs (each a
`mbs.SolveDynamic` from the initial state, after one untimed run).
"""
import argparse
import json
import time

import numpy as np
import exudyn as exu
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (MarkerNodeCoordinate, Mass1D, Node1D, ObjectConnectorCoordinateSpringDamper,
                                  ObjectGenericODE2)

esym = exu.symbolic


def contact(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
    """A linear unilateral contact: compression `displacement` > 0."""
    return esym.IfThenElse(displacement > 0, stiffness * displacement, esym.Real(0.0))


def one_way(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
    """The damper spring with a dashpot that acts only while the damper moves back."""
    return stiffness * displacement + esym.IfThenElse(velocity < 0, damping * velocity, esym.Real(0.0))


def build(spec, rtol, atol):
    w2 = np.array(spec["omega"]) ** 2
    n = len(w2)
    D = np.array(spec["damping"]).reshape(n, n)
    phi = np.array([spec["phi_b"], spec["phi_f"]])  # x = phi q, x = (u_b, u_f)
    pinv = np.linalg.inv(phi)
    M = pinv.T @ pinv
    K = pinv.T @ np.diag(w2) @ pinv
    C = pinv.T @ D @ pinv

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    bed = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    base = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[bed, base], massMatrix=M, stiffnessMatrix=K,
                                    dampingMatrix=C))
    slider = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialVelocities=[spec["v_s"]]))
    mbs.AddObject(Mass1D(nodeNumber=slider, mass=spec["m_s"]))
    damper = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    mbs.AddObject(Mass1D(nodeNumber=damper, mass=spec["m_d"]))
    mk = {name: mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
          for name, node in [("bed", bed), ("base", base), ("slider", slider), ("damper", damper)]}

    # Displacement of a coordinate connector = coordinate of marker 1 - of marker 0; its force
    # acts +f on marker 0 and -f on marker 1.
    keep = []
    for m0, m1, k, c, fn in [("bed", "slider", spec["K_s"], 0.0, contact),
                             ("damper", "bed", spec["K_d"], 0.0, contact),
                             ("base", "damper", spec["k_d"], spec["c_d"], one_way)]:
        obj = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mk[m0], mk[m1]],
                                                                  stiffness=k, damping=c))
        uf = CreateSymbolicUserFunction(mbs, fn, "springForceUserFunction", obj)
        mbs.SetObjectParameter(obj, "springForceUserFunction", uf)
        keep.append(uf)  # the expression tree must outlive the simulation
    mbs.Assemble()

    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = spec["meid_collision_end_s"]
    ti.numberOfSteps = 1  # the largest step (endTime / numberOfSteps) left to the error control
    ti.automaticStepSize = True
    ti.relativeTolerance = rtol
    ti.absoluteTolerance = atol
    ti.minimumStepSize = 1e-16
    ti.verboseMode = 0
    s.solution.file.write = False
    s.show.statistics = False
    s.show.computationTime = False
    s.parallel.numberOfThreads = 1
    return SC, mbs, s, keep, (bed, base, slider, damper)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("spec")
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--atol", type=float, default=1e-14)
    ap.add_argument("--runs", type=int, default=20)
    a = ap.parse_args()
    spec = json.load(open(a.spec))
    SC, mbs, s, keep, nodes = build(spec, a.rtol, a.atol)  # SC and keep: kept alive

    def blow():
        mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.DOPRI5)

    blow()  # untimed
    c0 = time.process_time()
    for _ in range(a.runs):
        blow()
    cpu = time.process_time() - c0
    names = ("bed", "base", "slider", "damper")
    x = {k: mbs.GetNodeOutput(i, exu.OutputVariableType.Coordinates) for k, i in zip(names, nodes)}
    v = {k: mbs.GetNodeOutput(i, exu.OutputVariableType.Coordinates_t) for k, i in zip(names, nodes)}
    es = 0.5 * spec["m_s"] * spec["v_s"] ** 2
    e_s = 0.5 * spec["m_s"] * v["slider"] ** 2
    e_d = 0.5 * spec["m_d"] * v["damper"] ** 2 + 0.5 * spec["k_d"] * (x["damper"] - x["base"]) ** 2
    ratio = (es - e_s - e_d) / es
    info = mbs.sys["dynamicSolver"].it if "dynamicSolver" in mbs.sys else None
    print(json.dumps({
        "peer": "Exudyn DOPRI5, symbolic user functions", "exudyn": exu.__version__,
        "rtol": a.rtol, "atol": a.atol, "runs": a.runs,
        "energy_ratio": ratio, "energy_ratio_error": ratio - spec["meid_energy_ratio"],
        "end_s": mbs.systemData.GetTime(), "overlaps_at_end_m":
        [x["slider"] - x["bed"], x["bed"] - x["damper"]],
        "steps": None if info is None else info.currentStepIndex,
        "rejected_steps": None if info is None else info.rejectedAutomaticStepSizeSteps,
        "cpu_per_collision_s": cpu / max(a.runs, 1)}))


if __name__ == "__main__":
    main()

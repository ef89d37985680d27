"""pyuff side of meid's UFF interoperability test (crates/meid/tests/uff_interop.rs).

    python interop_uff.py write DIR   pyuff writes DIR/*.uff and DIR/expected.json (SI values)
    python interop_uff.py read FILE   pyuff reads FILE and prints its datasets as JSON

Run by .ci/run through the Rust test, with the pyuff of its own virtual environment.
"""
import json
import os
import sys

import numpy as np
import pyuff

G = 9.80665


def ds58(name, node, x, y, spec, unit, binary, even=True, **more):
    return pyuff.prepare_58(
        **more,
        binary=binary,
        id1=name,
        func_type=1,
        rsp_node=node,
        rsp_dir=3,
        ref_node=0,
        ref_dir=0,
        abscissa_spacing=1 if even else 0,
        abscissa_spec_data_type=17,
        abscissa_axis_units_lab="s",
        ordinate_spec_data_type=spec,
        ordinate_axis_units_lab=unit,
        orddenom_spec_data_type=0,
        z_axis_spec_data_type=0,
        data=y,
        x=x,
    )


def write(d):
    fs = 51200.0
    n = 1000
    t = np.arange(n) / fs
    acc_g = np.exp(-30.0 * t) * np.sin(2 * np.pi * 283.0 * t) * 12.5
    force = np.where(t < 2e-3, 8e3 * np.sin(np.pi * t / 2e-3), 0.0) + 1e-3 * np.cos(t * 1e3)
    acc_mm = acc_g * G * 1e3
    expected = {}
    # ASCII, even abscissa, double precision: acceleration in g, force in N.
    path = os.path.join(d, "ascii.uff")
    u = pyuff.UFF(path)
    u.write_sets([ds58("accel_B", 1, t, acc_g, 12, "g", 0), ds58("force_floor", 2, t, force, 13, "N", 0)], mode="overwrite")
    expected["ascii.uff"] = [
        {"name": "accel_B", "unit": "m/s^2", "x0": 0.0, "dx": float(t[1]), "values": list(acc_g * G)},
        {"name": "force_floor", "unit": "N", "x0": 0.0, "dx": float(t[1]), "values": list(force)},
    ]
    # Binary 58b: acceleration in mm/s^2.
    path = os.path.join(d, "binary.uff")
    u = pyuff.UFF(path)
    # (pyuff 2.5.8 truncates the file around the binary data in "overwrite" mode: append to an
    # empty file instead.)
    if os.path.exists(path):
        os.remove(path)
    u = pyuff.UFF(path)
    u.write_sets([ds58("accel_B", 1, t, acc_mm, 12, "mm/s^2", 1), ds58("blow", 3, t, force, 13, "N", 1)], mode="add")
    expected["binary.uff"] = [
        {"name": "accel_B", "unit": "m/s^2", "x0": 0.0, "dx": float(t[1]), "values": list(acc_mm * 1e-3)},
        {"name": "blow", "unit": "N", "x0": 0.0, "dx": float(t[1]), "values": list(force)},
    ]
    # Uneven abscissa (times printed %13.5e by pyuff).
    tu = np.cumsum(np.r_[0.0, 1e-4 * (1.0 + 0.5 * np.sin(np.arange(49)))])
    yu = np.cos(tu * 100.0)
    path = os.path.join(d, "uneven.uff")
    u = pyuff.UFF(path)
    u.write_sets([ds58("accel_u", 4, tu, yu, 12, "m/s^2", 0, even=False)], mode="overwrite")
    expected["uneven.uff"] = [{"name": "accel_u", "unit": "m/s^2", "times": list(tu), "values": list(yu)}]
    # An even 51.2 kHz grid over 1 s written as (x, y) pairs: pyuff prints the times %13.5e (6
    # significant digits), so its steps differ by up to ~5e-7 s, the format's rounding.
    te = np.arange(51200) / fs
    ye = np.sin(2 * np.pi * 283.0 * te)
    path = os.path.join(d, "pairs_51k.uff")
    u = pyuff.UFF(path)
    u.write_sets([ds58("accel_p", 5, te, ye, 12, "m/s^2", 0, even=False)], mode="overwrite")
    expected["pairs_51k.uff"] = [{"name": "accel_p", "unit": "m/s^2", "x0": 0.0, "dx": 1.0 / fs, "values": list(ye)}]
    # The same uneven record in binary (pyuff announces the points' bytes, not the pairs').
    path = os.path.join(d, "uneven_binary.uff")
    if os.path.exists(path):
        os.remove(path)
    u = pyuff.UFF(path)
    # (pyuff writes nothing for it in "overwrite" mode or without the ordinate type.)
    u.write_sets([ds58("accel_u", 4, tu, yu, 12, "m/s^2", 1, even=False, ord_data_type=4)], mode="add")
    expected["uneven_binary.uff"] = expected["uneven.uff"]
    # Nodes and a normal mode.
    path = os.path.join(d, "modes.uff")
    u = pyuff.UFF(path)
    nodes = pyuff.prepare_2411(node_nums=np.array([1, 2, 3]), def_cs=np.ones(3, dtype=int), disp_cs=np.ones(3, dtype=int), color=np.full(3, 11, dtype=int),
                               x=np.array([0.0, 1.0, 2.5]), y=np.zeros(3), z=np.array([0.0, 0.125, -3.0]))
    mode = pyuff.prepare_55(model_type=1, analysis_type=2, data_ch=2, spec_data_type=8, load_case=1, mode_n=2, freq=283.0,
                            modal_m=1.0, modal_damp_vis=0.01, modal_damp_his=0.0, node_nums=np.array([1, 2, 3]),
                            r1=np.zeros(3), r2=np.zeros(3), r3=np.array([0.5, -0.25, 0.125]), id1="bed mode")
    u.write_sets([nodes, mode], mode="overwrite")
    expected["modes.uff"] = {"nodes": [[1, 0.0, 0.0, 0.0], [2, 1.0, 0.0, 0.125], [3, 2.5, 0.0, -3.0]],
                             "mode": {"number": 2, "frequency_hz": 283.0, "damping_ratio": 0.01, "z": [0.5, -0.25, 0.125]}}
    # Two modes that are not mass-normalised: shapes 2 psi with modal mass 4, for meid's modes
    # import ([structure.modes]), which divides by sqrt(modal mass).
    path = os.path.join(d, "modes_scaled.uff")
    u = pyuff.UFF(path)
    sets = [nodes]
    psi = {1: [0.125, -0.25, 0.5], 2: [0.0625, 0.375, -0.75]}
    for k, f in [(1, 12.5), (2, 310.0)]:
        sets.append(pyuff.prepare_55(model_type=1, analysis_type=2, data_ch=2, spec_data_type=8, load_case=1, mode_n=k, freq=f,
                                     modal_m=4.0, modal_damp_vis=0.02, modal_damp_his=0.0, node_nums=np.array([1, 2, 3]),
                                     r1=np.zeros(3), r2=np.zeros(3), r3=2.0 * np.array(psi[k]), id1=f"mode {k}"))
    u.write_sets(sets, mode="overwrite")
    # The same modes in mm, tonne, s, N, declared by a dataset 164 (length factor 1000, force 1:
    # 1 kg = 1e-3 t): shapes mass-normalised in mm/sqrt(t), psi * 1000 / sqrt(1e-3).
    path = os.path.join(d, "modes_mm.uff")
    u = pyuff.UFF(path)
    sets = [pyuff.prepare_164(units_code=9, units_description="mm t s N", temp_mode=1, length=1000.0, force=1.0, temp=1.0, temp_offset=273.15), nodes]
    for k, f in [(1, 12.5), (2, 310.0)]:
        sets.append(pyuff.prepare_55(model_type=1, analysis_type=2, data_ch=2, spec_data_type=8, load_case=1, mode_n=k, freq=f,
                                     modal_m=1.0, modal_damp_vis=0.02, modal_damp_his=0.0, node_nums=np.array([1, 2, 3]),
                                     r1=np.zeros(3), r2=np.zeros(3), r3=np.array(psi[k]) * 1e3 / np.sqrt(1e-3), id1=f"mode {k}"))
    u.write_sets(sets, mode="overwrite")
    expected["modes_scaled.uff"] = {"frequency_hz": [12.5, 310.0], "damping_ratio": 0.02,
                                    "psi": {"n1": [psi[1][0], psi[2][0]], "n2": [psi[1][1], psi[2][1]], "n3": [psi[1][2], psi[2][2]]}}
    with open(os.path.join(d, "expected.json"), "w") as f:
        json.dump(expected, f)


def read(path):
    out = []
    for s in pyuff.UFF(path).read_sets():
        if s["type"] == 58:
            out.append({"type": 58, "name": s["id1"].strip(), "unit": s["ordinate_axis_units_lab"].strip(),
                        "x_unit": s["abscissa_axis_units_lab"].strip(), "x": [float(v) for v in s["x"]],
                        "data": [float(v) for v in s["data"]], "node": int(s["rsp_node"]), "dir": int(s["rsp_dir"])})
        elif s["type"] == 164:
            out.append({"type": 164, "units_code": int(s["units_code"]), "length": float(s["length"]), "force": float(s["force"])})
        elif s["type"] == 2411:
            out.append({"type": 2411, "nodes": [[int(a), float(b), float(c), float(e)] for a, b, c, e in zip(s["node_nums"], s["x"], s["y"], s["z"])]})
        elif s["type"] == 15:
            out.append({"type": 15, "nodes": [[int(a), float(b), float(c), float(e)] for a, b, c, e in zip(s["node_nums"], s["x"], s["y"], s["z"])]})
        elif s["type"] == 82:
            out.append({"type": 82, "trace_num": int(s["trace_num"]), "id": s["id"].strip(), "nodes": [int(v) for v in s["nodes"]]})
        elif s["type"] == 2412:
            out.append({"type": 2412, "elements": [{"label": e["element_nums"], "fe_descriptor": e["fe_descriptor"], "nodes": e["nodes_nums"]}
                                                   for k, v in s.items() if isinstance(k, int) for e in v]})
        elif s["type"] == 55:
            out.append({"type": 55, "freq": float(s["freq"]), "mode_n": int(s["mode_n"]), "damping": float(s["modal_damp_vis"]),
                        "node_nums": [int(v) for v in s["node_nums"]], "r3": [float(v) for v in s["r3"]],
                        "id": [s["id%d" % k].strip() for k in range(1, 6)]})
    print(json.dumps(out))


if __name__ == "__main__":
    if sys.argv[1] == "write":
        write(sys.argv[2])
    else:
        read(sys.argv[2])

"""Tests of the meid Python package (run by .ci/run in its own venv after building the wheel).

Checks against meid's own CLI where the same numbers come out (the CLI is tested against
closed forms elsewhere) and, for the physics, the closed-form energy bookkeeping of one blow.
"""

import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import meid

ROOT = pathlib.Path(__file__).resolve().parents[3]
LUMPED = ROOT / "examples" / "paper-lumped.toml"
SOFT = ROOT / "examples" / "paper-soft-base.toml"
COARSE = "structure.fem.machine.elements_per_side=6"
MEID = os.environ.get("MEID_BIN", str(ROOT / "target" / "release" / "meid"))


def cli_json(*args):
    out = subprocess.run([MEID, *map(str, args), "--json"], check=True, capture_output=True)
    return json.loads(out.stdout)


def test_simulate_matches_the_cli_and_the_energy_balance():
    m = meid.Model.from_file(LUMPED)
    run = m.simulate(duration=0.05)
    s = run.summary
    ref = cli_json("simulate", LUMPED, "--duration", "0.05")
    assert s["energy_ratio"] == ref["energy_ratio"]
    # Paper Eq. 10: E_p+/E_s- = (E_s- - E_s+ - E_d+) / E_s-, E_s- = m_s v_s^2 / 2.
    e_s = s["slider_energy_before_j"]
    spec = m.to_dict()
    assert e_s == pytest.approx(0.5 * spec["slider"]["mass"] * spec["slider"]["velocity"] ** 2, rel=1e-15)
    eta = (e_s - s["slider_energy_after_j"] - s["damper_energy_after_j"]) / e_s
    assert s["energy_ratio"] == pytest.approx(eta, rel=1e-12)
    h = run.history
    t = h["time_s"]
    assert t[0] == 0.0 and t[-1] == pytest.approx(0.05)
    assert len(t) == 1001
    assert np.max(np.abs(h["bed_acceleration_m_per_s2"])) <= s["peak_bed_acceleration_m_per_s2"] * (1 + 1e-12)
    df = run.to_pandas()
    assert list(df.columns)[:2] == ["time_s", "bed_displacement_m"]
    assert len(df) == 1001


def test_model_constructors_agree():
    text = LUMPED.read_text()
    a = meid.Model.from_file(LUMPED)
    b = meid.Model.from_toml(text, name="x.toml")
    c = meid.Model.from_dict(a.to_dict())
    ra, rb, rc = (m.simulate(history=False).summary for m in (a, b, c))
    assert ra == rb == rc
    w = a.with_values({"contact.slider_bed.stiffness": 2.5e7, "damper.mass": 5})
    f = meid.Model.from_file(LUMPED, ["contact.slider_bed.stiffness=2.5e7", "damper.mass=5"])
    assert w.simulate(history=False).summary == f.simulate(history=False).summary
    assert w.to_dict()["damper"]["mass"] == 5.0


def test_errors_carry_file_line_column():
    bad = LUMPED.read_text().replace("mass = 1.2 ", "mass = -1.2 ", 1)
    with pytest.raises(meid.InputError) as e:
        meid.Model.from_toml(bad, name="bad.toml")
    assert "bad.toml:" in str(e.value) and "mass" in str(e.value)
    line, col = str(e.value).split("bad.toml:")[1].split(":")[:2]
    assert int(line) > 0 and int(col) > 0
    with pytest.raises(meid.InputError, match="--set damper.mass=-1"):
        meid.Model.from_file(LUMPED).with_values({"damper.mass": -1.0})
    with pytest.raises(meid.InputError, match="did you mean"):
        meid.Model.from_file(LUMPED).with_values({"damper.mas": 1.0})
    assert issubclass(meid.InputError, meid.MeidError)


def test_modes_of_the_fe_model():
    # The two kept modes of the structure (without the static correction's pseudo-modes).
    m = meid.Model.from_file(SOFT, [COARSE, "structure.fem.static_correction=false"])
    md = m.modes()
    f = md["frequencies_hz"]
    assert f.shape == (2,) and f[0] < f[1]
    assert md["shapes"].shape == (len(md["points"]), 2)
    assert "O_b" in md["points"]
    assert m.modes(1)["frequencies_hz"].shape == (1,)
    # With the correction (the default) the pseudo-modes follow them, labelled as such.
    mc = meid.Model.from_file(SOFT, [COARSE]).modes()
    n = mc["frequencies_hz"].shape[0]
    assert n > 2 and mc["frequencies_hz"][:2] == pytest.approx(f, rel=1e-9)
    assert all(lab.startswith("static correction") for lab in mc["labels"][2:])
    assert not any(lab.startswith("static correction") for lab in mc["labels"][:2])


def test_sweep_equals_the_cli_sweep():
    m = meid.Model.from_file(LUMPED)
    t = meid.sweep(m, vary={"wd/ws": "0.5..2:4", "damper.mass": [2.0, 3.5]})
    ref = cli_json("sweep", LUMPED, "--vary", "wd/ws=0.5..2:4", "--vary", "damper.mass=2,3.5")
    assert t.num_rows == 8
    for i, p in enumerate(ref["points"]):
        assert t.column("index")[i].as_py() == p["index"]
        assert t.column("energy_ratio")[i].as_py() == p["metrics"][0]
    assert t.schema.field("peak_floor_force_n").metadata[b"unit"] == b"N"
    df = meid.sweep(m, vary={"wd/ws": [0.5, 1.0]}, output="pandas")
    assert list(df["index"]) == [0, 1]


def test_montecarlo_any_split_and_the_cli():
    m = meid.Model.from_file(SOFT, [COARSE])
    vary = {"contact.slider_bed.stiffness": "lognormal(4.3e7,0.3)", "damper.mass": "uniform(2,5)"}
    whole = meid.montecarlo(m, vary, samples=12, seed=3, output="numpy")
    parts = [meid.montecarlo(m, vary, samples=12, seed=3, first=a, end=b, threads=t, output="numpy")
             for (a, b, t) in [(0, 5, 1), (5, 12, 2)]]
    for k in whole:
        if k == "error":
            continue
        np.testing.assert_array_equal(whole[k], np.concatenate([p[k] for p in parts]))
    ref = cli_json("montecarlo", SOFT, "--set", COARSE, "--vary", "contact.slider_bed.stiffness=lognormal(4.3e7,0.3)",
                   "--vary", "damper.mass=uniform(2,5)", "--samples", "12", "--seed", "3")
    er = whole["energy_ratio"]
    assert ref["metric_stats"][0]["mean"] == pytest.approx(float(np.mean(er)), rel=1e-14)


def test_evaluate_is_the_sweep_point():
    m = meid.Model.from_file(LUMPED)
    x = np.array([[0.5, 2.0], [1.0, 3.5], [2.0, 2.0]])
    y = meid.evaluate(m, ["wd/ws", "damper.mass"], x)
    assert y.shape == (3, len(meid.metric_names()))
    t = meid.sweep(m, vary={"wd/ws": [0.5, 1.0, 2.0], "damper.mass": [2.0, 3.5]}, output="numpy")
    for i, (w, md) in enumerate(x):
        j = [0.5, 1.0, 2.0].index(w) * 2 + [2.0, 3.5].index(md)
        for k, name in enumerate(meid.metric_names()):
            a, b = y[i, k], t[name][j]
            assert (math.isnan(a) and math.isnan(b)) or a == b, name
    e = meid.evaluate(m, ["damper.mass"], np.array([[-1.0]]), metrics=["energy_ratio"])
    assert np.isnan(e[0, 0])
    with pytest.raises(meid.InputError):
        meid.evaluate(m, ["wd/ws"], np.zeros((2, 2)))
    # A misspelled field is an error naming it (it used to give a row of NaN).
    with pytest.raises(meid.InputError, match="damper.mas.*did you mean `mass`"):
        meid.evaluate(m, ["damper.mas"], np.array([[1.0]]))
    with pytest.raises(meid.InputError, match="damper.mas"):
        meid.evaluate(m, ["damper.mas"], np.zeros((0, 1)))


def test_model_pickles_as_its_text():
    import pickle

    m = meid.Model.from_file(LUMPED, ["damper.mass=4.0"])
    m2 = pickle.loads(pickle.dumps(m))
    assert m2.overrides == ["damper.mass=4.0"]
    assert m2.simulate(history=False).summary == m.simulate(history=False).summary


def test_blows_steady_state_is_the_cli_s():
    """meid.blows(steady=True) is `meid blows --steady --json`'s object: the same steady state
    (regime, levels, multipliers) and verdict, for the case asked."""
    m = meid.Model.from_file(LUMPED)
    py = meid.blows(m, 60.0, steady=True, case="damper")
    ref = cli_json("blows", LUMPED, "--rate-bpm", "60", "--steady", "--case", "damper")
    s = py["steady_state"]
    for key in ["converged", "residual", "map_evaluations", "regime", "period_blows",
                "energy_ratio", "peak_floor_force_n", "peak_bed_acceleration_m_per_s2",
                "damper_gap_at_strike_m", "damper_touches_bed", "multipliers_abs"]:
        assert s[key] == ref["steady_state"][key], key
    assert s["converged"] and s["regime"] == "period-1"
    # At 60 /min the paper's damper does not return (docs/explanations/blows.md, "Production").
    assert s["damper_touches_bed"] is False
    assert py["verdict"] == ref["verdict"] and "does not return" in py["verdict"][0]


def test_impact_tables_are_the_cli_s():
    """Run.summary's `impacts` and `impact_totals`, and meid.blows(steady=False)'s `impacts`,
    are `meid simulate --json`'s and `meid blows --json`'s."""
    m = meid.Model.from_file(LUMPED)
    s = m.simulate(duration=0.05, history=False).summary
    ref = cli_json("simulate", LUMPED, "--duration", "0.05")
    assert s["impacts"] == ref["impacts"] and s["impact_totals"] == ref["impact_totals"]
    assert s["impacts"][0]["contact"] == "slider_bed"
    py = meid.blows(m, 60.0, steady=False, blows=2)
    ref = cli_json("blows", LUMPED, "--rate-bpm", "60", "--blows", "2")
    assert py["impacts"] == ref["impacts"]
    assert [r["blow"] for r in py["impacts"] if r["contact"] == "slider_bed"] == [1, 2]

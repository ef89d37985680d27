"""The Python API as a user meets it (run by .ci/run): the numbers equal the CLI's to the bit,
bad input raises a named Python exception (never a panic, an abort or a bare OverflowError),
returned arrays are copies, the stubs match the extension's signatures, and a huge request is
refused before anything is allocated."""

import ast
import inspect
import json
import os
import pathlib
import pickle
import subprocess
import warnings

import numpy as np
import pytest

import meid
import meid._meid as ext

ROOT = pathlib.Path(__file__).resolve().parents[3]
LUMPED = ROOT / "examples" / "paper-lumped.toml"
SOFT = ROOT / "examples" / "paper-soft-base.toml"
COARSE = "structure.fem.machine.elements_per_side=6"
STUB = ROOT / "crates" / "meid-py" / "python" / "meid" / "_meid.pyi"
MEID = os.environ.get("MEID_BIN", str(ROOT / "target" / "release" / "meid"))


def cli(*args, json_out=True):
    extra = ["--json"] if json_out else ["-q"]
    out = subprocess.run([MEID, *map(str, args), *extra], check=True, capture_output=True)
    return json.loads(out.stdout) if json_out else None


@pytest.fixture
def memory_limit():
    """Restores the process-wide memory limit a test changes."""
    before = meid.max_memory()
    yield
    meid.set_max_memory(before)


@pytest.mark.parametrize(
    "path, sets, kwargs, flags",
    [
        (LUMPED, [], {}, []),
        (LUMPED, [], {"method": "dopri5"}, ["--method", "dopri5"]),
        (LUMPED, [], {"case": "none"}, ["--case", "none"]),
        (LUMPED, [], {"duration": 0.013, "rate": 7777.0}, ["--duration", "0.013", "--rate", "7777"]),
        (SOFT, [COARSE], {"duration": 0.05}, ["--duration", "0.05"]),
    ],
)
def test_simulate_summary_is_the_cli_json_bit_for_bit(path, sets, kwargs, flags):
    # Every field of `meid simulate --json`, the truncation table, notes and warnings
    # included (Python's summary used to lack those three: a user of the soft-base model
    # never saw that the retained modes carry only 74 % of the flexibility at B).
    args = [a for s in sets for a in ("--set", s)]
    ref = cli("simulate", path, *args, *flags)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = meid.Model.from_file(path, sets).simulate(history=False, **kwargs).summary
    assert s == ref
    assert [str(w.message) for w in caught if w.category is meid.MeidWarning] == ref["warnings"]


def test_history_is_the_cli_history_csv_to_the_last_printed_digit(tmp_path):
    pd = pytest.importorskip("pandas")
    out = tmp_path / "sim"
    cli("simulate", LUMPED, "--duration", "0.05", "--method", "dopri5", "-o", out, json_out=False)
    csv = pd.read_csv(out / "history.csv", dtype=str)
    h = meid.Model.from_file(LUMPED).simulate(duration=0.05, method="dopri5").history
    assert list(csv.columns) == list(h)
    for col in csv.columns:
        # history.csv prints 13 significant digits ({:.12e}): each Python value, printed so,
        # is the CSV's number.
        printed = np.array([float(format(x, ".12e")) for x in h[col]])
        np.testing.assert_array_equal(printed, csv[col].to_numpy(dtype=float), err_msg=col)


def test_the_soft_base_truncation_warning_reaches_python():
    # Without the static correction, which restores B's share (and silences the warning).
    m = meid.Model.from_file(SOFT, [COARSE, "structure.fem.static_correction=false"])
    with pytest.warns(meid.MeidWarning, match="static flexibility at point 'B'"):
        run = m.simulate(duration=0.01, history=False)
    d = m.diagnostics()
    assert d["warnings"] == run.summary["warnings"] and d["warnings"]
    b = [r for r in d["truncation"] if r["point"] == "B"][0]
    # The captured share is the ratio of the two flexibilities it is printed beside.
    assert b["captured_share"] == pytest.approx(
        b["modal_flexibility_m_per_n"] / b["static_flexibility_m_per_n"], rel=1e-12
    )
    assert b["captured_share"] < 0.95


def test_history_time_vector_is_the_sample_grid_and_a_copy():
    m = meid.Model.from_file(LUMPED)
    duration, rate = 0.0123, 7000.0
    run = m.simulate(duration=duration, rate=rate)
    h = run.history
    t = h["time_s"]
    # floor(duration * rate) + 1 samples at i / rate.
    n = int(np.floor(duration * rate)) + 1
    assert t.shape == (n,) and t.dtype == np.float64
    np.testing.assert_allclose(t, np.arange(n) / rate, rtol=0, atol=1e-17)
    assert all(v.shape == (n,) and v.dtype == np.float64 for v in h.values())
    # Mutating a returned array leaves the Run intact.
    before = h["bed_acceleration_m_per_s2"].copy()
    h["bed_acceleration_m_per_s2"][:] = 0.0
    np.testing.assert_array_equal(run.history["bed_acceleration_m_per_s2"], before)
    md = m.modes()
    md["frequencies_hz"][:] = 0.0
    assert m.modes()["frequencies_hz"][0] > 0
    s = run.summary
    s["energy_ratio"] = -1.0
    assert run.summary["energy_ratio"] > 0
    assert repr(m.simulate(history=False)) == "meid.Run(no history)"


def test_run_pickles_bit_for_bit():
    m = meid.Model.from_file(LUMPED)
    run = m.simulate(duration=0.01)
    r2 = pickle.loads(pickle.dumps(run))
    assert r2.summary == run.summary
    for k, v in run.history.items():
        np.testing.assert_array_equal(r2.history[k], v, err_msg=k)
    r3 = pickle.loads(pickle.dumps(m.simulate(history=False)))
    assert r3.history is None
    assert r3.summary == m.simulate(history=False).summary
    with pytest.raises(meid.MeidError, match="not 21 columns"):
        meid.Run._from_state("{}", b"\0" * 8)


def test_file_errors_are_oserrors_and_meid_errors():
    path = ROOT / "no-such-model.toml"
    with pytest.raises(FileNotFoundError) as e:
        meid.Model.from_file(path)
    assert isinstance(e.value, meid.MeidError)
    assert e.value.errno == 2 and e.value.filename == str(path)
    with pytest.raises(OSError) as e:
        meid.Model.from_file(ROOT / "examples")
    assert isinstance(e.value, meid.FileError) and isinstance(e.value, meid.MeidError)
    # Picklable (Dask sends a task's exception back to the client).
    e2 = pickle.loads(pickle.dumps(meid.FileNotFound("x")))
    assert type(e2) is meid.FileNotFound


def test_numpy_values_in_from_dict_and_with_values():
    m = meid.Model.from_file(LUMPED)
    d = m.to_dict()
    d["damper"]["mass"] = np.float32(3.25)  # exactly representable
    d["slider"]["velocity"] = np.int64(1)
    d["structure"]["lumped"]["damping_ratios"] = np.array([0.01, 0.02])
    a = meid.Model.from_dict(d)
    b = meid.Model.from_file(LUMPED, ["damper.mass=3.25", "slider.velocity=1.0",
                                      "structure.lumped.damping_ratios=[0.01, 0.02]"])
    assert a.to_dict() == b.to_dict()
    assert a.simulate(history=False).summary == b.simulate(history=False).summary
    # One override may be given as a str.
    one = meid.Model.from_file(LUMPED, "damper.mass=3.25")
    assert one.overrides == ["damper.mass=3.25"]
    assert one.to_dict()["damper"]["mass"] == 3.25
    c = m.with_values({"damper.mass": np.float64(3.25), "slider.velocity": np.int64(1),
                       "damper.dashpot": "two-way"})
    assert c.to_dict()["damper"] == {**b.to_dict()["damper"], "dashpot": "two-way"}
    # A Python int beyond i64 is the nearest real, not an OverflowError.
    assert m.with_values({"damper.mass": 10**30}).to_dict()["damper"]["mass"] == 1e30
    # Shortest round-trip text: the double itself comes back.
    x = 1 / 3
    assert m.with_values({"damper.mass": x}).to_dict()["damper"]["mass"] == x


@pytest.mark.parametrize(
    "call, exc, match",
    [
        # NaN used to be spelled "NaN", which TOML reads as a string: "expected a number".
        (lambda m: m.with_values({"damper.mass": float("nan")}), meid.InputError,
         r"damper\.mass: must be a finite number > 0 kg \(got NaN\)"),
        (lambda m: m.simulate(duration=float("nan")), meid.InputError,
         r"simulation\.duration must be a finite number > 0 s \(got NaN\)"),
        (lambda m: m.simulate(rate=float("nan")), meid.InputError,
         r"simulation\.sample_rate must be a finite number > 0 Hz \(got NaN\)"),
        (lambda m: m.with_values({1: 3.0}), TypeError, "keys are field paths"),
        (lambda m: meid.Model.from_file(LUMPED, [3]), TypeError,
         r'overrides: a list of "PATH=VALUE" strings'),
        (lambda m: meid.Model.from_dict({1: 2}), meid.InputError,
         r"^from_dict: dictionary keys must be strings"),
        # A missing file is a FileNotFoundError too (it was a MeidError only).
        (lambda m: meid.Model.from_file(ROOT / "no-such-model.toml"), FileNotFoundError,
         "No such file or directory.*no-such-model.toml"),
        (lambda m: meid.Model.from_file(ROOT / "no-such-model.toml"), meid.FileNotFound, "Errno 2"),
        (lambda m: meid.Model.from_file(ROOT / "examples"), meid.FileError, "examples"),
        # Negative counts used to raise a bare OverflowError naming nothing.
        (lambda m: m.modes(-1), meid.InputError, r"count: must be an integer >= 0 \(got -1\)"),
        (lambda m: meid.evaluate(m, ["wd/ws"], [[1.0]], threads=-1), meid.InputError,
         r"threads: must be an integer >= 1 \(got -1\)"),
        (lambda m: meid.sweep(m, {"wd/ws": [1.0]}, threads=0), meid.InputError,
         r"threads: must be an integer >= 1 \(got 0\)"),
        (lambda m: meid.montecarlo(m, {"damper.mass": "uniform(2,5)"}, samples=-1),
         meid.InputError, r"samples: must be an integer >= 0 \(got -1\)"),
        (lambda m: meid.montecarlo(m, {"damper.mass": "uniform(2,5)"}, samples=3, seed=-1),
         meid.InputError, r"seed: must be an integer in 0\.\.2\^64 \(got -1\)"),
        (lambda m: meid.montecarlo(m, {"damper.mass": "uniform(2,5)"}, samples=3, first=-2),
         meid.InputError, r"first: must be an integer >= 0 \(got -2\)"),
        # Shapes: a 3-d array used to give numpy's "dimensionality mismatch: from=3, to=2".
        (lambda m: meid.evaluate(m, ["wd/ws", "damper.mass"], np.zeros((2, 2, 2))), ValueError,
         r"values: needs shape \(N, 2\).*got shape \(2, 2, 2\)"),
        (lambda m: meid.evaluate(m, ["wd/ws", "damper.mass"], np.zeros(2)), ValueError,
         r"values: needs shape \(N, 2\)"),
        (lambda m: meid.evaluate(m, ["wd/ws"], [["a"]]), TypeError, "values: needs an"),
        (lambda m: meid.evaluate(m, ["wd/ws"], np.zeros((2, 2))), meid.InputError,
         "values has 2 columns for 1 names"),
        (lambda m: meid.sweep(m, {"wd/ws": ["x"]}), TypeError, r"vary\['wd/ws'\]"),
    ],
)
def test_bad_input_raises_a_named_python_error(call, exc, match):
    m = meid.Model.from_file(LUMPED)
    with pytest.raises(exc, match=match):
        call(m)


def test_evaluate_takes_any_layout_dtype_and_a_single_name():
    m = meid.Model.from_file(LUMPED)
    names = ["wd/ws", "damper.mass"]
    x = np.array([[1.0, 3.5], [0.75, 2.0], [1.25, 3.0], [0.5, 4.0]])  # float32-exact
    y = meid.evaluate(m, names, x)
    # Fortran order, reversed rows (negative strides), a broadcast row (stride 0), float32
    # and int values: the same rows, bit for bit.
    np.testing.assert_array_equal(meid.evaluate(m, names, np.asfortranarray(x)), y)
    np.testing.assert_array_equal(meid.evaluate(m, names, x[::-1])[::-1], y)
    b = np.broadcast_to(x[:1], (3, 2))
    np.testing.assert_array_equal(meid.evaluate(m, names, b), np.repeat(y[:1], 3, axis=0))
    np.testing.assert_array_equal(meid.evaluate(m, names, x.astype(np.float32)), y)
    xi = np.array([[1, 3], [1, 2]])
    np.testing.assert_array_equal(meid.evaluate(m, names, xi), meid.evaluate(m, names, xi * 1.0))
    # A str is one name (it used to be split into its characters: "1 columns for 11 names").
    one = meid.evaluate(m, "damper.mass", [2.0, 3.5], metrics="energy_ratio")
    assert one.shape == (2, 1)
    np.testing.assert_array_equal(
        one[:, 0], meid.evaluate(m, ["damper.mass"], [[2.0], [3.5]])[:, 0]
    )


def test_sweep_with_a_duration_is_the_cli_and_the_whole_run():
    m = meid.Model.from_file(LUMPED)
    t = meid.sweep(m, {"damper.mass": [2.0, 3.0]}, duration=0.3, output="numpy")
    ref = cli("sweep", LUMPED, "--vary", "damper.mass=2,3", "--duration", "0.3")
    names = [k for k in t if k != "error"]
    for i, p in enumerate(ref["points"]):
        row = [p["index"], *p["values"], *p["derived"], *p["metrics"]]
        for n, v in zip(names, row):
            assert (np.isnan(t[n][i]) and v is None) or t[n][i] == v, (i, n)
    # Every point ran 0.3 s: the floor-force peak is the whole run's, as simulate gives it
    # (stopped at the end of the collision it is ~0.1 N, the peak during 0.6 ms of contact).
    for i, md in enumerate([2.0, 3.0]):
        s = m.with_values({"damper.mass": md}).simulate(duration=0.3, history=False).summary
        assert t["simulated_time_s"][i] == s["simulated_time_s"] == 0.3
        assert t["peak_floor_force_n"][i] == s["peak_floor_force_n"]
        assert t["energy_ratio"][i] == s["energy_ratio"]
    short = meid.sweep(m, {"damper.mass": [2.0]}, output="numpy")
    assert short["peak_floor_force_n"][0] < 1.0 < t["peak_floor_force_n"][0]


def test_evaluate_says_why_a_row_failed():
    m = meid.Model.from_file(LUMPED)
    x = [[2.0], [-1.0], [3.5]]
    y, why = meid.evaluate(m, ["damper.mass"], x, errors=True)
    np.testing.assert_array_equal(y, meid.evaluate(m, ["damper.mass"], x))
    assert why[0] is None and why[2] is None
    assert np.isnan(y[1]).all() and not np.isnan(y[0, 0])
    assert "damper.mass" in why[1] and "must be a finite number > 0 kg" in why[1]


@pytest.mark.parametrize(
    "name, call",
    [
        ("evaluate", lambda m: meid.evaluate(
            m, ["wd/ws", "damper.mass"], np.broadcast_to(np.array([[1.0, 3.5]]), (10**6, 2)),
            metrics=["energy_ratio"])),
        ("sweep", lambda m: meid.sweep(m, {"wd/ws": "0.5..2:1000", "damper.mass": "2..5:1000"})),
        ("montecarlo", lambda m: meid.montecarlo(m, {"damper.mass": "uniform(2,5)"},
                                                 samples=10**6)),
    ],
)
def test_a_long_study_stops_on_ctrl_c(name, call):
    import _thread
    import threading

    m = meid.Model.from_file(LUMPED)
    # 10^6 points each: tens of seconds of CPU. Ctrl-C (SIGINT's handler, as interrupt_main
    # runs it) 0.3 s in used to be ignored until the last point: the GIL is released, and
    # only the calling thread runs Python's signal handlers.
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as e:
            call(m)
    finally:
        timer.cancel()
    # Raised inside the study (meid/__init__.py), not before the call or after it returned.
    assert e.traceback[-1].name == name


def test_a_huge_request_is_refused_before_allocating(memory_limit):
    m = meid.Model.from_file(LUMPED)
    # 10^9 rows as a broadcast view (8 B of data): 10^9 x 25 x 8 B = 186 GiB would be
    # allocated. This used to abort the interpreter ("memory allocation of 192000000000
    # bytes failed"); now it is an InputError before any allocation.
    x = np.broadcast_to(np.array([[3.0]]), (10**9, 1))
    meid.set_max_memory("1GiB")
    assert meid.max_memory() == 1 << 30
    with pytest.raises(meid.InputError, match=r"evaluate's 1000000000 rows.*meid\.set_max_memory"):
        meid.evaluate(m, ["damper.mass"], x)
    with pytest.raises(meid.InputError, match="1.000e12 points"):
        meid.sweep(m, {"wd/ws": "0.5..2:1000000", "damper.mass": "1..5:1000000"})
    with pytest.raises(meid.InputError, match="1000000000000 Monte Carlo samples"):
        meid.montecarlo(m, {"damper.mass": "uniform(2,5)"}, samples=10**12)
    # The history Python holds is counted whole: 4001 samples x 160 B (meid's record alone)
    # is 0.61 MiB, under 1 MiB; with the Run's columns and the numpy copy (496 B a sample)
    # it is 1.89 MiB, refused.
    meid.set_max_memory(1 << 20)
    with pytest.raises(meid.InputError, match=r"4\.001e3 samples × 496 B"):
        m.simulate(duration=0.2, rate=20000.0)
    assert m.simulate(duration=0.2, rate=20000.0, history=False).summary["energy_ratio"] > 0
    with pytest.raises(meid.InputError, match="at least 1 byte"):
        meid.set_max_memory(0)
    with pytest.raises(meid.InputError, match="max_memory"):
        meid.set_max_memory("lots")


def test_units_are_the_parquet_units_of_the_cli(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    out = tmp_path / "sweep"
    vary = {"simulation.duration": [0.1, 0.2], "contact.slider_bed.damping": [0.0, 1.0]}
    cli("sweep", LUMPED, *[a for k, v in vary.items() for a in ("--vary", f"{k}={v[0]},{v[1]}")],
        "-o", out, json_out=False)
    ref = pq.read_table(out / "sweep.parquet").schema
    t = meid.sweep(meid.Model.from_file(LUMPED), vary)
    assert t.schema.names == ref.names
    # The same types (the index was int64 in Python, uint64 in the CLI's file) and values.
    assert [f.type for f in t.schema] == [f.type for f in ref]
    cli_table = pq.read_table(out / "sweep.parquet")
    for n in ref.names:
        assert t.column(n).to_pylist() == cli_table.column(n).to_pylist(), n
    for f in ref:
        if f.name == "error":
            continue
        want = (f.metadata or {}).get(b"unit")
        assert (t.schema.field(f.name).metadata or {}).get(b"unit") == want, f.name
        assert meid.units(f.name) == (None if want is None else want.decode()), f.name
    # A field of unknown unit has none (it used to be called dimensionless, "1").
    assert meid.units("simulation.duration") is None
    # History columns: displacements are metres (they used to be "1").
    assert meid.units("bed_displacement_m") == "m"
    assert meid.units("time_s") == "s"
    assert meid.units("bed_acceleration_m_per_s2") == "m/s^2"


def _stub_functions():
    """{qualified name: ast.FunctionDef} of _meid.pyi (top level and class bodies)."""
    tree = ast.parse(STUB.read_text())
    out = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = node
        elif isinstance(node, ast.ClassDef):
            for f in node.body:
                if isinstance(f, ast.FunctionDef):
                    deco = {d.id for d in f.decorator_list if isinstance(d, ast.Name)}
                    if "property" not in deco:
                        out[f"{node.name}.{f.name}"] = f
    return out


def test_stubs_match_the_extension_signatures():
    stubs = _stub_functions()
    checked = 0
    for qual, f in stubs.items():
        obj = ext
        for part in qual.split("."):
            obj = getattr(obj, part)
        sig = inspect.signature(obj)
        static = any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in f.decorator_list)
        args = f.args.args[(0 if static or "." not in qual else 1):]
        defaults = [None] * (len(f.args.args) - len(f.args.defaults)) + list(f.args.defaults)
        defaults = defaults[len(f.args.args) - len(args):]
        params = [p for p in sig.parameters.values() if p.name != "self"]
        assert [a.arg for a in args] == [p.name for p in params], qual
        for a, d, p in zip(args, defaults, params):
            assert (d is None) == (p.default is inspect.Parameter.empty), f"{qual}({a.arg})"
            if d is not None and isinstance(d, ast.Constant) and p.default is not Ellipsis:
                assert ast.literal_eval(d) == p.default, f"{qual}({a.arg})"
        checked += 1
    # Every public function and method of the extension has a stub.
    public = {n for n in dir(ext) if callable(getattr(ext, n)) and not n.startswith("_")
              and not isinstance(getattr(ext, n), type)}
    public |= {f"{c}.{n}" for c in ("Model", "Run") for n in vars(getattr(ext, c))
               if callable(getattr(getattr(ext, c), n)) and not n.startswith("__")}
    assert public <= set(stubs), public - set(stubs)
    assert checked >= 15

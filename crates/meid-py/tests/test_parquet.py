"""The Parquet files of `meid sweep -o DIR` and `meid montecarlo -o DIR`, read by pyarrow and
pandas (run by .ci/run): typed columns, units in the column metadata, the study's facts in the
file metadata, values equal to the CSV of the same run (and to the Python API's)."""

import hashlib
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import meid

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pd = pytest.importorskip("pandas")

ROOT = pathlib.Path(__file__).resolve().parents[3]
LUMPED = ROOT / "examples" / "paper-lumped.toml"
MEID = os.environ.get("MEID_BIN", str(ROOT / "target" / "release" / "meid"))


def meid_cli(*args):
    subprocess.run([MEID, *map(str, args), "-q"], check=True, capture_output=True)


def fnv1a(data: bytes) -> str:
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) % (1 << 64)
    return f"{h:016x}"


def test_sweep_parquet_has_types_units_and_the_csv_values(tmp_path):
    out = tmp_path / "sweep"
    # damper.mass = -1 is refused per point: failed rows (NaN metrics, an error message).
    meid_cli("sweep", LUMPED, "--vary", "wd/ws=0.5..2:4", "--vary", "damper.mass=2,3.5,-1",
             "-o", out)
    manifest = json.loads((out / "manifest.json").read_text())
    assert "sweep.parquet" in [f["name"] for f in manifest["files"]]
    t = pq.read_table(out / "sweep.parquet")
    s = t.schema
    assert s.field("index").type == pa.uint64()
    assert s.field("error").type == pa.string()
    for f in s:
        if f.name not in ("index", "error"):
            assert f.type == pa.float64(), f.name
    units = {f.name: f.metadata[b"unit"].decode() for f in s if f.metadata}
    assert units["peak_floor_force_n"] == "N"
    assert units["peak_bed_acceleration_m_per_s2"] == "m/s^2"
    assert units["slider_energy_before_j"] == "J"
    assert units["slider_contact_stiffness_n_per_m"] == "N/m"
    assert units["damper.mass"] == "kg"
    assert units["wd/ws"] == "1" and units["energy_ratio"] == "1"
    assert units["collision_end_s"] == "s"
    meta = {k.decode(): v.decode() for k, v in pq.read_metadata(out / "sweep.parquet").metadata.items()}
    assert meta["command"] == "sweep"
    assert meta["meid_version"] == meid.__version__
    assert meta["model_hash"] == fnv1a(LUMPED.read_bytes())
    assert json.loads(meta["sweep"])["columns"] == t.column_names
    assert s.metadata[b"model_hash"] == meta["model_hash"].encode()

    csv = pd.read_csv(out / "sweep.csv")
    df = t.to_pandas()
    assert list(df.columns) == list(csv.columns)
    assert len(df) == 12
    assert df["index"].dtype == np.uint64
    assert list(df["index"]) == list(range(12))
    failed = df["error"].notna()
    assert failed.sum() == 4
    assert list(df["error"][failed]) == list(csv["error"][csv["error"].notna()])
    for c in csv.columns:
        if c in ("index", "error"):
            continue
        # sweep.csv prints shortest round-trip numbers: the values are equal bit for bit
        # (an empty CSV field, a metric not defined, is null in Parquet: NaN in both frames).
        np.testing.assert_array_equal(df[c].to_numpy(dtype=float), csv[c].to_numpy(dtype=float),
                                      err_msg=c)


def test_montecarlo_parquet_has_types_units_and_the_csv_values(tmp_path):
    out = tmp_path / "mc"
    vary = {"contact.slider_bed.stiffness": "lognormal(4.3e7,0.3)", "damper.mass": "uniform(2,5)"}
    args = [a for k, v in vary.items() for a in ("--vary", f"{k}={v}")]
    meid_cli("montecarlo", LUMPED, *args, "--samples", "40", "--seed", "5", "-o", out)
    path = out / "samples.parquet"
    t = pq.read_table(path)
    s = t.schema
    assert s.field("sample").type == pa.uint64()
    assert s.field("error").type == pa.string()
    assert s.field("contact.slider_bed.stiffness").metadata[b"unit"] == b"N/m"
    assert s.field("damper.mass").metadata[b"unit"] == b"kg"
    assert s.field("peak_contact_force_slider_bed_n").metadata[b"unit"] == b"N"
    assert s.field("energy_ratio").metadata[b"unit"] == b"1"
    meta = {k.decode(): v.decode() for k, v in pq.read_metadata(path).metadata.items()}
    assert meta["command"] == "montecarlo"
    assert meta["seed"] == "5" and meta["samples"] == "40"
    assert meta["model_hash"] == fnv1a(LUMPED.read_bytes())
    assert meta["meid_version"] == meid.__version__
    assert [u["path"] for u in json.loads(meta["inputs"])] == list(vary)

    df = t.to_pandas()
    csv = pd.read_csv(out / "samples.csv")
    assert list(df.columns) == list(csv.columns)
    assert list(df["sample"]) == list(range(40))
    # samples.csv prints 13 significant digits ({:.12e}): equal to half a unit in its last
    # digit. Parquet holds the exact doubles: equal bit for bit to the Python API's samples.
    api = meid.montecarlo(meid.Model.from_file(LUMPED), vary, samples=40, seed=5, output="numpy")
    for c in csv.columns:
        if c in ("sample", "error"):
            continue
        a, b = df[c].to_numpy(dtype=float), csv[c].to_numpy(dtype=float)
        # (+ 2.3e-16: the rounding of the decimal text to a double.)
        np.testing.assert_allclose(a, b, rtol=5e-13 + 2.3e-16, atol=0, err_msg=c)
        np.testing.assert_array_equal(a, api[c], err_msg=c)

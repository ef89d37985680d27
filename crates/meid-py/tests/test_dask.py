"""meid.dask on a real LocalCluster of 2 worker processes (run by .ci/run).

Checks that a study cut into tasks and gathered from the workers equals the single-process
run row for row, and that a worker process dying mid-study (it exits on its second task, so a
finished result held in its memory is lost too) loses and duplicates nothing: Dask reruns the
lost tasks elsewhere and the gathered rows tile the study once.
"""

import os
import pathlib
import sys

import numpy as np
import pytest

import meid
import meid.dask

distributed = pytest.importorskip("distributed")
cloudpickle = pytest.importorskip("cloudpickle")
# The worker plugin below travels by value: the workers cannot import this test module.
cloudpickle.register_pickle_by_value(sys.modules[__name__])

ROOT = pathlib.Path(__file__).resolve().parents[3]
LUMPED = ROOT / "examples" / "paper-lumped.toml"
VARY = {"contact.slider_bed.stiffness": "lognormal(4.3e7,0.3)", "damper.mass": "uniform(2,5)"}


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def equal_columns(a, b):
    assert list(a) == list(b)
    for k in a:
        if k == "error":
            assert list(a[k]) == list(b[k])
        else:
            np.testing.assert_array_equal(a[k], b[k], err_msg=k)


class KillOnce(distributed.WorkerPlugin):
    """Makes the first worker process that starts its second task exit at once (os._exit:
    no cleanup, as a killed node), once per marker file."""

    def __init__(self, marker, prefix):
        self.marker = marker
        self.prefix = prefix
        self.started = 0

    def transition(self, key, start, finish, **kwargs):
        if finish != "executing" or not str(key).startswith(self.prefix):
            return
        self.started += 1
        if self.started < 2:
            return
        try:
            fd = os.open(self.marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            return
        os.write(fd, str(os.getpid()).encode())
        os.close(fd)
        os._exit(17)


def test_chunks_tile_the_study():
    assert meid.dask.chunks(5, 2) == [(0, 2), (2, 4), (4, 5)]
    assert meid.dask.chunks(0, 3) == []
    with pytest.raises(ValueError):
        meid.dask.chunks(5, 0)


def test_montecarlo_on_two_workers_equals_one_process(client):
    m = meid.Model.from_file(LUMPED)
    whole = meid.montecarlo(m, VARY, samples=300, seed=7, output="numpy")
    dist = meid.dask.montecarlo(client, LUMPED, VARY, samples=300, seed=7, chunk=40, output="numpy")
    equal_columns(whole, dist)
    assert list(dist["sample"]) == list(range(300))
    t = meid.dask.montecarlo(client, m, VARY, samples=300, seed=7, chunk=128)
    assert t.schema.field("peak_floor_force_n").metadata[b"unit"] == b"N"
    np.testing.assert_array_equal(t.column("energy_ratio").to_numpy(), whole["energy_ratio"])
    # A part of the study (first..end), as a client gathers one too large for its memory.
    part = meid.dask.montecarlo(client, m, VARY, samples=300, seed=7, first=100, end=260,
                                chunk=64, output="numpy")
    equal_columns(part, {k: v[100:260] for k, v in whole.items()})
    with pytest.raises(ValueError, match="outside"):
        meid.dask.montecarlo(client, m, VARY, samples=300, first=10, end=400)


def test_sweep_on_two_workers_equals_one_process(client):
    m = meid.Model.from_file(LUMPED)
    vary = {"wd/ws": np.linspace(0.5, 2.0, 7), "damper.mass": [2.0, 3.5, 5.0]}
    x, y = meid.dask.sweep(client, m, vary, chunk=4)
    t = meid.sweep(m, vary={k: list(v) for k, v in vary.items()}, output="numpy")
    assert x.shape == (21, 2) and y.shape == (21, len(meid.metric_names()))
    np.testing.assert_array_equal(x[:, 0], t["wd/ws"])
    np.testing.assert_array_equal(x[:, 1], t["damper.mass"])
    for k, name in enumerate(meid.metric_names()):
        np.testing.assert_array_equal(y[:, k], t[name], err_msg=name)
    with pytest.raises(TypeError, match="list or array"):
        meid.dask.sweep(client, m, {"wd/ws": "0.5..2:7"})
    with pytest.raises(meid.InputError):
        meid.dask.sweep(client, m, {"damper.mas": [1.0]})


def test_a_worker_killed_mid_study_loses_and_duplicates_nothing(client, tmp_path):
    marker = tmp_path / "killed"
    before = set(client.run(os.getpid).values())
    client.register_plugin(KillOnce(str(marker), "_mc_task"), name="kill-once")
    try:
        whole = meid.montecarlo(meid.Model.from_file(LUMPED), VARY, samples=400, seed=11,
                                output="numpy")
        dist = meid.dask.montecarlo(client, LUMPED, VARY, samples=400, seed=11, chunk=25,
                                    output="numpy")
    finally:
        client.unregister_worker_plugin("kill-once")
    # A worker process did die mid-study (it wrote its pid, then exited) and the nanny
    # replaced it.
    assert marker.exists()
    dead = int(marker.read_text())
    assert dead in before
    client.wait_for_workers(2, timeout=30)
    after = set(client.run(os.getpid).values())
    assert dead not in after
    # Nothing lost, nothing duplicated, every value the single-process one.
    assert list(dist["sample"]) == list(range(400))
    equal_columns(whole, dist)


def _simulate(model, duration):
    return model.simulate(duration=duration)


def test_a_run_comes_back_from_a_worker_process_and_errors_carry_meids_message(client):
    # A Run computed in a worker process travels back pickled (it used to fail: "Could not
    # serialize object of type Run"), bit for bit.
    m = meid.Model.from_file(LUMPED)
    here = m.simulate(duration=0.02)
    there = client.submit(_simulate, m, 0.02, pure=False).result()
    assert there.summary == here.summary
    for k, v in here.history.items():
        np.testing.assert_array_equal(there.history[k], v, err_msg=k)
    # An error raised in a task is meid's, class and message, on the client.
    with pytest.raises(meid.InputError, match=r"simulation\.duration must be a finite number > 0 s"):
        client.submit(_simulate, m, -1.0, pure=False).result()


def test_a_study_too_large_for_the_client_is_refused_before_any_task(client):
    m = meid.Model.from_file(LUMPED)
    before = len(client.futures)
    # 10^12 samples used to pass the check (it looked at 0 samples) and queue 5 * 10^8 tasks.
    with pytest.raises(meid.InputError, match=r"samples 0\.\.1000000000000: 1\.000e\+12 rows"):
        meid.dask.montecarlo(client, m, VARY, samples=10**12)
    # A grid of 10^4 x 10^4 x 10^4 points (the value lists are small; the grid is not).
    big = np.linspace(1.0, 2.0, 10**4)
    with pytest.raises(meid.InputError, match=r"the grid: 1\.000e\+12 rows of 27 columns"):
        meid.dask.sweep(client, m, {"wd/ws": big, "damper.mass": big + 1, "slider.mass": big})
    assert len(client.futures) == before

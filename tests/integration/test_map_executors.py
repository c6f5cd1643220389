"""Every map on every executor: a dask cluster's workers, Ctrl-C keeping what was computed.

- A map on a dask cluster runs as many tasks at once as the cluster's workers have
  threads, not as this machine has processors (issue 29: from a 2-core laptop a 100-worker
  cluster ran 4 tasks at a time). The tasks record when they run; their largest overlap is
  the concurrency.
- ``multi_impact_map`` takes the executors, progress and memory bound of
  ``stability_map`` (issue 29) and gives the same map on each.
- Ctrl-C during a map (issue 31): a first one returns the points computed, the others NaN
  and marked, with a WARNING of how many; a second one aborts; the pool's workers end.
"""

from __future__ import annotations

import concurrent.futures as cf
import functools
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis import family_maps, maps
from impactcont.analysis.maps import multi_impact_map, stability_map
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops

OMEGA = np.linspace(0.5, 6.0, 23)
GAP = np.linspace(-1.0, 2.0, 13)
K2 = [[1.0, -1.0], [-1.0, 2.0]]
GRID = {"omega": np.linspace(0.8, 1.8, 41), "b": np.linspace(0.3, 0.8, 11)}


@pytest.fixture(scope="module")
def paper():
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.0,
                               eta=0.1)


@pytest.fixture(scope="module")
def start():
    """The symmetric 1-2 motion the simulator settles on at omega = 1.6, b = 0.5."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=0.5,
                              omega=1.6, stops=Stops(mirror=True))
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))


@pytest.fixture(scope="module")
def banded(start):
    return multi_impact_map(start, ("omega", "b"), grid=GRID, rows_per_task=8)


def _timed_task(log: str, *args):
    """The map's task, its start and end appended to the file `log` (any executor)."""
    t0 = time.monotonic()
    time.sleep(0.4)
    out = maps._real_task(*args)
    with open(log, "a") as f:
        f.write(f"{t0} {time.monotonic()}\n")
    return out


def _most_at_once(log: Path) -> int:
    spans = [tuple(map(float, line.split())) for line in log.read_text().splitlines()]
    return max(sum(1 for a, b in spans if a <= t < b) for t, _ in spans)


def test_a_map_on_a_dask_cluster_runs_as_many_tasks_as_its_workers_threads(paper, tmp_path,
                                                                           monkeypatch):
    distributed = pytest.importorskip("dask.distributed")
    log = tmp_path / "spans"
    with distributed.LocalCluster(n_workers=4, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        # this machine seen as one processor: the cluster has 4 threads whatever it has
        monkeypatch.setattr(maps.os, "cpu_count", lambda: 1)
        monkeypatch.setattr(maps, "_real_task", maps._map_task, raising=False)
        monkeypatch.setattr(maps, "_map_task", functools.partial(_timed_task, str(log)))
        ds = stability_map(paper, [1], OMEGA[:12], GAP, executor=client, omega_block=1)
        monkeypatch.undo()
        assert _most_at_once(log) >= 4
        reference = stability_map(paper, [1], OMEGA[:12], GAP)
        xr.testing.assert_identical(ds.drop_attrs(), reference.drop_attrs())
        runner = maps.MapRunner(maps._StabilityJob(paper, [1], OMEGA, GAP, True), client,
                                None, ic.progress.Reporter("test", False))
        assert runner.workers == 4 and runner.submitted == 8
        cluster.scale(6)
        client.wait_for_workers(6, timeout=30)
        runner._threads = (runner._threads[0], -np.inf)  # read again now, not in 2 s
        assert runner.workers == 6  # workers that join are used
        runner.close()


def test_multi_impact_map_gives_the_same_map_on_every_executor(start, banded):
    assert '"tasks": 6' in banded.attrs["options"]
    pooled = multi_impact_map(start, ("omega", "b"), grid=GRID, rows_per_task=8,
                              executor="process", max_workers=2)
    xr.testing.assert_identical(pooled.drop_attrs(), banded.drop_attrs())
    with cf.ThreadPoolExecutor(2) as pool:  # the compiled sweep releases the GIL
        threaded = multi_impact_map(start, ("omega", "b"), grid=GRID, rows_per_task=8,
                                    executor=pool)
    xr.testing.assert_identical(threaded.drop_attrs(), banded.drop_attrs())
    assert '"executor": "ThreadPoolExecutor"' in threaded.attrs["options"]
    seen = []
    one = multi_impact_map(start, ("omega", "b"), grid=GRID, progress=seen.append)
    assert '"tasks": 1' in one.attrs["options"] and seen[-1].done == seen[-1].total == 451
    # the bands follow the family within themselves; here they find what one sweep finds
    np.testing.assert_array_equal(banded.found.values, one.found.values)


def test_multi_impact_map_refuses_what_it_cannot_run(start):
    with pytest.raises(ParameterError, match=r"executor must be .*tcp://localhost:8786"):
        multi_impact_map(start, ("omega", "b"), grid=GRID, executor="localhost:8786")
    with pytest.raises(ParameterError, match=r"memory_limit must be a finite number > 0"):
        multi_impact_map(start, ("omega", "b"), grid=GRID, memory_limit=0)
    with pytest.raises(ParameterError, match="rows_per_task must be an integer >= 1; got 0"):
        multi_impact_map(start, ("omega", "b"), grid=GRID, rows_per_task=0)


def test_an_address_that_answers_without_dask_is_named(paper, monkeypatch):
    """A scheduler address whose server answers, but not in dask's protocol (the handshake
    raises ValueError, not OSError: seen with a proxy listening on the port), is refused
    as the executor, naming the address and what went wrong."""
    import dask.distributed

    def not_dask(address, **kwargs):
        raise ValueError("Maximum allowed dimension exceeded")

    monkeypatch.setattr(dask.distributed, "Client", not_dask)
    with pytest.raises(ParameterError, match=r"executor='tcp://10\.0\.0\.5:8786': no dask "
                       r"scheduler answers at this address \(ValueError: Maximum"):
        stability_map(paper, 1, omega=OMEGA[:3], b=GAP[:3], executor="tcp://10.0.0.5:8786")


def test_a_machine_the_closed_form_cannot_map_is_refused_before_the_executor_opens(
        monkeypatch):
    """The N-1 map refuses a machine outside eq. (12)-(16) at once, not in its first task
    after a cluster was reached: no client is made."""
    import dask.distributed

    clients = []
    monkeypatch.setattr(dask.distributed, "Client", lambda *a, **k: clients.append(a))
    damper = ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                                 R=0.0, b=0.3, omega=2.3, eta=0.3,
                                 stops=Stops(mass=2, relative_to=1, mirror=True))
    with pytest.raises(ParameterError, match=r"the N-1 stability map: the closed form"):
        stability_map(damper, [1, 2], omega=OMEGA, b=GAP, executor="tcp://127.0.0.1:9")
    assert clients == []


def _interrupted_after(k: int, real, *args):
    """The task; the k-th call raises KeyboardInterrupt (as Ctrl-C in a serial map)."""
    _interrupted_after.calls += 1
    if _interrupted_after.calls == k:
        raise KeyboardInterrupt
    return real(*args)


def test_ctrl_c_during_a_stability_map_returns_the_points_computed(paper, monkeypatch,
                                                                   caplog):
    full = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=5)
    _interrupted_after.calls = 0
    monkeypatch.setattr(maps, "_map_task",
                        functools.partial(_interrupted_after, 4, maps._map_task))
    with caplog.at_level("WARNING"):
        ds = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=5)
    assert ds.attrs["interrupted"] == 1
    computed = ds["computed"]
    assert int(computed.sum()) == ds.attrs["points_computed"] == 3 * 5 * 13  # 3 tasks
    assert "195 of 897 points computed" in caplog.text
    xr.testing.assert_identical(ds.drop_vars("computed").where(computed).drop_attrs(),
                                full.where(computed).drop_attrs())
    assert np.isnan(ds["delta"].where(~computed)).all()
    assert not ds["exists"].where(~computed, False).any()


def test_ctrl_c_during_a_multi_impact_map_returns_the_points_computed(start, banded,
                                                                      monkeypatch, caplog):
    _interrupted_after.calls = 0
    monkeypatch.setattr(family_maps, "_band_task",
                        functools.partial(_interrupted_after, 3, family_maps._band_task))
    with caplog.at_level("WARNING"):
        ds = multi_impact_map(start, ("omega", "b"), grid=GRID, rows_per_task=8)
    computed = ds["computed"]
    assert ds.attrs["interrupted"] == 1 and int(computed.sum()) == 2 * 8 * 11
    assert "176 of 451 points computed" in caplog.text
    xr.testing.assert_identical(ds.drop_vars("computed").where(computed).drop_attrs(),
                                banded.where(computed).drop_attrs())
    assert not ds["found"].where(~computed, False).any()


def _signals(count: int, real, *args):
    """The task; the second call sends `count` SIGINTs to this process first."""
    _signals.calls += 1
    if _signals.calls == 2:
        for _ in range(count):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
    return real(*args)


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler, also in a runner started in the background by a shell
    without job control (SIGINT ignored there)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("count", [1, 2])
def test_one_ctrl_c_keeps_the_map_and_a_second_aborts(paper, monkeypatch, python_sigint,
                                                      count):
    _signals.calls = 0
    monkeypatch.setattr(maps, "_map_task", functools.partial(_signals, count, maps._map_task))
    if count == 2:
        with pytest.raises(KeyboardInterrupt):
            stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=5)
        return
    ds = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=5)
    # the Ctrl-C came during the second task: it finishes, the map stops after it
    assert ds.attrs["interrupted"] == 1 and ds.attrs["points_computed"] == 2 * 5 * 13
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


# A runner started in the background by a shell without job control ignores SIGINT, and
# its children inherit that: the child puts Python's own handler back first.
_CHILD = textwrap.dedent("""
    import signal
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import logging, multiprocessing, time, numpy as np, impactcont as ic
    from impactcont.analysis import maps
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              R=0.6, b=0.5, omega=1.0, eta=0.1)
    real = maps._map_task

    def slow(*args):  # 120 tasks of 0.2 s on 2 workers: the map lasts 12 s
        time.sleep(0.2)
        return real(*args)

    maps._map_task = slow  # the pool's forked workers have it too

    def started(record):
        if not started.told:
            started.told = True
            print("STARTED", flush=True)
    started.told = False
    ds = maps.stability_map(osc, [1, 2, 3], np.linspace(0.5, 6.0, 40),
                            np.linspace(-1.0, 2.0, 13), executor="process", max_workers=2,
                            omega_block=1, progress=started)
    print("RESULT", ds.attrs.get("interrupted"), ds.attrs.get("points_computed"),
          ds["computed"].size, len(multiprocessing.active_children()), flush=True)
""")


def test_ctrl_c_during_a_process_map_returns_and_ends_the_workers():
    child = subprocess.Popen([sys.executable, "-c", _CHILD], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "STARTED"
        t0 = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=15)
    finally:
        child.kill()
    assert time.monotonic() - t0 < 15
    assert child.returncode == 0, err
    words = out.split()
    assert words[:2] == ["RESULT", "1"], out + err
    assert 0 < int(words[2]) < int(words[3]) == 3 * 40 * 13
    assert words[4] == "0"  # the pool's workers ended with the map
    assert "points computed" in err and "Ctrl-C again to abort" in err
    assert "KeyboardInterrupt" not in err  # the workers ignore it; the parent took it

"""Maps of (N, omega, b): the batched closed form against the per-motion one; executors.

Maps in bounded memory: peak memory, memory_limit, temporary files, dead pool workers.

Peak memory is measured in a child interpreter (Linux with glibc: ``VmHWM`` of /proc,
reset between maps through /proc/self/clear_refs, the memory freed by the map before given
back by malloc_trim) above its memory right before each map, the NetCDF library and dask
already imported.
"""

from __future__ import annotations

import concurrent.futures as cf
import functools
import json
import math
import multiprocessing
import os
import platform
import re
import signal
import subprocess
import sys
import textwrap
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis import maps
from impactcont.analysis.maps import stability_map

matplotlib.use("Agg")


OMEGA = np.linspace(0.5, 6.0, 23)


GAP = np.linspace(-1.0, 2.0, 13)


@pytest.fixture(scope="module")
def paper():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.5, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def serial_map(paper):
    return stability_map(paper, [1, 2, 3], OMEGA, GAP)


def test_map_agrees_with_every_single_motion(paper, serial_map):
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(60):
        k, i, j = rng.integers(3), rng.integers(OMEGA.size), rng.integers(GAP.size)
        cell = serial_map.isel(N=k, omega=i, b=j)
        orbits = ic.periodic_orbits(paper.replace(omega=float(OMEGA[i]), b=float(GAP[j])),
                                    int(cell.N))
        assert bool(cell.exists) == bool(orbits)
        assert int(cell.n_physical) == sum(o.physical for o in orbits)
        assert int(cell.n_stable) == sum(o.physical and o.stable for o in orbits)
        for o in orbits:
            r = cell.sel(root=o.root)
            assert math.remainder(float(r.delta) - o.delta, 2 * math.pi) == pytest.approx(
                0, abs=1e-10)
            assert float(r.impact_velocity) == pytest.approx(o.impact_velocity, abs=1e-10)
            if math.isfinite(o.gap_min):
                assert float(r.gap_min) == pytest.approx(o.gap_min, abs=1e-10)
            else:
                assert not math.isfinite(float(r.gap_min))
            assert float(r.spectral_radius) == pytest.approx(o.spectral_radius, rel=1e-8)
            assert bool(r.physical) == o.physical and bool(r.stable) == o.stable
            compared += 1
    assert compared > 20


def test_process_pool_and_any_executor_give_the_same_map(paper, serial_map):
    pooled = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor="process", max_workers=2)
    xr.testing.assert_identical(pooled.drop_attrs(), serial_map.drop_attrs())
    with cf.ThreadPoolExecutor(2) as pool:
        threaded = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor=pool, omega_block=5)
    xr.testing.assert_identical(threaded.drop_attrs(), serial_map.drop_attrs())
    assert threaded.attrs["options"].count("ThreadPoolExecutor") == 1


def test_dask_distributed_local_cluster(paper, serial_map):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        with_client = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor=client)
        with_executor = stability_map(paper, [1, 2, 3], OMEGA, GAP,
                                      executor=client.get_executor())
    xr.testing.assert_identical(with_client.drop_attrs(), serial_map.drop_attrs())
    xr.testing.assert_identical(with_executor.drop_attrs(), serial_map.drop_attrs())
    assert '"executor": "dask.distributed"' in with_client.attrs["options"]


def test_two_parameter_figure(paper, serial_map, tmp_path):
    from impactcont.analysis.curves import curve
    from impactcont.plots.maps import region_codes, two_parameter_figure

    codes = region_codes(serial_map, 1)
    assert set(np.unique(codes.values)) <= {0, 1, 2, 3}
    assert ((codes == 0) == ~serial_map.exists.sel(N=1)).all()
    zv = curve(paper, 1, "ZV", start={"omega": 1.3012, "b": 0.4},
               bounds={"omega": (0.5, 6.0), "b": (-1.0, 2.0)}, detect_codim2_points=False)
    fig = two_parameter_figure(serial_map, [zv])
    path = tmp_path / "map.png"
    fig.savefig(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert "ZV" in texts


def test_results_are_bit_identical_for_every_block_size_and_executor(paper, serial_map):
    for block, executor in ((1, None), (5, None), (7, "process"), (23, "process")):
        other = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=block, executor=executor,
                              max_workers=2)
        xr.testing.assert_identical(other.drop_attrs(), serial_map.drop_attrs())


def test_a_map_written_to_disk_opens_lazily_and_equals_the_in_memory_one(paper, serial_map,
                                                                       tmp_path):
    pytest.importorskip("dask")
    lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, out=tmp_path / "map.nc", omega_block=4)
    assert hasattr(lazy.n_stable.data, "dask")  # nothing read yet
    xr.testing.assert_identical(lazy.load().drop_attrs(), serial_map.drop_attrs())
    pooled = stability_map(paper, [1, 2, 3], OMEGA, GAP, out=tmp_path / "pooled.nc",
                           executor="process", max_workers=2, omega_block=6)
    xr.testing.assert_identical(pooled.load().drop_attrs(), serial_map.drop_attrs())


def test_a_map_larger_than_the_memory_limit_goes_to_a_file(paper, serial_map, caplog):
    pytest.importorskip("dask")
    with caplog.at_level("WARNING", logger="impactcont.analysis"):
        lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, memory_limit=1e4)
    assert "more than memory_limit" in caplog.text
    path = lazy.encoding["source"]
    xr.testing.assert_identical(lazy.load().drop_attrs(), serial_map.drop_attrs())
    lazy.close()
    assert not os.path.exists(path)  # a temporary map is removed when it is closed


def test_a_memory_limit_below_what_a_map_on_disk_takes_is_warned_of(paper, tmp_path, caplog):
    # issue 28: a limit below about 35 MB was exceeded without a word
    pytest.importorskip("dask")
    with caplog.at_level("WARNING", logger="impactcont.analysis"):
        stability_map(paper, [1], OMEGA, GAP, memory_limit=1e4).close()
    assert re.search(r"memory_limit = 1e\+04 bytes is below 3\.25\d*e\+07 bytes \(32\.5 MB\), "
                     r"the least a map written to disk takes", caplog.text), caplog.text
    assert "will take more than memory_limit" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING", logger="impactcont.analysis"):
        stability_map(paper, [1], OMEGA, GAP, out=tmp_path / "a.nc").close()  # 1e9
        small = stability_map(paper, [1], OMEGA, GAP, memory_limit=1e6)  # fits in memory
    assert not any(hasattr(v.data, "dask") for v in small.data_vars.values())
    assert "is below" not in caplog.text


def test_map_without_eigenvalues_has_the_same_stability(paper, serial_map):
    quick = stability_map(paper, [1, 2, 3], OMEGA, GAP, spectral_radius=False)
    assert "spectral_radius" not in quick and "critical_multiplier" not in quick
    for key in ("exists", "n_physical", "n_stable", "delta", "gap_min", "stable", "physical"):
        xr.testing.assert_identical(quick[key], serial_map[key])
    rho = serial_map.spectral_radius.values
    decided = np.isfinite(rho) & (np.abs(rho - 1.0) > 1e-9)
    assert np.array_equal(serial_map.stable.values[decided], rho[decided] < 1.0)


# 4 x 250 x 250 = 2.5e5 points: a map of 29.3 MB (117 bytes per point), about 0.6 s
_CHILD = textwrap.dedent(r"""
    import ctypes, gc, json, sys
    import numpy as np
    import dask.array, netCDF4, xarray  # noqa: F401  (in the memory before the maps)
    import impactcont as ic

    def status(key):
        with open("/proc/self/status") as f:
            return next(int(l.split()[1]) * 1024 for l in f if l.startswith(key))

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                              omega=1.0, eta=0.1)
    small = (np.linspace(0.5, 6, 8), np.linspace(-1, 1.5, 8))
    ic.stability_map(osc, [1], *small)  # compiled kernel loaded
    ic.stability_map(osc, [1], *small, memory_limit=1e3).close()  # NetCDF library started
    omega, b = np.linspace(0.5, 6.0, 250), np.linspace(-1.0, 1.5, 250)
    trim = ctypes.CDLL(None).malloc_trim  # glibc: the memory of the map before goes back
    for case in json.loads(sys.argv[1]):
        gc.collect()
        trim(0)
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # VmHWM := VmRSS
        before = status("VmRSS")
        ds = ic.stability_map(osc, [1, 2, 3, 4], omega, b, **case)
        peak = status("VmHWM") - before
        lazy = hasattr(ds.n_stable.data, "dask")
        size = sum(v.dtype.itemsize * v.size for v in ds.variables.values())
        print(json.dumps({"peak": peak, "size": size, "lazy": lazy}), flush=True)
        ds.close()
        del ds
""")


@pytest.fixture(scope="module")
def peaks() -> list[dict]:
    """Peak memory of three maps of 29.3 MB: default arguments, memory_limit 37 MB (the map
    fits), 25 MB (it does not)."""
    if not Path("/proc/self/clear_refs").exists() or sys.platform != "linux" \
            or "glibc" not in " ".join(platform.libc_ver()):
        pytest.skip("peak memory is read from Linux's /proc, with glibc's malloc_trim")
    pytest.importorskip("dask")
    cases = [{}, {"memory_limit": 3.7e7}, {"memory_limit": 2.5e7}]
    run = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(cases)],
                         capture_output=True, text=True, timeout=300,
                         env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert run.returncode == 0, run.stderr
    return [json.loads(line) for line in run.stdout.splitlines()]


def test_a_map_in_memory_peaks_at_most_1_5_times_its_size(peaks):
    default = peaks[0]
    assert not default["lazy"]
    assert default["size"] > 2.9e7
    # before: 2.9 times (task results, assembled arrays and their astype copies at once)
    assert default["peak"] <= 1.5 * default["size"]


def test_memory_limit_bounds_the_peak_not_an_estimate(peaks):
    fits, on_disk = peaks[1], peaks[2]
    # 37 MB: the map (29.3 MB) stays in memory, its tasks within the rest (before: the map
    # stayed on a 70-byte-per-motion estimate and peaked at 3 times its size)
    assert not fits["lazy"]
    assert fits["peak"] <= 3.7e7
    # 25 MB: written to a file block by block, the blocks sized to fit with the NetCDF
    # library's own memory
    assert on_disk["lazy"]
    assert on_disk["peak"] <= 2.5e7


def test_long_b_grids_are_split_and_give_the_same_values(paper):
    b = np.linspace(-1.0, 2.0, 2500)  # more points than a task of this small map may hold
    ds = stability_map(paper, [2], [0.9, 2.1], b)
    assert json.loads(ds.attrs["options"])["b_block"] < b.size
    whole = maps._map_task(paper.to_json(), 2, np.array([0.9, 2.1]), b, True)
    for key in ("exists", "delta", "impact_velocity", "gap_min", "spectral_radius",
                "critical_multiplier", "physical", "stable"):
        np.testing.assert_array_equal(ds[key].values[0], whole[key])
    np.testing.assert_array_equal(ds.n_physical.values[0], whole["physical"].sum(axis=-1))


# -- temporary files ------------------------------------------------------------------------
def test_the_temporary_file_of_a_map_goes_when_the_map_is_closed(paper, caplog):
    pytest.importorskip("dask")
    serial = stability_map(paper, [1, 2, 3], OMEGA, GAP)
    with caplog.at_level("WARNING", logger="impactcont.analysis"):
        lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, memory_limit=1e4)
    path = Path(lazy.encoding["source"])
    assert str(path) in caplog.text and path.is_file()
    xr.testing.assert_identical(lazy.load().drop_attrs(), serial.drop_attrs())
    lazy.close()
    assert not path.exists()
    with stability_map(paper, [1], OMEGA, GAP, memory_limit=1e4) as lazy:
        path = Path(lazy.encoding["source"])
        assert path.is_file()
    assert not path.exists()


_LEFT_OPEN = textwrap.dedent("""
    import os, sys
    import numpy as np
    import impactcont as ic
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                              omega=1.0, eta=0.1)
    ds = ic.stability_map(osc, [1], np.linspace(0.5, 6, 8), np.linspace(-1, 1.5, 8),
                          memory_limit=1e3)
    print(ds.encoding["source"], flush=True)
    if sys.argv[1] == "killed":
        os.kill(os.getpid(), 9)
""")


def test_temporary_maps_go_at_exit_and_those_of_killed_processes_with_the_next_map(paper):
    pytest.importorskip("dask")
    left, killed = (subprocess.Popen([sys.executable, "-c", _LEFT_OPEN, how], text=True,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE)
                    for how in ("exit", "killed"))  # both at once
    out, err = left.communicate(timeout=120)
    assert left.returncode == 0, err
    assert not Path(out.strip()).exists()  # never closed: removed at exit
    out, err = killed.communicate(timeout=120)
    assert killed.returncode == -signal.SIGKILL, err
    path = Path(out.strip())
    assert path.is_file()  # nothing runs in a killed process...
    stability_map(paper, [1], OMEGA, GAP, memory_limit=1e3).close()
    assert not path.exists()  # ...the next temporary map removes its file


# -- a worker of the process pool dies ------------------------------------------------------
def _dies_once(marker: str, *args):
    """The map's task, but the first worker to run it is killed (as by the OOM killer)."""
    try:
        os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return maps.__dict__["_real_task"](*args)
    os.kill(os.getpid(), signal.SIGKILL)


def _always_dies(*args):
    os.kill(os.getpid(), signal.SIGKILL)


def _fork_pool() -> cf.ProcessPoolExecutor:
    # forked workers inherit the monkeypatched task
    return cf.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork"))


@pytest.mark.parametrize("to_file", [False, True])
def test_the_tasks_of_a_killed_worker_are_run_again(paper, monkeypatch, tmp_path, caplog,
                                                       to_file):
    if to_file:
        pytest.importorskip("dask")
    serial = stability_map(paper, [1, 2, 3], OMEGA, GAP)
    monkeypatch.setattr(maps, "_real_task", maps._map_task, raising=False)
    monkeypatch.setattr(maps, "_map_task", functools.partial(_dies_once,
                                                             str(tmp_path / "died")))
    out = tmp_path / "map.nc" if to_file else None
    with _fork_pool() as pool, caplog.at_level("WARNING", logger="impactcont.analysis"):
        retried = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor=pool, omega_block=4,
                                out=out)
    assert (tmp_path / "died").exists()
    assert "run again in a new pool" in caplog.text
    xr.testing.assert_identical(retried.load().drop_attrs(), serial.drop_attrs())
    retried.close()


@pytest.mark.parametrize("to_file", [False, True])
def test_a_task_that_kills_its_worker_every_time_ends_the_map_naming_it(paper, monkeypatch,
                                                                   tmp_path, to_file):
    if to_file:
        pytest.importorskip("dask")
    monkeypatch.setattr(maps, "_map_task", _always_dies)
    out = tmp_path / "map.nc"
    with _fork_pool() as pool, pytest.raises(BrokenProcessPool) as error:
        stability_map(paper, [1, 2], OMEGA, GAP, executor=pool, omega_block=4,
                      out=out if to_file else None)
    message = str(error.value)
    assert ("and again each of the 2 times the task was run again alone in a new process "
            "pool") in message
    assert re.search(r"the task N = [12], omega\[\d+:\d+\] in \[[0-9., ]+\], "
                     r"b\[0:13\] in \[-1, 2\]", message), message
    assert not out.exists() and not list(tmp_path.iterdir())  # no partial file left


def test_a_map_written_block_by_block_loads_with_its_schema_checked(paper, tmp_path):
    pytest.importorskip("dask")
    serial = stability_map(paper, [1, 2, 3], OMEGA, GAP, spectral_radius=False)
    with stability_map(paper, [1, 2, 3], OMEGA, GAP, spectral_radius=False,
                       out=tmp_path / "map.nc", omega_block=5) as lazy:
        assert hasattr(lazy.n_stable.data, "dask")
    loaded = ic.load(tmp_path / "map.nc")  # validate=True: the schema of a map
    xr.testing.assert_identical(loaded.drop_attrs(), serial.drop_attrs())


# -- Ctrl-C on a map written to a file (issue 31) -------------------------------------------
def _interrupted_after(k: int, real, *args):
    """The task; the k-th call raises KeyboardInterrupt (as Ctrl-C in a serial map)."""
    _interrupted_after.calls += 1
    if _interrupted_after.calls == k:
        raise KeyboardInterrupt
    return real(*args)


def _check_kept(lazy: xr.Dataset, full: xr.Dataset, points: int) -> None:
    """`lazy`, an interrupted map read from its file, is `full` where computed and not
    computed elsewhere, marked as the in-memory map is."""
    assert hasattr(lazy.n_stable.data, "dask")
    ds = lazy.load()
    assert ds.attrs["interrupted"] == 1 and ds.attrs["points_computed"] == points
    computed = ds["computed"]
    assert computed.dtype == bool and computed.dims == ("N", "omega", "b")
    assert int(computed.sum()) == points
    xr.testing.assert_identical(ds.drop_vars("computed").where(computed).drop_attrs(),
                                full.where(computed).drop_attrs())
    assert np.isnan(ds["delta"].where(~computed)).all()
    assert not ds["exists"].where(~computed, False).any()
    assert int(ds["n_physical"].where(~computed, 0).sum()) == 0


def test_ctrl_c_keeps_a_map_written_to_a_file_whole_and_marked(paper, serial_map, monkeypatch,
                                                               tmp_path, caplog):
    pytest.importorskip("dask")
    _interrupted_after.calls = 0
    monkeypatch.setattr(maps, "_map_task",
                        functools.partial(_interrupted_after, 4, maps._map_task))
    target = tmp_path / "map.nc"
    with caplog.at_level("WARNING"):
        lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=5, out=target)
    assert "195 of 897 points computed" in caplog.text  # 3 tasks of 5 x 13
    assert f"the interrupted map is kept in {target}" in caplog.text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.nc"]  # no temporary left
    _check_kept(lazy, serial_map, 3 * 5 * 13)
    lazy.close()
    loaded = ic.load(target)  # the schema of a map, with its variable 'computed'
    assert loaded.attrs["interrupted"] == 1 and int(loaded["computed"].sum()) == 195
    plain = xr.open_dataset(target)  # any reader sees the same marks
    assert plain.attrs["interrupted"] == 1 and int(plain["computed"].sum()) == 195
    plain.close()


def test_ctrl_c_keeps_a_map_too_large_for_memory_in_its_temporary_file(paper, serial_map,
                                                                       monkeypatch):
    pytest.importorskip("dask")
    _interrupted_after.calls = 0
    monkeypatch.setattr(maps, "_map_task",
                        functools.partial(_interrupted_after, 3, maps._map_task))
    lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=5, memory_limit=1e4)
    path = Path(lazy.encoding["source"])
    assert path.is_file()
    _check_kept(lazy, serial_map, 2 * 5 * 13)
    lazy.close()
    assert not path.exists()  # a temporary map goes when closed, interrupted or not


def test_a_second_ctrl_c_abandons_a_map_written_to_a_file(paper, monkeypatch, tmp_path):
    pytest.importorskip("dask")
    _interrupted_after.calls = 0
    monkeypatch.setattr(maps, "_map_task",
                        functools.partial(_interrupted_after, 2, maps._map_task))
    # as after a second Ctrl-C (runner.aborted): the map is not kept (the blocks of every map
    # written to a file come through map_runner.written_blocks)
    from impactcont.analysis import map_runner

    monkeypatch.setattr(map_runner, "keep_interrupted", lambda runner, total: False)
    with pytest.raises(KeyboardInterrupt):
        stability_map(paper, [1, 2], OMEGA, GAP, omega_block=5, out=tmp_path / "map.nc")
    assert not list(tmp_path.iterdir())  # nothing kept, no temporary left


# -- one entry, one set of checks for every map (issue 29, item 1) --------------------------
@pytest.mark.parametrize(("kwargs", "match"), [
    ({"max_workers": 0}, r"max_workers must be an integer >= 1 \(or None\); got 0"),
    ({"memory_limit": math.inf}, r"memory_limit must be a finite number > 0; got inf"),
    ({"memory_limit": True}, r"memory_limit must be a finite number > 0; got True"),
    ({"executor": "localhost:8786"}, r"executor"),
    ({"parameters": ("k2", "k2"), "grid": {"k2": [1.0, 2.0]}},
     r"parameters must be two different parameters; got \('k2', 'k2'\)"),
    ({"parameters": ("k2", "b"), "grid": {"k2": [1.0, -3.0], "b": [0.5]}},
     r"grid\['k2'\] must be strictly increasing"),
    ({"parameters": ("k2", "b"), "grid": {"k2": [-3.0, -2.0], "b": [0.5]}},
     r"grid\['k2'\]: the oscillator cannot take k2 = -3.0 \(2 of the values"),
])
def test_the_map_of_an_oscillator_and_of_a_motion_refuse_alike(paper, kwargs, match):
    """The N-1 map of an oscillator and the family map of a motion take their parameters,
    grids and run options through one check: the same refusal, naming the argument."""
    motion = next(o for o in ic.periodic_orbits(paper, 1) if o.physical)
    kwargs = {"parameters": ("omega", "b"), "grid": {"omega": [1.0, 1.1], "b": [0.5]},
              **kwargs}
    for start in (paper, motion):
        with pytest.raises(ic.ParameterError, match=match):
            stability_map(start, **kwargs)
    with pytest.raises(ic.ParameterError, match=match):
        maps.multi_impact_map(motion, **kwargs)


# -- the family of an N-1 motion: by the closed form, not by shooting (issue 29) -------------
@pytest.mark.parametrize(("parameters", "grid"), [
    (("omega", "b"), {"omega": np.linspace(0.9, 1.3, 9), "b": np.linspace(0.1, 0.9, 5)}),
    (("R", "omega"), {"R": [0.5, 0.6, 0.7], "omega": [1.0, 1.03, 1.06]}),
    (("eta", "R"), {"eta": [0.08, 0.1, 0.12], "R": [0.55, 0.6, 0.65]}),
])
def test_the_family_of_an_n1_motion_is_mapped_by_the_closed_form(paper, parameters, grid,
                                                                  caplog):
    """A map whose start is an N-1 motion of periodic_orbits is the closed form's map of its
    root of eq. (15) (the options and an INFO record say so), and equals the shooting map
    of the same family where both found it. Tolerance: shooting's Newton stops at tol =
    1e-11 relative to max(1, |u|), so its motion is that close to the exact one times the
    conditioning of the shooting system (1e-14 apart here); the closed form is exact to
    rounding. The spectral radius comes from two different G (eq. 25 in z, and shooting's
    in the state), equal analytically: rtol 1e-7, as their other comparisons."""
    motion = next(o for o in ic.periodic_orbits(paper, 1) if o.physical)
    with caplog.at_level("INFO", logger="impactcont.analysis.maps"):
        closed = stability_map(motion, parameters=parameters, grid=grid)
    assert json.loads(closed.attrs["options"])["evaluator"] == "closed_form"
    assert f"family of root {motion.root:+d} of eq. (15) over {parameters[0]} x " \
           f"{parameters[1]} by the closed form" in caplog.text
    shot = maps.multi_impact_map(motion, parameters, grid, evaluator="shooting")
    assert json.loads(shot.attrs["options"])["evaluator"] == "shooting"
    assert closed.attrs["impactcont_dataset"] == shot.attrs["impactcont_dataset"]
    assert list(closed.data_vars) == list(shot.data_vars)
    for key in ("N", "impacts", "pattern", "parameters", "symmetric", "seed"):
        assert closed.attrs[key] == shot.attrs[key], key
    found = closed["found"].values
    np.testing.assert_array_equal(found, shot["found"].values)
    assert found.sum() >= 9
    assert np.all(closed["newton_iterations"].values[found] == 0)
    assert np.all(shot["newton_iterations"].values[found] >= 0)
    phase = np.angle(np.exp(1j * (closed["delta"].values - shot["delta"].values)))
    np.testing.assert_allclose(phase[found], 0.0, rtol=0, atol=1e-9)
    for key in ("impact_velocity_k", "flight_time_k", "state_k", "gap_min"):
        np.testing.assert_allclose(closed[key].values[found], shot[key].values[found], rtol=0,
                                   atol=1e-9, err_msg=key)
    np.testing.assert_allclose(closed["spectral_radius"].values[found],
                               shot["spectral_radius"].values[found], rtol=1e-7)
    clear = found & (np.abs(closed["spectral_radius"].values - 1.0) > 1e-6)
    np.testing.assert_array_equal(closed["stable"].values[clear], shot["stable"].values[clear])
    for key in ("physical", "contact_checked"):
        np.testing.assert_array_equal(closed[key].values, shot[key].values, err_msg=key)
    for ds in (closed, shot):
        assert np.all(np.isnan(ds["state_k"].values[~found]))


def test_an_n1_family_map_says_why_the_closed_form_does_not_apply(paper):
    """evaluator='closed_form' where the closed form cannot map the family is refused, naming
    why; an unknown evaluator is refused, naming those allowed."""
    motion = next(o for o in ic.periodic_orbits(paper, 1) if o.physical)
    grid = {"omega": [1.0, 1.1], "b": [0.5]}
    with pytest.raises(ic.ParameterError, match=r"evaluator='closed_form': the family cannot be "
                                                r"mapped by the closed form here: checks=False"):
        maps.multi_impact_map(motion, ("omega", "b"), grid, checks=False,
                              evaluator="closed_form")
    with pytest.raises(ic.ParameterError, match=r"take .* GB, more than memory_limit = "
                                                r"1e-05 GB"):
        stability_map(motion, parameters=("omega", "b"), memory_limit=1e4,
                      grid={"omega": np.linspace(1.0, 1.1, 20), "b": np.linspace(0.4, 0.6, 20)},
                      evaluator="closed_form")
    with pytest.raises(ic.ParameterError, match=r"the root [+-]1 of eq. \(15\) does not exist "
                                                r"at the grid point nearest the start"):
        maps.multi_impact_map(motion, ("omega", "b"), {"omega": [1.0], "b": [5.0]},
                              evaluator="closed_form")
    with pytest.raises(ic.ParameterError, match=r"evaluator must be one of \[None, "
                                                r"'closed_form', 'shooting'\].*got 'newton'"):
        maps.multi_impact_map(motion, ("omega", "b"), grid, evaluator="newton")

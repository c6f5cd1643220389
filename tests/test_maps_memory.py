"""Maps in bounded memory: peak memory, memory_limit, temporary files, dead pool workers.

Peak memory is measured in a child interpreter (Linux with glibc: ``VmHWM`` of /proc,
reset between maps through /proc/self/clear_refs, the memory freed by the map before given
back by malloc_trim) above its memory right before each map, the NetCDF library and dask
already imported.
"""

from __future__ import annotations

import concurrent.futures as cf
import functools
import json
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

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis import maps
from impactcont.analysis.maps import stability_map

OMEGA = np.linspace(0.5, 6.0, 23)
GAP = np.linspace(-1.0, 2.0, 13)

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
    with caplog.at_level("WARNING", logger="impactcont.analysis.maps"):
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
def test_the_tasks_of_a_killed_worker_are_retried_once(paper, monkeypatch, tmp_path, caplog,
                                                       to_file):
    if to_file:
        pytest.importorskip("dask")
    serial = stability_map(paper, [1, 2, 3], OMEGA, GAP)
    monkeypatch.setattr(maps, "_real_task", maps._map_task, raising=False)
    monkeypatch.setattr(maps, "_map_task", functools.partial(_dies_once,
                                                             str(tmp_path / "died")))
    out = tmp_path / "map.nc" if to_file else None
    with _fork_pool() as pool, caplog.at_level("WARNING", logger="impactcont.analysis.maps"):
        retried = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor=pool, omega_block=4,
                                out=out)
    assert (tmp_path / "died").exists()
    assert "retried once in a new pool" in caplog.text
    xr.testing.assert_identical(retried.load().drop_attrs(), serial.drop_attrs())
    retried.close()


@pytest.mark.parametrize("to_file", [False, True])
def test_a_task_that_kills_its_worker_twice_ends_the_map_naming_it(paper, monkeypatch,
                                                                   tmp_path, to_file):
    if to_file:
        pytest.importorskip("dask")
    monkeypatch.setattr(maps, "_map_task", _always_dies)
    out = tmp_path / "map.nc"
    with _fork_pool() as pool, pytest.raises(BrokenProcessPool) as error:
        stability_map(paper, [1, 2], OMEGA, GAP, executor=pool, omega_block=4,
                      out=out if to_file else None)
    message = str(error.value)
    assert "again when the task was retried in a new process pool" in message
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

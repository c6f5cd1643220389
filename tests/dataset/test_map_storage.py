"""Temporary map files (:mod:`impactcont.dataset.map_storage`): a fresh name in the temporary
directory, the file opened lazily and removed when the map is closed (or its ``with`` block
ends, or the file cannot be read), those of killed processes removed with the next one."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset import io as dataset_io
from impactcont.dataset import map_storage

pytest.importorskip("dask")

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.6, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def small_map() -> xr.Dataset:
    return ic.stability_map(PAPER, [1, 2], np.linspace(0.9, 1.6, 5), np.linspace(0.4, 0.7, 4))


@pytest.fixture
def tmpdir_(tmp_path, monkeypatch) -> Path:
    """The temporary directory of this test only; the temporary maps it leaves are
    removed after it (and SIGTERM's default action is back)."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    yield tmp_path
    for path in list(map_storage._temporary):
        map_storage.remove_temporary_map(path)


def test_a_temporary_map_file_is_a_fresh_hidden_name_in_the_temporary_directory(tmpdir_):
    first, second = map_storage.temporary_map_file(), map_storage.temporary_map_file()
    assert first != second
    for path in (first, second):
        assert path.parent == tmpdir_
        assert re.fullmatch(rf"\.impactcont-map\.nc\.[A-Za-z0-9]+-{os.getpid()}"
                            r"\.[0-9a-f]{8}\.tmp", path.name), path.name
        assert not path.exists()  # a name only: the map's writer makes the file


def test_the_next_temporary_map_removes_those_of_killed_processes(tmpdir_):
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(gone.stdout)
    stale = tmpdir_ / f".impactcont-map.nc.{dataset_io._HOST}-{pid}.0123abcd.tmp"
    mine = dataset_io.temporary_path(tmpdir_ / "impactcont-map.nc")  # this process: running
    other = tmpdir_ / "impactcont-map.nc"  # not a temporary name
    for path in (stale, mine, other):
        path.write_bytes(b"x")
    map_storage.temporary_map_file()
    assert not stale.exists()
    assert mine.exists() and other.exists()


def test_the_map_is_read_lazily_and_its_file_removed_on_close(tmpdir_, small_map):
    path = map_storage.temporary_map_file()
    ic.save(small_map, path)
    lazy = map_storage.open_temporary_map(path)
    assert path.is_file()
    assert all(hasattr(lazy[name].data, "dask") for name in lazy.data_vars)  # nothing read yet
    xr.testing.assert_identical(lazy.load().drop_attrs(), small_map.drop_attrs())
    assert lazy.attrs["oscillator"] == small_map.attrs["oscillator"]
    lazy.close()
    assert not path.exists()
    assert list(tmpdir_.iterdir()) == []


def test_the_file_goes_at_the_end_of_a_with_block(tmpdir_, small_map):
    path = map_storage.temporary_map_file()
    ic.save(small_map, path)
    with map_storage.open_temporary_map(path) as lazy:
        assert int(lazy["n_stable"].sum()) == int(small_map["n_stable"].sum())
        assert path.is_file()
    assert not path.exists()


def test_a_file_that_cannot_be_read_as_a_map_is_removed_and_the_error_named(tmpdir_):
    path = map_storage.temporary_map_file()
    xr.Dataset({"x": ("i", [1.0])}, attrs={"impactcont_dataset": "map",
                                                      "oscillator": "{not json"}).to_netcdf(path)
    with pytest.raises(ValueError, match=r"attribute 'oscillator' must be the oscillator"):
        map_storage.open_temporary_map(path)
    assert not path.exists()
    missing = map_storage.temporary_map_file()
    with pytest.raises(FileNotFoundError, match="does not exist"):
        map_storage.open_temporary_map(missing)
    assert missing not in map_storage._temporary  # not left to remove at exit


def test_a_map_over_its_memory_limit_goes_to_a_temporary_map(tmpdir_, small_map):
    """stability_map's memory_limit: the map larger than it is this module's file."""
    big = ic.stability_map(PAPER, [1, 2], small_map["omega"].values, small_map["b"].values,
                           memory_limit=1e3)
    path = Path(big.encoding["source"])
    assert path.parent == tmpdir_ and path.name.startswith(".impactcont-map.nc.")
    xr.testing.assert_identical(big.load().drop_attrs(), small_map.drop_attrs())
    big.close()
    assert not path.exists()



# -- a process that ends without atexit (issue 28) ------------------------------------------
_SIGTERMED = """
import sys, time
import numpy as np
import impactcont as ic
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                          omega=1.0, eta=0.1)
ds = ic.stability_map(osc, [1], np.linspace(0.5, 6, 8), np.linspace(-1, 1.5, 8),
                      memory_limit=1e3)
print(ds.encoding["source"], flush=True)
time.sleep(60)
"""


_SIGTERMED_WRITING = """
import time
import numpy as np
import impactcont as ic
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                          omega=1.0, eta=0.1)
told = []
def progress(record):
    if not told:
        told.append(1)
        print("WRITING", flush=True)
        time.sleep(30)
ic.stability_map(osc, [1], np.linspace(0.5, 6, 64), np.linspace(-1, 1.5, 1024),
                 memory_limit=1e3, progress=progress)
"""


@pytest.mark.skipif(os.name != "posix", reason="SIGTERM")
@pytest.mark.parametrize("script", [_SIGTERMED, _SIGTERMED_WRITING], ids=["open", "writing"])
def test_sigterm_removes_the_temporary_map_and_still_ends_the_process(tmp_path, script):
    import signal

    child = subprocess.Popen([sys.executable, "-c", script], text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             env={**os.environ, "TMPDIR": str(tmp_path)})
    try:
        line = child.stdout.readline().strip()
        if line == "WRITING":  # the map is being written: its file and save_blocks' temporary
            assert len(list(tmp_path.iterdir())) == 1, list(tmp_path.iterdir())
            path = next(tmp_path.iterdir())
        else:
            path = Path(line)
        assert path.parent == tmp_path and path.is_file()
        child.send_signal(signal.SIGTERM)
        assert child.wait(30) == -signal.SIGTERM  # ended by SIGTERM, as by default
    finally:
        child.kill()
        child.communicate()
    assert not path.exists()  # before: left until a later temporary map
    assert list(tmp_path.iterdir()) == []


def test_sigterm_is_watched_only_while_a_temporary_map_exists(tmpdir_, small_map):
    import signal

    if signal.getsignal(signal.SIGTERM) != signal.SIG_DFL:
        pytest.skip("SIGTERM has a handler of its own here")
    path = map_storage.temporary_map_file()
    assert signal.getsignal(signal.SIGTERM) is map_storage._on_sigterm
    ic.save(small_map, path)
    map_storage.open_temporary_map(path).close()
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL and not path.exists()
    # a handler of the program's own is left alone
    mine = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    try:
        path = map_storage.temporary_map_file()
        assert signal.getsignal(signal.SIGTERM) is not map_storage._on_sigterm
        map_storage.remove_temporary_map(path)
    finally:
        signal.signal(signal.SIGTERM, mine)


def test_a_failed_temporary_map_is_removed_and_forgotten(tmpdir_, small_map, monkeypatch):
    import signal

    from impactcont.analysis import maps

    def fails(*args, **kwargs):
        raise RuntimeError("a task failed")

    monkeypatch.setattr(maps, "_map_task", fails)
    with pytest.raises(RuntimeError, match="a task failed"):
        ic.stability_map(PAPER, [1], np.linspace(0.5, 6, 8), np.linspace(-1, 1.5, 8),
                         memory_limit=1e3)
    assert list(tmpdir_.iterdir()) == [] and not map_storage._temporary
    assert signal.getsignal(signal.SIGTERM) is not map_storage._on_sigterm


def test_the_first_map_of_a_process_removes_the_temporary_maps_of_killed_ones(tmpdir_,
                                                                             monkeypatch):
    # before: only a later *temporary* map did; a process making maps in memory never did
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    stale = tmpdir_ / f".impactcont-map.nc.{dataset_io._HOST}-{int(gone.stdout)}.0123abcd.tmp"
    stale.write_bytes(b"x")
    monkeypatch.setattr(map_storage, "_swept", False)
    ic.stability_map(PAPER, [1], np.linspace(0.9, 1.6, 3), np.linspace(0.4, 0.7, 3))
    assert not stale.exists()
    stale.write_bytes(b"x")  # once per process: the next map in memory looks no more
    ic.stability_map(PAPER, [1], np.linspace(0.9, 1.6, 3), np.linspace(0.4, 0.7, 3))
    assert stale.exists()

"""Saving and loading (:mod:`impactcont.dataset.io`): NetCDF round trips of branch datasets,
atomic writes (fast, synthetic), robust files old and new.

Files a user can trust (issue 13): Ctrl-C during a save, stale temporary files, every
file the package writes loading back, and files that plain xarray / netCDF4 can read.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import matplotlib
import netCDF4
import numpy as np
import pytest
import xarray as xr

import impactcont
import impactcont as ic
from impactcont import ImpactOscillator
from impactcont.dataset import branch_dataset, load, oscillator_from_dataset, save
from impactcont.dataset import io as dataset_io
from impactcont.scene import run_scene, scene_sections
from tests._scene_data import SMALL_SCENE, write

matplotlib.use("Agg")


from tests._made_up_branch import (  # the fixtures osc and branch: tests/conftest.py
    _columns,
    _special,
)


# -- NetCDF I/O ---------------------------------------------------------------------------------
def test_single_branch_round_trip(branch, tmp_path):
    path = tmp_path / "branch.nc"
    assert save(branch, path) == path
    back = load(path)
    assert isinstance(back, xr.Dataset)
    xr.testing.assert_identical(back, branch)
    assert back["multipliers"].dtype == np.complex128
    np.testing.assert_array_equal(back["multipliers"].values, branch["multipliers"].values)
    assert back["stable"].dtype == bool and back["physical"].dtype == bool
    assert back["special_label"].dtype == np.dtype("<U2")
    assert oscillator_from_dataset(back).to_dict() == oscillator_from_dataset(branch).to_dict()
    # On disk: complex as real and imaginary float parts, booleans as int8 tagged dtype=bool.
    with netCDF4.Dataset(path) as nc:
        assert nc.data_model == "NETCDF4"
        assert "multipliers" not in nc.variables
        real, imag = nc.variables["multipliers_real"], nc.variables["multipliers_imag"]
        assert real.dtype == imag.dtype == np.float64
        assert real.dimensions == ("point", "multiplier")
        assert real.getncattr("long_name") == "real part of Floquet multipliers"
        assert imag.getncattr("impactcont_complex_part") == "imag"
        assert imag.getncattr("impactcont_complex_variable") == "multipliers"
        np.testing.assert_array_equal(real[:] + 1j * imag[:], branch["multipliers"].values)
        assert nc.variables["stable"].dtype == np.int8
        assert nc.variables["stable"].getncattr("dtype") == "bool"


def test_load_closes_file_so_it_can_be_overwritten(branch, tmp_path):
    path = tmp_path / "branch.nc"
    save(branch, path)
    first = load(path)
    changed = branch.assign(gap_min=branch["gap_min"] + 1.0)
    save(changed, path)
    xr.testing.assert_identical(load(path), changed)
    xr.testing.assert_identical(first, branch)


def test_empty_special_round_trip(osc, tmp_path):
    ds = branch_dataset(parameter="b", N=3, oscillator=osc, options={}, columns=_columns(),
                        special_points=[])
    save(ds, tmp_path / "e.nc")
    back = load(tmp_path / "e.nc")
    xr.testing.assert_identical(back, ds)
    assert back["special_label"].dtype == np.dtype("<U2")
    assert back["special_multipliers"].shape == (0, 4)


def test_multi_branch_round_trip(branch, osc, tmp_path):
    cols = _columns(npoints=30)
    other = branch_dataset(parameter="omega", N=2, oscillator=osc.replace(b=0.1),
                           options={"ds": -0.01}, columns=cols,
                           special_points=[_special("PD", 5, cols)])
    path = tmp_path / "many.nc"
    save({"N1": branch, "N2": other}, path)
    tree = load(path)
    assert isinstance(tree, xr.DataTree)
    assert set(tree.children) == {"N1", "N2"}
    xr.testing.assert_identical(tree["N1"].to_dataset(inherit=False), branch)
    xr.testing.assert_identical(tree["N2"].to_dataset(inherit=False), other)
    assert tree["N2"]["multipliers"].dtype == np.complex128
    assert tree["N2"]["physical"].dtype == bool
    # A DataTree is written as it is and reads back identical.
    save(tree, tmp_path / "tree.nc")
    xr.testing.assert_identical(load(tmp_path / "tree.nc"), tree)
    # A mapping with one branch is still a file of groups.
    save({"only": branch}, tmp_path / "one.nc")
    assert isinstance(load(tmp_path / "one.nc"), xr.DataTree)


def test_groups_named_like_variables_are_fully_loaded(branch, tmp_path):
    # A group "b" and a variable "b" in each group: all data must be in memory after load.
    path = tmp_path / "named.nc"
    save({"b": branch, "omega": branch}, path)
    tree = load(path)
    path.unlink()
    for name in ("b", "omega"):
        ds = tree[name].to_dataset(inherit=False)
        # Checked before any value is read: reading a closed netCDF4 file can crash.
        lazy = [k for k, var in ds.variables.items() if not var._in_memory]
        assert lazy == [], f"group {name}: {lazy} not loaded"
        xr.testing.assert_identical(ds, branch)


def _leftovers(directory):
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


@pytest.mark.parametrize("multi", [False, True])
def test_failed_write_leaves_old_file_and_no_temp(branch, tmp_path, monkeypatch, multi):
    path = tmp_path / "branch.nc"
    save(branch, path)
    before = path.read_bytes()

    def broken(self, target, *args, **kwargs):
        with open(target, "wb") as f:
            f.write(b"\x89HDF half a file")
        raise OSError("disk full")

    cls = xr.DataTree if multi else xr.Dataset
    monkeypatch.setattr(cls, "to_netcdf", broken)
    obj = {"a": branch} if multi else branch
    with pytest.raises(OSError, match="disk full"):
        save(obj, path)
    assert path.read_bytes() == before
    assert _leftovers(tmp_path) == []
    monkeypatch.undo()
    xr.testing.assert_identical(load(path), branch)


def test_failed_replace_removes_temp(branch, tmp_path, monkeypatch):
    def no_replace(src, dst):
        raise PermissionError(f"cannot replace {dst}")

    monkeypatch.setattr(dataset_io.os, "replace", no_replace)
    with pytest.raises(PermissionError):
        save(branch, tmp_path / "new.nc")
    assert list(tmp_path.iterdir()) == []


def test_io_bad_arguments(branch, tmp_path):
    with pytest.raises(TypeError, match=r"obj must be .* got int"):
        save(42, tmp_path / "x.nc")
    with pytest.raises(TypeError, match=r"path must be a str or os\.PathLike; got 123"):
        save(branch, 123)
    with pytest.raises(ValueError, match="not a directory"):
        save(branch, tmp_path)
    with pytest.raises(FileNotFoundError, match="nope"):
        save(branch, tmp_path / "nope" / "x.nc")
    with pytest.raises(ValueError, match=r"branch names .* got 'a/b'"):
        save({"a/b": branch}, tmp_path / "x.nc")
    with pytest.raises(TypeError, match=r"obj\['a'\] must be an xarray.Dataset; got int"):
        save({"a": 1}, tmp_path / "x.nc")
    with pytest.raises(ValueError, match=r"missing variable\(s\) \['state'\]"):
        save(branch.drop_vars("state"), tmp_path / "x.nc")
    assert _leftovers(tmp_path) == [] and not (tmp_path / "x.nc").exists()
    missing = tmp_path / "missing.nc"
    with pytest.raises(FileNotFoundError, match=r"missing\.nc"):
        load(missing)
    garbage = tmp_path / "garbage.nc"
    garbage.write_bytes(b"not a netcdf file")
    with pytest.raises(ValueError, match=r"garbage\.nc"):
        load(garbage)
    other = tmp_path / "other.nc"
    xr.Dataset({"a": ("t", np.arange(3.0))}).to_netcdf(other, engine="netcdf4")
    with pytest.raises(ValueError, match=r"other.nc.*missing attribute"):
        load(other)
    assert os.path.exists(other)


def test_a_bad_encoding_or_schema_is_refused_naming_what_to_do(branch, tmp_path):
    """Before, an encoding entry for a variable the dataset does not have raised a bare
    ``KeyError: 'nonexistent'`` from xarray's writer, and a dataset that fails its schema on
    save did not say that ``validate=False`` writes it (load says so)."""
    with pytest.raises(ValueError, match=r"encoding has an entry for 'nonexistent', which is "
                                         r"not a variable of the dataset; its variables: .*"
                                         r"'state'"):
        save(branch, tmp_path / "x.nc", encoding={"nonexistent": {"zlib": True}})
    with pytest.raises(ValueError, match=r"encoding\['state'\] must be a mapping"):
        save(branch, tmp_path / "x.nc", encoding={"state": True})
    plain = xr.Dataset({"a": ("t", np.arange(3.0))})
    with pytest.raises(ValueError, match=r"missing attribute.*save\(obj, path, "
                                         r"validate=False\) writes it"):
        save(plain, tmp_path / "x.nc")
    assert _leftovers(tmp_path) == [] and not (tmp_path / "x.nc").exists()
    save(branch, tmp_path / "x.nc", encoding={"state": {"zlib": True}})
    assert load(tmp_path / "x.nc")["state"].encoding["zlib"]


# -- robust datasets: element names 1-based; files of before element_indexing ---------------------
def _robust_dataset(attrs: dict) -> xr.Dataset:
    """A robust dataset as the scene's [[robust]] writes it (the attributes readers use)."""
    osc = ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.6,
                           omega=1.0, eta=0.1)
    return xr.Dataset({"epsilon": ((), 0.01), "epsilon0": ((), 0.3), "robust": ((), True)},
                      attrs={"title": "Robust stability of the N=1 motion", "name": "rb",
                             "impactcont_dataset": "robust", "N": 1, "root": -1,
                             "samples": 3, "evaluations": 9, "message": "robustly stable",
                             "oscillator": osc.to_json(), **attrs})


def test_old_robust_file_keeps_the_meaning_of_its_forcing_entries(tmp_path):
    """A file of before element_indexing, written by hand as the old writer did (0-based
    F[i]), reads with the 1-based names of the same masses: its nominal F[0] = 1.0 was mass
    1's forcing, which the 1-based F[1] of the stored oscillator is (F[2] would be 0)."""
    from impactcont.model.parameters import model_parameter

    old = _robust_dataset({
        "vary": json.dumps({"F[0]": [0.95, 1.05], "b": [0.5, 0.7]}),
        "nominal": json.dumps({"F[0]": 1.0, "b": 0.6}),
        "argmax": json.dumps({"0,0": {"F[0]": 1.05, "b": 0.5}, "1,1": {"F[0]": 0.95,
                                                                     "b": 0.7}})})
    path = tmp_path / "old_robust.nc"
    old.to_netcdf(path, engine="netcdf4")  # on disk as before, no element_indexing
    ds = impactcont.load(path)
    assert json.loads(ds.attrs["vary"]) == {"F[1]": [0.95, 1.05], "b": [0.5, 0.7]}
    assert json.loads(ds.attrs["nominal"]) == {"F[1]": 1.0, "b": 0.6}
    assert json.loads(ds.attrs["argmax"]) == {"0,0": {"F[1]": 1.05, "b": 0.5},
                                              "1,1": {"F[1]": 0.95, "b": 0.7}}
    assert ds.attrs["element_indexing"] == "1-based"
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    for name, value in json.loads(ds.attrs["nominal"]).items():
        assert model_parameter(osc, name).value(osc) == value
    # read again after saving: today's file, names unchanged
    impactcont.save(ds, tmp_path / "again.nc")
    again = impactcont.load(tmp_path / "again.nc")
    assert again.attrs["vary"] == ds.attrs["vary"] and again.attrs["argmax"] == ds.attrs["argmax"]


def test_new_robust_file_reads_its_names_as_written(tmp_path):
    from impactcont.dataset.schema import robust_attributes

    attrs = robust_attributes({"F[2]": (-0.1, 0.1), "k2": (0.9, 1.1)}, {"F[2]": 0.0, "k2": 1.0},
                              {(0, 1): {"F[2]": 0.1, "k2": 0.9}})
    impactcont.save(_robust_dataset(attrs), tmp_path / "new.nc")
    ds = impactcont.load(tmp_path / "new.nc")
    for key in ("vary", "nominal", "argmax", "element_indexing"):
        assert ds.attrs[key] == attrs[key]
    assert json.loads(ds.attrs["vary"]) == {"F[2]": [-0.1, 0.1], "k2": [0.9, 1.1]}


@pytest.mark.parametrize(("attrs", "pattern"), [
    ({"vary": json.dumps({"gap": [0.2, 1.0]}), "nominal": "{}"}, r"'vary'.*names \['gap'\]"),
    ({"vary": json.dumps({"x1": [0.2, 1.0]}), "nominal": "{}"}, r"'vary'.*names \['x1'\]"),
    ({"vary": json.dumps({"b": [0.2, 1.0]}), "nominal": "{}", "element_indexing": "0-based"},
     "'element_indexing' must be '1-based'"),
])
def test_robust_file_with_what_robust_cannot_vary_is_refused(tmp_path, attrs, pattern):
    path = tmp_path / "bad.nc"
    _robust_dataset(attrs).to_netcdf(path, engine="netcdf4")
    with pytest.raises(ValueError, match=pattern):
        impactcont.load(path)


ROOT = Path(__file__).resolve().parents[2]


TWO_PARAMETER = (
    '[[curves]]\nname = "sn"\nkind = "SN"\nstart = "br"\n'
    "bounds = { omega = [0.9, 1.6], b = [0.45, 0.7] }\nds_max = 0.1\n"
    '[[maps]]\nname = "m"\nN = 1\nomega_range = [0.9, 1.6]\nomega_points = 8\n'
    "b_range = [0.45, 0.7]\nb_points = 6\n")


def _temporaries(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


# -- Ctrl-C and kill -9 during a save ---------------------------------------------------------
# A tree of compressed random data: about 5 s to write on a 2-core machine (20 MB/s).
# A runner started in the background by a shell without job control ignores SIGINT, and its
# children inherit that: each child script puts Python's own handler back first.
_SAVER = textwrap.dedent("""
    import signal, sys
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import numpy as np, xarray as xr
    import impactcont as ic
    from impactcont.dataset import io
    if sys.argv[3] == "in-process":
        io._FORK_BYTES = float("inf")  # the path of dask-backed data: Ctrl-C is held
    rng = np.random.default_rng(0)
    groups = {}
    for k in range(int(sys.argv[2])):
        ds = xr.Dataset({"a": (("x", "y"), rng.random((1000, 1000))),
                         "m": (("x", "z"), rng.random((1000, 100)) * (1 + 2j))})
        for var in ds.data_vars.values():
            var.encoding = {"zlib": True, "complevel": 9}
        groups[f"g{k}"] = ds
    print("saving", flush=True)
    ic.save(xr.DataTree.from_dict(groups), sys.argv[1], validate=False)
    print("saved", flush=True)
""")


def _start_save(target: Path, groups: int, how: str, **popen) -> subprocess.Popen[str]:
    """Start a large save in a child interpreter; return once it writes its temporary file."""
    proc = subprocess.Popen([sys.executable, "-c", _SAVER, str(target), str(groups), how],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "saving"
    deadline = time.monotonic() + 60
    while not _temporaries(target.parent):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the save never started writing"
        time.sleep(0.02)
    time.sleep(0.3)  # well inside the NetCDF library now
    assert proc.poll() is None, "the save ended before it could be interrupted"
    return proc


def _finish(proc: subprocess.Popen, timeout: float, hung: str) -> tuple[str, str]:
    """``(stdout, stderr)`` of an interrupted child; fail with `hung` if it does not end."""
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(hung)


@pytest.mark.parametrize("target_of_signal", ["process", "process group"])
def test_ctrl_c_ends_a_large_save_promptly(tmp_path: Path, target_of_signal: str) -> None:
    """SIGINT in the middle of writing a large DataTree (once a 10-minute hang)."""
    target = tmp_path / "big.nc"
    target.write_bytes(b"the previous file")
    group = target_of_signal == "process group"  # a terminal's Ctrl-C reaches the whole group
    proc = _start_save(target, 12, "fork", start_new_session=group)
    start = time.monotonic()
    if group:
        os.killpg(proc.pid, signal.SIGINT)
    else:
        proc.send_signal(signal.SIGINT)
    _, err = _finish(proc, 30, "the save hung after Ctrl-C")
    elapsed = time.monotonic() - start
    assert proc.returncode == -signal.SIGINT, err  # ended by KeyboardInterrupt
    assert "KeyboardInterrupt" in err
    assert elapsed < 3.0, f"Ctrl-C took {elapsed:.1f} s to end the save"
    assert target.read_bytes() == b"the previous file"
    assert _temporaries(tmp_path) == []


def test_ctrl_c_is_held_until_an_in_process_write_ends(tmp_path: Path) -> None:
    """Where no child process can write (dask-backed data), the write ends, then Ctrl-C."""
    target = tmp_path / "big.nc"
    target.write_bytes(b"the previous file")
    proc = _start_save(target, 6, "in-process")
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == -signal.SIGINT, err
    assert f"interrupted: finishing the write of {target} first" in err
    assert "saved" not in out
    assert target.read_bytes() == b"the previous file"
    assert _temporaries(tmp_path) == []


_MAP = textwrap.dedent("""
    import signal, sys
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import numpy as np
    import impactcont as ic
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                              omega=1.0, eta=0.1)
    print("saving", flush=True)  # about 2 minutes uninterrupted on 2 cores
    ic.stability_map(osc, [1, 2, 3, 4], np.linspace(0.5, 6, 4000), np.linspace(0, 1, 1000),
                     out=sys.argv[1], omega_block=200)
    print("saved", flush=True)
""")


def test_ctrl_c_stops_a_dask_backed_map_between_chunks(tmp_path: Path) -> None:
    """A map larger than memory is computed as it is written: Ctrl-C stops at the next chunk,
    and the file is finished marked as interrupted (issue 31) before it replaces the target
    (tests/analysis/test_maps.py checks its values)."""
    pytest.importorskip("dask")
    target = tmp_path / "map.nc"
    target.write_bytes(b"the previous file")
    proc = subprocess.Popen([sys.executable, "-c", _MAP, str(target)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "saving"
    deadline = time.monotonic() + 120
    while not _temporaries(tmp_path):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    time.sleep(1.0)
    assert proc.poll() is None
    start = time.monotonic()
    proc.send_signal(signal.SIGINT)
    out, err = _finish(proc, 60, "the map went on after Ctrl-C")
    assert proc.returncode == 0 and "saved" in out, err
    # the task in flight, then the 99 % not computed written as such: 11.5 s at load 8
    assert time.monotonic() - start < 30.0
    assert "the interrupted map is kept in" in err
    with xr.open_dataset(target) as kept:
        assert kept.attrs["interrupted"] == 1
        assert 0 < int(kept["computed"].sum()) == kept.attrs["points_computed"] < 16_000_000
    assert _temporaries(tmp_path) == []


def test_the_next_save_removes_the_temporary_of_a_killed_save(tmp_path: Path) -> None:
    target = tmp_path / "big.nc"
    proc = _start_save(target, 6, "in-process")
    proc.kill()  # kill -9: no cleanup possible
    proc.communicate(timeout=30)
    (left,) = _temporaries(tmp_path)
    assert left.startswith(".big.nc.") and f"-{proc.pid}." in left  # recognisably ours
    ic.save(xr.Dataset({"x": ("t", np.arange(3.0))}, attrs={"impactcont_dataset": "t"}),
            tmp_path / "other.nc")
    assert _temporaries(tmp_path) == []
    assert not target.exists()


def test_only_temporaries_of_gone_writers_on_this_host_are_removed(tmp_path: Path) -> None:
    gone = subprocess.run([sys.executable, "-c", "pass"], check=True)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    host = dataset_io._HOST
    names = {
        f".a.nc.{host}-{dead.pid}.0123abcd.tmp": False,    # writer gone: removed
        f".b.png.{host}-{dead.pid}.89abcdef.tmp": False,   # a figure's, writer gone: removed
        f".c.nc.{host}-{os.getpid()}.0123abcd.tmp": True,  # this process may be writing it
        f".d.nc.{host}-{os.getppid()}.0123abcd.tmp": True,  # writer still running
        f".e.nc.otherhost-{dead.pid}.0123abcd.tmp": True,  # another machine's (shared disk)
        f".f.nc.{host}-{dead.pid}.zz.tmp": True,           # not our pattern
        "notes.tmp": True,
    }
    for name in names:
        (tmp_path / name).write_text("x")
    assert gone.returncode == 0
    removed = dataset_io.remove_stale_temporaries(tmp_path)
    assert sorted(p.name for p in removed) == sorted(n for n, keep in names.items() if not keep)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(n for n, k in names.items() if k)
    tmp = dataset_io.temporary_path(tmp_path / "x.nc")
    assert tmp.parent == tmp_path and dataset_io._TEMPORARY.match(tmp.name)
    assert f"{host}-{os.getpid()}." in tmp.name


# -- every file the package writes loads back ------------------------------------------------
@pytest.fixture(scope="module")
def every_section(tmp_path_factory: pytest.TempPathFactory):
    """A scene run with an entry of every section (curves and maps when present)."""
    directory = tmp_path_factory.mktemp("files")
    text = SMALL_SCENE + (TWO_PARAMETER if "curves" in scene_sections() else "")
    result = run_scene(write(directory, text), output=directory / "out")
    assert result.ok, result.failures
    return result


def test_every_scene_file_loads_back_identical(every_section) -> None:
    expected = {"orbits", "branches", "robust", "simulations"}
    assert expected <= set(every_section.datasets)
    for section, datasets in every_section.datasets.items():
        tree = ic.load(every_section.output_dir / f"{section}.nc")
        assert isinstance(tree, xr.DataTree), section
        assert tree.attrs["impactcont_kind"] == section
        assert not tree.has_data  # the index of the root group is dropped
        assert set(tree.children) == set(datasets)
        for name, ds in datasets.items():
            xr.testing.assert_identical(tree[name].to_dataset(inherit=False), ds)


def test_every_single_dataset_saves_and_loads_back(every_section, tmp_path: Path) -> None:
    for section, datasets in every_section.datasets.items():
        for name, ds in datasets.items():
            back = ic.load(ic.save(ds, tmp_path / f"{section}_{name}.nc"))
            assert isinstance(back, xr.Dataset)
            xr.testing.assert_identical(back, ds)
            complex_vars = [k for k, v in ds.data_vars.items() if v.dtype.kind == "c"]
            assert all(back[k].dtype == np.complex128 for k in complex_vars), section


def test_orbits_without_any_motion_round_trip(tmp_path: Path) -> None:
    text = SMALL_SCENE.split("[[orbits]]")[0] + '[[orbits]]\nname = "far"\nb = 100.0\n'
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    ds = result.datasets["orbits"]["far"]
    assert ds.sizes["orbit"] == 0 and "c^2 + s^2 = 1.74355 < b^2 = 10000" in ds.attrs["note"]
    xr.testing.assert_identical(ic.load(tmp_path / "o" / "orbits.nc")["far"].to_dataset(), ds)


def test_load_still_refuses_what_is_not_ours(tmp_path: Path) -> None:
    other = tmp_path / "other.nc"
    xr.Dataset({"a": ("t", np.arange(3.0))}).to_netcdf(other, engine="netcdf4")
    with pytest.raises(ValueError, match=r"other\.nc.*not a branch dataset"):
        ic.load(other)


# -- plain readers -----------------------------------------------------------------------------
def test_plain_xarray_sees_an_index_and_plain_numbers(every_section) -> None:
    for section, datasets in every_section.datasets.items():
        path = every_section.output_dir / f"{section}.nc"
        with xr.open_dataset(path) as root:  # no auto_complex, no impactcont
            assert root["group_name"].values.tolist() == list(datasets)
            assert set(root["group_kind"].values.tolist()) <= {
                "branch", "orbits", "robust", "simulation", "curve", "map"}
            assert all("long_name" in v.attrs for v in root.data_vars.values())
        with xr.open_datatree(path) as tree:
            for name, ds in datasets.items():
                group = tree[name].to_dataset(inherit=False)
                for key, var in group.data_vars.items():
                    assert var.dtype.kind != "V", f"{section}/{name}/{key} is a void dtype"
                    assert {"long_name", "description"} <= set(var.attrs), key
                for key in [k for k, v in ds.data_vars.items() if v.dtype.kind == "c"]:
                    real, imag = group[f"{key}_real"], group[f"{key}_imag"]
                    assert real.dtype == imag.dtype == np.float64
                    assert real.attrs["impactcont_complex_variable"] == key
                    assert real.attrs["units"] == ds[key].attrs["units"]
                    np.testing.assert_array_equal(np.abs(real + 1j * imag), np.abs(ds[key]))


def test_orbit_groups_carry_omega_and_b_as_scalar_coordinates(every_section) -> None:
    path = every_section.output_dir / "orbits.nc"
    with netCDF4.Dataset(path) as nc:
        group = nc.groups["o1"]
        osc = json.loads(group.getncattr("oscillator"))
        assert float(group["omega"][...]) == osc["omega"] == 1.0
        assert float(group["b"][...]) == osc["b"] == 0.6
        assert abs(float(group["amplitude_squared"][...]) - 1.7435511) < 1e-6
        assert group["omega"].getncattr("long_name") == "forcing frequency"
    for section, name in (("robust", "rb"), ("simulations", "sim")):
        with xr.open_dataset(every_section.output_dir / f"{section}.nc", group=name) as ds:
            assert {"omega", "b"} <= set(ds.coords)
            assert ds["omega"].ndim == 0 and ds["b"].ndim == 0


def test_ncdump_reads_the_files(every_section) -> None:
    ncdump = "/usr/bin/ncdump" if Path("/usr/bin/ncdump").exists() else None
    if ncdump is None:
        pytest.skip("ncdump is not installed (Debian: apt-get install netcdf-bin)")
    path = every_section.output_dir / "orbits.nc"
    index = subprocess.run([ncdump, "-v", "group_name", str(path)], capture_output=True,
                           text=True, check=True).stdout
    assert 'group_name = "o1" ;' in index
    values = subprocess.run([ncdump, "-g", "o1", "-v", "delta,multipliers_real", str(path)],
                            capture_output=True, text=True, check=True).stdout
    assert "delta = " in values and "multipliers_real =" in values


# -- a full disk (issue 28): an OSError naming the target, no temporary, no half file -----------
def _statvfs(free_blocks: int) -> os.statvfs_result:
    """What os.statvfs says of a 1 GB device with `free_blocks` blocks of 4 kB free."""
    return os.statvfs_result((4096, 4096, 262144, free_blocks, free_blocks, 65536, 60000,
                              60000, 0, 255))


@pytest.fixture
def filling_disk(monkeypatch: pytest.MonkeyPatch):
    """os.statvfs of dataset.io reports a device with room, until `fill()` fills it."""
    state = {"free": 1000}

    def statvfs(path):
        return _statvfs(state["free"])

    monkeypatch.setattr(dataset_io.os, "statvfs", statvfs)

    def fill() -> None:
        state["free"] = 0

    return fill


def _failing_write(monkeypatch, cls, error, fill=None):
    """``cls.to_netcdf`` writes half a file, fills the disk (``fill``), then raises ``error``."""
    def broken(self, target, *args, **kwargs):
        with open(target, "wb") as f:
            f.write(b"\x89HDF half a file")
        if fill is not None:
            fill()
        raise error(target)

    monkeypatch.setattr(cls, "to_netcdf", broken)


def _netcdf_error(target):
    return RuntimeError("NetCDF: HDF error")


def _permission_error(target):  # what the NetCDF library says on a 100 % full tmpfs
    return PermissionError(errno.EACCES, "Permission denied", str(target))


@pytest.mark.parametrize("error", [_netcdf_error, _permission_error])
@pytest.mark.parametrize("form", ["single", "groups", "lazy"])
def test_a_disk_filling_up_during_a_save_is_no_space_left_naming_the_path(
        branch, tmp_path, monkeypatch, filling_disk, form, error):
    path = tmp_path / "branch.nc"
    save(branch, path)
    before = path.read_bytes()
    obj = {"single": branch, "groups": {"a": branch}, "lazy": branch.chunk()}[form]
    _failing_write(monkeypatch, xr.DataTree if form == "groups" else xr.Dataset, error,
                   filling_disk)
    with pytest.raises(OSError) as info:
        save(obj, path)
    exc = info.value
    assert type(exc) is OSError and exc.errno == errno.ENOSPC, repr(exc)
    text = str(exc)
    assert f"cannot write {str(path)!r}" in text and "no space left" in text, text
    assert str(tmp_path) in text and ".tmp" not in text, text
    assert path.read_bytes() == before  # the previous file untouched, no half file
    assert _leftovers(tmp_path) == []


def test_a_netcdf_error_with_room_left_is_an_oserror_saying_what_failed(
        branch, tmp_path, monkeypatch, filling_disk):
    _failing_write(monkeypatch, xr.Dataset, _netcdf_error)
    path = tmp_path / "b.nc"
    with pytest.raises(OSError) as info:
        save(branch, path)
    exc, text = info.value, str(info.value)
    assert exc.errno == errno.EIO and f"cannot write {str(path)!r}" in text, text
    assert "NetCDF: HDF error" in text and "no space left" not in text, text
    assert ".tmp" not in text
    assert list(tmp_path.iterdir()) == []


def test_a_permission_error_with_room_left_still_says_permission_denied(
        branch, tmp_path, monkeypatch, filling_disk):
    _failing_write(monkeypatch, xr.Dataset, _permission_error)
    path = tmp_path / "b.nc"
    with pytest.raises(PermissionError) as info:
        save(branch, path)
    text = str(info.value)
    assert info.value.errno == errno.EACCES
    assert f"cannot write {str(path)!r}" in text and "ermission denied" in text, text
    assert f"directory {str(tmp_path)!r}" in text and ".tmp" not in text, text
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_is_refused_before_writing(branch, tmp_path, monkeypatch, filling_disk):
    filling_disk()
    written = []
    monkeypatch.setattr(xr.Dataset, "to_netcdf", lambda *a, **k: written.append(a))
    path = tmp_path / "b.nc"
    with pytest.raises(OSError) as info:
        save(branch, path)
    assert info.value.errno == errno.ENOSPC and written == []
    assert f"cannot write {str(path)!r}" in str(info.value)
    assert "no space left" in str(info.value)
    with pytest.raises(OSError, match="no space left") as info:
        dataset_io.check_output_directory(tmp_path)
    assert info.value.errno == errno.ENOSPC and str(tmp_path) in str(info.value)
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def file_size_limit():
    """Files of this process may not grow past 64 kB while the body runs: the NetCDF library
    fails for real (EFBIG, "NetCDF: HDF error"), as on a full disk."""
    resource = pytest.importorskip("resource")
    if not hasattr(signal, "SIGXFSZ"):
        pytest.skip("no SIGXFSZ here")
    old = resource.getrlimit(resource.RLIMIT_FSIZE)
    if old[1] != resource.RLIM_INFINITY and old[1] < 2**16:
        pytest.skip("the file size limit is already below 64 kB")
    previous = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    @contextlib.contextmanager
    def limited():
        resource.setrlimit(resource.RLIMIT_FSIZE, (2**16, old[1]))
        try:
            yield
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, old)

    try:
        yield limited
    finally:
        signal.signal(signal.SIGXFSZ, previous)


def _held_in(directory: Path) -> list[tuple[str, int]]:
    """The files under `directory` this process holds open (removed ones included) that
    take disk space: ``(path, bytes)``."""
    fds = Path("/proc/self/fd")
    if not fds.is_dir():
        pytest.skip("no /proc/self/fd here to list the open files")
    found = []
    for fd in fds.iterdir():
        try:
            target = os.readlink(fd)
            size = os.stat(fd).st_blocks * 512
        except OSError:
            continue
        if target.startswith(str(directory)) and size:
            found.append((target, size))
    return found


def _big_map():
    values = np.random.default_rng(0).random((40, 1000))
    return xr.Dataset({"x": (("a", "c"), values)}, attrs={"impactcont_dataset": "t"})


@pytest.mark.parametrize("full", [False, True])
def test_a_real_netcdf_failure_in_save_blocks_is_an_oserror_naming_the_path(
        tmp_path, monkeypatch, file_size_limit, full):
    """The file size limit fails the NetCDF library for real; with `full`, os.statvfs says
    the device is full while the temporary file holds its data, and has room once it no
    longer does (as a disk the write filled up)."""
    pytest.importorskip("dask")
    import dask.array as da

    def statvfs(path):
        held = full and any(p.stat().st_size for p in tmp_path.iterdir()
                            if p.name.endswith(".tmp"))
        return _statvfs(0 if held else 1000)

    monkeypatch.setattr(dataset_io.os, "statvfs", statvfs)
    big = _big_map()
    layout = big.copy()
    layout["x"] = (("a", "c"), da.empty((40, 1000), chunks=-1))

    def blocks():
        for i in range(40):
            yield {"a": i}, {"x": big["x"].values[i]}

    path = tmp_path / "map.nc"
    with file_size_limit(), pytest.raises(OSError) as info:
        dataset_io.save_blocks(layout, path, blocks())
    text = str(info.value)
    assert f"cannot write {str(path)!r}" in text and ".tmp" not in text, text
    assert info.value.errno == (errno.ENOSPC if full else errno.EIO), text
    assert ("no space left" in text) == full, text
    assert list(tmp_path.iterdir()) == []
    # the NetCDF library keeps open a file whose close failed: not its disk space
    assert _held_in(tmp_path) == []
    with file_size_limit(), pytest.raises(OSError) as info:  # and a lazy save, for real
        save(big.chunk({"a": 4}), path)
    assert f"cannot write {str(path)!r}" in str(info.value)
    assert info.value.errno == (errno.ENOSPC if full else errno.EIO)
    assert list(tmp_path.iterdir()) == [] and _held_in(tmp_path) == []


def test_atomic_output_names_the_target_on_a_full_disk(tmp_path, filling_disk):
    path = tmp_path / "summary.md"
    with pytest.raises(OSError) as info, dataset_io.atomic_output(path) as tmp:
        filling_disk()
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp))
    text = str(info.value)
    assert info.value.errno == errno.ENOSPC and f"cannot write {str(path)!r}" in text, text
    assert ".tmp" not in text and list(tmp_path.iterdir()) == []


def test_no_file_entry_left_is_no_space_not_a_permission_problem(branch, tmp_path, monkeypatch):
    """A device out of inodes refuses to create the probe with ENOSPC: said as such."""
    real_open = os.open

    def no_inode(path, flags, *args):
        if Path(path).parent == tmp_path and flags & os.O_CREAT:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real_open(path, flags, *args)

    monkeypatch.setattr(dataset_io.os, "open", no_inode)
    path = tmp_path / "b.nc"
    with pytest.raises(OSError) as info:
        save(branch, path)
    text = str(info.value)
    assert info.value.errno == errno.ENOSPC and type(info.value) is OSError
    assert (f"cannot write {str(path)!r}: no space left on the device of directory "
            f"{str(tmp_path)!r} (No space left on device)") in text, text
    assert "permission" not in text and ".tmp" not in text, text


class _FailingClose:
    """A file whose first close fails as HDF5's does on a full disk."""

    def __init__(self) -> None:
        self.closes = 0

    def close(self) -> None:
        self.closes += 1
        if self.closes == 1:
            raise RuntimeError("NetCDF: HDF error")


def test_a_failed_close_keeps_the_error_that_stopped_the_write(tmp_path, filling_disk):
    tmp = tmp_path / ".x.nc.tmp"
    tmp.write_bytes(b"\x89HDF data")
    filling_disk()
    stopped = KeyboardInterrupt()
    nc = _FailingClose()
    dataset_io._close_written(nc, tmp, stopped)  # the caller raises `stopped`, not this
    assert nc.closes == 2 and tmp.read_bytes() == b"\x89HDF data"  # not open: not emptied
    assert getattr(stopped, dataset_io._FULL_NOTE) == "0 bytes free"
    nc = _FailingClose()
    with pytest.raises(RuntimeError, match="HDF error") as info:
        dataset_io._close_written(nc, tmp, None)
    assert nc.closes == 2 and getattr(info.value, dataset_io._FULL_NOTE) == "0 bytes free"

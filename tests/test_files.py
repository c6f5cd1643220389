"""Files a user can trust (issue 13): Ctrl-C during a save, stale temporary files, every
file the package writes loading back, and files that plain xarray / netCDF4 can read."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr
from _scene_data import SMALL_SCENE, write

import impactcont as ic
from impactcont.dataset import io as dataset_io
from impactcont.scene import run_scene, scene_sections

ROOT = Path(__file__).resolve().parents[1]
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
    """A map larger than memory is computed as it is written: Ctrl-C stops at the next chunk."""
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
    assert proc.returncode == -signal.SIGINT and "saved" not in out, err
    assert time.monotonic() - start < 10.0
    assert target.read_bytes() == b"the previous file"
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


def test_orbit_groups_carry_omega_and_b_as_variables(every_section) -> None:
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
            assert {"omega", "b"} <= set(ds.data_vars)


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

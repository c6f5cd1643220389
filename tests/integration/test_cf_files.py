"""Files any reader understands (issue 22): every file the package writes passes the IOOS
``compliance-checker`` for CF 1.10 in every group, reads with plain xarray and netCDF4
(numeric coordinates, no 64-bit integers, a root that says what the file holds), and still
reads back with ``impactcont.load`` as it was written, old files included."""

from __future__ import annotations

import functools
import json
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset import io as dataset_io
from impactcont.dataset import oscillator_from_dataset, point_table, with_parameter_coords
from impactcont.scene import run_scene
from tests._scene_data import SMALL_SCENE, write

TWO_PARAMETER = (
    '[[curves]]\nname = "sn"\nkind = "SN"\nstart = "br"\n'
    "bounds = { omega = [0.9, 1.6], b = [0.45, 0.7] }\nds_max = 0.1\n"
    '[[maps]]\nname = "m"\nN = 1\nomega_range = [0.9, 1.6]\nomega_points = 8\n'
    "b_range = [0.45, 0.7]\nb_points = 6\n")
# compliance-checker 6.1's check of CF 2.7.1 reads a dimension "time" in the first two groups
# of any file of two groups or more (a KeyError where there is none); it checks nothing else.
CHECKER_BUG = "check_invalid_same_named_dimension_across_groups"


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Every kind of file: each scene section, each dataset alone, files of several groups."""
    directory = tmp_path_factory.mktemp("cf")
    result = run_scene(write(directory, SMALL_SCENE + TWO_PARAMETER), output=directory / "out")
    assert result.ok, result.failures
    files = {f"scene {s}": directory / "out" / f"{s}.nc" for s in result.datasets}
    for section, datasets in result.datasets.items():
        name, ds = next(iter(datasets.items()))
        files[f"single {section}"] = ic.save(ds, directory / f"{section}_{name}.nc")
    branch = result.datasets["branches"]["br"]
    osc = oscillator_from_dataset(branch).replace(b=0.0, omega=1.75)
    n1 = ic.continuation(osc, N=1, bounds=(1.6, 1.9), detect=("PD",))
    two = ic.period_doubling_switch(n1, 0, ds_max=0.05)
    files["single N-p branch"] = ic.save(two, directory / "np_branch.nc")
    files["branches"] = ic.save({"N1": n1, "two": two}, directory / "branches.nc")
    files["curves"] = ic.save({"sn": result.datasets["curves"]["sn"]}, directory / "curves.nc")
    files["mixed"] = ic.save({"sn": result.datasets["curves"]["sn"],
                              "o1": result.datasets["orbits"]["o1"]}, directory / "mixed.nc")
    return files


def _group_paths(path: Path) -> list[str]:
    with netCDF4.Dataset(path) as nc:
        out, todo = [], [nc]
        while todo:
            group = todo.pop()
            out.append(group.path)
            todo.extend(group.groups.values())
    return out


def _group_as_file(path: Path, group: str, target: Path) -> Path:
    """The group ``group`` of ``path`` alone in a file, byte for byte its variables and
    attributes (compliance-checker checks the root group of a file only)."""
    with netCDF4.Dataset(path) as nc, netCDF4.Dataset(target, "w") as out:
        src = nc[group] if group != "/" else nc
        for dim in src.dimensions.values():
            out.createDimension(dim.name, len(dim))
        out.setncatts({k: src.getncattr(k) for k in src.ncattrs()})
        for name, var in src.variables.items():
            fill = var.getncattr("_FillValue") if "_FillValue" in var.ncattrs() else None
            new = out.createVariable(name, var.datatype, var.dimensions, fill_value=fill)
            new.setncatts({k: var.getncattr(k) for k in var.ncattrs() if k != "_FillValue"})
            var.set_auto_maskandscale(False)
            new.set_auto_maskandscale(False)
            new[...] = var[...]
    return target


@functools.cache
def _suite():
    from compliance_checker.runner import CheckSuite

    suite = CheckSuite()
    suite.load_all_available_checkers()
    return suite


def _check(path: Path) -> tuple[list[str], dict[str, str]]:
    """``(failed checks of any priority, exceptions raised by checks)`` of cf:1.10."""
    suite = _suite()
    nc = suite.load_dataset(str(path))
    try:  # left open, the file crashes the next netCDF4 open of it
        results, errors = suite.run_all(nc, ["cf:1.10"], skip_checks=[])["cf:1.10"]
    finally:
        nc.close()
    failed = []
    for r in results:
        ok = r.value if isinstance(r.value, bool) else r.value[0] == r.value[1]
        if not ok:
            failed.append(f"{r.name}: {r.msgs}")
    return failed, {name: repr(exc) for name, (exc, _) in errors.items()}


KINDS = ["scene orbits", "scene branches", "scene robust", "scene simulations", "scene curves",
         "scene maps", "single orbits", "single branches", "single robust",
         "single simulations", "single curves", "single maps", "single N-p branch", "branches",
         "curves", "mixed"]


@pytest.mark.parametrize("kind", KINDS)
def test_compliance_checker_passes_every_group(written, kind: str, tmp_path: Path) -> None:
    pytest.importorskip("compliance_checker")
    path = written[kind]
    failed, crashed = _check(path)
    assert failed == [], f"{kind}: the file as it is"
    several = len(_group_paths(path)) > 2
    assert crashed == ({CHECKER_BUG: "KeyError('time')"} if several else {}), kind
    for k, group in enumerate(_group_paths(path)):
        alone = _group_as_file(path, group, tmp_path / f"group{k}.nc")
        failed, crashed = _check(alone)
        assert (failed, crashed) == ([], {}), f"{kind}, group {group}"


def _walk(nc: netCDF4.Dataset):
    yield nc
    for child in nc.groups.values():
        yield from _walk(child)


@pytest.mark.parametrize("kind", KINDS)
def test_netcdf4_sees_cf_numbers_in_every_group(written, kind: str) -> None:
    with netCDF4.Dataset(written[kind]) as nc:
        for group in _walk(nc):
            where = f"{kind}, group {group.path}"
            attrs = {k: group.getncattr(k) for k in group.ncattrs()}
            if group.variables:  # every dataset says where it comes from
                assert {"Conventions", "history", "impactcont_version", "source",
                        "references"} <= set(attrs), where
                assert "Cao" in attrs["references"] and "Shu" in attrs["references"]
            for key, value in attrs.items():
                assert np.asarray(value).dtype.itemsize <= 4 or np.asarray(value).dtype.kind \
                    not in "iu", f"{where}: attribute {key} is {np.asarray(value).dtype}"
            for name, var in group.variables.items():
                kind_ = np.dtype(var.dtype).kind if var.dtype is not str else "U"
                assert not (kind_ in "iu" and np.dtype(var.dtype).itemsize == 8), \
                    f"{where}: {name} is {var.dtype}"
                if var.dimensions == (name,):  # a coordinate variable: numbers, no fill value
                    assert kind_ in "iuf", f"{where}: coordinate {name} is {var.dtype}"
                    assert "_FillValue" not in var.ncattrs(), f"{where}: {name}"
                flag = "flag_values" in var.ncattrs() or (
                    "dtype" in var.ncattrs() and var.getncattr("dtype") == "bool")
                if kind_ == "U" or flag:
                    assert "units" not in var.ncattrs(), f"{where}: {name} has units"


def test_plain_xarray_root_says_what_the_file_holds(written) -> None:
    with xr.open_dataset(written["mixed"]) as root:
        assert json.loads(root.attrs["impactcont_groups"]) == ["sn", "o1"]
        assert "xarray.open_dataset(path, group=NAME)" in root.attrs["comment"]
        assert "impactcont.load(path)" in root.attrs["comment"]
        assert root.attrs["title"] == "Codimension-1 curves and periodic impacting motions"
    with xr.open_dataset(written["curves"]) as root:
        assert root.attrs["title"] == "Codimension-1 curves"
    with xr.open_dataset(written["branches"]) as root:
        assert root.attrs["title"] == "Branches of periodic impacting motions"
        assert root["group_name"].values.tolist() == ["N1", "two"]
    with xr.open_dataset(written["scene orbits"]) as root:  # the scene's own title stays
        assert root.attrs["title"].startswith("Periodic orbits")
        assert json.loads(root.attrs["impactcont_groups"]) == ["o1"]


def test_plain_xarray_plots_a_branch_against_its_parameter(written) -> None:
    with xr.open_dataset(written["branches"], group="two") as two:
        velocity = two["impact_velocity"]
        assert {"omega", "b"} <= set(velocity.coords)  # CF auxiliary coordinates
        assert velocity.coords["omega"].dims == ("point",)
        assert two["component"].dtype.kind == "i"
        assert two["component"].attrs["flag_meanings"] == "x1 x2 v1 v2"
        assert two["special_point"].dtype == np.int32
    with xr.open_dataset(written["scene maps"], group="m") as m:
        assert m["omega"].dtype == np.float64
    with netCDF4.Dataset(written["scene maps"]) as nc:
        assert "_FillValue" not in nc.groups["m"]["omega"].ncattrs()


def test_a_branch_plots_against_its_parameter_and_gives_one_row_per_point(written) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    branch = ic.load(written["single N-p branch"])
    lines = branch.impact_velocity.plot(x="omega")  # its parameters are its coordinates
    np.testing.assert_array_equal(lines[0].get_xdata(), branch["omega"].values)
    plt.close("all")
    assert "omega" in branch.coords and "omega" not in branch.data_vars
    xr.testing.assert_identical(with_parameter_coords(branch), branch)  # already so
    table = point_table(branch)
    assert len(table) == branch.sizes["point"] < len(branch.to_dataframe())
    assert list(table.columns[:2]) == ["omega", "b"]
    assert {"state_x1", "state_v2", "multipliers_0", "state_k_1_v2"} <= set(table.columns)
    np.testing.assert_array_equal(table["state_v2"], branch["state"].sel(component="v2"))
    specials = point_table(branch, "special")
    assert len(specials) == branch.sizes["special"]
    with pytest.raises(ValueError, match=r"dim must be a dimension .* got 'row'"):
        point_table(branch, "row")
    with pytest.raises(ValueError, match="must be a branch or curve dataset"):
        with_parameter_coords(xr.Dataset({"omega": 1.0}))
    with pytest.raises(TypeError, match=r"xarray\.Dataset"):
        point_table(branch["omega"])


@pytest.mark.parametrize("kind", KINDS)
def test_load_gives_back_what_was_saved(written, kind: str, tmp_path: Path) -> None:
    data = ic.load(written[kind])
    again = ic.load(ic.save(data, tmp_path / "again.nc"))
    if isinstance(data, xr.Dataset):
        xr.testing.assert_identical(again, data)
        return
    for node in data.subtree:
        if node.has_data:
            xr.testing.assert_identical(again[node.path].to_dataset(inherit=False),
                                        node.to_dataset(inherit=False))
            assert not set(node.attrs) & {"impactcont_file_attributes"}


def test_files_written_before_the_cf_form_still_load(written, tmp_path: Path) -> None:
    """Before, save wrote each dataset with its complex variables split and nothing else."""
    for kind in ("single N-p branch", "single orbits", "single curves", "single maps"):
        ds = ic.load(written[kind])
        old = tmp_path / f"{kind}.nc"
        dataset_io._split_complex(ds).to_netcdf(old, engine="netcdf4")
        xr.testing.assert_identical(ic.load(old), ds)


def test_a_contradicted_cf_mark_is_refused_by_name(written, tmp_path: Path) -> None:
    path = tmp_path / "branch.nc"
    path.write_bytes(written["single N-p branch"].read_bytes())
    with netCDF4.Dataset(path, "a") as nc:
        nc["component"].setncattr("flag_meanings", "x1 x2 v1")
    with pytest.raises(ValueError, match=r"'component' .* one word of flag_meanings per entry"):
        ic.load(path)

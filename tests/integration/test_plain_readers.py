"""Files plain readers understand (issue 31): labels as text, the parameters as coordinates in
every kind of group, ``delta`` described as it is stored; ``impactcont.load`` still reads the
files written before (integer flags alone, ``omega`` and ``b`` as scalar data variables)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset import io as dataset_io
from impactcont.scene import run_scene
from tests._made_up_branch import _columns, _specials
from tests._scene_data import SMALL_SCENE, write

TWO_PARAMETER = (
    '[[curves]]\nname = "sn"\nkind = "SN"\nstart = "br"\n'
    "bounds = { omega = [0.9, 1.6], b = [0.45, 0.7] }\nds_max = 0.1\n"
    '[[maps]]\nname = "m"\nN = 1\nomega_range = [0.9, 1.6]\nomega_points = 8\n'
    "b_range = [0.45, 0.7]\nb_points = 6\n")
PAPER = dict(M=[[1.0, 0.0], [0.0, 1.0]], K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
             eta=0.1)


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("plain")
    result = run_scene(write(directory, SMALL_SCENE + TWO_PARAMETER), output=directory / "out")
    assert result.ok, result.failures
    return directory / "out"


@pytest.fixture(scope="module")
def loop_in_b() -> xr.Dataset:
    """The N = 1 motions of the paper's example at omega = 1 over b: a closed loop through
    both roots of eq. (15), on which delta goes once round the circle."""
    osc = ic.ImpactOscillator(**PAPER, b=0.6, omega=1.0)
    return ic.continuation(osc, N=1, parameter="b", bounds=(-2.0, 2.0), detect=(),
                           progress=False)


def test_delta_of_an_n1_branch_is_described_as_stored(loop_in_b, tmp_path: Path) -> None:
    delta = loop_in_b["delta"]
    assert np.max(np.abs(delta.values)) > math.pi + 1.0  # continuous, not wrapped
    assert np.max(np.abs(np.diff(delta.values))) < 0.5
    for var in (delta, loop_in_b["special_delta"]):
        assert "(-pi, pi]" not in var.attrs["description"]
    assert "not wrapped" in delta.attrs["description"]
    with xr.open_dataset(ic.save(loop_in_b, tmp_path / "loop.nc")) as plain:
        assert "not wrapped" in plain["delta"].attrs["description"]


def _made_up() -> xr.Dataset:
    """The made-up branch of the schema's tests (special points SN, PD, ...)."""
    from impactcont.dataset import branch_dataset

    osc = ic.ImpactOscillator(**PAPER, b=0.0, omega=1.0)
    cols = _columns()
    return branch_dataset(parameter="omega", N=1, oscillator=osc, options={"ds": 0.03},
                          columns=cols, special_points=_specials(cols))


def _stated_ranges_hold(ds: xr.Dataset, where: str) -> int:
    """Every phase (units rad) whose description states a wrapped range lies in it."""
    checked = 0
    for name, var in ds.variables.items():
        text = str(var.attrs.get("description", ""))
        if var.attrs.get("units") != "rad" or var.dtype.kind != "f":
            continue
        values = np.asarray(var.values, dtype=float)
        values = values[np.isfinite(values)]
        if "(-pi, pi]" in text:
            assert np.all((values > -math.pi) & (values <= math.pi)), f"{where}: {name}"
            checked += 1
        elif "[-pi, pi]" in text:
            assert np.all(np.abs(values) <= math.pi), f"{where}: {name}"
            checked += 1
    return checked


def test_every_kind_states_the_range_of_its_phases(scene) -> None:
    checked = 0
    for path in scene.glob("*.nc"):
        for node in ic.load(path).subtree:
            if node.has_data:
                checked += _stated_ranges_hold(node.to_dataset(inherit=False),
                                               f"{path.name}{node.path}")
    # orbits delta, robust delta, simulation impact_phases, curve delta and codim2_delta, map
    assert checked >= 6


def test_plain_xarray_sees_the_labels(loop_in_b, tmp_path: Path) -> None:
    path = ic.save(loop_in_b, tmp_path / "branch.nc")
    with xr.open_dataset(path) as plain:
        state = plain["state"]
        assert state.coords["component_label"].values.tolist() == ["x1", "x2", "v1", "v2"]
        assert plain["component"].attrs["flag_meanings"] == "x1 x2 v1 v2"  # as before
        table = ic.point_table(plain)
        assert {"state_x1", "state_v2", "multipliers_real_0", "multipliers_imag_0"} \
            <= set(table.columns)
        assert plain["multipliers_real"].attrs["long_name"].startswith("real part of")
        np.testing.assert_array_equal(table["state_v2"],
                                      loop_in_b["state"].sel(component="v2").values)
    assert ic.point_table is ic.dataset.point_table and "point_table" in ic.__all__


def test_special_points_select_by_label_in_plain_xarray(tmp_path: Path) -> None:
    ds = _made_up()
    labels = ds["special_label"].values
    path = ic.save(ds, tmp_path / "branch.nc")
    with xr.open_dataset(path) as plain:
        assert "special_label" in plain.coords
        assert plain["special_omega"].coords["special_label"].dtype.kind in "UO"
        first = str(labels[0])
        chosen = plain.isel(special=plain["special_label"] == first)
        np.testing.assert_array_equal(chosen["special_omega"].values,
                                      ds["special_omega"].values[labels == first])
        by_index = plain.set_xindex("special_label").sel(special_label=first)
        np.testing.assert_array_equal(np.atleast_1d(by_index["special_omega"].values),
                                      ds["special_omega"].values[labels == first])
    back = ic.load(path)
    assert "special_label" in back.data_vars  # in memory as it was given to save
    xr.testing.assert_identical(back, ds)


def test_omega_and_b_are_coordinates_in_every_group(scene) -> None:
    for section in ("orbits", "robust", "simulations", "branches"):
        path = scene / f"{section}.nc"
        loaded = ic.load(path)
        for node in loaded.subtree:
            if not node.has_data:
                continue
            ds = node.to_dataset(inherit=False)
            assert {"omega", "b"} <= set(ds.coords), f"{section}{node.path}"
            with xr.open_dataset(path, group=node.path) as plain:
                assert {"omega", "b"} <= set(plain.coords), f"{section}{node.path}"
                if "g_row" in plain.dims:
                    assert plain["g_row_label"].values.tolist()[-1] == "ddelta"


def _previous_form(ds: xr.Dataset) -> xr.Dataset:
    """What the version before wrote: integer flags without text labels, the labels of the
    special points and the scalar omega, b of orbits as data variables."""
    disk = dataset_io._to_cf(dataset_io._split_complex(ds))
    disk = disk.drop_vars([k for k, v in disk.variables.items()
                           if "impactcont_label_of" in v.attrs])
    labels = [k for k, v in disk.coords.items() if "impactcont_file_coordinate" in v.attrs]
    disk = disk.reset_coords(labels)
    for k in labels:
        del disk[k].attrs["impactcont_file_coordinate"]
    scalars = [k for k in ("omega", "b") if k in disk.coords and disk[k].ndim == 0]
    return disk.reset_coords(scalars)


def test_files_of_the_previous_form_still_load(scene, tmp_path: Path) -> None:
    made_up = _made_up()
    orbits = ic.load(scene / "orbits.nc")
    o1 = orbits[next(n.path for n in orbits.subtree if n.has_data)].to_dataset(inherit=False)
    for name, ds in (("branch", made_up), ("orbits", o1)):
        old = tmp_path / f"{name}.nc"
        _previous_form(ds).to_netcdf(old, engine="netcdf4")
        with xr.open_dataset(old) as plain:
            assert "component_label" not in plain.variables
        xr.testing.assert_identical(ic.load(old), ds)


def test_a_contradicted_label_is_refused_by_name(tmp_path: Path) -> None:
    import netCDF4

    path = ic.save(_made_up(), tmp_path / "branch.nc")
    with netCDF4.Dataset(path, "a") as nc:
        nc["component_label"][0] = "y1"
    with pytest.raises(ValueError, match=r"'component_label' .* labels of 'component'"):
        ic.load(path)

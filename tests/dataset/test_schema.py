"""Branch datasets' schema (:mod:`impactcont.dataset.schema`): dims, coords, dtypes and
attributes; bad inputs named; incomplete datasets refused (fast, synthetic)."""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest
import xarray as xr

import impactcont
from impactcont.dataset import (
    POINT_VARIABLES,
    branch_dataset,
    oscillator_from_dataset,
    schema,
    validate_branch_dataset,
)

matplotlib.use("Agg")


from tests._made_up_branch import (  # the fixtures osc and branch: tests/conftest.py
    NPOINTS,
    _columns,
    _specials,
)


# -- schema -------------------------------------------------------------------------------------
def test_schema_dims_coords_and_dtypes(branch):
    assert dict(branch.sizes) == {"point": NPOINTS, "multiplier": 4, "component": 4, "special": 3}
    assert branch["point"].dtype == np.int64
    np.testing.assert_array_equal(branch["point"].values, np.arange(NPOINTS))
    assert branch["component"].values.tolist() == ["x1", "x2", "v1", "v2"]
    # the points are labelled by the parameters (coordinates on point: plots take x="omega")
    assert set(branch.coords) == {"point", "component", "omega", "b"}
    assert branch["impact_velocity"].coords["omega"].dims == ("point",)
    for name in ("omega", "b", "delta", "impact_velocity", "gap_min", "spectral_radius",
                 "arclength"):
        assert branch[name].dims == ("point",)
        assert branch[name].dtype == np.float64
    assert branch["stable"].dtype == bool and branch["physical"].dtype == bool
    assert branch["multipliers"].dims == ("point", "multiplier")
    assert branch["multipliers"].dtype == np.complex128
    assert branch["state"].dims == ("point", "component")
    assert branch["special_label"].dims == ("special",)
    assert branch["special_label"].dtype == np.dtype("<U2")
    assert branch["special_label"].values.tolist() == ["NS", "GR", "ZV"]
    assert branch["special_status"].values.tolist() == ["located", "bracketed", "located"]
    assert branch["special_point"].dtype == np.int64
    assert branch["special_multipliers"].dims == ("special", "multiplier")
    assert branch["special_multipliers"].dtype == np.complex128
    for name in ("omega", "b", "delta", "bracket_lo", "bracket_hi", "precision"):
        assert branch[f"special_{name}"].dtype == np.float64


@pytest.mark.parametrize("parameter", ["omega", "R"])
def test_the_dataset_is_what_xarrays_own_constructor_builds(osc, parameter):
    """branch_dataset builds its dataset at once (schema._assembled): the same dataset as
    ``xr.Dataset(data_vars, coords=coords).set_coords(parameters)`` of its variables, in
    their order, with the same default indexes (point, component), dims and attributes."""
    cols = _columns()
    if parameter == "R":
        cols["R"] = np.linspace(0.5, 0.9, NPOINTS)
    ds = branch_dataset(parameter=parameter, N=1, oscillator=osc, options={}, columns=cols,
                        special_points=_specials(cols) if parameter == "omega" else [])
    indexed = ["point", "component"]
    general = xr.Dataset(
        {k: (v.dims, v.values, v.attrs) for k, v in ds.variables.items() if k not in indexed},
        coords={k: (k, ds[k].values, ds[k].attrs) for k in indexed}, attrs=ds.attrs,
    ).set_coords(["omega", "b", parameter])
    xr.testing.assert_identical(ds, general)
    assert list(ds.variables) == list(general.variables)
    assert list(ds.dims) == list(general.dims)
    assert set(ds.coords) == {"point", "component", "omega", "b", parameter}
    assert set(ds.xindexes) == set(indexed)
    for name in indexed:
        assert ds.xindexes[name].equals(general.xindexes[name])
        assert type(ds.variables[name]) is type(general.variables[name])
        assert ds[name].dtype == general[name].dtype
    ds.isel(point=slice(2, 5)).sel(component="x2")  # the indexes select
    validate_branch_dataset(ds)


@pytest.mark.parametrize("private", ["gone", "other arguments"])
def test_without_xarrays_private_constructor_the_dataset_is_the_same(osc, monkeypatch,
                                                                      private):
    """A release of xarray without ``Dataset._construct_direct`` (or with other arguments)
    gets the same branch dataset from the public constructor (schema._constructed)."""
    cols = _columns()
    kwargs = dict(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                  special_points=_specials(cols))
    direct = branch_dataset(**kwargs)

    def refuse(*args, **kw):
        raise TypeError("unexpected keyword argument")

    monkeypatch.setattr(schema, "_direct_constructor",
                        (lambda: None) if private == "gone" else (lambda: refuse))
    built = []
    public_way = schema._constructed
    monkeypatch.setattr(schema, "_constructed", lambda *a: built.append(1) or public_way(*a))
    public = branch_dataset(**kwargs)
    assert built == [1]  # the public constructor built it
    xr.testing.assert_identical(direct, public)
    assert set(public.xindexes) == {"point", "component"}
    assert set(public.coords) == set(direct.coords)
    validate_branch_dataset(public)


def test_schema_attributes(branch, osc):
    for name, var in branch.data_vars.items():
        assert {"long_name", "units", "description"} <= set(var.attrs), name
    assert branch["delta"].attrs["units"] == "rad"
    assert branch["special_delta"].attrs["units"] == "rad"
    assert branch["omega"].attrs["units"] == "1"
    attrs = branch.attrs
    assert attrs["N"] == 1 and attrs["parameter"] == "omega"
    assert attrs["Conventions"] == "CF-1.10"
    assert attrs["impactcont_version"] == impactcont.__version__
    assert json.loads(attrs["options"]) == {"ds": 0.03, "max_steps": 50, "tol": 1e-10}
    assert attrs["oscillator"] == osc.to_json()
    assert "omega" in attrs["title"] and attrs["history"]
    back = oscillator_from_dataset(branch)
    assert back.to_dict() == osc.to_dict()
    at10 = oscillator_from_dataset(branch, point=10)
    assert at10.omega == pytest.approx(float(branch["omega"][10]), abs=0.0)
    assert validate_branch_dataset(branch) is branch


def test_schema_other_parameter_and_no_special_points(osc):
    cols = _columns()
    cols["R"] = np.linspace(0.5, 0.9, NPOINTS)
    ds = branch_dataset(parameter="R", N=2, oscillator=osc, options={}, columns=cols,
                        special_points=[])
    assert ds.sizes["special"] == 0
    assert "R" in ds.coords and "special_R" in ds.data_vars
    assert ds.attrs["parameter"] == "R"
    assert abs(oscillator_from_dataset(ds, point=-1).R - 0.9) <= 1e-15
    validate_branch_dataset(ds)


def _bad(osc, **changes):
    cols = _columns()
    kw = {"parameter": "omega", "N": 1, "oscillator": osc, "options": {}, "columns": cols,
          "special_points": _specials(cols)}
    for key, value in changes.items():
        if key.startswith("col_"):
            name = key[4:]
            if value is None:
                del cols[name]
            else:
                cols[name] = value
        elif key.startswith("sp_"):
            kw["special_points"][0][key[3:]] = value
        else:
            kw[key] = value
    return branch_dataset(**kw)


@pytest.mark.parametrize(("changes", "error", "match"), [
    ({"col_gap_min": None}, ValueError, r"missing key\(s\) \['gap_min'\]"),
    ({"col_delta": np.zeros(NPOINTS - 1)}, ValueError, r"'delta' must have shape \(50,\)"),
    ({"col_multipliers": np.zeros((NPOINTS, 3))}, ValueError, r"'multipliers' .*\(50, 4\)"),
    ({"col_speed": np.zeros(NPOINTS)}, ValueError, r"unknown key\(s\) \['speed'\]"),
    ({"col_stable": np.full(NPOINTS, 2.0)}, ValueError, r"'stable' must be boolean"),
    ({"col_omega": np.full(NPOINTS, np.nan)}, ValueError, r"'omega' must be finite"),
    ({"sp_label": "XX"}, ValueError, r"\['label'\] must be one of .*got 'XX'"),
    ({"sp_status": "guessed"}, ValueError, r"\['status'\] .*got 'guessed'"),
    ({"sp_point": NPOINTS}, ValueError, r"\['point'\] must be an integer index .*got 50"),
    ({"sp_precision": -1.0}, ValueError, r"\['precision'\] must be >= 0.*-1.0"),
    ({"sp_bracket_lo": 5.0}, ValueError, r"bracket_lo=5.0"),
    ({"sp_multipliers": np.zeros(3)}, ValueError, r"special_points\[0\] key 'multipliers'"),
    ({"parameter": "mass"}, ValueError, r"parameter must be one of .*got 'mass'"),
    ({"N": 0}, ValueError, r"N .* got 0"),
    ({"oscillator": "osc"}, TypeError, r"oscillator must be an ImpactOscillator; got 'osc'"),
    ({"options": {"f": object}}, TypeError, r"options must be JSON-serialisable"),
])
def test_bad_inputs_raise_naming_the_value(osc, changes, error, match):
    with pytest.raises(error, match=match):
        _bad(osc, **changes)


def test_missing_special_key_is_named(osc):
    cols = _columns()
    sps = _specials(cols)
    del sps[1]["precision"]
    with pytest.raises(ValueError, match=r"special_points\[1\] is missing key\(s\) \['precision'"):
        branch_dataset(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                       special_points=sps)


def test_validate_rejects_incomplete_datasets(branch):
    with pytest.raises(ValueError, match=r"missing variable\(s\) \['gap_min'\]"):
        validate_branch_dataset(branch.drop_vars("gap_min"))
    with pytest.raises(ValueError, match=r"missing attribute\(s\) \['oscillator'\]"):
        validate_branch_dataset(branch.drop_attrs(deep=False).assign_attrs(
            {k: v for k, v in branch.attrs.items() if k != "oscillator"}))
    with pytest.raises(ValueError, match="'stable' must have dtype kind 'b'"):
        validate_branch_dataset(branch.assign(stable=branch["stable"].astype(float)))
    with pytest.raises(TypeError, match="DataArray"):
        validate_branch_dataset(branch["omega"])
    assert set(POINT_VARIABLES) <= set(branch.variables)

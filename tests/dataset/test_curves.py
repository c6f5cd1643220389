"""The datasets of codim-1 curves and N-1 maps (:mod:`impactcont.dataset.curves`): built from
the columns of a continued PD curve and of a computed map, they hold those columns with the
schema's dims, dtypes and CF metadata, save and load back identical, and bad columns are
refused naming the column, what it got and what is required."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset import curves as dc
from impactcont.dataset import maps as dm

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.0, omega=1.75, eta=0.1)


@pytest.fixture(scope="module")
def pd_curve() -> xr.Dataset:
    """The PD curve through the period doubling of the paper's N-1 branch at b = 0."""
    branch = ic.continuation(PAPER, N=1, bounds=(1.6, 1.9), detect=("PD",))
    return ic.curve(None, kind="PD", start=branch, special=0,
                    bounds={"omega": [1.6, 1.9], "b": [-0.1, 0.1]}, max_points=30)


@pytest.fixture(scope="module")
def n1_map() -> xr.Dataset:
    return ic.stability_map(PAPER, [1, 2], np.linspace(0.9, 1.6, 5), np.linspace(0.4, 0.7, 4))


def _columns(curve: xr.Dataset, parameters=("omega", "b")) -> dict[str, np.ndarray]:
    names = [*(p for p in parameters if p not in ("omega", "b")), *dc.CURVE_VARIABLES]
    return {name: curve[name].values for name in names}


def _codim2(curve: xr.Dataset, label: str = "PD+NS", **changes) -> dict:
    """A codim-2 point at curve point 3 (its values made up from the curve's)."""
    point = {"label": label, "omega": float(curve["omega"][3]), "b": float(curve["b"][3]),
             "delta": float(curve["delta"][3]), "point": 3, "precision": 1e-9,
             "status": "located", "multipliers": curve["multipliers"].values[3]}
    point.update(changes)
    return point


def _build(curve: xr.Dataset, **changes) -> xr.Dataset:
    args = {"kind": "PD", "N": 1, "parameters": ("omega", "b"), "oscillator": PAPER,
            "options": {"ds_max": 0.1}, "columns": _columns(curve),
            "codim2_points": [_codim2(curve)], "end_status": "both ends at a bound"}
    args.update(changes)
    return dc.curve_dataset(**args)


# -- curves ----------------------------------------------------------------------------------
def test_a_curve_holds_its_columns_and_its_codim2_points(pd_curve) -> None:
    ds = _build(pd_curve)
    npoints = pd_curve.sizes["point"]
    assert dict(ds.sizes) == {"point": npoints, "multiplier": 4, "component": 4, "codim2": 1}
    for name, values in _columns(pd_curve).items():
        np.testing.assert_array_equal(ds[name].values, values)
        assert ds[name].dims[0] == "point"
    assert ds["root"].dtype == np.int64 and ds["physical"].dtype == bool
    assert ds["multipliers"].dtype == np.complex128
    assert ds["omega"].dims == ("point",) and "omega" in ds.coords  # plots take x="omega"
    assert ds["codim2_label"].values.tolist() == ["PD+NS"]
    assert ds["codim2_point"].values.tolist() == [3]
    np.testing.assert_array_equal(ds["codim2_multipliers"].values[0],
                                  pd_curve["multipliers"].values[3])
    assert ds.attrs["impactcont_dataset"] == "curve" and ds.attrs["kind"] == "PD"
    assert ds.attrs["parameters"] == "omega,b" and ds.attrs["N"] == 1
    assert ic.ImpactOscillator.from_json(ds.attrs["oscillator"]).to_json() == PAPER.to_json()
    assert json.loads(ds.attrs["options"]) == {"ds_max": 0.1}
    assert ds.attrs["title"] == "PD curve of periodic 1-1 motions in (omega, b)"
    assert dc.validate_dataset(ds) is ds


def test_every_variable_carries_its_cf_name_and_units(pd_curve, n1_map) -> None:
    for ds in (_build(pd_curve), dm.map_dataset(
            oscillator=PAPER, N=[1, 2], omega=n1_map["omega"].values, b=n1_map["b"].values,
            values={k: n1_map[k].values for k in dm.MAP_VARIABLES}, options={})):
        assert ds.attrs["Conventions"].startswith("CF-")
        for name, var in ds.variables.items():
            if var.dtype.kind in "fcib" and name not in ("multiplier",):
                assert isinstance(var.attrs.get("long_name"), str), name
                assert isinstance(var.attrs.get("units"), str), name
        assert ds["delta"].attrs["units"] == "rad"


def test_a_curve_saves_and_loads_back_identical(pd_curve, tmp_path) -> None:
    ds = _build(pd_curve)
    back = ic.load(ic.save(ds, tmp_path / "curve.nc"))
    xr.testing.assert_identical(back, ds)
    assert back["codim2_label"].dtype == ds["codim2_label"].dtype
    assert back["codim2_status"].values.tolist() == ["located"]


def test_a_curve_in_another_parameter_gets_its_column(pd_curve) -> None:
    columns = {**_columns(pd_curve), "R": np.full(pd_curve.sizes["point"], 0.6)}
    point = {**_codim2(pd_curve), "R": 0.6}
    ds = _build(pd_curve, parameters=("omega", "R"), columns=columns, codim2_points=[point])
    assert ds.attrs["parameters"] == "omega,R"
    np.testing.assert_array_equal(ds["R"].values, 0.6)
    assert ds["codim2_R"].values.tolist() == [0.6]
    with pytest.raises(ValueError, match=r"columns: missing \['R'\], unknown \[\]; required "
                                         r"\['R', 'omega', 'b', 'delta'"):
        _build(pd_curve, parameters=("omega", "R"), codim2_points=[point])


@pytest.mark.parametrize(("changes", "error", "match"), [
    ({"kind": "XY"}, ValueError, r"kind must be one of \('SN', 'PD', 'NS', 'GR', 'ZV'\); "
                                 r"got 'XY'"),
    ({"parameters": ("omega", "omega")}, ValueError,
     r"parameters must be two different parameters; got \['omega', 'omega'\]"),
    ({"oscillator": "paper"}, TypeError, r"oscillator must be an ImpactOscillator; got 'paper'"),
    ({"N": 0}, ValueError, r"N must be an integer >= 1 \(forcing periods per impact\); got 0"),
])
def test_a_bad_argument_of_a_curve_is_named(pd_curve, changes, error, match) -> None:
    with pytest.raises(error, match=match):
        _build(pd_curve, **changes)


def test_a_bad_column_of_a_curve_is_named(pd_curve) -> None:
    columns = _columns(pd_curve)
    del columns["gap_min"]
    with pytest.raises(ValueError, match=r"columns: missing \['gap_min'\], unknown \[\]"):
        _build(pd_curve, columns=columns)
    with pytest.raises(ValueError, match=r"missing \[\], unknown \['speed'\]; required "
                                         r"\['omega', 'b', 'delta'"):
        _build(pd_curve, columns={**_columns(pd_curve), "speed": pd_curve["omega"].values})
    npoints = pd_curve.sizes["point"]
    short = {**_columns(pd_curve), "delta": pd_curve["delta"].values[:-1]}
    with pytest.raises(ValueError, match=rf"column 'delta' must have shape \({npoints},\); "
                                         rf"got shape \({npoints - 1},\)"):
        _build(pd_curve, columns=short)
    flat = {**_columns(pd_curve), "state": pd_curve["state"].values[:, :2]}
    with pytest.raises(ValueError, match=rf"column 'state' must have shape \({npoints}, 4\)"):
        _build(pd_curve, columns=flat)


@pytest.mark.parametrize(("point", "error", "match"), [
    ({"label": "PD+XX"}, ValueError, r"codim2 labels must be in \('SN\+ZV'.*'R2'.*\); got "
                                     r"\['PD\+XX'\]"),
    ({"status": "guessed"}, ValueError, r"codim2 statuses must be in \('located', "
                                        r"'bracketed'\); got \['guessed'\]"),
    ({"extra": 1}, ValueError, r"codim2_points\[0\] must have keys \['b', 'delta', 'label', "
                               r"'multipliers', 'omega', 'point', 'precision', 'status'\]"),
])
def test_a_bad_codim2_point_is_named(pd_curve, point, error, match) -> None:
    with pytest.raises(error, match=match):
        _build(pd_curve, codim2_points=[_codim2(pd_curve, **point)])
    with pytest.raises(TypeError, match=r"codim2_points\[0\] must be a dict; got 3"):
        _build(pd_curve, codim2_points=[3])


def test_validate_refuses_a_curve_that_is_not_one(pd_curve) -> None:
    ds = _build(pd_curve)
    with pytest.raises(TypeError, match=r"expected an xarray.Dataset of a curve; got dict"):
        dc.validate_curve_dataset({})
    del_kind = ds.copy()
    del del_kind.attrs["kind"]
    with pytest.raises(ValueError, match=r"not a curve dataset: missing attribute\(s\) "
                                         r"\['kind'\]"):
        dc.validate_curve_dataset(del_kind)
    with pytest.raises(ValueError, match=r"attribute 'parameters' must name two of"):
        dc.validate_curve_dataset(ds.assign_attrs(parameters="omega"))
    with pytest.raises(ValueError, match=r"not a curve dataset: missing variable\(s\) "
                                         r"\['gap_min'\]"):
        dc.validate_curve_dataset(ds.drop_vars("gap_min"))
    wrong = ds.copy()
    wrong["codim2_label"] = wrong["codim2_label"].copy(data=np.array(["XX"]))
    with pytest.raises(ValueError, match=r"codim2_label must hold values in .*; got \['XX'\]"):
        dc.validate_curve_dataset(wrong)


def test_codim2_labels_of_older_files_get_their_name(pd_curve) -> None:
    ds = _build(pd_curve, codim2_points=[_codim2(pd_curve, label="R2")])
    old = ds.copy()
    old["codim2_label"] = old["codim2_label"].copy(data=np.array(["PD+PD"], dtype="<U5"))
    new = dc.normalise_dataset(old)
    assert new["codim2_label"].values.tolist() == ["R2"]
    assert new["codim2_label"].dtype == ds["codim2_label"].dtype
    assert dc.CODIM2_FORMER_LABELS == {"SN+SN": "R1", "PD+PD": "R2"}


# -- maps ------------------------------------------------------------------------------------
def _map(n1_map: xr.Dataset, **changes) -> xr.Dataset:
    args = {"oscillator": PAPER, "N": n1_map["N"].values.tolist(),
            "omega": n1_map["omega"].values, "b": n1_map["b"].values,
            "values": {k: n1_map[k].values for k in dm.MAP_VARIABLES},
            "options": {"executor": "serial"}}
    args.update(changes)
    return dm.map_dataset(**args)


def test_a_map_holds_its_values_on_its_grid_and_loads_back(n1_map, tmp_path) -> None:
    ds = _map(n1_map)
    assert dict(ds.sizes) == {"N": 2, "omega": 5, "b": 4, "root": 2}
    assert ds["root"].values.tolist() == [1, -1]
    for name, (_, dims) in dm.MAP_VARIABLES.items():
        assert ds[name].dims == dims
        np.testing.assert_array_equal(ds[name].values, n1_map[name].values)
    assert ds.attrs["impactcont_dataset"] == "map"
    assert json.loads(ds.attrs["options"]) == {"executor": "serial"}
    assert dc.validate_dataset(ds) is ds
    xr.testing.assert_identical(ic.load(ic.save(ds, tmp_path / "map.nc")), ds)


def test_a_map_without_eigenvalues_has_no_spectral_radius(n1_map, tmp_path) -> None:
    values = {k: n1_map[k].values for k in dm.MAP_VARIABLES
              if k not in ("spectral_radius", "critical_multiplier")}
    ds = _map(n1_map, values=values)
    assert "spectral_radius" not in ds and "critical_multiplier" not in ds
    xr.testing.assert_identical(ic.load(ic.save(ds, tmp_path / "map.nc")), ds)


def test_a_bad_map_is_named(n1_map) -> None:
    values = {k: n1_map[k].values for k in dm.MAP_VARIABLES if k != "gap_min"}
    with pytest.raises(ValueError, match=r"values is missing 'gap_min'; required "
                                         r"\['amplitude_squared'"):
        _map(n1_map, values=values)
    values = {**{k: n1_map[k].values for k in dm.MAP_VARIABLES},
              "exists": n1_map["exists"].values[:1]}
    with pytest.raises(ValueError, match=r"column 'exists' must have shape \(2, 5, 4\); got "
                                         r"shape \(1, 5, 4\)"):
        _map(n1_map, values=values)
    with pytest.raises(ValueError, match=r"omega and b must be 1-D grids; got shapes \(1, 5\)"):
        _map(n1_map, omega=n1_map["omega"].values[None, :])
    with pytest.raises(TypeError, match=r"options must be a mapping; got \['serial'\]"):
        _map(n1_map, options=["serial"])
    with pytest.raises(TypeError, match=r"oscillator must be an ImpactOscillator; got None"):
        _map(n1_map, oscillator=None)
    with pytest.raises(ValueError, match=r"variable 'exists' must have dims \('N', 'omega', "
                                         r"'b'\); got \('N', 'omega'\)"):
        dm.validate_map_dataset(_map(n1_map).isel(b=0, drop=True))


def test_any_curve_of_either_evaluator_is_validated(caplog) -> None:
    """``validate_any_curve``: a curve followed by shooting is an N-p branch dataset with
    ``curve_kind`` and its two parameter columns; one written before it had
    ``stable_side`` gets one of False, with a WARNING; a bad kind or parameters are
    refused by name."""
    import numpy as np

    import impactcont as ic
    from impactcont.dataset.curves import kind_of_curve, validate_any_curve

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              R=0.6, eta=0.1, b=0.0, omega=1.75)
    start = ic.multi_impact_orbit(osc, 1, 1, next(q for q in ic.periodic_orbits(osc, 1)
                                                  if q.physical))
    branch = ic.multi_impact_continuation(start, "omega", (1.6, 1.9), detect=("PD",),
                                          both_directions=True)
    curve = ic.curve(None, None, "PD", start=branch, parameters=("omega", "b"),
                     bounds={"omega": (1.5, 2.0), "b": (-0.05, 0.05)})
    assert kind_of_curve(curve) == "PD" and validate_any_curve(curve) is curve
    old = curve.drop_vars("stable_side")
    with caplog.at_level("WARNING", logger="impactcont.dataset.curves"):
        mended = validate_any_curve(old)
    assert not mended["stable_side"].values.any() and "has no stable_side" in caplog.text
    with pytest.raises(ValueError, match="curve_kind"):
        validate_any_curve(curve.assign_attrs(curve_kind="XX"))
    with pytest.raises(ValueError, match="parameters"):
        validate_any_curve(curve.assign_attrs(parameters="omega,q7"))

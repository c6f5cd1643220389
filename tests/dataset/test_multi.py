"""Branch datasets of N-p motions (:mod:`impactcont.dataset.multi`): built from the columns of
the 2-2 branch born at a period doubling, they hold the per-impact columns on ``(point,
impact)``, the attributes ``impacts`` and ``pattern``, save and load back identical; a missing,
unknown or misshapen per-impact column, a bad ``p`` or pattern is refused by name."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset import multi as dm
from impactcont.model.stops import Stops

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.0, omega=1.75, eta=0.1)


@pytest.fixture(scope="module")
def n1() -> xr.Dataset:
    return ic.continuation(PAPER, N=1, bounds=(1.6, 1.9), detect=("PD",))


@pytest.fixture(scope="module")
def two(n1) -> xr.Dataset:
    """The 2-2 branch born at the first period doubling of the N-1 branch."""
    return ic.period_doubling_switch(n1, 0, ds_max=0.05)


def _parts(ds: xr.Dataset) -> dict:
    """The builder's arguments that give back ``ds`` (its columns and special points)."""
    per_point = [v for v in ds.data_vars if ds[v].dims[0] == "point"]
    columns = {v: ds[v].values for v in [*per_point, "omega", "b"]
               if v not in dm.IMPACT_VARIABLES}
    special_names = [v.removeprefix("special_") for v in ds.data_vars
                     if v.startswith("special_")
                     and v.removeprefix("special_") not in dm.SPECIAL_IMPACT_VARIABLES]
    specials = [{k: ds[f"special_{k}"].values[i].item() if ds[f"special_{k}"].ndim == 1
                 else ds[f"special_{k}"].values[i] for k in special_names}
                for i in range(ds.sizes["special"])]
    return {
        "parameter": ds.attrs["parameter"], "N": int(ds.attrs["N"]),
        "p": int(ds.attrs["impacts"]), "oscillator": ic.ImpactOscillator.from_json(
            ds.attrs["oscillator"]), "options": {"ds_max": 0.05}, "columns": columns,
        "impact_columns": {k: ds[k].values for k in dm.IMPACT_VARIABLES},
        "special_points": specials,
        "special_impact_columns": {k: ds[f"special_{k}"].values
                                   for k in dm.SPECIAL_IMPACT_VARIABLES},
    }


def _build(two: xr.Dataset, **changes) -> xr.Dataset:
    return dm.multi_impact_dataset(**{**_parts(two), **changes})


def test_the_branch_holds_its_per_impact_columns(two) -> None:
    ds = _build(two, extra_attrs={"born_at": "PD", "parent_N": 1})
    assert ds.sizes["impact"] == 2 and ds["impact"].values.tolist() == [0, 1]
    for key, spec in dm.IMPACT_VARIABLES.items():
        assert ds[key].dims == ("point", "impact", *spec.extra_dims)
        np.testing.assert_array_equal(ds[key].values, two[key].values)
    for key in dm.SPECIAL_IMPACT_VARIABLES:
        assert ds[f"special_{key}"].dims[:2] == ("special", "impact")
        np.testing.assert_array_equal(ds[f"special_{key}"].values, two[f"special_{key}"].values)
        assert ds[f"special_{key}"].attrs["long_name"].endswith("at special point")
    assert ds.attrs["impacts"] == 2 and ds.attrs["pattern"] == "UU"
    assert ds.attrs["born_at"] == "PD" and ds.attrs["parent_N"] == 1
    assert ds.attrs["title"] == "Branch of periodic 2-2 impacting motions continued in omega"
    assert ds["special_label"].values.tolist() == two["special_label"].values.tolist()
    assert dm.impacts_of(ds) == 2 and dm.pattern_of(ds) == "UU"
    assert dm.validate_multi_impact_dataset(ds) is ds


def test_the_flight_times_close_the_period_2_pi_N_over_omega(two) -> None:
    """What the attribute N is checked against (the sum of the flight times)."""
    ds = _build(two)
    np.testing.assert_allclose(ds["flight_time_k"].sum("impact") * ds["omega"] / (2 * np.pi),
                               ds.attrs["N"], rtol=1e-10)


def test_the_branch_saves_and_loads_back_identical(two, tmp_path) -> None:
    ds = _build(two)
    back = ic.load(ic.save(ds, tmp_path / "two.nc"))
    xr.testing.assert_identical(back, ds)
    assert dm.pattern_of(back) == "UU"


def test_an_n1_branch_is_one_impact_of_the_upper_stop(n1) -> None:
    assert dm.impacts_of(n1) == 1 and dm.pattern_of(n1) == "U"
    assert dm.validate_multi_impact_dataset(n1) is n1  # no impact dimension: a branch


def test_a_two_sided_pattern_is_kept_and_needs_a_lower_stop(two) -> None:
    mirrored = PAPER.replace(b=0.5, stops=Stops(mirror=True))
    ds = _build(two, oscillator=mirrored, pattern="UL")
    assert dm.pattern_of(ds) == "UL"
    with pytest.raises(ValueError, match=r"attribute 'pattern' must be 2 letters \(one per "
                                         r"impact\) from 'U' \(upper stop\): the oscillator has "
                                         r"no lower stop; got 'UL'"):
        _build(two, pattern="UL")
    with pytest.raises(ValueError, match=r"attribute 'pattern' must be 2 letters.*got 'U'$"):
        _build(two, oscillator=mirrored, pattern="U")


@pytest.mark.parametrize("p", [0, -1, 1.5, True, "2"])
def test_p_must_be_a_count_of_impacts(two, p) -> None:
    with pytest.raises(ValueError, match=rf"p must be an integer >= 1 \(impacts per motion\); "
                                         rf"got {p!r}"):
        _build(two, p=p)


def test_a_missing_unknown_or_misshapen_impact_column_is_named(two) -> None:
    cols = _parts(two)["impact_columns"]
    without = {k: v for k, v in cols.items() if k != "gap_min_k"}
    with pytest.raises(ValueError, match=r"impact columns: missing \['gap_min_k'\], unknown "
                                         r"\[\]; required: \['delta_k'"):
        _build(two, impact_columns=without)
    with pytest.raises(ValueError, match=r"impact columns: missing \[\], unknown \['speed_k'\]"):
        _build(two, impact_columns={**cols, "speed_k": cols["delta_k"]})
    npoints = two.sizes["point"]
    with pytest.raises(ValueError, match=rf"impact column 'delta_k' must have shape "
                                         rf"\({npoints}, 2\); got shape \({npoints}, 1\)"):
        _build(two, impact_columns={**cols, "delta_k": cols["delta_k"][:, :1]})
    with pytest.raises(ValueError, match=r"impact column 'flight_time_k' must be real numbers; "
                                         r"got dtype complex128"):
        _build(two, impact_columns={**cols, "flight_time_k": cols["flight_time_k"] + 0j})
    special = _parts(two)["special_impact_columns"]
    with pytest.raises(ValueError, match=r"special impact columns: missing \['state_k'\]"):
        _build(two, special_impact_columns={k: v for k, v in special.items() if k != "state_k"})
    with pytest.raises(TypeError, match=r"impact_columns and special_impact_columns must be "
                                        r"mappings"):
        _build(two, impact_columns=list(cols.values()))


def test_extra_attributes_must_be_numbers_or_text(two) -> None:
    with pytest.raises(TypeError, match=r"extra_attrs\['born'\] must be a str, int or float; "
                                        r"got True"):
        _build(two, extra_attrs={"born": True})
    with pytest.raises(TypeError, match=r"extra_attrs\['where'\] must be a str, int or float; "
                                        r"got \[1\]"):
        _build(two, extra_attrs={"where": [1]})


def test_validate_names_a_per_impact_variable_that_is_missing_or_misplaced(two) -> None:
    ds = _build(two)
    with pytest.raises(ValueError, match=r"not a N-p branch dataset: missing variable\(s\) "
                                         r"\['special_state_k'\]"):
        dm.validate_multi_impact_dataset(ds.drop_vars("special_state_k"))
    swapped = ds.assign(delta_k=ds["delta_k"].transpose("impact", "point"))
    with pytest.raises(ValueError, match=r"variable 'delta_k' must have dims \('point', "
                                         r"'impact'\); got \('impact', 'point'\)"):
        dm.validate_multi_impact_dataset(swapped)

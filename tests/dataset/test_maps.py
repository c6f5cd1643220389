"""Maps of one N-p motion family (:mod:`impactcont.dataset.maps`): built from the values
of a computed map, the dataset holds them on the two parameters' grid (per-impact values on
``impact``), says which motion it maps, saves and loads back identical; a missing or
misshapen value, a bad pattern or parameter pair is refused by name."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.maps import multi_impact_map
from impactcont.dataset import maps as dmm
from impactcont.model.stops import Stops

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.6, omega=1.0, eta=0.1)
OMEGA, B = np.linspace(0.6, 1.6, 6), np.linspace(0.0, 1.2, 5)


@pytest.fixture(scope="module")
def computed() -> xr.Dataset:
    """The 1-1 family of the paper's system seeded by its physical closed-form motion."""
    physical = next(o for o in ic.periodic_orbits(PAPER, 1) if o.physical)
    return multi_impact_map(physical, ("omega", "b"), grid={"omega": OMEGA, "b": B})


def _args(computed: xr.Dataset, **changes) -> dict:
    args = {"oscillator": PAPER, "N": 1, "pattern": "U", "parameters": ("omega", "b"),
            "grid": {"omega": OMEGA, "b": B},
            "values": {k: computed[k].values for k in dmm.MULTI_MAP_VARIABLES if k in computed},
            "symmetric": False, "seed": {"omega": 1.0, "b": 0.6}, "options": {"tol": 1e-11}}
    args.update(changes)
    return args


def _build(computed: xr.Dataset, **changes) -> xr.Dataset:
    return dmm.multi_impact_map_dataset(**_args(computed, **changes))


def test_the_map_holds_its_values_on_the_grid(computed) -> None:
    ds = _build(computed)
    assert dict(ds.sizes) == {"omega": 6, "b": 5, "impact": 1, "component": 4}
    np.testing.assert_array_equal(ds["omega"].values, OMEGA)
    assert ds["component"].values.tolist() == ["x1", "x2", "v1", "v2"]
    for key, spec in dmm.MULTI_MAP_VARIABLES.items():
        if key == "asymmetry":
            assert key not in ds  # one stop: no symmetric motions
            continue
        assert ds[key].dims == ("omega", "b", *spec.extra_dims)
        np.testing.assert_array_equal(ds[key].values, computed[key].values)
        assert ds[key].attrs["long_name"] == spec.long_name
    assert ds.attrs["impactcont_dataset"] == dmm.MULTI_MAP_KIND == "multi_impact_map"
    assert (ds.attrs["N"], ds.attrs["impacts"], ds.attrs["pattern"]) == (1, 1, "U")
    assert ds.attrs["parameters"] == "omega,b" and ds.attrs["symmetric"] == 0
    assert json.loads(ds.attrs["seed"]) == {"b": 0.6, "omega": 1.0}
    assert json.loads(ds.attrs["options"]) == {"tol": 1e-11}
    assert ds.attrs["title"] == ("Stability map of the N=1, p=1 motion family over "
                                 "(omega, b)")
    assert dmm.validate_multi_impact_map_dataset(ds) is ds


def test_the_map_saves_and_loads_back_identical(computed, tmp_path) -> None:
    ds = _build(computed)
    back = ic.load(ic.save(ds, tmp_path / "map.nc"))
    xr.testing.assert_identical(back, ds)
    found = back["found"].values
    assert found.any() and not found.all()  # the family ends inside the grid
    assert np.isnan(back["spectral_radius"].values[~found]).all()


def test_a_two_sided_symmetric_map_in_the_other_order_keeps_its_asymmetry(tmp_path) -> None:
    """Made-up values of a 1-2 family of a system with mirrored stops, grid (b, omega)."""
    mirrored = PAPER.replace(b=0.5, stops=Stops(mirror=True))
    rng = np.random.default_rng(1)
    shape = (3, 4)  # (b, omega)
    values = {
        "found": np.ones(shape, bool), "newton_iterations": np.full(shape, 3, np.int64),
        "stable": rng.random(shape) < 0.5, "physical": np.ones(shape, bool),
        "contact_checked": np.ones(shape, bool), "spectral_radius": rng.random(shape),
        "critical_multiplier": rng.random(shape) + 1j * rng.random(shape),
        "delta": rng.random(shape), "gap_min": rng.random(shape),
        "impact_velocity_k": rng.random((*shape, 2)), "flight_time_k": rng.random((*shape, 2)),
        "state_k": rng.random((*shape, 2, 4)), "asymmetry": np.zeros(shape)}
    ds = dmm.multi_impact_map_dataset(
        oscillator=mirrored, N=1, pattern="UL", parameters=("b", "omega"),
        grid={"b": [0.3, 0.5, 0.7], "omega": [1.0, 1.2, 1.4, 1.6]}, values=values,
        symmetric=True, seed={"b": 0.5, "omega": 1.6}, options={})
    assert ds["state_k"].dims == ("b", "omega", "impact", "component")
    assert ds.attrs["pattern"] == "UL" and ds.attrs["symmetric"] == 1
    assert ds.attrs["parameters"] == "b,omega"
    np.testing.assert_array_equal(ds["asymmetry"].values, 0.0)
    xr.testing.assert_identical(ic.load(ic.save(ds, tmp_path / "sym.nc")), ds)


def test_a_missing_or_misshapen_value_is_named(computed) -> None:
    values = _args(computed)["values"]
    without = {k: v for k, v in values.items() if k != "delta"}
    with pytest.raises(ValueError, match=r"values is missing 'delta'; required \['found', "
                                         r"'newton_iterations'.*'state_k'\]$"):
        _build(computed, values=without)
    with pytest.raises(ValueError, match=r"values\['state_k'\] must have shape \(6, 5, 1, 4\) "
                                         r"\(dims \('omega', 'b', 'impact', 'component'\)\); "
                                         r"got \(6, 5, 4\)"):
        _build(computed, values={**values, "state_k": values["state_k"][:, :, 0]})
    with pytest.raises(ValueError, match=r"values\['found'\] must have shape \(5, 6\) \(dims "
                                         r"\('b', 'omega'\)\); got \(6, 5\)"):
        _build(computed, parameters=("b", "omega"))
    with pytest.raises(TypeError, match=r"oscillator must be an ImpactOscillator; got 'paper'"):
        _build(computed, oscillator="paper")


def test_a_value_of_the_wrong_kind_is_refused_when_saved(computed, tmp_path) -> None:
    values = _args(computed)["values"]
    ds = _build(computed, values={**values, "found": values["found"].astype(float)})
    with pytest.raises(ValueError, match=r"variable 'found' must have dtype kind 'b'; got "
                                         r"dtype float64"):
        ic.save(ds, tmp_path / "bad.nc")
    # the builder keeps the pattern it is given; save checks it against the oscillator
    with pytest.raises(ValueError, match=r"attribute 'pattern' must be 1 letter .*no lower "
                                         r"stop; got 'L'"):
        ic.save(_build(computed, pattern="L"), tmp_path / "bad.nc")
    assert list(tmp_path.iterdir()) == []  # no half file


def test_validate_names_a_bad_attribute(computed) -> None:
    ds = _build(computed)
    with pytest.raises(TypeError, match=r"expected an xarray.Dataset of a multi_impact_map; "
                                        r"got list"):
        dmm.validate_multi_impact_map_dataset([])
    with pytest.raises(ValueError, match=r"not a multi_impact_map dataset: missing "
                                         r"attribute\(s\) \[\] or impactcont_dataset != "
                                         r"'multi_impact_map'"):
        dmm.validate_multi_impact_map_dataset(ds.assign_attrs(impactcont_dataset="map"))
    no_seed = ds.copy()
    del no_seed.attrs["seed"]
    with pytest.raises(ValueError, match=r"missing attribute\(s\) \['seed'\]"):
        dmm.validate_multi_impact_map_dataset(no_seed)
    with pytest.raises(ValueError, match=r"attribute 'parameters' must name two different "
                                         r"parameters .*; got 'omega,omega'"):
        dmm.validate_multi_impact_map_dataset(ds.assign_attrs(parameters="omega,omega"))
    with pytest.raises(ValueError, match=r"attribute 'impacts' must be p >= 1, the size of "
                                         r"dimension 'impact' \(1\); got 2"):
        dmm.validate_multi_impact_map_dataset(ds.assign_attrs(impacts=2))
    with pytest.raises(ValueError, match=r"attribute 'pattern' must be 1 letter .*no lower "
                                         r"stop; got 'L'"):
        dmm.validate_multi_impact_map_dataset(ds.assign_attrs(pattern="L"))
    with pytest.raises(ValueError, match=r"not a multi_impact_map dataset: missing "
                                         r"variable\(s\) \['gap_min'\]"):
        dmm.validate_multi_impact_map_dataset(ds.drop_vars("gap_min"))


# -- every map: one module, one check ------------------------------------------------------
def _n1_map() -> xr.Dataset:
    """A small map of every N-1 motion (closed form), over (omega, b) and over (k2, b)."""
    return ic.stability_map(PAPER, 1, OMEGA[:3], B[:2])


def test_validate_map_checks_either_layout_by_its_attribute(computed) -> None:
    family = _build(computed)
    n1 = _n1_map()
    assert dmm.validate_map(family) is family and dmm.validate_map(n1) is n1
    assert dmm.map_parameters(family) == dmm.map_parameters(n1) == ("omega", "b")
    assert set(dmm.MAP_KINDS) == {n1.attrs["impactcont_dataset"],
                                  family.attrs["impactcont_dataset"]}
    with pytest.raises(TypeError, match=r"expected an xarray.Dataset of a map; got dict"):
        dmm.validate_map({})
    with pytest.raises(ValueError, match=r"not a map dataset: missing attribute\(s\) \[\] or "
                                         r"impactcont_dataset != 'map'"):
        dmm.validate_map(n1.assign_attrs(impactcont_dataset="curve"))
    with pytest.raises(ValueError, match=r"not a multi_impact_map dataset: missing "
                                         r"variable\(s\) \['found'\]"):
        dmm.validate_map(family.drop_vars("found"))
    # the two layouts read their parameters the same way, and refuse a bad pair the same way
    for ds in (family, n1):
        with pytest.raises(ValueError, match=r"attribute 'parameters' must name two "
                                             r"different parameters .*; got 'b,b'"):
            dmm.validate_map(ds.assign_attrs(parameters="b,b"))


def test_a_map_over_an_element_is_one_of_either_layout(computed, tmp_path) -> None:
    """An N-1 map over (k2, b) and a family map over (b, k2) carry their pair alike."""
    n1 = ic.stability_map(PAPER, 1, parameters=("k2", "b"),
                          grid={"k2": [1.8, 2.0], "b": [0.4, 0.6]})
    assert n1.attrs["parameters"] == "k2,b" and dmm.map_parameters(n1) == ("k2", "b")
    values = {k: np.swapaxes(computed[k].values[:2, :2], 0, 1)
              for k in dmm.MULTI_MAP_VARIABLES if k in computed}
    family = _build(computed, parameters=("b", "k2"), grid={"b": B[:2], "k2": [1.8, 2.0]},
                    values=values)
    assert dmm.map_parameters(family) == ("b", "k2")
    for ds in (n1, family):
        xr.testing.assert_identical(ic.load(ic.save(ds, tmp_path / "m.nc")), ds)


# -- a map of a motion with sticking phases ------------------------------------------------
PRELOADED = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.0,
                                omega=0.8, eta=0.05)


def _sticky_values(shape: tuple[int, int], p: int = 1, n: int = 1) -> dict:
    """Values of every variable of a sticky map: a point not physical where its stick
    ended (reason 1), one not found."""
    values = {"found": np.ones(shape, bool), "newton_iterations": np.full(shape, 3, np.int32),
              "stable": np.ones(shape, bool), "physical": np.ones(shape, bool),
              "contact_checked": np.ones(shape, bool), "spectral_radius": np.zeros(shape),
              "critical_multiplier": np.zeros(shape, complex), "delta": np.ones(shape),
              "gap_min": np.ones(shape), "impact_velocity_k": np.ones((*shape, p)),
              "flight_time_k": np.ones((*shape, p)), "state_k": np.zeros((*shape, p, 2 * n)),
              "stick_time_k": np.full((*shape, p), 0.5), "release_phase_k": np.ones((*shape, p)),
              "pressing_min_k": np.ones((*shape, p)), "landing_pressing_k": np.ones((*shape, p)),
              "stick_time_min": np.full(shape, 0.5), "pressing_min": np.ones(shape),
              "reason": np.zeros(shape, np.int32)}
    values["physical"][0, 0] = False
    values["stick_time_min"][0, 0] = values["stick_time_k"][0, 0] = -0.1
    values["reason"][0, 0] = dmm.MAP_REASONS["stick_ended"]
    values["found"][-1, -1] = values["physical"][-1, -1] = values["stable"][-1, -1] = False
    return values


def test_a_sticky_map_holds_its_sticks_and_reasons_and_round_trips(tmp_path) -> None:
    """A pattern with a lowercase letter takes the sticky variables (required: one missing
    is refused by name), the reason with its CF flag attributes, and loads back identical;
    the reasons are distinct bits named in the order of their masks."""
    masks = list(dmm.MAP_REASONS.values())
    assert masks == [1 << k for k in range(len(masks))]
    values = _sticky_values((2, 3))
    args = {"oscillator": PRELOADED, "N": 1, "pattern": "u", "parameters": ("omega", "F[1]"),
            "grid": {"omega": [0.7, 0.8], "F[1]": [2.0, 3.0, 4.0]}, "values": values,
            "symmetric": False, "seed": {"omega": 0.8}, "options": {}}
    ds = dmm.multi_impact_map_dataset(**args)
    for key, spec in dmm.STICKY_MAP_VARIABLES.items():
        assert ds[key].dims == ("omega", "F[1]", *spec.extra_dims)
        assert ds[key].attrs["units"] == spec.units
    assert ds["reason"].attrs["flag_meanings"].split() == list(dmm.MAP_REASONS)
    assert dmm.validate_multi_impact_map_dataset(ds) is ds
    back = ic.load(ic.save(ds, tmp_path / "sticky.nc"))
    xr.testing.assert_identical(back, ds)
    assert dmm.sticky_pattern("u") and not dmm.sticky_pattern("UL")
    with pytest.raises(ValueError, match="missing 'reason'"):
        dmm.multi_impact_map_dataset(**{**args, "values": {
            k: v for k, v in values.items() if k != "reason"}})
    with pytest.raises(ValueError, match=r"missing variable\(s\) \['stick_time_min'\]"):
        dmm.validate_multi_impact_map_dataset(ds.drop_vars("stick_time_min"))

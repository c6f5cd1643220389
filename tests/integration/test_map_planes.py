"""One map entry for every motion and every pair of parameters (issue 29, items 1 and 5).

``ic.stability_map`` of an oscillator over a pair other than (omega, b) against the closed
form of :func:`ic.periodic_orbits` on an oscillator built afresh at each sampled point (the
parameter set by hand, not through :mod:`impactcont.model.parameters`); the same call over
(b, omega) against the (omega, b) map; ``ic.stability_map`` of a motion against
:func:`ic.multi_impact_map`; files and bad input.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic

K_CHAIN = [[1.0, -1.0], [-1.0, 2.0]]  # k1 = k2 = 1


def paper(**changes) -> ic.ImpactOscillator:
    args = {"M": np.eye(2), "K": K_CHAIN, "F": [1.0, 0.0], "R": 0.6, "b": 0.5, "omega": 1.0,
            "eta": 0.1, **changes}
    return ic.ImpactOscillator(**args)


OMEGA = np.linspace(0.6, 5.0, 12)
GAP = np.linspace(-0.5, 1.5, 9)


def _agrees_with_fresh_oscillators(ds, Ns, fresh, first, second, samples, seed):
    """Every sampled cell of `ds` against ic.periodic_orbits of fresh(x, y); the number of
    motions compared."""
    rng = np.random.default_rng(seed)
    compared = 0
    for _ in range(samples):
        k, i, j = (rng.integers(len(Ns)), rng.integers(ds.sizes[first]),
                   rng.integers(ds.sizes[second]))
        cell = ds.isel({"N": k, first: i, second: j})
        orbits = ic.periodic_orbits(fresh(float(cell[first]), float(cell[second])), int(cell.N))
        assert bool(cell.exists) == bool(orbits)
        assert int(cell.n_physical) == sum(o.physical for o in orbits)
        assert int(cell.n_stable) == sum(o.physical and o.stable for o in orbits)
        for o in orbits:
            r = cell.sel(root=o.root)
            assert math.remainder(float(r.delta) - o.delta, 2 * math.pi) == pytest.approx(
                0, abs=1e-9)
            assert float(r.impact_velocity) == pytest.approx(o.impact_velocity, abs=1e-9)
            assert float(r.spectral_radius) == pytest.approx(o.spectral_radius, rel=1e-7)
            assert bool(r.physical) == o.physical and bool(r.stable) == o.stable
            compared += 1
    return compared


def test_a_k2_b_map_holds_the_closed_form_of_fresh_oscillators():
    k2 = np.linspace(0.6, 2.2, 7)
    ds = ic.stability_map(paper(omega=1.2), [1, 2], parameters=("k2", "b"),
                          grid={"k2": k2, "b": GAP})
    assert dict(ds.sizes) == {"N": 2, "k2": 7, "b": 9, "root": 2}
    assert ds["amplitude_squared"].dims == ("N", "k2")
    assert ds.attrs["parameters"] == "k2,b"
    compared = _agrees_with_fresh_oscillators(
        ds, [1, 2], lambda v, b: paper(omega=1.2, b=b, K=[[1.0, -1.0], [-1.0, 1.0 + v]]),
        "k2", "b", 25, 3)
    assert compared > 10
    assert 0 < int(ds["n_stable"].sum()) < ds["n_stable"].size


def test_an_R_F0_map_holds_the_closed_form_of_fresh_oscillators():
    ds = ic.stability_map(paper(omega=2.5, b=0.2), 1, parameters=("R", "F0"),
                          grid={"R": [0.3, 0.5, 0.7, 0.9], "F0": [0.4, 0.8, 1.2, 1.6]})
    assert ds["amplitude_squared"].dims == ("N", "R", "F0")  # it depends on F0
    compared = _agrees_with_fresh_oscillators(
        ds, [1], lambda r, f: paper(omega=2.5, b=0.2, R=r, F=[f, 0.0]), "R", "F0", 12, 5)
    assert compared > 6


def test_an_omega_k2_map_batched_along_omega_holds_the_closed_form():
    ds = ic.stability_map(paper(), [1], parameters=("omega", "k2"),
                          grid={"omega": OMEGA, "k2": [0.8, 1.4]})
    assert ds["amplitude_squared"].dims == ("N", "omega", "k2")
    compared = _agrees_with_fresh_oscillators(
        ds, [1], lambda w, v: paper(omega=w, K=[[1.0, -1.0], [-1.0, 1.0 + v]]), "omega", "k2",
        12, 11)
    assert compared > 6


def test_a_b_omega_map_is_the_omega_b_map_transposed():
    # the same evaluation, batched along both: identical numbers
    osc = paper()
    plane = ic.stability_map(osc, [1, 2], OMEGA, GAP)
    turned = ic.stability_map(osc, [1, 2], parameters=("b", "omega"),
                              grid={"omega": OMEGA, "b": GAP})
    assert turned["exists"].dims == ("N", "b", "omega")
    xr.testing.assert_identical(
        turned.drop_vars("amplitude_squared").transpose("N", "omega", "b", "root").drop_attrs(),
        plane.drop_vars("amplitude_squared").drop_attrs())
    np.testing.assert_array_equal(turned["amplitude_squared"].isel(b=0).values,
                                  plane["amplitude_squared"].values)
    same = ic.stability_map(osc, [1, 2], parameters=("omega", "b"),
                            grid={"omega": OMEGA, "b": GAP})
    xr.testing.assert_identical(same.drop_attrs(), plane.drop_attrs())


def test_a_map_over_other_parameters_saves_loads_and_writes_to_a_file(tmp_path):
    pytest.importorskip("dask")
    osc = paper(omega=2.5)
    grid = {"k2": [0.8, 1.2, 1.6], "R": [0.4, 0.8]}
    ds = ic.stability_map(osc, [1, 2], parameters=("k2", "R"), grid=grid)
    ic.save(ds, tmp_path / "saved.nc")
    xr.testing.assert_identical(ic.load(tmp_path / "saved.nc").drop_attrs(), ds.drop_attrs())
    with ic.stability_map(osc, [1, 2], parameters=("k2", "R"), grid=grid,
                          out=tmp_path / "out.nc") as lazy:
        xr.testing.assert_identical(lazy.load().drop_attrs(), ds.drop_attrs())


@pytest.mark.parametrize(("call", "match"), [
    (lambda o: ic.stability_map(o, 1, [1.0, 2.0], [0.1, 0.2], k2=[1.0, 2.0]),
     r"parameters=\(p1, p2\), grid=.*\['k2'\]"),
    (lambda o: ic.stability_map(o, 1, parameters=("k2", "b"), grid={"k2": [1.0]}),
     r"grid must map each of the parameters \['k2', 'b'\]"),
    (lambda o: ic.stability_map(o, 1, [1.0, 2.0], parameters=("k2", "b"),
                                grid={"k2": [1.0], "b": [0.1]}),
     r"omega: with parameters=\('k2', 'b'\) give the grid of every parameter in grid="),
    (lambda o: ic.stability_map(o, 1, parameters=("k3", "b"), grid={"k3": [1.0], "b": [0.1]}),
     r"parameters='k3' names an element past the oscillator's n=2 masses"),
    (lambda o: ic.stability_map(o, 1, parameters=("k2", "k2"), grid={"k2": [1.0]}),
     r"parameters must be two different parameters"),
    (lambda o: ic.stability_map(o, 1, parameters="k2", grid={"k2": [1.0]}),
     r"parameters must be two parameter names"),
    (lambda o: ic.stability_map(o, 1, grid={"k2": [1.0], "b": [0.1]}),
     r"grid needs parameters=\(p1, p2\)"),
    (lambda o: ic.stability_map(o, 1, parameters=("k2", "b"),
                                grid={"k2": [2.0, 1.0], "b": [0.1]}),
     r"grid\['k2'\] must be strictly increasing"),
    (lambda o: ic.stability_map(o, 1, parameters=("R", "b"), grid={"R": [0.5, 1.5], "b": [0.1]}),
     r"grid\['R'\]: the oscillator cannot take R = 1.5"),
])
def test_bad_combinations_name_the_argument(call, match):
    with pytest.raises(ic.ParameterError, match=match):
        call(paper())


# -- a motion as the start: the map of its family -------------------------------------------
@pytest.fixture(scope="module")
def n1_motion():
    osc = paper(omega=1.2, b=0.3)
    return next(o for o in ic.periodic_orbits(osc, 1) if o.physical and o.stable)


GRID = {"omega": [1.1, 1.2, 1.3], "b": [0.2, 0.3, 0.4]}


def test_a_map_of_a_motion_is_the_map_of_its_family(n1_motion, tmp_path):
    family = ic.multi_impact_map(n1_motion, ("omega", "b"), GRID)
    by_keyword = ic.stability_map(n1_motion, parameters=("omega", "b"), grid=GRID)
    by_place = ic.stability_map(n1_motion, ("omega", "b"), GRID, tol=1e-11)
    assert family.attrs["impactcont_dataset"] == "multi_impact_map"
    for ds in (by_keyword, by_place):
        xr.testing.assert_identical(ds.drop_attrs(), family.drop_attrs())
    assert bool(by_keyword["found"].all())
    # the family's points are the closed form's motion of the same root there
    pytest.importorskip("dask")
    with ic.stability_map(n1_motion, parameters=("omega", "b"), grid=GRID,
                          out=tmp_path / "family.nc") as lazy:  # out= passed on
        xr.testing.assert_identical(lazy.load().drop_attrs(), family.drop_attrs())
        assert '"evaluator": "closed_form"' in lazy.attrs["options"]  # as in memory
    plane = ic.stability_map(n1_motion.oscillator, 1, GRID["omega"], GRID["b"])
    delta = plane["delta"].sel(N=1, root=n1_motion.root).values
    np.testing.assert_allclose(np.cos(by_keyword["delta"].values), np.cos(delta), atol=1e-9)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"N": 2}, r"N: a map of a motion's family takes parameters="),
    ({"omega": [1.0, 2.0]}, r"omega: a map of a motion's family"),
    ({"omega_block": 2}, r"omega_block: a map of a motion's family does not take it"),
    ({"spectral_radius": False}, r"spectral_radius: a map of a motion's family"),
    ({"k2": [1.0]}, r"takes the options .*of multi_impact_map; got \['k2'\]"),
])
def test_a_motion_refuses_the_arguments_of_the_oscillator_map(n1_motion, kwargs, match):
    with pytest.raises(ic.ParameterError, match=match):
        ic.stability_map(n1_motion, parameters=("omega", "b"), grid=GRID, **kwargs)
    with pytest.raises(ic.ParameterError, match="grid: a map of a motion's family needs grid"):
        ic.stability_map(n1_motion, parameters=("omega", "b"))
    with pytest.raises(ic.ParameterError, match="osc must be an ImpactOscillator, or a motion"):
        ic.stability_map("paper", 1, OMEGA, GAP)


def test_impactcont_plot_draws_a_map_over_other_parameters(tmp_path):
    from impactcont.scene.figures import draw_map, plot_file

    ds = ic.stability_map(paper(omega=1.2), [1, 2], parameters=("k2", "R"),
                          grid={"k2": [0.6, 1.0, 1.4, 1.8], "R": [0.3, 0.6, 0.9]})
    ic.save(ds, tmp_path / "k2_R.nc")
    written = plot_file(tmp_path / "k2_R.nc", tmp_path / "k2_R.png")
    assert [Path(p).read_bytes()[:8] for p in written] == [b"\x89PNG\r\n\x1a\n"]
    fig = draw_map({"maps": ds})
    panel = fig.axes[0]
    assert panel.get_xlabel() == "spring k2"
    assert panel.get_ylabel() == "coefficient of restitution $R$"
    assert panel.get_xlim()[0] < 0.6 < 1.8 < panel.get_xlim()[1]

"""The compiled map sweep (:func:`impactcont.kernel.sweep.sweep_stops`, driven by
:func:`impactcont.analysis.maps.multi_impact_map`) cell by cell.

Independent witness: :func:`impactcont.multi_impact_orbit` (Newton on the full shooting
system in Python, its own G and contact check) on an oscillator built afresh at the cell's
parameters. Three paths of the sweep: a two-sided 1-2 motion on its full system, the same
motion on its half system (symmetric), and a one-sided N-1 motion over ``(omega, R)`` (a flow
per omega and a stop geometry per R). The start of the 1-2 motion comes from the
event-driven simulator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.maps import multi_impact_map
from impactcont.model.stops import Stops

K2 = [[1.0, -1.0], [-1.0, 2.0]]
OMEGA = [1.5, 1.55, 1.6, 1.65]
B = [0.45, 0.5, 0.55]


def mirrored(omega: float, b: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=b,
                               omega=omega, stops=Stops(mirror=True))


@pytest.fixture(scope="module")
def start() -> ic.MultiImpactOrbit:
    """The symmetric 1-2 motion (pattern "LU") the simulator settles on at omega = 1.6."""
    osc = mirrored(1.6, 0.5)
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))


def _wrap(x):
    return np.arctan2(np.sin(x), np.cos(x))


def _compare(cell, orbit: ic.MultiImpactOrbit) -> None:
    """A map cell equals the motion Newton finds there (within Newton's tolerance and
    the conditioning of the two-parameter motion)."""
    assert bool(cell["found"])
    assert abs(_wrap(float(cell["delta"]) - orbit.delta)) < 1e-8
    np.testing.assert_allclose(cell["flight_time_k"].values, orbit.flight_times, atol=1e-8)
    np.testing.assert_allclose(cell["state_k"].values, orbit.states, atol=1e-8)
    np.testing.assert_allclose(cell["impact_velocity_k"].values, orbit.impact_velocities,
                               atol=1e-8)
    assert float(cell["gap_min"]) == pytest.approx(orbit.gap_min, abs=1e-8)
    assert float(cell["spectral_radius"]) == pytest.approx(orbit.spectral_radius, abs=1e-8)
    assert bool(cell["stable"]) == orbit.stable
    assert bool(cell["physical"]) == orbit.physical


@pytest.mark.parametrize("symmetric", [False, True])
def test_cells_are_the_motions_newton_finds(start, symmetric):
    ds = multi_impact_map(start, ("omega", "b"), grid={"omega": OMEGA, "b": B},
                          symmetric=symmetric)
    assert int(ds["found"].sum()) >= 10
    checked = 0
    for omega, b in [(1.5, 0.45), (1.55, 0.5), (1.6, 0.5), (1.65, 0.55), (1.65, 0.45)]:
        cell = ds.sel(omega=omega, b=b)
        orbit = ic.multi_impact_orbit(mirrored(omega, b), 1, 2, start, pattern=start.pattern)
        _compare(cell, orbit)
        checked += 1
    assert checked == 5
    if symmetric:  # the half system: the second impact is the mirror image of the first
        found = ds["found"].values
        states = ds["state_k"].values[found]
        np.testing.assert_array_equal(states[:, 1], -states[:, 0])
        assert np.all(ds["asymmetry"].values[found] == 0.0)


def test_one_sided_cells_over_a_flow_and_a_geometry_axis(paper):
    """An N-1 motion over ``(omega, R)``: omega changes the flow, R the stop geometry."""
    osc = paper.replace(omega=0.9, b=0.6)
    seed = next(o for o in ic.periodic_orbits(osc, 1) if o.physical and o.stable)
    grid = {"omega": [0.85, 0.9, 0.95], "R": [0.5, 0.6, 0.7]}
    ds = multi_impact_map(seed, ("omega", "R"), grid=grid, evaluator="shooting")
    assert bool(ds["found"].all())
    for omega in grid["omega"]:
        for R in grid["R"]:
            orbit = ic.multi_impact_orbit(osc.replace(omega=omega, R=R), 1, 1, seed)
            _compare(ds.sel(omega=omega, R=R), orbit)
            # and the closed form of the N-1 motion at the same point
            closed = min(ic.periodic_orbits(osc.replace(omega=omega, R=R), 1),
                         key=lambda o: abs(_wrap(o.delta - orbit.delta)))
            assert abs(_wrap(closed.delta - float(ds.sel(omega=omega, R=R)["delta"]))) < 1e-8


def test_max_change_refuses_every_neighbour(start):
    """A solution farther than ``max_change`` from its predictor is refused: with a tiny
    bound only the seed is found."""
    ds = multi_impact_map(start, ("omega", "b"), grid={"omega": OMEGA, "b": B},
                          max_change=1e-9, symmetric=False)
    assert int(ds["found"].sum()) == 1
    assert bool(ds.sel(omega=1.6, b=0.5)["found"])


def test_without_checks_no_gap_and_nothing_physical(start):
    ds = multi_impact_map(start, ("omega", "b"), grid={"omega": OMEGA[1:3], "b": B[:2]},
                          checks=False, symmetric=False)
    found = ds["found"].values
    assert found.all()
    assert np.all(np.isnan(ds["gap_min"].values))
    assert not ds["physical"].values.any()
    # the rest is computed as with the checks
    cell = ds.sel(omega=1.55, b=0.45)
    orbit = ic.multi_impact_orbit(mirrored(1.55, 0.45), 1, 2, start, pattern=start.pattern)
    assert float(cell["spectral_radius"]) == pytest.approx(orbit.spectral_radius, abs=1e-8)
    assert math.isnan(float(cell["gap_min"]))

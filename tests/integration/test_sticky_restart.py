"""A branch of motions with sticking phases restarts from any of its points: its stick times
are unknowns of the shooting system, and the restart read only the phases, flight times and
states (the stored motion's residual was 3.9, and ``continuation_from`` and ``extend``
failed: "Newton failed at the start point"). Both ways a stick is entered: the plastic
ride (R = 0) and the ride entered through complete chatter (R = 0.3)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.branch import restart_problem
from tests.integration.test_chatter_entered_motions import damper, riding_start


def _riding(osc: ic.ImpactOscillator) -> ic.MultiImpactOrbit:
    """The ball riding each wall ("lu"), from its simulated steady state."""
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 16.0))


@pytest.fixture(scope="module", params=[(1.2, 0.0, 0.1), (0.2, 0.3, 0.02)],
                ids=["plastic", "chatter-entered"])
def ride(request) -> xr.Dataset:
    omega, R, half = request.param
    start = _riding(damper(omega, R))
    assert start.physical and start.pattern == "lu"
    return ic.continuation(start, parameter="omega", bounds=(omega - half, omega + half),
                           ds_max=half / 4, detect=())


def test_every_stored_motion_solves_its_shooting_system(ride):
    for row in range(ride.sizes["point"]):
        problem, u, lam = restart_problem(ride, row)
        assert np.abs(problem.residual(u, lam)).max() < 1e-9, row


def test_a_restart_reproduces_the_points_beyond_it(ride):
    k = ride.sizes["point"] // 2
    again = ic.continuation_from(ride, k, bounds=(float(ride.omega.min()),
                                                  float(ride.omega.max())), detect=())
    assert again.sizes["point"] >= 3
    # every restarted point lies on the branch: its motion at that omega agrees with the
    # branch's (the branch is a graph over omega here: no fold)
    omega = ride.omega.values
    order = np.argsort(omega)
    for j in range(again.sizes["point"]):
        w = float(again.omega.values[j])
        delta = float(np.interp(w, omega[order], ride.delta.values[order]))
        assert abs(float(again.delta.values[j]) - delta) < 1e-3, (w, delta)


def test_an_extension_continues_past_the_old_bounds(ride):
    lo, hi = float(ride.omega.min()), float(ride.omega.max())
    wider = ic.extend(ride, bounds=(lo - 0.01, hi + 0.01), detect=())
    assert float(wider.omega.min()) < lo and float(wider.omega.max()) > hi

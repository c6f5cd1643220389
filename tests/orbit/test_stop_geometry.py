"""Clearances between two masses (issue 21): the two-body impact law at every simulated
impact (momentum, restitution of the relative velocity, energy), the flights against
solve_ivp, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from tests.orbit.test_flow import _ivp

M = np.diag([1.0, 0.4])
K = np.array([[1.5, -0.5], [-0.5, 0.5]])  # both masses held by springs


def _pair(**kw):
    params = {"M": M, "K": K, "F": [1.0, 0.0], "R": 0.7, "b": 0.2, "omega": 1.2,
              "stops": Stops(mass=2, relative_to=1, b_low=0.25, R_low=0.5)}
    if "C" not in kw:
        params["eta"] = 0.03
    return ic.ImpactOscillator(**{**params, **kw})


def test_impact_matrix_is_the_rigid_two_body_law_and_eq4_at_a_wall():
    stops = Stops(mass=2, relative_to=1)
    np.testing.assert_array_equal(stops.normal(3), [-1.0, 1.0, 0.0])
    Mf = np.diag([2.0, 0.5, 1.0])
    D = stops.impact_matrix(Mf, 0.6)
    v = np.array([0.3, -1.1, 0.7])
    w = D @ v
    assert np.sum(Mf @ w) == pytest.approx(np.sum(Mf @ v), abs=1e-15)  # total momentum
    np.testing.assert_allclose(w[1] - w[0], -0.6 * (v[1] - v[0]), rtol=1e-14)
    assert w[2] == v[2]
    # a wall stop: eq. (4) for any M (non-diagonal M keeps eq. 4 as documented)
    wall = Stops(mass=2)
    for Mw in (Mf, np.array([[2.0, 0.1, 0.0], [0.1, 0.5, 0.0], [0.0, 0.0, 1.0]])):
        np.testing.assert_array_equal(wall.impact_matrix(Mw, 0.6), np.diag([1.0, -0.6, 1.0]))


@pytest.mark.parametrize("damping", [{"eta": 0.03}, {"C": [[0.05, -0.02], [-0.02, 0.04]]}])
def test_every_pair_impact_conserves_momentum_and_restitutes_the_relative_velocity(damping):
    osc = _pair(**damping)
    res = ic.simulate(osc, np.zeros(4), 0.0, 12.0)
    assert res.impact_times.size >= 6 and set(res.impact_stops) == {"U", "L"}
    flow = Flow(osc)
    start, phase, t0 = np.zeros(4), 0.0, 0.0
    mu = 1.0 / (1.0 / M[0, 0] + 1.0 / M[1, 1])  # reduced mass of the pair
    for k, stop in enumerate(res.impact_stops[:6]):
        tau = res.impact_times[k] - t0
        before = _ivp(osc, start, phase, tau)(tau)  # independent witness of the flight
        after = res.impact_states[k]
        np.testing.assert_allclose(flow.state(tau, start, phase)[0], before, rtol=0,
                                   atol=1e-8)
        level = osc.b if stop == "U" else -osc.stops.b_low
        assert after[1] - after[0] == pytest.approx(level, abs=1e-14)
        np.testing.assert_allclose(before[:2], after[:2], rtol=0, atol=1e-8)
        R = osc.R if stop == "U" else osc.stops.R_low
        s_before, s_after = before[3] - before[2], after[3] - after[2]
        assert s_after == pytest.approx(-R * s_before, rel=1e-7)
        assert np.sum(M @ after[2:]) == pytest.approx(np.sum(M @ before[2:]), abs=1e-8)
        # energy lost at the impact: (1 - R^2) mu s'^2 / 2
        loss = 0.5 * before[2:] @ M @ before[2:] - 0.5 * after[2:] @ M @ after[2:]
        assert loss == pytest.approx(0.5 * (1 - R * R) * mu * s_before**2, rel=1e-7)
        assert res.impact_velocities[k] == pytest.approx(
            s_before if stop == "U" else -s_before, rel=1e-7)
        start, phase, t0 = after, res.impact_phases[k], res.impact_times[k]


def test_the_pair_coordinate_stays_in_the_clearance():
    osc = _pair()
    res = ic.simulate(osc, np.zeros(4), 0.0, 8.0, trajectory=True, samples_per_period=400)
    s = res.X[:, 1] - res.X[:, 0]
    assert s.max() <= osc.b + 1e-12 and s.min() >= -osc.stops.b_low - 1e-12


def test_bad_pairs_are_refused():
    with pytest.raises(ParameterError, match="a stop between a mass and itself"):
        Stops(mass=2, relative_to=2)
    with pytest.raises(ParameterError, match=r"stops.relative_to must be in 1..2"):
        _pair(stops=Stops(mass=1, relative_to=3))
    with pytest.raises(ParameterError, match="clearance that closes"):
        _pair(stops=Stops(mass=2, relative_to=1, b_low=-0.3))
    with pytest.raises(ParameterError, match="relative_to must be None"):
        Stops(mass=2, relative_to=0)
    with pytest.raises(ParameterError, match="beyond the stop"):
        ic.simulate(_pair(), [0.0, 0.5, 0.0, 0.0], 0.0, 1.0)


def test_pair_stops_are_serialised_and_refused_by_the_closed_form():
    osc = _pair()
    again = ic.ImpactOscillator.from_dict(osc.to_dict())
    assert again.stops == osc.stops and again.stops.relative_to == 1
    assert "relative_to=1" in repr(osc)
    with pytest.raises(ParameterError, match="multi_impact_orbit"):
        ic.periodic_orbits(osc, 1)


@pytest.mark.parametrize("stops, change", [
    (Stops(mirror=True), {"b": 0.7}),                       # both stops move with b
    (Stops(b_low=0.8), {"b": 0.6}),                         # the upper stop alone
    (Stops(mass=2, relative_to=1, b_low=0.5), {"b": 0.3}),  # a clearance between masses
    (Stops(mirror=True), {"R": 0.4}),                       # another restitution: rebuilt
])
def test_a_moved_geometry_is_the_one_built_afresh(stops, change):
    from impactcont.orbit.stop_geometry import moved_stop_geometry, stop_geometry
    before = ic.ImpactOscillator(M=np.diag([1.0, 2.0]), K=[[2.0, -1.0], [-1.0, 1.0]],
                                 F=[1.0, 0.0], R=0.6, b=0.5, omega=1.2, eta=0.1, stops=stops)
    osc = before.replace(**change)
    pattern = "ULLU"
    moved = moved_stop_geometry(stop_geometry(before, pattern), before, osc, pattern)
    fresh = ic.orbit.stop_geometry._stop_geometry(osc, pattern)
    for name in ("pivots", "normals", "signs", "positions", "matrices", "normal",
                 "extra_normals", "extra_signs", "extra_positions"):
        np.testing.assert_array_equal(getattr(moved, name), getattr(fresh, name), err_msg=name)
        assert not getattr(moved, name).flags.writeable
    assert (moved.b, moved.b_low, moved.two_sided, moved.extra_names) == \
        (fresh.b, fresh.b_low, fresh.two_sided, fresh.extra_names)
    assert stop_geometry(osc, pattern) is moved  # kept for the oscillator

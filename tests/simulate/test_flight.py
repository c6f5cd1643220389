"""The simulator's own flight (:mod:`impactcont.simulate.flight`): the matrix exponential
of the forced system as one autonomous linear system, its eigenvalues as the fast path.

Both evaluations find the same impacts; a defective system (an undamped free mass under a
constant force) keeps its closed form on the exact path.
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.oscillator import ImpactOscillator
from impactcont.simulate import flight as flight_module
from impactcont.simulate import simulate


def _slow_path(monkeypatch):
    """Every evaluation through the matrix exponential (no eigenvector is trusted)."""
    monkeypatch.setattr(flight_module, "_COND_LIMIT", 0.0)


@pytest.mark.parametrize("params", [
    {"eta": 0.1, "b": 0.2},
    {"C": [[0.3, -0.1], [-0.1, 0.05]], "F": [1.0, 0.3j], "F_static": [0.05, 0.0], "b": 0.2},
], ids=["modal", "any-C-static"])
def test_both_evaluations_of_the_flight_find_the_same_impacts(monkeypatch, params):
    """The fast path (eigenvalues of A) and the matrix exponential at every evaluation find
    the same impacts over 30 forcing periods: the same stops, times to 1e-11."""
    osc = ImpactOscillator(**{"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0],
                              "R": 0.6, "b": 0.6, "omega": 1.3, **params})
    assert flight_module.Flight(osc).fast
    fast = simulate(osc, np.zeros(4), 0.3, 30.0)
    _slow_path(monkeypatch)
    assert not flight_module.Flight(osc).fast
    slow = simulate(osc, np.zeros(4), 0.3, 30.0)
    assert fast.impact_stops == slow.impact_stops and fast.impact_times.size > 10
    np.testing.assert_allclose(fast.impact_times, slow.impact_times, rtol=0, atol=1e-11)
    np.testing.assert_allclose(fast.impact_velocities, slow.impact_velocities, rtol=1e-10)


def test_a_free_mass_under_a_constant_force_is_exact():
    """An undamped free mass drifting under a constant force makes A defective (a Jordan
    block at 0): the flight is the matrix exponential, and the bounces of a ball on a
    still table under gravity 1 keep their closed form, flights 2 v / g, v -> R v."""
    ball = ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[0.0], F_static=[-1.0], R=0.8, b=100.0,
                            omega=1.0, stops=ic.Stops(b_low=0.0, R_low=0.8))
    assert not flight_module.Flight(ball).fast
    res = simulate(ball, [0.0, 3.0], 0.0, 4.0)
    speeds = 3.0 * 0.8 ** np.arange(8)
    np.testing.assert_allclose(res.impact_times[:8], np.cumsum(2.0 * speeds), rtol=1e-13)
    np.testing.assert_allclose(res.impact_velocities[:8], speeds, rtol=1e-13)

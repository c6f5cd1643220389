"""The simulator's own flight (:mod:`impactcont.simulate.flight`): the matrix exponential
of the forced system as one autonomous linear system, its eigenvalues as the fast path.

Both evaluations find the same impacts; a defective system (an undamped free mass under a
constant force) keeps its closed form on both paths; an undamped free mass splits off with
its polynomial part exact (issue 30, item 5: it was the matrix exponential at every step).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

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


@pytest.mark.parametrize("fast", [True, False], ids=["polynomial", "expm"])
def test_a_free_mass_under_a_constant_force_is_exact(monkeypatch, fast):
    """An undamped free mass drifting under a constant force makes A defective (a Jordan
    block at 0): the flight splits the free mode off, its polynomial part exact (or, with
    the split switched off, is the matrix exponential), and the bounces of a ball on a
    still table under gravity 1 keep their closed form, flights 2 v / g, v -> R v."""
    ball = ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[0.0], F_static=[-1.0], R=0.8, b=100.0,
                            omega=1.0, stops=ic.Stops(b_low=0.0, R_low=0.8))
    if not fast:
        monkeypatch.setattr(flight_module, "_split_free", lambda *args: None)
    flight = flight_module.Flight(ball)
    assert flight.fast == fast and (flight.chains is not None) == fast
    res = simulate(ball, [0.0, 3.0], 0.0, 4.0)
    speeds = 3.0 * 0.8 ** np.arange(8)
    np.testing.assert_allclose(res.impact_times[:8], np.cumsum(2.0 * speeds), rtol=1e-13)
    np.testing.assert_allclose(res.impact_velocities[:8], speeds, rtol=1e-13)


_DAMPER = {"M": np.diag([1.0, 0.5, 0.2]),
           "K": [[2.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.0]],
           "C": np.diag([0.1, 0.0, 0.0]), "F": [1.0, 0.3j, 0.0], "R": 0.6, "b": 0.3,
           "omega": 0.9, "stops": ic.Stops(mass=3, relative_to=2, mirror=True)}


@pytest.mark.parametrize("params", [
    {},  # a two-mass primary with a dashpot on mass 1, a free ball in a cavity of mass 2
    {"F_static": [0.1, 0.0, -0.05]},  # and gravity on the ball: g t^2 / 2
    {"C": np.diag([0.1, 0.0, 0.02]), "F_static": [0.1, 0.0, 0.0]},  # the ball damped
], ids=["undamped-ball", "undamped-ball-gravity", "damped-ball"])
def test_the_split_flight_is_the_matrix_exponential(params):
    """The fast path of an undamped free ball (was every evaluation a matrix exponential):
    the state, a stop coordinate's four derivatives and the state by StopMotion against
    expm(A t) Y(0) up to t = 60 (the drift grows: relative to the motion's size), and
    a damped ball still as before (the eigenvectors of A, no polynomial part)."""
    osc = ImpactOscillator(**{**_DAMPER, **params})
    flight = flight_module.Flight(osc)
    undamped = "C" not in params
    assert flight.fast and (flight.chains is not None) == undamped
    X = np.linspace(-0.3, 0.5, 6)
    t = np.array([0.0, 0.3, 2.0, 17.0, 60.0])
    Y0 = flight.start(X, 0.4)
    ref = np.array([scipy.linalg.expm(flight.A * tt) @ Y0 for tt in t])
    rates = ref @ flight.A.T
    size = np.abs(ref).max(axis=1)
    np.testing.assert_allclose(flight.samples(t, X, 0.4), ref[:, :6], rtol=0,
                               atol=1e-13 * size.max())
    s = flight.motion(X, 0.4, osc.stops.normal(3)).derivatives(t)
    expect = (ref[:, 2] - ref[:, 1], ref[:, 5] - ref[:, 4], rates[:, 5] - rates[:, 4],
              (rates @ flight.A.T)[:, 5] - (rates @ flight.A.T)[:, 4])
    for got, want in zip(s, expect, strict=True):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * size.max())
    motion = flight.motion(X, 0.4, osc.stops.normal(3))
    np.testing.assert_allclose(motion.state(17.0), ref[3, :6], rtol=0, atol=1e-13 * size[3])
    # the central difference of the stop coordinate is its derivative
    h = 1e-6
    fd = (motion.derivatives(t + h)[0] - motion.derivatives(t - h)[0]) / (2 * h)
    np.testing.assert_allclose(fd, s[1], rtol=0, atol=1e-8 * size.max())



def test_both_evaluations_find_the_same_impacts_of_an_undamped_free_ball(monkeypatch):
    """The split flight (polynomial part) and the matrix exponential at every evaluation
    find the same impacts of the ball of a two-mass primary with a dashpot on mass 1 over
    six forcing periods from a state near its periodic motion: the same stops, times to
    1e-11, velocities to 1e-10."""
    osc = ImpactOscillator(**{**_DAMPER, "F": [1.0, 0.0, 0.0], "b": 1.0, "R": 0.8,
                              "omega": 2.0})
    X0 = np.array([0.4409, 0.165, -0.835, -0.1653, -0.2599, 1.0632])  # s = x3 - x2 = -1
    assert flight_module.Flight(osc).chains is not None
    fast = simulate(osc, X0, 3.1359, 6.0)
    _slow_path(monkeypatch)
    assert not flight_module.Flight(osc).fast
    slow = simulate(osc, X0, 3.1359, 6.0)
    assert fast.impact_stops == slow.impact_stops and fast.impact_times.size >= 10
    np.testing.assert_allclose(fast.impact_times, slow.impact_times, rtol=0, atol=1e-11)
    np.testing.assert_allclose(fast.impact_velocities, slow.impact_velocities, rtol=1e-10)

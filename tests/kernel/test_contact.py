"""The interior-contact check (eq. 16) where a constant force pushes a free mode: the stop
coordinate then carries a polynomial in time (``g t^2 / 2`` undamped, the drift
``g t^2 phi(2at) / 2`` damped, ``d t`` on the first-order flow), which the contact search
now represents exactly.

The machine is the bouncing ball of Holmes (1982): a ball under gravity ``g`` on a table
vibrating harmonically, written in the table's frame (``z = x_ball - x_table``: one free
mass, ``K = [[0]]``, ``F_static = [-g]``, the table's acceleration as the harmonic force
``F``, the table a lower stop at ``z = 0`` with restitution R). Its period-1 motions are
in closed form: the ball leaves the table at ``v = R g T / (1 + R)`` with the phase
``sin(delta) = pi g (R - 1) / ((1 + R) F)``, two of them where ``F >= pi g (1 - R) /
(1 + R)`` (Holmes, J. Sound Vib. 84 (1982) 173-189, eq. 2.5 in his units). Between the
impacts ``z(t) = F (cos(delta) - cos(omega t + delta)) / omega^2 + g t (T - t) / 2``: with a
strong table the second motion's table overtakes the ball mid-flight (no such motion).

Witnesses: the closed form (phases), a dense sampling of the exact flow (``Flow.state``,
1e5 + 1 points a flight) for where the ball crosses the table and how deep, the two flows
(modal and first-order) against each other with damping, and the event-driven simulator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.orbit.flow import flow_of
from impactcont.orbit.multi_impact import multi_impact_orbit

G = 0.5  # gravity
R = 0.5  # restitution of the table
OMEGA = 1.0
T = 2.0 * math.pi / OMEGA
SAMPLES = 100_001


def _ball(F: float, **damping) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[F], F_static=[-G], R=R, b=100.0,
                               omega=OMEGA, stops=Stops(mass=1, b_low=0.0, R_low=R), **damping)


def _holmes_phases(F: float) -> tuple[float, float]:
    """The two period-1 phases of Holmes' closed form (undamped)."""
    s = math.pi * G * (R - 1.0) / ((1.0 + R) * F)
    return math.asin(s), math.pi - math.asin(s)


def _period_one(osc: ic.ImpactOscillator, delta: float):
    v = R * G * T / (1.0 + R)
    return multi_impact_orbit(osc, 1, 1, {"delta": delta, "flight_times": [T],
                                          "states": [[0.0, v]], "pattern": "L"})


def _dense(orbit) -> tuple[np.ndarray, np.ndarray, float]:
    """Times and ``z`` of the flight sampled densely with the exact flow, and the bound
    ``h^2 max|z''| / 8`` on how far the sampled minimum lies above the true one."""
    t = np.linspace(0.0, float(orbit.flight_times[0]), SAMPLES)
    z = flow_of(orbit.oscillator).state(t, orbit.states[0], float(orbit.phases[0]))[:, 0]
    F = float(orbit.oscillator.F[0].real)
    return t, z, (t[1] - t[0]) ** 2 * (abs(F) + G) / 8.0


def _interior_minimum(t: np.ndarray, z: np.ndarray) -> float:
    """The lowest interior local minimum of the sampled ``z`` (inf when none)."""
    inner = (z[1:-1] <= z[:-2]) & (z[1:-1] <= z[2:])
    return float(z[1:-1][inner].min()) if inner.any() else math.inf


def _check_against_dense(orbit) -> bool:
    """The kernel's verdict and lower gap against the dense sampling; returns whether the
    sampling finds the ball below the table inside the flight."""
    t, z, slack = _dense(orbit)
    crossing = bool(np.any(z[1:-1] < 0.0))
    assert orbit.physical == (not crossing), orbit.reason
    assert "not checked" not in orbit.reason
    if crossing:
        assert "reaches a stop inside the flight" in orbit.reason
    low = _interior_minimum(t, z)
    gap = float(orbit.flight_gap_lower[0])
    if math.isinf(low):
        assert gap == math.inf
    else:
        # the polished minimum is the true one (to rounding): at most the sampled one, and
        # below it by no more than the sampling's own error
        tol = 1e-12 * max(1.0, abs(low))
        assert low - slack - tol <= gap <= low + tol
    return crossing


@pytest.mark.parametrize("F", [1.0, 1.252, 1.2522, 3.0])
def test_bouncing_ball_period_one_checked_against_dense_sampling(F):
    """Both period-1 motions of Holmes' closed form: physical where the dense sampling of
    the flight stays above the table, not physical where it finds the ball below it
    (F = 1.2522 dips by 1e-4 over 1% of the flight, F = 3 by 3.5), with the lower gap the
    sampling's minimum within the sampling's error."""
    osc = _ball(F)
    crossings = []
    for delta in _holmes_phases(F):
        orbit = _period_one(osc, delta)
        assert orbit.residual < 1e-12 and orbit.impact_velocity > 0
        assert math.remainder(float(orbit.phases[0]) - delta, 2 * math.pi) == pytest.approx(
            0.0, abs=1e-10)
        crossings.append(_check_against_dense(orbit))
    # the first motion (table moving down at the impact) never dips; the second does from
    # F ~ 1.2521 on
    assert crossings == [False, F > 1.2521]


@pytest.mark.parametrize("F", [1.0, 3.0])
def test_damped_free_mode_with_drift_both_flows(F):
    """A damped free mode (C = 0.1 M: its decay a = 0.05, the constant force's response
    the drift ``g t^2 phi(2at) / 2``) on the modal flow and the same damping as a matrix C on
    the first-order flow (a linear drift ``d t`` of the stop coordinate): the same motions,
    the same gaps, each against the dense sampling."""
    modal, general = _ball(F, alpha=0.1), _ball(F, C=[[0.1]])
    assert flow_of(modal).a[0] == pytest.approx(0.05) and flow_of(modal).free[0]
    assert abs(flow_of(general).drift[0]) > 0.1  # g / c: the free mode's drift speed
    for delta in _holmes_phases(F):
        a, b = _period_one(modal, delta), _period_one(general, delta)
        assert a.residual < 1e-10 and b.residual < 1e-10
        np.testing.assert_allclose(b.states, a.states, rtol=0, atol=1e-10)
        assert b.flight_gap_lower[0] == pytest.approx(a.flight_gap_lower[0], rel=0, abs=1e-10)
        assert b.flight_gap_min[0] == pytest.approx(a.flight_gap_min[0], rel=0, abs=1e-10)
        assert _check_against_dense(a) == _check_against_dense(b)


@pytest.mark.parametrize("F, lands_early", [(1.252, False), (1.2524, True)])
def test_simulated_ball_lands_where_the_kernel_says(F, lands_early):
    """The event-driven simulator from the start of the second motion: where the kernel
    finds an interior contact the simulated ball lands inside the flight, at the first
    crossing of the dense sampling (a dip of 5e-4), else after the whole flight T."""
    osc = _ball(F)
    orbit = _period_one(osc, _holmes_phases(F)[1])
    assert orbit.physical == (not lands_early)
    t, z, _ = _dense(orbit)
    res = ic.simulate(osc, orbit.states[0], float(orbit.phases[0]), 1.5)
    first = float(res.impact_times[0])
    assert res.impact_stops[0] == "L"
    if lands_early:
        i = int(np.flatnonzero(z[1:] < 0.0)[0]) + 1  # z[i - 1] >= 0 > z[i]
        assert t[i - 1] <= first <= t[i]
        assert first < float(orbit.flight_gap_min_times[0])  # before the deepest point
    else:
        assert first == pytest.approx(T, rel=0, abs=1e-9)

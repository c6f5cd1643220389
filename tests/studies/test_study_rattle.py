"""The rattle study (studies/rattle): the bouncing ball on a vibrating table as a free mass
under a constant force, against its closed form (Holmes 1982; Tufillaro, Mello, Choi &
Albano 1986): the period-N one-impact motion has ``-Gamma sin(delta) = N pi (1-R)/(1+R)``,
impact velocity ``2 pi N/(1+R)``, an impact map with determinant ``R^2`` and trace
``1 + R^2 - (1+R)^2 Gamma cos(delta)``, and doubles its period at
``Gamma_2^2 = (N pi (1-R)/(1+R))^2 + (2 (1+R^2)/(1+R)^2)^2``.

The witness is the closed form itself (derived independently of the shooting code); the
Newton guesses know nothing of it (phase 0, the ball leaving at the mean launch speed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic

R = 0.5


def _ball(gamma: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[gamma], F_static=[-1.0], R=R,
                               b=1000.0, omega=1.0, stops=ic.Stops(b_low=0.0, R_low=R))


def _orbit(gamma: float, N: int) -> ic.MultiImpactOrbit:
    guess = {"delta": 0.0, "flight_times": [2 * math.pi * N], "states": [[0.0, math.pi * N]]}
    orb = ic.multi_impact_orbit(_ball(gamma), N, 1, guess, pattern="L")
    assert orb.residual < 1e-10
    return orb


def _gamma_2(N: int) -> float:
    return math.hypot(N * math.pi * (1 - R) / (1 + R), 2 * (1 + R * R) / (1 + R) ** 2)


@pytest.mark.parametrize(("gamma", "N"), [(1.1, 1), (1.5, 1), (2.25, 2)])
def test_period_N_motion_matches_the_closed_form(gamma, N):
    orb = _orbit(gamma, N)
    delta = -math.asin(N * math.pi * (1 - R) / (gamma * (1 + R)))  # the stable root
    tol = 1e-9  # Newton's guarantee (error_estimate ~1e-15 here), far above rounding
    assert orb.error_estimate < tol
    assert abs(math.remainder(orb.delta - delta, 2 * math.pi)) < tol
    assert orb.impact_velocities[0] == pytest.approx(2 * math.pi * N / (1 + R), abs=tol)
    assert orb.states[0][1] == pytest.approx(2 * math.pi * N * R / (1 + R), abs=tol)
    assert orb.flight_times[0] == pytest.approx(2 * math.pi * N, abs=tol)
    trace = 1 + R * R - (1 + R) ** 2 * gamma * math.cos(delta)
    mult = np.asarray(orb.multipliers, complex)
    assert mult.sum().real == pytest.approx(trace, abs=tol)
    assert np.prod(mult).real == pytest.approx(R * R, abs=tol)
    assert orb.stable == (gamma < _gamma_2(N))


@pytest.mark.parametrize("N", [1, 2])
def test_period_doubling_threshold_against_the_multipliers(N):
    g2 = _gamma_2(N)
    at = _orbit(g2, N)
    assert float(np.min(np.abs(np.asarray(at.multipliers) + 1))) < 1e-9
    assert _orbit(g2 - 1e-4, N).stable
    assert not _orbit(g2 + 1e-4, N).stable


def test_period_doubling_curve_in_gamma_and_restitution_is_holmes_closed_form():
    """The PD point followed in two parameters (Gamma = F0, the table's restitution R_low):
    every curve point on ``Gamma_2(R)``, and the fold of the same branch on
    ``Gamma_1(R) = pi (1-R)/(1+R)`` (the free mass and the constant force on the curve
    path, issue 21)."""
    branch = ic.multi_impact_continuation(_orbit(1.3, 1), "F0", (1.0, 2.0))
    labels = [str(v) for v in branch.special_label.values]
    assert labels == ["SN", "PD"]
    assert float(branch.special_F0.values[0]) == pytest.approx(math.pi / 3, abs=1e-8)
    curve = ic.multi_impact_curve(branch, "PD", 0, parameter="R_low",
                                  bounds={"F0": (1.0, 3.0), "R_low": (0.2, 0.8)},
                                  max_points=40)
    r = curve.R_low.values
    gamma_2 = np.hypot(math.pi * (1 - r) / (1 + r), 2 * (1 + r * r) / (1 + r) ** 2)
    assert curve.sizes["point"] >= 10 and r.min() < 0.25 and r.max() > 0.75
    np.testing.assert_allclose(curve.F0.values, gamma_2, rtol=1e-8)

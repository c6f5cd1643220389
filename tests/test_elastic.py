"""Elastic impacts without damping (R = 1, C = 0): eq. (12) is singular, the motions are not.

For R = 1 and no damping ``I - D U W(T) U^-1`` is singular at every omega (in modal
form ``Delta = (1 - R)/2 + kappa sum c_i h_i = 0``); the periodic motions are
isolated and fixed by ``x1p'(delta) = 0`` and the impact condition. Witnesses:
the published closed form for one mass (Budd & Dux), the exact event-driven
impact map (fixed point, finite-difference G), and the limit of vanishing damping.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_periodic import section_point, simulated_impact_map, simulated_map_jacobian

import impactcont as ic


def _one_mass(omega: float, b: float, **params) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[1.0], R=1.0, b=b, omega=omega, **params)


def _budd_dux(omega: float, b: float, N: int) -> list[float]:
    """V = -(b -+ gamma)(1 - cos T)/sin T, gamma = 1/(1 - omega^2), T = 2 pi N / omega."""
    gamma = 1.0 / (1.0 - omega**2)
    T = 2.0 * math.pi * N / omega
    return [-(b - sign * gamma) * (1.0 - math.cos(T)) / math.sin(T) for sign in (+1, -1)]


@pytest.mark.parametrize(("omega", "b", "N"), [(2.8, 0.05, 1), (2.8, 0.05, 2), (1.5, -0.2, 1),
                                               (0.7, 0.3, 1), (3.3, -0.1, 3)])
def test_one_mass_matches_the_published_closed_form(omega, b, N):
    osc = _one_mass(omega, b)
    orbits = ic.periodic_orbits(osc, N)
    assert len(orbits) == 2
    expected = sorted(_budd_dux(omega, b, N))
    for orbit, v in zip(sorted(orbits, key=lambda o: o.impact_velocity), expected, strict=True):
        assert orbit.impact_velocity == pytest.approx(v, rel=1e-12)
        assert orbit.state[0] == pytest.approx(b, abs=1e-14)
        # the phase: the forced motion gamma cos(omega t + delta) of the mass is at rest
        assert math.sin(orbit.delta) == pytest.approx(0.0, abs=1e-15)


def test_one_mass_issue_case_is_the_published_velocity():
    """The case reported wrong before: omega = 2.8, b = 0.05 -> 0.19976 (was 0.1429)."""
    physical = [o for o in ic.periodic_orbits(_one_mass(2.8, 0.05), 1) if o.physical]
    assert len(physical) == 1
    assert physical[0].impact_velocity == pytest.approx(0.19976, abs=5e-6)


def _elastic_chain(n: int, omega: float, b: float) -> ic.ImpactOscillator:
    rng = np.random.default_rng(7 + n)
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=1.0 + 0.5 * rng.random(n),
                                     springs=1.0 + rng.random(n), F=F, R=1.0, b=b, omega=omega)


@pytest.mark.parametrize(("n", "omega", "b"), [(1, 2.8, 0.05), (2, 2.3, 0.1), (3, 2.9, 0.05),
                                               (3, 1.7, -0.1)])
def test_elastic_motions_are_fixed_points_of_the_exact_impact_map(n, omega, b):
    osc = _elastic_chain(n, omega, b)
    orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2
    checked = 0
    for orbit in orbits:
        # periodicity through the exact flow, whatever the physical flag
        X_T = ic.Flow(osc).state(orbit.period, orbit.state, orbit.delta)[0]
        assert X_T[0] == pytest.approx(b, abs=1e-12)
        assert X_T[n] == pytest.approx(orbit.impact_velocity, rel=1e-12, abs=1e-13)
        X_plus = X_T.copy()
        X_plus[n] *= -1.0
        np.testing.assert_allclose(X_plus, orbit.state, atol=1e-12)
        if not (orbit.physical and orbit.impact_velocity > 0.05 and orbit.gap_min > 0.01):
            continue
        checked += 1
        z0 = section_point(orbit)
        np.testing.assert_allclose(simulated_impact_map(osc, 1, z0), z0, atol=1e-11)
        fd = simulated_map_jacobian(osc, 1, z0)
        assert np.abs(fd - orbit.G).max() < 1e-7 * max(1.0, np.abs(orbit.G).max())
        # area preserving: det G = R^2 exp(-T tr M^-1 C) = 1
        assert abs(np.prod(orbit.multipliers)) == pytest.approx(1.0, rel=1e-9)
    assert checked >= 1 or n == 3


@pytest.mark.parametrize("eta", [1e-6, 1e-9])
def test_vanishing_damping_tends_to_the_elastic_motions(eta):
    """Light damping is a regular case; its motions converge to the elastic ones (O(eta))."""
    elastic = ic.periodic_orbits(_elastic_chain(2, 2.3, 0.1), 1)
    damped = ic.periodic_orbits(_elastic_chain(2, 2.3, 0.1).replace(eta=eta), 1)
    by_velocity = sorted(damped, key=lambda o: o.impact_velocity)
    for e, d in zip(sorted(elastic, key=lambda o: o.impact_velocity), by_velocity, strict=True):
        assert abs(math.remainder(e.delta - d.delta, 2 * math.pi)) < 1e3 * eta
        assert d.impact_velocity == pytest.approx(e.impact_velocity, rel=1e3 * eta)


def test_no_forced_motion_of_mass_one_is_refused():
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, 0.0], [0.0, 3.0]], F=[0.0, 1.0], R=1.0, b=0.1,
                              omega=1.3)
    with pytest.raises(ic.ParameterError, match="no forced motion of mass 1"):
        ic.periodic_orbits(osc, 1)


@pytest.mark.parametrize(("parameter", "bounds", "params"), [
    ("omega", (2.0, 3.0), {}), ("b", (0.0, 0.2), {}), ("R", (0.5, 1.0), {}),
    ("eta", (0.0, 0.1), {"eta": 0.05})])
def test_continuation_into_the_elastic_undamped_case_is_refused(parameter, bounds, params):
    osc = _one_mass(2.8, 0.05, **params)
    if parameter == "R":
        osc = osc.replace(R=0.7)
    with pytest.raises(ic.ParameterError, match="elastic impacts without damping"):
        ic.continuation(osc, 1, parameter, bounds)


def test_continuation_with_restitution_below_one_is_not_refused():
    osc = _one_mass(2.8, 0.05).replace(R=0.7)
    assert ic.continuation(osc, 1, "R", (0.5, 0.9)).sizes["point"] > 1

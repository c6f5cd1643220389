"""studies/vi_nes: the two-impact (UL) motions of a vibro-impact energy sink in closed
form (derived in the study: one scalar equation in the first flight time, the stability by
central differences of the closed-form return map) against ``multi_impact_orbit``, its
multipliers and its stability verdict.

The closed form is an independent witness (``studies/vi_nes/closed_form.py``, numpy and
scipy only, no code shared with the package). Three machines: symmetric walls, walls of
unequal restitution, a vertical VI-NES (gravity, ``F_static``)."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic

HERE = Path(__file__).resolve().parents[2] / "studies" / "vi_nes"
MU, ZETA, R, B = 0.05, 0.02, 0.6, 5.0


@pytest.fixture(scope="module")
def cf():
    spec = importlib.util.spec_from_file_location("vi_nes_closed_form", HERE / "closed_form.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look the module up by name
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(spec.name, None)


def _params(cf, r, **extra):
    kw = {"r": r, "mu": MU, "zeta": ZETA, "b": B, "b_low": B, "R": R, "R_low": R, **extra}
    return cf.VINES(**kw)


def _package(m):
    p = m.p
    osc = ic.ImpactOscillator(M=np.diag([1.0, p.mu]), K=[[1.0, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], R=p.R, b=p.b, omega=p.r, eta=p.zeta,
                              F_static=[-p.g, -p.mu * p.g],
                              stops=ic.Stops(mass=2, relative_to=1, b_low=p.b_low,
                                             R_low=p.R_low))
    return ic.multi_impact_orbit(osc, 1, 2, {"delta": m.delta,
                                             "flight_times": list(m.flight_times),
                                             "states": [m.state_upper, m.state_lower],
                                             "pattern": "UL"})


@pytest.mark.parametrize("r, extra", [(1.2, {}), (1.2, {"R_low": 0.3}), (1.2, {"g": 0.5}),
                                      (0.9, {"g": 0.5})])
def test_closed_form_motions_are_the_packages(cf, r, extra):
    """Every UL root (symmetric or not, physical or not): phase, states after both
    impacts, flight times and approach speeds within Newton's guarantee; the physical
    verdict; on the physical roots the multipliers (central differences: 1e-5)."""
    motions = cf.ul_motions(_params(cf, r, **extra), scan=200)
    assert len(motions) >= 2
    for m in motions:
        orbit = _package(m)
        assert orbit.residual < 1e-11 and orbit.error_estimate < 1e-10
        k = orbit.pattern.index("U")
        order = [k, 1 - k]
        tol = 1e-9  # >> the error estimate, << any difference in the formulas
        assert abs(math.remainder(orbit.phases[k] - m.delta, 2 * math.pi)) < tol
        np.testing.assert_allclose(orbit.states[order[0]], m.state_upper, rtol=0, atol=tol)
        np.testing.assert_allclose(orbit.states[order[1]], m.state_lower, rtol=0, atol=tol)
        np.testing.assert_allclose(orbit.flight_times[order], m.flight_times, rtol=0, atol=tol)
        np.testing.assert_allclose(orbit.impact_velocities[order],
                                   [m.approach_upper, m.approach_lower], rtol=0, atol=1e-8)
        assert orbit.physical == m.physical
        if m.physical:
            for q in m.multipliers:
                assert np.min(np.abs(orbit.multipliers - q)) < 1e-5 * max(1.0, abs(q))
            assert orbit.stable == m.stable


def test_unequal_restitution_makes_the_flights_unequal(cf):
    """R_low != R: the stable motion's flights are not half a period each (t1/T = 0.3846),
    where the symmetric machine's are exactly."""
    sym = [m for m in cf.ul_motions(_params(cf, 1.2), scan=200) if m.physical and m.stable]
    asym = [m for m in cf.ul_motions(_params(cf, 1.2, R_low=0.3), scan=200)
            if m.physical and m.stable]
    assert len(sym) == len(asym) == 1
    assert sym[0].t1 / sym[0].p.T == pytest.approx(0.5, abs=1e-12)
    assert asym[0].t1 / asym[0].p.T == pytest.approx(0.3846, abs=1e-3)
    orbit = _package(asym[0])
    assert orbit.stable and orbit.physical
    assert orbit.flight_times[orbit.pattern.index("U")] == pytest.approx(asym[0].t1, abs=1e-9)


@pytest.mark.parametrize("r, stable", [(1.085, False), (1.095, True)])
def test_stability_verdict_either_side_of_the_pitchfork(cf, r, stable):
    """Either side of the study's symmetry-breaking point (omega = 1.08930) of the
    symmetric machine (the stable asymmetric pair exists below it): the closed form's
    verdict on the root of the branch (delta near -3), the package's multipliers and the
    expected side agree."""
    m = min((m for m in cf.ul_motions(_params(cf, r), scan=200)
             if m.physical and abs(m.t1 / m.p.T - 0.5) < 1e-9),
            key=lambda m: abs(math.remainder(m.delta + 3.0, 2 * math.pi)))
    orbit = _package(m)
    assert m.stable == orbit.stable == stable
    assert np.max(np.abs(m.multipliers)) == pytest.approx(orbit.spectral_radius, rel=1e-5)

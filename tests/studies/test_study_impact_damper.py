"""studies/impact_damper: the closed form of the symmetric two-impact motion of an impact
damper (derived in the study, after Masri & Caughey 1966) against the package's N-p
shooting (``multi_impact_orbit``) and its multipliers.

The closed form is an independent witness: the motion from three linear equations and a
quadratic (the phase), the stability from the half-period map written out by hand
(``studies/impact_damper/closed_form.py``), no code shared with the package."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from tests._study_files import study_file

MU, E, ZETA = 0.2, 0.8, 0.05


@pytest.fixture(scope="module")
def cf():
    with study_file("impact_damper", "closed_form.py") as module:
        yield module


def _package(m):
    osc = ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], R=E, b=0.5 * m.d, omega=m.r, eta=ZETA,
                              stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    T2 = math.pi / m.r
    return ic.multi_impact_orbit(osc, 1, 2, {"delta": m.delta, "flight_times": [T2, T2],
                                             "states": [m.state, -m.state],
                                             "pattern": "UL"})


@pytest.mark.parametrize("r, d", [(1.5, 2.0), (2.5, 1.0), (0.7, 4.0)])
def test_closed_form_motion_is_the_packages(cf, r, d):
    """Both roots: phase, state after the impact, approach speed, flight times and
    multipliers agree within Newton's guarantee (error_estimate ~ 1e-12 here)."""
    motions = cf.symmetric_motions(r, d, MU, E, ZETA)
    assert len(motions) == 2
    for m in motions:
        orbit = _package(m)
        assert orbit.residual < 1e-12 and orbit.error_estimate < 1e-10
        k = orbit.pattern.index("U")
        tol = 1e-9  # >> the error estimate, << any difference in the formulas
        assert abs(math.remainder(orbit.phases[k] - m.delta, 2 * math.pi)) < tol
        np.testing.assert_allclose(orbit.states[k], m.state, rtol=0, atol=tol)
        np.testing.assert_allclose(orbit.flight_times, math.pi / r, rtol=0, atol=tol)
        assert orbit.impact_velocities[k] == pytest.approx(m.impact_velocity, abs=tol)
        for q in m.multipliers:  # each closed-form multiplier is one of the package's
            assert np.min(np.abs(orbit.multipliers - q)) < 1e-7 * max(1.0, abs(q))
        assert orbit.physical == m.physical


@pytest.mark.parametrize("r, stable", [(1.47, False), (1.48, True), (1.85, True),
                                       (1.87, False)])
def test_closed_form_stability_verdict_is_the_multipliers(cf, r, stable):
    """Either side of the pitchfork (omega = 1.47404) and of the Neimark-Sacker point
    (1.86058) of the study's b = 1 branch: the closed form's verdict on its physical
    root, the package's multipliers, and the expected side agree."""
    m = next(m for m in cf.symmetric_motions(r, 2.0, MU, E, ZETA) if m.physical
             and abs(m.delta - (-3.0)) < 0.3)  # the root on the study's branch
    orbit = _package(m)
    assert m.stable == orbit.stable == stable
    assert np.max(np.abs(m.multipliers)) == pytest.approx(orbit.spectral_radius, rel=1e-8)


def test_stability_map_is_the_closed_form_cell_by_cell(cf):
    """``multi_impact_map`` over (omega, b) of the damper (a clearance between masses, a
    free mass: refused with an ``impact_geometry`` error before the map moved to
    ``stop_geometry``), seeded by the closed form, against the closed form at every
    cell: found exactly where a symmetric motion exists, and there the root of nearest
    phase has the map's phase, spectral radius, physical and stable flags."""
    seed = _package(next(m for m in cf.symmetric_motions(1.5, 2.0, MU, E, ZETA)
                         if m.stable and m.physical))
    omegas, bs = np.linspace(1.0, 3.0, 21), np.linspace(0.3, 2.5, 12)
    ds = ic.multi_impact_map(seed, ("omega", "b"), {"omega": omegas, "b": bs},
                             max_change=2.0)
    verdicts = set()
    for i, r in enumerate(omegas):
        for j, b in enumerate(bs):
            roots = cf.symmetric_motions(float(r), 2.0 * float(b), MU, E, ZETA)
            point = ds.isel(omega=i, b=j)
            assert bool(point["found"]) == bool(roots), (r, b)
            if not roots:
                continue
            delta = float(point["delta"])
            m = min(roots, key=lambda m: abs(math.remainder(m.delta - delta, 2 * math.pi)))
            assert abs(math.remainder(m.delta - delta, 2 * math.pi)) < 1e-9
            rho = float(np.max(np.abs(m.multipliers)))
            assert float(point["spectral_radius"]) == pytest.approx(rho, rel=1e-8)
            assert bool(point["physical"]) == m.physical, (r, b)
            if abs(rho - 1.0) > 1e-6:  # the verdict off the knife edge
                assert bool(point["stable"]) == m.stable, (r, b)
            verdicts.add((m.physical, m.stable))
    # the grid crosses the BP and NS curves and the grazing of the family
    assert verdicts == {(True, True), (True, False), (False, False)}

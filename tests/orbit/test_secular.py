"""Multipliers from the secular function against the dense eigenvalues of G (eq. 25).

The dense path forms G from the physical transition matrix and calls LAPACK; the
secular path never forms G (2 x 2 determinant of modal sums, Aberth iteration).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import closed_form, stability
from impactcont.orbit import secular
from impactcont.orbit.periodic import modal_arrays
from tests.kernel.test_closed_form import DAMPING, _random_oscillator


def _secular(orbit: ic.PeriodicOrbit) -> tuple[np.ndarray, bool]:
    osc = orbit.oscillator
    arrays = modal_arrays(osc)
    w, a, f, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0
    return secular.secular_multipliers(orbit.modal, w, a, f, u0, ui0, osc.omega, osc.R,
                                       orbit.delta, orbit.impact_velocity)


def _distance(mu: np.ndarray, reference: np.ndarray) -> float:
    """Largest distance from a multiplier of either set to the nearest of the other."""
    d = np.abs(mu[:, None] - reference[None, :])
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def _chain(n: int, **damping: float) -> ic.ImpactOscillator:
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.7, b=0.1,
                                     omega=1.1, **(damping or {"eta": 0.05}))


@pytest.mark.parametrize("damping", list(DAMPING))
def test_secular_multipliers_match_dense_eigenvalues(damping):
    rng = np.random.default_rng(77 + len(damping))
    checked = accepted = 0
    for n in (1, 2, 3, 5, 8, 12):
        for _ in range(5):
            osc = _random_oscillator(rng, n, DAMPING[damping])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ic.IllConditionedWarning)
                orbits = ic.periodic_orbits(osc, 1)
            for orbit in orbits:
                mu, ok = _secular(orbit)
                dense = stability.multipliers(orbit.G)
                checked += 1
                if not ok:  # refused by the guard: the dense path takes over
                    continue
                accepted += 1
                assert mu.shape == dense.shape
                # clusters of tiny multipliers (over-damped modes) reach 0.5e-12 under 1-ulp
                # changes of the inputs: compare at 1e-11
                assert _distance(mu, dense) <= 1e-11 * max(1.0, abs(dense[0]))
                assert abs(abs(mu[0]) - abs(dense[0])) <= 1e-11 * max(1.0, abs(dense[0]))
                # exact conjugate pairs, as from LAPACK
                assert _distance(mu, np.conj(mu)) == 0.0
    assert checked >= 6
    assert accepted >= 0.75 * checked  # refused: clusters of tiny roots (over-damped)


@pytest.mark.parametrize("n", [40, 80])
@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"alpha": 0.05, "beta": 0.02}, {}])
def test_large_chain_uses_the_secular_path_and_matches_dense(n, damping):
    osc = _chain(n, **damping)
    orbits = ic.periodic_orbits(osc, 1)
    assert orbits
    for orbit in orbits:
        mu, ok = _secular(orbit)
        assert ok
        np.testing.assert_array_equal(orbit.multipliers, mu)  # what the orbit reports
        dense = stability.multipliers(orbit.G)
        assert _distance(mu, dense) <= 1e-11 * max(1.0, abs(dense[0]))
        assert orbit.stable == (abs(dense[0]) < 1.0)


def test_power_sum_guard_catches_a_missing_or_moved_root():
    orbit = ic.periodic_orbits(_chain(20), 1)[0]
    osc = orbit.oscillator
    arrays = modal_arrays(osc)
    w, a, f, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0
    pieces = closed_form.jacobian_pieces(orbit.modal, w, a, f, ui0, osc.omega, osc.R, orbit.delta,
                                    orbit.impact_velocity)
    *_, h2, xn = secular.secular_coefficients(orbit.modal, u0, ui0, osc.omega, osc.R,
                                              *pieces)
    traces = secular.power_sums(orbit.modal, u0, ui0, osc.omega, osc.R, *pieces, h2, xn)
    mu = orbit.multipliers
    assert secular.power_sums_agree(mu, *traces)
    np.testing.assert_allclose(traces[:2], [np.trace(orbit.G), np.trace(orbit.G @ orbit.G)],
                               rtol=1e-12, atol=1e-13)
    dropped = mu.copy()
    dropped[3] = 0.0
    assert not secular.power_sums_agree(dropped, *traces)
    moved = mu.copy()
    moved[0] *= 1.0 + 1e-6
    assert not secular.power_sums_agree(moved, *traces)


def test_orbit_falls_back_to_dense_eigenvalues_when_the_guard_refuses(monkeypatch):
    orbit = ic.periodic_orbits(_chain(20), 1)[0]
    dense = stability.multipliers(orbit.G)
    monkeypatch.setattr(secular, "secular_multipliers",
                        lambda *args: (np.zeros(40, dtype=complex), False))
    np.testing.assert_array_equal(orbit.multipliers, dense)


def test_heavily_damped_chain_matches_high_precision_eigenvalues():
    """Over-damped modes: their fast multipliers (below eps) are exact zeros of the
    secular polynomial; left in they made a ring of 1e-8 spurious multipliers."""
    mpmath = pytest.importorskip("mpmath")
    orbit = ic.periodic_orbits(_chain(16, eta=3.0), 1)[0]
    mu, ok = _secular(orbit)
    assert ok
    mpmath.mp.dps = 40
    exact = np.array([complex(e) for e in mpmath.eig(mpmath.matrix(orbit.G.tolist()),
                                                     left=False, right=False)])
    assert _distance(mu, exact) <= 1e-13 * abs(exact).max()

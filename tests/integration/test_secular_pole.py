"""The secular multipliers where the velocity of mass 1 in modal form cancels (issue 29,
item 8): the motion's own velocity as the pole and the velocity column corrected by an
exact dot product, instead of a fallback to the dense eigenvalues of G (O(n^3): 30-80 s
for a 2000-mass chain whose impact velocity was polished).
"""

from __future__ import annotations

import warnings
from fractions import Fraction

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import stability
from impactcont.orbit import secular
from impactcont.orbit.dense import VELOCITY_POLISH
from impactcont.orbit.periodic import modal_arrays


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance between matched members of two sets of multipliers."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(a[:, None] - b[None, :])
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].max())


def test_exact_dot_is_the_rounded_exact_sum():
    rng = np.random.default_rng(3)
    for scale in (1.0, 1e-8, 1e8):
        x = scale * rng.standard_normal(500)
        y = rng.standard_normal(500)
        y[-1] = -float(np.dot(x[:-1], y[:-1])) / x[-1]  # a sum that cancels
        exact = sum((Fraction(float(a)) * Fraction(float(b)) for a, b in zip(x, y, strict=True)),
                    Fraction(0))
        assert secular.exact_dot(x, y) == float(exact)


@pytest.mark.parametrize("n", [40, 64])
def test_cancelling_modal_velocity_takes_the_motions_velocity_as_pole(n, make_chain):
    """Far above the lowest mode (omega = 1000, b = 0) the modal velocity of mass 1 cancels
    past the guard for both roots; the secular multipliers are accepted and are the dense
    eigenvalues of G (pole: the motion's velocity) within the secular path's 1e-11, where
    the modal sum as the pole was 5e-10-2e-9 off."""
    osc = make_chain(n, omega=1000.0, b=0.0)
    arrays = modal_arrays(osc)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2
    for orbit in orbits:
        args = (orbit.modal, arrays.u0, arrays.ui0, osc.omega, osc.R, orbit.delta,
                orbit.impact_velocity)
        assert secular.velocity_row_error(*args) > VELOCITY_POLISH * abs(orbit.impact_velocity)
        mu, ok = secular.secular_multipliers(orbit.modal, arrays.w, arrays.a, arrays.f,
                                             arrays.u0, arrays.ui0, osc.omega, osc.R,
                                             orbit.delta, orbit.impact_velocity)
        assert ok
        dense = stability.multipliers(orbit.G)
        assert _distance(mu, dense) <= 1e-11 * max(1.0, abs(dense[0]))
        np.testing.assert_array_equal(orbit.multipliers, mu)  # what the orbit reports

"""Newton on a branch cut by a hyperplane (:mod:`impactcont.core.corrector`): a step that
leaves the problem's domain is halved (issue 19)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.core import solve_on_hyperplane


class _Line:
    """``F(u, lam) = u - lam``: the branch ``u = lam``, refused for ``lam <= 0``."""

    def residual(self, u, lam):
        if not lam > 0:
            raise ic.ParameterError(f"lam must be > 0; got {lam}")
        return np.array([u[0] - lam])

    def jacobian(self, u, lam):
        return np.array([[1.0]])

    def dparam(self, u, lam):
        return np.array([-1.0])


def test_hyperplane_newton_halves_a_step_that_leaves_the_domain():
    class Cubic(_Line):  # u = lam^3 near lam = 0.05: Newton from lam = 0.3 overshoots below 0
        def residual(self, u, lam):
            super().residual(u, lam)
            return np.array([u[0] - lam ** 3])

        def dparam(self, u, lam):
            return np.array([-3 * lam ** 2])

    found = solve_on_hyperplane(Cubic(), np.array([1.25e-4, 0.3]), np.array([1.0, 0.0]),
                                tol=1e-14)
    assert found.converged
    assert found.lam == pytest.approx(0.05, rel=1e-12)

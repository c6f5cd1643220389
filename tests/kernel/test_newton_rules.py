"""The kernel's Newton rules (:mod:`impactcont.kernel.newton_rules`): converged when the
residual and the last step are within ``tol * scale`` (or at the last iteration); a trial
point taken when it lowers the residual, meets the tolerance or the step is down to a
thousandth; the iterate kept at its rounding floor when within tol a trial does not lower
it (compiled-only functions, called here through njit)."""

from __future__ import annotations

import math

import numba as nb
import pytest

from impactcont.kernel import newton_rules as rules


@nb.njit(cache=False)
def _converged(norm, step_norm, bound, it, max_iter):
    return rules._converged(norm, step_norm, bound, it, max_iter)


@nb.njit(cache=False)
def _outcome(tnorm, norm, small, bound, lam_step):
    return rules._trial_outcome(tnorm, norm, small, bound, lam_step)


@pytest.mark.parametrize("norm, step_norm, it, expected", [
    (1e-13, math.inf, 0, (True, False)),   # residual within tol, no step yet
    (1e-13, 1e-13, 3, (True, True)),       # both within tol
    (1e-13, 1e-3, 3, (True, False)),       # the step is not
    (1e-13, 1e-3, 10, (True, True)),       # the last iteration
    (1e-3, 1e-13, 10, (False, False)),     # the residual is not, even at the last
])
def test_converged(norm, step_norm, it, expected):
    assert _converged(norm, step_norm, 1e-12, it, 10) == expected


@pytest.mark.parametrize("tnorm, norm, small, lam_step, expected", [
    (1e-6, 1e-3, False, 1.0, rules.TAKE),          # lowers the residual
    (1e-2, 1e-3, False, 1.0, rules.HALVE),         # raises it: halve the step
    (1e-2, 1e-3, False, 5e-4, rules.TAKE),         # down to a thousandth: taken
    (1e-13, 1e-11, False, 1.0, rules.TAKE),        # meets the tolerance
    (2e-13, 1e-13, True, 1.0, rules.FLOOR),        # within tol, not lowered: at the floor
    (math.nan, 1e-13, True, 1.0, rules.FLOOR),
    (math.nan, 1e-3, False, 1.0, rules.HALVE),     # not finite: halve
    (math.inf, 1e-3, False, 5e-4, rules.HALVE),    # not finite is never taken
    (5e-14, 1e-13, True, 1.0, rules.TAKE),         # within tol and lowered: taken
])
def test_trial_outcome(tnorm, norm, small, lam_step, expected):
    assert _outcome(tnorm, norm, small, 1e-12, lam_step) == expected

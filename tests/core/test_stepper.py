"""The pseudo-arclength stepper (:mod:`impactcont.core.stepper`): its tangent stays
oriented and of unit length."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impactcont.core import ContinuationOptions, PalcStepper


class Circle:
    """``u^2 + lam^2 = 1``: folds at ``lam = +-1``, a closed loop."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] ** 2 + lam**2 - 1.0])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[2.0 * u[0]]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([2.0 * lam])


def test_stepper_tangent_stays_oriented_and_unit() -> None:
    options = ContinuationOptions(bounds=(-2.0, 2.0), ds=0.05, theta=0.3)
    stepper = PalcStepper(Circle(), options)
    previous = stepper.init(np.array([1.0]), 0.0)

    assert previous.tangent == pytest.approx([0.0, 1.0 / math.sqrt(options.theta)])
    for _ in range(40):
        current = stepper.step()
        assert stepper.scaled_norm(current.tangent) == pytest.approx(1.0)
        assert stepper.scaled_dot(previous.tangent, current.tangent) > 0.0
        assert stepper.scaled_norm(current.state - previous.state) <= current.ds * 1.01
        previous = current


def test_a_step_that_jumps_along_the_branch_is_refused() -> None:
    """A chain of 10 masses (the accuracy study's, eta = 0.02) whose N = 1 branch bends
    sharply at omega = 0.5113 just above the bound 0.5: the landing on the bound from
    omega = 0.512, and then a PALC step of ds = 0.004, were corrected 0.15-0.21 away from
    their predictors (the second to omega = 0.309) and accepted, so the step over the
    bend hid the grazing at 0.51202 (left bracketed, precision 8e-3). Refused, the bend
    is followed in small steps and the GR is located where Brent's method on the closed
    form's gap_min puts it."""
    from scipy.optimize import brentq

    import impactcont as ic

    F = np.zeros(10)
    F[0] = 1.0
    osc = ic.ImpactOscillator.chain(masses=np.ones(10), springs=np.ones(10), F=F, R=0.6,
                                    b=0.0, omega=0.515, eta=0.02)
    branch = ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 0.53), detect=("GR",),
                             components="start")
    (label,), (status,) = branch.special_label.values, branch.special_status.values
    assert (str(label), str(status)) == ("GR", "located")

    def gap_min(omega: float) -> float:
        return next(o for o in ic.periodic_orbits(osc.replace(omega=omega), 1)
                    if o.root == -1).gap_min

    truth = brentq(gap_min, 0.511, 0.5125, xtol=1e-15, rtol=1e-15)
    assert abs(float(branch.special_omega[0]) - truth) <= max(
        float(branch.special_precision[0]), 1e-12)
    omega = np.sort(branch.omega.values)
    assert np.max(np.diff(omega)) < 0.005  # no step across the bend

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

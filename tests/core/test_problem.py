"""The problem protocol (:mod:`impactcont.core.problem`): what the core asks of ``F(u, lam)``.

Tiny analytic problems: the circle ``u^2 + lam^2 = 1`` (folds at ``lam = +-1``) and the
fold ``lam = u^2`` (at 0), continued by the core through the three methods or through
``linearize`` alone, with their folds and a user test located to the precision the
locator claims (the exact answers are known by hand). The shape checks of
:func:`check_problem_outputs` name the method, the shape and the one expected.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from impactcont.core import ContinuationOptions, Event, follow, locate_events
from impactcont.core.problem import (
    Problem,
    ProblemOutputError,
    check_problem_outputs,
    evaluate_monitors,
)


class Circle:
    """``u^2 + lam^2 = 1``, with the monitor ``u^2`` (so ``u^2 + lam^2`` is checkable)."""

    def residual(self, u, lam):
        return np.array([u[0] ** 2 + lam ** 2 - 1.0])

    def jacobian(self, u, lam):
        return np.array([[2.0 * u[0]]])

    def dparam(self, u, lam):
        return np.array([2.0 * lam])

    def monitors(self, u, lam):
        return {"u_squared": u[0] ** 2, "radius": np.float32(math.hypot(u[0], lam))}


class Parabola:
    """``lam = u1^2``, ``u2 = u1 lam`` (m = 2): one fold at ``lam = 0``, with ``linearize``
    (``F`` and ``[dF/du | dF/dlam]`` at once), which the corrector asks."""

    calls = 0

    def residual(self, u, lam):
        return np.array([u[0] ** 2 - lam, u[1] - u[0] * lam])

    def jacobian(self, u, lam):
        return np.array([[2.0 * u[0], 0.0], [-lam, 1.0]])

    def dparam(self, u, lam):
        return np.array([-1.0, -u[0]])

    def linearize(self, u, lam):
        type(self).calls += 1
        return self.residual(u, lam), np.column_stack([self.jacobian(u, lam),
                                                       self.dparam(u, lam)])


def test_the_analytic_problems_are_problems():
    assert isinstance(Circle(), Problem)
    assert isinstance(Parabola(), Problem)
    assert not isinstance(object(), Problem)  # runtime_checkable: the three methods


def test_the_circle_is_continued_and_its_folds_located_to_their_precision():
    options = ContinuationOptions(bounds=(-2.0, 2.0), ds=0.1, ds_max=0.2, both_directions=True)
    result = follow(Circle(), [1.0], 0.0, options,
                    events=[Event("SN", None), Event("half", lambda u, lam: lam - 0.5)])
    np.testing.assert_allclose(result.u[:, 0] ** 2 + result.lam ** 2, 1.0, atol=1e-10)
    np.testing.assert_allclose(result.monitors["u_squared"] + result.lam ** 2, 1.0, atol=1e-10)
    folds = [e for e in result.events if e.label == "SN"]
    assert sorted(round(e.lam) for e in folds) == [-1, 1]
    for fold in folds:
        assert fold.status == "located"
        assert 0.0 < fold.precision < 1e-10
        assert abs(abs(fold.lam) - 1.0) <= fold.precision
        assert abs(fold.u[0]) <= math.sqrt(2.0 * fold.precision)  # u^2 = 1 - lam^2
    # the user test lam = 1/2 is crossed on both halves of the loop (u = +-sqrt(3)/2)
    half = [e for e in result.events if e.label == "half"]
    assert len(half) == 2
    for e in half:
        assert abs(e.lam - 0.5) <= e.precision < 1e-10
        assert abs(abs(e.u[0]) - math.sqrt(3.0) / 2.0) < 1e-10


def test_a_problem_with_linearize_is_corrected_through_it_alone():
    Parabola.calls = 0
    problem = Parabola()
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, ds_max=0.1, both_directions=True)
    result = follow(problem, [0.8, 0.8 * 0.64], 0.64, options)
    assert Parabola.calls > 0
    np.testing.assert_allclose(result.u[:, 0] ** 2, result.lam, atol=1e-10)
    np.testing.assert_allclose(result.u[:, 1], result.u[:, 0] * result.lam, atol=1e-10)
    # both arms of the parabola are reached through the fold at lam = 0
    assert result.u[:, 0].min() < -0.5 and result.u[:, 0].max() > 0.5
    events = locate_events(problem, result.u, result.lam, result.tangent, [Event("SN", None)])
    assert len(events) == 1
    fold = events[0]
    assert fold.status == "located"
    assert abs(fold.lam) <= fold.precision < 1e-10
    assert abs(fold.u[0]) <= math.sqrt(2.0 * fold.precision)


class _Wrong:
    """A problem whose method `bad` returns an array of the wrong shape."""

    def __init__(self, bad):
        self.bad = bad

    def residual(self, u, lam):
        return np.zeros(3 if self.bad == "residual" else 2)

    def jacobian(self, u, lam):
        return np.zeros((2, 3) if self.bad == "jacobian" else (2, 2))

    def dparam(self, u, lam):
        return np.zeros((2, 1) if self.bad == "dparam" else 2)


@pytest.mark.parametrize(("bad", "fragment"), [
    ("residual", r"problem\.residual\(u, lam\) returned shape \(3,\) for m = 2 unknowns; "
                 r"expected shape \(2,\)"),
    ("jacobian", r"problem\.jacobian\(u, lam\) returned shape \(2, 3\).*expected shape \(2, 2\)"),
    ("dparam", r"problem\.dparam\(u, lam\) returned shape \(2, 1\).*expected shape \(2,\)"),
])
def test_a_wrong_shape_is_named(bad, fragment):
    with pytest.raises(ProblemOutputError, match=fragment):
        check_problem_outputs(_Wrong(bad), np.zeros(2), 0.0)
    check_problem_outputs(_Wrong(None), np.zeros(2), 0.0)  # the right shapes pass


def test_a_wrong_linearize_is_named():
    problem = _Wrong(None)
    problem.linearize = lambda u, lam: (np.zeros(2), np.zeros((2, 2)))
    with pytest.raises(ProblemOutputError, match=r"linearize.*\(2, 2\).*expected \(2,\) "
                                                 r"and \(2, 3\)"):
        check_problem_outputs(problem, np.zeros(2), 0.0)


def test_the_problem_cannot_change_the_callers_unknowns():
    """The methods receive copies: a problem that writes into u changes nothing."""

    class Scribbler(Circle):
        def residual(self, u, lam):
            u[:] = 99.0
            return super().residual(u, lam)

        def monitors(self, u, lam):
            u[:] = 99.0
            return {"x": 1}

    u = np.array([0.5])
    check_problem_outputs(Scribbler(), u, 0.1)
    assert evaluate_monitors(Scribbler(), u, 0.1) == {"x": 1.0}
    assert u[0] == 0.5


def test_monitors_are_plain_floats_and_optional():
    values = evaluate_monitors(Circle(), np.array([0.6]), 0.8)
    assert values == {"u_squared": pytest.approx(0.36, rel=1e-15),
                      "radius": pytest.approx(1.0, rel=1e-7)}
    assert all(type(v) is float for v in values.values())
    assert evaluate_monitors(Parabola(), np.array([0.6, 0.1]), 0.36) == {}

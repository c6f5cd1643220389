"""The core's events, stop rules and corrector on a problem-free example (a circle)."""

from __future__ import annotations

import math

import numpy as np

from impactcont.core import (
    ContinuationOptions,
    ContinuationStatus,
    Event,
    Stop,
    follow,
    locate_events,
    solve_on_hyperplane,
)


class Circle:
    """``u^2 + lam^2 = 1``: folds at ``lam = +-1``."""

    def residual(self, u, lam):
        return np.array([u[0] ** 2 + lam**2 - 1.0])

    def jacobian(self, u, lam):
        return np.array([[2.0 * u[0]]])

    def dparam(self, u, lam):
        return np.array([2.0 * lam])


def test_events_are_located_on_the_branch_with_an_arclength_bracket():
    options = ContinuationOptions(bounds=(-2.0, 2.0), ds=0.05, ds_max=0.1, both_directions=True)
    events = [Event("fold", None), Event("half", lambda u, lam: lam - 0.5)]
    branch = follow(Circle(), [1.0], 0.0, options, events=events)
    found = locate_events(Circle(), branch.u, branch.lam, branch.tangent, events)
    assert [e.lam for e in branch.events] == [e.lam for e in found]
    folds = [e for e in found if e.label == "fold"]
    halves = [e for e in found if e.label == "half"]
    assert folds and all(abs(abs(e.lam) - 1.0) < 1e-9 for e in folds)
    assert halves and all(abs(e.lam - 0.5) < 1e-12 and e.status == "located" for e in halves)
    for e in found:
        assert e.arclength[0] < e.arclength[1]
        assert e.bracket[0] <= e.bracket[1]


def test_a_stop_rule_ends_a_direction_with_its_typed_status_and_the_accept_hook_runs():
    seen = []

    class Watched(Circle):
        def accept(self, u, lam):
            seen.append(float(lam))

    def rule(direction):
        def stop(previous, current):
            if current.lam > 0.5:
                return Stop(ContinuationStatus.STOPPED_AFTER_EVENT, "lam > 0.5", keep=False)
            return None
        return stop

    options = ContinuationOptions(bounds=(-2.0, 2.0), ds=0.05, ds_max=0.1)
    branch = follow(Watched(), [1.0], 0.0, options, stop=rule)
    assert branch.status is ContinuationStatus.STOPPED_AFTER_EVENT
    assert branch.lam.max() <= 0.5 and seen[0] == 0.0 and len(seen) >= len(branch)


def test_hyperplane_corrector():
    found = solve_on_hyperplane(Circle(), np.array([0.9, 0.3]), np.array([0.0, 1.0]), tol=1e-14)
    assert found.converged and found.lam == 0.3
    assert abs(found.u[0] - math.sqrt(1 - 0.09)) < 1e-14

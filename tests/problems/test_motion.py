"""The one interface of a motion and a branch problem (:mod:`impactcont.problems.motion`)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.orbit.multi_impact import multi_impact_orbit
from impactcont.problems import PeriodicBranchProblem
from impactcont.problems.motion import BranchProblem, Motion
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem


@pytest.fixture(scope="module")
def paper():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=0.5, omega=1.0, eta=0.1)


def test_the_closed_form_motion_is_the_p1_motion_of_the_shooting_path(paper):
    """The N-1 closed form's per-impact view is the shooting path's p = 1 motion through
    it: the same phases, flight times, states, impact velocities and clearances (both
    exact to rounding; the shooting solve to its Newton tolerance)."""
    (orbit,) = [o for o in ic.periodic_orbits(paper, 1) if o.physical]
    shot = multi_impact_orbit(paper, 1, 1, orbit)
    for motion in (orbit, shot):
        assert isinstance(motion, Motion)
    assert (orbit.p, orbit.pattern) == (shot.p, shot.pattern) == (1, "U")
    np.testing.assert_allclose(np.angle(np.exp(1j * (orbit.phases - shot.phases))), 0.0,
                               atol=1e-10)
    for name in ("flight_times", "states", "impact_velocities", "flight_gap_min"):
        mine, theirs = getattr(orbit, name), getattr(shot, name)
        assert mine.shape == theirs.shape, name
        np.testing.assert_allclose(mine, theirs, rtol=1e-9, atol=1e-10, err_msg=name)
    # the scalar view is the per-impact view's impact 0 / minimum
    assert orbit.states[0] is not None and orbit.impact_velocities.min() == orbit.impact_velocity
    assert orbit.flight_gap_min.min() == orbit.gap_min


def test_both_evaluators_are_branch_problems_with_one_orbit_signature(paper):
    """``orbit(u, lam, checks=...)`` on both problems, the closed form's u being [delta]."""
    closed = PeriodicBranchProblem(paper, 1, "omega")
    shooting = MultiImpactBranchProblem(paper, 1, 1, "omega")
    for problem in (closed, shooting):
        assert isinstance(problem, BranchProblem)
        problem.check_bounds((0.5, 3.0))
    (orbit,) = [o for o in ic.periodic_orbits(paper, 1) if o.physical]
    u = np.array([orbit.delta])
    assert closed.orbit(u, 1.0, checks=False).delta == closed.orbit(orbit.delta, 1.0).delta
    shot = shooting.orbit(multi_impact_orbit(paper, 1, 1, orbit).unknowns, 1.0, checks=False)
    assert abs(np.angle(np.exp(1j * (shot.delta - orbit.delta)))) < 1e-10
    # the evaluators' own hooks: the exact fold of eq. (14-15), the pitchfork of N-p folds
    assert callable(closed.locate_fold) and not hasattr(shooting, "locate_fold")
    assert callable(shooting.fold_kind) and not hasattr(closed, "fold_kind")
    assert (closed.impact_dimension, shooting.impact_dimension) == (False, True)

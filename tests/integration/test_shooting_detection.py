"""Special points of N-p branches (the one detector, :mod:`impactcont.detection.special_points`).

A small branch: the paper's N-1 motion followed in omega on the shooting path (p = 1,
:class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem` continued by
the core), which meets a grazing (GR), a period doubling (PD), a zero-velocity impact (ZV)
and the fold of eq. (15) (SN). Independent witness: the closed form of the same motion
(:func:`impactcont.periodic_orbits`, the compiled kernel, no shooting), whose special
points are zeros of scalar functions of omega located here by ``scipy.optimize.brentq``:
``gap_min``, ``det(G + I)``, ``impact_velocity`` and ``c^2 + s^2 - b^2`` (eq. 15).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import impactcont as ic
from impactcont.core import ContinuationOptions, follow
from impactcont.detection.points import SpecialPoint as MultiImpactSpecialPoint
from impactcont.detection.special_points import BranchSample as MultiImpactSample
from impactcont.detection.special_points import check_user_functions
from impactcont.detection.special_points import detect_special_points as detect_multi_impact_points
from impactcont.detection.special_points import (
    locate_sample_events as locate_multi_impact_events,
)
from impactcont.errors import LowImpactVelocityWarning, ParameterError
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

K2 = [[1.0, -1.0], [-1.0, 2.0]]


def paper(omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.6, omega=omega,
                               eta=0.1)


def _closed(omega: float, near: float) -> ic.PeriodicOrbit:
    """The closed-form N-1 motion at omega whose phase is nearest `near`."""
    return min(ic.periodic_orbits(paper(omega), 1),
               key=lambda o: abs(math.remainder(o.delta - near, 2 * math.pi)))


@pytest.fixture(scope="module")
def branch():
    """The samples of the branch through the physical motion at omega = 1 (0.6 .. 1.3)."""
    osc = paper(1.0)
    start = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    problem = MultiImpactBranchProblem(osc, 1, 1, "omega")
    u0 = ic.multi_impact_orbit(osc, 1, 1, start).unknowns
    result = follow(problem, u0, 1.0, ContinuationOptions(bounds=(0.6, 1.3), ds=0.02,
                                                          ds_max=0.05, both_directions=True))
    samples = [MultiImpactSample(u=u, lam=float(lam), tangent=t, orbit=problem.orbit(u, lam))
               for u, lam, t in zip(result.u, result.lam, result.tangent, strict=True)]
    return problem, samples


@pytest.fixture(scope="module")
def points(branch):
    problem, samples = branch
    found = []
    specials = detect_multi_impact_points(problem, samples, on_found=found.append)
    assert found == specials  # on_found sees every point, in branch order
    return specials


def _witness(label: str, point: MultiImpactSpecialPoint) -> float:
    """The closed form's omega of the special point, by brentq in a bracket around it."""
    near = point.delta

    def g(omega: float) -> float:
        with warnings.catch_warnings():  # the closed form at h2 ~ 0 says it lost digits
            warnings.simplefilter("ignore", LowImpactVelocityWarning)
            return _g(omega)

    def _g(omega: float) -> float:
        if label == "SN":  # the two roots of eq. (15) merge: c^2 + s^2 = b^2
            return ic.amplitude_squared(paper(omega), 1) - 0.6 ** 2
        orbit = _closed(omega, near)
        if label == "GR":
            return orbit.gap_min
        if label == "ZV":
            return orbit.impact_velocity
        return float(np.linalg.det(orbit.G + np.eye(orbit.G.shape[0])).real)  # PD

    lo, hi = point.bracket
    if label == "SN":  # the fold is the end of the branch's omega range: bracket outwards
        lo, hi = point.value - 1e-3, point.value + 1e-3
    return brentq(g, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)


def test_the_special_points_of_the_branch_are_the_closed_forms(points):
    labels = sorted(p.label for p in points)
    assert labels == ["GR", "PD", "SN", "ZV"]
    for point in points:
        assert point.status == "located"
        assert 0.0 < point.precision < 1e-7
        expected = _witness(point.label, point)
        # the located value within its claimed precision (plus the witness's rounding)
        assert abs(point.value - expected) <= point.precision + 1e-11, (point.label, expected)


def test_the_records_describe_their_motion(branch, points):
    problem, samples = branch
    lams = np.array([s.lam for s in samples])
    for point in points:
        assert isinstance(point, MultiImpactSpecialPoint)
        lo, hi = point.bracket
        if point.label != "SN":  # a fold lies beyond both points around it in omega
            assert lo <= point.value <= hi
        # the nearer of the two accepted points around it
        near = lams[point.point]
        assert near in (lo, hi)
        other = hi if near == lo else lo
        assert abs(near - point.value) <= abs(other - point.value)
        assert point.orbit.oscillator.omega == point.value
        assert point.delta == point.orbit.delta == pytest.approx(point.u[0], abs=1e-12)
        np.testing.assert_allclose(problem.residual(point.u, point.value), 0.0, atol=1e-10)
        if point.label == "PD":
            assert np.min(np.abs(point.orbit.multipliers + 1.0)) < 1e-7
        if point.label == "ZV":
            assert abs(point.orbit.impact_velocity) < 1e-8
        if point.label == "GR":
            assert abs(point.orbit.gap_min) < 1e-8


def test_the_labels_asked_for_only(branch):
    problem, samples = branch
    only = detect_multi_impact_points(problem, samples, labels=["PD", "GR"])
    assert sorted(p.label for p in only) == ["GR", "PD"]
    # BP is not among this problem's events: asked for, it finds nothing
    assert detect_multi_impact_points(problem, samples, labels=["BP"]) == []
    with pytest.raises(ParameterError, match="XX"):
        detect_multi_impact_points(problem, samples, labels=["XX"])


def test_a_user_event_is_located_on_the_branch(branch):
    """The user's function of the motion (its flight time minus 2 pi / 0.9, zero at
    omega = 0.9 exactly for an N = 1 motion) with its values at every sample; the branch
    folds back (SN), so it crosses omega = 0.9 on both of its sheets."""
    problem, samples = branch
    functions = check_user_functions(
        events={"period": lambda orbit: float(orbit.flight_times[0]) - 2 * math.pi / 0.9})
    values, events = locate_multi_impact_events(problem, samples, functions)
    np.testing.assert_allclose(values["period"],
                               [2 * math.pi / s.lam - 2 * math.pi / 0.9 for s in samples],
                               atol=1e-12)
    assert len(events) == 2
    for event in events:
        assert event.name == "period" and event.status == "located"
        assert abs(event.lam - 0.9) <= event.precision < 1e-10
        closed = _closed(0.9, event.orbit.delta)
        assert abs(math.remainder(event.orbit.delta - closed.delta, 2 * math.pi)) < 1e-9
    assert abs(math.remainder(events[0].orbit.delta - events[1].orbit.delta, 2 * math.pi)) > 0.1
    assert locate_multi_impact_events(problem, samples, None) == ({}, [])


def test_ctrl_c_while_computing_the_motions_keeps_the_points_before(branch, points):
    """Issue 31: the first Ctrl-C of a call while the motion at the second special point is
    computed keeps the first; outside a driver's call it is raised."""
    from impactcont.progress import interrupted, interruptible

    problem, samples = branch

    second = (np.asarray(points[1].u, dtype=float).tobytes(), float(points[1].value))

    class Interrupted:
        """The problem, whose motion at the second special point raises. That motion is
        computed once, with its checks, by the locator's last step or by the classification
        (which takes the locator's last motions)."""

        def __getattr__(self, name):
            return getattr(problem, name)

        def orbit(self, u, lam, **kw):
            if (np.asarray(u, dtype=float).tobytes(), float(lam)) == second:
                raise KeyboardInterrupt
            return problem.orbit(u, lam, **kw)

    with interruptible("test"):
        kept = detect_multi_impact_points(Interrupted(), samples)
        assert interrupted("location")
    assert [p.label for p in kept] == [points[0].label]
    assert kept[0].value == points[0].value and kept[0].status == points[0].status
    with pytest.raises(KeyboardInterrupt):
        detect_multi_impact_points(Interrupted(), samples)

"""Special points on branches of N-p motions (any number of unknowns).

The test functions are those of :mod:`impactcont.detection.special_points`,
applied to a :class:`~impactcont.orbit.multi_impact.MultiImpactOrbit`, whose
``gap_min`` and ``impact_velocity`` are the minima over its flights and impacts:

========  =============================================  ==============================
label     test function                                  meaning
========  =============================================  ==============================
``SN``    ``d lam / ds`` of the tangent                  fold, a multiplier +1
``PD``    ``det(G + I)``, ``G = G_{p-1} .. G_0``          a real multiplier through -1
``NS``    ``prod_{i<j} (mu_i mu_j - 1)``                 a complex pair through |mu| = 1
``GR``    ``min_k gap_min_k`` over the p flights         x1 touches a stop inside a flight
``ZV``    ``min_k impact_velocity_k`` over the p impacts an impact at zero velocity
``BP``    ``det(H + I)``, ``H = S G_{h-1} .. G_0``         symmetry-breaking pitchfork
========  =============================================  ==============================

BP is tested only on a branch of symmetric motions (a problem with ``symmetric =
True``, :class:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem`):
``H`` is the half-map of :mod:`impactcont.orbit.symmetry`, and a zero of its test
is kept only where ``H`` has a multiplier within 1e-7 of -1. An asymmetric branch
(followed as a general N-p motion) meets the symmetric one at a BP, where its
parameter turns (``lam - lam_BP`` grows like the square of the asymmetry): that fold
is reported as the BP it is when the motion there is nearly symmetric (asymmetry at most
1e-2, :func:`~impactcont.orbit.symmetry.symmetry_defect`: it grows like the square root of
the distance to the BP, and the fold next to a BP is often only bracketed: the full
system is singular there) with a multiplier of ``H`` within 1e-2 of -1, there or at
one of the two branch points around it.

With two stops (:mod:`impactcont.model.stops`) ``gap_min_k`` is the smallest clearance
of flight k to either stop, so GR locates the grazing of the lower stop as well (the
located motion's ``flight_gap_lower`` tells which stop is grazed), and ZV uses the speed
towards the stop hit.

A sign change between two accepted points brackets a special point. The
branch between them is parametrised by the chord: ``s in [0, 1]`` gives the
point of the branch on the hyperplane through ``x_left + s (x_right - x_left)``
orthogonal to the chord (``x = (u, lam)``), found by Newton; this works
through folds as well. Brent's method on ``s`` then locates the zero of the
test function; the special point keeps status ``"bracketed"`` when the test
function does not vanish there (a jump, e.g. of ``gap_min`` when the highest
interior maximum changes, or from ``+inf`` when a flight gains one), and is dropped
when the PD/NS checks fail (the NS product vanishes at a neutral saddle). The PD, NS
and BP tests were multiplied free of the poles of the ``G_k`` at a zero impact
velocity: a step in which an impact velocity changes sign is split at its zero, and a
sign change across it is the pole's, not a special point
(:func:`~impactcont.core.locate.parts_beside_poles`).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from impactcont.core.locate import Event, MotionTest, locate_events, tangent_at
from impactcont.detection.locator import (
    drop_grazing_at_zero_velocity,
    kind_event,
    last_motions,
    watched_labels,
)
from impactcont.detection.points import SpecialPoint
from impactcont.detection.special_points import (
    UserEvent,
    UserFunctions,
    locate_user_events,
    user_values,
)
from impactcont.orbit.multi_impact import MultiImpactOrbit
from impactcont.orbit.symmetry import half_map, symmetry_defect
from impactcont.problems.events import BRANCH_TESTS
from impactcont.progress import take_interrupt
from impactcont.vocabulary import LABELS, Label, check_labels

__all__ = ["MultiImpactSample", "MultiImpactSpecialPoint", "detect_multi_impact_points",
           "locate_multi_impact_events", "tangent_at"]

log = logging.getLogger(__name__)

_S_TOL = 1e-13
_NEWTON_TOL = 1e-13


@dataclasses.dataclass(frozen=True, eq=False)
class MultiImpactSample:
    """An accepted branch point as detection sees it.

    Attributes
    ----------
    u : ndarray, shape (m,)
        Unknowns of the problem.
    lam : float
        Parameter value.
    tangent : ndarray, shape (m + 1,)
        Unit tangent along the branch order.
    orbit : MultiImpactOrbit
    """

    u: np.ndarray
    lam: float
    tangent: np.ndarray
    orbit: MultiImpactOrbit

    @property
    def dlam(self) -> float:
        """Parameter component of the tangent."""
        return float(self.tangent[-1])


#: A special point of an N-p branch: the one special-point record, with the shooting
#: unknowns ``u`` (the phase of the first impact is ``u[0]``, ``delta`` the motion's) and a
#: :class:`MultiImpactOrbit` (:class:`~impactcont.detection.points.SpecialPoint`).
MultiImpactSpecialPoint = SpecialPoint


def detect_multi_impact_points(problem: Any, samples: Sequence[MultiImpactSample],
                               labels: Sequence[str] = LABELS,
                               on_found: Callable[[MultiImpactSpecialPoint], None] | None = None,
                               ) -> list[MultiImpactSpecialPoint]:
    """The special points of an N-p branch, as ``detect_special_points`` for N-1 motions.

    `problem` provides ``residual``, ``jacobian``, ``dparam`` and
    ``orbit(u, lam, checks=True) -> MultiImpactOrbit`` (e.g.
    :class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem`); the
    samples are :class:`MultiImpactSample` and the result
    :class:`MultiImpactSpecialPoint` in branch order; GR and ZV use the minimum
    over the flights and impacts.
    """
    asked = [Label(label) for label in check_labels(labels, "labels")]
    parameter = getattr(problem, "parameter", "lam")
    # the kinds the problem declares (BP only on a branch of symmetric motions), each but
    # the fold with its test of the motion
    declared = getattr(problem, "events", (Label.SN, *BRANCH_TESTS))
    tests: Mapping[str, MotionTest] = getattr(problem, "motion_tests", BRANCH_TESTS)
    asked = [label for label in asked if label in declared]
    watched = watched_labels(asked)

    orbits = {checks: last_motions(lambda u, lam, c=checks: problem.orbit(u, lam, checks=c))
              for checks in (False, True)}

    def event(label: Label) -> Event:
        test = tests.get(label)
        if test is None:  # the fold: the parameter component of the tangent changes sign
            return Event(label, None)
        # only some tests (GR) need the (costly) interior-contact search of every flight
        return kind_event(label, test, orbits[test.checks], lambda k: samples[k].orbit)

    found: list[MultiImpactSpecialPoint] = []
    located = locate_events(problem, [s.u for s in samples], [s.lam for s in samples],
                            [s.tangent for s in samples], [event(label) for label in watched],
                            s_tol=_S_TOL, newton_tol=_NEWTON_TOL)
    try:
        _classify(problem, samples, located, tests, found)
    except KeyboardInterrupt:  # the first Ctrl-C of a driver's call: those built are kept
        if not (found and take_interrupt(
                "location", "interrupted by the user (KeyboardInterrupt) while computing the "
                "motions at the special points: the %d before are kept", len(found))):
            raise
    # a companion watched but not asked (ZV for GR) only tells which GR to drop
    found = [special for special in drop_grazing_at_zero_velocity(found, parameter)
             if special.label in asked or special.label not in watched]
    for special in found:
        log.info("%s at %s = %.12g (N=%d, p=%d, %s, precision %.1e)", special.label,
                 parameter, special.value, special.orbit.N, special.orbit.p, special.status,
                 special.precision)
        if on_found is not None:
            on_found(special)
    return found


def _classify(problem: Any, samples: Sequence[MultiImpactSample], located: Sequence[Any],
              tests: Mapping[str, MotionTest], found: list[SpecialPoint]) -> None:
    """The records of the `located` zeros that are special points, appended to `found`:
    the motion there, the kind's criticality, a fold that is a BP."""
    parameter = getattr(problem, "parameter", "lam")
    for ep in located:
        orbit = problem.orbit(ep.u, ep.lam)
        test = tests.get(ep.label)
        if not ep.failed and test is not None and test.critical is not None \
                and not test.critical(orbit):
            log.debug("the %s test vanishes near %s=%.12g without a critical multiplier "
                      "(a neutral saddle, or the pole of G at h2 = 0)", ep.label, parameter,
                      ep.lam)
            continue
        label = ep.label
        if label == Label.SN and any(_meets_symmetric_branch(o) for o in (
                orbit, samples[ep.step].orbit, samples[ep.step + 1].orbit)):
            log.debug("the fold at %s=%.12g is where the branch meets the symmetric branch: BP",
                      parameter, ep.lam)
            label = Label.BP
        left, right = samples[ep.step], samples[ep.step + 1]
        nearest = ep.step if abs(ep.lam - left.lam) <= abs(ep.lam - right.lam) else ep.step + 1
        special = SpecialPoint(label=label, value=ep.lam, u=ep.u, point=nearest,
                               bracket=ep.bracket, precision=ep.precision, status=ep.status,
                               orbit=orbit)
        found.append(special)


_MEETS_TOL = 1e-2


def _meets_symmetric_branch(orbit: MultiImpactOrbit) -> bool:
    """Whether a fold of a general N-p branch is a BP: the motion there is symmetric to
    ``_MEETS_TOL`` and its half-map has a multiplier within ``_MEETS_TOL`` of -1."""
    if not symmetry_defect(orbit) <= _MEETS_TOL:
        return False
    H = half_map(orbit)
    return bool(np.all(np.isfinite(H))
                and np.min(np.abs(np.linalg.eigvals(H) + 1.0)) <= _MEETS_TOL)


def locate_multi_impact_events(problem: Any, samples: Sequence[MultiImpactSample],
                               functions: UserFunctions | None, *,
                               position: Callable[[np.ndarray, float], Any] | None = None
                               ) -> tuple[dict[str, np.ndarray], list[UserEvent]]:
    """The user's functions at every sample and the zeros of its events, located.

    As :func:`~impactcont.detection.special_points.locate_user_events` on an N-p branch
    (or curve: `position` gives both parameters of a point): the functions receive the
    full :class:`MultiImpactOrbit` at a point (with its interior-contact checks), also on
    a branch of symmetric motions followed by their half.

    Returns
    -------
    values : dict of str to ndarray
        Each function at every sample (empty without `functions`).
    events : list of UserEvent
        In branch order.
    """
    if not functions:
        return {}, []
    parameter = getattr(problem, "parameter", None)
    values = user_values(functions, [s.orbit for s in samples], parameter)
    events = locate_user_events(problem, [s.u for s in samples], [s.lam for s in samples],
                                [s.tangent for s in samples], functions, values,
                                lambda u, lam: problem.orbit(u, lam), position=position,
                                parameter=parameter)
    return values, events

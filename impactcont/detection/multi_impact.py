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
========  =============================================  ==============================

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
interior maximum changes), or when the PD/NS checks fail (``det(G + I)``
changes sign through the pole of G at a zero impact velocity; the NS product
vanishes at a neutral saddle), in which case the point is dropped.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from impactcont.core.locate import Event, locate_events, tangent_at
from impactcont.detection.locator import drop_grazing_at_zero_velocity, is_critical
from impactcont.detection.special_points import event_function, event_noise
from impactcont.orbit.multi_impact import MultiImpactOrbit
from impactcont.vocabulary import LABELS, check_labels

__all__ = ["MultiImpactSample", "MultiImpactSpecialPoint", "detect_multi_impact_points",
           "tangent_at"]

log = logging.getLogger(__name__)

_S_TOL = 1e-13
_UNIT_TOL = 1e-7
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


@dataclasses.dataclass(frozen=True, eq=False)
class MultiImpactSpecialPoint:
    """A located special point of an N-p branch.

    The fields of :class:`impactcont.detection.SpecialPoint`, with the unknowns
    ``u`` (shape ``(m,)``) of the shooting system in place of the phase ``delta``
    (the phase of the first impact is ``u[0]``) and a :class:`MultiImpactOrbit`.
    """

    label: str
    value: float
    u: np.ndarray
    point: int
    bracket: tuple[float, float]
    precision: float
    status: str
    orbit: MultiImpactOrbit

    @property
    def delta(self) -> float:
        """Forcing phase at impact 0."""
        return self.orbit.delta


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
    check_labels(labels, "labels")
    parameter = getattr(problem, "parameter", "lam")

    def event(label: str) -> Event:
        if label == "SN":
            return Event(label, None)

        def test(u: np.ndarray, lam: float) -> float:
            # only GR needs the (costly) interior-contact search of every flight
            return event_function(label, problem.orbit(u, lam, checks=label == "GR"))

        return Event(label, test, lambda k: event_function(label, samples[k].orbit),
                     lambda k: event_noise(label, samples[k].orbit))

    found: list[MultiImpactSpecialPoint] = []
    for ep in locate_events(problem, [s.u for s in samples], [s.lam for s in samples],
                            [s.tangent for s in samples], [event(lab) for lab in labels],
                            s_tol=_S_TOL, newton_tol=_NEWTON_TOL):
        orbit = problem.orbit(ep.u, ep.lam)
        if not ep.failed and not is_critical(ep.label, orbit.multipliers, _UNIT_TOL):
            log.debug("the %s test vanishes near %s=%.12g without a critical multiplier "
                      "(a neutral saddle, or the pole of G at h2 = 0)", ep.label, parameter,
                      ep.lam)
            continue
        left, right = samples[ep.step], samples[ep.step + 1]
        nearest = ep.step if abs(ep.lam - left.lam) <= abs(ep.lam - right.lam) else ep.step + 1
        special = MultiImpactSpecialPoint(
            label=ep.label, value=ep.lam, u=ep.u, point=nearest, bracket=ep.bracket,
            precision=ep.precision, status=ep.status, orbit=orbit)
        found.append(special)
    found = drop_grazing_at_zero_velocity(found, parameter)
    for special in found:
        log.info("%s at %s = %.12g (N=%d, p=%d, %s, precision %.1e)", special.label,
                 parameter, special.value, special.orbit.N, special.orbit.p, special.status,
                 special.precision)
        if on_found is not None:
            on_found(special)
    return found

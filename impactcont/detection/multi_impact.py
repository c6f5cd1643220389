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
``GR``    ``min_k gap_min_k`` over the p flights         x1 touches b inside a flight
``ZV``    ``min_k impact_velocity_k`` over the p impacts an impact at zero velocity
========  =============================================  ==============================

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
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from impactcont.core.corrector import solve_on_hyperplane
from impactcont.detection.locator import is_critical, locate_zero
from impactcont.detection.special_points import (
    detect_special_points,  # noqa: F401 (docs)
    event_function,
)
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


def tangent_at(problem: Any, u: np.ndarray, lam: float, reference: np.ndarray) -> np.ndarray:
    """Unit null vector of ``[dF/du | dF/dlam]`` with a positive dot product with `reference`."""
    extended = np.column_stack([problem.jacobian(u, lam), problem.dparam(u, lam)])
    t = np.linalg.svd(extended)[2][-1]
    return t if float(t @ reference) >= 0 else -t


class _Chord:
    """The branch between two accepted points, parametrised by the chord ``s in [0, 1]``."""

    def __init__(self, problem: Any, left: MultiImpactSample, right: MultiImpactSample):
        self.problem = problem
        self.left, self.right = left, right
        self.x0 = np.append(left.u, left.lam)
        self.chord = np.append(right.u, right.lam) - self.x0
        self._cache: dict[float, tuple[np.ndarray, float]] = {}

    def point(self, s: float) -> tuple[np.ndarray, float]:
        """``(u, lam)`` of the branch on the hyperplane at chord coordinate ``s``."""
        if s in self._cache:
            return self._cache[s]
        if s == 0.0:
            return self.left.u, self.left.lam
        if s == 1.0:
            return self.right.u, self.right.lam
        found = solve_on_hyperplane(self.problem, self.x0 + s * self.chord, self.chord,
                                    tol=_NEWTON_TOL)
        if not found.converged:
            log.debug("chord Newton at s=%.3g stopped with last step %.3g", s, found.last_step)
        self._cache[s] = (found.u, found.lam)
        return self._cache[s]

    def fold_test(self, s: float) -> float:
        u, lam = self.point(s)
        return float(tangent_at(self.problem, u, lam, self.chord)[-1])


def _locate(chord: _Chord, test: Callable[[float], float]) -> tuple[float, str]:
    cache: dict[float, float] = {}

    def g(s: float) -> float:
        if s not in cache:
            cache[s] = test(s)
        return cache[s]

    g0, g1 = g(0.0), g(1.0)
    if not (math.isfinite(g0) and math.isfinite(g1)) or (g0 < 0) == (g1 < 0):
        return 0.5, "bracketed"  # the re-evaluated ends disagree with the stream: keep bracket
    return locate_zero(g, 0.0, 1.0, _S_TOL)


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
    found: list[MultiImpactSpecialPoint] = []
    parameter = getattr(problem, "parameter", "lam")
    for k in range(len(samples) - 1):
        left, right = samples[k], samples[k + 1]
        chord = _Chord(problem, left, right)
        for label in labels:
            if label == "SN":
                if (left.dlam > 0) == (right.dlam > 0):
                    continue
                test = chord.fold_test
            else:
                before = event_function(label, left.orbit)
                after = event_function(label, right.orbit)
                if not (math.isfinite(before) and math.isfinite(after)
                        and (before < 0) != (after < 0)):
                    continue

                def test(s: float, label: str = label, chord: _Chord = chord) -> float:
                    # only GR needs the (costly) interior-contact search of every flight
                    orbit = problem.orbit(*chord.point(s), checks=label == "GR")
                    return event_function(label, orbit)
            failed = False
            try:
                s, status = _locate(chord, test)
            except (ValueError, np.linalg.LinAlgError) as exc:
                failed = True
                # kept as bracketed (never dropped), at the middle of the step
                log.warning("%s between points %d and %d not located, kept as bracketed: %s",
                            label, k, k + 1, exc)
                s, status = 0.5, "bracketed"
            u, lam = chord.point(s)
            orbit = problem.orbit(u, lam)
            if not failed and not is_critical(label, orbit.multipliers, _UNIT_TOL):
                log.debug("the %s test vanishes near %s=%.12g without a critical multiplier "
                          "(a neutral saddle, or the pole of G at h2 = 0)", label, parameter,
                          lam)
                continue
            ds_s = max(_S_TOL, 4 * np.finfo(float).eps)
            lams = [chord.point(min(max(s + e, 0.0), 1.0))[1] for e in (-ds_s, ds_s)]
            precision = 2 * max(abs(v - lam) for v in lams) + 4 * np.finfo(float).eps * abs(lam)
            nearest = k if abs(lam - left.lam) <= abs(lam - right.lam) else k + 1
            special = MultiImpactSpecialPoint(
                label=label, value=lam, u=np.array(u, float), point=nearest,
                bracket=(min(left.lam, right.lam), max(left.lam, right.lam)),
                precision=float(precision), status=status, orbit=orbit)
            log.info("%s at %s = %.12g (N=%d, p=%d, %s, precision %.1e)", label, parameter, lam,
                     orbit.N, orbit.p, status, precision)
            found.append(special)
            if on_found is not None:
                on_found(special)
    return found

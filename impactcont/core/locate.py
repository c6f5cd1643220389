"""Events along a branch: where a test function changes sign, located on the branch.

An :class:`Event` names a test function of the accepted points (or a fold: the
sign of the tangent's parameter component). :func:`locate_events` watches every
step between two accepted points for a sign change, parametrises the branch
there by the chord coordinate ``s in [0, 1]`` (the point of the branch on the
hyperplane across the chord through ``x_left + s (x_right - x_left)``, found by
:func:`~impactcont.core.corrector.solve_on_hyperplane`; this works through folds)
and locates the zero with :func:`locate_zero`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.problem import FloatArray, Problem

__all__ = ["Event", "EventPoint", "MotionTest", "locate_events", "locate_zero", "tangent_at",
           "zero_precision"]

log = logging.getLogger(__name__)

_EPS = float(np.finfo(float).eps)

#: the rounding noise of a test function, in units of eps times its size at the step's ends
_NOISE_ULPS = 1024.0

#: a chord Newton that stopped with a larger last step (relative) found no branch point
_FAR_STEP = 1e-8


@dataclass(frozen=True, eq=False)
class Event:
    """A point to watch along a branch.

    Attributes
    ----------
    label : str
        What the point is called (e.g. a :class:`~impactcont.vocabulary.Label`).
    test : callable or None
        ``test(u, lam) -> float``, changing sign at the point; ``None``: a fold,
        where the parameter component of the tangent changes sign.
    at_point : callable, optional
        ``at_point(k) -> float``: the test's value at accepted point ``k`` when
        the driver already has it (else ``test`` is evaluated there).
    noise : callable, optional
        ``noise(k) -> float``: the rounding error of the test's value at accepted
        point ``k``. A step whose two ends are both within it of zero changes sign
        by rounding only (a degenerate branch on which the test is zero, e.g. a
        motion resting against the stop) and is not an event.
    """

    label: str
    test: Callable[[FloatArray, float], float] | None
    at_point: Callable[[int], float] | None = None
    noise: Callable[[int], float] | None = None


@dataclass(frozen=True, eq=False)
class MotionTest:
    """A special point a problem declares, as functions of the motion at a branch point.

    A problem lists the tests of its own special points (beyond the built-in ones of
    the detectors) in ``problem.motion_tests``: ``label -> MotionTest``; the detector
    evaluates them on the motion ``problem.orbit(u, lam)`` of each point.

    Attributes
    ----------
    test : callable
        ``test(motion) -> float``, changing sign at the point.
    noise : callable, optional
        ``noise(motion) -> float``: the rounding error of the test (see :class:`Event`).
    critical : callable, optional
        ``critical(motion) -> bool``: whether a located zero is the bifurcation (not,
        e.g., a pole of the test); every zero when None.
    checks : bool
        The test needs the motion's interior-contact search (costly).
    """

    test: Callable[[Any], float]
    noise: Callable[[Any], float] | None = None
    critical: Callable[[Any], bool] | None = None
    checks: bool = False


@dataclass(frozen=True, eq=False)
class EventPoint:
    """Where an event's test function vanishes between accepted points ``k`` and ``k + 1``.

    Attributes
    ----------
    label : str
    u : ndarray
    lam : float
    step : int
        ``k``, the first of the two bracketing accepted points.
    s : float
        Chord coordinate in ``[0, 1]``.
    status : {"located", "bracketed"}
    precision : float
        Bound on the error of `lam`.
    bracket : (float, float)
        The parameter values of the two bracketing points, ascending.
    arclength : (float, float)
        The bracket as an interval of the chord arclength from the branch start.
    failed : bool
        The locator failed (the point is the middle of the step, ``bracketed``).
    """

    label: str
    u: FloatArray
    lam: float
    step: int
    s: float
    status: str
    precision: float
    bracket: tuple[float, float]
    arclength: tuple[float, float]
    failed: bool = False


def locate_zero(g: Callable[[float], float], lo: float, hi: float, xtol: float
                ) -> tuple[float, str]:
    """The zero of `g` in ``[lo, hi]`` by Brent's method, and how well it is known.

    Parameters
    ----------
    g : callable
        The test function along the step (evaluations are best cached by the caller).
    lo, hi : float
        The bracket, where `g` has opposite signs.
    xtol : float
        Absolute tolerance in the coordinate.

    Returns
    -------
    s : float
        The zero, inside ``[lo, hi]``.
    status : {"located", "bracketed"}
        ``located`` when ``|g(s)|`` is at most 1e-6 of the larger end value (plus
        1e-12); else the test function jumps there (a pole) and the point is only
        bracketed.

    Raises
    ------
    ValueError
        When `g` has the same sign at both ends.
    """
    g0, g1 = g(lo), g(hi)
    # Brent is slow on a double zero (superlinear steps keep failing): room to finish
    s = brentq(g, lo, hi, xtol=xtol, rtol=4 * _EPS, maxiter=500)
    scale = max(abs(g0), abs(g1))
    status = "located" if abs(g(s)) <= 1e-6 * max(scale, 1e-300) + 1e-12 else "bracketed"
    return s, status


def tangent_at(problem: Problem, u: FloatArray, lam: float, reference: FloatArray) -> FloatArray:
    """Unit null vector of ``[dF/du | dF/dlam]`` with a positive dot product with `reference`."""
    extended = np.column_stack([problem.jacobian(u, lam), problem.dparam(u, lam)])
    t = np.linalg.svd(extended)[2][-1]
    return t if float(t @ reference) >= 0 else -t


class _Chord:
    """The branch between two accepted points, parametrised by the chord ``s in [0, 1]``."""

    def __init__(self, problem: Problem, x0: FloatArray, x1: FloatArray, newton_tol: float):
        self.problem, self.x0, self.x1 = problem, x0, x1
        self.chord = x1 - x0
        self.newton_tol = newton_tol
        self._cache: dict[float, tuple[FloatArray, float]] = {}

    def point(self, s: float) -> tuple[FloatArray, float]:
        """``(u, lam)`` of the branch on the hyperplane at chord coordinate ``s``."""
        if s in self._cache:
            return self._cache[s]
        if s == 0.0:
            return self.x0[:-1], float(self.x0[-1])
        if s == 1.0:
            return self.x1[:-1], float(self.x1[-1])
        found = solve_on_hyperplane(self.problem, self.x0 + s * self.chord, self.chord,
                                    tol=self.newton_tol)
        if not found.converged:
            log.debug("chord Newton at s=%.3g stopped with last step %.3g", s, found.last_step)
            if not found.last_step <= _FAR_STEP * max(1.0, float(np.max(np.abs(found.x)))):
                raise ValueError(f"no branch point found on the step at chord coordinate "
                                 f"s={s:.6g} (Newton's last step {found.last_step:.3g})")
        self._cache[s] = (found.u, found.lam)
        return self._cache[s]

    def lam(self, s: float) -> float:
        """The parameter of the branch point at ``s``."""
        return self.point(s)[1]

    def fold_test(self, s: float) -> float:
        u, lam = self.point(s)
        return float(tangent_at(self.problem, u, lam, self.chord)[-1])


def _locate(g: Callable[[float], float], s_tol: float) -> tuple[float, str]:
    cache: dict[float, float] = {}

    def cached(s: float) -> float:
        if s not in cache:
            cache[s] = g(s)
        return cache[s]

    g0, g1 = cached(0.0), cached(1.0)
    if not (math.isfinite(g0) and math.isfinite(g1)) or (g0 < 0) == (g1 < 0):
        return 0.5, "bracketed"  # the re-evaluated ends disagree with the stream: keep bracket
    return locate_zero(cached, 0.0, 1.0, s_tol)


def _middle(chord: _Chord) -> tuple[float, str, tuple[FloatArray, float]]:
    """The branch point in the middle of a step, or its first end if that cannot be found."""
    try:
        return 0.5, "bracketed", chord.point(0.5)
    except (ValueError, np.linalg.LinAlgError):
        return 0.0, "bracketed", chord.point(0.0)


def zero_precision(g: Callable[[float], float], position: Callable[[float], Any], s: float,
                   s_tol: float, lo: float = 0.0, hi: float = 1.0) -> float:
    """A bound on the error of a located zero ``s`` of `g`, measured in `position`.

    Two sources: Brent's tolerance `s_tol` on the coordinate, and the rounding noise of
    the test function, taken as ``_NOISE_ULPS`` eps times its size at the ends `lo` and
    `hi` of the bracket. The zero is known only within the interval around `s` where ``|g|``
    is below that noise: it is searched outwards from `s` by factors of 10 until
    ``|g|`` rises above the noise on both sides. A simple zero leaves that interval at
    the first try; a double zero (``g ~ (s - s0)^2``, e.g. a grazing at a zero-velocity
    impact) is known only to about the square root of the noise, and the bound says so.

    Parameters
    ----------
    g : callable
        The test function of the coordinate ``s in [lo, hi]`` (best cached by the caller).
    position : callable
        ``position(s)``: where the point at ``s`` is (the parameter, or the parameters of
        a curve); the bound is twice the largest max-norm distance from ``position(s)``.
    s : float
        The located zero.
    s_tol : float
        Brent's tolerance on ``s``.
    lo, hi : float
        The bracket searched.
    """
    noise = _NOISE_ULPS * _EPS * max(abs(g(lo)), abs(g(hi)))
    here = np.asarray(position(s), dtype=float)

    def distance(t: float) -> float:
        return float(np.max(np.abs(np.asarray(position(t)) - here)))

    ds = max(s_tol, 4 * _EPS)
    reach = 0.0
    for side, end in ((-1.0, lo), (1.0, hi)):
        h = ds
        while True:
            t = min(max(s + side * h, lo), hi)
            try:
                reach = max(reach, distance(t))
                if t == end or abs(g(t)) > noise:
                    break
            except (ValueError, ArithmeticError, RuntimeError, np.linalg.LinAlgError):
                # no branch point there (the corrector failed): as far as that end
                reach = max(reach, distance(end))
                break
            h *= 10.0
    return 2 * reach + 4 * _EPS * float(np.max(np.abs(here)))


def _changes(a: float, b: float) -> bool:
    return math.isfinite(a) and math.isfinite(b) and (a < 0) != (b < 0)


def locate_events(problem: Problem, u: Any, lam: Any, tangent: Any, events: Sequence[Event],
                  *, s_tol: float = 1e-13, newton_tol: float = 1e-13,
                  position: Callable[[FloatArray, float], Any] | None = None
                  ) -> list[EventPoint]:
    """Every sign change of every event between consecutive accepted points, located.

    Parameters
    ----------
    problem : Problem
    u, lam, tangent : array_like
        The accepted points in branch order (shapes ``(n, m)``, ``(n,)``, ``(n, m + 1)``),
        tangents along the branch order.
    events : sequence of Event
    s_tol, newton_tol : float
        Tolerances of the chord coordinate and of the hyperplane Newton.
    position : callable, optional
        ``position(u, lam)``: where a point is, e.g. both parameters of a curve (one of
        them an unknown); ``precision`` bounds the max-norm error of it. Default the
        parameter ``lam``.

    Returns
    -------
    list of EventPoint
        By step, then in the order of `events`; a failed location is kept with
        ``failed=True`` and status ``bracketed`` at the middle of the step.
    """
    if len(lam) < 2:  # no step to search (a run that failed at its start)
        return []
    x = np.column_stack([np.asarray(u, dtype=float), np.asarray(lam, dtype=float)])
    dlam = np.asarray(tangent, dtype=float)[:, -1]
    arclength = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))])
    found: list[EventPoint] = []
    for k in range(len(x) - 1):
        chord = _Chord(problem, x[k], x[k + 1], newton_tol)
        for event in events:
            if event.test is None:
                if (dlam[k] > 0) == (dlam[k + 1] > 0):
                    continue
                g = chord.fold_test
            else:
                value = event.at_point or (lambda j, t=event.test: t(x[j, :-1], x[j, -1]))
                if not _changes(value(k), value(k + 1)):
                    continue
                if event.noise is not None and all(
                        abs(value(j)) <= event.noise(j) for j in (k, k + 1)):
                    log.debug("%s between points %d and %d: a sign change by rounding only",
                              event.label, k, k + 1)
                    continue

                def g(s: float, test: Callable[..., float] = event.test,
                      chord: _Chord = chord) -> float:
                    return test(*chord.point(s))
            failed = False
            try:
                s, status = _locate(g, s_tol)
                uk, lamk = chord.point(s)
            except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
                failed = True  # kept as bracketed (never dropped), at the middle of the step
                log.warning("%s between points %d and %d not located, kept as bracketed: %s",
                            event.label, k, k + 1, exc)
                s, status, (uk, lamk) = _middle(chord)
            if position is None:
                where: Callable[[float], Any] = chord.lam
            else:
                def where(t: float, chord: _Chord = chord) -> Any:
                    return position(*chord.point(t))
            if status == "located":
                precision = zero_precision(g, where, s, s_tol)
            else:  # somewhere on the step: as far as its farther end
                here = np.asarray(where(s), dtype=float)
                precision = max(float(np.max(np.abs(np.asarray(where(end), dtype=float)
                                                    - here))) for end in (0.0, 1.0))
            found.append(EventPoint(
                label=event.label, u=np.array(uk, float), lam=float(lamk), step=k, s=float(s),
                status=status, precision=float(precision),
                bracket=(min(x[k, -1], x[k + 1, -1]), max(x[k, -1], x[k + 1, -1])),
                arclength=(float(arclength[k]), float(arclength[k + 1])), failed=failed))
    return found

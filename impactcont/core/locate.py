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

import functools
import itertools
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.problem import FloatArray, Problem
from impactcont.progress import interrupted, take_interrupt

__all__ = ["Event", "EventPoint", "MotionTest", "crossing_steps", "dip_bottom", "locate_events",
           "locate_zero",
           "parts_beside_poles", "tangent_at", "zero_precision"]

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
    poles : callable, optional
        ``poles(u, lam) -> sequence of float``: quantities whose zeros are poles of the
        test (or where it was multiplied free of one, e.g. the impact velocities ``h2``
        of a PD or NS test cleared of the pole of G). A sign change of the test across
        such a zero is the pole's, not a zero: the step is split at every zero of a
        pole quantity inside it, each part watched on its own (:func:`locate_events`).
    poles_at : callable, optional
        ``poles_at(k)``: the pole quantities at accepted point ``k`` when the driver
        already has them (else ``poles`` is evaluated there).
    noise_at : callable, optional
        ``noise_at(u, lam) -> float``: the rounding error of the test at any point of
        the branch (e.g. of multipliers that lose accuracy next to a pole). Next to a
        pole the test's sign is taken only where it rises above this noise, and a located
        zero's precision counts it (:func:`zero_precision`).
    """

    label: str
    test: Callable[[FloatArray, float], float] | None
    at_point: Callable[[int], float] | None = None
    noise: Callable[[int], float] | None = None
    poles: Callable[[FloatArray, float], Any] | None = None
    poles_at: Callable[[int], Any] | None = None
    noise_at: Callable[[FloatArray, float], float] | None = None


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
    poles : callable, optional
        ``poles(motion) -> sequence of float``: the quantities whose zeros are poles of
        the test or were cleared from it (:attr:`Event.poles`).
    """

    test: Callable[[Any], float]
    noise: Callable[[Any], float] | None = None
    critical: Callable[[Any], bool] | None = None
    checks: bool = False
    poles: Callable[[Any], Any] | None = None


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


def locate_zero(g: Callable[[float], float], lo: float, hi: float, xtol: float,
                noise: Callable[[float], float] | None = None) -> tuple[float, str]:
    """The zero of `g` in ``[lo, hi]`` by Brent's method, and how well it is known.

    Parameters
    ----------
    g : callable
        The test function along the step (evaluations are best cached by the caller).
        It may be ``+inf`` or ``-inf`` on part of the step (a test with no finite value
        there, e.g. the clearance of a flight without an interior extremum): the bracket
        is first halved until both its ends are finite.
    lo, hi : float
        The bracket, where `g` has opposite signs.
    xtol : float
        Absolute tolerance in the coordinate.
    noise : callable, optional
        ``noise(t)``: the rounding error of ``g(t)`` (a value within it is zero).

    Returns
    -------
    s : float
        The zero, inside ``[lo, hi]``.
    status : {"located", "bracketed"}
        ``located`` when `g` vanishes at `s` (:func:`_vanishes`: ``|g(s)|`` is small
        against both the ends of the bracket and `g` on both sides of `s` nearby); else
        `g` changes sign through a pole or a jump there and the point is only bracketed.

    Raises
    ------
    ValueError
        When `g` has the same sign at both ends (or is not a number at one).
    """
    g0, g1 = g(lo), g(hi)
    if not _changes(g0, g1):
        raise ValueError(f"g must have different signs at lo={lo!r} and hi={hi!r}; got "
                         f"{g0!r} and {g1!r}")
    a, b, ga, gb = lo, hi, g0, g1
    while not (math.isfinite(ga) and math.isfinite(gb)) and abs(b - a) > xtol:
        m = 0.5 * (a + b)
        gm = g(m)
        if math.isnan(gm):
            raise ValueError(f"the test function is not a number at {m!r}")
        if _changes(ga, gm):
            b, gb = m, gm
        else:
            a, ga = m, gm
    if math.isfinite(ga) and math.isfinite(gb):
        # Brent is slow on a double zero (superlinear steps keep failing): room to finish
        s = brentq(g, a, b, xtol=xtol, rtol=4 * _EPS, maxiter=500)
    else:  # a jump from infinity: its finite side
        s = a if math.isfinite(ga) else b
    return s, "located" if _vanishes(g, s, lo, hi, (g0, g1), noise) else "bracketed"


#: a located zero: |g| at most this fraction of its size at the bracket's ends ...
_SMALL_AGAINST_ENDS = 1e-6
#: ... and of its size on either side at _NEARBY of the bracket's width
_SMALL_AGAINST_SIDES = 1e-3
_NEARBY = 1e-3


def _vanishes(g: Callable[[float], float], s: float, lo: float, hi: float,
              ends: tuple[float, float], noise: Callable[[float], float] | None = None
              ) -> bool:
    """Whether the sign change of `g` at `s` is a zero, not a pole or a jump.

    A zero: ``|g(s)|`` at most 1e-6 of the larger finite end value (plus 1e-12), and at
    most 1e-3 of ``|g|`` on each side of `s` at a thousandth of the bracket's width (the
    sides inside the bracket; an infinite side counts as large; a side within rounding of
    zero, ``_NOISE_ULPS`` eps times the ends' size or `noise` there, is a flat zero).
    Through a pole ``|g|`` grows towards `s`; across a jump it stays at the size of the
    jump on one side: both fail the second test even when the jump starts next to zero.
    A simple zero passes with ``|g(s)| / |g(s +- d)|`` about ``xtol / d``; a zero of odd
    order k about ``(xtol / d)^k`` (or rounding over ``d^k``).
    """
    gs = g(s)
    if gs == 0.0:
        return True
    if not math.isfinite(gs):
        return False
    scale = max((abs(v) for v in ends if math.isfinite(v)), default=math.inf)
    if not abs(gs) <= _SMALL_AGAINST_ENDS * scale + 1e-12:
        return False
    rounding = _NOISE_ULPS * _EPS * scale  # a side within it: zero there too (a flat zero)
    left, right = min(lo, hi), max(lo, hi)
    d = _NEARBY * (right - left)
    for t in (max(s - d, left), min(s + d, right)):
        if t == s:
            continue
        try:
            side = abs(g(t))
            level = max(rounding, noise(t) if noise is not None else 0.0)
        except (ValueError, ArithmeticError, RuntimeError, np.linalg.LinAlgError):
            continue  # no branch point there: that side says nothing
        if not (abs(gs) <= _SMALL_AGAINST_SIDES * side or side <= level):  # nan: no
            return False
    return True


def tangent_at(problem: Problem, u: FloatArray, lam: float, reference: FloatArray) -> FloatArray:
    """Unit null vector of ``[dF/du | dF/dlam]`` with a positive dot product with `reference`."""
    extended = np.column_stack([problem.jacobian(u, lam), problem.dparam(u, lam)])
    t = np.linalg.svd(extended)[2][-1]
    return t if float(t @ reference) >= 0 else -t


class _Chord:
    """The branch between two accepted points, parametrised by the chord ``s in [0, 1]``."""

    def __init__(self, problem: Problem, x0: FloatArray, x1: FloatArray, newton_tol: float,
                 before: Callable[[], None] | None = None):
        self.problem, self.x0, self.x1 = problem, x0, x1
        self.chord = x1 - x0
        self.newton_tol = newton_tol
        self._cache: dict[float, tuple[FloatArray, float]] = {}
        self._before = before  # called once, before the step's first point

    def point(self, s: float) -> tuple[FloatArray, float]:
        """``(u, lam)`` of the branch on the hyperplane at chord coordinate ``s``."""
        if self._before is not None:
            before, self._before = self._before, None
            before()
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


def _locate(g: Callable[[float], float], s_tol: float, lo: float = 0.0, hi: float = 1.0,
            noise: Callable[[float], float] | None = None) -> tuple[float, str]:
    g0, g1 = g(lo), g(hi)
    if not _changes(g0, g1):
        return 0.5 * (lo + hi), "bracketed"  # the re-evaluated ends disagree: keep bracket
    return locate_zero(g, lo, hi, s_tol, noise)


def _middle(chord: _Chord) -> tuple[float, str, tuple[FloatArray, float]]:
    """The branch point in the middle of a step, or its first end if that cannot be found."""
    try:
        return 0.5, "bracketed", chord.point(0.5)
    except (ValueError, np.linalg.LinAlgError):
        return 0.0, "bracketed", chord.point(0.0)


def zero_precision(g: Callable[[float], float], position: Callable[[float], Any], s: float,
                   s_tol: float, lo: float = 0.0, hi: float = 1.0,
                   noise: Callable[[float], float] | None = None) -> float:
    """A bound on the error of a located zero ``s`` of `g`, measured in `position`.

    Two sources: Brent's tolerance `s_tol` on the coordinate, and the rounding noise of
    the test function, taken as ``_NOISE_ULPS`` eps times its size at the ends `lo` and
    `hi` of the bracket. The zero is known only within the interval around `s` where ``|g|``
    is below that noise: it is searched outwards from `s` by factors of 10 until
    ``|g|`` rises above the noise on both sides. A simple zero leaves that interval at
    the first try; a double zero (``g ~ (s - s0)^2``, e.g. a grazing at a zero-velocity
    impact) is known only to about the square root of the noise, and the bound says so.
    Where the test's own rounding is known (`noise`, e.g. multipliers next to a pole of
    G that lose ``1 / h2^2`` of their accuracy) the noise is the larger of the two.

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
    noise : callable, optional
        ``noise(t)``: the rounding error of ``g(t)``.
    """
    floor = _NOISE_ULPS * _EPS * max((abs(v) for v in (g(lo), g(hi)) if math.isfinite(v)),
                                     default=0.0)

    def above_noise(t: float) -> bool:
        value = abs(g(t))
        return value > floor and (noise is None or value > noise(t))

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
                if t == end or above_noise(t):
                    break
            except (ValueError, ArithmeticError, RuntimeError, np.linalg.LinAlgError):
                # no branch point there (the corrector failed): as far as that end
                reach = max(reach, distance(end))
                break
            h *= 10.0
    return 2 * reach + 4 * _EPS * float(np.max(np.abs(here)))


def _changes(a: float, b: float) -> bool:
    """Opposite signs; ``+inf`` and ``-inf`` count by their sign, NaN as no sign."""
    return not (math.isnan(a) or math.isnan(b)) and (a < 0) != (b < 0)


def locate_events(problem: Problem, u: Any, lam: Any, tangent: Any, events: Sequence[Event],
                  *, s_tol: float = 1e-13, newton_tol: float = 1e-13,
                  position: Callable[[FloatArray, float], Any] | None = None,
                  before_step: Callable[[int], None] | None = None) -> list[EventPoint]:
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
    before_step : callable, optional
        ``before_step(k)``: called before the first point inside step ``k`` is computed,
        on the steps searched only (a curve renews the borders of its augmented system).

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
    # each event's test at the accepted points, evaluated once each (ends and neighbours)
    values = {id(event): functools.cache(event.at_point or (
        lambda j, t=event.test: t(x[j, :-1], x[j, -1]))) for event in events if event.test}
    # and its pole quantities there (a step reads both its ends', a point ends two steps)
    poles = {id(event): functools.cache(functools.partial(_poles_at_point, event, x))
             for event in events if event.test and event.poles is not None}
    k = 0
    try:
        for k in range(len(x) - 1):
            if interrupted("location"):  # Ctrl-C taken in an earlier location of the call
                break
            _locate_step(problem, x, dlam, arclength, k, events, (values, poles), found,
                         s_tol, newton_tol, position, before_step)
    except KeyboardInterrupt:  # the first Ctrl-C of a driver's call: those located are kept
        if not (found and take_interrupt(
                "location", "interrupted by the user (KeyboardInterrupt) while locating "
                "between points %d and %d: that one is dropped, the %d located before are "
                "kept", k, k + 1, len(found))):
            raise
    return found


def _locate_step(problem: Problem, x: FloatArray, dlam: FloatArray, arclength: FloatArray,
                 k: int, events: Sequence[Event],
                 at_points: tuple[dict[int, Callable[[int], float]],
                                  dict[int, Callable[[int], np.ndarray]]],
                 found: list[EventPoint], s_tol: float, newton_tol: float,
                 position: Callable[[FloatArray, float], Any] | None,
                 before_step: Callable[[int], None] | None) -> None:
    """The events of :func:`locate_events` in step ``k``, appended to `found` (`at_points`:
    each event's test and pole quantities at the accepted points, by ``id(event)``)."""
    values, poles = at_points
    chord = _Chord(problem, x[k], x[k + 1], newton_tol,
                   None if before_step is None else lambda k=k: before_step(k))
    if position is None:
        where: Callable[[float], Any] = chord.lam
    else:
        def where(t: float, chord: _Chord = chord) -> Any:
            return position(*chord.point(t))
    for event in events:
        noise: Callable[[float], float] | None = None
        if event.test is None:
            if (dlam[k] > 0) == (dlam[k + 1] > 0):
                continue
            g: Callable[[float], float] = chord.fold_test
            parts = [(0.0, 1.0)]
        else:
            # at the step's ends the test (and its noise) of the accepted points; a curve
            # renews its borders before the step's first point: its ends are evaluated there
            known, value = before_step is None, values[id(event)]
            g = _cached(lambda s, test=event.test, chord=chord: test(*chord.point(s)),
                        (lambda i, v=value: v(k + i)) if known else None)
            if event.noise_at is not None:
                noise = _cached(lambda s, n=event.noise_at, chord=chord: n(*chord.point(s)),
                                (lambda i, n=event.noise: n(k + i))
                                if known and event.noise is not None else None)
            parts = _watched_parts(event, values[id(event)], x, k, chord, g, noise,
                                   arclength, poles.get(id(event)))
        for lo, hi in parts:
            found.append(_event_point(event.label, chord, g, noise, where, lo, hi, k, x,
                                      arclength, s_tol))


def _cached(f: Callable[[float], float], end: Callable[[int], Any] | None = None
            ) -> Callable[[float], float]:
    """`f` evaluated once per chord coordinate (its value as a float; a call that raises
    keeps nothing). A plain table: ``functools.cache`` costs a few microseconds to build,
    and a branch builds two per watched event and step. With `end`, the values at the
    coordinates 0 and 1 are ``end(0)`` and ``end(1)`` (what the accepted points already
    have), not evaluated on the chord again."""
    known: dict[float, float] = {}

    def cached(s: float) -> float:
        value = known.get(s)
        if value is None:
            at_end = end is not None and (s == 0.0 or s == 1.0)
            value = known[s] = float(end(int(s)) if at_end else f(s))
        return value
    return cached


def _watched_parts(event: Event, value: Callable[[int], float], x: FloatArray, k: int,
                   chord: _Chord, g: Callable[[float], float],
                   noise: Callable[[float], float] | None, arclength: FloatArray,
                   poles: Callable[[int], np.ndarray] | None = None
                   ) -> list[tuple[float, float]]:
    """The parts ``[lo, hi]`` of step `k` (chord coordinates) where `event`'s test changes
    sign (`value`: the test at accepted point ``j``; `poles`, optional: its pole quantities
    there, :func:`_poles_at_point`): the whole step; or, across the zeros
    of the event's pole quantities inside it, the parts between them
    (:func:`parts_beside_poles`); or, where the test has the same sign at both ends but
    dips through zero and back inside the step (:func:`dip_bottom`), the two halves of the
    step at the dip's bottom."""
    cuts = _pole_cuts(event, x, k, chord, poles) if event.poles is not None else []
    if cuts:
        return parts_beside_poles(event.label, g, noise, cuts, k)

    def rounding_only() -> bool:  # both ends within the test's rounding of zero
        return event.noise is not None and all(
            abs(value(j)) <= event.noise(j) for j in (k, k + 1))

    if _changes(value(k), value(k + 1)):
        if not rounding_only():
            return [(0.0, 1.0)]
        log.debug("%s between points %d and %d: a sign change by rounding only",
                  event.label, k, k + 1)
        return []
    bottom = dip_bottom(value, arclength, k)
    if bottom is None or rounding_only():
        return []
    try:
        low = g(bottom)
        level = noise(bottom) if noise is not None else 0.0
    except (ValueError, ArithmeticError, RuntimeError, np.linalg.LinAlgError):
        return []
    if not _changes(value(k), low) or abs(low) <= level:
        return []
    log.info("%s dips through zero and back between points %d and %d: two sign changes",
             event.label, k, k + 1)
    return [(0.0, bottom), (bottom, 1.0)]


def dip_bottom(value: Callable[[int], float], arclength: FloatArray, k: int) -> float | None:
    """Where the test may dip through zero and back inside step `k`: the chord coordinate
    of the bottom of a parabola through the test at three consecutive points (step `k` and
    the point before, or after) whose two zeros both lie inside the step; else None.

    A test function sampled at the accepted points only shows a sign change when its zeros
    are an odd number per step; a pair of them in one step (a clearance dipping through the
    stop and back, a pair of multipliers crossing out and back) shows in the curvature of
    the samples around it. Only a suspected dip costs an evaluation (at its bottom).
    """
    t0, t1 = float(arclength[k]), float(arclength[k + 1])
    width = t1 - t0
    if not width > 0.0:
        return None
    size = len(arclength)
    for i in (k - 1, k):  # the triples (i, i + 1, i + 2) around the step
        if i < 0 or i + 2 >= size:
            continue
        p, q, r = (float(arclength[i]) - t0, float(arclength[i + 1]) - t0,
                   float(arclength[i + 2]) - t0)
        yp, yq, yr = float(value(i)), float(value(i + 1)), float(value(i + 2))
        if not (p < q < r and math.isfinite(yp) and math.isfinite(yq) and math.isfinite(yr)):
            continue
        # the parabola a t^2 + b t + c through the three samples (divided differences)
        first = (yq - yp) / (q - p)
        a = ((yr - yq) / (r - q) - first) / (r - p)
        b = first - a * (p + q)
        c = yp - first * p + a * p * q
        discriminant = b * b - 4.0 * a * c
        if a == 0.0 or not discriminant > 0.0:
            continue
        root = math.sqrt(discriminant)
        lo, hi = (-b - root) / (2.0 * a), (-b + root) / (2.0 * a)
        if min(lo, hi) > 0.0 and max(lo, hi) < width:
            return min(max(-b / (2.0 * a) / width, 0.0), 1.0)
    return None


def _poles_at_point(event: Event, x: FloatArray, j: int) -> np.ndarray:
    """The event's pole quantities at accepted point `j` (:attr:`Event.poles_at` when the
    driver has them), as a float array."""
    assert event.poles is not None
    if event.poles_at is not None:
        return np.atleast_1d(np.asarray(event.poles_at(j), dtype=float))
    return np.atleast_1d(np.asarray(event.poles(x[j, :-1], x[j, -1]), dtype=float))


def _pole_cuts(event: Event, x: FloatArray, k: int, chord: _Chord,
               poles: Callable[[int], np.ndarray] | None = None) -> list[float]:
    """The chord coordinates of the zeros of the event's pole quantities on step `k`
    (`poles`: them at accepted point ``j``, :func:`_poles_at_point` by default)."""
    assert event.poles is not None
    if poles is None:
        poles = functools.partial(_poles_at_point, event, x)
    left, right = poles(k), poles(k + 1)
    cuts = []
    crossing = [i for i, (a, b) in enumerate(zip(left.tolist(), right.tolist(), strict=True))
                if _changes(a, b)]
    for i in crossing:
        def h(s: float, i: int = int(i)) -> float:
            return float(np.atleast_1d(np.asarray(event.poles(*chord.point(s)), float))[i])
        try:
            cut = float(brentq(h, 0.0, 1.0, xtol=1e-14, rtol=4 * _EPS, maxiter=200))
        except (ValueError, RuntimeError, ArithmeticError, np.linalg.LinAlgError) as exc:
            cut = float(left[i] / (left[i] - right[i]))  # where it crosses, linearly
            log.debug("pole %d of %s between points %d and %d placed linearly at s=%.6g: %s",
                      i, event.label, k, k + 1, cut, exc)
        cuts.append(min(max(cut, 0.0), 1.0))
    return sorted(set(cuts))


#: the first distance (relative to a part's width) at which a test is read next to a pole
_POLE_OFFSET = 1e-7
#: next to a pole the test's sign is read where it is this many times its noise
_POLE_MARGIN = 10.0


def parts_beside_poles(label: str, g: Callable[[float], float],
                       noise: Callable[[float], float] | None, cuts: list[float], k: int = -1
                       ) -> list[tuple[float, float]]:
    """The parts of a step between the zeros `cuts` of the pole quantities where the test
    changes sign.

    Next to a pole the test's sign is read where it first rises well above its noise (ten
    times its own, ``noise``, and ``_NOISE_ULPS`` eps times its size at the step's ends),
    at distances from the pole growing by factors of 10 from ``1e-7`` of the part up to
    half of it; a part without such a point says nothing. A sign change across a pole is the
    pole's: not an event (logged). A zero of the test closer to a pole than where its
    sign can be read cannot be told from the pole's and is not reported either.

    Parameters
    ----------
    label : str
        The event, for the log.
    g, noise : callable
        The test and its rounding error (or None) at a chord coordinate in ``[0, 1]``.
    cuts : list of float
        The poles' chord coordinates, ascending.
    k : int
        The step, for the log.

    Returns
    -------
    list of (float, float)
        The parts ``(lo, hi)`` with a sign change of `g` at their ends.
    """
    floor = _NOISE_ULPS * _EPS * max(
        (abs(v) for v in (g(0.0), g(1.0)) if math.isfinite(v)), default=0.0)

    def readable(t: float) -> float | None:
        try:
            value = g(t)
            level = max(floor, noise(t) if noise is not None else 0.0)
        except (ValueError, ArithmeticError, RuntimeError, np.linalg.LinAlgError):
            return None
        return value if abs(value) > _POLE_MARGIN * level else None

    def beside(cut: float, towards: float) -> float | None:
        width = abs(towards - cut)
        d = _POLE_OFFSET * width
        while d <= 0.5 * width:
            t = cut + math.copysign(d, towards - cut)
            if readable(t) is not None:
                return t
            d *= 10.0
        return None

    edges = [0.0, *cuts, 1.0]
    parts = []
    for a, b in itertools.pairwise(edges):
        if b <= a:
            continue
        lo = a if a == 0.0 else beside(a, b)
        hi = b if b == 1.0 else beside(b, a)
        if lo is None or hi is None or not lo < hi:
            continue
        if _changes(g(lo), g(hi)):
            parts.append((lo, hi))
    if not parts and _changes(g(0.0), g(1.0)):
        log.info("%s changes sign on step %d only through the pole of its test (at chord "
                 "coordinate %s): not a special point", label, k,
                 ", ".join(f"{c:.6g}" for c in cuts))
    return parts


def _event_point(label: str, chord: _Chord, g: Callable[[float], float],
                 noise: Callable[[float], float] | None, where: Callable[[float], Any],
                 lo: float, hi: float, k: int, x: FloatArray, arclength: FloatArray,
                 s_tol: float) -> EventPoint:
    """The event's zero in the part ``[lo, hi]`` of step `k`, located or bracketed."""
    failed = False
    try:
        s, status = _locate(g, s_tol, lo, hi, noise)
        uk, lamk = chord.point(s)
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
        failed = True  # kept as bracketed (never dropped), at the middle of the step
        log.warning("%s between points %d and %d not located, kept as bracketed: %s",
                    label, k, k + 1, exc)
        s, status, (uk, lamk) = _middle(chord)
        lo, hi = 0.0, 1.0
    if status == "located":
        precision = zero_precision(g, where, s, s_tol, lo, hi, noise=noise)
    else:  # somewhere in the part: as far as its farther end
        here = np.asarray(where(s), dtype=float)
        precision = max(float(np.max(np.abs(np.asarray(where(end), dtype=float) - here)))
                        for end in (lo, hi))
    return EventPoint(
        label=label, u=np.array(uk, float), lam=float(lamk), step=k, s=float(s),
        status=status, precision=float(precision),
        bracket=(min(x[k, -1], x[k + 1, -1]), max(x[k, -1], x[k + 1, -1])),
        arclength=(float(arclength[k]), float(arclength[k + 1])), failed=failed)


def crossing_steps(values: np.ndarray, value: float) -> list[tuple[int, float]]:
    """The steps ``k -> k + 1`` of a polyline that cross ``value``, with the fraction
    ``t`` of the step where the chord does.

    A crossing exactly at a point is reported once (on the step that ends there), and a
    step along ``value`` (both ends equal) is none.
    """
    kept: list[int] = []
    for k in np.flatnonzero((values[:-1] - value) * (values[1:] - value) <= 0):
        if values[k] == values[k + 1] or (kept and kept[-1] == k - 1 and values[k] == value):
            continue
        kept.append(int(k))
    return [(k, float((value - values[k]) / (values[k + 1] - values[k]))) for k in kept]

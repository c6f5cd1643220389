"""Reliable location of the turning points and stop crossings of a stop coordinate.

Sampling alone can miss a short excursion past a stop. The stretch searched is cut into
cells short against the fastest motion the coordinate ``y`` sees (:func:`search_grid`:
1/16 of its shortest damped period, refined geometrically near the start for a fast
over-damped decay). Within a cell ``y''`` changes sign at most once, so the roots of
``y''`` (located in the cells where it changes sign) cut the stretch into pieces on
which ``y'`` is monotone: each holds at most one root of ``y'``, a turning point of
``y`` (:func:`turning_points`). Between consecutive turning points ``y`` is monotone and
crosses a stop level at most once (:func:`first_crossing`). Every root is polished to a
few ulps by Newton's method (with ``y''``: the quadratic Taylor step) kept inside its
bracket (:func:`newton_in_brackets`), a crossing to a few ulps or to where ``y`` is within
its own rounding of the level, whichever is wider. A
crossing is missed only if ``y''`` changes sign twice inside one cell, i.e. only for a
component faster than the grid was built for.

The evaluator is the simulator's own (:class:`impactcont.simulate.flight.StopMotion`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from impactcont.errors import UnresolvedMotionWarning
from impactcont.simulate.flight import Flight, StopMotion

__all__ = ["first_crossing", "newton_in_brackets", "search_grid", "turning_points"]

_CELLS_PER_PERIOD = 16
_MAX_CELLS = 2_000_000
_ABS_TOL = 1e-15
_REL_TOL = 4.0 * float(np.finfo(float).eps)
_MAX_STEPS = 200
# an evaluation of a stop coordinate is exact to this many ulps of the terms it is summed
# from (StopMotion.size): a crossing found where it is within that of its level is found
_NOISE_ULPS = 4.0
_EPS = float(np.finfo(float).eps)


def search_grid(flight: Flight, t0: float, t1: float, normal: Any, *,
                row: np.ndarray | None = None) -> np.ndarray:
    """Times on ``[t0, t1]``, both ends included, with at most one root of ``y''`` per cell.

    Parameters
    ----------
    flight : Flight
    t0, t1 : float
        The stretch, ``t1 > t0``.
    normal : array_like, shape (n,)
        The stop coordinate ``y = normal . x`` searched: the cells follow the time scales
        of the modes it sees (:meth:`Flight.time_scales`).
    row : ndarray, optional
        Instead of `normal`: a linear function ``row . Y`` of the flight's internal state
        (a contact force, :meth:`Flight.row_scales`).

    Returns
    -------
    ndarray
        Sorted times.

    Warns
    -----
    UnresolvedMotionWarning
        When the grid would need more than ``_MAX_CELLS`` cells (it is capped there).
    """
    rate, decay = flight.time_scales(normal) if row is None else flight.row_scales(row)
    span = t1 - t0
    cells = max(math.ceil(span * _CELLS_PER_PERIOD * rate / (2.0 * math.pi)), 8)
    if cells > _MAX_CELLS:
        warnings.warn(f"contact search grid capped at {_MAX_CELLS} cells for a stretch of "
                      f"{span:.3g} (the fastest damped frequency {rate:.3g} asks for {cells}): "
                      "a short excursion past a stop (eq. 16) may be missed; damping the "
                      "fastest modes or a shorter period avoids this",
                      UnresolvedMotionWarning, stacklevel=2)
        cells = _MAX_CELLS
    grid = np.linspace(t0, t1, cells + 1)
    width = span / cells
    if decay > 0.0 and 1.0 / (_CELLS_PER_PERIOD * decay) < width:
        # a decay faster than a cell right after the start: halve the first cell until the
        # smallest piece resolves it
        halvings = math.ceil(math.log2(width * _CELLS_PER_PERIOD * decay))
        grid = np.union1d(grid, t0 + width * 0.5 ** np.arange(1, halvings + 1))
    return grid


def newton_in_brackets(fun: Callable[[np.ndarray], tuple[np.ndarray, ...]],
                       lo: np.ndarray, hi: np.ndarray, at_lo: np.ndarray,
                       at_hi: np.ndarray | None = None, noise: float = 0.0) -> np.ndarray:
    """One root of ``g`` in each bracket, all brackets iterated at once.

    Parameters
    ----------
    fun : callable
        ``fun(t) -> (g(t), g'(t))`` or ``(g(t), g'(t), g''(t))`` for an array of times.
        With ``g''`` each step goes to the root of the quadratic Taylor model nearest the
        iterate (where it has one), not the Newton step: a root near a turning point of
        ``g`` (the small bounces of a chatter: ``g`` close to a parabola whose vertex lies
        just below zero) is then reached in a few steps, where Newton's steps from the far
        side only halve the distance.
    lo, hi : ndarray
        Brackets, ``lo < hi``, with ``g`` of opposite signs (``< 0`` against ``>= 0``) at
        their ends.
    at_lo : ndarray
        ``g(lo)`` (its sign is what is read).
    at_hi : ndarray, optional
        ``g(hi)``: the first iterate is then the false position (the secant's root) of
        the bracket, when strictly inside it, rather than its midpoint.
    noise : float
        The rounding of ``g``'s evaluation (``>= 0``): an iterate on the side of ``lo``
        (``g`` of the sign of ``g(lo)``) where ``|g|`` is within it is a root (a bracket
        narrower than ``noise / |g'|`` cannot be told from rounding; bisecting it further
        costs evaluations and finds no better root). Only on that side: the root of a
        crossing of a stop level is never past the level.

    Returns
    -------
    ndarray
        The roots, to a few ulps (or to ``noise / |g'|``): each iteration keeps the part of
        the bracket where the sign changes and takes the step from the last iterate when
        it lands strictly inside that part, else its midpoint (so the bracket shrinks every
        iteration and the convergence near a simple root is quadratic, cubic with
        ``g''``).

    Notes
    -----
    Near a root ``g`` is known only to rounding: its sign may flip between neighbouring
    iterates while the Newton step between them stays above the tolerance. A step landing
    on an end of the bracket (a previous iterate) would then cycle between the two ends
    without shrinking the bracket; it is replaced by the midpoint.
    """
    left = np.array(lo, dtype=float)
    right = np.array(hi, dtype=float)
    negative_left = np.asarray(at_lo, dtype=float) < 0
    t = 0.5 * (left + right)
    if at_hi is not None:
        g_lo = np.asarray(at_lo, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            secant = left - g_lo * (right - left) / (np.asarray(at_hi, dtype=float) - g_lo)
        inside = np.isfinite(secant) & (secant > left) & (secant < right)
        t = np.where(inside, secant, t)
    todo = np.arange(t.size)
    for _ in range(_MAX_STEPS):
        if todo.size == 0:
            break
        here = t[todo]
        values = fun(here)
        g, slope = values[0], values[1]
        same = (g < 0) == negative_left[todo]  # the sign change is right of `here`
        left[todo] = np.where(same, here, left[todo])
        right[todo] = np.where(same, right[todo], here)
        width = right[todo] - left[todo]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            step = g / slope
            if len(values) > 2:  # the root of the quadratic model nearest the iterate
                disc = slope * slope - 2.0 * g * values[2]
                quadratic = 2.0 * g / (slope + np.copysign(np.sqrt(np.abs(disc)), slope))
                step = np.where((disc >= 0) & np.isfinite(quadratic), quadratic, step)
        tol = _ABS_TOL + _REL_TOL * np.abs(here)
        small = np.abs(step) <= tol  # converged: judged before the safeguard
        # within rounding of the root on the side of `lo` (before the sign change: a
        # crossing's root is never past its level)
        rounding = same & (np.abs(g) <= noise)
        done = (g == 0) | rounding | small | (width <= tol)
        guess = here - step
        kept = np.isfinite(guess) & (guess > left[todo]) & (guess < right[todo])
        guess = np.where(kept | (done & small), guess, 0.5 * (left[todo] + right[todo]))
        t[todo] = np.where((g == 0) | rounding, here, guess)
        todo = todo[~done]
    return t


def _sign_changes(values: np.ndarray) -> np.ndarray:
    """Indices i where ``values[i]`` and ``values[i + 1]`` lie on either side of 0."""
    below = values < 0
    return np.flatnonzero(below[:-1] != below[1:])


def _derivative_roots(motion: StopMotion, order: int, times: np.ndarray,
                      values: np.ndarray) -> np.ndarray:
    """Roots of ``y^(order)`` in the cells of `times` where `values` (``y^(order)`` there)
    changes sign, polished with ``y^(order + 1)`` as the slope (and ``y^(order + 2)`` as
    the curvature, where the motion gives it)."""
    cells = _sign_changes(values)

    def fun(s: np.ndarray) -> tuple[np.ndarray, ...]:
        d = motion.derivatives(s)
        return tuple(d[order:order + 3])

    return newton_in_brackets(fun, times[cells], times[cells + 1], values[cells],
                              values[cells + 1])


def turning_points(motion: StopMotion, grid: np.ndarray) -> np.ndarray:
    """Every root of ``y'`` strictly inside the grid's span, sorted.

    Parameters
    ----------
    motion : StopMotion
        The coordinate searched and its derivatives.
    grid : ndarray
        From :func:`search_grid`.

    Returns
    -------
    ndarray
        Times where ``y'`` vanishes.
    """
    inflections = _derivative_roots(motion, 2, grid, motion.derivatives(grid)[2])
    pieces = np.union1d(grid, inflections)  # y' monotone on each piece
    roots = _derivative_roots(motion, 1, pieces, motion.derivatives(pieces)[1])
    return np.unique(roots[(roots > grid[0]) & (roots < grid[-1])])


def first_crossing(motion: StopMotion, level: float, grid: np.ndarray, *,
                   after: float = -math.inf, released: bool = False) -> float | None:
    """When ``y`` first reaches `level` from below in ``(grid[0], grid[-1]]``, to a few ulps
    or to where ``y`` is within 4 ulps of its size (:meth:`StopMotion.size`) of `level`
    (None when ``y < level`` throughout): the first piece between the grid's times and the
    turning points of ``y`` whose left end is below `level` and whose right end is not.

    A crossing whose piece ends by `after` is ignored: the rounding-size excursion of a
    flight that starts on a stop and leaves it. With `released` (a flight that leaves the
    stop at zero speed and acceleration: a release) `after` is itself a piece's end: such
    a flight starts with ``y``, ``y'`` and ``y''`` zero up to rounding, so the first cell
    may hold the sign changes of ``y''`` and ``y'`` at the start and at the apex of a
    short hop together, where the cell rule sees none (a ball released from a table that
    landed again within that cell was searched past its landing); from `after` (the
    separation time) on ``y`` is below `level` beyond rounding, so the landing is
    bracketed. `grid` comes from :func:`search_grid`.
    """
    pieces = np.union1d(grid, turning_points(motion, grid))  # y monotone on each piece
    if released and grid[0] < after < grid[-1]:
        pieces = np.union1d(pieces, [after])
    gap = motion(pieces)[0] - level
    up = np.flatnonzero((gap[:-1] < 0) & (gap[1:] >= 0) & (pieces[1:] > after))
    if up.size == 0:
        return None
    i = int(up[0])

    def fun(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        y, slope, curvature = motion(s)
        return y - level, slope, curvature

    noise = _NOISE_ULPS * _EPS * (motion.size() + abs(level))
    return float(newton_in_brackets(fun, pieces[i:i + 1], pieces[i + 1:i + 2], gap[i:i + 1],
                                    gap[i + 1:i + 2], noise)[0])

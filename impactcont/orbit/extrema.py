"""Reliable location of the critical points and stop crossings of ``x1(t)``.

Sampling alone can miss a short excursion of mass 1 past the stop. Here the
interval is cut into cells short against the fastest motion present (1/16 of
the shortest damped period, and geometrically refined near the start for fast
over-damped decays). In each cell the roots of ``x1''`` split ``x1'`` into
monotone pieces, each holding at most one root of ``x1'``; those roots split
``x1`` into monotone pieces, each holding at most one crossing of the stop.
Every root is then polished by Brent's method to machine precision. A root is
missed only if ``x1''`` changes sign twice inside one cell, i.e. only for a
component faster than the grid was built for.
"""

from __future__ import annotations

import itertools
import logging
import math

import numpy as np
from scipy.optimize import brentq

from impactcont.orbit.flow import Flow, Mass1Motion

__all__ = ["critical_points", "first_upward_crossing", "interior_maxima", "sample_times"]

log = logging.getLogger(__name__)

_CELLS_PER_PERIOD = 16
_MAX_SAMPLES = 2_000_000
_XTOL = 1e-15
_RTOL = 4.0 * np.finfo(float).eps


def _time_scales(flow: Flow) -> tuple[float, float]:
    """Fastest oscillation frequency and fastest decay rate seen by mass 1."""
    part = np.abs(flow.u[0]) > 0
    w, a = flow.w[part], flow.a[part]
    d = (w - a) * (w + a)
    wd = np.sqrt(np.maximum(d, 0.0))
    fast = a + np.sqrt(np.maximum(-d, 0.0))
    return float(max(flow.omega, wd.max(initial=0.0))), float(fast.max(initial=0.0))


def sample_times(flow: Flow, t0: float, t1: float) -> np.ndarray:
    """Grid on ``[t0, t1]`` fine enough that each cell holds at most one root of ``x1''``.

    Parameters
    ----------
    flow : Flow
    t0, t1 : float
        Interval, ``t1 > t0``.

    Returns
    -------
    ndarray
        Sorted times including both ends.
    """
    osc_rate, decay_rate = _time_scales(flow)
    h = 2.0 * math.pi / (_CELLS_PER_PERIOD * osc_rate)
    length = t1 - t0
    count = max(math.ceil(length / h), 8)
    if count > _MAX_SAMPLES:
        log.warning("x1 search grid capped at %d cells for an interval of %.3g (fastest "
                    "frequency %.3g); short excursions may be missed", _MAX_SAMPLES, length,
                    osc_rate)
        count = _MAX_SAMPLES
    grid = np.linspace(t0, t1, count + 1)
    cell = length / count
    tau = 1.0 / (_CELLS_PER_PERIOD * decay_rate) if decay_rate > 0 else cell
    if tau < cell:
        # fast over-damped transients right after the start: geometric refinement
        k = math.ceil(math.log2(cell / tau))
        extra = t0 + cell * np.exp2(-np.arange(1, k + 1))
        grid = np.union1d(grid, extra)
    return grid


def _root(fun, lo: float, hi: float) -> float:
    return brentq(fun, lo, hi, xtol=_XTOL, rtol=_RTOL)


def _changes(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    return (left < 0) != (right < 0)


def critical_points(motion: Mass1Motion, grid: np.ndarray) -> np.ndarray:
    """All roots of ``x1'(t)`` strictly inside the grid's span, sorted.

    Parameters
    ----------
    motion : Mass1Motion
        Evaluator of ``x1, x1', x1''``.
    grid : ndarray
        Sorted times from :func:`sample_times`.

    Returns
    -------
    ndarray
        Times where the velocity of mass 1 vanishes.
    """
    _, v, acc = motion(grid)
    cells = np.flatnonzero(_changes(v[:-1], v[1:]) | _changes(acc[:-1], acc[1:]))
    vel = lambda s: motion(s)[1][0]  # noqa: E731
    accel = lambda s: motion(s)[2][0]  # noqa: E731
    roots: list[float] = []
    for i in cells:
        ta, tb = grid[i], grid[i + 1]
        bounds = [(ta, v[i]), (tb, v[i + 1])]
        if (acc[i] < 0) != (acc[i + 1] < 0):
            tc = _root(accel, ta, tb)
            bounds.insert(1, (tc, vel(tc)))
        for (lo, vlo), (hi, vhi) in itertools.pairwise(bounds):
            if (vlo < 0) != (vhi < 0):
                roots.append(_root(vel, lo, hi))
    inner = [r for r in roots if grid[0] < r < grid[-1]]
    return np.unique(np.array(inner, dtype=float))


def interior_maxima(motion: Mass1Motion, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times and values of the local maxima of ``x1`` strictly inside the grid's span."""
    cp = critical_points(motion, grid)
    if cp.size == 0:
        return cp, cp
    x, _, acc = motion(cp)
    keep = acc < 0
    return cp[keep], x[keep]


def first_upward_crossing(motion: Mass1Motion, level: float, grid: np.ndarray
                          ) -> float | None:
    """First time in ``(grid[0], grid[-1]]`` where ``x1`` reaches ``level`` from below.

    Parameters
    ----------
    motion : Mass1Motion
    level : float
        The stop position ``b``.
    grid : ndarray
        Sorted times from :func:`sample_times`.

    Returns
    -------
    float or None
        The crossing time, to machine precision, or None if ``x1 < level`` throughout.
    """
    cp = critical_points(motion, grid)
    points = np.union1d(grid, cp)
    x = motion(points)[0] - level
    hit = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    if hit.size == 0:
        return None
    i = int(hit[0])
    return _root(lambda s: motion(s)[0][0] - level, points[i], points[i + 1])

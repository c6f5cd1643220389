"""Reliable location of the critical points and stop crossings of ``x1(t)``.

Sampling alone can miss a short excursion of mass 1 past the stop. Here the
interval is cut into cells short against the fastest motion present (1/16 of
the shortest damped period, and geometrically refined near the start for fast
over-damped decays). In each cell the roots of ``x1''`` split ``x1'`` into
monotone pieces, each holding at most one root of ``x1'``; those roots split
``x1`` into monotone pieces, each holding at most one crossing of the stop.
Every root is then polished to machine precision by safeguarded Newton. A root is
missed only if ``x1''`` changes sign twice inside one cell, i.e. only for a
component faster than the grid was built for.
"""

from __future__ import annotations

import logging
import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from impactcont.errors import ParameterError, UnresolvedMotionWarning
from impactcont.orbit.flow import Flow, Mass1Motion, flow_of

__all__ = ["bracketed_roots", "critical_points", "displacement_extrema", "first_upward_crossing",
           "interior_maxima", "max_displacement", "min_displacement", "sample_times"]

log = logging.getLogger(__name__)

_CELLS_PER_PERIOD = 16
_MAX_SAMPLES = 2_000_000
_XTOL = 1e-15
_RTOL = 4.0 * np.finfo(float).eps
_MAX_ITER = 200


def sample_times(flow: Flow, t0: float, t1: float, *, row: int | None = None,
                 normal: Any = None) -> np.ndarray:
    """Grid on ``[t0, t1]`` fine enough that each cell holds at most one root of ``y''``.

    ``y`` is the coordinate searched: mass ``row + 1`` (mass 1 by default) or the stop
    coordinate ``s = normal . x``. The cells follow the time scales of the modes that
    coordinate sees (:meth:`Flow.time_scales`): for a clearance between two masses,
    ``x_j - x_k``, a fast mode of mass k counts, though mass j's row does not see it.

    Parameters
    ----------
    flow : Flow
    t0, t1 : float
        Interval, ``t1 > t0``.
    row : int, optional
        0-based index of the mass whose motion is searched.
    normal : array_like, shape (n,), optional
        The stop coordinate searched (:meth:`~impactcont.model.stops.Stops.normal`); not
        with `row`.

    Returns
    -------
    ndarray
        Sorted times including both ends.
    """
    osc_rate, decay_rate = flow.time_scales(row, normal=normal)
    h = 2.0 * math.pi / (_CELLS_PER_PERIOD * osc_rate)
    length = t1 - t0
    count = max(math.ceil(length / h), 8)
    if count > _MAX_SAMPLES:
        warnings.warn(f"contact search grid capped at {_MAX_SAMPLES} cells for an interval "
                      f"of {length:.3g} (fastest damped frequency {osc_rate:.3g} would need "
                      f"{count} cells): a short excursion past the stop (eq. 16) may "
                      "be missed; damping the fastest modes or a shorter period avoids this",
                      UnresolvedMotionWarning, stacklevel=2)
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


def _changes(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    return (left < 0) != (right < 0)


def bracketed_roots(fun: Callable[..., tuple[np.ndarray, np.ndarray]],
                    lo: np.ndarray, hi: np.ndarray, g_lo: np.ndarray,
                    index: np.ndarray | None = None) -> np.ndarray:
    """Roots of ``g`` in many brackets at once by safeguarded Newton.

    Parameters
    ----------
    fun : callable
        ``fun(t) -> (g(t), g'(t))`` for an array of times, or with `index`,
        ``fun(k, t)`` where ``k`` says which bracket each time belongs to.
    lo, hi : ndarray
        Brackets, ``lo < hi``, with ``g(lo)`` and ``g(hi)`` of opposite signs.
    g_lo : ndarray
        ``g(lo)`` (its sign is what matters).
    index : ndarray, optional
        A label per bracket, passed to `fun` for the brackets still iterating.

    Returns
    -------
    ndarray
        One root per bracket, to a few ulps: a Newton step that would leave the
        current bracket is replaced by bisection, so each bracket shrinks
        every iteration and convergence is quadratic near a simple root.
    """
    a, b = lo.astype(float).copy(), hi.astype(float).copy()
    ga = g_lo.astype(float).copy()
    x = 0.5 * (a + b)
    active = np.arange(x.size)
    for _ in range(_MAX_ITER):
        if active.size == 0:
            break
        g, dg = fun(x[active]) if index is None else fun(index[active], x[active])
        xa = x[active]
        left = (g < 0) == (ga[active] < 0)  # root lies right of x
        a[active] = np.where(left, xa, a[active])
        ga[active] = np.where(left, g, ga[active])
        b[active] = np.where(left, b[active], xa)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = g / dg
        tol = _XTOL + _RTOL * np.abs(xa)
        # converged: the Newton correction is below the tolerance (judged before the
        # safeguard, which would otherwise bisect away from a root sitting on the bracket end)
        done = (g == 0) | (np.abs(step) <= tol) | (b[active] - a[active] <= tol)
        xn = xa - step
        inside = np.isfinite(xn) & (xn >= a[active]) & (xn <= b[active])
        # (a bracket that closed with a Newton step leaving it, e.g. at a near-zero slope,
        # returns its midpoint, not the step)
        xn = np.where(inside | (done & (np.abs(step) <= tol)), xn, 0.5 * (a[active] + b[active]))
        x[active] = np.where(g == 0, xa, xn)
        active = active[~done]
    return x


def critical_points(motion: Mass1Motion, grid: np.ndarray) -> np.ndarray:
    """All roots of ``x1'(t)`` strictly inside the grid's span, sorted.

    Parameters
    ----------
    motion : Mass1Motion
        Evaluator of ``x1`` and its derivatives.
    grid : ndarray
        Sorted times from :func:`sample_times`.

    Returns
    -------
    ndarray
        Times where the velocity of mass 1 vanishes.
    """
    _, _, acc, _ = motion.derivatives(grid)
    cells = np.flatnonzero(_changes(acc[:-1], acc[1:]))
    inflections = bracketed_roots(lambda s: motion.derivatives(s)[2:4], grid[cells],
                                   grid[cells + 1], acc[cells])
    points = np.union1d(grid, inflections)  # x1' is monotone between consecutive points
    _, v, acc, _ = motion.derivatives(points)
    cells = np.flatnonzero(_changes(v[:-1], v[1:]))
    roots = bracketed_roots(lambda s: motion.derivatives(s)[1:3], points[cells],
                             points[cells + 1], v[cells])
    return np.unique(roots[(roots > grid[0]) & (roots < grid[-1])])


def interior_maxima(motion: Mass1Motion, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times and values of the local maxima of ``x1`` strictly inside the grid's span."""
    cp = critical_points(motion, grid)
    if cp.size == 0:
        return cp, cp
    x, _, acc = motion(cp)
    keep = acc < 0
    return cp[keep], x[keep]


def first_upward_crossing(motion: Mass1Motion, level: float, grid: np.ndarray, *,
                          after: float = -math.inf) -> float | None:
    """First time in ``(grid[0], grid[-1]]`` where ``x1`` reaches ``level`` from below.

    Parameters
    ----------
    motion : Mass1Motion
    level : float
        The stop position ``b``.
    grid : ndarray
        Sorted times from :func:`sample_times`.
    after : float
        Ignore crossings completed by this time (the rounding-size excursion of a
        flight that starts on the stop at rest and leaves it).

    Returns
    -------
    float or None
        The crossing time, to machine precision, or None if ``x1 < level`` throughout.
    """
    points = np.union1d(grid, critical_points(motion, grid))  # x1 monotone in between
    x = motion(points)[0] - level
    hit = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0) & (points[1:] > after))
    if hit.size == 0:
        return None
    i = hit[:1]

    def shifted(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x1, v1, _ = motion(s)
        return x1 - level, v1

    return float(bracketed_roots(shifted, points[i], points[i + 1], x[i])[0])


def _flights(orbit: Any) -> list[tuple[np.ndarray, float, float]]:
    """``(state after the impact, forcing phase there, flight time)`` of each flight."""
    states = getattr(orbit, "states", None)
    if states is not None:  # an N-p motion: p flights
        return [(np.asarray(states[k], dtype=float), float(orbit.phases[k]),
                 float(orbit.flight_times[k])) for k in range(orbit.p)]
    return [(np.asarray(orbit.state, dtype=float), float(orbit.delta), float(orbit.period))]


def displacement_extrema(orbit: Any, mass: int) -> tuple[float, float]:
    """Smallest and largest displacement ``x_mass`` of a periodic motion over its period.

    Each flight (the one flight of an N-1 motion, the p flights of an N-p motion) is
    searched as the impact search is (:func:`sample_times`, :func:`critical_points`):
    ``x_mass`` is evaluated at both ends of the flight and at every root of its velocity
    inside, each to machine precision, so no short excursion is missed. Displacements
    are continuous through the impacts (only velocities jump), so these are the extrema
    over the whole period. For user events and monitors
    (``events={"x2max": lambda o: max_displacement(o, 2) - 0.3}``, ``docs/engine.md``).

    Parameters
    ----------
    orbit : PeriodicOrbit or MultiImpactOrbit
        The motion (state, phase and duration of each flight).
    mass : int
        Which mass, ``1 .. n`` (as ``x1 .. xn`` in the paper).

    Returns
    -------
    (float, float)
        ``(min x_mass, max x_mass)`` over one period.

    Raises
    ------
    ParameterError
        `mass` is not an integer in ``1 .. n``.
    TypeError
        `orbit` is not a periodic motion.
    """
    osc = getattr(orbit, "oscillator", None)
    if osc is None or not (hasattr(orbit, "states") or hasattr(orbit, "state")):
        raise TypeError(f"orbit must be a PeriodicOrbit or MultiImpactOrbit; got "
                        f"{type(orbit).__name__}")
    n = osc.n
    if isinstance(mass, bool) or not isinstance(mass, (int, np.integer)) or not 1 <= mass <= n:
        raise ParameterError(f"mass must be an integer in 1 .. {n} (the masses x1 .. x{n}); "
                             f"got {mass!r}")
    row = int(mass) - 1
    flow = flow_of(osc)
    lowest, highest = math.inf, -math.inf
    for state, phase, duration in _flights(orbit):
        motion = flow.motion(state, phase, row)
        grid = sample_times(flow, 0.0, duration, row=row)
        times = np.concatenate([[0.0, duration], critical_points(motion, grid)])
        x = motion(times)[0]
        lowest, highest = min(lowest, float(np.min(x))), max(highest, float(np.max(x)))
    return lowest, highest


def max_displacement(orbit: Any, mass: int) -> float:
    """Largest displacement ``x_mass`` over one period (:func:`displacement_extrema`)."""
    return displacement_extrema(orbit, mass)[1]


def min_displacement(orbit: Any, mass: int) -> float:
    """Smallest displacement ``x_mass`` over one period (:func:`displacement_extrema`)."""
    return displacement_extrema(orbit, mass)[0]

"""Contact geometry of one flight against both stops of the impacting mass.

The stops act on the stop coordinate ``s = normal . x`` (:meth:`Stops.normal`: ``x_j``, or
``x_j - x_k`` for a clearance between two masses); everything below follows ``s``, a
modal sum with the weights ``normal^T U``. "``x_j``" below reads ``s`` in general. Its
time scales too (the search grid, the windows: :meth:`Flow.time_scales` with the normal)
are those of the modes ``s`` sees, as in the compiled search: for a pair a fast mode of
mass k, or one that cancels in ``x_j`` but not in ``x_j - x_k``, is resolved.

The impacting mass ``j`` (``osc.stops.mass``) meets the upper stop ``x_j = b``
moving up and, when present, the lower stop ``x_j = -b_low`` moving down. Both
are the same problem for the signed coordinate ``y = s x_j`` (``s = +1`` for the
upper stop, ``-1`` for the lower) reaching the level ``s c`` from below
(``c = b`` or ``-b_low``), so the reliable bracketing of
:mod:`impactcont.orbit.extrema` (cells cut at the critical points of ``x_j``, each
root polished to a few ulps) serves both stops: ``flow.motion(X0, delta, j, s)``
is the evaluator of ``y`` and its derivatives (modal or first-order flow),
:func:`next_contact` the first impact on any stop, :func:`flight_clearances`
the interior check of eq. (16) against both stops and, with ``extra=True``, every extra
stop on its own coordinate (the simulator's own, in numpy: the
shooting of N-p motions runs the compiled search of
:mod:`impactcont.kernel.shooting`, and the tests hold one against the other).
:func:`stop_sign` comes from :mod:`impactcont.orbit.stop_geometry`, below both.

The cost of :func:`next_contact` follows the motion's own time scales, not the
length of the flight searched: the flight is searched in windows of a few up to
``_WINDOW_PERIODS`` periods of its fastest component (or one forcing period, if
shorter), and a stretch where an envelope of the motion stays clear of both stops
is skipped in one step (:func:`contact_free_until`). A flight at a forcing
frequency far below the natural ones (quasi-static forcing) thus costs a few
windows per impact and per approach to a stop, however long the forcing period.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from impactcont.orbit.extrema import critical_points, first_upward_crossing, sample_times
from impactcont.orbit.flow import Flow, GeneralMass1Motion, Mass1Motion
from impactcont.orbit.stop_geometry import stop_sign

__all__ = ["contact_free_until", "flight_clearances", "next_contact", "search_window",
           "stop_sign"]

TWO_PI = 2.0 * math.pi
_EPS = float(np.finfo(float).eps)
# first and longest contact-search windows, in periods of the fastest component seen by the
# stop coordinate (16 grid cells each): the cost of a window, not of the flight searched, is
# what an impact costs
_FIRST_WINDOW_PERIODS = 2
_WINDOW_PERIODS = 64
# rounding allowance of the envelope test, in ulps of the size of the motion
_ENVELOPE_ULPS = 1e3


def flight_clearances(flow: Flow, X0: np.ndarray, delta: float, tau: float, *,
                      extra: bool = False) -> tuple[Any, ...]:
    """Smallest clearance to each stop at the interior extrema of its coordinate on one flight.

    Eq. (16) for every stop: the upper clearance is ``b - s`` at the interior maxima of
    the stop coordinate ``s = normal . x``, the lower ``s + b_low`` at its interior minima;
    an extra stop met moving up at ``s' = c`` (its own coordinate,
    :meth:`~impactcont.model.stops.Stops.stop`) has ``c - s`` at the maxima of its ``s``,
    one met moving down ``s - c`` at the minima. A flight is free of contact when every
    clearance is ``> 0``.

    Parameters
    ----------
    flow : Flow
    X0 : ndarray, shape (2n,)
        State right after the impact that starts the flight.
    delta : float
        Forcing phase there.
    tau : float
        Flight time, ``> 0``.
    extra : bool
        Also return the clearances to the extra stops (``osc.stops.extra``).

    Returns
    -------
    gap_upper, time_upper, gap_lower, time_lower : float
        Each clearance (``+inf`` with no such extremum, or no lower stop) and the
        time of its extremum after the start (NaN when there is none).
    gap_extra, time_extra : ndarray, shape (q,)
        With `extra`: the same for each extra stop, in the order of ``osc.stops.extra``
        (as :func:`impactcont.kernel.shooting.motion_checks` returns them).
    """
    osc = flow.osc
    normal = osc.stops.normal(osc.n)
    motion = flow.motion(X0, delta, osc.stops.index, normal=normal)
    cp = critical_points(motion, sample_times(flow, 0.0, tau, normal=normal))
    gap_u = gap_l = math.inf
    t_u = t_l = math.nan
    if cp.size:
        x, _, acc = motion(cp)
        top = acc < 0
        if np.any(top):
            i = int(np.argmax(np.where(top, x, -np.inf)))
            gap_u, t_u = float(osc.b - x[i]), float(cp[i])
        bottom = acc > 0
        if osc.stops.two_sided and np.any(bottom):
            i = int(np.argmin(np.where(bottom, x, np.inf)))
            gap_l, t_l = float(x[i] + osc.stops.b_low), float(cp[i])
    if not extra:
        return gap_u, t_u, gap_l, t_l
    stops = osc.stops.extra
    gap_x = np.full(len(stops), math.inf)
    t_x = np.full(len(stops), math.nan)
    for k, e in enumerate(stops):
        view = osc.stops.stop(e.name, osc.M, osc.b, osc.R)
        gap_x[k], t_x[k] = _stop_clearance(flow, X0, delta, tau, view.normal, view.sign,
                                           view.position, view.pivot)
    return gap_u, t_u, gap_l, t_l, gap_x, t_x


def _stop_clearance(flow: Flow, X0: np.ndarray, delta: float, tau: float, normal: np.ndarray,
                    sign: float, position: float, pivot: int) -> tuple[float, float]:
    """``(gap, time)`` of eq. (16) against one stop met with ``sign s' > 0`` at
    ``s = position``: ``sign (position - s)`` at the interior extremum of ``s`` nearest it
    (the highest maximum of ``y = sign s``); ``(inf, nan)`` when there is none."""
    motion = flow.motion(X0, delta, pivot, sign, normal)
    cp = critical_points(motion, sample_times(flow, 0.0, tau, normal=normal))
    if cp.size:
        y, _, acc = motion(cp)
        top = acc < 0
        if np.any(top):
            i = int(np.argmax(np.where(top, y, -np.inf)))
            return float(sign * position - y[i]), float(cp[i])
    return math.inf, math.nan


def search_window(flow: Flow, index: int | None = None, *, normal: np.ndarray | None = None
                  ) -> tuple[float, float]:
    """First and longest contact-search windows for the stop coordinate ``normal . x``
    (or mass ``index + 1``).

    The forcing period ``2 pi / omega`` when it holds at most ``_FIRST_WINDOW_PERIODS``
    periods of the fastest damped oscillation seen by that coordinate (then both windows
    are that period; :meth:`Flow.time_scales`: for a clearance between two masses, the
    modes of either mass that ``x_j - x_k`` sees). A slower forcing (the natural motion
    far faster) is searched from ``_FIRST_WINDOW_PERIODS`` fastest periods on, the window
    doubling up to ``_WINDOW_PERIODS`` of them (or the forcing period): a short flight,
    e.g. in chatter, costs a short window, a long one a number of windows that grows with
    its length over ``_WINDOW_PERIODS`` fastest periods.

    Parameters
    ----------
    flow : Flow
    index : int, optional
        0-based index of a mass (mass 1 by default); not with `normal`.
    normal : ndarray, shape (n,), optional
        The stop coordinate (:meth:`~impactcont.model.stops.Stops.normal`).

    Returns
    -------
    first, longest : float
    """
    rate, _ = flow.time_scales(index, normal=normal)  # >= omega
    forcing, fast = TWO_PI / flow.omega, TWO_PI / rate
    return min(forcing, _FIRST_WINDOW_PERIODS * fast), min(forcing, _WINDOW_PERIODS * fast)


def _envelope(motion: Mass1Motion, t0: float) -> tuple[complex, float, float, float] | None:
    """Forced amplitude, a bound on the free part from ``t0`` on, and the motion's size.

    ``y(t) = Re(Z e^{i(omega t + delta)}) + y_free(t)`` for the evaluated coordinate
    ``y = s x_j``, with ``|y_free(t)| <= bound`` for every ``t >= t0``:

    - modal flow: each free mode ``y_i'' + 2 a_i y_i' + w_i^2 y_i = 0`` (``a_i >= 0``)
      has the non-increasing energy ``(y_i'^2 + w_i^2 y_i^2) / 2``, so
      ``|y_i(t)| <= sqrt(y_i(t0)^2 + (y_i'(t0) / w_i)^2)``;
    - first-order flow: ``|sum_k c_k e^{lambda_k t}| <= sum_k |c_k| e^{Re(lambda_k) t0}``
      (``Re lambda_k <= 0``).

    A constant force adds its constant part (the fourth item, ``offset``). None when a
    mode grows (negative damping) or a free mode moves the coordinate (a free mass
    drifts): no bound.
    """
    flow = motion.flow
    if isinstance(motion, GeneralMass1Motion):
        rates = flow.lam.real
        if np.any(rates > 0.0) or motion.rate != 0.0 or np.any(flow.lam == 0.0):
            return None
        start = float(np.sum(np.abs(motion.c)))
        free = float(np.sum(np.abs(motion.c) * np.exp(rates * t0)))
        return complex(motion.z), free, start, motion.offset
    if np.any(flow.a < 0.0) or np.any(flow.free):
        return None
    W11, W12, W21, W22 = (blk[0] for blk in flow.transfer(np.array([t0])))
    y = W11 * motion.dy + W12 * motion.dv
    v = W21 * motion.dy + W22 * motion.dv
    weights = np.abs(motion.u0)
    free = float(weights @ np.hypot(y, v / flow.w))
    start = float(weights @ np.hypot(motion.dy, motion.dv / flow.w))
    forced = complex(motion.u0 @ (flow.gamma - 1j * flow.beta))
    return forced, free, start, float(motion.u0 @ flow.static_offset)


def contact_free_until(motion: Mass1Motion, level: float, t0: float) -> float:
    """A time up to which ``y = s x_j`` provably stays below ``level``, from ``t0`` on.

    The motion is its forced part plus a free part bounded from ``t0`` on (the
    modal energy, or the decay of the complex modes), so ``y(t) <= A cos(omega t +
    phi) + bound`` for ``t >= t0``; the result is the first ``t >= t0`` where the
    right-hand side (less a rounding allowance) reaches ``level``: no contact can
    happen before it.

    Parameters
    ----------
    motion : Mass1Motion
        Evaluator of ``y = s x_j`` (``flow.motion(X0, delta, j, s)``).
    level : float
        The stop's level in ``y`` (``s c``).
    t0 : float
        Start of the stretch, time since the start of the flight.

    Returns
    -------
    float
        ``t0`` when contact is possible at once, ``inf`` when never.
    """
    env = _envelope(motion, t0)
    if env is None:
        return t0
    forced, free, start, offset = env
    amplitude = abs(forced)
    allowance = _ENVELOPE_ULPS * _EPS * (abs(level) + abs(offset) + amplitude + start)
    clear = level - offset - free - allowance  # the forced part must reach this for contact
    if clear > amplitude:
        return math.inf
    if clear <= -amplitude:
        return t0
    omega = motion.flow.omega
    reach = math.acos(clear / amplitude)  # forced >= clear <=> |phase| <= reach (mod 2 pi)
    psi = omega * t0 + motion.delta + math.atan2(forced.imag, forced.real)
    phase = math.remainder(psi, TWO_PI)
    if abs(phase) <= reach:
        return t0
    ahead = (-reach if phase < 0 else TWO_PI - reach) - phase
    slack = 1e-9 + 8.0 * _EPS * abs(psi)  # the rounding of the phase, on the safe side
    return t0 + max(ahead - slack, 0.0) / omega


def next_contact(flow: Flow, X: np.ndarray, phase: float, t_max: float, *,
                 after: dict[str, float] | None = None
                 ) -> tuple[float, np.ndarray, str] | None:
    """First impact on any stop within ``t_max`` of a flight from state X.

    Every stop of the oscillator (:attr:`Stops.names`: ``U``, ``L`` and the extra stops,
    each on its own coordinate ``s = normal . x``) is searched on its own grid (the time
    scales of its own coordinate) over the same windows; the earliest crossing wins.

    Parameters
    ----------
    flow : Flow
    X : ndarray, shape (2n,)
        State at the start (on the allowed side of every stop).
    phase : float
        Forcing phase at the start.
    t_max : float
        Longest flight to search.
    after : dict, optional
        Per stop (``"U"``, ``"L"``, an extra stop's name), ignore a crossing completed by
        this time (a flight that starts on that stop and leaves it). Any other stop whose
        coordinate is evaluated on or past it at the start, moving into it, is hit at once
        (a state short of it only by the rounding of the evaluation: no crossing from below
        is left to find).

    Returns
    -------
    (float, ndarray, str) or None
        Flight time to the impact, the state just before it and the stop hit
        (its name); None when no stop is reached within ``t_max``.

    Notes
    -----
    The flight is searched window by window (:func:`search_window`: each window
    twice the last, up to the longest), each window
    on the reliable grid of :func:`impactcont.orbit.extrema.sample_times`; before
    each window, a stretch that :func:`contact_free_until` proves free of contact
    with both stops is skipped when it is longer than a window. The cost is thus a
    few windows per approach to a stop, not proportional to ``t_max``.
    """
    osc = flow.osc
    after = after or {}
    views = {s: osc.stops.stop(s, osc.M, osc.b, osc.R) for s in osc.stops.names}
    stops = list(views)
    normals = {s: views[s].normal for s in stops}
    motions = {s: flow.motion(X, phase, views[s].pivot, views[s].sign, normals[s])
               for s in stops}
    levels = {s: views[s].sign * views[s].position for s in stops}
    below = dict.fromkeys(stops, True)
    windows = [search_window(flow, normal=normals[s]) for s in stops]
    first, longest = min(w[0] for w in windows), min(w[1] for w in windows)
    window = first
    start = 0.0
    while start < t_max:
        free = min(contact_free_until(motions[s], levels[s], start) for s in stops)
        if free >= start + window:  # no contact with either stop before `free`: skip there
            if free >= t_max:
                return None
            start, window = free, first
            below = dict.fromkeys(stops, True)
            continue
        stop_time = min(start + window, t_max)
        grids = {s: sample_times(flow, start, stop_time, normal=normals[s]) for s in stops}
        best: tuple[float, str] | None = None
        for s in stops:
            grid = grids[s]
            x, v, _ = motions[s](grid[:1])
            if below[s] and (start > 0 or s not in after) and x[0] >= levels[s] and v[0] >= 0:
                # the previous window ended just short of this stop at this very time, moving
                # into it: the impact sits on the boundary (the evaluations differ by rounding);
                # at the start of the flight, a state short of the stop by less than the
                # rounding of the evaluation, moving into it (no crossing from below to find)
                tc: float | None = start
            else:
                tc = first_upward_crossing(motions[s], levels[s], grid,
                                           after=after.get(s, -math.inf))
            if tc is not None and (best is None or tc < best[0]):
                best = (tc, s)
        if best is not None:
            return best[0], flow.state(best[0], X, phase)[0], best[1]
        for s in stops:
            below[s] = bool(motions[s](grids[s][-1:])[0][0] < levels[s])
        start, window = stop_time, min(2.0 * window, longest)
    return None

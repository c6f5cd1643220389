"""Contact geometry of one flight against every stop.

The stops act on stop coordinates ``s = normal . x`` (:meth:`Stops.normal`: ``x_j``, or
``x_j - x_k`` for a clearance between two masses; each extra stop its own). A stop met
moving up at ``s = c`` and one met moving down are the same problem for the signed
coordinate ``y = sign s`` reaching the level ``sign c`` from below, so one search serves
every stop: :class:`~impactcont.simulate.flight.StopMotion` evaluates ``y`` and its
derivatives along the simulator's own exact flight (:mod:`impactcont.simulate.flight`:
the matrix exponential of the forced system, nothing of the orbit code), and the
reliable bracketing of :mod:`impactcont.simulate.search` (cells cut at the turning
points of ``y``, each root polished to a few ulps) finds its crossings. The time scales
of the search (its grid, its windows) are those of the modes ``s`` sees
(:meth:`Flight.time_scales`): for a pair, a fast mode of mass k, or one that cancels in
``x_j`` but not in ``x_j - x_k``, is resolved.

:func:`next_contact` is the first impact on any stop, :func:`flight_clearances` the
interior check of eq. (16) against U and L and, with ``extra=True``, every extra stop
(the simulator's own, in numpy: the shooting of N-p motions runs the compiled search of
:mod:`impactcont.kernel.shooting`, and the tests hold one against the other).

The cost of :func:`next_contact` follows the motion's own time scales, not the
length of the flight searched: the flight is searched in windows of a few up to
``_WINDOW_PERIODS`` periods of its fastest component (or one forcing period, if
shorter), and a stretch where an envelope of the motion stays clear of every stop
is skipped in one step (:func:`contact_free_until`). A flight at a forcing
frequency far below the natural ones (quasi-static forcing) thus costs a few
windows per impact and per approach to a stop, however long the forcing period.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from impactcont.errors import ParameterError
from impactcont.simulate.flight import StopMotion, flight_of
from impactcont.simulate.search import first_crossing, search_grid, turning_points

__all__ = ["contact_free_until", "flight_clearances", "next_contact", "search_window"]

TWO_PI = 2.0 * math.pi
_EPS = float(np.finfo(float).eps)
# first and longest contact-search windows, in periods of the fastest component seen by the
# stop coordinate (16 grid cells each): the cost of a window, not of the flight searched, is
# what an impact costs
_FIRST_WINDOW_PERIODS = 2
_WINDOW_PERIODS = 64
# rounding allowance of the envelope test, in ulps of the size of the motion (times the
# condition number of the eigenvectors the envelope is read from)
_ENVELOPE_ULPS = 1e3
# how far a search window reaches, in its own lengths
_WINDOW_REACH = 1.0 + 2.0**-20


def _highest_top(motion: StopMotion, grid: np.ndarray) -> tuple[float, float] | None:
    """``(y, t)`` at the highest interior maximum of ``y`` on the grid's span, or None."""
    times = turning_points(motion, grid)
    if times.size == 0:
        return None
    y, _, acc = motion(times)
    tops = acc < 0
    if not np.any(tops):
        return None
    i = int(np.argmax(np.where(tops, y, -np.inf)))
    return float(y[i]), float(times[i])


def flight_clearances(flight: Any, X0: np.ndarray, delta: float, tau: float, *,
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
    flight : Flight, ImpactOscillator or an object carrying one
        The flight (:func:`~impactcont.simulate.flight.flight_of`: of an oscillator, or of
        the oscillator a :class:`impactcont.Flow` carries).
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
    fl = flight_of(flight)
    osc = fl.osc
    normal = osc.stops.normal(osc.n)
    grid = search_grid(fl, 0.0, tau, normal)
    top = _highest_top(fl.motion(X0, delta, normal), grid)
    gap_u, t_u = (math.inf, math.nan) if top is None else (float(osc.b - top[0]), top[1])
    gap_l, t_l = math.inf, math.nan
    if osc.stops.two_sided:  # the lowest minimum of s is the highest maximum of -s
        bottom = _highest_top(fl.motion(X0, delta, normal, -1.0), grid)
        if bottom is not None:
            gap_l, t_l = float(osc.stops.b_low - bottom[0]), bottom[1]
    if not extra:
        return gap_u, t_u, gap_l, t_l
    stops = osc.stops.extra
    gap_x = np.full(len(stops), math.inf)
    t_x = np.full(len(stops), math.nan)
    for k, e in enumerate(stops):
        view = osc.stops.stop(e.name, osc.M, osc.b, osc.R)
        top = _highest_top(fl.motion(X0, delta, view.normal, view.sign),
                           search_grid(fl, 0.0, tau, view.normal))
        if top is not None:
            gap_x[k], t_x[k] = view.sign * view.position - top[0], top[1]
    return gap_u, t_u, gap_l, t_l, gap_x, t_x


def search_window(flight: Any, index: int | None = None, *, normal: Any = None
                  ) -> tuple[float, float]:
    """First and longest contact-search windows for the stop coordinate ``normal . x``
    (or mass ``index + 1``).

    The forcing period ``2 pi / omega`` when it holds at most ``_FIRST_WINDOW_PERIODS``
    periods of the fastest damped oscillation seen by that coordinate (then both windows
    are that period; :meth:`Flight.time_scales`: for a clearance between two masses, the
    modes of either mass that ``x_j - x_k`` sees). A slower forcing (the natural motion
    far faster) is searched from ``_FIRST_WINDOW_PERIODS`` fastest periods on, the window
    doubling up to ``_WINDOW_PERIODS`` of them (or the forcing period): a short flight,
    e.g. in chatter, costs a short window, a long one a number of windows that grows with
    its length over ``_WINDOW_PERIODS`` fastest periods.

    Parameters
    ----------
    flight : Flight, ImpactOscillator or an object carrying one
        :func:`~impactcont.simulate.flight.flight_of`.
    index : int, optional
        0-based index of a mass (mass 1 by default); not with `normal`.
    normal : array_like, shape (n,), optional
        The stop coordinate (:meth:`~impactcont.model.stops.Stops.normal`).

    Returns
    -------
    first, longest : float

    Raises
    ------
    TypeError
        Both `index` and `normal` are given.
    ParameterError
        `index` is not a mass, or `normal` not a finite vector of length n.
    """
    fl = flight_of(flight)
    rate, _ = fl.time_scales(_coordinate(fl.n, index, normal))  # >= omega
    forcing, fast = TWO_PI / fl.omega, TWO_PI / rate
    return min(forcing, _FIRST_WINDOW_PERIODS * fast), min(forcing, _WINDOW_PERIODS * fast)


def _coordinate(n: int, index: int | None, normal: Any) -> np.ndarray:
    """``normal``, or ``e_index`` (mass 1 with neither), checked."""
    if normal is not None:
        if index is not None:
            raise TypeError(f"give index (a mass) or normal (a stop coordinate), not both; "
                            f"got index={index!r}, normal={normal!r}")
        r = np.asarray(normal, dtype=float)
        if r.shape != (n,) or not np.all(np.isfinite(r)) or not np.any(r):
            raise ParameterError(f"normal must be a finite real vector of length {n} with a "
                                 f"non-zero entry (the stop coordinate s = normal . x); got "
                                 f"{normal!r}")
        return r
    index = 0 if index is None else index
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or not 0 <= index < n:
        raise ParameterError(f"index must be an integer in 0 .. {n - 1} (the 0-based index of "
                             f"a mass); got {index!r}")
    return np.eye(n)[index]


def contact_free_until(motion: StopMotion, level: float, t0: float,
                       horizon: float = math.inf) -> float:
    """A time up to which ``y`` provably stays below `level`, from ``t0`` on.

    The motion is its forced part plus a constant part plus a free part bounded on
    ``[t0, horizon]`` (the decay of its modes, :meth:`StopMotion.envelope`), so
    ``y(t) <= A cos(omega t + phi) + offset + bound`` there; the result is the first
    ``t >= t0`` where the right-hand side (less a rounding allowance) reaches `level`: no
    contact can happen before it.

    Parameters
    ----------
    motion : StopMotion
        Evaluator of ``y = sign s`` (:meth:`Flight.motion`).
    level : float
        The stop's level in ``y``.
    t0 : float
        Start of the stretch, time since the start of the flight.
    horizon : float
        End of the stretch the claim is for (the bound on a mode whose computed real part
        is positive, an undamped one in rounding, is taken there).

    Returns
    -------
    float
        ``t0`` when contact is possible at once (or no envelope is known: a free mass, a
        defective system), ``inf`` when never before `horizon`.
    """
    env = motion.envelope(t0, horizon)
    if env is None:
        return t0
    forced, free, start, offset = env
    amplitude = abs(forced)
    ulps = _ENVELOPE_ULPS * max(1.0, motion.flight.condition)
    allowance = ulps * _EPS * (abs(level) + abs(offset) + amplitude + start)
    clear = level - offset - free - allowance  # the forced part must reach this for contact
    if clear > amplitude:
        return math.inf
    if clear <= -amplitude:
        return t0
    omega = motion.flight.omega
    reach = math.acos(clear / amplitude)  # forced >= clear <=> |phase| <= reach (mod 2 pi)
    psi = omega * t0 + math.atan2(forced.imag, forced.real)
    phase = math.remainder(psi, TWO_PI)
    if abs(phase) <= reach:
        return t0
    ahead = (-reach if phase < 0 else TWO_PI - reach) - phase
    slack = 1e-9 + 8.0 * _EPS * abs(psi)  # the rounding of the phase, on the safe side
    return t0 + max(ahead - slack, 0.0) / omega


def next_contact(flight: Any, X: np.ndarray, phase: float, t_max: float, *,
                 after: dict[str, float] | None = None, stops: Any = None,
                 releases: dict[str, np.ndarray] | None = None,
                 released: tuple[str, ...] = ()
                 ) -> tuple[float, np.ndarray, str] | None:
    """First impact on any stop within ``t_max`` of a flight from state X.

    Every stop of the oscillator (:attr:`Stops.names`: ``U``, ``L`` and the extra stops,
    each on its own coordinate ``s = normal . x``) is searched on its own grid (the time
    scales of its own coordinate) over the same windows; the earliest crossing wins.

    Parameters
    ----------
    flight : Flight, ImpactOscillator or an object carrying one
        :func:`~impactcont.simulate.flight.flight_of`; a constrained flight
        (:class:`impactcont.simulate.sticking.HeldFlight`) along a sticking phase.
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
    stops : iterable of str, optional
        The stops searched (all by default; a sticking phase leaves out the stops it holds).
    releases : dict, optional
        Further events ``name -> row``: the first time the linear function ``row . Y`` of
        the flight's internal state (:meth:`Flight.row`) reaches 0 from below (the contact
        force of a held stop falling to zero, :mod:`impactcont.simulate.sticking`),
        searched with the stops; the event is returned under its name.
    released : tuple of str
        The stops of `after` the flight leaves at a release (zero speed and acceleration):
        their ``after`` is the separation time, past which a landing is searched
        (:func:`~impactcont.simulate.search.first_crossing`'s ``released``).

    Returns
    -------
    (float, ndarray, str) or None
        Flight time to the impact, the state just before it and the stop hit
        (its name, or the name of a release); None when no stop is reached within
        ``t_max``.

    Notes
    -----
    The flight is searched window by window (:func:`search_window`: each window
    twice the last, up to the longest), each window on the reliable grid of
    :func:`impactcont.simulate.search.search_grid`; before each window, a stretch that
    :func:`contact_free_until` proves free of contact with every stop is skipped when it
    is longer than a window. The cost is thus a few windows per approach to a stop, not
    proportional to ``t_max``.
    """
    fl = flight_of(flight)
    osc = fl.osc
    after = after or {}
    names = osc.stops.names if stops is None else list(stops)
    views = {s: osc.stops.stop(s, osc.M, osc.b, osc.R) for s in names}
    targets = {}  # name -> (motion, level, the row whose time scales grid its search)
    for s, view in views.items():
        motion = fl.motion(X, phase, view.normal, view.sign)
        targets[s] = (motion, view.sign * view.position, motion.row)
    for name, row in (releases or {}).items():
        motion = fl.motion(X, phase, None, row=row)
        targets[name] = (motion, 0.0, motion.row)
    if not targets:
        return None
    return _first_event(fl, targets, t_max, after, released)


def _windows(fl: Any, row: np.ndarray) -> tuple[float, float]:
    """:func:`search_window` of any linear function ``row . Y`` of the internal state."""
    rate, _ = fl.row_scales(row)
    forcing, fast = TWO_PI / fl.omega, TWO_PI / rate
    return min(forcing, _FIRST_WINDOW_PERIODS * fast), min(forcing, _WINDOW_PERIODS * fast)


def _first_event(fl: Any, targets: dict[str, tuple[StopMotion, float, np.ndarray]],
                 t_max: float, after: dict[str, float], released: tuple[str, ...] = ()
                 ) -> tuple[float, np.ndarray, str] | None:
    """The earliest first crossing of its level from below among `targets` (each a
    motion, a level and the row its grid follows), within ``t_max``; see
    :func:`next_contact`."""
    names = list(targets)
    motions = {s: targets[s][0] for s in names}
    levels = {s: targets[s][1] for s in names}
    rows = {s: targets[s][2] for s in names}
    below = dict.fromkeys(names, True)
    windows = [_windows(fl, rows[s]) for s in names]
    first, longest = min(w[0] for w in windows), min(w[1] for w in windows)
    window = first
    start = 0.0
    while start < t_max:
        free = min(contact_free_until(motions[s], levels[s], start, t_max) for s in names)
        if free >= start + window:  # no contact with any stop before `free`: skip there
            if free >= t_max:
                return None
            start, window = free, first
            below = dict.fromkeys(names, True)
            continue
        # a window reaches a little past its length: the next impact of a motion of the
        # forcing's period comes one period after the last, at a window's end up to rounding,
        # and is found in this window rather than at the start of the next
        stop_time = min(start + window * _WINDOW_REACH, t_max)
        grids = {s: search_grid(fl, start, stop_time, None, row=rows[s]) for s in names}
        best: tuple[float, str] | None = None
        for s in names:
            grid = grids[s]
            y, v, _ = motions[s](grid[:1])
            if below[s] and (start > 0 or s not in after) and y[0] >= levels[s] and v[0] >= 0:
                # the previous window ended just short of this stop at this very time, moving
                # into it: the impact sits on the boundary (the evaluations differ by rounding);
                # at the start of the flight, a state short of the stop by less than the
                # rounding of the evaluation, moving into it (no crossing from below to find)
                tc: float | None = start
            else:
                tc = first_crossing(motions[s], levels[s], grid, after=after.get(s, -math.inf),
                                    released=s in released)
            if tc is not None and (best is None or tc < best[0]):
                best = (tc, s)
        if best is not None:
            return best[0], motions[best[1]].state(best[0]), best[1]
        for s in names:
            below[s] = bool(motions[s](grids[s][-1:])[0][0] < levels[s])
            motions[s].anchor(stop_time)
        start, window = stop_time, min(2.0 * window, longest)
    return None

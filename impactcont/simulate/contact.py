"""Contact geometry of one flight against both stops of the impacting mass.

The impacting mass ``j`` (``osc.stops.mass``) meets the upper stop ``x_j = b``
moving up and, when present, the lower stop ``x_j = -b_low`` moving down. Both
are the same problem for the signed coordinate ``y = s x_j`` (``s = +1`` for the
upper stop, ``-1`` for the lower) reaching the level ``s c`` from below
(``c = b`` or ``-b_low``), so the reliable bracketing of
:mod:`impactcont.orbit.extrema` (cells cut at the critical points of ``x_j``, each
root polished to a few ulps) serves both stops: ``flow.motion(X0, delta, j, s)``
is the evaluator of ``y`` and its derivatives (modal or first-order flow),
:func:`next_contact` the first impact on either stop, :func:`flight_clearances`
the interior check of eq. (16) against both stops.
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.model.stops import LOWER, UPPER
from impactcont.orbit.extrema import critical_points, first_upward_crossing, sample_times
from impactcont.orbit.flow import Flow

__all__ = ["flight_clearances", "next_contact", "stop_sign"]

TWO_PI = 2.0 * math.pi


def stop_sign(stop: str) -> float:
    """``+1`` for the upper stop (met moving up), ``-1`` for the lower (met moving down)."""
    return 1.0 if stop == UPPER else -1.0


def flight_clearances(flow: Flow, X0: np.ndarray, delta: float, tau: float
                      ) -> tuple[float, float, float, float]:
    """Smallest clearance to each stop at the interior extrema of ``x_j`` on one flight.

    Eq. (16) for both stops: the upper clearance is ``b - x_j`` at the interior
    maxima of ``x_j``, the lower ``x_j + b_low`` at its interior minima; a flight is
    free of contact when both are ``> 0``.

    Parameters
    ----------
    flow : Flow
    X0 : ndarray, shape (2n,)
        State right after the impact that starts the flight.
    delta : float
        Forcing phase there.
    tau : float
        Flight time, ``> 0``.

    Returns
    -------
    gap_upper, time_upper, gap_lower, time_lower : float
        Each clearance (``+inf`` with no such extremum, or no lower stop) and the
        time of its extremum after the start (NaN when there is none).
    """
    osc = flow.osc
    j = osc.stops.index
    motion = flow.motion(X0, delta, j)
    cp = critical_points(motion, sample_times(flow, 0.0, tau, row=j))
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
    return gap_u, t_u, gap_l, t_l


def next_contact(flow: Flow, X: np.ndarray, phase: float, t_max: float, *,
                 after: dict[str, float] | None = None
                 ) -> tuple[float, np.ndarray, str] | None:
    """First impact on either stop within ``t_max`` of a flight from state X.

    Parameters
    ----------
    flow : Flow
    X : ndarray, shape (2n,)
        State at the start (``-b_low <= x_j <= b``).
    phase : float
        Forcing phase at the start.
    t_max : float
        Longest flight to search.
    after : dict, optional
        Per stop (``"U"``, ``"L"``), ignore a crossing completed by this time (a
        flight that starts on that stop at rest and leaves it).

    Returns
    -------
    (float, ndarray, str) or None
        Flight time to the impact, the state just before it and the stop hit
        (``"U"``/``"L"``); None when neither stop is reached within ``t_max``.
    """
    osc = flow.osc
    j = osc.stops.index
    after = after or {}
    stops = [UPPER, LOWER] if osc.stops.two_sided else [UPPER]
    motions = {s: flow.motion(X, phase, j, stop_sign(s)) for s in stops}
    levels = {s: stop_sign(s) * osc.stops.position(s, osc.b) for s in stops}
    below = dict.fromkeys(stops, True)
    window = TWO_PI / flow.omega
    start = 0.0
    while start < t_max:
        stop_time = min(start + window, t_max)
        grid = sample_times(flow, start, stop_time, row=j)
        best: tuple[float, str] | None = None
        for s in stops:
            x, v, _ = motions[s](grid[:1])
            if start > 0 and below[s] and x[0] >= levels[s] and v[0] >= 0:
                # the previous window ended just short of this stop at this very time, moving
                # into it: the impact sits on the boundary (the evaluations differ by rounding)
                tc: float | None = start
            else:
                tc = first_upward_crossing(motions[s], levels[s], grid,
                                           after=after.get(s, -math.inf))
            if tc is not None and (best is None or tc < best[0]):
                best = (tc, s)
        if best is not None:
            return best[0], flow.state(best[0], X, phase)[0], best[1]
        for s in stops:
            below[s] = bool(motions[s](grid[-1:])[0][0] < levels[s])
        start = stop_time
    return None

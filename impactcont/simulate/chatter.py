"""Complete chatter: the accumulation point of impacts on one stop, without resolving them.

Near a stop whose coordinate ``s`` is pushed into it (acceleration ``a > 0`` towards the
stop, the stop's restitution ``0 < R < 1``), a bounce leaving the stop at speed ``u`` is
to leading order a parabola: it returns after ``2 u / a`` at speed ``u``, leaves again at
``R u``, and so on. The flight times form a geometric series, so infinitely many impacts
accumulate in the finite time (Budd & Dux 1994, "Chattering and related behaviour in
impact oscillators", Phil. Trans. R. Soc. A 347; Nordmark & Piiroinen 2009, "Simulation and
stability analysis of impacting systems with complete chattering", Nonlinear Dyn. 58)

    t_inf - t_k = sum_{j >= 0} 2 R^j u / a = 2 u / (a (1 - R)),      u = R v_k,      (C1)

after which the coordinate rests on the stop: a sticking phase starts
(:mod:`impactcont.simulate.sticking`).

**When the jump is taken** (:func:`accumulation`): the local quadratic model must hold over
the accumulation, and the motion must stay pressed through it. (i) The acceleration
changes little over (C1): ``|a'| (t_inf - t_k) <= tolerance * a`` with ``a'`` the rate of
change of the acceleration of ``s`` along the flight (its third derivative), so the
relative error of each flight time of the model is at most about `tolerance`; and the
bounces are small, their apex ``u^2 / (2 a) <= tolerance * a (2 pi / w)^2`` (``w`` the
fastest frequency ``s`` sees): the trajectory sampled over the jump (the held motion)
departs from the bouncing one by at most that apex. With a constant acceleration (a ball
on a fixed floor) the model is exact and only the second condition holds the jump back.
(ii) Along the held flow from the impact, the contact force stays
compressive up to ``t_inf`` (no release, :class:`~impactcont.simulate.sticking.HeldFlight`)
and no other stop is hit: the accumulation lies within the time over which the
acceleration keeps its sign. Otherwise the next impact is resolved: incomplete chatter
(the acceleration reverses before accumulation) is followed impact by impact. A bounce too
small to resolve in rounding (its apex within ``1000`` ulps of the stop) with ``a > 0`` is
an accumulation whatever (i) says.

**The state after the jump** is the held flow from the impact's state with the stop
coordinate's speed removed (the plastic law, ``R = 0``, of the stop: the momentum of a pair
conserved), run for ``t_inf - t_k``. Its error against the motion resolved impact by impact
is ``O(v_k^2)`` in the last impact speed ``v_k``: the bounces still to come rise
``O(v_k^2)`` above the stop and last ``O(v_k)`` in all, and (C1) neglects the change of
``a`` over them, ``O(|a'| v_k^2 / a^3)``. Measured (tests/simulate/test_chatter.py,
studies/chatter_sticking): in the study's case the accumulation time is off by about
``v_k^2 / 2`` and the motion after the sticking phase by far less.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from impactcont.model.stops import StopView
from impactcont.simulate.contact import next_contact
from impactcont.simulate.flight import Flight

__all__ = ["ChatterPoint", "accumulation", "plastic_projection"]

_EPS = float(np.finfo(float).eps)
_BOUNCE_ULPS = 1e3
TWO_PI = 2.0 * math.pi


@dataclasses.dataclass(frozen=True)
class ChatterPoint:
    """The accumulation point of a complete chatter (eq. C1 of :mod:`.chatter`).

    Attributes
    ----------
    time : float
        ``t_inf``: where the impacts accumulate and the sticking phase starts.
    stop : str
        The stop chattered on.
    last_impact : float
        Time of the last impact resolved (``t_k``).
    last_velocity : float
        Its impact speed ``v_k``.
    acceleration : float
        ``a``: the acceleration of the stop coordinate into the stop after it.
    restitution : float
        ``R`` of the stop.
    resolved : bool
        False when the bounce after ``t_k`` was too small to resolve in rounding (the
        model's conditions not checked).
    """

    time: float
    stop: str
    last_impact: float
    last_velocity: float
    acceleration: float
    restitution: float
    resolved: bool = True


def plastic_projection(view: StopView, v: np.ndarray) -> np.ndarray:
    """The velocity with the stop coordinate's speed removed by the stop's plastic law:
    ``D_0 = (D_R + R I) / (1 + R)`` (eq. 4 with ``R = 0`` at a frame stop, the two-body law
    with ``R = 0`` at a pair: momentum conserved)."""
    R = view.restitution
    out = (view.jump @ v + R * v) / (1.0 + R)
    p = view.pivot  # s' = 0 exactly, not up to rounding
    out[p] = -float(np.delete(view.normal, p) @ np.delete(out, p))
    return out


def accumulation(flight: Flight, held_flight: Callable[[], Flight], X: np.ndarray,
                 phase: float, view: StopView, others: list[str], t_left: float,
                 tolerance: float) -> tuple[float, np.ndarray, float, bool] | None:
    """The accumulation point of the chatter that an impact at state X starts, if taken.

    Parameters
    ----------
    flight : Flight
        The flight after the impact (free, or with other stops held).
    held_flight : callable
        Returns the flight with this stop held as well
        (:class:`~impactcont.simulate.sticking.HeldFlight`).
    X : ndarray, shape (2n,)
        The state right after the impact (on the stop, leaving it at ``u = R v``).
    phase : float
    view : StopView
        The stop hit.
    others : list of str
        The stops not held while this one holds (watched during the accumulation).
    t_left : float
        Time left in the simulation.
    tolerance : float
        Condition (i) of the module docstring.

    Returns
    -------
    (dt, X_stick, a, resolved) or None
        ``t_inf - t_k``, the state on the stop with its speed removed (the start of the
        held flow to ``t_inf``), the acceleration and whether the bounce was resolvable;
        None when the jump is not taken.
    """
    n = flight.n
    R = view.restitution
    if not 0.0 < R < 1.0:
        return None
    motion = flight.motion(X, phase, view.normal, view.sign)
    _, ds, acc, jerk = (float(d[0]) for d in motion.derivatives(np.zeros(1)))
    u = -ds  # speed away from the stop
    if acc <= 0.0 or u < 0.0:
        return None
    dt = 2.0 * u / (acc * (1.0 - R))
    floor = _BOUNCE_ULPS * _EPS * max(1.0, abs(view.position))
    resolved = not u * u < 2.0 * acc * floor
    rate, _ = flight.time_scales(view.normal)
    reach = acc * (TWO_PI / rate) ** 2  # how far a moves s in the fastest period it sees
    if resolved and (abs(jerk) * dt > tolerance * acc or u * u > 2.0 * acc * tolerance * reach
                     or dt > t_left):
        return None
    X_stick = X.copy()
    X_stick[n:] = plastic_projection(view, X[n:])
    hf = held_flight()
    releases = getattr(hf, "release_rows", {})
    if resolved and next_contact(hf, X_stick, phase, dt, stops=others,
                                 releases=releases) is not None:
        return None  # the force reverses, or another stop is hit, before accumulation
    if not math.isfinite(dt):
        return None
    return dt, X_stick, acc, resolved

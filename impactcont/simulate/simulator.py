"""Event-driven simulation with the exact flow: the independent witness.

Between impacts the state is the exact flow of eq. (1), computed by the simulator itself
from the oscillator's matrices (:mod:`impactcont.simulate.flight`: the forced system as
one autonomous linear system, ``Y(t) = expm(A t) Y(0)``; no time-stepping error, and
nothing of the orbit code it witnesses). Impacts are located as the first upward crossing
of a stop by the bracketing of :mod:`impactcont.simulate.search`, which cuts each flight
at the turning points of the stop coordinate and so cannot miss a short excursion past
the stop inside a sampling cell; each impact time is polished to a few ulps (or to where
the stop coordinate is within its rounding of the stop, for a slow crossing). The impact
law is eq. (4).

With a stop on another mass or a lower stop (``osc.stops``, see
:mod:`impactcont.model.stops`) the impacting mass ``j`` is followed to the first
contact with either stop (:func:`impactcont.simulate.contact.next_contact`) and
the restitution of the stop hit applies.

Contact at the start of a flight (after an impact, or at the given state) is decided by the
signs of each stop coordinate's speed towards the stops it touches within rounding
(:func:`_contact_now`): moving into one is an impact now; at rest on one, the contact forces
decide which stops hold (:func:`impactcont.simulate.sticking.holding`), and the motion
continues as a sticking phase (:mod:`impactcont.simulate.sticking`), the same for a stop
fixed to the frame, a clearance between two masses and every extra stop. Impacts that
accumulate on a stop (complete chatter) are summed to their accumulation point, where a
sticking phase starts (:mod:`impactcont.simulate.chatter`). A plastic impact (restitution
0) leaves the stop coordinate's speed exactly zero. A crossing met without speed towards the
stop (``<= 0``: rounding, e.g. of a coordinate leaving a stop at ``b = 0`` after a release)
is a touch at zero speed, not an impact: the speed is made exactly zero by the stop's
plastic law and the contact forces decide, a sticking phase or a grazing; every recorded
impact has a speed ``> 0`` towards its stop. A coordinate short of its stop by more
than rounding is searched along the flight however slowly it approaches, so the next
contact is not taken too early (issue 28: no result crosses a stop).

In general the stops act on the stop coordinate ``s = normal . x``
(:meth:`~impactcont.model.stops.Stops.normal`: ``x_j``, or ``x_j - x_k`` for a clearance
between two masses), and an impact applies the velocity jump ``v+ = D v`` of
:meth:`~impactcont.model.stops.Stops.impact_matrix` (eq. 4 at a stop fixed to the frame;
the two-body law, momentum conserved and ``s'`` reversed times R, at a pair). Stops on
several coordinates (``osc.stops.extra``: e.g. one above mass 1 and one above mass 2) are
all followed: the first crossing among every stop's coordinate is the impact, with the law
of the stop hit (:meth:`~impactcont.model.stops.Stops.stop`). Free masses, any damping
matrix, a complex F and a constant force ``F_static`` are all in the one system matrix.
"""

from __future__ import annotations

import dataclasses
import enum
import logging
import math
import numbers
from typing import Any

import numpy as np

from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import UPPER, StopView
from impactcont.simulate.chatter import ChatterPoint, accumulation, plastic_projection
from impactcont.simulate.contact import next_contact
from impactcont.simulate.flight import Flight, flight_of
from impactcont.simulate.sticking import (
    HeldFlight,
    StickingPhase,
    holding,
    impact_with_held,
    release_name,
)
from impactcont.threads import blas_limited

__all__ = ["SimulationResult", "SimulationStatus", "next_impact", "simulate"]

log = logging.getLogger(__name__)

TWO_PI = 2.0 * math.pi
_ON_STOP = 1e-12  # allowance of a given start state past a stop (relative to its position)
# a stop coordinate within this many ulps of its size from its stop touches it (rounding of
# the state); a speed towards it within this many ulps of the velocities' size is zero
_ON_ULPS = 256
# a state past a stop by more than this fraction of its size (position and coordinates) is a
# crossing the contact search missed (:func:`_check_sides`)
_PAST_STOP = 1e-9
_EPS = float(np.finfo(float).eps)
# a bounce off a stop whose apex v^2 / (2 |x_j''|) lies within this many ulps of the stop
# position cannot be resolved (the crossing test sees rounding, not the motion): complete
# chatter, whatever chatter_velocity says
_BOUNCE_ULPS = 1e3
# the ends a simulation may be asked to stop at (stop_at=)
_STOP_AT = {"sticking": "STICKING", "chatter": "CHATTER"}
# separation time after a release capped at this fraction of the fastest period
_RELEASE_SPAN = 1e-4
# an impact within this many ulps of the end of the span simulated belongs to it (a periodic
# motion simulated for whole periods meets its last impact at the end, up to rounding)
_END_ULPS = 1024


class SimulationStatus(enum.Enum):
    """Why a simulation stopped; the value is the message."""

    COMPLETED = "reached the requested number of forcing periods"
    STICKING = ("a stop coordinate came to rest on its stop, pushed into it (a sticking "
                "phase starts), and stop_at asked to stop there")
    CHATTER = ("accumulating impacts (complete chatter), and stop_at asked to stop there: "
               "the accumulation point would be taken, the impact velocity fell below "
               "chatter_velocity, or the next bounce would rise too little above the stop to "
               "be resolved")
    MAX_IMPACTS = "reached max_impacts"


@dataclasses.dataclass(frozen=True, eq=False)
class SimulationResult:
    """Outcome of :func:`simulate`.

    Attributes
    ----------
    impact_times : ndarray, shape (k,)
        Times of the impacts since the start.
    impact_velocities : ndarray, shape (k,)
        Speed of the impacting mass towards the stop just before each impact
        (``> 0``): ``x_j'`` at the upper stop, ``-x_j'`` at the lower.
    impact_phases : ndarray, shape (k,)
        Forcing phase ``omega t + delta`` at each impact, wrapped to ``(-pi, pi]``.
    impact_states : ndarray, shape (k, 2n)
        State right after each impact.
    final_time, final_state, final_phase
        Where the simulation stopped (state at ``final_time``, phase wrapped).
    status : SimulationStatus
    t, X : ndarray or None
        Trajectory samples (times, states; both sides of each impact), if requested.
    impact_stops : str
        The stop of each impact, ``"U"`` (upper, ``x_j = b``), ``"L"`` (lower,
        ``x_j = -b_low``) or an extra stop's name; all ``"U"`` for the paper's single stop.
    sticking : tuple of StickingPhase
        The sticking phases, in time order (:class:`impactcont.simulate.sticking.
        StickingPhase`: start, end, the stops held, their contact forces); each holds one
        set of stops, so a phase in which a second stop comes to hold is two phases.
    chatter : tuple of ChatterPoint
        The accumulation points of complete chatter (:mod:`impactcont.simulate.chatter`):
        where the impacts on a stop accumulate and a sticking phase starts, in time order.
    oscillator : ImpactOscillator or None
        The oscillator simulated.
    start_state : ndarray, shape (2n,), or None
        The state at ``t = 0``.
    start_phase : float
        The forcing phase ``delta`` at ``t = 0``.
    periods : float
        The forcing periods asked for (``final_time`` says how far the run went).
    """

    impact_times: np.ndarray
    impact_velocities: np.ndarray
    impact_phases: np.ndarray
    impact_states: np.ndarray
    final_time: float
    final_state: np.ndarray
    final_phase: float
    status: SimulationStatus
    t: np.ndarray | None = None
    X: np.ndarray | None = None
    impact_stops: str = ""
    sticking: tuple[StickingPhase, ...] = ()
    chatter: tuple[ChatterPoint, ...] = ()
    oscillator: ImpactOscillator | None = None
    start_state: np.ndarray | None = None
    start_phase: float = math.nan
    periods: float = math.nan

    def sticking_arrays(self) -> dict[str, np.ndarray]:
        """The sticking phases and the chatter accumulation points as flat arrays (one
        entry per phase, per force sample, per accumulation point), as a dataset stores
        them.

        Returns
        -------
        dict
            ``sticking_start``, ``sticking_end`` (float), ``sticking_stops``,
            ``sticking_ended_by`` (str), one per phase; ``force_time``, ``force``
            (the pressing force, ``>= 0``), ``force_phase`` (the index of its phase),
            ``force_stop`` (the stop it presses), one per sample of each held stop;
            ``chatter_time`` (the accumulation point), ``chatter_stop``,
            ``chatter_last_impact``, ``chatter_last_velocity``, one per point.
        """
        phases = self.sticking
        samples = [(k, p.stops[j], p.times, p.forces[:, j]) for k, p in enumerate(phases)
                   for j in range(len(p.stops))]
        return {
            "sticking_start": np.array([p.start for p in phases], dtype=float),
            "sticking_end": np.array([p.end for p in phases], dtype=float),
            "sticking_stops": np.array([p.stops for p in phases], dtype=str),
            "sticking_ended_by": np.array([p.ended_by for p in phases], dtype=str),
            "force_time": np.concatenate([s[2] for s in samples] or [np.zeros(0)]),
            "force": np.concatenate([s[3] for s in samples] or [np.zeros(0)]),
            "force_phase": np.concatenate([np.full(s[2].size, s[0]) for s in samples]
                                          or [np.zeros(0, dtype=int)]).astype(np.int64),
            "force_stop": np.concatenate([np.full(s[2].size, s[1]) for s in samples]
                                         or [np.zeros(0, dtype=str)]).astype(str),
            "chatter_time": np.array([c.time for c in self.chatter], dtype=float),
            "chatter_stop": np.array([c.stop for c in self.chatter], dtype=str),
            "chatter_last_impact": np.array([c.last_impact for c in self.chatter],
                                            dtype=float),
            "chatter_last_velocity": np.array([c.last_velocity for c in self.chatter],
                                              dtype=float),
        }

    @property
    def message(self) -> str:
        """Human-readable reason for stopping."""
        return self.status.value

    @property
    def success(self) -> bool:
        """True if the requested time span was simulated."""
        return self.status is SimulationStatus.COMPLETED


def _wrap(phase: float) -> float:
    return math.remainder(phase, TWO_PI)


def next_impact(flight: Any, X: np.ndarray, phase: float, t_max: float, *,
                after: float = -math.inf) -> tuple[float, np.ndarray] | None:
    """First impact within ``t_max`` of a flight starting at state X and phase.

    Parameters
    ----------
    flight : Flight, ImpactOscillator or an object carrying one
        The flight (:func:`~impactcont.simulate.flight.flight_of`: of an oscillator, or of
        the oscillator a :class:`impactcont.Flow` carries; only the oscillator is read).
    X : ndarray, shape (2n,)
        State at the start of the flight (``x1 <= b``).
    phase : float
        Forcing phase at the start.
    t_max : float
        Longest flight to search.
    after : float
        Ignore an upward crossing completed by this time (see :func:`simulate`).

    Returns
    -------
    (float, ndarray) or None
        Flight time to the impact and the state just before it; None if no
        impact happens within ``t_max``.

    Raises
    ------
    ParameterError
        The oscillator has a lower stop (``osc.stops.b_low``): the result would not
        say which stop is hit; :func:`impactcont.simulate.contact.next_contact` does.

    Notes
    -----
    With the stop on another mass (``osc.stops.mass = j``) the impact is the first
    upward crossing of ``x_j = b`` (eq. 3 with ``x1`` replaced by ``x_j``). The
    search is :func:`impactcont.simulate.contact.next_contact`'s: its cost follows
    the motion's time scales, not ``t_max``.
    """
    fl = flight_of(flight)
    stops = fl.osc.stops
    if len(stops.names) > 1:
        raise ParameterError(f"next_impact follows one stop; the oscillator has "
                             f"{len(stops.names)} ({list(stops.names)}, stops={stops!r}): use "
                             "impactcont.simulate.contact.next_contact, which also returns the "
                             "stop hit (its name)")
    hit = next_contact(fl, X, phase, t_max, after={UPPER: after})
    return None if hit is None else (hit[0], hit[1])


def _unresolved_bounce(flight: Flight, X: np.ndarray, phase: float, normal: np.ndarray,
                       level: float, v: float) -> bool:
    """The bounce after an impact at speed ``v`` rises less than ``_BOUNCE_ULPS`` ulps."""
    floor = _BOUNCE_ULPS * np.finfo(float).eps * max(1.0, abs(level))
    if v * v > 1e10 * floor:  # cheap exit: |x_j''| would have to exceed 5e9
        return False
    acc = abs(float(normal @ flight.rate(X, phase)[flight.n:]))
    return bool(v * v < 2.0 * acc * floor)


def _touching(X: np.ndarray, views: dict[str, StopView], last: str | None) -> list[str]:
    """The stops the state touches: the one just hit (``last``, projected onto it) and every
    stop whose coordinate is on it or past it within rounding (``_ON_ULPS`` of its size).

    A coordinate short of its stop by more than rounding does not touch it, however slowly
    it approaches: its contact is searched along the flight (a contact assumed at once
    would come too early and too fast, issue 28).
    """
    out = []
    for name, view in views.items():
        clearance, size = _clearance(X, view)
        if name == last or clearance <= _ON_ULPS * _EPS * size:
            out.append(name)
    return out


def _clearance(X: np.ndarray, view: StopView) -> tuple[float, float]:
    """``(sign (c - s), size)`` of the state X at a stop: its clearance (``>= 0`` on the
    allowed side) and the size of the terms it is computed from (``|c| + |n| . |x|``, the
    scale of its rounding)."""
    x = X[:X.size // 2]
    s = float(view.normal @ x)
    size = abs(view.position) + float(np.abs(view.normal) @ np.abs(x))
    return view.sign * (view.position - s), size


def _check_sides(X: np.ndarray, views: dict[str, StopView], t: float) -> None:
    """Refuse a state past a stop by more than ``_PAST_STOP`` of its size: a crossing the
    contact search missed. The search is built never to miss one
    (:mod:`impactcont.simulate.search`); should it, the simulation stops here with an error
    rather than go on through the stop (a wrong trajectory, silently)."""
    for name, view in views.items():
        clearance, size = _clearance(X, view)
        if clearance < -_PAST_STOP * size:
            s = float(view.normal @ X[:X.size // 2])
            raise RuntimeError(f"at t={t!r} stop coordinate {name!r} is {s!r}, past its stop "
                               f"at {view.position!r}: the contact search missed a crossing "
                               f"(state {X.tolist()}); please report this case")


def _contact_now(flight: Flight, X: np.ndarray, views: dict[str, StopView],
                 last: str | None, skip: Any = ()
                 ) -> tuple[tuple[float, np.ndarray, str] | None, list[str]]:
    """An impact at once, or the stops a state rests on (:func:`_touching`).

    Decided by the sign of the stop coordinate's speed towards each stop touched, not by its
    clearance: moving into a stop is an impact now; at rest on it (the speed zero within
    ``_ON_ULPS`` of the velocities' size: a plastic impact, R = 0, leaves it exactly zero)
    it is a candidate for sticking (:func:`impactcont.simulate.sticking.holding` decides,
    from the contact forces), the same for a stop fixed to the frame, a clearance between
    two masses and every extra stop. Stops in `skip` (just released) are left out.

    Returns
    -------
    hit, resting
        ``(0, X, name)`` for an impact now (else None), and the stops the state rests on.
    """
    n = flight.n
    resting = []
    for name in _touching(X, views, last):
        if name in skip:
            continue
        view = views[name]
        u = view.sign * float(view.normal @ X[n:])
        if u > _ON_ULPS * _EPS * float(np.abs(view.normal) @ np.abs(X[n:])):
            return (0.0, X.copy(), name), []
        if u >= -_ON_ULPS * _EPS * float(np.abs(view.normal) @ np.abs(X[n:])):
            resting.append(name)
    return None, resting


def _check_state(osc: ImpactOscillator, state: object) -> np.ndarray:
    try:
        X = np.array(state, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"state must be a real vector of length {2 * osc.n}; "
                        f"got {state!r}") from exc
    if X.shape != (2 * osc.n,) or not np.all(np.isfinite(X)):  # (a matrix is not flattened)
        raise ParameterError(f"state must be a finite vector [x; x'] of length {2 * osc.n}; "
                             f"got {np.asarray(state).tolist()!r}")
    j = osc.stops.index
    s = float(osc.stops.normal(osc.n) @ X[:osc.n])
    name = (f"state[{j}] = x{j + 1}" if not osc.stops.pair
            else f"the stop coordinate s = {osc.stops.coordinate}")
    if s > osc.b + _ON_STOP * max(1.0, abs(osc.b)):
        raise ParameterError(f"{name} = {s!r} is beyond the stop b = {osc.b!r}; s <= b is "
                             f"required (s = {osc.stops.coordinate})")
    if osc.stops.two_sided:
        low = -osc.stops.b_low
        if s < low - _ON_STOP * max(1.0, abs(low)):
            raise ParameterError(f"{name} = {s!r} is beyond the lower stop -b_low = {low!r}; "
                                 f"s >= -b_low is required (s = {osc.stops.coordinate})")
    for e in osc.stops.extra:
        view = osc.stops.stop(e.name, osc.M, osc.b, osc.R)
        s = float(view.normal @ X[:osc.n])
        if view.sign * (s - view.position) > _ON_STOP * max(1.0, abs(view.position)):
            raise ParameterError(
                f"the coordinate {e.coordinate} = {s!r} of state is beyond stop {e.name!r} "
                f"at {view.position!r}; {e.coordinate} {'<=' if e.side > 0 else '>='} "
                f"{view.position!r} is required")
    return X


def _check_count(name: str, value: object, least: int) -> int:
    """`value` as an int ``>= least``, or a ParameterError naming `name` (an integral
    float is taken; a bool, a fraction or a string is refused, not truncated)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not math.isfinite(value) or value != int(value) or value < least:
        raise ParameterError(f"{name} must be an integer >= {least}; got {value!r}")
    return int(value)


def _check_stop_at(stop_at: object) -> frozenset[str]:
    if isinstance(stop_at, str):
        stop_at = (stop_at,)
    try:
        asked = list(stop_at)  # type: ignore[call-overload]
    except TypeError:
        asked = None
    if asked is None or not all(isinstance(a, str) and a in _STOP_AT for a in asked):
        raise ParameterError(f"stop_at must be a tuple of the ends {sorted(_STOP_AT)} (empty: "
                             f"simulate through them); got {stop_at!r}")
    return frozenset(asked)


def _separation_time(flight: Flight, X: np.ndarray, phase: float, view: StopView) -> float:
    """How long after a release at X the stop coordinate stays within rounding of its stop.

    At a release the contact force, hence the free acceleration of ``s``, is zero: ``s``
    leaves the stop as ``s''' t^3 / 6``, and an evaluation of ``s`` along the flight is
    exact only up to ``_ON_ULPS`` ulps of the terms it is summed from
    (:meth:`~impactcont.simulate.flight.StopMotion.size`: the whole state and the forcing
    states, not ``s`` alone, which is zero on a stop at ``b = 0``). A crossing of that stop
    before this time is rounding, not an impact (:func:`next_contact`'s ``after``)."""
    motion = flight.motion(X, phase, view.normal, view.sign)
    jerk = abs(float(motion.derivatives(np.zeros(1))[3][0]))
    band = _ON_ULPS * _EPS * (abs(view.position) + motion.size())
    rate, _ = flight.time_scales(view.normal)
    cap = _RELEASE_SPAN * TWO_PI / rate
    if jerk == 0.0:
        return cap
    return min(cap, (6.0 * band / jerk) ** (1.0 / 3.0))


@blas_limited
def simulate(osc: ImpactOscillator, state: np.ndarray, delta: float, periods: float, *,
             trajectory: bool = False, samples_per_period: int = 200,
             max_impacts: int = 1_000_000, chatter_velocity: float = 1e-9,
             stop_at: tuple[str, ...] = (), chatter_tolerance: float = 1e-6
             ) -> SimulationResult:
    """Integrate the impact oscillator exactly from a given state, through sticking phases.

    Parameters
    ----------
    osc : ImpactOscillator
    state : array_like, shape (2n,)
        ``[x; x']`` at ``t = 0``, with ``x1 <= b`` (``-b_low <= x_j <= b`` for the
        impacting mass j of ``osc.stops``).
    delta : float
        Forcing phase at ``t = 0`` (the forcing is ``F cos(omega t + delta)``).
    periods : float
        Duration in forcing periods ``2 pi / omega``. An impact at the end of that span up
        to rounding (``_END_ULPS`` ulps of it: a periodic motion simulated for whole periods)
        is the last one recorded, and the simulation ends there.
    trajectory : bool
        Also return sampled states ``t, X`` (both sides of each impact).
    samples_per_period : int
        Trajectory samples per forcing period (and contact-force samples of the sticking
        phases), ``>= 2``.
    max_impacts : int
        Stop after this many impacts, ``>= 1``.
    chatter_velocity : float
        Finite, ``>= 0``. With ``"chatter"`` in `stop_at` only: also stop with status
        CHATTER when an impact velocity falls below this fraction of the largest impact
        velocity seen (or below it in absolute value, if none yet), or when the bounce
        after an impact would rise less than 1000 ulps of the stop position above it
        (``v^2 / (2 |x_j''|)``: below that the motion cannot be told from rounding).
    stop_at : tuple of str
        Ends to stop at rather than simulate through: ``"sticking"`` stops with status
        STICKING where a sticking phase would start, ``"chatter"`` with status CHATTER
        where complete chatter would be jumped to its accumulation point. Empty (the
        default): both are simulated (:mod:`impactcont.simulate.sticking`,
        :mod:`impactcont.simulate.chatter`) and recorded in ``result.sticking`` and
        ``result.chatter``.
    chatter_tolerance : float
        In ``(0, 1)``: how far the local quadratic model of a chatter must hold for its
        accumulation point to be taken, ``|a'| (t_inf - t_k) <= chatter_tolerance * a``
        (:func:`~impactcont.simulate.chatter.accumulation`); smaller resolves more
        impacts before the jump, whose error is ``O(v_k^2)`` in the last impact speed.

    Returns
    -------
    SimulationResult

    Notes
    -----
    A stop coordinate at rest on its stop (after a plastic impact, R = 0, or an impact at
    zero speed, or at the start) and pressed into it (the contact force, the Lagrange
    multiplier of the constraint, compressive) sticks: the motion continues as the exact
    flow of the system with that coordinate held
    (:class:`~impactcont.simulate.sticking.HeldFlight`) until the contact force falls to
    zero (the release, located to a few ulps on that flow) or another stop is hit (an
    impact while held: :func:`~impactcont.simulate.sticking.impact_with_held`). Several
    stops may be held at once (:func:`~impactcont.simulate.sticking.holding`).

    A stop met without speed towards it (the speed at the crossing ``<= 0``, which only
    rounding gives) is touched at zero speed, not hit: no impact is recorded, the stop
    coordinate's speed is set to zero by the stop's plastic law (a change of rounding size)
    and the contact forces decide as above: a sticking phase starts if they press it into
    the stop, otherwise the motion goes on past a grazing (logged at level INFO). After a
    release the stop coordinate leaves as ``s''' t^3 / 6``; crossings while it is within
    rounding of the stop (``_ON_ULPS`` ulps of the terms ``s`` is summed from, the whole
    state and the forcing) are rounding and are not searched.
    """
    X = _check_state(osc, state)
    X_start = X.copy()
    if isinstance(periods, bool) or not isinstance(periods, numbers.Real) or not (
            math.isfinite(periods) and periods > 0):
        raise ParameterError(f"periods must be a finite number > 0; got {periods!r}")
    if isinstance(delta, bool) or not isinstance(delta, numbers.Real) or not math.isfinite(
            delta):
        raise ParameterError(f"delta must be a finite real number; got {delta!r}")
    periods, delta = float(periods), float(delta)
    samples_per_period = _check_count("samples_per_period", samples_per_period, 2)
    max_impacts = _check_count("max_impacts", max_impacts, 1)
    if isinstance(chatter_velocity, bool) or not isinstance(chatter_velocity, numbers.Real) \
            or not (math.isfinite(chatter_velocity) and chatter_velocity >= 0.0):
        raise ParameterError(f"chatter_velocity must be a finite number >= 0 (a fraction of "
                             f"the largest impact speed; 0: never stop for a slow impact); got "
                             f"{chatter_velocity!r}")
    ends = _check_stop_at(stop_at)
    if isinstance(chatter_tolerance, bool) or not isinstance(chatter_tolerance, numbers.Real) \
            or not 0.0 < chatter_tolerance < 1.0:
        raise ParameterError(f"chatter_tolerance must be a number in (0, 1) (the relative "
                             f"change of the acceleration allowed over an accumulation); got "
                             f"{chatter_tolerance!r}")
    flight = Flight(osc)
    n = osc.n
    sides = list(osc.stops.names)
    views = {s: osc.stops.stop(s, osc.M, osc.b, osc.R) for s in sides}
    level = {s: views[s].position for s in sides}
    sign = {s: views[s].sign for s in sides}
    normal = {s: views[s].normal for s in sides}
    jump = {s: views[s].jump for s in sides}  # v+ = D v, the law of the stop hit
    period = TWO_PI / osc.omega
    t_end = periods * period
    dt_sample = period / int(samples_per_period)
    times, vels, phases, states, hits = [], [], [], [], []
    t_chunks: list[np.ndarray] = []
    X_chunks: list[np.ndarray] = []
    t_now, phase = 0.0, _wrap(float(delta))
    status = SimulationStatus.COMPLETED
    v_scale = 0.0
    flights: dict[tuple[str, ...], Flight] = {(): flight}

    def flight_for(held: tuple[str, ...]) -> Flight:
        if held not in flights:
            flights[held] = HeldFlight(osc, held)
        return flights[held]

    sticks: list[StickingPhase] = []
    chatter: list[ChatterPoint] = []
    stick: tuple[float, np.ndarray, float] | None = None  # start, state, phase of the phase

    def close(held: tuple[str, ...], ended_by: str) -> None:
        if not held or stick is None:
            return
        t0, X0, p0 = stick
        hf = flight_for(held)
        span = t_now - t0
        if span <= 0.0:  # the held set changed at once (a second stop comes to hold)
            return
        tau = np.append(np.arange(0.0, span, dt_sample), span)
        assert isinstance(hf, HeldFlight)
        sticks.append(StickingPhase(
            start=t0, end=t_now, stops="".join(held), times=t0 + tau,
            forces=hf.pressing(tau, X0, p0), ended_by=ended_by, start_state=X0,
            start_phase=p0, _flight=hf))

    held: tuple[str, ...] = ()
    released: dict[str, float] = {}  # stops just released -> their separation time
    last: str | None = None  # the stop of the impact that starts this flight
    switches = 0  # changes of the held set at one instant (a guard against a loop)
    touches = 0  # touches at zero speed at one instant (the same guard)
    while True:
        fl = flight_for(held)
        free_views = {s: views[s] for s in sides if s not in held}
        hit, resting = _contact_now(fl, X, free_views, last, released)
        if hit is None:
            candidates = list(held) + [s for s in resting if s not in held]
            chosen = set(holding(osc, X, phase, candidates)) if candidates else set()
            if chosen != set(held):
                if chosen - set(held) and "sticking" in ends:
                    status = SimulationStatus.STICKING
                    break
                switches += 1
                if switches > 4 * len(sides) + 4:
                    raise RuntimeError(f"the held stops keep changing at t={t_now!r} "
                                       f"(state {X.tolist()}): a contact-force law that "
                                       "cannot decide; please report this case")
                close(held, "release" if chosen < set(held) else "stick")
                held = tuple(s for s in sides if s in chosen)
                stick = (t_now, X.copy(), phase) if held else None
                last = None
                continue
        switches = 0
        if hit is None:
            # a start on a stop that leaves it (moving away, or at rest pulled away): its
            # velocity or position is exact only up to rounding, which may show a crossing
            # of that stop a few ulps after the start; it is not an impact
            after = {s: _ON_STOP * period for s in _touching(X, free_views, last)}
            # at rest on a stop that does not hold (its contact force zero within rounding,
            # or pulling away), or just released: it may leave with zero acceleration
            for s in resting:
                if s not in held:
                    released.setdefault(s, _separation_time(fl, X, phase, views[s]))
            for s, t_sep in released.items():
                after[s] = max(after.get(s, 0.0), t_sep)
            hit = next_contact(fl, X, phase, t_end - t_now + _END_ULPS * _EPS * t_end,
                               after=after, stops=list(free_views),
                               releases=fl.release_rows if held else None,
                               released=tuple(released))
        released = {}
        duration = hit[0] if hit is not None else max(t_end - t_now, 0.0)
        if trajectory:
            tau = np.arange(0.0, duration, dt_sample)
            t_chunks.append(t_now + np.append(tau, duration))
            X_chunks.append(fl.samples(np.append(tau, duration), X, phase))
        if hit is None:
            X = fl.state(duration, X, phase)
            _check_sides(X, free_views, t_now + duration)
            phase = _wrap(phase + osc.omega * duration)
            t_now = max(t_now, t_end)
            close(held, "end")
            break
        tc, X_minus, side = hit
        t_now += tc
        _check_sides(X_minus, {s: v for s, v in free_views.items() if s != side}, t_now)
        phase = _wrap(phase + osc.omega * tc)
        if side not in views:  # a release: the contact force of a held stop reached zero
            stop = next(s for s in held if release_name(s) == side)
            close(held, "release")
            X = X_minus.copy()
            held = tuple(s for s in held if s != stop)
            stick = (t_now, X.copy(), phase) if held else None
            released = {stop: _separation_time(flight_for(held), X, phase, views[stop])}
            last = None
            continue
        v = sign[side] * float(normal[side] @ X_minus[n:])  # speed towards the stop hit
        X = X_minus.copy()
        p = views[side].pivot  # s on the stop: x_p = c - sum_{i != p} n_i x_i (n_p = 1)
        X[p] = level[side] - float(np.delete(normal[side], p) @ np.delete(X_minus[:n], p))
        if v <= 0.0:
            # an upward crossing met without speed towards the stop: a touch at zero speed
            # (its speed is rounding), not an impact. The speed is made exactly zero by the
            # stop's plastic law and the contact forces decide at the top of the loop: a
            # sticking phase starts if they press it into the stop, else the flight goes on
            # past a grazing (:func:`_contact_now`, :func:`holding`)
            log.info("t=%.17g: stop %r touched at zero speed (%.3g towards it): not an "
                     "impact; a sticking phase or a grazing", t_now, side, v)
            X[n:] = plastic_projection(views[side], X_minus[n:])
            touches = touches + 1 if tc == 0.0 else 1  # touches at one instant in a row
            if touches > 4 * len(sides) + 4:
                raise RuntimeError(f"stop {side!r} touched at zero speed again and again at "
                                   f"t={t_now!r} (state {X.tolist()}); please report this "
                                   "case")
            last = None
            continue
        if held:  # an impact while stops are held: those whose impulses press them stay
            close(held, "impact")
            X[n:], kept = impact_with_held(osc, X_minus[n:], side, held)
            held = tuple(s for s in sides if s in kept)
            stick = (t_now, X.copy(), phase) if held else None
        else:
            X[n:] = jump[side] @ X_minus[n:]
            if views[side].restitution == 0.0:  # plastic: s' = 0 exactly, not up to rounding
                X[n + p] = -float(np.delete(normal[side], p) @ np.delete(X[n:], p))
        last = side
        times.append(t_now)
        vels.append(v)
        phases.append(phase)
        states.append(X.copy())
        hits.append(side)
        v_scale = max(v_scale, v)
        if views[side].restitution > 0.0:
            fl = flight_for(held)
            if "chatter" in ends and (v < chatter_velocity * max(v_scale, 1.0)
                                      or _unresolved_bounce(fl, X, phase, normal[side],
                                                            level[side], v)):
                status = SimulationStatus.CHATTER
                close(held, "chatter")
                break
            both = tuple(s for s in sides if s in held or s == side)
            point = accumulation(fl, lambda both=both: flight_for(both), X, phase,
                                 views[side], [s for s in sides if s not in both],
                                 t_end - t_now, chatter_tolerance)
            if point is not None:
                if "chatter" in ends:
                    status = SimulationStatus.CHATTER
                    close(held, "chatter")
                    break
                dt, X_stick, acc, resolved = point
                hf = flight_for(both)
                if trajectory:
                    tau = np.append(np.arange(0.0, dt, dt_sample), dt)
                    t_chunks.append(t_now + tau)
                    X_chunks.append(hf.samples(tau, X_stick, phase))
                # a phase of other held stops goes on through the accumulation (it ends
                # where this stop comes to hold as well)
                X = hf.state(dt, X_stick, phase)
                t_now += dt
                phase = _wrap(phase + osc.omega * dt)
                chatter.append(ChatterPoint(
                    time=t_now, stop=side, last_impact=times[-1], last_velocity=v,
                    acceleration=acc, restitution=views[side].restitution,
                    resolved=resolved))
        if len(times) >= max_impacts:
            status = SimulationStatus.MAX_IMPACTS
            close(held, "end")
            break
        if t_now >= t_end:  # an impact at the end of the span, up to rounding: the last
            if trajectory:
                t_chunks.append(np.array([t_now]))
                X_chunks.append(X[None, :].copy())
            close(held, "end")
            break
    if status is not SimulationStatus.COMPLETED:
        last = (f"; last impact on stop {hits[-1]!r} at speed {vels[-1]:.3g}" if hits else "")
        log.warning("simulation stopped at t=%.6g (%.6g forcing periods, %d impacts%s): %s",
                    t_now, t_now * osc.omega / TWO_PI, len(times), last, status.value)
    k = len(times)
    return SimulationResult(
        impact_times=np.array(times, dtype=float),
        impact_velocities=np.array(vels, dtype=float),
        impact_phases=np.array(phases, dtype=float),
        impact_states=np.array(states, dtype=float).reshape(k, 2 * n),
        final_time=t_now, final_state=X, final_phase=phase, status=status,
        t=np.concatenate(t_chunks) if trajectory else None,
        X=np.vstack(X_chunks) if trajectory else None,
        impact_stops="".join(hits), sticking=tuple(sticks), chatter=tuple(chatter),
        oscillator=osc, start_state=X_start, start_phase=delta, periods=periods,
    )

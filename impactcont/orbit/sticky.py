"""Periodic motions with sticking phases, by shooting with the exact flow.

A lowercase letter of a pattern (``"u"``, ``"l"``, ``"a"`` for the extra stop ``"A"``) is
an impact on that stop followed by a sticking phase on it: the stop coordinate is held at
the stop (the held system of :mod:`impactcont.orbit.held_flow`) until the pressing force
falls to zero, the release, and the flight from the release ends at the next impact.
Segment k of such a motion is impact k, the sticking phase after it (where there is one)
and the flight from its release to impact ``k + 1``; the shooting system
(:func:`sticky_shooting`) is that of :mod:`impactcont.orbit.multi_impact` with one more
unknown (the stick time ``s_k``) and one more row (the pressing force at the release,
``p(X_r, theta_r) = 0``) per sticking phase.
:func:`impactcont.orbit.multi_impact.multi_impact_orbit` dispatches a pattern with sticking
phases here.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.kernel.arrays import HeldSegments, StickyFlights
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import LOWER, UPPER, sticking_pattern
from impactcont.orbit.flow import Flow
from impactcont.orbit.held_flow import held_flow
from impactcont.orbit.multi_impact import (
    _EPS,
    _ERROR_WARN,
    _NEAR_SOLUTION,
    STICKY_SOLVER,
    TWO_PI,
    MultiImpactOrbit,
    Shooting,
    _bifurcation,
    _coordinate,
    _geometry,
    _kernel,
    _orbit,
    _parameters,
    _writable,
    contact_stops,
    impact_sequence,
    shooting_accuracy,
    unknowns_scale,
)
from impactcont.orbit.periodic import IllConditionedWarning
from impactcont.orbit.stop_geometry import StopGeometry

__all__ = [
    "CHATTER_SPEED",
    "HELD_END_ULPS",
    "OMEGA_STEP",
    "RELEASE_SHIFT",
    "Chatter",
    "StickyShooting",
    "chatter_bounces",
    "chatter_entered",
    "chatter_impacts",
    "chatter_restitution",
    "held_forcing",
    "held_omega_derivatives",
    "held_segments",
    "sticky_jacobians",
    "sticky_newton",
    "sticky_omega_column",
    "sticky_orbit_from_unknowns",
    "sticky_palc_step",
    "sticky_shooting",
]

log = logging.getLogger(__name__)


#: Where the contact search of a flight from a release starts, in periods of the fastest
#: motion its stop coordinate sees (:func:`_sticky_orbit`).
RELEASE_SHIFT = 1e-4


class StickyShooting(StickyFlights):
    """The shooting system of a motion with sticking phases evaluated at one ``u``: the
    compiled :func:`impactcont.kernel.shooting.sticky_system`'s record
    (:class:`~impactcont.kernel.arrays.StickyFlights`, whose fields it documents), with the
    flights from the releases as a :class:`~impactcont.orbit.multi_impact.Shooting`.

    Segment k is impact k, the sticking phase after it (where there is one) and the flight
    from its release to impact ``k + 1``. Arrays per segment k.

    Attributes
    ----------
    phases : ndarray, shape (p,)
        ``theta_k`` at impact k (not wrapped).
    stick_times, flight_times : ndarray, shape (p,)
        ``s_k`` (0 without a stick) and ``tau_k``.
    starts : ndarray, shape (p, 2n)
        ``X_k``, the state after impact k, on its stop's section.
    releases, release_phases : ndarray, shape (p, 2n), (p,)
        The state and phase where the flight starts (the release; ``X_k``, ``theta_k``
        without a stick).
    held_transitions, held_phase_columns, held_rates : ndarray
        ``dX_r/dX_k`` (p, 2n, 2n), ``dX_r/dtheta_k`` and ``dX_r/ds_k`` (p, 2n) of the held
        flow (identity and zeros without a stick).
    arrivals, arrival_rates, transitions, phase_columns : ndarray
        The flight from the release: ``X_k^-``, ``X'(tau_k^-)``, ``Phi`` and ``dX^-/dtheta``.
    residual : ndarray, shape (2np + q,)
        ``[r_0, .., r_{p-1}, p_k..]``: ``r_k = D_{k+1} X_k^- - X_{k+1}`` and the pressing
        force at each release (q sticks).
    jacobian : ndarray or None
        ``dr/du``, exact (None where not asked for).
    search_shifts, search_starts, search_phases : ndarray, shape (p,), (p, 2n), (p,)
        Where the contact search of each flight from a release starts (0, the release
        state and phase without a stick; :data:`RELEASE_SHIFT`).
    accumulations, accumulation_phases : ndarray, shape (p, 2n), (p,)
        Where the held flow of each sticking phase starts: the accumulation point of the
        chatter after impact k on a stop with restitution above 0, else ``X_k``,
        ``theta_k``.
    chatter_times, chatter_status : ndarray, shape (p,)
        The chatter's duration (0 without one; the held flow lasts ``s_k`` minus it) and
        the chatter map's status (the impacts resolved, ``-1`` the chatter does not
        accumulate, ``-2`` a bounce's return not found:
        :func:`impactcont.kernel.shooting._chatter_map`).
    """

    __slots__ = ()

    def flights(self) -> Shooting:
        """The flights from the releases as a
        :class:`~impactcont.orbit.multi_impact.Shooting` (their contact checks)."""
        return Shooting(phases=self.release_phases, flight_times=self.flight_times,
                        starts=self.releases, arrivals=self.arrivals,
                        arrival_rates=self.arrival_rates, transitions=self.transitions,
                        phase_columns=self.phase_columns, residual=self.residual,
                        jacobian=None)


def _python_flight(flow: Flow, t: float, X0: np.ndarray, theta: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(X(t), X'(t), Phi(t), dX(t)/dtheta)`` of one flight of `flow` (either kind)."""
    transition, forcing = flow.matrices(t)[:2]
    X = flow.state(t, X0, theta)[0]
    rate = flow.state_derivative(t, X0, theta)[0]
    return X, rate, np.array(transition), forcing @ np.array([-math.sin(theta), math.cos(theta)])


def sticky_shooting(flow: Flow, N: int, pattern: str, u: np.ndarray, *,
                    jacobian: bool = True) -> StickyShooting:
    """Residual (and exact Jacobian) of the shooting system of a motion with sticking phases.

    The unknowns are ``u = [delta, tau_0..tau_{p-2}, s_k.., z_0..z_{p-1}]``: the phase of
    impact 0, the flight times but the last (fixed by the period ``2 pi N / omega`` minus
    every other flight and stick time), the stick times ``s_k`` of the q sticking phases
    in the order of their impacts, and each post-impact state on its stop's section. The
    residual is ``r_k = D_{k+1} X_k^- - X_{k+1}`` of each segment (impact k, the sticking
    phase on its stop for ``s_k`` with the held flow of
    :mod:`impactcont.orbit.held_flow`, then the flight from the release) and, for each
    sticking phase, the pressing force at its end: the release row, ``p(X_r, theta_r) =
    0``. ``2 n p + q`` equations for ``2 n p + q`` unknowns.

    Parameters
    ----------
    flow : Flow
    N : int
    pattern : str
        With lowercase letters where a sticking phase follows an impact
        (:func:`~impactcont.model.stops.sticking_pattern`).
    u : ndarray, shape (2np + q,)
    jacobian : bool

    Returns
    -------
    StickyShooting
    """
    osc = flow.osc
    impacts = sticking_pattern(osc, pattern)[0]
    x = _sticky_unknowns(osc, pattern, u, "u")
    sh = StickyShooting._make(_kernel().sticky_system(
        flow.flight_arrays(), tuple(flow.forcing_arrays()),
        tuple(impact_sequence(_geometry(flow, impacts))), held_segments(flow, pattern),
        TWO_PI * N / osc.omega, _writable(x), bool(jacobian), _NO_FREQUENCY))
    return sh if jacobian else sh._replace(jacobian=None)


#: :func:`impactcont.kernel.shooting.sticky_system`'s ``frequency`` where no omega column
#: is asked (empty arrays of its types).
_NO_FREQUENCY = (np.zeros(0), np.zeros(0), np.zeros(0, complex), np.zeros((0, 0), complex),
                 np.zeros((0, 0)))


def _sticky_unknowns(osc: ImpactOscillator, pattern: str, u: Any, argument: str
                     ) -> np.ndarray:
    """`u` as the kernel takes it, checked to have the shape ``(2 n p + q,)`` of `pattern`
    (the message names `argument`)."""
    p, m = len(pattern), 2 * osc.n
    q = int(np.count_nonzero(sticking_pattern(osc, pattern)[1]))
    x = np.asarray(u, dtype=float)
    if x.shape != (m * p + q,):
        raise ParameterError(f"{argument} must have shape ({m * p + q},) = (2 n p + q,) for "
                             f"n={osc.n}, p={p} and q={q} sticking phases; got shape "
                             f"{x.shape}")
    return _writable(x)


def held_segments(flow: Flow, pattern: str) -> tuple[np.ndarray, ...]:
    """The sticking phases of `pattern` as the kernel takes them: the plain tuple of
    :class:`~impactcont.kernel.arrays.HeldSegments` (rows of
    :meth:`~impactcont.orbit.held_flow.HeldFlow.kernel_rows`, zeros where no stick follows
    an impact), built once per flow and pattern.

    The tables free of omega (all but the held systems' forced amplitudes ``Z`` and the
    release shifts) are built once per held system and pattern and shared by the flows
    of its oscillator at other omegas whose held flows
    :func:`~impactcont.orbit.held_flow.held_flow_at` made (a branch in omega: as
    :func:`impactcont.kernel.sticky.sticky_palc_correct` replaces only ``Z``); the
    arrays are those built afresh (the same rows, copied)."""
    cache = flow.__dict__.setdefault("_held_segments", {})
    held = cache.get(pattern)
    if held is None:
        osc = flow.osc
        impacts, sticks = sticking_pattern(osc, pattern)
        p, m = len(pattern), 2 * osc.n
        helds = [held_flow(osc, impacts[k]) if sticks[k] else None for k in range(p)]
        statics = tuple(None if h is None else h.static_rows() for h in helds)
        first = next((h for h in helds if h is not None), None)
        shared = first.shared() if first is not None else {}
        key = ("held_segments", pattern)
        entry = shared.get(key)
        if entry is None or any(a is not b for a, b in zip(entry[0], statics, strict=True)):
            entry = shared[key] = (statics, _static_tables(osc, impacts, sticks, statics))
        tables = entry[1]
        r = m - 2
        Z = np.zeros((p, r), dtype=complex)
        shifts = np.zeros(p)
        geo = _geometry(flow, impacts)
        for k in np.flatnonzero(sticks):
            if helds[k].reduced is not None:
                Z[k] = helds[k].reduced.Z
            shifts[k] = RELEASE_SHIFT * TWO_PI / _release_rate(flow, shared, geo.normals[k])
        held = cache[pattern] = HeldSegments(*tables[:9], Z, *tables[9:12], shifts,
                                             *tables[12:])
    return tuple(held)


def _release_rate(flow: Flow, shared: dict, normal: np.ndarray) -> float:
    """``flow.time_scales(normal=normal)[0]``, ``max(omega, fastest damped frequency the
    stop coordinate sees)``: the modes' part is free of omega, so where a flow sharing
    `shared` (:func:`held_segments`) found it above its omega, it is that at any omega."""
    key = ("release_rate", np.asarray(normal, dtype=float).tobytes())
    known = shared.get(key)
    if known is not None and known[1] > known[0]:  # the fastest mode's: above omega there
        return float(max(flow.omega, known[1]))
    rate = flow.time_scales(normal=normal)[0]
    shared[key] = (flow.omega, rate)
    return rate


def _static_tables(osc: ImpactOscillator, impacts: str, sticks: Any, statics: tuple
                   ) -> tuple[np.ndarray, ...]:
    """The fields of :class:`~impactcont.kernel.arrays.HeldSegments` free of omega in its
    order (``sticks``, ``L, L^+, X_c, lam, V, V^-1, X_s, d``, ``grad, force, level``,
    restitutions, chatter impacts), from each stick's
    :meth:`~impactcont.orbit.held_flow.HeldFlow.static_rows` (`statics`, None where no
    stick follows an impact)."""
    p, m = len(impacts), 2 * osc.n
    r = m - 2
    shapes = ((m, r), (r, m), (m,), (r,), (r, r), (r, r), (r,), (r,), (m,), (), ())
    kinds = (float, float, float, complex, complex, complex, float, float, float, complex,
             float)
    fields = []
    for i, (shape, kind) in enumerate(zip(shapes, kinds, strict=True)):
        table = np.zeros((p, *shape), dtype=kind)
        for k in range(p):
            if statics[k] is not None:
                table[k] = statics[k][i]
        fields.append(table)
    restitutions = np.array([chatter_restitution(osc, impacts[k]) if sticks[k] else 0.0
                             for k in range(p)])
    counts = np.array([chatter_impacts(r) for r in restitutions], dtype=np.int64)
    return (np.array(sticks, dtype=np.bool_), *fields, restitutions, counts)


#: The chatter after a landing impact is resolved impact by impact until its impact speed
#: falls below this fraction of the landing's (``R^K <= CHATTER_SPEED``), then jumped over
#: to its accumulation point (:func:`impactcont.kernel.shooting._chatter_map`): the jump's
#: error is ``O(v_K^2)``, and the release forgets it (the held flow from the accumulation
#: point, shifted along itself), measured in tests/integration/test_chatter_entered_motions.py.
CHATTER_SPEED = 1e-5


def chatter_restitution(osc: ImpactOscillator, stop: str) -> float:
    """The restitution of `stop` (its name, a capital) on `osc`, above 0 where a sticking
    phase on it is entered through complete chatter."""
    known = _RESTITUTIONS.setdefault(osc, {})
    found = known.get(stop)
    if found is None:
        found = known[stop] = float(osc.stops.stop(stop, osc.M, osc.b, osc.R).restitution)
    return found


#: :func:`chatter_restitution` of each live oscillator, by stop name.
_RESTITUTIONS: weakref.WeakKeyDictionary[ImpactOscillator, dict[str, float]] = \
    weakref.WeakKeyDictionary()


def chatter_impacts(restitution: float) -> int:
    """How many impacts of a chatter on a stop of this restitution are resolved before the
    jump: the smallest K with ``R^K <= CHATTER_SPEED`` (0 for a plastic stop). A fixed
    count keeps the shooting residual smooth (no threshold switches inside a Newton solve)."""
    if not restitution > 0.0:
        return 0
    return max(1, math.ceil(math.log(CHATTER_SPEED) / math.log(restitution)))


def chatter_entered(osc: ImpactOscillator, pattern: str) -> bool:
    """A sticking phase of `pattern` is entered through complete chatter (its stop's
    restitution is above 0)."""
    impacts, sticks = sticking_pattern(osc, pattern)
    return any(chatter_restitution(osc, impacts[k]) > 0.0 for k in np.flatnonzero(sticks))


@dataclasses.dataclass(frozen=True, eq=False)
class Chatter:
    """The complete chatter that enters the sticking phase after one impact: its resolved
    bounces (the flights between its impacts) and its accumulation point.

    Attributes
    ----------
    impact : int
        k, the landing impact that starts the chatter.
    stop : str
        Its stop (a capital).
    starts : ndarray, shape (c, 2n)
        The state right after each resolved impact (the landing's first), on the stop's
        section; bounce i is the flight from ``starts[i]`` at ``phases[i]`` for
        ``times[i]``.
    phases, times : ndarray, shape (c,)
        Each bounce's forcing phase at its start (not wrapped) and its duration.
    arrivals, transitions, phase_columns, rates : ndarray
        Each bounce's ``X^-`` (c, 2n), ``Phi`` (c, 2n, 2n), ``dX^-/dtheta`` and ``X'``
        (c, 2n) at its end (the return to the stop), as a flight's.
    accumulation : ndarray, shape (2n,)
        The state at the accumulation point, where the held flow starts.
    accumulation_phase : float
    duration : float
        From the landing to the accumulation point: the resolved bounces and the jump over
        the rest (:func:`impactcont.kernel.shooting._chatter_map`).
    reached : str
        The other stops a resolved bounce reaches (their names, in the motion's stop order;
        empty: none, or the bounces not checked): what the motion's reason says of them in
        words, for readers of its numbers (``impactcont.analysis.family_maps``' bit
        ``bounce_reaches_stop``).
    """

    impact: int
    stop: str
    starts: np.ndarray
    phases: np.ndarray
    times: np.ndarray
    arrivals: np.ndarray
    transitions: np.ndarray
    phase_columns: np.ndarray
    rates: np.ndarray
    accumulation: np.ndarray
    accumulation_phase: float
    duration: float
    reached: str = ""


def chatter_bounces(flow: Flow, pattern: str, sh: StickyShooting) -> tuple[Chatter, ...]:
    """The chatters of the shot `sh` whose impacts accumulate, one per chatter-entered
    sticking phase of `pattern`: the bounces :func:`impactcont.kernel.shooting._chatter_map`
    resolved, replayed (:func:`impactcont.kernel.sticky.chatter_checks`: the same flights,
    returns and impacts, bitwise the shooting path's bounces), and the accumulation point
    `sh` holds. A chatter whose map failed (``chatter_status < 0``) is left out (the motion
    is not physical for it)."""
    return _checked_chatters(flow, pattern, sh, False)[0]


def _checked_chatters(flow: Flow, pattern: str, sh: StickyShooting, checks: bool
                      ) -> tuple[tuple[Chatter, ...], dict[int, list[_HeldGap]]]:
    """:func:`chatter_bounces` and, with `checks`, every stop's smallest clearance along each
    chatter's resolved bounces (each stop but the chatter's own: one :class:`_HeldGap` per
    stop, its time from the landing, crossed where a bounce reaches it), by the chatter's
    landing impact; a chatter's ``reached`` names the stops its bounces cross. One compiled
    call per chatter (:func:`impactcont.kernel.sticky.chatter_checks`).

    Each bounce is checked as every flight is (each a flight from an impact on the
    chatter's stop to the next): the contact search of eq. (16) at the interior extrema
    of every stop coordinate (exact to its root search; a clearance ``<= 0`` there is a
    crossing) and every stop's clearance at both ends (past the stop by more than its
    rounding: a coordinate crossing monotonically inside a bounce). The chatter's own stop
    is not searched (a bounce starts and ends on it and its return is the chatter map's).
    The jumped rest of the chatter (after the last resolved impact, its speed ``<=
    CHATTER_SPEED`` of the landing's) rises about ``(CHATTER_SPEED / R)^2`` of the first
    bounce's apex (the apex goes as the square of the speed) and is not checked."""
    osc = flow.osc
    impacts, sticks = sticking_pattern(osc, pattern)
    held = held_segments(flow, pattern)
    restitutions = HeldSegments(*held).restitutions
    found = []
    bounces: dict[int, list[_HeldGap]] = {}
    arrays = None  # the kernel's arguments, once per call
    for k in np.flatnonzero(sticks):
        if not restitutions[k] > 0.0 or sh.chatter_status[k] < 0:
            continue
        if arrays is None:
            from impactcont.kernel.sticky import chatter_checks

            geo = _geometry(flow, impacts)
            arrays = (tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
                      tuple(impact_sequence(geo)), held, tuple(contact_stops(geo)))
            names, coordinates = _stop_names(geo)
        (starts, phases, times, arr, tr, cols, rates, count, gap, when, crossed,
         present) = chatter_checks(*arrays, int(k), names.index(impacts[k]),
                                   _writable(np.asarray(sh.starts[k], dtype=float)),
                                   float(sh.phases[k]), bool(checks))
        c = max(int(count), 0)
        gaps = [_HeldGap(float(gap[i]), float(when[i]), names[i], coordinates[i],
                         bool(crossed[i])) for i in np.flatnonzero(present)]
        if checks:
            bounces[int(k)] = gaps
        found.append(Chatter(impact=int(k), stop=impacts[k], starts=starts[:c].copy(),
                             phases=phases[:c].copy(), times=times[:c].copy(),
                             arrivals=arr[:c].copy(), transitions=tr[:c].copy(),
                             phase_columns=cols[:c].copy(), rates=rates[:c].copy(),
                             accumulation=np.array(sh.accumulations[k], dtype=float),
                             accumulation_phase=float(sh.accumulation_phases[k]),
                             duration=float(sh.chatter_times[k]),
                             reached="".join(g.stop for g in gaps if g.crossed)))
    return tuple(found), bounces


def _stop_names(geo: StopGeometry) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The names of the stops of `geo` in the kernel's order (U, L, the extra stops) and
    their stop coordinates in words, kept per geometry."""
    found = _NAMES.get(geo)
    if found is None:
        normals = (geo.normal, geo.normal, *geo.extra_normals)
        found = _NAMES[geo] = ((UPPER, LOWER, *geo.extra_names),
                               tuple(_coordinate(nv) for nv in normals))
    return found


#: :func:`_stop_names` of each live stop geometry.
_NAMES: weakref.WeakKeyDictionary[StopGeometry, tuple] = weakref.WeakKeyDictionary()


#: A stop's clearance at an end of a sticking phase (its start, its release) is a crossing
#: below ``-HELD_END_ULPS eps (|c| + sum |n_i x_i|)``, the rounding of its evaluation, as at
#: a flight's ends (:data:`impactcont.kernel.shooting._END_ULPS`).
HELD_END_ULPS = 64.0


@dataclasses.dataclass(frozen=True)
class _HeldGap:
    """The smallest clearance of one other stop along one sticking phase (its chatter's
    bounces or its held flow)."""

    gap: float
    time: float  # after the impact that starts the sticking phase
    stop: str
    coordinate: str
    crossed: bool


def _held_clearances(flow: Flow, impacts: str, k: int, start: np.ndarray, phase: float,
                     duration: float, release: np.ndarray, offset: float) -> list[_HeldGap]:
    """Every stop's smallest clearance along the held flow of the sticking phase after
    impact k (but the held stop's own), one :class:`_HeldGap` per stop.

    The held flow runs `duration` from `start` at `phase` (the accumulation point of a
    chatter, `offset` after the landing; else the plastic impact's state, `offset` 0) to
    the release state `release`. Each stop coordinate is searched at both ends and at its
    turning point nearest the stop inside (:meth:`~impactcont.orbit.held_flow.HeldFlow.
    stop_clearances`, the contact search of eq. (16) on the held system's flow): a
    clearance ``<= 0`` at a turning point, or below the rounding of its evaluation at an
    end (:data:`HELD_END_ULPS`), is the stop crossed while the other is held.
    """
    geo = _geometry(flow, impacts)
    n = flow.osc.n
    names, normals, signs, positions = _other_stops(flow, geo, impacts[k])
    inner, inner_times = held_flow(flow.osc, impacts[k]).stop_clearances(
        duration, start, phase, (normals, signs, positions))
    ends = np.array((start[:n], release[:n]))
    found = []
    for i, name in enumerate(names):
        at_ends = signs[i] * (positions[i] - ends @ normals[i])
        tol = HELD_END_ULPS * _EPS * (abs(positions[i]) + np.abs(ends * normals[i]).sum(axis=1))
        gaps = (float(at_ends[0]), float(at_ends[1]), float(inner[i]))
        when = (0.0, duration, float(inner_times[i]))
        nans = [g for g in range(3) if math.isnan(gaps[g])]
        j = nans[0] if nans else gaps.index(min(gaps))  # np.argmin's: the first NaN, smallest
        crossed = bool(not gaps[2] > 0.0 or at_ends[0] < -tol[0] or at_ends[1] < -tol[1])
        found.append(_HeldGap(gaps[j], offset + when[j], name, _coordinate(normals[i]),
                              crossed))
    return found


def _other_stops(flow: Flow, geo: StopGeometry, stop: str
                 ) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Every stop of `geo` but `stop`: their names, normals (q, n), signs and positions,
    kept per flow, geometry and stop (:func:`_held_clearances`)."""
    cache = flow.__dict__.setdefault("_other_stops", {})
    entry = cache.get(stop)
    if entry is not None and entry[0] is geo:
        return entry[1]
    n = flow.osc.n
    names = [UPPER, *([LOWER] if geo.two_sided else []), *geo.extra_names]
    normals = np.vstack([geo.normal[None], *([geo.normal[None]] if geo.two_sided else []),
                         np.reshape(geo.extra_normals, (-1, n))])
    signs = np.concatenate([[1.0], [-1.0] if geo.two_sided else [], geo.extra_signs])
    positions = np.concatenate([[geo.b], [-geo.b_low] if geo.two_sided else [],
                                geo.extra_positions])
    others = np.array([name != stop for name in names])
    names = [name for name, other in zip(names, others, strict=True) if other]
    found = (names, normals[others], signs[others], positions[others])
    cache[stop] = (geo, found)
    return found


def sticky_newton(flow: Flow, N: int, pattern: str, u0: np.ndarray, *, tol: float = 1e-12,
                  max_iter: int = 40) -> tuple[np.ndarray, StickyShooting, int]:
    """:func:`~impactcont.orbit.multi_impact.newton` on :func:`sticky_shooting`: the same
    iteration, stopping rules and messages (compiled:
    :func:`impactcont.kernel.shooting.sticky_newton_solve`).

    Raises
    ------
    NoPeriodicMotionError
        No convergence, or a singular Jacobian.
    """
    osc = flow.osc
    impacts = sticking_pattern(osc, pattern)[0]
    x0 = _sticky_unknowns(osc, pattern, u0, "u0")
    x, status, it, norm, step_norm, out = _kernel().sticky_newton_solve(
        flow.flight_arrays(), tuple(flow.forcing_arrays()),
        tuple(impact_sequence(_geometry(flow, impacts))), held_segments(flow, pattern),
        TWO_PI * N / osc.omega, x0, float(tol), int(max_iter))
    sh = StickyShooting._make(out)
    if status == 0:
        return x, sh, int(it)
    cond, error = shooting_accuracy(sh.jacobian, sh.residual, x)
    p = len(pattern)
    if norm <= _NEAR_SOLUTION * unknowns_scale(x) and not cond * _EPS <= _ERROR_WARN:
        raise NoPeriodicMotionError(
            f"{_bifurcation(N, p, flow.osc, cond, error)}; Newton stopped at residual "
            f"{norm:.3g} (last update {step_norm:.3g}) after {it} iterations")
    raise NoPeriodicMotionError(
        f"N={N}, p={p}: Newton did not converge in {it} iterations (residual {norm:.3g}, "
        f"last update {step_norm:.3g}) at {_parameters(flow.osc)} with the pattern "
        f"{pattern!r} of sticking phases (is the guess a motion whose impacts on the "
        "lowercase stops are each followed by a sticking phase ended by a release? a "
        "simulation's sticking phases show the one it settled on)")


def held_omega_derivatives(flow: Flow, pattern: str) -> np.ndarray:
    """``dZ/d omega`` of the steady amplitude of each held system of `pattern` at the flow's
    omega, shape (p, 2n - 2) complex (zeros where no stick follows an impact, or one mass
    held): the held systems' part of :func:`sticky_omega_column`
    (:meth:`impactcont.orbit.flow.GeneralFlow.omega_arrays` of each held flow)."""
    osc = flow.osc
    impacts, sticks = sticking_pattern(osc, pattern)
    r = 2 * osc.n - 2
    out = np.zeros((len(pattern), r), dtype=complex)
    for k in np.flatnonzero(sticks):
        reduced = held_flow(osc, impacts[k]).reduced
        if reduced is not None:
            out[k] = reduced.omega_arrays().dZ
    return out


def sticky_omega_column(flow: Flow, N: int, pattern: str, u: np.ndarray,
                        sh: StickyShooting | None = None) -> np.ndarray:
    """``dr/d omega`` of :func:`sticky_shooting` at fixed unknowns ``u``, exact (compiled:
    :func:`impactcont.kernel.shooting.sticky_frequency_column`).

    The phases, the period's last flight time, the steady forced state of each flight and
    of each held system (its amplitude ``Z_r(omega)``) and, through them, the release rows;
    with a sticking phase entered through complete chatter, the chatter map's omega too
    (each resolved bounce's forced state, return time and impact, the jump to the
    accumulation point: :func:`impactcont.kernel.shooting.sticky_system`'s ``frequency``,
    one more residual). The column of the continuation in omega
    (``MultiImpactBranchProblem.dparam``).

    Parameters
    ----------
    flow, N, pattern, u
        As :func:`sticky_shooting` takes them.
    sh : StickyShooting, optional
        :func:`sticky_shooting` at ``u`` if already computed (its Jacobian is not read).

    Returns
    -------
    ndarray, shape (2np + q,)
    """
    osc = flow.osc
    impacts = sticking_pattern(osc, pattern)[0]
    x = _sticky_unknowns(osc, pattern, u, "u")
    geo = tuple(impact_sequence(_geometry(flow, impacts)))
    held, held_dZ = held_segments(flow, pattern), held_omega_derivatives(flow, pattern)
    derivatives = tuple(_writable_arrays(flow.omega_arrays()))
    d_release = np.zeros((0, 0))
    if chatter_entered(osc, pattern):  # the chatter map's omega comes with the residual
        d_release = np.zeros((len(pattern), 2 * osc.n))
        sh = StickyShooting._make(_kernel().sticky_system(
            flow.flight_arrays(), tuple(flow.forcing_arrays()), geo, held,
            TWO_PI * N / osc.omega, x, False, (*derivatives, held_dZ, d_release)))
    elif sh is None:
        sh = sticky_shooting(flow, N, pattern, x, jacobian=False)
    shot = tuple(sh._replace(jacobian=np.zeros((0, 0))))  # the record's plain tuple
    return _kernel().sticky_frequency_column(
        tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()), derivatives, geo, held,
        held_dZ, TWO_PI * N / osc.omega, shot, d_release)


def _writable_arrays(arrays: tuple) -> list[np.ndarray]:
    """Each array of `arrays` contiguous and writable, its dtype kept (the kernel's
    argument types: one compile)."""
    return [a if a.flags.c_contiguous and a.flags.writeable else np.array(a, order="C")
            for a in arrays]


#: The relative step in omega of the central differences that served as
#: :func:`sticky_omega_column` for a motion whose sticking phases are entered through
#: complete chatter before the chatter map's omega was written out (the step of the
#: tests' witness).
OMEGA_STEP = 1e-5


def held_forcing(flow: Flow, pattern: str) -> tuple[np.ndarray, ...]:
    """The held systems of `pattern` as their forced amplitudes need them at any omega: the
    plain tuple of :class:`~impactcont.kernel.arrays.HeldForcing` (each held system's
    ``M_r, K_r, C_r`` and ``F_r``, zeros where no stick follows an impact or one mass is
    held), built once per flow and pattern."""
    cache = flow.__dict__.setdefault("_held_segments", {})
    key = (pattern, "forcing")
    found = cache.get(key)
    if found is None:
        osc = flow.osc
        impacts, sticks = sticking_pattern(osc, pattern)
        p, n = len(pattern), osc.n - 1
        M, K, C = (np.zeros((p, n, n)) for _ in range(3))
        F = np.zeros((p, n), dtype=complex)
        for k in np.flatnonzero(sticks):
            reduced = held_flow(osc, impacts[k]).reduced
            if reduced is not None:
                arrays = reduced.basis.kernel_arrays
                M[k], K[k], C[k] = arrays.M, arrays.K, arrays.C
                F[k] = reduced.osc.F
        found = cache[key] = (M, K, C, F)
    return found


def sticky_palc_step(flow: Flow, N: int, pattern: str, predicted: np.ndarray,
                     tangent: np.ndarray, weights: np.ndarray, tol: float, max_iter: int,
                     singular: float, *, hyperplane: bool = False, with_shot: bool = False
                     ) -> Any:
    """One corrector step of a branch in omega of a motion with sticking phases, compiled
    (:func:`impactcont.kernel.sticky.sticky_palc_correct`).

    The continuation core's pseudo-arclength Newton and tangent on ``[u, omega]``
    (``MultiImpactBranchProblem.palc_step``, as
    :func:`impactcont.kernel.shooting.palc_correct` is for motions without sticking
    phases), each iterate's flights, held systems, residual, exact Jacobian and
    :func:`sticky_omega_column` at its own omega, in one compiled call.

    Parameters
    ----------
    flow : Flow
        The modal flow of the branch's start (any omega: only its modes, the stops and
        the held systems' modes are read).
    N : int
    pattern : str
        With lowercase letters where a sticking phase follows an impact.
    predicted, tangent, weights : ndarray, shape (2np + q + 1,)
        The predicted point ``[u, omega]``, the tangent and the arclength weights.
    tol : float
    max_iter : int
    singular : float
        The Frobenius condition bound above which a bordered matrix is returned flagged.
    hyperplane : bool
        The Newton of :func:`impactcont.core.corrector.solve_on_hyperplane` instead.
    with_shot : bool
        Return the converged point's shot too.

    Returns
    -------
    PalcResult
        As :func:`impactcont.kernel.shooting.palc_correct` returns it.
    StickyShooting or None
        With `with_shot`: :func:`sticky_shooting` at the converged point (its flights and
        held systems at its omega computed in the corrector, with the Jacobian), None where
        the step did not converge or ends on the hyperplane (its last update comes after
        its last shot).

    Raises
    ------
    ParameterError
        `flow` is not modal (a first-order flow's forced amplitudes are not recomputed in
        compiled code), or the arrays do not have the pattern's size.
    """
    from impactcont.kernel import sticky
    from impactcont.kernel.shooting import CONVERGED

    osc = flow.osc
    if type(flow) is not Flow or not np.isrealobj(flow.f):
        raise ParameterError(f"sticky_palc_step: flow must be a modal flow (proportional "
                             f"damping, real F); got {type(flow).__name__} of {osc!r}")
    size = _sticky_unknowns(osc, pattern, np.asarray(predicted, dtype=float)[:-1],
                            "predicted[:-1]").size + 1
    for name, value in (("tangent", tangent), ("weights", weights)):
        if np.shape(value) != (size,):
            raise ParameterError(f"{name} must have shape ({size},) like predicted; got "
                                 f"{np.shape(value)}")
    impacts = sticking_pattern(osc, pattern)[0]
    errors = osc.modes.eigenvalue_errors
    errors = np.zeros(osc.n) if errors is None else np.asarray(errors, dtype=float)
    out, shot = sticky.sticky_palc_correct(
        tuple(flow.shooting_arrays()), _writable(errors),
        tuple(impact_sequence(_geometry(flow, impacts))), held_segments(flow, pattern),
        held_forcing(flow, pattern), float(N),
        (_writable(np.asarray(predicted, dtype=float)),
         _writable(np.asarray(tangent, dtype=float)),
         _writable(np.asarray(weights, dtype=float))),
        (float(tol), int(max_iter), float(singular), bool(hyperplane)))
    if not with_shot:
        return out
    if hyperplane or out.status != CONVERGED:
        return out, None
    return out, StickyShooting._make(shot)


def sticky_jacobians(flow: Flow, pattern: str, sh: StickyShooting
                     ) -> tuple[np.ndarray, np.ndarray]:
    """``G_k`` of each segment (impact k's section to impact ``k + 1``'s, in ``[z,
    theta]``) and their product G, for a motion with sticking phases.

    A sticking phase ends where the pressing force vanishes, so its duration moves by
    ``ds = -(dp/dX dX_r + dp/dtheta dtheta_r) / (dp/dt)`` (the release row's saltation),
    and the flight from the release ends on the next section as in eq. (25); the stick
    collapses the directions it holds (``G`` has exact zero multipliers). Compiled
    (:func:`impactcont.kernel.shooting.sticky_jacobians`).

    Returns
    -------
    jacobians : ndarray, shape (p, 2n, 2n)
    G : ndarray, shape (2n, 2n)
    """
    impacts = sticking_pattern(flow.osc, pattern)[0]
    segments = tuple(_writable(np.asarray(a, dtype=float)) for a in (
        sh.releases, sh.release_phases, sh.held_transitions, sh.held_phase_columns,
        sh.held_rates, sh.transitions, sh.phase_columns, sh.arrival_rates))
    return _kernel().sticky_jacobians(tuple(impact_sequence(_geometry(flow, impacts))),
                                      held_segments(flow, pattern), float(flow.osc.omega),
                                      segments)


@dataclasses.dataclass(frozen=True)
class _Sticks:
    """What :func:`~impactcont.orbit.multi_impact._orbit` reports of a motion with sticking
    phases beside its flights."""

    pattern: str
    phases: np.ndarray
    states: np.ndarray
    stick_times: np.ndarray
    flight_times: np.ndarray
    shift: np.ndarray
    release_states: np.ndarray
    pressing_min: np.ndarray
    landing_pressing: np.ndarray
    jacobians: np.ndarray
    G: np.ndarray
    multipliers: np.ndarray
    reasons: tuple[str, ...]
    chatters: tuple[Chatter, ...] = ()
    held_gaps: tuple[tuple[_HeldGap, ...], ...] = ()


def _sticks(flow: Flow, pattern: str, sh: StickyShooting, shift: np.ndarray,
            checks: bool = True) -> _Sticks:
    """The sticking phases' part of a motion: G, its multipliers and the physical checks
    of each sticking phase (its chatter's bounces and its held flow clear of every other
    stop, with `checks`, their clearances kept for :func:`_with_held_gaps`; its onset, its
    pressing force inside, its release); `shift` the start of each flight's contact search
    after its release."""
    osc = flow.osc
    impacts, sticks = sticking_pattern(osc, pattern)
    p, m = len(pattern), 2 * osc.n
    jacs, G = sticky_jacobians(flow, pattern, sh)
    mu = np.linalg.eigvals(G) if np.all(np.isfinite(G)) else np.full(m, np.nan + 0j)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    releases = np.full((p, m), np.nan)
    pressing = np.full(p, np.nan)
    landing = np.full(p, np.nan)
    reasons = []
    held_gaps: list[tuple[_HeldGap, ...]] = [() for _ in range(p)]
    chatters, bounces = _checked_chatters(flow, pattern, sh, checks)
    for k in np.flatnonzero(sticks):
        held = held_flow(osc, impacts[k])
        held_gaps[k] = tuple(bounces.get(int(k), ()))
        reasons.extend(f"impact {k}: a bounce of the chatter on stop {impacts[k]!r} reaches "
                       f"stop {g.stop!r}: {g.coordinate} has clearance {g.gap:.3g} at "
                       f"t={g.time:.6g} after the landing" for g in held_gaps[k] if g.crossed)
        stop, s = impacts[k], float(sh.stick_times[k])
        releases[k] = sh.releases[k]
        start, phase = sh.accumulations[k], float(sh.accumulation_phases[k])
        onset = landing[k] = float(held.pressing(start, phase))
        status, chatter = int(sh.chatter_status[k]), float(sh.chatter_times[k])
        if status == -1:
            reasons.append(f"impact {k}: incomplete chatter: the acceleration of the stop "
                           f"coordinate does not point into stop {stop!r} during the chatter "
                           "the impact starts (its impacts do not accumulate)")
        elif status < 0:
            reasons.append(f"impact {k}: the chatter on stop {stop!r} has a bounce whose "
                           "return to the stop is not found")
        if not s > chatter:
            reasons.append(f"sticking phase {k} (stop {stop!r}) has duration {s - chatter:.3g} "
                           f"<= 0 after its chatter ({chatter:.3g})")
            continue
        if not onset > 0.0:
            where = ("at the chatter's accumulation point" if chatter > 0.0 else
                     "after the plastic impact")
            reasons.append(f"impact {k}: sticking onset: the pressing force on stop {stop!r} "
                           f"{where} is {onset:.3g} <= 0 (the acceleration does not point "
                           "into the stop)")
        low, when = held.pressing_minimum(s - chatter, start, phase,
                                          samples=_held_pressing(flow, pattern, int(k), start,
                                                                 phase))
        pressing[k] = low
        if onset > 0.0 and not low > 0.0:
            reasons.append(f"sticking phase {k}: release grazing: the pressing force on stop "
                           f"{stop!r} falls to {low:.3g} <= 0 at t={when:.6g} inside the "
                           "sticking phase")
        rate = held.pressing_rate(sh.held_rates[k], float(sh.release_phases[k]))
        if not rate < 0.0:
            reasons.append(f"sticking phase {k}: at the release the pressing force on stop "
                           f"{stop!r} does not fall through zero (dp/dt = {rate:.3g} >= 0): "
                           "the stop coordinate does not leave the stop")
        if checks:
            ride = _held_clearances(flow, impacts, int(k), start, phase, s - chatter,
                                    sh.releases[k], chatter)
            held_gaps[k] += tuple(ride)
            reasons.extend(
                f"sticking phase {k} (stop {stop!r}): {g.coordinate} reaches stop {g.stop!r} "
                f"while {stop!r} holds (clearance {g.gap:.3g} at t={g.time:.6g} after impact "
                f"{k})" for g in ride if g.crossed)
    return _Sticks(pattern=pattern, phases=sh.phases, states=sh.starts,
                   stick_times=sh.stick_times, flight_times=sh.flight_times, shift=shift,
                   release_states=releases, pressing_min=pressing, landing_pressing=landing,
                   jacobians=jacs, G=G, multipliers=mu, reasons=tuple(reasons),
                   chatters=chatters, held_gaps=tuple(held_gaps))


def _held_pressing(flow: Flow, pattern: str, k: int, start: np.ndarray, phase: float
                   ) -> Callable[[np.ndarray], np.ndarray]:
    """The pressing force along the held flow of the sticking phase after impact k from
    `start` at `phase`, at an array of times after it: compiled
    (:func:`impactcont.kernel.shooting.held_pressing`, the shooting path's held flow), the
    samples of :meth:`~impactcont.orbit.held_flow.HeldFlow.pressing_minimum`."""
    held = held_segments(flow, pattern)
    omega = float(flow.osc.omega)
    X0 = _writable(np.asarray(start, dtype=float))
    press = _kernel().held_pressing

    def samples(times: np.ndarray) -> np.ndarray:
        return press(held, k, omega, X0, float(phase), _writable(times))

    return samples


def _sticky_orbit(flow: Flow, N: int, pattern: str, u0: np.ndarray, tol: float,
                  max_iter: int) -> MultiImpactOrbit:
    """:func:`~impactcont.orbit.multi_impact.multi_impact_orbit` of a pattern with sticking
    phases."""
    osc = flow.osc
    p = len(pattern)
    u, sh, iterations = sticky_newton(flow, N, pattern, u0, tol=tol, max_iter=max_iter)
    cond, error = shooting_accuracy(sh.jacobian, sh.residual, u)
    if not error <= _ERROR_WARN * unknowns_scale(u):
        warnings.warn(f"{_bifurcation(N, p, osc, cond, error)} (residual "
                      f"{float(np.max(np.abs(sh.residual))):.3g})", IllConditionedWarning,
                      stacklevel=3)
    log.debug("N=%d p=%d %s motion with sticking phases in %d Newton iterations", N, p,
              pattern, iterations)
    return _sticky_motion(flow, N, pattern, sh, True, cond, error)


def _sticky_motion(flow: Flow, N: int, pattern: str, sh: StickyShooting, checks: bool,
                   condition_number: float = math.nan, error_estimate: float = math.nan
                   ) -> MultiImpactOrbit:
    """The motion with sticking phases of the shot `sh` (at a solution): its flights'
    checks (with `checks`, the interior-contact search), G and the sticking phases' checks.
    """
    impacts = sticking_pattern(flow.osc, pattern)[0]
    # the contact search of each flight from a release starts RELEASE_SHIFT of the fastest
    # period after it (held_segments): there s = c, s' = 0 and s'' = 0 (the pressing force
    # is 0), so the start itself is a (degenerate) maximum of the coordinate at the stop;
    # past it the coordinate leaves as the cube of the time (the release row's
    # transversality) and a later return is found as on any flight
    shift = sh.search_shifts
    flights = dataclasses.replace(sh.flights(), starts=sh.search_starts,
                                  phases=sh.search_phases, flight_times=sh.flight_times - shift)
    sticks = _sticks(flow, pattern, sh, shift, checks)
    orbit = _orbit(flow, N, len(pattern), flights, checks, impacts, condition_number,
                   error_estimate, sticks=sticks)
    if not checks:
        return orbit
    return _with_held_gaps(orbit, sticks)


def _with_held_gaps(orbit: MultiImpactOrbit, sticks: _Sticks) -> MultiImpactOrbit:
    """`orbit` with each segment's smallest clearance over its sticking phase too: segment k
    is impact k, the sticking phase after it (its chatter's resolved bounces and its held
    flow) and the flight from its release, so a sticking phase's clearance smaller than
    its flight's becomes ``flight_gap_min[k]`` (the stop in
    ``flight_gap_stops[k]``, the time in ``flight_gap_min_times[k]`` counted from the
    release as the flight's are: negative, inside the sticking phase). The GR test
    function ``gap_min`` then changes sign where another stop coordinate touches its stop
    inside a sticking phase or a chatter's bounce, as it does inside a flight."""
    gaps = orbit.flight_gap_min.copy()
    times = orbit.flight_gap_min_times.copy()
    stops = list(orbit.flight_gap_stops)
    for k, found in enumerate(sticks.held_gaps):
        for g in found:
            if g.gap < gaps[k]:
                gaps[k] = g.gap
                times[k] = g.time - float(sticks.stick_times[k])
                stops[k] = g.stop
    return dataclasses.replace(orbit, flight_gap_min=gaps, flight_gap_min_times=times,
                               flight_gap_stops="".join(stops))


def sticky_orbit_from_unknowns(flow: Flow, N: int, pattern: str, u: np.ndarray,
                               sh: StickyShooting | None = None, *, checks: bool = True
                               ) -> MultiImpactOrbit:
    """:func:`~impactcont.orbit.multi_impact.orbit_from_unknowns` of a motion with sticking
    phases: the motion at the solution ``u`` of :func:`sticky_shooting` (a point of its
    branch), with G, the stick times, release states and pressing minima, and every check.

    Parameters
    ----------
    flow, N, pattern
        As :func:`sticky_shooting` takes them.
    u : ndarray, shape (2np + q,)
        A (converged) solution of :func:`sticky_shooting`.
    sh : StickyShooting, optional
        :func:`sticky_shooting` at ``u`` if already computed (with its Jacobian, for the
        motion's error estimate).
    checks : bool
        Search every flight for interior contact (eq. 16); without it ``flight_gap_min``
        is NaN and the motion is reported not physical with that reason.

    Returns
    -------
    MultiImpactOrbit
    """
    if sh is None:
        sh = sticky_shooting(flow, N, pattern, u)
    x = _sticky_unknowns(flow.osc, pattern, u, "u")
    cond, error = (shooting_accuracy(sh.jacobian, sh.residual, x) if sh.jacobian is not None
                   else (math.nan, math.nan))
    return _sticky_motion(flow, N, pattern, sh, checks, cond, error)


STICKY_SOLVER[:] = [_sticky_orbit]

"""The compiled corrector of a branch of motions with sticking phases in omega.

:func:`sticky_palc_correct` is :func:`impactcont.kernel.shooting.palc_correct` on the
shooting system of a motion with sticking phases
(:func:`~impactcont.kernel.shooting.sticky_system`, its omega column
:func:`~impactcont.kernel.shooting.sticky_frequency_column`), with the held systems'
forced amplitudes at each iterate's omega
(:func:`impactcont.kernel.general.forced_response`). A module of its own so that the
shooting path of motions without sticking phases neither imports
:mod:`impactcont.kernel.general` (its entry points are compiled on import) nor compiles
this one: only a sticky branch in omega imports it
(:func:`impactcont.orbit.sticky.sticky_palc_step`), and a motion whose sticking phases are
entered through complete chatter (:func:`chatter_checks`, its bounces and their contact
checks).
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.arrays import (
    ContactStops,
    CorrectorSettings,
    CorrectorStep,
    Forcing,
    HeldForcing,
    HeldSegments,
    ImpactSequence,
    PalcResult,
    ShootingFlow,
    StickyFlights,
)
from impactcont.kernel.general import forced_response, forced_response_derivative
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.shooting import (
    FAILED,
    GOING,
    REFUSED,
    _bordered_newton,
    _bounce_log,
    _clearances,
    _corrector_amplitudes,
    _corrector_start,
    _flights,
    _jacobian_wanted,
    _state_clearance,
    _stop_clearance,
    sticky_frequency_column,
    sticky_system,
)

__all__ = ["chatter_checks", "sticky_palc_correct"]

#: A held system's dynamic stiffness is singular (an undamped resonance) where the condition
#: number of its equilibrated form reaches ``1 / eps`` (``first_order._check_resonance``).
_EPS = float(np.finfo(np.float64).eps)


@_jit
def sticky_palc_correct(flow, errors, impacts, held, held_forcing, N, step, settings):
    """The pseudo-arclength corrector of a branch in omega of a motion with sticking phases
    (modal flow), compiled: :func:`palc_correct` on :func:`sticky_system`.

    `flow`, `errors`, `impacts`, `N`, `step` and `settings` as :func:`palc_correct` takes
    them (the full system: no embedding), `held` the plain tuple of
    :class:`~impactcont.kernel.arrays.HeldSegments` at any omega (its forced amplitudes
    ``Z`` are replaced) and `held_forcing` that of
    :class:`~impactcont.kernel.arrays.HeldForcing`. Compiled only where a motion with
    sticking phases is continued in omega (no other entry point calls it).

    At each iterate's omega: the flights' amplitudes of eq. (7)
    (:func:`~impactcont.kernel.shooting.forced_amplitudes`), each held system's ``Z_r`` and
    ``dZ_r/d omega`` (:func:`impactcont.kernel.general.forced_response` and
    :func:`~impactcont.kernel.general.forced_response_derivative`, what
    :meth:`impactcont.orbit.flow.GeneralFlow.omega_arrays` computes), the residual and exact
    Jacobian (:func:`sticky_system`) and ``dr/d omega`` (:func:`sticky_frequency_column`,
    exact; with a sticking phase entered through complete chatter the chatter map's omega
    comes with the residual, :func:`sticky_system`'s ``frequency``); then the bordered
    Newton step, its tests and the tangent of :func:`palc_correct`.

    Returns
    -------
    result : PalcResult
        As :func:`palc_correct`; :data:`REFUSED` also where a held system is at an undamped
        resonance (its dynamic stiffness singular: the caller's held flow says so in its
        words).
    shot : tuple
        The fields of :class:`~impactcont.kernel.arrays.StickyFlights` of the last iterate
        (:func:`sticky_system` with its Jacobian: at a converged step, the converged point's
        shot, what its motion is made from), empty arrays where none was shot.
    """
    modal = ShootingFlow(*flow)
    named = HeldSegments(*held)
    hf = HeldForcing(*held_forcing)
    predicted, tangent, weights = CorrectorStep(*step)
    max_iter = CorrectorSettings(*settings).max_iter
    w, a, f = modal.w, modal.a, modal.f
    flight = (modal.general, modal.w, modal.a, modal.f, modal.u, modal.ui, modal.g,
              modal.free, modal.lam, modal.V, modal.Vi, modal.xs, modal.xd)
    sticks = named.sticks
    p = sticks.size
    chatter = False  # a sticking phase entered through complete chatter
    for k in range(p):
        if sticks[k] and named.restitutions[k] > 0.0:
            chatter = True
    r = named.Z.shape[1]
    m = ImpactSequence(*impacts).matrices.shape[1]
    size = predicted.size - 1
    empty_c = np.zeros(0, dtype=np.complex128)
    state, border, raw, last_update, worst, worst_omega, flagged, norm = _corrector_start(
        predicted, tangent, weights)
    omega = state[size]
    shot = _no_shot()
    for it in range(max_iter + 1):
        ok, omega, gam, bet, dgam, dbet, worst, worst_omega = _corrector_amplitudes(
            w, a, f, errors, state, worst, worst_omega)
        if not ok:
            return PalcResult(state, it, REFUSED, omega, norm, raw, worst, worst_omega, flagged,
                              last_update), shot
        Z = np.zeros((p, r), dtype=np.complex128)
        dZ = np.zeros((p, r), dtype=np.complex128)
        if not _held_response(hf, sticks, omega, Z, dZ):
            return PalcResult(state, it, REFUSED, omega, norm, raw, worst, worst_omega,
                              flagged, last_update), shot
        now = (named.sticks, named.lifts, named.inverses, named.offsets, named.lam, named.V,
               named.Vi, named.xs, named.xd, Z, named.grads, named.forces, named.levels,
               named.shifts, named.restitutions, named.chatter_impacts)
        forcing = (omega, gam, bet, empty_c)
        period = 2.0 * math.pi * N / omega
        x = state[:size].copy()
        # the chatter map's omega comes with the residual (sticky_system's frequency)
        d_release = np.zeros((p, m) if chatter else (0, 0))
        sh = sticky_system(flight, forcing, impacts, now, period, x, _jacobian_wanted(x),
                           (dgam, dbet, empty_c, dZ, d_release))
        shot = sh
        col = sticky_frequency_column(flow, forcing, (dgam, dbet, empty_c), impacts, now, dZ,
                                      period, sh, d_release)
        named_shot = StickyFlights(*sh)
        residual = named_shot.residual
        J = named_shot.jacobian
        A = np.empty((size + 1, size + 1))  # [J | dF/domega] (the border: _bordered_newton)
        for row in range(size):
            for k in range(size):
                A[row, k] = J[row, k]
            A[row, size] = col[row]
        status, done, norm, column, last_update, flagged = _bordered_newton(
            A, residual, border, state, predicted, it, settings, last_update, flagged)
        if status != GOING:
            return PalcResult(state, done, status, omega, norm, column, worst, worst_omega,
                              flagged, last_update), shot
    return PalcResult(state, max_iter, FAILED, omega, norm, raw, worst, worst_omega, flagged,
                      last_update), shot


@_inner
def _no_shot():
    """The fields of :class:`~impactcont.kernel.arrays.StickyFlights` as empty arrays (of
    :func:`sticky_system`'s types): :func:`sticky_palc_correct`'s shot before any."""
    one = np.zeros(0)
    two = np.zeros((0, 0))
    three = np.zeros((0, 0, 0))
    return (one, one, one, two, two, one, three, two, two, two, two, three, two, one, two, one,
            two, one, two, one, one, one)


@_inner
def _held_response(hf, sticks, omega, Z, dZ):
    """Each held system's forced amplitude ``Z_r`` at `omega` into ``Z[k]`` (every impact k
    followed by a sticking phase, `sticks`) and, where `dZ` has rows, ``dZ_r/d omega`` into
    ``dZ[k]`` (:func:`impactcont.kernel.general.forced_response` and
    :func:`~impactcont.kernel.general.forced_response_derivative`; `hf` the
    :class:`~impactcont.kernel.arrays.HeldForcing`). False at an undamped resonance of a
    held system (the condition number of its dynamic stiffness reaches ``1 / eps``)."""
    r = Z.shape[1]
    for k in range(sticks.size):
        if sticks[k] and r > 0:
            Zk, cond = forced_response(hf.K[k], hf.M[k], hf.C[k], hf.F[k], omega)
            if not (cond < np.inf and cond * _EPS < 1.0):
                return False
            Z[k] = Zk
            if dZ.shape[0] > 0:
                dZ[k] = forced_response_derivative(hf.K[k], hf.M[k], hf.C[k], Zk, omega)
    return True


@_jit
def chatter_checks(flow, forcing, impacts, held, stops, k, own, X0, theta0, checks):
    """The bounces of the chatter after the landing impact k and, with `checks`, every
    stop's smallest clearance along them (but the chatter's own stop, `own`: 0 U, 1 L,
    ``2 + i`` extra stop i), in one compiled call.

    The bounces are those the shooting path resolves (:func:`impactcont.kernel.shooting.
    _bounces` from ``X0`` at `theta0`, as :func:`impactcont.kernel.shooting.chatter_bounces`
    replays them: bitwise the same); each bounce is checked as
    :func:`~impactcont.kernel.shooting.motion_checks` checks a flight (the contact search
    of eq. (16) at the interior extrema of every stop coordinate, a gap ``+inf`` where none)
    and at both ends as :func:`~impactcont.kernel.shooting.end_clearances` (its nearest
    other stop, crossed below the rounding of its evaluation). Each stop's entries, the
    interior extrema bounce by bounce then the ends (bounce by bounce, start first), are
    reduced to the first smallest (with a NaN among them, the last entry not above the one
    before: what ``orbit.sticky._HeldGap`` reports), at its time from the landing (the
    bounces' durations summed in order).

    Parameters
    ----------
    flow : tuple
        :class:`~impactcont.kernel.arrays.ShootingFlow` (its flight fields replay the
        bounces, the rest searches them).
    forcing, impacts, held
        As :func:`~impactcont.kernel.shooting.sticky_system` takes them.
    stops : tuple
        :class:`~impactcont.kernel.arrays.ContactStops`.
    k, own : int
    X0 : ndarray, shape (2n,)
        The state right after the landing impact k.
    theta0 : float
    checks : bool
        Search the bounces (else the gaps are ``+inf``, none present).

    Returns
    -------
    tuple
        ``(starts, phases, times, arrivals, transitions, phase_columns, rates)`` of
        :func:`~impactcont.kernel.shooting.chatter_bounces` (K rows), its ``count``, and per
        stop (U, L, the extra stops) the smallest clearance, its time, whether a bounce
        crosses the stop and whether the stop has an entry at all.
    """
    modal = ShootingFlow(*flow)
    clock = Forcing(*forcing)
    sequence = ImpactSequence(*impacts)
    named = HeldSegments(*held)
    contact = ContactStops(*stops)
    log, count = _bounce_log(_flights(modal), clock, sequence, named, k, X0, theta0)
    starts, phases, times, arrivals, transitions, pcols, rates = log
    q = contact.extra_signs.size
    gap = np.full(q + 2, np.inf)
    when = np.full(q + 2, np.nan)
    crossed = np.zeros(q + 2, dtype=np.bool_)
    present = np.zeros(q + 2, dtype=np.bool_)
    c = max(count, 0)
    if not checks or c == 0:
        return starts, phases, times, arrivals, transitions, pcols, rates, count, gap, when, \
            crossed, present
    offsets = np.zeros(c)
    for i in range(1, c):
        offsets[i] = offsets[i - 1] + times[i - 1]
    # every entry (stop, gap, time, crossed) in the order the reduction meets them
    inner_gap = np.full((c, q + 2), np.inf)
    inner_time = np.full((c, q + 2), np.nan)
    for i in range(c):
        if not times[i] > 0.0:
            continue
        for j in range(q):
            g, t, _ = _stop_clearance(modal, clock, contact, j, starts[i], phases[i], times[i])
            inner_gap[i, 2 + j] = g
            inner_time[i, 2 + j] = t
        gu, tu, gl, tl, _ = _clearances(modal, clock, contact, starts[i], phases[i], times[i])
        inner_gap[i, 0] = gu
        inner_time[i, 0] = tu
        inner_gap[i, 1] = gl
        inner_time[i, 1] = tl
    end_gap = np.full((c, 2), np.inf)
    end_stop = np.full((c, 2), -1, dtype=np.int64)
    end_tol = np.zeros((c, 2))
    own_normal, own_sign = sequence.normals[k], sequence.signs[k]
    for i in range(c):
        for j in range(2):
            g, s, t = _state_clearance(starts[i] if j == 0 else arrivals[i], own_normal,
                                       own_sign, contact.normal, contact.two_sided, contact.b,
                                       contact.b_low, contact.extra_normals,
                                       contact.extra_signs, contact.extra_positions)
            end_gap[i, j] = g
            end_stop[i, j] = s
            end_tol[i, j] = t
    for stop in range(q + 2):
        if stop == own or (stop == 1 and not contact.two_sided):
            continue
        entries = 0
        nan = False
        for i in range(c):
            g = inner_gap[i, stop]
            if g != np.inf:
                entries += 1
                nan = nan or g != g
        for i in range(c):
            for j in range(2):
                if end_stop[i, j] == stop:
                    entries += 1
                    nan = nan or end_gap[i, j] != end_gap[i, j]
        if entries == 0:
            continue
        present[stop] = True
        low = np.inf
        at = np.nan
        first = True
        for i in range(c):
            g = inner_gap[i, stop]
            if g == np.inf:
                continue
            crossed[stop] = crossed[stop] or not g > 0.0
            if (nan and not g >= low) or (not nan and (first or g < low)):
                low = g
                at = offsets[i] + inner_time[i, stop]
            first = False
        for i in range(c):
            for j in range(2):
                if end_stop[i, j] != stop:
                    continue
                g = end_gap[i, j]
                crossed[stop] = crossed[stop] or g < -end_tol[i, j]
                if (nan and not g >= low) or (not nan and (first or g < low)):
                    low = g
                    at = offsets[i] + j * times[i]
                first = False
        gap[stop] = low
        when[stop] = at
    return starts, phases, times, arrivals, transitions, pcols, rates, count, gap, when, \
        crossed, present

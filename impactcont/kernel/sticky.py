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
(:func:`impactcont.orbit.sticky.sticky_palc_step`).
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.arrays import (
    CorrectorSettings,
    CorrectorStep,
    HeldForcing,
    HeldSegments,
    ImpactSequence,
    PalcResult,
    ShootingFlow,
)
from impactcont.kernel.general import forced_response, forced_response_derivative
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.shooting import (
    FAILED,
    GOING,
    REFUSED,
    _bordered_newton,
    _jacobian_wanted,
    forced_amplitudes,
    sticky_frequency_column,
    sticky_system,
)

__all__ = ["sticky_palc_correct"]

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

    At each iterate's omega: the flights' amplitudes of eq. (7) (:func:`forced_amplitudes`),
    each held system's ``Z_r`` and ``dZ_r/d omega``
    (:func:`impactcont.kernel.general.forced_response` and
    :func:`~impactcont.kernel.general.forced_response_derivative`, what
    :meth:`impactcont.orbit.flow.GeneralFlow.omega_arrays` computes), the residual and exact
    Jacobian (:func:`sticky_system`) and ``dr/d omega`` (:func:`sticky_frequency_column`,
    exact; with a sticking phase entered through complete chatter the chatter map's omega
    comes with the residual, :func:`sticky_system`'s ``frequency``); then the bordered
    Newton step, its tests and the tangent of :func:`palc_correct`.

    Returns
    -------
    PalcResult
        As :func:`palc_correct`; :data:`REFUSED` also where a held system is at an undamped
        resonance (its dynamic stiffness singular: the caller's held flow says so in its
        words).
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
    state = predicted.copy()
    last_update = np.inf
    worst = 0.0
    worst_omega = np.nan
    flagged = np.zeros((0, 0))
    border = weights * tangent
    raw = np.zeros(size + 1)
    omega = state[size]
    norm = np.nan
    for it in range(max_iter + 1):
        omega = state[size]
        if not (omega > 0.0 and omega < np.inf):
            return PalcResult(state, it, REFUSED, omega, norm, raw, worst, worst_omega, flagged,
                              last_update)
        gam, bet, dgam, dbet, bound, resonant = forced_amplitudes(w, a, f, errors, omega)
        if resonant:
            return PalcResult(state, it, REFUSED, omega, norm, raw, worst, worst_omega, flagged,
                              last_update)
        if bound > worst or bound != bound:
            worst = bound
            worst_omega = omega
        Z = np.zeros((p, r), dtype=np.complex128)
        dZ = np.zeros((p, r), dtype=np.complex128)
        if not _held_response(hf, sticks, omega, Z, dZ):
            return PalcResult(state, it, REFUSED, omega, norm, raw, worst, worst_omega,
                              flagged, last_update)
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
        col = sticky_frequency_column(flow, forcing, (dgam, dbet, empty_c), impacts, now, dZ,
                                      period, sh, d_release)
        residual = sh[13]
        J = sh[14]
        A = np.empty((size + 1, size + 1))  # [J | dF/domega] and the border
        for row in range(size):
            for k in range(size):
                A[row, k] = J[row, k]
            A[row, size] = col[row]
        for k in range(size + 1):
            A[size, k] = border[k]
        status, done, norm, column, last_update, flagged = _bordered_newton(
            A, residual, border, state, predicted, it, settings, last_update, flagged)
        if status != GOING:
            return PalcResult(state, done, status, omega, norm, column, worst, worst_omega,
                              flagged, last_update)
    return PalcResult(state, max_iter, FAILED, omega, norm, raw, worst, worst_omega, flagged,
                      last_update)


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

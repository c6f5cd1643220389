"""Periodic N-1 motions over many parameter values at once.

:func:`batched_orbits`: every root of eq. (15) on an ``omega x b`` grid with its
physical checks and stability, by the compiled kernel
(:mod:`impactcont.kernel.closed_form`); ``b`` enters only eq. (14)-(15), so the
per-frequency work (eq. 12-13 in modal form, the time grid of the interior-contact
check) is shared by every gap and root.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import require_paper_stops
from impactcont.orbit.dense import COND_WARN, VELOCITY_POLISH, polished_velocity, velocity_bound
from impactcont.orbit.periodic import (
    IllConditionedWarning,
    _kernel_tuple,
    modal_arrays,
    modal_jacobian,
)

__all__ = ["batched_orbits"]

_EPS = float(np.finfo(float).eps)


def _warn_grid(omega: np.ndarray, cond: np.ndarray) -> None:
    """One warning for the frequencies of a map where eq. (12) is ill-conditioned."""
    bad = ~(cond <= COND_WARN)
    if np.any(bad):
        warnings.warn(f"eq. (12) is ill-conditioned at omega = {omega[bad][:5].tolist()} "
                      f"(condition estimates {cond[bad][:5].tolist()}); the periodic motions "
                      "there may be inexact", IllConditionedWarning, stacklevel=3)


def batched_orbits(osc: ImpactOscillator, N: int, omega: np.ndarray, b: np.ndarray, *,
                   spectral_radius: bool = True) -> dict[str, np.ndarray]:
    """Every root of eq. (15) on the grid ``omega x b`` with its checks and stability.

    Evaluated by the compiled kernel (:func:`impactcont.kernel.closed_form.block_map`):
    per omega O(n) for eq. (12)-(15) and one time grid for the interior-contact
    check of eq. (16) shared by every gap and root; per motion G (eq. 25) and the
    Schur-Cohn test of its characteristic polynomial, plus LAPACK eigenvalues
    when `spectral_radius` is asked for.

    Parameters
    ----------
    osc : ImpactOscillator
        Its own ``omega`` and ``b`` are ignored.
    N : int
        One impact every N forcing periods.
    omega : ndarray, shape (nw,)
    b : ndarray, shape (nb,)
    spectral_radius : bool
        Also compute ``spectral_radius`` and ``critical_multiplier`` (NaN otherwise).

    Returns
    -------
    dict of str to ndarray
        ``amplitude_squared`` ``c^2 + s^2`` (nw,); ``exists`` (nw, nb) bool; and,
        with shape (nw, nb, 2) for the roots ``+1, -1`` of eq. (15) (NaN where the
        motion does not exist): ``delta``, ``impact_velocity`` (h2 of eq. 22),
        ``gap_min`` (eq. 16, ``+inf`` with no interior maximum), ``gap_min_time``,
        ``spectral_radius`` (rho(G)) and ``critical_multiplier`` (complex, the
        multiplier of largest modulus); ``physical`` and ``stable`` (bool, False
        where the motion does not exist; ``stable``: every multiplier strictly inside
        the unit circle).
    """
    from impactcont.kernel import closed_form

    omega = np.ascontiguousarray(np.atleast_1d(np.asarray(omega, dtype=float)))
    b = np.ascontiguousarray(np.atleast_1d(np.asarray(b, dtype=float)))
    require_paper_stops(osc, "the N-1 stability map")  # stops: mass 1, one stop only
    if osc.general:
        return _general_block(osc, int(N), omega, b, bool(spectral_radius))
    (r2, cond, count, delta, vel, gap, gap_t, stable, rho,
     crit) = closed_form.block_map(_kernel_tuple(osc), osc.R, int(N), omega, b,
                                   bool(spectral_radius))
    _warn_grid(omega, cond)
    _polish_modal_block(osc, int(N), omega, b, count, delta, vel, gap, gap_t, stable, rho,
                        crit, bool(spectral_radius))
    exists = count > 0
    return {"amplitude_squared": r2, "exists": exists, "delta": delta,
            "impact_velocity": vel, "gap_min": gap, "gap_min_time": gap_t,
            "spectral_radius": rho, "critical_multiplier": crit,
            "physical": exists[..., None] & (vel > 0) & (gap > 0), "stable": stable}


def _polish_modal_block(osc: ImpactOscillator, N: int, omega: np.ndarray, b: np.ndarray,
                        count: np.ndarray, delta: np.ndarray, vel: np.ndarray, gap: np.ndarray,
                        gap_t: np.ndarray, stable: np.ndarray, rho: np.ndarray,
                        crit: np.ndarray, spectral_radius: bool) -> None:
    """Re-evaluate, in place, the motions of the kernel's map whose impact velocity lost
    digits (:func:`impactcont.orbit.dense.impact_velocity`: far above the lowest natural
    frequency the kernel's form cancels), with the velocity's second exact form: gap
    (eq. 16), G (eq. 25), its multipliers and stability. A bound per frequency keeps the
    check off the grid points that need none."""
    from impactcont.kernel import closed_form, contact, stability

    arrays = modal_arrays(osc)
    R = osc.R
    setups = [closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                      arrays.eig_err, R, float(om), N) for om in omega]
    sc = np.array([s for _, s in setups])  # (nw, 10): T, Gam, B, g, Delta, c, s, ...
    # an upper bound of the rounding error of x1p'(delta) / Delta at any phase (0 where
    # the kernel takes elastic undamped velocities from the impact condition)
    bound = velocity_bound(sc[:, 1], sc[:, 2], sc[:, 4], omega) * (sc[:, 9] == 0.0)
    with np.errstate(invalid="ignore"):  # NaN where no motion
        flagged = np.argwhere(bound[:, None, None] > VELOCITY_POLISH * np.abs(vel))
    for iw, ib, k in flagged.tolist():
        if k >= count[iw, ib]:  # the copy of a double root
            continue
        om, bb = omega.item(iw), b.item(ib)
        modal, scalars = setups[iw]
        Gam, B, g, Delta = scalars[1:5].tolist()
        d, sg = delta.item(iw, ib, k), vel.item(iw, ib, k)
        better, _ = polished_velocity(Gam, B, g, Delta, om, R, bb, d, sg)
        if better is None:
            continue
        best, best_t = contact.other_maximum(arrays.w, arrays.a, arrays.u0, modal, scalars, om,
                                             R, d, better, math.nan)
        G, _ = modal_jacobian(osc, modal, d, better, omega=om)
        mu = stability.multipliers(G)
        ks = slice(k, 2) if count[iw, ib] == 1 else slice(k, k + 1)  # a double root: both
        vel[iw, ib, ks] = better
        gap[iw, ib, ks], gap_t[iw, ib, ks] = bb - best, best_t
        stable[iw, ib, ks] = bool(np.all(np.abs(mu) < 1.0))
        if spectral_radius:
            j = int(np.argmax(np.abs(mu)))
            rho[iw, ib, ks], crit[iw, ib, ks] = abs(mu[j]), mu[j]


def _general_block(osc: ImpactOscillator, N: int, omega: np.ndarray, b: np.ndarray,
                   spectral_radius: bool) -> dict[str, np.ndarray]:
    """:func:`batched_orbits` on the first-order path (general damping matrix or complex F):
    per omega eq. (12)-(14) once (:func:`impactcont.orbit.general.periodic_form`), per gap
    the roots of eq. (15); their G, multipliers and eq. (16) for all gaps at once
    (:func:`impactcont.orbit.general.orbit_values_many`). An omega at the natural
    frequency of an undamped mode (no forced response, eq. 6) leaves its column empty,
    with a :class:`~impactcont.errors.NearResonanceWarning`; the ill-conditioned
    frequencies are named in one warning, as on the modal path."""
    from impactcont.errors import NearResonanceWarning, ResonanceError
    from impactcont.orbit import general

    nw, nb = omega.size, b.size
    r2 = np.full(nw, np.nan)
    cond = np.ones(nw)
    count = np.zeros((nw, nb), dtype=np.int64)
    shape = (nw, nb, 2)
    delta, vel, gap, gap_t, rho = (np.full(shape, np.nan) for _ in range(5))
    crit = np.full(shape, np.nan + 0j)
    stable = np.zeros(shape, dtype=bool)
    for i, w in enumerate(omega):
        at = osc.replace(omega=float(w))
        try:
            form = general.periodic_form(at, N, warn=False)
        except ResonanceError as exc:  # no forced response at this omega: an empty column
            warnings.warn(f"stability map: no motion at omega={float(w)!r} (column left "
                          f"empty): {exc}", NearResonanceWarning, stacklevel=3)
            continue
        c, s = form.c, form.s
        r2[i], cond[i] = c * c + s * s, form.cond
        where, phases = [], []
        for j, bj in enumerate(b):
            roots = general.roots(c, s, float(bj))
            count[i, j] = len(roots)
            for k, (d, _) in enumerate(roots):
                where.append((j, k))
                phases.append(d)
        if not phases:
            continue
        jj, kk = np.array(where).T
        h2, mu, g, g_t = general.orbit_values_many(form, np.array(phases), b[jj])
        delta[i, jj, kk], vel[i, jj, kk] = phases, h2
        gap[i, jj, kk], gap_t[i, jj, kk] = g, g_t
        stable[i, jj, kk] = np.all(np.abs(mu) < 1.0, axis=1)
        if spectral_radius:
            rho[i, jj, kk], crit[i, jj, kk] = np.abs(mu[:, 0]), mu[:, 0]
    _warn_grid(omega, cond)
    exists = count > 0
    return {"amplitude_squared": r2, "exists": exists, "delta": delta,
            "impact_velocity": vel, "gap_min": gap, "gap_min_time": gap_t,
            "spectral_radius": rho, "critical_multiplier": crit,
            "physical": exists[..., None] & (vel > 0) & (gap > 0), "stable": stable}

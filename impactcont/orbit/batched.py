"""Periodic N-1 motions over many parameter values at once.

:func:`batched_orbits`: every root of eq. (15) on an ``omega x b`` grid with its
physical checks and stability, by the compiled kernel
(:mod:`impactcont.orbit.kernel`); ``b`` enters only eq. (14)-(15), so the
per-frequency work (eq. 12-13 in modal form, the time grid of the interior-contact
check) is shared by every gap and root.
"""

from __future__ import annotations

import warnings

import numpy as np

from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import require_paper_stops
from impactcont.orbit.periodic import IllConditionedWarning

__all__ = ["batched_orbits"]

_COND_WARN = 1e10


def batched_orbits(osc: ImpactOscillator, N: int, omega: np.ndarray, b: np.ndarray, *,
                   spectral_radius: bool = True) -> dict[str, np.ndarray]:
    """Every root of eq. (15) on the grid ``omega x b`` with its checks and stability.

    Evaluated by the compiled kernel (:func:`impactcont.orbit.kernel.block_map`):
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
    from impactcont.orbit import kernel

    omega = np.ascontiguousarray(np.atleast_1d(np.asarray(omega, dtype=float)))
    b = np.ascontiguousarray(np.atleast_1d(np.asarray(b, dtype=float)))
    require_paper_stops(osc, "the N-1 stability map")  # stops: mass 1, one stop only
    if osc.general:
        return _general_block(osc, int(N), omega, b, bool(spectral_radius))
    w, a, f, u, ui, eig_err, _, _ = osc.modes.kernel_arrays
    (r2, cond, count, delta, vel, gap, gap_t, stable, rho,
     crit) = kernel.block_map(w, a, f, u, ui, eig_err, osc.R, int(N), omega, b,
                              bool(spectral_radius))
    bad = ~(cond <= _COND_WARN)
    if np.any(bad):
        warnings.warn(f"eq. (12) is ill-conditioned at omega = {omega[bad][:5].tolist()} "
                      f"(condition estimates {cond[bad][:5].tolist()}); the periodic motions "
                      "there may be inexact", IllConditionedWarning, stacklevel=2)
    exists = count > 0
    return {"amplitude_squared": r2, "exists": exists, "delta": delta,
            "impact_velocity": vel, "gap_min": gap, "gap_min_time": gap_t,
            "spectral_radius": rho, "critical_multiplier": crit,
            "physical": exists[..., None] & (vel > 0) & (gap > 0), "stable": stable}


def _general_block(osc: ImpactOscillator, N: int, omega: np.ndarray, b: np.ndarray,
                   spectral_radius: bool) -> dict[str, np.ndarray]:
    """:func:`batched_orbits` on the first-order path (general damping matrix or complex F):
    per omega the dense eq. (12)-(13) once (:func:`impactcont.orbit.general.orbit_pieces`),
    per gap the roots of eq. (15); their G, multipliers and eq. (16) for all gaps at once
    (:func:`impactcont.orbit.general.orbit_values_many`). An omega at the natural
    frequency of an undamped mode (no forced response, eq. 6) leaves its column empty,
    with a :class:`~impactcont.errors.NearResonanceWarning`."""
    from impactcont.errors import NearResonanceWarning, ResonanceError
    from impactcont.orbit import general

    nw, nb = omega.size, b.size
    r2 = np.full(nw, np.nan)
    count = np.zeros((nw, nb), dtype=np.int64)
    shape = (nw, nb, 2)
    delta, vel, gap, gap_t, rho = (np.full(shape, np.nan) for _ in range(5))
    crit = np.full(shape, np.nan + 0j)
    stable = np.zeros(shape, dtype=bool)
    for i, w in enumerate(omega):
        at = osc.replace(omega=float(w))
        try:
            flow, S, DPhi, T = general.orbit_pieces(at, N)
        except ResonanceError as exc:  # no forced response at this omega: an empty column
            warnings.warn(f"stability map: no motion at omega={float(w)!r} (column left "
                          f"empty): {exc}", NearResonanceWarning, stacklevel=3)
            continue
        c, s = float(S[0, 0]), float(S[0, 1])
        r2[i] = c * c + s * s
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
        h2, mu, g, g_t = general.orbit_values_many(flow, S, DPhi, T, np.array(phases), b[jj])
        delta[i, jj, kk], vel[i, jj, kk] = phases, h2
        gap[i, jj, kk], gap_t[i, jj, kk] = g, g_t
        stable[i, jj, kk] = np.all(np.abs(mu) < 1.0, axis=1)
        if spectral_radius:
            rho[i, jj, kk], crit[i, jj, kk] = np.abs(mu[:, 0]), mu[:, 0]
    exists = count > 0
    return {"amplitude_squared": r2, "exists": exists, "delta": delta,
            "impact_velocity": vel, "gap_min": gap, "gap_min_time": gap_t,
            "spectral_radius": rho, "critical_multiplier": crit,
            "physical": exists[..., None] & (vel > 0) & (gap > 0), "stable": stable}

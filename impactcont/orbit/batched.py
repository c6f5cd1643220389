"""Periodic N-1 motions over many parameter values at once.

- :func:`batched_orbits`: every root of eq. (15) on an ``omega x b`` grid with its
  physical checks and stability, by the compiled kernel
  (:mod:`impactcont.orbit.kernel`); ``b`` enters only eq. (14)-(15), so the
  per-frequency work (eq. 12-13 in modal form, the time grid of the
  interior-contact check) is shared by every gap and root.
- :func:`batched_matrices`: the dense matrices of eq. (9) and ``S`` of eq. (13)
  for many frequencies (stacked numpy), used where a problem needs them whole
  (the augmented systems of the codim-1 curves).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from impactcont.model.modal import forced_coefficients, free_transfer
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.periodic import IllConditionedWarning

__all__ = ["batched_matrices", "batched_orbits"]

_COND_WARN = 1e10


def batched_matrices(osc: ImpactOscillator, N: int, omega: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``S`` of eq. (13) and the flow matrices of eq. (9) at ``T = 2 pi N / omega``.

    Parameters
    ----------
    osc : ImpactOscillator
        Its ``omega`` and ``b`` are ignored.
    N : int
        Forcing periods per impact.
    omega : ndarray, shape (nw,)
        Forcing frequencies, ``> 0``.

    Returns
    -------
    S : ndarray, shape (nw, 2n, 2)
        ``X(0) = S [cos delta; sin delta]`` (eq. 13).
    transition : ndarray, shape (nw, 2n, 2n)
        ``U W(T) U^-1``.
    forcing : ndarray, shape (nw, 2n, 2)
        ``U E(T)``.
    T : ndarray, shape (nw,)
    """
    modes = osc.modes
    n = osc.n
    omega = np.asarray(omega, dtype=float)
    T = 2.0 * math.pi * N / omega
    W11, W12, W21, W22 = free_transfer(modes.natural_frequencies, modes.decay_rates, T)
    u, ui = modes.u, modes.u_inv
    transition = np.empty((omega.size, 2 * n, 2 * n))
    for rows, (A, B) in ((slice(0, n), (W11, W12)), (slice(n, 2 * n), (W21, W22))):
        transition[:, rows, :n] = np.einsum("ij,wj,jk->wik", u, A, ui)
        transition[:, rows, n:] = np.einsum("ij,wj,jk->wik", u, B, ui)
    g, bt = forced_coefficients(modes.natural_frequencies, modes.decay_rates,
                                modes.modal_forces, omega[:, None])
    om = omega[:, None]
    # omega T = 2 pi N: the forced columns at T equal those at 0, P(T) = P(0)
    phi, psi = g, bt
    dphi, dpsi = om * bt, -om * g
    e_y_cos = phi - W11 * g - W12 * om * bt
    e_y_sin = psi - W11 * bt + W12 * om * g
    e_v_cos = dphi - W21 * g - W22 * om * bt
    e_v_sin = dpsi - W21 * bt + W22 * om * g
    forcing = np.empty((omega.size, 2 * n, 2))
    forcing[:, :n, 0] = e_y_cos @ u.T
    forcing[:, :n, 1] = e_y_sin @ u.T
    forcing[:, n:, 0] = e_v_cos @ u.T
    forcing[:, n:, 1] = e_v_sin @ u.T
    d = np.ones(2 * n)
    d[n] = -osc.R
    A = np.eye(2 * n) - d[:, None] * transition
    cond = np.linalg.cond(A)
    bad = ~np.isfinite(cond) | (cond > _COND_WARN)
    if np.any(bad):
        warnings.warn(f"I - D U W(T) U^-1 of eq. (12) is ill-conditioned at omega = "
                      f"{omega[bad][:5].tolist()} (condition numbers {cond[bad][:5].tolist()}); "
                      "the periodic motions there may be inexact", IllConditionedWarning,
                      stacklevel=2)
    S = np.linalg.solve(A, d[:, None] * forcing)
    return S, transition, forcing, T


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

"""Periodic N-1 motions, their physical checks and stability, batched over parameter values.

The same closed form as :mod:`impactcont.orbit.periodic` (eq. 12-16, 22-25),
evaluated for many values of ``omega`` and ``b`` at once with stacked numpy
arrays instead of one Python call per motion. The modal basis (M, K, C, F)
and ``R`` are fixed; ``omega`` enters ``S`` (eq. 13) and the flow, ``b`` only
eq. (14)-(15), so ``S`` is computed once per ``omega`` and reused for every gap.

Interior maxima of ``x1`` (eq. 16) are found as in :mod:`impactcont.orbit.extrema`:
a grid of at least 16 cells per shortest damped period, each cell split at its
root of ``x1''`` so that ``x1'`` is monotone on every piece, and every root of
``x1'`` polished by safeguarded Newton, all orbits and all brackets at once.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from impactcont.model.modal import forced_coefficients, free_transfer
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.extrema import bracketed_roots
from impactcont.orbit.periodic import IllConditionedWarning

__all__ = ["OrbitBatch", "batched_matrices", "batched_orbits"]

_CELLS_PER_PERIOD = 16
_COND_WARN = 1e12


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


class OrbitBatch:
    """``x1`` and its time derivatives along many flights at once.

    Parameters
    ----------
    osc : ImpactOscillator
    omega : ndarray, shape (k,)
        Forcing frequency of each flight.
    delta : ndarray, shape (k,)
        Forcing phase at the start of each flight.
    state : ndarray, shape (k, 2n)
        State at the start of each flight.
    """

    def __init__(self, osc: ImpactOscillator, omega: np.ndarray, delta: np.ndarray,
                 state: np.ndarray) -> None:
        modes = osc.modes
        n = osc.n
        self.w = modes.natural_frequencies
        self.a = modes.decay_rates
        self.f = modes.modal_forces
        self.u0 = modes.u[0]
        self.omega = np.asarray(omega, dtype=float)
        self.delta = np.asarray(delta, dtype=float)
        self.gamma, self.beta = forced_coefficients(self.w, self.a, self.f, self.omega[:, None])
        y0 = state[:, :n] @ modes.u_inv.T
        v0 = state[:, n:] @ modes.u_inv.T
        cd, sd = np.cos(self.delta)[:, None], np.sin(self.delta)[:, None]
        self.dy = y0 - (self.gamma * cd + self.beta * sd)
        self.dv = v0 - self.omega[:, None] * (self.beta * cd - self.gamma * sd)

    def on_grid(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``x1'`` and ``x1''`` of every flight at its row of ``times``, shape (k, nt).

        Flights with the same ``omega`` must be consecutive and share their row of
        times: the modal transfer and the forcing are then evaluated once per run of
        equal ``omega`` and combined with each flight's coefficients by one matrix
        product (no transcendental function per flight and time).
        """
        w, a, f, u0 = self.w, self.a, self.f, self.u0
        om = self.omega[:, None]
        cd, sd = np.cos(self.delta)[:, None], np.sin(self.delta)[:, None]
        A = self.gamma * cd + self.beta * sd  # y_p = A cos(omega t) + B sin(omega t)
        B = self.beta * cd - self.gamma * sd
        uy, uv = u0 * self.dy, u0 * self.dv
        zero = np.zeros_like(uy)
        # basis [cos, sin, W11, W12, W21, W22]; rows: x1', x1''
        coef_v = np.hstack([om * (B @ u0)[:, None], -om * (A @ u0)[:, None], zero, zero, uy, uv])
        coef_a = np.hstack([((f * cd - 2.0 * a * om * B - w**2 * A) @ u0)[:, None],
                            ((-f * sd + 2.0 * a * om * A - w**2 * B) @ u0)[:, None],
                            -(w**2) * uy, -(w**2) * uv, -2.0 * a * uy, -2.0 * a * uv])
        coef = np.stack([coef_v, coef_a], axis=1)  # (k, 2, 2 + 4n)
        out = np.empty((2, *times.shape))
        starts = np.flatnonzero(np.r_[True, self.omega[1:] != self.omega[:-1]])
        ends = np.r_[starts[1:], self.omega.size]
        for lo, hi in zip(starts, ends, strict=True):
            t = times[lo]
            wt = self.omega[lo] * t
            blocks = free_transfer(w, a, t)
            basis = np.vstack([np.cos(wt), np.sin(wt), *(blk.T for blk in blocks)])
            out[:, lo:hi] = np.einsum("kpb,bt->pkt", coef[lo:hi], basis)
        return out[0], out[1]

    def derivatives(self, index: np.ndarray, t: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``x1, x1', x1'', x1'''`` of flights ``index`` at times ``t`` (same shapes)."""
        index = np.asarray(index)
        t = np.asarray(t, dtype=float)
        shape = t.shape
        idx, tt = index.ravel(), t.ravel()
        W11, W12, W21, W22 = free_transfer(self.w, self.a, tt)
        theta = self.omega[idx] * tt + self.delta[idx]
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        g, bt, om = self.gamma[idx], self.beta[idx], self.omega[idx][:, None]
        y = g * c + bt * s + W11 * self.dy[idx] + W12 * self.dv[idx]
        v = om * (bt * c - g * s) + W21 * self.dy[idx] + W22 * self.dv[idx]
        acc = self.f * c - 2.0 * self.a * v - self.w**2 * y
        jerk = -om * self.f * s - 2.0 * self.a * acc - self.w**2 * v
        return tuple((q @ self.u0).reshape(shape) for q in (y, v, acc, jerk))


def _time_grid(osc: ImpactOscillator, omega: float, T: float) -> np.ndarray:
    """Normalised grid ``tau`` on [0, 1] (``t = tau T``) for one forcing frequency.

    Each cell is at most 1/16 of the shortest damped period seen by mass 1 (or of
    the forcing period), with a geometric refinement near 0 for fast over-damped
    decays, as :func:`impactcont.orbit.extrema.sample_times`. It depends on
    ``omega`` alone, so a map does not depend on how its grid is split into tasks.
    """
    modes = osc.modes
    part = np.abs(modes.u[0]) > 0
    w, a = modes.natural_frequencies[part], modes.decay_rates[part]
    d = (w - a) * (w + a)
    wd = float(np.sqrt(np.maximum(d, 0.0)).max(initial=0.0))
    fast = float((a + np.sqrt(np.maximum(-d, 0.0))).max(initial=0.0))
    count = max(math.ceil(T * max(omega, wd) * _CELLS_PER_PERIOD / (2.0 * math.pi)), 8)
    tau = np.linspace(0.0, 1.0, count + 1)
    if fast > 0:
        cell = 1.0 / count
        scale = 1.0 / (_CELLS_PER_PERIOD * fast * T)  # tau of one decay cell
        if scale < cell:
            k = math.ceil(math.log2(cell / scale))
            tau = np.union1d(tau, cell * np.exp2(-np.arange(1, k + 1)))
    return tau


def _time_grids(osc: ImpactOscillator, omega: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Per-omega grids of :func:`_time_grid`, padded with 1.0 (empty cells) to one width."""
    grids = [_time_grid(osc, float(w), float(t)) for w, t in zip(omega, T, strict=True)]
    width = max(g.size for g in grids)
    out = np.ones((len(grids), width))
    for i, g in enumerate(grids):
        out[i, :g.size] = g
    return out


def _highest_interior_maxima(batch: OrbitBatch, T: np.ndarray, tau: np.ndarray
                             ) -> tuple[np.ndarray, np.ndarray]:
    """Value and time of the highest interior maximum of ``x1`` on ``(0, T)`` per flight.

    ``tau`` (k, nt): each flight's normalised grid (flights of one omega share it).
    Returns ``(-inf, nan)`` for a flight without interior maximum.
    """
    k = T.size
    best = np.full(k, -np.inf)
    best_t = np.full(k, np.nan)
    if k == 0:
        return best, best_t
    times = T[:, None] * tau
    v, acc = batch.on_grid(times)
    # 1. split the cells where x1'' changes sign at its root: x1' is then monotone per piece
    o, c = np.nonzero((acc[:, :-1] < 0) != (acc[:, 1:] < 0))
    infl = bracketed_roots(lambda i, t: batch.derivatives(i, t)[2:4], times[o, c],
                           times[o, c + 1], acc[o, c], index=o)
    v_infl = batch.derivatives(o, infl)[1]
    split = np.zeros(acc[:, :-1].shape, dtype=bool)
    split[o, c] = True
    po, pc = np.nonzero(~split & ((v[:, :-1] < 0) != (v[:, 1:] < 0)))
    lo = np.concatenate([times[po, pc], times[o, c], infl])
    hi = np.concatenate([times[po, pc + 1], infl, times[o, c + 1]])
    v_lo = np.concatenate([v[po, pc], v[o, c], v_infl])
    v_hi = np.concatenate([v[po, pc + 1], v_infl, v[o, c + 1]])
    owner = np.concatenate([po, o, o])
    # 2. one root of x1' per monotone piece with a sign change
    sel = (v_lo < 0) != (v_hi < 0)
    owner, lo, hi, v_lo = owner[sel], lo[sel], hi[sel], v_lo[sel]
    crit = bracketed_roots(lambda i, t: batch.derivatives(i, t)[1:3], lo, hi, v_lo, index=owner)
    x, _, a2, _ = batch.derivatives(owner, crit)
    keep = (a2 < 0) & (crit > 0) & (crit < T[owner])
    owner, crit, x = owner[keep], crit[keep], x[keep]
    if owner.size:
        order = np.lexsort((x, owner))  # the highest maximum of each flight last
        owner, crit, x = owner[order], crit[order], x[order]
        last = np.r_[owner[1:] != owner[:-1], True]
        best[owner[last]] = x[last]
        best_t[owner[last]] = crit[last]
    return best, best_t


def batched_orbits(osc: ImpactOscillator, N: int, omega: np.ndarray, b: np.ndarray
                   ) -> dict[str, np.ndarray]:
    """Every root of eq. (15) on the grid ``omega x b`` with its checks and multipliers.

    Parameters
    ----------
    osc : ImpactOscillator
        Its own ``omega`` and ``b`` are ignored.
    N : int
        One impact every N forcing periods.
    omega : ndarray, shape (nw,)
    b : ndarray, shape (nb,)

    Returns
    -------
    dict of str to ndarray
        ``amplitude_squared`` ``c^2 + s^2`` (nw,); ``exists`` (nw, nb) bool
        (``c^2 + s^2 >= b^2``); and, with shape (nw, nb, 2) for the roots
        ``+1, -1`` of eq. (15) (NaN where the motion does not exist):
        ``delta``, ``impact_velocity`` (h2 of eq. 22), ``gap_min`` (eq. 16,
        ``+inf`` with no interior maximum), ``gap_min_time``,
        ``spectral_radius`` (rho(G), eq. 25) and ``critical_multiplier``
        (complex, the multiplier of largest modulus); ``physical`` and
        ``stable`` (bool, False where the motion does not exist).
    """
    n = osc.n
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    b = np.atleast_1d(np.asarray(b, dtype=float))
    nw, nb = omega.size, b.size
    S, transition, forcing, T = batched_matrices(osc, N, omega)
    c, s = S[:, 0, 0], S[:, 0, 1]
    r2 = c * c + s * s
    disc = r2[:, None] - b[None, :] ** 2
    exists = disc >= 0
    iw, ib = np.nonzero(exists)
    root_r = np.sqrt(disc[iw, ib])
    iw2, ib2 = np.repeat(iw, 2), np.repeat(ib, 2)
    sign = np.tile([1.0, -1.0], iw.size)
    rr = np.repeat(root_r, 2)
    cc, ss, bb, r2k = c[iw2], s[iw2], b[ib2], r2[iw2]
    delta = np.arctan2((bb * ss + sign * cc * rr) / r2k, (bb * cc - sign * ss * rr) / r2k)
    cs = np.stack([np.cos(delta), np.sin(delta)], axis=-1)
    state = np.einsum("kij,kj->ki", S[iw2], cs)
    d = np.ones(2 * n)
    d[n] = -osc.R
    # state just before the next impact and its time derivative from eq. (1)
    X_T = np.einsum("kij,kj->ki", transition[iw2], state) + np.einsum("kij,kj->ki",
                                                                      forcing[iw2], cs)
    Minv = np.linalg.inv(osc.M)
    acc = (np.outer(cs[:, 0], osc.F) - X_T[:, n:] @ osc.C.T - X_T[:, :n] @ osc.K.T) @ Minv.T
    dX = d * np.hstack([X_T[:, n:], acc])
    h2, H2 = dX[:, 0], dX[:, 1:]
    DPhi = d[:, None] * transition[iw2]
    h0_p, H0 = DPhi[:, 0, 1:], DPhi[:, 1:, 1:]
    dE = d * np.einsum("kij,kj->ki", forcing[iw2], np.stack([-cs[:, 1], cs[:, 0]], axis=-1))
    h1, H1 = dE[:, 0], dE[:, 1:]
    om = omega[iw2]
    k = iw2.size
    G = np.empty((k, 2 * n, 2 * n))
    with np.errstate(divide="ignore", invalid="ignore"):
        G[:, :-1, :-1] = H0 - H2[:, :, None] * h0_p[:, None, :] / h2[:, None, None]
        G[:, :-1, -1] = H1 - H2 * (h1 / h2)[:, None]
        G[:, -1, :-1] = -(om / h2)[:, None] * h0_p
        G[:, -1, -1] = 1.0 - om * h1 / h2
    finite = np.all(np.isfinite(G), axis=(1, 2))
    crit = np.full(k, np.nan + 0j)
    if np.any(finite):
        mu = np.linalg.eigvals(G[finite])
        crit[finite] = mu[np.arange(mu.shape[0]), np.argmax(np.abs(mu), axis=1)]
    rho = np.abs(crit)
    tau = _time_grids(osc, omega, T)
    batch = OrbitBatch(osc, om, delta, state)
    peak, peak_t = _highest_interior_maxima(batch, T[iw2], tau[iw2])
    gap = bb - peak

    out: dict[str, np.ndarray] = {"amplitude_squared": r2, "exists": exists}

    def grid(values: np.ndarray, fill: object, dtype: object) -> np.ndarray:
        a = np.full((nw, nb, 2), fill, dtype=dtype)
        a[iw2, ib2, (sign < 0).astype(int)] = values
        return a

    out["delta"] = grid(delta, np.nan, float)
    out["impact_velocity"] = grid(h2, np.nan, float)
    out["gap_min"] = grid(gap, np.nan, float)
    out["gap_min_time"] = grid(peak_t, np.nan, float)
    out["spectral_radius"] = grid(rho, np.nan, float)
    out["critical_multiplier"] = grid(crit, np.nan + 0j, complex)
    out["physical"] = grid((h2 > 0) & (gap > 0), False, bool)
    out["stable"] = grid(rho < 1.0, False, bool)
    return out

"""The N-1 motion of the paper in closed form: eq. (12)-(15) and G of eq. (22)-(25), O(n).

Everything here is a numba function over floats and arrays (no Python objects),
compiled on first use and cached on disk (``cache=True``); importing
:mod:`impactcont` does not import this module.

The modal form of eq. (12)-(16)
-------------------------------
In mass-normalised modal coordinates ``z = [y; y']`` the flow over one period
``T = 2 pi N / omega`` is block diagonal (``W_i(T)``, eq. 9) and the impact
(eq. 4) is the rank-one map ``z+ = (I - kappa p q^T) z-`` with
``kappa = 1 + R``, ``q = [0; u_1.]`` (the velocity of mass 1) and
``p = [0; (u^-1)_.1]``. Because ``omega T = 2 pi N`` the forcing block of
eq. (9) is ``E_i = (I - W_i) P_i`` with ``P_i`` the forced response (eq. 7),
and the solve of eq. (12) collapses (Sherman-Morrison) to per-mode scalars:

    x1(0)  = x1p(delta) - kappa sigma g,         g     = sum_i c_i W12_i / d_i
    sigma  = x1p'(delta) / Delta,                Delta = (1 - R)/2 + kappa sum_i c_i h_i

with ``c_i = u_1i (u^-1)_i1`` (``sum_i c_i = 1``), ``d_i = det(I - W_i)``,
``h_i = (1 - det W_i + W22_i - W11_i) / (2 d_i)`` and the forced motion of mass 1
``x1p(delta) = Gamma cos(delta) + B sin(delta)``. ``sigma`` is the impact
velocity ``x1'(T^-)`` (``h2`` of eq. 22). Eq. (14) is therefore

    c cos(delta) + s sin(delta) = b,   c = Gamma - rho B,   s = B + rho Gamma,
    rho = kappa omega g / Delta.

Every ``d_i``, ``h_i`` and ``1 - W11_i`` is written without cancellation
(``expm1``, half-angle sines, and for over-damped modes the divided difference of
``lambda coth(lambda T / 2)``), so the cost is O(n) per frequency and O(1) per
root, with no dense solve.

Elastic impacts without damping (``R = 1``, every ``a_i = 0``) give ``h_i = 0``
and ``Delta = 0`` exactly: ``I - D Phi`` of eq. (12) is singular for every
omega. The motions are still isolated: ``x1p'(delta) = 0`` fixes the phase
(``delta = atan2(B, Gamma)`` or that plus pi) and the impact condition fixes
``sigma = (x1p(delta) - b) / (kappa g)``; for one mass this is the classical
``V = -(b -+ gamma)(1 - cos T)/sin T``.

The pieces this module assembles live beside it: the flights (eq. 7, 9) in
:mod:`impactcont.kernel.flights`, the roots of eq. (15) in
:mod:`impactcont.kernel.roots`, the interior-contact check of eq. (16) in
:mod:`impactcont.kernel.contact`, and stability without eigenvalues (the
characteristic polynomial of G, eq. 25, and the Schur-Cohn recursion) in
:mod:`impactcont.kernel.stability`. Here: the per-frequency setup
(:func:`omega_setup`), the amplitude and its exact derivatives, the state after
the impact, G and its pole-free period-doubling condition, and the drivers of a
point (:func:`point_orbits`, :func:`phase_orbit`) and of a block of the
``(omega, b)`` plane (:func:`block_map`).
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.contact import flight_tables, x1_maximum
from impactcont.kernel.flights import (
    _forced_slope,
    _period_slope,
    _physical_into,
    _re,
    _transition_into,
    forced,
    mode_period,
    transition,
)
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.linalg import _solve_in_place
from impactcont.kernel.roots import orbit_roots, phase_sigma
from impactcont.kernel.stability import (
    _charpoly_in_place,
    _schur_stable_in_place,
    multipliers,
    multipliers_of,
)

__all__ = [
    "amplitude",
    "amplitude_derivative",
    "assemble_jacobian",
    "block_map",
    "impact_jacobian",
    "jacobian_split",
    "omega_setup",
    "orbit_states",
    "pd_condition",
    "pd_condition_slope",
    "phase_orbit",
    "physical_state",
    "point_orbits",
    "setup_slope",
]


BLAS_MIN = 32  # degrees of freedom above which G's matrix products go to BLAS (numpy)
EAGER_JACOBIAN = 16  # G and its multipliers come with the orbit up to this size (2n)


@_jit
def omega_setup(w, a, f, u0, ui0, eig_err, R, omega, N):
    """Everything eq. (12)-(15) needs at one forcing frequency, O(n).

    Parameters
    ----------
    w, a, f : ndarray, shape (n,)
        Natural frequencies, decay rates, modal forces.
    u0, ui0 : ndarray, shape (n,)
        First row of ``u`` and first column of ``u^-1``.
    eig_err : ndarray, shape (n,)
        Rounding-error scale of ``w_i^2``.
    R, omega : float
    N : int

    Returns
    -------
    modal : ndarray, shape (8, n)
        Rows ``gamma, beta, W11, W12, W21, W22, dy, dv`` (``dy, dv``: the free
        modal deviation ``z(0) - z_p(0)`` per unit ``kappa sigma``).
    scalars : ndarray, shape (10,)
        ``T, Gamma, B, g, Delta, c, s, cond, resonance_error, elastic``.
    """
    n = w.size
    T = 2.0 * np.pi * N / omega
    kappa = 1.0 + R
    gamma, beta, worst = forced(w, a, f, omega, eig_err)
    modal = np.empty((8, n), dtype=gamma.dtype)
    Gam = 0.0 * gamma[0]
    B = 0.0 * gamma[0]
    g = 0.0 * gamma[0]
    hs = 0.0 * gamma[0]
    g_abs = 0.0
    h_abs = 0.0
    mode_cond = 1.0
    damped = False
    for i in range(n):
        w11, w12, w21, w22, det, h, omw, cond = mode_period(w[i], a[i], T)
        ci = u0[i] * ui0[i]
        modal[0, i] = gamma[i]
        modal[1, i] = beta[i]
        modal[2, i] = w11
        modal[3, i] = w12
        modal[4, i] = w21
        modal[5, i] = w22
        modal[6, i] = -ui0[i] * w12 / det
        modal[7, i] = -ui0[i] * omw / det
        Gam += u0[i] * gamma[i]
        B += u0[i] * beta[i]
        g += ci * w12 / det
        hs += ci * h
        g_abs += abs(_re(ci * w12 / det))
        h_abs += abs(_re(ci * h))
        if ci != 0.0 and cond > mode_cond:
            mode_cond = cond
        if _re(a[i]) != 0.0:
            damped = True
    Delta = 0.5 * (1.0 - R) + kappa * hs
    elastic = (not damped) and _re(R) == 1.0
    scalars = np.empty(10, dtype=gamma.dtype)
    if elastic:
        rho = 0.0 * Gam
        cond_total = mode_cond * (1.0 + g_abs / max(abs(_re(g)), 1e-300))
    else:
        rho = kappa * omega * g / Delta
        cond_d = (0.5 * (1.0 - _re(R)) + _re(kappa) * h_abs) / max(abs(_re(Delta)), 1e-300)
        cond_g = g_abs / max(abs(_re(g)), 1e-300)
        cond_total = mode_cond * (1.0 + abs(_re(rho)) * (cond_d + cond_g))
    scalars[0] = T
    scalars[1] = Gam
    scalars[2] = B
    scalars[3] = g
    scalars[4] = Delta
    scalars[5] = Gam - rho * B
    scalars[6] = B + rho * Gam
    scalars[7] = cond_total
    scalars[8] = worst
    scalars[9] = 1.0 if elastic else 0.0
    return modal, scalars


@_jit
def amplitude(w, a, f, u0, ui0, R, omega, N):
    """``c, s`` of eq. (14) (float or complex inputs: complex-step differentiable)."""
    eig_err = np.zeros(w.size)
    _, sc = omega_setup(w, a, f, u0, ui0, eig_err, R, omega, N)
    return sc[5], sc[6]


_STEP = 1e-100


@_jit
def amplitude_derivative(w, a, f, u0, ui0, R, omega, N, which, da):
    """Exact ``d(c, s)/d lam`` by one complex-step evaluation (no cancellation, no step error).

    ``which``: 0 omega, 1 R, 2 the damping (``a`` moves along ``da``).
    """
    h = _STEP * max(1.0, abs(omega))
    wc = w.astype(np.complex128)
    ac = a.astype(np.complex128)
    Rc = complex(R, 0.0)
    omc = complex(omega, 0.0)
    if which == 0:
        omc = complex(omega, h)
    elif which == 1:
        h = _STEP
        Rc = complex(R, h)
    else:
        h = _STEP
        for i in range(a.size):
            ac[i] = complex(a[i], h * da[i])
    # complex f as every complex-stepped caller passes it: one compiled complex variant
    c, s = amplitude(wc, ac, f.astype(np.complex128), u0, ui0, Rc, omc, N)
    return c.imag / h, s.imag / h


@_jit
def setup_slope(w, a, f, u0, ui0, R, omega, N, which):
    """Exact derivatives of :func:`omega_setup`'s outputs in real arithmetic: ``which`` 0
    omega, 1 R.

    Returns ``d modal`` (8, n) and ``d scalars`` (10,) in the layout of
    :func:`omega_setup` (the rounding scales ``cond``, ``resonance_error`` and the flag
    ``elastic`` have derivative 0, as under a complex step). The chain rule: in omega the
    period ``T = 2 pi N / omega`` moves every mode (``dW/dT = A W`` of eq. 9,
    :func:`~impactcont.kernel.flights._period_slope`) and the forced response
    (:func:`~impactcont.kernel.flights._forced_slope`); in R only ``kappa`` and
    ``Delta`` move (the modal rows do not depend on R); then ``rho = kappa omega g /
    Delta``, ``c = Gamma - rho B``, ``s = B + rho Gamma``. Equal to the complex step of
    :func:`amplitude_derivative` within rounding, without complex variants of the
    flights (those are compiled for the damping only).
    """
    n = w.size
    T = 2.0 * np.pi * N / omega
    kappa = 1.0 + R
    gamma, beta, _ = forced(w, a, f, omega, np.zeros(n))
    d_modal = np.zeros((8, n))
    d_sc = np.zeros(10)
    Gam = B = g = hs = 0.0
    d_T = -T / omega if which == 0 else 0.0
    damped = False
    for i in range(n):
        _, w12, w21, w22, det, h, omw, _ = mode_period(w[i], a[i], T)
        ci = u0[i] * ui0[i]
        Gam += u0[i] * gamma[i]
        B += u0[i] * beta[i]
        g += ci * w12 / det
        hs += ci * h
        damped = damped or a[i] != 0.0
        if which == 0:
            d_gamma, d_beta = _forced_slope(w[i], a[i], f[i], omega)
            d_w12, d_det, d_h = _period_slope(w[i], a[i], T, w12, w22, det, h)
            d_modal[0, i] = d_gamma
            d_modal[1, i] = d_beta
            d_modal[2, i] = w21 * d_T  # dW/dT = A W (eq. 9)
            d_modal[3, i] = d_w12 * d_T
            d_modal[4, i] = -(w[i] * w[i] * (1.0 - omw) + 2.0 * a[i] * w21) * d_T
            d_modal[5, i] = -(w[i] * w[i] * w12 + 2.0 * a[i] * w22) * d_T
            d_modal[6, i] = -ui0[i] * (d_w12 * det - w12 * d_det) / (det * det) * d_T
            d_modal[7, i] = -ui0[i] * (-w21 * det - omw * d_det) / (det * det) * d_T
            d_sc[1] += u0[i] * d_gamma
            d_sc[2] += u0[i] * d_beta
            d_sc[3] += ci * (d_w12 * det - w12 * d_det) / (det * det) * d_T
            d_sc[4] += kappa * ci * d_h * d_T
    d_sc[0] = d_T
    if which == 1:
        d_sc[4] = hs - 0.5  # Delta = (1 - R) / 2 + kappa hs
    if not damped and R == 1.0:  # elastic: rho = 0 for every omega and R (omega_setup)
        d_sc[5] = d_sc[1]
        d_sc[6] = d_sc[2]
        return d_modal, d_sc
    Delta = 0.5 * (1.0 - R) + kappa * hs
    rho = kappa * omega * g / Delta
    if which == 0:
        d_rho = kappa * (g + omega * d_sc[3] - omega * g * d_sc[4] / Delta) / Delta
    else:
        d_rho = omega * g * (1.0 - kappa * d_sc[4] / Delta) / Delta
    d_sc[5] = d_sc[1] - d_rho * B - rho * d_sc[2]
    d_sc[6] = d_sc[2] + d_rho * Gam + rho * d_sc[1]
    return d_modal, d_sc


@_jit
def orbit_states(modal, omega, R, delta, sigma):
    """Modal state right after the impact, ``y(0), y'(0)`` (eq. 13 in modal form)."""
    n = modal.shape[1]
    ks = (1.0 + R) * sigma
    cd, sd = math.cos(delta), math.sin(delta)
    y = np.empty(n)
    v = np.empty(n)
    for i in range(n):
        gm, bt = modal[0, i], modal[1, i]
        y[i] = gm * cd + bt * sd + ks * modal[6, i]
        v[i] = omega * (bt * cd - gm * sd) + ks * modal[7, i]
    return y, v


@_jit
def physical_state(modal, u, omega, R, delta, sigma):
    """``X(0) = [x; x']`` right after the impact and the velocity scale of the motion.

    ``x1' = -R sigma`` is set exactly (eq. 4). The scale ``max(|x'|, omega |x|)``
    bounds the rounding of ``h2`` (``eps`` times it).
    """
    n = modal.shape[1]
    y, v = orbit_states(modal, omega, R, delta, sigma)
    X = np.empty(2 * n)
    scale = 0.0
    _physical_into(u, y, v, X)
    X[n] = -R * sigma
    for r in range(n):
        scale = max(scale, abs(X[n + r]), omega * abs(X[r]))
    return X, scale


# -- G of eq. (25) ---------------------------------------------------------------------------------
@_jit
def jacobian_pieces(modal, w, a, f, ui0, omega, R, delta, sigma):
    """The modal ingredients of G (eq. 22-25) at a motion, each shape (n,).

    ``e_y, e_v``: d/d delta of the forcing term over a period, ``E_delta = (I - W) P_delta``
    per mode; ``v_pre, acc``: modal velocity and acceleration just before the impact,
    ``z'(T^-)`` (forced part harmonic, ``-omega^2 y_p``; free part by the mode's
    equation: no cancellation of ``f cos(delta)`` against ``w^2 y`` for stiff modes).
    """
    pieces = np.empty((4, modal.shape[1]))
    _jacobian_pieces_into(modal, w, a, f, ui0, omega, R, delta, sigma, pieces)
    return pieces[0], pieces[1], pieces[2], pieces[3]


@_inner
def _jacobian_pieces_into(modal, w, a, f, ui0, omega, R, delta, sigma, pieces):
    """:func:`jacobian_pieces` as the rows of ``pieces`` (4, n), no allocation."""
    kappa = 1.0 + R
    cd, sd = np.cos(delta), np.sin(delta)
    for i in range(modal.shape[1]):
        gm, bt = modal[0, i], modal[1, i]
        py = -gm * sd + bt * cd
        pv = omega * (-bt * sd - gm * cd)
        pieces[0, i] = (1.0 - modal[2, i]) * py - modal[3, i] * pv
        pieces[1, i] = -modal[4, i] * py + (1.0 - modal[5, i]) * pv
        free_v = modal[7, i] + ui0[i]
        pieces[2, i] = omega * (bt * cd - gm * sd) + kappa * sigma * free_v
        pieces[3, i] = (-omega * omega * (gm * cd + bt * sd)
                        + kappa * sigma * (-w[i] * w[i] * modal[6, i] - 2.0 * a[i] * free_v))


@_jit
def assemble_jacobian(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma):
    """G of eq. (22)-(25) from the transition ``tr = U W(T) U^-1``, O(n^2)."""
    m = 2 * modal.shape[1]
    G = np.empty((m, m), dtype=modal.dtype)
    h2 = _assemble_into(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma,
                        np.empty((4, m // 2), dtype=modal.dtype),
                        np.empty((2, m), dtype=modal.dtype), G)
    return G, h2


@_inner
def _assemble_into(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma, pieces, dedx, G):
    """:func:`assemble_jacobian` into ``G`` with scratch ``pieces`` (4, n), ``dedx`` (2, 2n)."""
    m = 2 * modal.shape[1]
    h1, h2 = _impact_vectors(modal, w, a, f, u, ui0, omega, R, delta, sigma, pieces, dedx)
    dE = dedx[0]
    dX = dedx[1]
    n = m // 2
    for r in range(m - 1):
        dr = -R if r + 1 == n else 1.0
        for col in range(m - 1):
            G[r, col] = dr * tr[r + 1, col + 1] - dX[r + 1] * tr[0, col + 1] / h2
        G[r, m - 1] = dE[r + 1] - dX[r + 1] * h1 / h2
    for col in range(m - 1):
        G[m - 1, col] = -omega * tr[0, col + 1] / h2
    G[m - 1, m - 1] = 1.0 - omega * h1 / h2
    return h2


@_jit
def jacobian_split(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma):
    """G of eq. (25) as ``G_reg + a b^T / h2``: its 1/h2 pole (a rank-one term) set apart.

    Returns ``(G_reg, a, b, h2)``; every piece is finite where the impact velocity
    ``h2`` vanishes (ZV). ``det [[G_reg + I, a], [b^T, -h2]] = -h2 det(G + I)`` (Schur
    complement) is then a pole-free form of the period-doubling condition.
    """
    n = modal.shape[1]
    m = 2 * n
    dedx = np.empty((2, m), dtype=modal.dtype)
    h1, h2 = _impact_vectors(modal, w, a, f, u, ui0, omega, R, delta, sigma,
                             np.empty((4, n), dtype=modal.dtype), dedx)
    G_reg = np.zeros((m, m), dtype=modal.dtype)
    av = np.empty(m, dtype=modal.dtype)
    bv = np.empty(m, dtype=modal.dtype)
    for r in range(m - 1):
        dr = -R if r + 1 == n else 1.0
        for col in range(m - 1):
            G_reg[r, col] = dr * tr[r + 1, col + 1]
        G_reg[r, m - 1] = dedx[0, r + 1]
        av[r] = -dedx[1, r + 1]
        bv[r] = tr[0, r + 1]
    G_reg[m - 1, m - 1] = 1.0
    av[m - 1] = -omega
    bv[m - 1] = h1
    return G_reg, av, bv, h2


@_jit
def pd_condition(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma, left, right):
    """The period-doubling condition ``g`` of a motion, free of G's 1/h2 pole.

    ``g`` is the last component of the solution of ``[[E, w], [v^T, 0]] [q; g] =
    [0; 1]`` with ``E = [[G_reg + I, a], [b^T, -h2]]`` (:func:`jacobian_split`,
    ``det E = -h2 det(G + I)``) and the borders ``w = left``, ``v = right`` (size
    2n + 1): it vanishes exactly where ``h2 det(G + I)`` does. One compiled call:
    Gaussian elimination with partial pivoting (as LAPACK's ``dgesv``).
    """
    G_reg, av, bv, h2 = jacobian_split(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma)
    A = _pd_bordered(G_reg, av, bv, h2, left, right)
    k = A.shape[0]
    rhs = np.zeros(k, dtype=G_reg.dtype)
    rhs[k - 1] = 1.0
    if not _solve_in_place(A, rhs):  # singular
        return rhs[k - 1] * np.nan
    return rhs[k - 1]


@_inner
def _pd_bordered(G_reg, av, bv, h2, left, right):
    """The bordered matrix ``[[E, w], [v^T, 0]]``, ``E = [[G_reg + I, a], [b^T, -h2]]``,
    borders ``w = left``, ``v = right`` (:func:`pd_condition`), shape (2n + 2, 2n + 2)."""
    m = G_reg.shape[0]
    k = m + 2
    A = np.zeros((k, k), dtype=G_reg.dtype)
    for r in range(m):
        for col in range(m):
            A[r, col] = G_reg[r, col]
        A[r, r] += 1.0
        A[r, m] = av[r]
        A[m, r] = bv[r]
    A[m, m] = -h2
    for r in range(m + 1):
        A[r, m + 1] = left[r]
        A[m + 1, r] = right[r]
    return A


@_jit
def pd_condition_slope(tr, d_tr, modal, d_modal, w, a, u, ui0, point, d_point, left, right):
    """Exact derivatives of :func:`pd_condition`'s ``g`` along ``k`` directions, in real
    arithmetic (no complex step: no complex variant of G's assembly and solve).

    ``point = [omega, R, delta, sigma]``; direction ``j`` moves the transition by
    ``d_tr[j]`` (m, m), the modal rows of :func:`omega_setup` by ``d_modal[j]`` (8, n)
    and ``point`` by ``d_point[j]`` (4,). With ``A x = e`` the bordered system and
    ``A^T psi = e``, ``dg = -psi^T dA x`` (``A`` moves in its block ``E`` only: G's
    pieces of eq. 22-25, :func:`_pieces_slope`, :func:`_split_slope`). Returns ``g`` and
    ``dg`` (k,), NaN where ``A`` is singular; ``k = 0`` gives ``g`` alone (one solve).
    """
    omega, R, delta, sigma = point[0], point[1], point[2], point[3]
    G_reg, av, bv, h2 = jacobian_split(tr, modal, w, a, w, u, ui0, omega, R, delta, sigma)
    A = _pd_bordered(G_reg, av, bv, h2, left, right)
    k = A.shape[0]
    slopes = np.full(d_point.shape[0], np.nan)
    At = A.T.copy() if slopes.size > 0 else np.empty((0, 0))  # the solve overwrites A
    x = np.zeros(k)
    x[k - 1] = 1.0
    if not _solve_in_place(A, x):
        return np.nan, slopes
    if slopes.size == 0:
        return x[k - 1], slopes
    psi = np.zeros(k)
    psi[k - 1] = 1.0
    if not _solve_in_place(At, psi):
        return x[k - 1], slopes
    m = k - 2
    n = m // 2
    # E, X of eq. 22 before the impact law (rows 0, 2) and their derivatives (rows 1, 3)
    raw = np.empty((4, m))
    pieces = np.empty((4, n))
    _jacobian_pieces_into(modal, w, a, w, ui0, omega, R, delta, sigma, pieces)
    _physical_into(u, pieces[0], pieces[1], raw[0])
    _physical_into(u, pieces[2], pieces[3], raw[2])
    dE = np.empty((m + 1, m + 1))
    for j in range(d_point.shape[0]):
        _pieces_slope(modal, d_modal[j], w, a, ui0, point, d_point[j], pieces)
        _physical_into(u, pieces[0], pieces[1], raw[1])
        _physical_into(u, pieces[2], pieces[3], raw[3])
        _split_slope(tr, d_tr[j], raw, R, d_point[j], dE)
        total = 0.0
        for r in range(m + 1):
            for col in range(m + 1):
                total += psi[r] * dE[r, col] * x[col]
        slopes[j] = -total
    return x[k - 1], slopes


@_inner
def _split_slope(tr, d_tr, raw, R, d_point, dE):
    """The derivative of ``E = [[G_reg + I, a], [b^T, -h2]]`` (:func:`jacobian_split`)
    along one direction (:func:`pd_condition_slope`) into ``dE`` (m + 1, m + 1), from the
    rows ``E, dE, X, dX`` of ``raw`` (4, m): eq. 22's vectors before the impact law."""
    m = raw.shape[1]
    n = m // 2
    d_omega, d_R = d_point[0], d_point[1]
    for r in range(m + 1):
        for col in range(m + 1):
            dE[r, col] = 0.0
    for r in range(m - 1):
        dr = -R if r + 1 == n else 1.0
        ddr = -d_R if r + 1 == n else 0.0
        for col in range(m - 1):
            dE[r, col] = dr * d_tr[r + 1, col + 1] + ddr * tr[r + 1, col + 1]
        dE[r, m - 1] = ddr * raw[0, r + 1] + dr * raw[1, r + 1]
        dE[r, m] = -(ddr * raw[2, r + 1] + dr * raw[3, r + 1])
        dE[m, r] = d_tr[0, r + 1]
    dE[m - 1, m] = -d_omega
    dE[m, m - 1] = raw[1, 0]
    dE[m, m] = -raw[3, 0]


@_inner
def _pieces_slope(modal, d_modal, w, a, ui0, point, d_point, d_pieces):
    """The derivative of :func:`_jacobian_pieces_into`'s modal pieces along one direction
    (``d_modal`` (8, n), ``d_point = d [omega, R, delta, sigma]``) into ``d_pieces`` (4, n):
    the product rule, each piece a polynomial in the modal rows, ``cos delta``,
    ``sin delta``, omega and ``kappa sigma``."""
    omega, R, delta, sigma = point[0], point[1], point[2], point[3]
    d_omega, d_R, d_delta, d_sigma = d_point[0], d_point[1], d_point[2], d_point[3]
    ks = (1.0 + R) * sigma
    d_ks = d_R * sigma + (1.0 + R) * d_sigma
    cd, sd = np.cos(delta), np.sin(delta)
    for i in range(modal.shape[1]):
        gm, bt, dgm, dbt = modal[0, i], modal[1, i], d_modal[0, i], d_modal[1, i]
        py = -gm * sd + bt * cd  # d/d delta of the forced displacement
        d_py = -dgm * sd + dbt * cd - (gm * cd + bt * sd) * d_delta
        q = -bt * sd - gm * cd
        d_pv = d_omega * q + omega * (-dbt * sd - dgm * cd - py * d_delta)
        d_pieces[0, i] = (-d_modal[2, i] * py + (1.0 - modal[2, i]) * d_py
                          - d_modal[3, i] * omega * q - modal[3, i] * d_pv)
        d_pieces[1, i] = (-d_modal[4, i] * py - modal[4, i] * d_py
                          - d_modal[5, i] * omega * q + (1.0 - modal[5, i]) * d_pv)
        free_v = modal[7, i] + ui0[i]  # the forced velocity is omega py
        d_pieces[2, i] = d_omega * py + omega * d_py + d_ks * free_v + ks * d_modal[7, i]
        y_p = gm * cd + bt * sd
        d_y_p = dgm * cd + dbt * sd + py * d_delta
        free_a = -w[i] * w[i] * modal[6, i] - 2.0 * a[i] * free_v
        d_free_a = -w[i] * w[i] * d_modal[6, i] - 2.0 * a[i] * d_modal[7, i]
        d_pieces[3, i] = (-2.0 * omega * d_omega * y_p - omega * omega * d_y_p + d_ks * free_a
                          + ks * d_free_a)


@_inner
def _impact_vectors(modal, w, a, f, u, ui0, omega, R, delta, sigma, pieces, dedx):
    """``dE`` (phase derivative of the forcing term) and ``dX`` (state derivative before
    the impact), both after the impact law, into the rows of ``dedx``; returns
    ``(h1, h2)`` (eq. 22)."""
    n = modal.shape[1]
    _jacobian_pieces_into(modal, w, a, f, ui0, omega, R, delta, sigma, pieces)
    dE = dedx[0]
    dX = dedx[1]
    _physical_into(u, pieces[0], pieces[1], dE)
    _physical_into(u, pieces[2], pieces[3], dX)
    # the impact law (eq. 4) scales the velocity row of mass 1 by -R
    dE[n] *= -R
    dX[n] *= -R
    return dE[0], dX[0]


@_jit
def impact_jacobian(modal, w, a, f, u, ui, omega, R, delta, sigma):
    """G of eq. (22)-(25) in ``[dx2..dxn, dx1'..dxn', d delta]``, shape (2n, 2n)."""
    return assemble_jacobian(transition(modal, u, ui), modal, w, a, f, u, ui[:, 0].copy(),
                             omega, R, delta, sigma)


# -- a block of the (omega, b) plane ---------------------------------------------------------
@_jit
def block_map(arrays, R, N, omegas, bs, want_rho):
    """Every root of eq. (15) on ``omegas x bs``: existence, checks, stability.

    ``arrays``: the oscillator's modal arrays, :meth:`impactcont.kernel.arrays.
    ModalArrays.as_tuple`.

    Returns ``r2 (nw,)``, ``cond (nw,)``, ``count (nw, nb)`` (of :func:`orbit_roots`)
    and, on ``(nw, nb, 2)``: ``delta``,
    ``impact_velocity``, ``gap_min``, ``gap_min_time``, ``stable`` (Schur-Cohn on
    the characteristic polynomial of G), ``spectral_radius`` and
    ``critical_multiplier`` (NaN unless ``want_rho``).
    """
    w, a, f, u, ui, eig_err, u0, ui0 = arrays
    n = w.size
    nw = omegas.size
    nb = bs.size
    r2 = np.empty(nw)
    conds = np.empty(nw)
    delta = np.full((nw, nb, 2), np.nan)
    vel = np.full((nw, nb, 2), np.nan)
    gap = np.full((nw, nb, 2), np.nan)
    gap_t = np.full((nw, nb, 2), np.nan)
    stable = np.zeros((nw, nb, 2), dtype=np.bool_)
    rho = np.full((nw, nb, 2), np.nan)
    crit = np.full((nw, nb, 2), np.nan + 0j)
    counts = np.zeros((nw, nb), dtype=np.int8)
    # scratch of G and its stability test, reused for every root (no allocation per root)
    m = 2 * n
    tr = np.empty((m, m))
    G = np.empty((m, m))
    H = np.empty((m, m))
    P = np.empty((m + 1, m + 1))
    pieces = np.empty((4, n))
    dedx = np.empty((2, m))
    v = np.empty(m)
    v_new = np.empty(m + 1)
    for iw in range(nw):
        om = omegas[iw]
        modal, sc = omega_setup(w, a, f, u0, ui0, eig_err, R, om, N)
        r2[iw] = sc[5] * sc[5] + sc[6] * sc[6]
        conds[iw] = sc[7]
        times, _, free, cw, sw, dy, dv, work = flight_tables(w, a, u0, modal, om, sc[0])
        _transition_into(modal, u, ui, tr)
        for ib in range(nb):
            count, dl, sg, _, _ = orbit_roots(sc, bs[ib], om, R)
            counts[iw, ib] = count
            for idx in range(max(count, 0)):
                k = idx
                delta[iw, ib, idx] = dl[k]
                vel[iw, ib, idx] = sg[k]
                ks = (1.0 + R) * sg[k]
                best, best_t = x1_maximum(times, free, cw, sw, sc[1], sc[2], om, dl[k], ks,
                                          w, a, u0, dy, dv, work, np.nan)
                gap[iw, ib, idx] = bs[ib] - best
                gap_t[iw, ib, idx] = best_t
                _assemble_into(tr, modal, w, a, f, u, ui0, om, R, dl[k], sg[k], pieces,
                               dedx, G)
                finite = True
                for r in range(m):
                    for col in range(m):
                        H[r, col] = G[r, col]
                        if not np.isfinite(G[r, col]):
                            finite = False
                if not finite:
                    continue
                _charpoly_in_place(H, P, v)
                stable[iw, ib, idx] = _schur_stable_in_place(P[m], v_new)
                if want_rho:
                    mu = multipliers_of(G)
                    j = np.argmax(np.abs(mu))
                    crit[iw, ib, idx] = mu[j]
                    rho[iw, ib, idx] = abs(mu[j])
            if count == 1:  # a double root: both labels describe the same motion
                for arr in (delta, vel, gap, gap_t, rho):
                    arr[iw, ib, 1] = arr[iw, ib, 0]
                crit[iw, ib, 1] = crit[iw, ib, 0]
                stable[iw, ib, 1] = stable[iw, ib, 0]
    return r2, conds, counts, delta, vel, gap, gap_t, stable, rho, crit


# -- one point: what periodic_orbits needs --------------------------------------------------------
@_jit
def point_orbits(arrays, R, omega, N, b):
    """Every root of eq. (15) at one ``(omega, b)`` with its interior-contact check.

    Returns ``(modal, scalars, count, delta, sigma, fold_error, gap_min, gap_min_time,
    capped, states, velocity_scales, jacobians, multipliers)`` (see :func:`omega_setup`,
    :func:`orbit_roots`, :func:`x1_maximum`, :func:`physical_state`); ``jacobians``
    and ``multipliers`` hold G of each root and its eigenvalues when
    ``2n <= EAGER_JACOBIAN`` (cheaper here than later calls), empty arrays otherwise.
    ``arrays``: the oscillator's modal arrays, :meth:`impactcont.kernel.arrays.
    ModalArrays.as_tuple`.
    """
    w, a, f, u, ui, eig_err, u0, ui0 = arrays
    modal, sc = omega_setup(w, a, f, u0, ui0, eig_err, R, omega, N)
    count, dl, sg, _, fold_error = orbit_roots(sc, b, omega, R)
    gap = np.full(2, np.inf)
    gap_t = np.full(2, np.nan)
    states = np.zeros((2, 2 * w.size))
    scales = np.zeros(2)
    capped = False
    m = 2 * w.size
    small = m <= EAGER_JACOBIAN
    jacobians = np.zeros((2, m, m) if small else (2, 0, 0))
    mults = np.zeros((2, m) if small else (2, 0), dtype=np.complex128)
    for k in range(max(count, 0)):
        # element loops, not slice assignment: numba's broadcasting setitem (with its
        # error-message formatting) would add seconds to the first compilation
        state, scales[k] = physical_state(modal, u, omega, R, dl[k], sg[k])
        for r in range(m):
            states[k, r] = state[r]
        if small:
            # impact_jacobian's body: its entry point is then not compiled for the first
            # orbit (an entry calling an entry compiles the callee's code again)
            G, _ = assemble_jacobian(transition(modal, u, ui), modal, w, a, f, u,
                                     ui[:, 0].copy(), omega, R, dl[k], sg[k])
            mu = multipliers(G)
            for r in range(m):
                mults[k, r] = mu[r]
                for col in range(m):
                    jacobians[k, r, col] = G[r, col]
    if count > 0:
        times, capped, free, cw, sw, dy, dv, work = flight_tables(w, a, u0, modal, omega,
                                                                  sc[0])
        for k in range(count):
            best, best_t = x1_maximum(times, free, cw, sw, sc[1], sc[2], omega, dl[k],
                                      (1.0 + R) * sg[k], w, a, u0, dy, dv, work, np.nan)
            gap[k] = b - best
            gap_t[k] = best_t
    return (modal, sc, count, dl, sg, fold_error, gap, gap_t, capped, states, scales,
            jacobians, mults)


@_jit
def phase_orbit(arrays, R, omega, N, b, delta):
    """The motion with impact phase ``delta``: ``(modal, scalars, sigma, gap_min,
    gap_min_time, capped, state)``; ``arrays``: the oscillator's modal arrays,
    :meth:`impactcont.kernel.arrays.ModalArrays.as_tuple`."""
    w, a, f, u, _, eig_err, u0, ui0 = arrays
    modal, sc = omega_setup(w, a, f, u0, ui0, eig_err, R, omega, N)
    sigma = phase_sigma(sc, omega, R, b, delta)
    state, _ = physical_state(modal, u, omega, R, delta, sigma)
    times, capped, free, cw, sw, dy, dv, work = flight_tables(w, a, u0, modal, omega, sc[0])
    best, best_t = x1_maximum(times, free, cw, sw, sc[1], sc[2], omega, delta,
                              (1.0 + R) * sigma, w, a, u0, dy, dv, work, np.nan)
    return modal, sc, sigma, b - best, best_t, capped, state

"""The compiled evaluation kernel: periodic N-1 motions in modal form, O(n) per motion.

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

Stability without eigenvalues: the characteristic polynomial of G (eq. 25),
from its Hessenberg form, and the Schur-Cohn recursion decide whether every
multiplier lies strictly inside the unit circle.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numba.extending import overload
from numba.np.linalg import _LAPACK, ensure_lapack

__all__ = [
    "amplitude",
    "amplitude_derivative",
    "block_map",
    "charpoly",
    "impact_jacobian",
    "omega_setup",
    "orbit_roots",
    "orbit_states",
    "schur_stable",
    "x1_maximum",
]

_jit = nb.njit(cache=True, nogil=True, error_model="numpy")  # x/0 -> inf, as numpy

ensure_lapack()  # numba's LAPACK bindings resolve to scipy's
_rgeev = _LAPACK().numba_ez_rgeev(nb.float64)
_KIND = np.int8(ord("d"))
_NO = np.int8(ord("N"))

_EPS = 2.220446049250313e-16
_CELLS_PER_PERIOD = 16
_MAX_SAMPLES = 2_000_000
_XTOL = 1e-15
_RTOL = 4.0 * _EPS
_MAX_ITER = 200
BLAS_MIN = 32  # degrees of freedom above which G's matrix products go to BLAS (numpy)
EAGER_JACOBIAN = 16  # G and its multipliers come with the orbit up to this size (2n)
_END_TOL = 1e-12  # critical points this close (relative to T) to an impact are the impact


# -- scalar helpers usable for float and complex (complex step) ---------------------------------
def _expm1(x):  # pragma: no cover - replaced by the overload inside compiled code
    return math.expm1(x)


@overload(_expm1)
def _expm1_overload(x):
    if isinstance(x, nb.types.Complex):
        def impl(x):
            # expm1(x + iy) = e^x (cos y + i sin y) - 1, accurate for the tiny y of a complex step
            ex = math.exp(x.real)
            return complex(math.expm1(x.real) - 2.0 * ex * math.sin(0.5 * x.imag) ** 2,
                           ex * math.sin(x.imag))
        return impl
    return lambda x: math.expm1(x)


@_jit
def _re(x):
    return x.real


# -- one mode: the exact free transfer W(t) of eq. (9) ------------------------------------------
@_jit
def mode_transfer(w, a, t):
    """``W11, W12, W21, W22`` of one mode at time t, every damping class (eq. 9)."""
    d = (w - a) * (w + a)
    if _re(d) > 0.0:
        wd = np.sqrt(d)
        e = np.exp(-a * t)
        ec = e * np.cos(wd * t)
        es = e * np.sin(wd * t) / wd
        w22 = ec - a * es
    elif _re(d) == 0.0:
        e = np.exp(-a * t)
        ec = e
        es = e * t
        w22 = e * (1.0 - a * t)
    else:
        k = np.sqrt(-d)
        e_slow = np.exp(-(w * w / (a + k)) * t)
        e_fast = np.exp(-(a + k) * t)
        ec = 0.5 * (e_slow + e_fast)
        es = e_slow * (-_expm1(-2.0 * k * t)) / (2.0 * k)
        if _re(k * t) < 1.0:
            w22 = ec - a * es
        else:
            w22 = 0.5 * (-(w * w) / ((a + k) * k) * e_slow + (1.0 + a / k) * e_fast)
    return ec + a * es, es, -(w * w) * es, w22


@_jit
def mode_period(w, a, T):
    """One mode over a period: ``W(T)``, ``d = det(I - W)``, ``h`` and ``1 - W11``.

    Returns ``(W11, W12, W21, W22, d, h, one_minus_w11, cond)`` where
    ``h = (1 - det W + W22 - W11) / (2 d)`` and ``cond`` bounds the relative error
    of ``d`` caused by the rounding of ``omega_d T`` (large only close to an undamped
    resonance of the free mode, ``omega_d T`` near a multiple of 2 pi).
    """
    w11, w12, w21, w22 = mode_transfer(w, a, T)
    d = (w - a) * (w + a)
    aT = a * T
    em1 = _expm1(-aT)
    cond = 1.0
    if _re(d) > 0.0:
        wd = np.sqrt(d)
        th = wd * T
        e = np.exp(-aT)
        sh = np.sin(0.5 * th)
        det = em1 * em1 + 4.0 * e * sh * sh
        one_m_w11 = -em1 + 2.0 * e * sh * sh - a * w12
        h = (-_expm1(-2.0 * aT) - 2.0 * a * w12) / (2.0 * det)
        if _re(det) > 0.0:
            cond = 1.0 + _re(th) * abs(_re(e * np.sin(th))) / abs(_re(det))
    elif _re(d) == 0.0:
        det = em1 * em1
        one_m_w11 = -em1 - aT * np.exp(-aT)
        h = (-_expm1(-2.0 * aT) - 2.0 * a * w12) / (2.0 * det)
    else:
        k = np.sqrt(-d)
        ls = w * w / (a + k)
        lf = a + k
        ems = _expm1(-ls * T)
        emf = _expm1(-lf * T)
        det = ems * emf
        if _re(k) >= 0.5 * _re(a):
            # heavy damping: W11 = (lf e_s - ls e_f)/(lf - ls) and the divided difference of
            # phi(l) = l coth(l T / 2), free of the cancellation of 1 - e_s against a/k
            one_m_w11 = (-lf * ems + ls * emf) / (lf - ls)
            phi_f = lf * (2.0 + emf) / (-emf)
            phi_s = ls * (2.0 + ems) / (-ems)
            h = (phi_f - phi_s) / (2.0 * (lf - ls))
        else:
            one_m_w11 = -0.5 * (ems + emf) - a * w12
            h = (-_expm1(-2.0 * aT) - 2.0 * a * w12) / (2.0 * det)
    return w11, w12, w21, w22, det, h, one_m_w11, cond


# -- one frequency: S of eq. (13) in modal form ---------------------------------------------------
@_jit
def forced(w, a, f, omega, eig_err):
    """``gamma_i, beta_i`` of eq. (7) and the worst relative error near a resonance."""
    n = w.size
    gamma = np.empty_like(w * (a[0] * omega))  # complex when any input is (complex step)
    beta = np.empty_like(gamma)
    worst = 0.0
    for i in range(n):
        detune = (w[i] - omega) * (w[i] + omega)
        damp = 2.0 * a[i] * omega
        den = detune * detune + damp * damp
        if _re(den) == 0.0:
            gamma[i] = np.nan if f[i] != 0.0 else 0.0
            beta[i] = gamma[i]
            if f[i] != 0.0:
                worst = np.inf
            continue
        gamma[i] = detune * f[i] / den
        beta[i] = damp * f[i] / den
        if f[i] != 0.0:
            scale = 4.0 * eig_err[i] + 4.0 * _EPS * _re(w[i] * w[i])
            rel = scale * abs(_re(detune)) / _re(den)
            if rel > worst:
                worst = rel
    return gamma, beta, worst


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
    c, s = amplitude(wc, ac, f, u0, ui0, Rc, omc, N)
    return c.imag / h, s.imag / h


# -- roots of eq. (15) ----------------------------------------------------------------------
@_jit
def orbit_roots(scalars, b, omega, R):
    """Impact phases and velocities of the motions at gap b.

    Returns ``(count, delta[2], sigma[2], sign[2], fold_error)``; ``count`` is 0, 1
    (double root) or 2, ``-1`` when every phase solves eq. (14) (no forcing reaches
    mass 1) and ``-2`` for an elastic system whose forced motion of mass 1 vanishes.
    """
    Gam, B, g, Delta, c, s = scalars[1], scalars[2], scalars[3], scalars[4], scalars[5], scalars[6]
    elastic = scalars[9] != 0.0
    kappa = 1.0 + R
    delta = np.zeros(2)
    sigma = np.zeros(2)
    sign = np.array([1.0, -1.0])
    if elastic:
        amp = math.hypot(Gam, B)
        if amp == 0.0 or g == 0.0:
            return -2, delta, sigma, sign, 0.0
        d0 = math.atan2(B, Gam)
        for k in range(2):
            dk = d0 if k == 0 else d0 + math.pi
            if dk > math.pi:
                dk -= 2.0 * math.pi
            delta[k] = dk
            sigma[k] = ((amp if k == 0 else -amp) - b) / (kappa * g)
        return 2, delta, sigma, sign, 0.0
    r2 = c * c + s * s
    if r2 == 0.0:
        return (-1 if b == 0.0 else 0), delta, sigma, sign, 0.0
    disc = r2 - b * b
    if disc < 0.0:
        return 0, delta, sigma, sign, 0.0
    root_r = math.sqrt(disc)
    fold_error = _EPS * math.sqrt(r2) / root_r if root_r > 0.0 else math.sqrt(_EPS)
    count = 2 if root_r > 0.0 else 1
    for k in range(count):
        sg = sign[k]
        sin_d = (b * s + sg * c * root_r) / r2
        cos_d = (b * c - sg * s * root_r) / r2
        dk = math.atan2(sin_d, cos_d)
        delta[k] = dk
        sigma[k] = omega * (B * math.cos(dk) - Gam * math.sin(dk)) / Delta
    return count, delta, sigma, sign, fold_error


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
    for r in range(n):
        sx = 0.0
        sv = 0.0
        for i in range(n):
            sx += u[r, i] * y[i]
            sv += u[r, i] * v[i]
        X[r] = sx
        X[n + r] = sv
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


@_jit
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
def transition(modal, u, ui):
    """Physical transition ``U W(T) U^-1`` (eq. 9), shape (2n, 2n), by plain loops.

    For small systems (no BLAS call on tiny arrays); above ``BLAS_MIN`` degrees of
    freedom :func:`impactcont.orbit.periodic.modal_jacobian` forms it with numpy
    matrix products instead.
    """
    n = modal.shape[1]
    tr = np.empty((2 * n, 2 * n), dtype=modal.dtype)
    _transition_into(modal, u, ui, tr)
    return tr


@_jit
def _transition_into(modal, u, ui, tr):
    """:func:`transition` into ``tr`` (2n, 2n), no allocation."""
    n = modal.shape[1]
    for r in range(n):
        for col in range(n):
            s11 = 0.0
            s12 = 0.0
            s21 = 0.0
            s22 = 0.0
            for i in range(n):
                p = u[r, i] * ui[i, col]
                s11 += p * modal[2, i]
                s12 += p * modal[3, i]
                s21 += p * modal[4, i]
                s22 += p * modal[5, i]
            tr[r, col] = s11
            tr[r, n + col] = s12
            tr[n + r, col] = s21
            tr[n + r, n + col] = s22


@_jit
def assemble_jacobian(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma):
    """G of eq. (22)-(25) from the transition ``tr = U W(T) U^-1``, O(n^2)."""
    m = 2 * modal.shape[1]
    G = np.empty((m, m), dtype=modal.dtype)
    h2 = _assemble_into(tr, modal, w, a, f, u, ui0, omega, R, delta, sigma,
                        np.empty((4, m // 2), dtype=modal.dtype),
                        np.empty((2, m), dtype=modal.dtype), G)
    return G, h2


@_jit
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
    rhs = np.zeros(k, dtype=G_reg.dtype)
    rhs[k - 1] = 1.0
    return _solve_small(A, rhs)[k - 1]


@_jit
def _solve_small(A, x):
    """Solve ``A y = x`` in place (both overwritten) by Gaussian elimination with partial
    pivoting; returns ``x`` holding ``y`` (inf or NaN when A is singular)."""
    k = x.size
    for j in range(k):
        p = j
        for r in range(j + 1, k):
            if abs(A[r, j]) > abs(A[p, j]):
                p = r
        if p != j:
            for col in range(k):
                A[j, col], A[p, col] = A[p, col], A[j, col]
            x[j], x[p] = x[p], x[j]
        for r in range(j + 1, k):
            factor = A[r, j] / A[j, j]
            for col in range(j + 1, k):
                A[r, col] -= factor * A[j, col]
            x[r] -= factor * x[j]
    for j in range(k - 1, -1, -1):
        acc = x[j]
        for col in range(j + 1, k):
            acc -= A[j, col] * x[col]
        x[j] = acc / A[j, j]
    return x


@_jit
def _impact_vectors(modal, w, a, f, u, ui0, omega, R, delta, sigma, pieces, dedx):
    """``dE`` (phase derivative of the forcing term) and ``dX`` (state derivative before
    the impact), both after the impact law, into the rows of ``dedx``; returns
    ``(h1, h2)`` (eq. 22)."""
    n = modal.shape[1]
    _jacobian_pieces_into(modal, w, a, f, ui0, omega, R, delta, sigma, pieces)
    dE = dedx[0]
    dX = dedx[1]
    for r in range(n):
        sy = 0.0
        sv = 0.0
        xv = 0.0
        xa = 0.0
        for i in range(n):
            sy += u[r, i] * pieces[0, i]
            sv += u[r, i] * pieces[1, i]
            xv += u[r, i] * pieces[2, i]
            xa += u[r, i] * pieces[3, i]
        dE[r] = sy
        dE[n + r] = sv
        dX[r] = xv
        dX[n + r] = xa
    # the impact law (eq. 4) scales the velocity row of mass 1 by -R
    dE[n] *= -R
    dX[n] *= -R
    return dE[0], dX[0]


@_jit
def impact_jacobian(modal, w, a, f, u, ui, omega, R, delta, sigma):
    """G of eq. (22)-(25) in ``[dx2..dxn, dx1'..dxn', d delta]``, shape (2n, 2n)."""
    return assemble_jacobian(transition(modal, u, ui), modal, w, a, f, u, ui[:, 0].copy(),
                             omega, R, delta, sigma)


# -- stability without eigenvalues -----------------------------------------------------------------
@_jit
def hessenberg(A):
    """Upper Hessenberg form of A by Householder reflections (similar to A)."""
    H = A.copy()
    _hessenberg_in_place(H, np.empty(A.shape[0]))
    return H


@_jit
def _hessenberg_in_place(H, v):
    """Reduce ``H`` to upper Hessenberg form in place; ``v``: scratch of size m."""
    m = H.shape[0]
    for k in range(m - 2):
        alpha = 0.0
        for i in range(k + 1, m):
            alpha += H[i, k] * H[i, k]
        alpha = math.sqrt(alpha)
        if alpha == 0.0:
            continue
        if H[k + 1, k] > 0.0:
            alpha = -alpha
        v[k + 1] = H[k + 1, k] - alpha
        for i in range(k + 2, m):
            v[i] = H[i, k]
        vv = 0.0
        for i in range(k + 1, m):
            vv += v[i] * v[i]
        if vv == 0.0:
            continue
        for col in range(m):  # H <- (I - 2 v v^T / vv) H
            t = 0.0
            for i in range(k + 1, m):
                t += v[i] * H[i, col]
            t *= 2.0 / vv
            for i in range(k + 1, m):
                H[i, col] -= t * v[i]
        for r in range(m):  # H <- H (I - 2 v v^T / vv)
            t = 0.0
            for i in range(k + 1, m):
                t += H[r, i] * v[i]
            t *= 2.0 / vv
            for i in range(k + 1, m):
                H[r, i] -= t * v[i]
        for i in range(k + 2, m):
            H[i, k] = 0.0


@_jit
def charpoly(A):
    """Coefficients (ascending, monic) of ``det(lambda I - A)`` via the Hessenberg form."""
    m = A.shape[0]
    P = np.zeros((m + 1, m + 1))
    _charpoly_in_place(A.copy(), P, np.empty(m))
    return P[m].copy()


@_jit
def _charpoly_in_place(H, P, v):
    """Characteristic polynomial of ``H`` (overwritten) into row m of ``P`` (m+1, m+1)."""
    m = H.shape[0]
    _hessenberg_in_place(H, v)
    # p_k(l) = (l - h_kk) p_{k-1} - sum_{i<k} h_ik (prod_{j=i+1..k} h_{j,j-1}) p_{i-1}
    P[:, :] = 0.0
    P[0, 0] = 1.0
    for k in range(1, m + 1):
        for j in range(k):
            P[k, j + 1] += P[k - 1, j]
            P[k, j] -= H[k - 1, k - 1] * P[k - 1, j]
        prod = 1.0
        for i in range(k - 1, 0, -1):
            prod *= H[i, i - 1]
            coef = H[i - 1, k - 1] * prod
            if coef != 0.0:
                for j in range(i):
                    P[k, j] -= coef * P[i - 1, j]


@_jit
def schur_stable(p):
    """All roots of the real polynomial ``p`` (ascending) strictly inside the unit circle.

    Schur-Cohn: ``p`` of degree m is Schur stable iff ``|p_0| < |p_m|`` and the
    degree ``m - 1`` polynomial ``(p_m p(z) - p_0 p*(z)) / z`` is.
    """
    return _schur_stable_in_place(p.copy(), np.empty(p.size))


@_jit
def _schur_stable_in_place(c, new):
    """:func:`schur_stable` of ``c`` (overwritten); ``new``: scratch of the same size."""
    m = c.size - 1
    while m > 0:
        scale = 0.0
        for k in range(m + 1):
            scale = max(scale, abs(c[k]))
        if scale == 0.0 or not np.isfinite(scale):
            return False
        if abs(c[0]) >= abs(c[m]):
            return False
        for k in range(m):
            new[k] = (c[m] * c[k + 1] - c[0] * c[m - 1 - k]) / (scale * scale)
        for k in range(m):
            c[k] = new[k]
        m -= 1
    return True


# -- the interior-contact check of eq. (16) --------------------------------------------------
@_jit
def time_grid(w, a, u0, omega, T):
    """Times on [0, T], each cell at most 1/16 of the fastest period seen by mass 1.

    With a geometric refinement near 0 for fast over-damped decays (as
    :func:`impactcont.orbit.extrema.sample_times`). Returns ``(times, capped)``.
    """
    rate = omega
    decay = 0.0
    for i in range(w.size):
        if u0[i] == 0.0:
            continue
        d = (w[i] - a[i]) * (w[i] + a[i])
        if d > 0.0:
            rate = max(rate, math.sqrt(d))
        fast = a[i] + (math.sqrt(-d) if d < 0.0 else 0.0)
        decay = max(decay, fast)
    h = 2.0 * math.pi / (_CELLS_PER_PERIOD * rate)
    count = max(math.ceil(T / h), 8)
    capped = count > _MAX_SAMPLES
    if capped:
        count = _MAX_SAMPLES
    cell = T / count
    extra = 0
    if decay > 0.0:
        tau = 1.0 / (_CELLS_PER_PERIOD * decay)
        if tau < cell:
            extra = math.ceil(math.log2(cell / tau))
    times = np.empty(count + 1 + extra)
    times[0] = 0.0
    for j in range(extra):
        times[1 + j] = cell * 2.0 ** (-(extra - j))
    for j in range(1, count + 1):
        times[extra + j] = T * j / count
    times[extra + count] = T
    return times, capped


@_jit
def free_x1(t, w, a, u0, dy, dv):
    """x1 and its first four time derivatives of the free deviation (per unit kappa sigma)."""
    x0 = 0.0
    x1 = 0.0
    x2 = 0.0
    x3 = 0.0
    x4 = 0.0
    for i in range(w.size):
        if u0[i] == 0.0:
            continue
        w11, w12, w21, w22 = mode_transfer(w[i], a[i], t)
        y = w11 * dy[i] + w12 * dv[i]
        v = w21 * dy[i] + w22 * dv[i]
        acc = -w[i] * w[i] * y - 2.0 * a[i] * v
        jerk = -w[i] * w[i] * v - 2.0 * a[i] * acc
        x0 += u0[i] * y
        x1 += u0[i] * v
        x2 += u0[i] * acc
        x3 += u0[i] * jerk
        x4 += u0[i] * (-w[i] * w[i] * acc - 2.0 * a[i] * jerk)
    return x0, x1, x2, x3, x4


_ANCHOR = 32  # grid steps of the recurrence between direct evaluations


@_jit
def free_on_grid(times, w, a, u0, dy, dv):
    """``free_x1`` at every grid time, shape (5, nt): x1 and its first four derivatives.

    On the uniform part of the grid the modal deviation is advanced by the one-step
    transfer ``W(h)`` (the flow is a semigroup: four products per mode and step
    instead of three transcendental functions) and evaluated directly every
    ``_ANCHOR`` steps, so rounding cannot accumulate beyond a few dozen ulps; the
    grid only brackets roots, which are then polished by direct evaluation.
    """
    nt = times.size
    out = np.zeros((5, nt))
    # the uniform part ends the grid: find where it starts (after the refinement near 0)
    j0 = nt - 1
    while j0 > 1 and abs((times[j0] - times[j0 - 1]) - (times[nt - 1] - times[nt - 2])) <= (
            1e-9 * (times[nt - 1] - times[nt - 2])):
        j0 -= 1
    for k in range(j0):
        x0, x1, x2, x3, x4 = free_x1(times[k], w, a, u0, dy, dv)
        out[0, k] = x0
        out[1, k] = x1
        out[2, k] = x2
        out[3, k] = x3
        out[4, k] = x4
    h = (times[nt - 1] - times[j0]) / max(nt - 1 - j0, 1)
    for i in range(w.size):
        if u0[i] == 0.0:
            continue
        s11, s12, s21, s22 = mode_transfer(w[i], a[i], h)
        wi2 = w[i] * w[i]
        ai2 = 2.0 * a[i]
        y = 0.0
        yv = 0.0
        for k in range(j0, nt):
            if (k - j0) % _ANCHOR == 0:
                w11, w12, w21, w22 = mode_transfer(w[i], a[i], times[k])
                y = w11 * dy[i] + w12 * dv[i]
                yv = w21 * dy[i] + w22 * dv[i]
            else:
                y, yv = s11 * y + s12 * yv, s21 * y + s22 * yv
            ya = -wi2 * y - ai2 * yv
            yj = -wi2 * yv - ai2 * ya
            out[0, k] += u0[i] * y
            out[1, k] += u0[i] * yv
            out[2, k] += u0[i] * ya
            out[3, k] += u0[i] * yj
            out[4, k] += u0[i] * (-wi2 * ya - ai2 * yj)
    return out


@_jit
def x1_derivatives(t, Gam, B, omega, delta, ks, w, a, u0, dy, dv):
    """``x1`` and its first three derivatives at time t after the impact at ``delta``.

    ``Gam, B``: the forced motion of mass 1 (``scalars[1:3]`` of :func:`omega_setup`);
    ``ks = kappa sigma``; ``dy, dv``: ``modal[6], modal[7]``.
    """
    d = _x1_derivs(t, Gam, B, omega, delta, ks, w, a, u0, dy, dv)
    return d[0], d[1], d[2], d[3]


@_jit
def _x1_derivs(t, Gam, B, omega, delta, ks, w, a, u0, dy, dv):
    th = omega * t + delta
    c, s = np.cos(th), np.sin(th)
    p = Gam * c + B * s
    dp = omega * (B * c - Gam * s)
    f0, f1, f2, f3, f4 = free_x1(t, w, a, u0, dy, dv)
    om2 = omega * omega
    return (p + ks * f0, dp + ks * f1, -om2 * p + ks * f2, -om2 * dp + ks * f3,
            om2 * om2 * p + ks * f4)


# the derivative a polish finds a root of, as run-time integers: a literal argument would
# make numba compile _polish once per value
_ORDER_VEL = np.int64(1)
_ORDER_ACC = np.int64(2)


@_jit
def _polish(order, lo, hi, g_lo, g_hi, dg_lo, dg_hi, ddg_lo, ddg_hi, Gam, B, omega, delta, ks,
            w, a, u0, dy, dv):
    """Root of the ``order``-th derivative of x1 in [lo, hi] by safeguarded Newton.

    Returns the root and x1 with its first three derivatives there. The start is the
    root of the quintic Hermite interpolant of the ``order``-th derivative from its
    values ``g``, slopes ``dg`` and curvatures ``ddg`` at the ends (cubic when a
    curvature is not finite, the secant point when a slope is not), so one Newton
    step (two from a cubic start) reaches rounding level; a step that would leave the
    shrinking bracket bisects instead. A Newton step below the tolerance, or whose predicted
    error (the next derivative over twice the slope, times the step squared) is, is
    the last: the values at the root then follow from the Taylor series at the last
    evaluation (exact to rounding, no further evaluation).
    """
    left, right = lo, hi
    ga = g_lo
    x = _hermite_root(lo, hi, g_lo, g_hi, dg_lo, dg_hi, ddg_lo, ddg_hi)
    for _ in range(_MAX_ITER):
        d = _x1_derivs(x, Gam, B, omega, delta, ks, w, a, u0, dy, dv)
        g = d[order]
        dg = d[order + 1]
        if (g < 0.0) == (ga < 0.0):
            left = x
            ga = g
        else:
            right = x
        if g == 0.0:
            return x, d[0], d[1], d[2], d[3]
        step = g / dg if dg != 0.0 else np.inf
        tol = _XTOL + _RTOL * abs(x)
        xn = x - step
        if np.isfinite(xn) and (abs(step) <= tol or (
                left <= xn <= right and abs(d[order + 2] / (2.0 * dg)) * step * step <= tol)):
            return _taylor(xn, -step, d)  # the Newton step is the last
        if right - left <= tol:
            d = _x1_derivs(xn, Gam, B, omega, delta, ks, w, a, u0, dy, dv) if np.isfinite(xn) \
                else d
            return (xn if np.isfinite(xn) else x), d[0], d[1], d[2], d[3]
        if not (np.isfinite(xn) and left <= xn <= right):
            xn = 0.5 * (left + right)
        x = xn
    d = _x1_derivs(x, Gam, B, omega, delta, ks, w, a, u0, dy, dv)
    return x, d[0], d[1], d[2], d[3]


@_jit
def _taylor(t, h, d):
    """``t`` and x1 with its first three derivatives at ``t`` from ``d`` (x1 to its fourth)
    at ``t - h``: for the tiny last Newton step ``h`` the remainder is O(h^4) or less."""
    return (t, d[0] + h * (d[1] + h * (0.5 * d[2] + h * (d[3] / 6.0 + h * d[4] / 24.0))),
            d[1] + h * (d[2] + h * (0.5 * d[3] + h * d[4] / 6.0)),
            d[2] + h * (d[3] + 0.5 * h * d[4]), d[3] + h * d[4])


@_jit
def _hermite_root(lo, hi, g_lo, g_hi, dg_lo, dg_hi, ddg_lo, ddg_hi):
    """Root in (lo, hi) of the Hermite interpolant of g (g of opposite signs at the ends).

    The cubic one from the values and slopes at the ends, by three Newton steps from the
    secant point, then, when the second derivatives ``ddg`` are finite, the quintic one
    by two Newton steps from there; the secant point (or the midpoint) when a slope is
    not finite; a step that leaves the interval ends the iteration."""
    h = hi - lo
    x = g_lo / (g_lo - g_hi) if g_lo != g_hi else 0.5
    if not 0.0 < x < 1.0:
        return 0.5 * (lo + hi)
    if not (np.isfinite(dg_lo) and np.isfinite(dg_hi)):
        return lo + h * x
    m0 = h * dg_lo
    m1 = h * dg_hi
    for _ in range(3):
        x2 = x * x
        x3 = x2 * x
        p = ((2 * x3 - 3 * x2 + 1) * g_lo + (x3 - 2 * x2 + x) * m0
             + (-2 * x3 + 3 * x2) * g_hi + (x3 - x2) * m1)
        dp = ((6 * x2 - 6 * x) * g_lo + (3 * x2 - 4 * x + 1) * m0
              + (-6 * x2 + 6 * x) * g_hi + (3 * x2 - 2 * x) * m1)
        if dp == 0.0:
            break
        xn = x - p / dp
        if not 0.0 < xn < 1.0:
            break
        x = xn
    if not (np.isfinite(ddg_lo) and np.isfinite(ddg_hi)):
        return lo + h * x
    c0 = h * h * ddg_lo
    c1 = h * h * ddg_hi
    for _ in range(2):
        # quintic Hermite basis on [0, 1]: values, slopes and curvatures at 0 and 1
        x2 = x * x
        x3 = x2 * x
        x4 = x3 * x
        x5 = x4 * x
        p = ((1.0 - 10.0 * x3 + 15.0 * x4 - 6.0 * x5) * g_lo
             + (x - 6.0 * x3 + 8.0 * x4 - 3.0 * x5) * m0
             + 0.5 * (x2 - 3.0 * x3 + 3.0 * x4 - x5) * c0
             + 0.5 * (x3 - 2.0 * x4 + x5) * c1
             + (-4.0 * x3 + 7.0 * x4 - 3.0 * x5) * m1
             + (10.0 * x3 - 15.0 * x4 + 6.0 * x5) * g_hi)
        dp = ((-30.0 * x2 + 60.0 * x3 - 30.0 * x4) * g_lo
              + (1.0 - 18.0 * x2 + 32.0 * x3 - 15.0 * x4) * m0
              + 0.5 * (2.0 * x - 9.0 * x2 + 12.0 * x3 - 5.0 * x4) * c0
              + 0.5 * (3.0 * x2 - 8.0 * x3 + 5.0 * x4) * c1
              + (-12.0 * x2 + 28.0 * x3 - 15.0 * x4) * m1
              + (30.0 * x2 - 60.0 * x3 + 30.0 * x4) * g_hi)
        if dp == 0.0:
            break
        xn = x - p / dp
        if not 0.0 < xn < 1.0:
            break
        x = xn
    return lo + h * x


@_jit
def x1_maximum(times, free, cw, sw, Gam, B, omega, delta, ks, w, a, u0, dy, dv, work, exclude):
    """Highest interior local maximum of ``x1`` on ``(0, T)``: ``(value, time)``.

    ``free``: :func:`free_on_grid` at ``times``; ``cw, sw``: cos and sin of
    ``omega times``; ``work``: scratch of shape ``(WORK_ROWS, 2 nt)`` (reused across calls).
    Each grid cell holds at most one root of ``x1''`` (the grid is built so), hence
    at most two roots of ``x1'``:

    - ``x1''`` keeps its sign: ``x1'`` is monotone, a maximum iff ``x1'`` goes from
      ``>= 0`` to ``< 0``;
    - ``x1''`` changes sign: ``x1'`` is unimodal; with ``x1'`` of opposite signs at
      the ends there is one root and the cell brackets it; with equal signs the
      root of ``x1''`` is polished first and splits the cell in two monotone pieces.

    A candidate piece ``[p, q]`` with ``x1'`` decreasing through 0 is concave, so x1
    lies below the meeting point of its tangents at ``p`` and ``q``; candidates are
    polished (safeguarded Newton from a quintic Hermite start, :func:`_polish`) in
    decreasing order of that bound, and the search stops once the bound is below the
    best maximum found: the result is the same as polishing every one.
    A maximum within ``1e-7 T`` of the time ``exclude`` is skipped (NaN: none is),
    e.g. the tangency of a grazing motion. ``(-inf, nan)`` when there is none.
    """
    cd, sd = math.cos(delta), math.sin(delta)
    nt = times.size
    T = times[nt - 1]
    om2 = omega * omega
    x = work[0]
    v = work[1]
    acc = work[2]
    c_lo = work[3]
    c_hi = work[4]
    c_v = work[5]
    c_ub = work[6]
    c_vh = work[7]
    c_a = work[8]
    c_ah = work[9]
    # first x1, x1', x1'' on the whole grid (a branch-free loop the compiler vectorises:
    # faster than one pass that classifies each cell as it goes)
    for k in range(nt):
        c = cw[k] * cd - sw[k] * sd
        s = sw[k] * cd + cw[k] * sd
        p = Gam * c + B * s
        x[k] = p + ks * free[0, k]
        v[k] = omega * (B * c - Gam * s) + ks * free[1, k]
        acc[k] = -om2 * p + ks * free[2, k]
    m = 0
    for k in range(1, nt):
        lo, hi = times[k - 1], times[k]
        v0, v1 = v[k - 1], v[k]
        a0, a1 = acc[k - 1], acc[k]
        if (a0 < 0.0) == (a1 < 0.0) or (v0 < 0.0) != (v1 < 0.0):
            if v0 >= 0.0 and v1 < 0.0:  # one root of x1', a maximum
                m = _candidate(work, m, lo, hi, v0, v1, a0, a1,
                               _jerk(omega, ks, v0, free[1, k - 1], free[3, k - 1]),
                               _jerk(omega, ks, v1, free[1, k], free[3, k]),
                               _concave_bound(lo, hi, x[k - 1], x[k], v0, v1))
            continue
        # x1'' changes sign, x1' has one sign at both ends: zero or two roots; none when
        # x1' falls then rises from below 0, or rises then falls to >= 0
        if (a0 < 0.0) == (v0 < 0.0):
            continue
        j0 = _jerk(omega, ks, v0, free[1, k - 1], free[3, k - 1])
        j1 = _jerk(omega, ks, v1, free[1, k], free[3, k])
        tm, xm, vm, am, jm = _polish(_ORDER_ACC, lo, hi, a0, a1, j0, j1,
                                     _snap(omega, ks, x[k - 1], free[0, k - 1], free[4, k - 1]),
                                     _snap(omega, ks, x[k], free[0, k], free[4, k]),
                                     Gam, B, omega, delta, ks, w, a, u0, dy, dv)
        if v0 >= 0.0 and vm < 0.0:  # falls through 0 before the inflection
            m = _candidate(work, m, lo, tm, v0, vm, a0, am, j0, jm,
                           _concave_bound(lo, tm, x[k - 1], xm, v0, vm))
        elif vm >= 0.0 and v1 < 0.0:  # rises above 0, then falls through it
            m = _candidate(work, m, tm, hi, vm, v1, am, a1, jm, j1,
                           _concave_bound(tm, hi, xm, x[k], vm, v1))
    best = -np.inf
    best_t = np.nan
    for _ in range(m):
        j = 0
        for i in range(1, m):
            if c_ub[i] > c_ub[j]:
                j = i
        if not c_ub[j] > best:
            break
        c_ub[j] = -np.inf  # done
        best, best_t = _take(best, best_t, c_lo[j], c_hi[j], c_v[j], c_vh[j], c_a[j], c_ah[j],
                             work[10, j], work[11, j], T, Gam, B, omega, delta, ks, w, a, u0,
                             dy, dv, exclude)
    return best, best_t


@_jit
def _jerk(omega, ks, v, free_v, free_jerk):
    """The third derivative of x1 at a grid point from ``x1'`` there: the forced part's
    is ``-omega^2`` times its velocity ``x1' - ks free'``."""
    return ks * free_jerk - omega * omega * (v - ks * free_v)


@_jit
def _snap(omega, ks, x, free_x, free_snap):
    """The fourth derivative of x1 at a grid point from ``x1`` there: the forced part's
    is ``omega^4`` times its displacement ``x1 - ks free``."""
    return ks * free_snap + omega ** 4 * (x - ks * free_x)


@_jit
def _concave_bound(p, q, xp, xq, vp, vq):
    """An upper bound of x1 on ``[p, q]`` where it is concave (``x1'' < 0``) with
    ``x1'(p) >= 0 > x1'(q)``: the meeting point of the tangents at both ends."""
    t = (xq - xp + vp * p - vq * q) / (vp - vq)
    return xp + vp * (min(max(t, p), q) - p)


@_jit
def _candidate(work, m, lo, hi, v_lo, v_hi, a_lo, a_hi, j_lo, j_hi, bound):
    """Record the piece ``[lo, hi]`` where x1' falls through 0 (a maximum) as candidate ``m``
    in the rows 3-11 of ``work`` with the upper bound of x1 on it (``j``: its third
    derivative at the ends, NaN where unknown); returns ``m + 1``."""
    work[3, m] = lo
    work[4, m] = hi
    work[5, m] = v_lo
    work[6, m] = bound
    work[7, m] = v_hi
    work[8, m] = a_lo
    work[9, m] = a_hi
    work[10, m] = j_lo
    work[11, m] = j_hi
    return m + 1


@_jit
def _take(best, best_t, lo, hi, v_lo, v_hi, a_lo, a_hi, j_lo, j_hi, T, Gam, B, omega, delta, ks,
          w, a, u0, dy, dv, exclude):
    r, xr, _, acc, _ = _polish(_ORDER_VEL, lo, hi, v_lo, v_hi, a_lo, a_hi, j_lo, j_hi, Gam, B,
                            omega, delta,
                            ks, w, a, u0, dy, dv)
    if r <= _END_TOL * T or r >= (1.0 - _END_TOL) * T:
        # the impact itself, not an interior contact (with R = 0, x1' = 0 at t = 0 and
        # its rounding would otherwise place a "maximum" a few ulps after the impact)
        return best, best_t
    if abs(r - exclude) <= _EXCLUDE_TOL * T:
        return best, best_t
    if acc < 0.0 and xr > best:
        return xr, r
    return best, best_t


WORK_ROWS = 12  # rows of the scratch of x1_maximum (its grid values and candidates)
_EXCLUDE_TOL = 1e-7  # relative to T: a maximum this close to ``exclude`` is the same one


@_jit
def flight_tables(w, a, u0, modal, omega, T):
    """Per-frequency tables of the interior-contact check, shared by every gap and root.

    Returns ``(times, capped, free, cw, sw, dy, dv, work)``: the grid of
    :func:`time_grid`, the free response of :func:`free_on_grid` on it, cos and sin of
    ``omega t``, the free modal deviation per unit ``kappa sigma`` and the scratch of
    :func:`x1_maximum`.
    """
    times, capped = time_grid(w, a, u0, omega, T)
    dy = modal[6].copy()
    dv = modal[7].copy()
    free = free_on_grid(times, w, a, u0, dy, dv)
    return (times, capped, free, np.cos(omega * times), np.sin(omega * times), dy, dv,
            np.empty((WORK_ROWS, 2 * times.size)))


# -- a block of the (omega, b) plane ---------------------------------------------------------
@_jit
def block_map(w, a, f, u, ui, eig_err, R, N, omegas, bs, want_rho):
    """Every root of eq. (15) on ``omegas x bs``: existence, checks, stability.

    Returns ``r2 (nw,)``, ``cond (nw,)``, ``count (nw, nb)`` (of :func:`orbit_roots`)
    and, on ``(nw, nb, 2)``: ``delta``,
    ``impact_velocity``, ``gap_min``, ``gap_min_time``, ``stable`` (Schur-Cohn on
    the characteristic polynomial of G), ``spectral_radius`` and
    ``critical_multiplier`` (NaN unless ``want_rho``).
    """
    n = w.size
    nw = omegas.size
    nb = bs.size
    u0 = u[0].copy()
    ui0 = ui[:, 0].copy()
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
def point_orbits(w, a, f, u, ui, u0, ui0, eig_err, R, omega, N, b):
    """Every root of eq. (15) at one ``(omega, b)`` with its interior-contact check.

    Returns ``(modal, scalars, count, delta, sigma, fold_error, gap_min, gap_min_time,
    capped, states, velocity_scales, jacobians, multipliers)`` (see :func:`omega_setup`,
    :func:`orbit_roots`, :func:`x1_maximum`, :func:`physical_state`); ``jacobians``
    and ``multipliers`` hold G of each root and its eigenvalues when
    ``2n <= EAGER_JACOBIAN`` (cheaper here than later calls), empty arrays otherwise.
    """
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
            G, _ = impact_jacobian(modal, w, a, f, u, ui, omega, R, dl[k], sg[k])
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
def _balance(a):
    """Diagonal similarity by powers of 2 that equalises row and column norms (in place)."""
    m = a.shape[0]
    done = False
    while not done:
        done = True
        for i in range(m):
            r = 0.0
            c = 0.0
            for j in range(m):
                if j != i:
                    c += abs(a[j, i])
                    r += abs(a[i, j])
            if c == 0.0 or r == 0.0:
                continue
            g = r / 2.0
            f = 1.0
            total = c + r
            while c < g:
                f *= 2.0
                c *= 4.0
            g = r * 2.0
            while c > g:
                f /= 2.0
                c /= 4.0
            if (c + r) / f < 0.95 * total:
                done = False
                for j in range(m):
                    a[i, j] /= f
                for j in range(m):
                    a[j, i] *= f


@_jit
def _hqr(a, out):
    """Eigenvalues of the upper Hessenberg ``a`` by Francis double-shift QR (in place).

    The classical EISPACK ``hqr`` iteration (as in Numerical Recipes, 3rd ed.,
    ``Unsymmeig::hqr``). Returns False if an eigenvalue needs more than 60 iterations.
    """
    n = a.shape[0]
    anorm = 0.0
    for i in range(n):
        for j in range(max(i - 1, 0), n):
            anorm += abs(a[i, j])
    nn = n - 1
    t = 0.0
    p = q = r = s = w = x = y = z = 0.0
    while nn >= 0:
        its = 0
        while True:
            ll = nn
            while ll > 0:
                s = abs(a[ll - 1, ll - 1]) + abs(a[ll, ll])
                if s == 0.0:
                    s = anorm
                if abs(a[ll, ll - 1]) <= _EPS * s:
                    a[ll, ll - 1] = 0.0
                    break
                ll -= 1
            x = a[nn, nn]
            if ll == nn:  # one root found
                out[nn] = x + t
                nn -= 1
                break
            y = a[nn - 1, nn - 1]
            w = a[nn, nn - 1] * a[nn - 1, nn]
            if ll == nn - 1:  # two roots found
                p = 0.5 * (y - x)
                q = p * p + w
                z = math.sqrt(abs(q))
                x += t
                if q >= 0.0:
                    z = p + (z if p >= 0.0 else -z)
                    out[nn - 1] = x + z
                    out[nn] = x + z
                    if z != 0.0:
                        out[nn] = x - w / z
                else:
                    out[nn] = complex(x + p, -z)
                    out[nn - 1] = complex(x + p, z)
                nn -= 2
                break
            if its == 60:
                return False
            if its == 10 or its == 20:  # exceptional shift
                t += x
                for i in range(nn + 1):
                    a[i, i] -= x
                s = abs(a[nn, nn - 1]) + abs(a[nn - 1, nn - 2])
                x = 0.75 * s
                y = x
                w = -0.4375 * s * s
            its += 1
            mm = nn - 2
            while mm >= ll:
                z = a[mm, mm]
                r = x - z
                s = y - z
                p = (r * s - w) / a[mm + 1, mm] + a[mm, mm + 1]
                q = a[mm + 1, mm + 1] - z - r - s
                r = a[mm + 2, mm + 1]
                s = abs(p) + abs(q) + abs(r)
                p /= s
                q /= s
                r /= s
                if mm == ll:
                    break
                u = abs(a[mm, mm - 1]) * (abs(q) + abs(r))
                v = abs(p) * (abs(a[mm - 1, mm - 1]) + abs(z) + abs(a[mm + 1, mm + 1]))
                if u <= _EPS * v:
                    break
                mm -= 1
            for i in range(mm, nn - 1):
                a[i + 2, i] = 0.0
                if i != mm:
                    a[i + 2, i - 1] = 0.0
            for k in range(mm, nn):
                if k != mm:
                    p = a[k, k - 1]
                    q = a[k + 1, k - 1]
                    r = 0.0
                    if k + 1 != nn:
                        r = a[k + 2, k - 1]
                    x = abs(p) + abs(q) + abs(r)
                    if x != 0.0:
                        p /= x
                        q /= x
                        r /= x
                s = math.sqrt(p * p + q * q + r * r)
                if p < 0.0:
                    s = -s
                if s != 0.0:
                    if k == mm:
                        if ll != mm:
                            a[k, k - 1] = -a[k, k - 1]
                    else:
                        a[k, k - 1] = -s * x
                    p += s
                    x = p / s
                    y = q / s
                    z = r / s
                    q /= p
                    r /= p
                    for j in range(k, nn + 1):
                        p = a[k, j] + q * a[k + 1, j]
                        if k + 1 != nn:
                            p += r * a[k + 2, j]
                            a[k + 2, j] -= p * z
                        a[k + 1, j] -= p * y
                        a[k, j] -= p * x
                    mmin = nn if nn < k + 3 else k + 3
                    for i in range(ll, mmin + 1):
                        p = x * a[i, k] + y * a[i, k + 1]
                        if k + 1 != nn:
                            p += z * a[i, k + 2]
                            a[i, k + 2] -= p * r
                        a[i, k + 1] -= p * q
                        a[i, k] -= p
    return True


SMALL_EIG = 16  # matrices up to this size get the in-kernel QR; larger ones LAPACK


@_jit
def multipliers_of(G):
    """Eigenvalues of G: balanced Hessenberg QR for small G, LAPACK ``dgeev`` otherwise.

    Non-finite G gives NaN. The QR is the classical double-shift iteration on the
    balanced Hessenberg form (no allocation of LAPACK workspaces, no BLAS): about
    ten times cheaper than ``dgeev`` for 4 x 4; it falls back to ``dgeev`` if it
    does not converge.
    """
    m = G.shape[0]
    out = np.empty(m, dtype=np.complex128)
    for r in range(m):
        for col in range(m):
            if not np.isfinite(G[r, col]):
                out[:] = np.nan
                return out
    if m <= SMALL_EIG:
        a = G.copy()
        _balance(a)
        H = hessenberg(a)
        if _hqr(H, out):
            return out
    return eigvals(G)


@_jit
def eigvals(A):
    """Eigenvalues of a real square matrix by LAPACK ``dgeev`` (exact conjugate pairs).

    numba's ``np.linalg.eigvals`` refuses real input with complex eigenvalues, and
    the complex ``zgeev`` does not return exact conjugate pairs; this calls numba's
    own binding of the real routine (scipy's LAPACK, cacheable). The transpose has
    the same eigenvalues, so the row-major copy is passed as it is.
    """
    m = A.shape[0]
    a = A.copy()
    wr = np.empty(m)
    wi = np.empty(m)
    vl = np.empty(1)
    vr = np.empty(1)
    info = _rgeev(_KIND, _NO, _NO, m, a.ctypes, m, wr.ctypes, wi.ctypes, vl.ctypes, 1,
                  vr.ctypes, 1)
    out = np.empty(m, dtype=np.complex128)
    for i in range(m):
        out[i] = complex(wr[i], wi[i]) if info == 0 else np.nan
    _keep_alive(a.size + wr.size + wi.size + vl.size + vr.size)
    return out


@_jit
def _keep_alive(size):
    """``.ctypes`` does not keep its array alive; a use after the call does."""
    return size


@_jit
def multipliers(G):
    """Eigenvalues of G, largest modulus first (stable order among equal moduli)."""
    return by_modulus(multipliers_of(G))


@_jit
def by_modulus(mu):
    """``mu`` sorted by decreasing modulus, stable among equal moduli (insertion sort:
    a few entries; numba's mergesort would add seconds to the first compilation)."""
    out = mu.copy()
    size = np.abs(out)
    for i in range(1, out.size):
        z = out[i]
        r = size[i]
        j = i - 1
        while j >= 0 and size[j] < r:
            out[j + 1] = out[j]
            size[j + 1] = size[j]
            j -= 1
        out[j + 1] = z
        size[j + 1] = r
    return out


@_jit
def phase_sigma(scalars, omega, R, b, delta):
    """Impact velocity of the motion with impact phase ``delta`` (a root of eq. 14)."""
    Gam, B, g, Delta = scalars[1], scalars[2], scalars[3], scalars[4]
    cd, sd = np.cos(delta), np.sin(delta)
    if scalars[9] != 0.0:  # elastic, undamped: from the impact condition x1(0) = b
        return (Gam * cd + B * sd - b) / ((1.0 + R) * g)
    return omega * (B * cd - Gam * sd) / Delta


@_jit
def phase_orbit(w, a, f, u, u0, ui0, eig_err, R, omega, N, b, delta):
    """The motion with impact phase ``delta``: ``(modal, scalars, sigma, gap_min,
    gap_min_time, capped, state)``."""
    modal, sc = omega_setup(w, a, f, u0, ui0, eig_err, R, omega, N)
    sigma = phase_sigma(sc, omega, R, b, delta)
    state, _ = physical_state(modal, u, omega, R, delta, sigma)
    times, capped, free, cw, sw, dy, dv, work = flight_tables(w, a, u0, modal, omega, sc[0])
    best, best_t = x1_maximum(times, free, cw, sw, sc[1], sc[2], omega, delta,
                              (1.0 + R) * sigma, w, a, u0, dy, dv, work, np.nan)
    return modal, sc, sigma, b - best, best_t, capped, state


@_jit
def other_maximum(w, a, u0, modal, scalars, omega, R, delta, sigma, exclude):
    """Highest interior maximum of ``x1`` other than the one at time ``exclude``:
    ``(value, time)``, ``(-inf, nan)`` when there is none (:func:`x1_maximum`)."""
    times, _, free, cw, sw, dy, dv, work = flight_tables(w, a, u0, modal, omega, scalars[0])
    return x1_maximum(times, free, cw, sw, scalars[1], scalars[2], omega, delta,
                      (1.0 + R) * sigma, w, a, u0, dy, dv, work, exclude)

"""The compiled first-order periodic form: N-1 motions with any damping matrix C, O(n^2).

The numba counterpart of :mod:`impactcont.orbit.general` (which documents eq. 12-15 in
the first-order modal form, :class:`impactcont.orbit.general.PeriodicForm`; its numpy
implementation is kept there as the reference of this one). Everything here is a
function of floats and arrays (``cache=True``), in five entry points with explicit
argument types (each compiled once, when this module is first imported):

- :func:`forced_response`: ``x_hat`` of ``(K - omega^2 M + i omega C) x_hat = F`` by a
  row- and column-equilibrated solve, with the 2-norm condition number of the
  equilibrated dynamic stiffness (:meth:`impactcont.model.first_order.FirstOrderBasis.
  forced_amplitude` raises and warns from it), and its exact omega derivative
  (:func:`forced_response_derivative`);
- :func:`periodic_setup`: the pieces of eq. (12)-(14) at one frequency in the impact's
  rank-one form (``D Phi(T)``, ``P(0)``, ``P'(0)``, ``E(T)``, ``y``, ``V^-1 y``,
  ``A (y + e)``, ``S``), ``g``, ``Delta``, the condition estimate of eq. (12) and the
  rows of ``d y / dT`` the exact omega derivative of ``c, s`` needs; and
  :func:`amplitude_setup`, those scalars alone in O(n) (the continuation's eq. 14);
- :func:`orbit_values`: per impact phase (a root of eq. 15) the impact velocity from the
  better of its two exact forms, the state ``X(0)``, G of eq. (25), its eigenvalues and
  the interior-contact check of eq. (16) (the search of
  :func:`impactcont.kernel.contact.x1_maximum` on the scalar pairs of modes, its tables
  built once per call for every phase).

Complex ``expm1`` and complex division are written out as numpy computes them
(numba's complex ``expm1`` loses digits for a small argument, and its complex
division raises on zero where numpy gives inf/NaN). Importing :mod:`impactcont` does
not import this module.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from impactcont.kernel.contact import WORK_ROWS, free_on_grid, time_grid, x1_maximum
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.jit import typed_entry
from impactcont.kernel.linalg import _cdiv, _solve_in_place
from impactcont.kernel.stability import multipliers

__all__ = ["amplitude_setup", "forced_response", "forced_response_derivative",
           "orbit_values", "periodic_setup"]

_EPS = 2.220446049250313e-16
# the constants of the numpy reference (tests/kernel/test_general.py checks they agree)
VELOCITY_POLISH = 1e-12  # impactcont.orbit.dense.VELOCITY_POLISH
VELOCITY_AGREE = 16.0  # impactcont.orbit.dense._VELOCITY_AGREE
BERNOULLI = np.array([  # impactcont.model.first_order._BERNOULLI: B_2k / (2k)!
    8.3333333333333333333e-2, -1.3888888888888888889e-3, 3.3068783068783068783e-5,
    -8.2671957671957671958e-7, 2.0876756987868098979e-8, -5.2841901386874931848e-10,
    1.3382536530684678833e-11, -3.3896802963225828668e-13, 8.5860620562778445641e-15,
    -2.174868698558061873e-16, 5.5090028283602295152e-18])
SERIES_RADIUS = 1.0  # impactcont.model.first_order._SERIES_RADIUS
#: From this order of D Phi(T) (2n; n = 32 degrees of freedom, as the modal kernel's
#: ``BLAS_MIN``) :func:`periodic_setup` leaves ``D Phi(T)`` to numpy's BLAS (the caller).
BLAS_MIN = 64


_f8 = nb.float64
_f8_1 = nb.float64[::1]
_f8_2 = nb.float64[:, ::1]
_c16_1 = nb.complex128[::1]
_c16_2 = nb.complex128[:, ::1]
_i8_1 = nb.int64[::1]


def _entry(*argument_types):
    """An entry point compiled once for exactly these argument types."""
    return typed_entry(argument_types)


# -- complex scalars as numpy computes them ----------------------------------------------------
@_inner
def _cexpm1(x):
    """``exp(x) - 1`` of a complex x without cancellation (numpy's formula)."""
    half = math.sin(0.5 * x.imag)
    return complex(math.expm1(x.real) * math.cos(x.imag) - 2.0 * half * half,
                   math.exp(x.real) * math.sin(x.imag))


@_inner
def _coth_remainder(x, em1):
    """``s(x) = 1/expm1(x) + 1/2 - 1/x`` and ``s'(x)``
    (:func:`impactcont.model.first_order.coth_remainder`); ``em1 = expm1(x)``."""
    if abs(x) < SERIES_RADIUS:  # Horner in x^2: s = sum_k B_2k / (2k)! x^(2k-1) and s'
        x2 = x * x
        acc = 0j
        dacc = 0j
        for k in range(BERNOULLI.size, 0, -1):
            acc = acc * x2 + BERNOULLI[k - 1]
            dacc = dacc * x2 + (2 * k - 1) * BERNOULLI[k - 1]
        return acc * x, dacc
    return (_cdiv(1.0 + 0j, em1) + 0.5 - _cdiv(1.0 + 0j, x),
            _cdiv(1.0 + 0j, x * x) - _cdiv(em1 + 1.0, em1 * em1))


# -- the forced response ------------------------------------------------------------------------
@_jit
def _power_of_two_scale(v):
    """``2^-round(log2 v)`` where ``v > 0`` (1 elsewhere): an exact rescaling."""
    return np.exp2(-np.round(np.log2(v))) if v > 0.0 else 1.0


@_inner
def _solve(H, rhs):
    """``H^-1 rhs`` (complex, in place: H and rhs are overwritten) by
    :func:`impactcont.kernel.linalg._solve_in_place` (partial pivoting as LAPACK ``zgesv``
    pivots, largest ``|Re| + |Im|``); NaN when a pivot is exactly zero. numba's
    ``np.linalg.solve`` would add seconds to the first compilation."""
    if not _solve_in_place(H, rhs):
        rhs[:] = complex(np.nan, np.nan)
    return rhs


@_entry(_f8_2, _f8_2, _f8_2, _c16_1, _f8)
def forced_response(K, M, C, F, omega):
    """The complex amplitude ``Z = [x_hat; i omega x_hat]`` of the steady forced state,
    ``(K - omega^2 M + i omega C) x_hat = F``, and the 2-norm condition number of the row-
    and column-equilibrated dynamic stiffness (inf when singular or not finite; ``Z`` is
    then NaN).

    Returns
    -------
    Z : ndarray, shape (2n,), complex
    cond : float
    """
    n = K.shape[0]
    H = np.empty((n, n), dtype=np.complex128)
    for r in range(n):
        for c in range(n):
            H[r, c] = complex(K[r, c] - omega * omega * M[r, c], omega * C[r, c])
    rows = np.empty(n)
    cols = np.empty(n)
    finite = True
    for r in range(n):
        big = 0.0
        for c in range(n):
            big = max(big, abs(H[r, c]))
            finite = finite and np.isfinite(H[r, c].real) and np.isfinite(H[r, c].imag)
        rows[r] = _power_of_two_scale(big)
    for c in range(n):
        big = 0.0
        for r in range(n):
            big = max(big, abs(rows[r] * H[r, c]))
        cols[c] = _power_of_two_scale(big)
    Z = np.full(2 * n, complex(np.nan, np.nan))
    if not finite:
        return Z, np.inf
    rhs = np.empty(n, dtype=np.complex128)
    for r in range(n):
        rhs[r] = rows[r] * F[r]
        for c in range(n):
            H[r, c] = rows[r] * H[r, c] * cols[c]
    cond = np.linalg.cond(H)
    if not (np.isfinite(cond) and cond * _EPS < 1.0):
        return Z, np.inf
    sol = _solve(H, rhs)
    iw = complex(0.0, omega)
    for r in range(n):
        Z[r] = cols[r] * sol[r]
        Z[n + r] = iw * Z[r]
    return Z, cond


@_entry(_f8_2, _f8_2, _f8_2, _c16_1, _f8)
def forced_response_derivative(K, M, C, Z, omega):
    """``dZ / d omega`` of :func:`forced_response` (exact): ``d x_hat = -H^-1 (-2 omega M +
    i C) x_hat`` with ``H = K - omega^2 M + i omega C``, ``Z = [x_hat; i omega x_hat]``.

    Returns
    -------
    ndarray, shape (2n,), complex
    """
    n = K.shape[0]
    H = np.empty((n, n), dtype=np.complex128)
    rhs = np.zeros(n, dtype=np.complex128)
    for r in range(n):
        for c in range(n):
            H[r, c] = complex(K[r, c] - omega * omega * M[r, c], omega * C[r, c])
            rhs[r] += complex(-2.0 * omega * M[r, c], C[r, c]) * Z[c]
    dx = _solve(H, rhs)
    dZ = np.empty(2 * n, dtype=np.complex128)
    for r in range(n):
        dZ[r] = -dx[r]
        dZ[n + r] = 1j * Z[r] + complex(0.0, omega) * dZ[r]
    return dZ


# -- eq. (12)-(14) at one frequency -------------------------------------------------------------
@_inner
def _transition_into(V, Vi, em1, R, DPhi):
    """``D Phi(T) = D (I + Re(V diag(expm1(lambda T)) V^-1))`` into ``DPhi``: only the real
    part, in loops over real rows that the compiler vectorises (numba's BLAS ``np.dot``
    would add a second to the first compilation; from :data:`BLAS_MIN` the caller takes
    numpy's instead)."""
    m = V.shape[0]
    n = m // 2
    Vi_re = np.empty((m, m))
    Vi_im = np.empty((m, m))
    for k in range(m):
        for c in range(m):
            Vi_re[k, c] = Vi[k, c].real
            Vi_im[k, c] = Vi[k, c].imag
            DPhi[k, c] = 0.0
    for r in range(m):
        for k in range(m):
            v = V[r, k] * em1[k]
            a = v.real
            b = v.imag
            for c in range(m):
                DPhi[r, c] += a * Vi_re[k, c] - b * Vi_im[k, c]
    for r in range(m):
        for c in range(m):
            DPhi[r, c] = (DPhi[r, c] + 1.0 if r == c else DPhi[r, c]) * (
                -R if r == n else 1.0)


@_jit
def _condition(V, Vi, pk, pj, x, em1, sw, w, R, omega, g, Delta):
    """The condition estimate of eq. (12) summed over the scalar pairs of modes
    (:func:`impactcont.orbit.general._condition`)."""
    n = pk.size
    kappa = 1.0 + R
    ci = np.empty(n)
    ci_sum = 0.0
    h_sum = 0.0
    g_sum = 0.0
    for i in range(n):
        k, j = pk[i], pj[i]
        ci[i] = (V[0, k] * Vi[k, 0] + V[0, j] * Vi[j, 0]).real
        ci_sum += abs(ci[i])
        h_sum += abs((V[n, k] * sw[k] + V[n, j] * sw[j]).real)
        g_sum += abs((V[0, k] * _cdiv(w[k], em1[k]) + V[0, j] * _cdiv(w[j], em1[j])).real)
    mode_cond = 1.0
    for i in range(n):
        k = pk[i]
        if x[k].imag != 0.0 and abs(ci[i]) > 1e-12 * ci_sum:
            e = em1[k]
            resonance = 1.0 + abs(x[k].imag) * abs(e.imag) / abs(e) ** 2
            if resonance > mode_cond or resonance != resonance:  # NaN propagates, as np.max
                mode_cond = resonance
    rho = kappa * omega * g / max(abs(Delta), 1e-300)
    cond_d = (0.5 * (1.0 - R) + kappa * h_sum) / max(abs(Delta), 1e-300)
    cond_g = g_sum / max(abs(g), 1e-300)
    cond = mode_cond * (1.0 + abs(rho) * (cond_d + cond_g))
    return cond if np.isfinite(cond) else np.inf


@_jit
def form_rows(pieces):
    """Views of the rows of :func:`periodic_setup`'s ``pieces``: ``DPhi`` (2n, 2n) and
    ``P0, rate0, E, S`` (2n, 2) as transposes of two rows each, ``y`` and ``rate``
    (:class:`impactcont.orbit.general.PeriodicForm`)."""
    m = pieces.shape[1]
    return (pieces[:m], pieces[m:m + 2].T, pieces[m + 2:m + 4].T, pieces[m + 4:m + 6].T,
            pieces[m + 6:m + 8].T, pieces[m + 8], pieces[m + 9])


@_inner
def _modal_terms(lam, Vi, T):
    """Per complex mode over the period: ``x = lambda T``, ``expm1(x)``, ``w = V^-1
    e_{n+1}``, ``s(x) w`` and ``lambda s'(x) w`` (:func:`_coth_remainder`)."""
    m = lam.size
    n = m // 2
    x = np.empty(m, dtype=np.complex128)
    em1 = np.empty(m, dtype=np.complex128)
    w = np.empty(m, dtype=np.complex128)
    sw = np.empty(m, dtype=np.complex128)
    dsw = np.empty(m, dtype=np.complex128)
    for k in range(m):
        x[k] = lam[k] * T
        em1[k] = _cexpm1(x[k])
        w[k] = Vi[k, n]
        s_k, ds_k = _coth_remainder(x[k], em1[k])
        sw[k] = s_k * w[k]
        dsw[k] = lam[k] * ds_k * w[k]
    return x, em1, w, sw, dsw


@_entry(_c16_1, _c16_2, _c16_2, _f8_1, _i8_1, _i8_1, _c16_1, _f8, _f8, _f8)
def amplitude_setup(lam, V, Vi, impact_column, pk, pj, Z, omega, R, T):
    """The scalars of :func:`periodic_setup` alone (``c, s`` of eq. 14 and what their
    exact derivatives need), from rows 1 and ``n + 1`` only: O(n) after the forced
    amplitude, the same sums in the same order (equal results).

    Returns
    -------
    scalars : ndarray, shape (7,)
        As :func:`periodic_setup`'s.
    """
    m = lam.size
    n = m // 2
    kappa = 1.0 + R
    x, em1, w, sw, dsw = _modal_terms(lam, Vi, T)
    part_0 = 0.0
    part_n = 0.0
    d0 = 0.0
    dn = 0.0
    for k in range(m):
        part_0 += (V[0, k] * sw[k]).real
        part_n += (V[n, k] * sw[k]).real
        d0 += (V[0, k] * dsw[k]).real
        dn += (V[n, k] * dsw[k]).real
    y0 = impact_column[0] / T + part_0
    Delta = 0.5 * (1.0 - R) - kappa * part_n
    g = -y0
    scalars = np.empty(7)
    scalars[0] = g
    scalars[1] = Delta
    scalars[2] = _condition(V, Vi, pk, pj, x, em1, sw, w, R, omega, g, Delta)
    scalars[3] = d0
    scalars[4] = dn
    scalars[5] = Z[0].real + kappa * (y0 * (Z[n].real / Delta))
    scalars[6] = -Z[0].imag + kappa * (y0 * (-Z[n].imag / Delta))
    return scalars


@_entry(_c16_1, _c16_2, _c16_2, _f8_2, _f8_1, _i8_1, _i8_1, _c16_1, _f8, _f8, _f8)
def periodic_setup(lam, V, Vi, A, impact_column, pk, pj, Z, omega, R, T):
    """Eq. (12)-(14) at one frequency in the rank-one form of
    :class:`impactcont.orbit.general.PeriodicForm` (the arrays of
    :attr:`impactcont.model.first_order.FirstOrderBasis.kernel_arrays`, the forced
    amplitude ``Z`` and ``T = 2 pi N / omega``).

    Returns
    -------
    pieces : ndarray, shape (2n + 10, 2n)
        The real fields of :class:`~impactcont.orbit.general.PeriodicForm` as rows
        (:func:`form_rows`): ``D Phi(T)`` (left unset from :data:`BLAS_MIN`: the caller's),
        then the columns of ``P0``, ``rate0``, ``E`` and ``S``, then ``y`` and ``rate``.
    y_modal : ndarray, shape (2n,), complex
    scalars : ndarray, shape (7,)
        ``g, Delta, cond``, ``Re(V diag(lambda s'(lambda T)) V^-1 e_{n+1})`` at rows 1
        and ``n + 1`` (the ``T``-derivative of ``y`` less ``-A^-1 e / T^2``) and ``c, s``
        of eq. (14) (the first row of ``S``).
    """
    m = lam.size
    n = m // 2
    kappa = 1.0 + R
    x, em1, w, sw, dsw = _modal_terms(lam, Vi, T)
    y_modal = np.empty(m, dtype=np.complex128)
    for k in range(m):
        y_modal[k] = _cdiv(w[k], em1[k])
    pieces = np.empty((m + 10, m))
    DPhi, P0, rate0, E, S, y, rate = form_rows(pieces)
    iw = complex(0.0, omega)
    part_n = 0.0
    for r in range(m):
        part = 0.0
        for k in range(m):
            part += (V[r, k] * sw[k]).real
        y[r] = impact_column[r] / T + part
        if r == n:
            part_n = part
        P0[r, 0] = Z[r].real
        P0[r, 1] = -Z[r].imag
        q = iw * Z[r]
        rate0[r, 0] = q.real
        rate0[r, 1] = -q.imag
    y[n] -= 0.5
    Delta = 0.5 * (1.0 - R) - kappa * part_n
    g = -y[0]
    # E = -Re(V diag(expm1(lambda T)) V^-1 P0), the forcing columns over a period
    VP = np.zeros((m, 2), dtype=np.complex128)
    for k in range(m):
        for r in range(m):
            VP[k, 0] += Vi[k, r] * P0[r, 0]
            VP[k, 1] += Vi[k, r] * P0[r, 1]
        VP[k, 0] *= em1[k]
        VP[k, 1] *= em1[k]
    for r in range(m):
        E[r, 0] = 0.0
        E[r, 1] = 0.0
        for k in range(m):
            E[r, 0] -= (V[r, k] * VP[k, 0]).real
            E[r, 1] -= (V[r, k] * VP[k, 1]).real
    if m < BLAS_MIN:  # else D Phi(T) by the caller (numpy's BLAS), its rows left unset
        _transition_into(V, Vi, em1, R, DPhi)
    for r in range(m):
        acc = 0.0
        for c in range(m):
            acc += A[r, c] * (y[c] + 1.0 if c == n else y[c])
        rate[r] = acc
    for r in range(m):
        for c in range(2):
            S[r, c] = P0[r, c] + kappa * (y[r] * (P0[n, c] / Delta))
    scalars = np.empty(7)
    scalars[0] = g
    scalars[1] = Delta
    scalars[2] = _condition(V, Vi, pk, pj, x, em1, sw, w, R, omega, g, Delta)
    d0 = 0.0
    dn = 0.0
    for k in range(m):
        d0 += (V[0, k] * dsw[k]).real
        dn += (V[n, k] * dsw[k]).real
    scalars[3] = d0
    scalars[4] = dn
    scalars[5] = S[0, 0]
    scalars[6] = S[0, 1]
    return pieces, y_modal, scalars


# -- one motion per impact phase ----------------------------------------------------------------
@_inner
def _velocity(Gam, B, g, Delta, omega, R, b, delta, cd, sd):
    """The impact velocity from the better of its two exact forms and its relative error
    (:meth:`impactcont.orbit.general.PeriodicForm.velocity_at`)."""
    tilt = 1.0 + abs(delta)
    xp = abs(Gam * cd + B * sd)
    vp = abs(B * cd - Gam * sd)
    err_a = _EPS * omega * (abs(B * cd) + abs(Gam * sd) + xp * tilt) / (abs(Delta) + 1e-300)
    err_b = _EPS * (abs(Gam * cd) + abs(B * sd) + abs(b) + vp * tilt) / (
        abs((1.0 + R) * g) + 1e-300)
    first = omega * (B * cd - Gam * sd) / Delta if Delta != 0.0 else np.inf
    if err_b < err_a and g != 0.0:
        second = (Gam * cd + B * sd - b) / ((1.0 + R) * g)
        if (err_a > VELOCITY_POLISH * abs(first) and err_b < err_a
                and abs(first - second) <= VELOCITY_AGREE * (err_a + err_b)):
            return second, err_b / max(abs(second), 1e-300)
    return first, err_a / max(abs(first), 1e-300)


@_jit
def _pair_coefficients(coef, lam, pk, pj):
    """``y(0), y'(0)`` of each scalar pair from the complex coefficients of ``x1``'s free
    part (:func:`impactcont.orbit.general._pair_coefficients`)."""
    n = pk.size
    dy = np.empty(n)
    dv = np.empty(n)
    for i in range(n):
        k, j = pk[i], pj[i]
        if abs(lam[k].imag) > 0.0:  # a conjugate pair: Re((c_k + conj c_j) e^{lam_k t})
            total = coef[k] + np.conj(coef[j])
            dy[i] = total.real
            dv[i] = (total * lam[k]).real
        else:
            dy[i] = (coef[k] + coef[j]).real
            dv[i] = (coef[k] * lam[k] + coef[j] * lam[j]).real
    return dy, dv


@_inner
def _jacobian_into(DPhi, E, rate0, rate, omega, R, h2, cd, sd, G):
    """G of eq. (25) at one phase (:func:`impactcont.orbit.general.orbit_values`)."""
    m = DPhi.shape[0]
    n = m // 2
    dE = np.empty(m)
    dX = np.empty(m)
    for r in range(m):
        d = -R if r == n else 1.0
        dE[r] = d * (E[r, 1] * cd - E[r, 0] * sd)
        dX[r] = d * (rate0[r, 0] * cd + rate0[r, 1] * sd + (1.0 + R) * h2 * rate[r])
    for r in range(m - 1):
        for c in range(m - 1):
            G[r, c] = DPhi[r + 1, c + 1] - dX[r + 1] * DPhi[0, c + 1] / h2
        G[r, m - 1] = dE[r + 1] - dX[r + 1] * dE[0] / h2
    for c in range(m - 1):
        G[m - 1, c] = -omega * DPhi[0, c + 1] / h2
    G[m - 1, m - 1] = 1.0 - omega * dE[0] / h2


@_entry(_f8_2, _c16_1, _c16_1, _c16_1, _f8_1, _f8_1, _i8_1, _i8_1, _f8, _f8, _f8, _f8, _f8,
        _f8_1, _f8_1)
def orbit_values(pieces, y_modal, V0, lam, pw, pa, pk, pj, omega, R, T, g, Delta, deltas, b):
    """The motions with impact phases ``deltas`` (roots of eq. 15 at the gaps ``b``) from
    the pieces of :func:`periodic_setup` (``V0``: the first row of ``V``; ``pw, pa, pk,
    pj``: the scalar pairs of modes).

    Returns
    -------
    values : ndarray, shape (5, m)
        Rows ``h2`` (the impact velocity), its estimated relative error, the velocity
        scale ``max(|x'|, omega |x|)`` of the state, ``gap_min`` (``b`` less the highest
        interior maximum of ``x1``, eq. 16; inf when there is none) and its time (NaN).
    states : ndarray, shape (m, 2n)
        ``X(0)``, with ``x1' = -R h2`` exactly (eq. 4).
    G : ndarray, shape (m, 2n, 2n)
    mu : ndarray, shape (m, 2n), complex
        Eigenvalues of each G, largest modulus first (NaN when G is not finite).
    capped : bool
        The search grid was capped (a short excursion may be missed).
    """
    DPhi, P0, rate0, E, _, y, rate = form_rows(pieces)
    size = DPhi.shape[0]
    n = size // 2
    count = deltas.size
    kappa = 1.0 + R
    Gam, B = P0[0, 0], P0[0, 1]
    values = np.empty((5, count))
    states = np.empty((count, size))
    G = np.empty((count, size, size))
    mu = np.empty((count, size), dtype=np.complex128)
    capped = False
    if count == 0:
        return values, states, G, mu, capped
    # x1's free part is kappa sigma Re sum_k V_1k (V^-1 y)_k e^{lambda_k t}: one search
    # table per unit velocity, shared by every phase
    coef = np.empty(size, dtype=np.complex128)
    for k in range(size):
        coef[k] = V0[k] * y_modal[k]
    dy, dv = _pair_coefficients(coef, lam, pk, pj)
    ones = np.ones(n)
    times, capped = time_grid(pw, pa, ones, omega, T)
    free = free_on_grid(times, pw, pa, ones, dy, dv)
    cw = np.cos(omega * times)
    sw = np.sin(omega * times)
    work = np.empty((WORK_ROWS, 2 * times.size))
    for i in range(count):
        delta = deltas[i]
        cd, sd = math.cos(delta), math.sin(delta)
        sigma, values[1, i] = _velocity(Gam, B, g, Delta, omega, R, b[i], delta, cd, sd)
        values[0, i] = sigma
        _jacobian_into(DPhi, E, rate0, rate, omega, R, sigma, cd, sd, G[i])
        mu_i = multipliers(G[i])
        for r in range(size):
            mu[i, r] = mu_i[r]
        scale = 0.0
        for r in range(size):
            states[i, r] = P0[r, 0] * cd + P0[r, 1] * sd + kappa * sigma * y[r]
        states[i, n] = -R * sigma  # eq. (4)
        for r in range(n):
            scale = max(scale, abs(states[i, n + r]), omega * abs(states[i, r]))
        values[2, i] = scale
        best, values[4, i] = x1_maximum(times, free, cw, sw, Gam, B, omega, delta,
                                        kappa * sigma, pw, pa, ones, dy, dv, work, np.nan)
        values[3, i] = b[i] - best
    return values, states, G, mu, capped

"""Stability of a fixed point from its Jacobian G (eq. 25): with and without eigenvalues.

Without eigenvalues: the characteristic polynomial of G from its Hessenberg form
(Householder reflections) and the Schur-Cohn recursion decide whether every
multiplier lies strictly inside the unit circle (:func:`charpoly`,
:func:`schur_stable`). The multipliers themselves: the balanced Hessenberg
double-shift QR (EISPACK ``hqr``) for small G, LAPACK ``dgeev`` (scipy's, through
numba's binding) otherwise (:func:`multipliers_of`, :func:`eigvals`), sorted by
decreasing modulus (:func:`multipliers`, :func:`by_modulus`).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numba.np.linalg import _LAPACK, ensure_lapack

from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner

__all__ = ["by_modulus", "charpoly", "eigvals", "hessenberg", "multipliers", "multipliers_of",
           "schur_stable"]


ensure_lapack()  # numba's LAPACK bindings resolve to scipy's
_rgeev = _LAPACK().numba_ez_rgeev(nb.float64)
_KIND = np.int8(ord("d"))
_NO = np.int8(ord("N"))

_EPS = 2.220446049250313e-16


# -- stability without eigenvalues -----------------------------------------------------------------
@_jit
def hessenberg(A):
    """Upper Hessenberg form of A by Householder reflections (similar to A)."""
    H = A.copy()
    _hessenberg_in_place(H, np.empty(A.shape[0]))
    return H


@_inner
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


@_inner
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


@_inner
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


@_inner
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


@_inner
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


@_inner
def _multipliers_into(G, out, a, v, size):
    """:func:`multipliers` of G into ``out`` (m, complex) with the scratch ``a`` (m, m),
    ``v`` and ``size`` (m): the same arithmetic, no array allocated (but by the LAPACK
    fallback)."""
    m = G.shape[0]
    finite = True
    for r in range(m):
        for col in range(m):
            if not np.isfinite(G[r, col]):
                finite = False
    if not finite:
        out[:] = np.nan
    else:
        done = False
        if m <= SMALL_EIG:
            a[:, :] = G
            _balance(a)
            _hessenberg_in_place(a, v)
            done = _hqr(a, out)
        if not done:
            out[:] = eigvals(G)
    _by_modulus_in_place(out, size)


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


@_inner
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
    _by_modulus_in_place(out, np.empty(out.size))
    return out


@_inner
def _by_modulus_in_place(out, size):
    """:func:`by_modulus` of ``out`` in place; ``size``: scratch of its size."""
    for i in range(out.size):
        size[i] = np.abs(out[i])
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

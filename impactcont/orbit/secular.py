"""Multipliers of G (eq. 25) for large systems: a 2 x 2 secular function, O(n) per evaluation.

Write the perturbation of the impact map on the whole state and the phase,
``[dX; d delta]`` (size 2n + 1). Over one period the flow is ``A = [[Phi, dE], [0, 1]]``
with ``Phi = U W(T) U^-1`` (eq. 9) and ``dE`` the phase derivative of the forcing
term (eq. 22); the impact then corrects the time (``dt = -dx1 / h2``) and reverses
the velocity of mass 1 (eq. 4). Together

    M = (I - Q E^T) A,   E = [e_v1, e_x1],   Q = [kappa e_v1, [D dX; omega] / h2],

with ``kappa = 1 + R``, ``D = I - kappa e_v1 e_v1^T`` and ``dX = [x'(T-); x''(T-)]``.
``M`` has a zero row (``dx1 = 0`` on the impact section), so its eigenvalues are
those of G and one 0. By the matrix determinant lemma

    det(mu - M) = det(mu - A) det S(mu),   S(mu) = I - E^T Q + mu E^T (mu - A)^-1 Q,

and in modal coordinates ``(mu - A)^-1`` is a 2 x 2 block per mode plus the phase:
every entry of the 2 x 2 matrix ``S`` is a sum over the modes of
``(alpha_i mu + beta_i) / d_i(mu)``, ``d_i = det(mu - W_i)``, O(n) per evaluation.

The multipliers are the zeros of the degree-2n polynomial
``det(mu - A) det S(mu) / mu``; they are found together by the Aberth-Ehrlich
iteration (as in MPSolve's secular solver) from the modal multipliers, using only
the logarithmic derivative ``sum_i d_i'/d_i + 1/(mu - 1) + (det S)'/det S - 1/mu``.
Cost: O(n) per root and sweep instead of the O(n^3) of a dense eigenvalue solve.

Modal multipliers below ``DEAD`` (the fast decay of over-damped modes) are set apart as
exact zeros: left in, they would make a near-multiple root at 0 that a root finder
working from function values resolves only to about ``eps^(1/k)`` (a ring of 1e-8
spurious multipliers for a heavily damped chain), while the eigenvalues of G there
are well conditioned. Clusters of small but not negligible multipliers keep a
smaller absolute error of that kind: up to 1e-11 was seen for multipliers of size
1e-11 (random over-damped 2-DOF systems; this path serves n >= ``SECULAR_MIN``).

The accuracy guard: the result is accepted only if every root converged and the
first two power sums of the roots agree with ``tr G = tr M`` and ``tr G^2 = tr M^2``
(both O(n) in closed form) to ``POWER_SUM_TOL`` relative to the sizes of the roots and
of the terms of those traces; otherwise the caller falls back to
the dense eigenvalues of G.

A guard before it: the rank-two form sees the impact velocity as the velocity of mass 1
in modal coordinates, ``h2 = sum_i u_1i v_i`` (``v = z'(T^-)``), and its zero row needs
``e_x1^T Q = [0, 1]`` exactly. Far above the lowest natural frequency the forced modal
velocities nearly vanish at the impact and ``h2`` is a small difference of their terms
(issue 19: 6e-10 relative for a 16-mass chain at ``omega = 1e4 omega_1``, R = 0.8, and
the multipliers with it), a loss no later test sees (the power sums are of the same
pieces). The secular path is refused (``ok`` False: the caller takes the eigenvalues of
G with the motion's own velocity as its pole,
:func:`impactcont.orbit.periodic.modal_jacobian`) where the rounding bound of that sum
(:func:`velocity_row_error`) exceeds :data:`impactcont.orbit.dense.VELOCITY_POLISH` of the
motion's velocity ``sigma``. Chains up to n = 200 at ordinary frequencies stay below
1.1e-13 (relative).
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.closed_form import jacobian_pieces
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.stability import by_modulus
from impactcont.orbit.dense import VELOCITY_POLISH

__all__ = ["DEAD", "POWER_SUM_TOL", "SECULAR_MIN", "power_sums_agree", "secular_multipliers",
           "velocity_row_error"]

_EPS = float(np.finfo(np.float64).eps)  # unit roundoff of float64, a compile-time constant

SECULAR_MIN = 16
"""Systems with at least this many degrees of freedom get their multipliers here (below,
the dense G and its eigenvalues cost less)."""
POWER_SUM_TOL = 1e-9
"""Largest accepted ``|sum mu^k - tr G^k| / sum |mu|^k`` (k = 1, 2) of the roots."""
_MAX_SWEEPS = 200
_STAGNATION = 1e-9  # a root whose correction stops shrinking below this (relative) is done
DEAD = _EPS
"""Modal multipliers (eigenvalues of ``W_i(T)``, dimensionless) below this are set apart as
exact zeros: the fast decay of over-damped modes, modes that die out within the period."""


@_jit
def _modal_multipliers(t, p):
    """Both eigenvalues of a 2 x 2 block from its trace and determinant, without
    cancellation (the smaller of a real pair as ``p / larger``); larger modulus first."""
    disc = 0.25 * t * t - p
    if disc >= 0.0:
        big = 0.5 * t + math.copysign(math.sqrt(disc), t)
        small = p / big if big != 0.0 else 0.0
        return complex(big), complex(small)
    root = 1j * math.sqrt(-disc)
    return 0.5 * t + root, 0.5 * t - root


@_jit
def secular_coefficients(modal, u0, ui0, omega, R, e_y, e_v, v_pre, acc):
    """The modal pieces of ``S(mu)``: ``(coef, kind, t, p, lam, const, zeros, h2, xn)``.

    ``coef[k, 0, i] mu + coef[k, 1, i]`` over ``d_i(mu) = mu^2 - t_i mu + p_i`` is mode
    i's share of ``row^T (mu - W_i)^-1 column``: rows ``v`` (velocity of mass 1, even
    k) and ``x`` (its displacement, odd k); columns ``kappa e_v1`` (k = 0, 1),
    ``D dX / h2`` (k = 2, 3) and ``dE`` (k = 4, 5, entering with ``omega / (h2 (mu-1))``).

    A modal multiplier below ``DEAD`` (the fast decay of an over-damped mode, or both
    of a mode that has died out over the period) is taken as exactly 0: it is a zero
    of ``det(mu - A)`` set apart (``zeros`` counts them, less M's extra zero), and
    the mode's share of ``mu S`` loses that pole: ``kind`` 1 keeps the one pole
    ``lam_i``, ``kind`` 0 leaves the constant ``const[k]``. Left in, such multipliers
    make a near-multiple root at 0 that no root finder resolves from values.
    """
    n = modal.shape[1]
    kappa = 1.0 + R
    h2 = 0.0
    xn = 0.0
    for i in range(n):
        h2 += u0[i] * v_pre[i]
        xn += u0[i] * acc[i]
    coef = np.empty((6, 2, n))
    kind = np.empty(n, dtype=np.int64)
    t = np.empty(n)
    p = np.empty(n)
    lam = np.empty(n, dtype=np.complex128)
    const = np.zeros(6)
    cols = np.empty((3, 2))
    removed = 0
    for i in range(n):
        w11, w12, w21, w22 = modal[2, i], modal[3, i], modal[4, i], modal[5, i]
        t[i] = w11 + w22
        p[i] = w11 * w22 - w12 * w21
        big, small = _modal_multipliers(t[i], p[i])
        lam[i] = big
        kind[i] = 2 if abs(small) > DEAD else 1 if abs(big) > DEAD else 0
        removed += 2 - kind[i]
        cols[0, 0] = 0.0
        cols[0, 1] = kappa * ui0[i]
        cols[1, 0] = v_pre[i] / h2
        cols[1, 1] = (acc[i] - kappa * ui0[i] * xn) / h2
        cols[2, 0] = e_y[i]
        cols[2, 1] = e_v[i]
        for k in range(3):
            cy, cv = cols[k, 0], cols[k, 1]
            coef[2 * k, 0, i] = u0[i] * cv
            coef[2 * k, 1, i] = u0[i] * (w21 * cy - w11 * cv)
            coef[2 * k + 1, 0, i] = u0[i] * cy
            coef[2 * k + 1, 1, i] = u0[i] * (w12 * cv - w22 * cy)
            if kind[i] == 0:  # mu (alpha mu + 0) / mu^2
                const[2 * k] += coef[2 * k, 0, i]
                const[2 * k + 1] += coef[2 * k + 1, 0, i]
    return coef, kind, t, p, lam, const, removed - 1, h2, xn


@_jit
def log_derivative(mu, coef, kind, t, p, lam, const, zeros, omega, R, h2, xn):
    """``F'(mu) / F(mu)`` of the polynomial whose zeros are the multipliers not set apart, O(n).

    ``F = det(mu - A) det S(mu) / mu`` when no modal multiplier is set apart
    (``zeros = -1``); otherwise ``det(mu - A)`` without its zeros at 0, times
    ``det S(mu)``.
    """
    n = t.size
    if mu == 0 or mu == 1:
        return complex(np.inf, 0.0)  # M's extra zero root / the phase pole: stop here
    # G_k = mu F_k: mu row^T (mu - A)^-1 column, mode by mode; dG_k its derivative
    G = np.zeros(6, dtype=np.complex128)
    dG = np.zeros(6, dtype=np.complex128)
    logd = 0j
    for i in range(n):
        if kind[i] == 0:
            continue
        if kind[i] == 1:  # mu (alpha mu + beta) / (mu (mu - lam))
            inv = 1.0 / (mu - lam[i])
            logd += inv
            for k in range(6):
                num = coef[k, 0, i] * mu + coef[k, 1, i]
                G[k] += num * inv
                dG[k] += (coef[k, 0, i] - num * inv) * inv
            continue
        dd = 2.0 * mu - t[i]
        d = mu * (mu - t[i]) + p[i]
        if d == 0:
            return complex(np.inf, 0.0)  # on a modal multiplier that is a root
        inv = 1.0 / d
        logd += dd * inv
        for k in range(6):
            num = coef[k, 0, i] * mu + coef[k, 1, i]
            f = num * inv
            G[k] += mu * f
            dG[k] += f + mu * (coef[k, 0, i] - num * dd * inv) * inv
    G += const
    q = omega / h2
    z = 1.0 / (mu - 1.0)
    s11 = -R + G[0]
    s21 = G[1]
    s12 = R * xn / h2 + G[2] + q * z * G[4]
    s22 = G[3] + q * z * G[5]
    ds11 = dG[0]
    ds21 = dG[1]
    ds12 = dG[2] + q * z * (dG[4] - z * G[4])
    ds22 = dG[3] + q * z * (dG[5] - z * G[5])
    det = s11 * s22 - s12 * s21
    if det == 0:
        return complex(np.inf, 0.0)
    ddet = ds11 * s22 + s11 * ds22 - ds12 * s21 - s12 * ds21
    out = logd + z + ddet / det
    return out - 1.0 / mu if zeros < 0 else out


@_jit
def _apply_a(modal, e_y, e_v, cy, cv, cd):
    """``A [c; c_delta]`` in modal coordinates (the phase entry is unchanged)."""
    n = cy.size
    oy = np.empty(n)
    ov = np.empty(n)
    for i in range(n):
        oy[i] = modal[2, i] * cy[i] + modal[3, i] * cv[i] + e_y[i] * cd
        ov[i] = modal[4, i] * cy[i] + modal[5, i] * cv[i] + e_v[i] * cd
    return oy, ov


@_jit
def power_sums(modal, u0, ui0, omega, R, e_y, e_v, v_pre, acc, h2, xn):
    """``tr G`` and ``tr G^2`` (equal to ``tr M``, ``tr M^2``) in O(n), with the sizes of
    the terms summed for each (the scale of their rounding errors)."""
    n = u0.size
    kappa = 1.0 + R
    # the two columns of Q in modal coordinates
    qy = np.zeros((2, n))
    qv = np.empty((2, n))
    qd = np.array([0.0, omega / h2])
    for i in range(n):
        qv[0, i] = kappa * ui0[i]
        qy[1, i] = v_pre[i] / h2
        qv[1, i] = (acc[i] - kappa * ui0[i] * xn) / h2
    eaq = np.empty((2, 2))  # E^T A Q
    ea2q = np.empty((2, 2))  # E^T A^2 Q
    for col in range(2):
        y1, v1 = _apply_a(modal, e_y, e_v, qy[col], qv[col], qd[col])
        y2, v2 = _apply_a(modal, e_y, e_v, y1, v1, qd[col])
        eaq[0, col] = np.sum(u0 * v1)
        eaq[1, col] = np.sum(u0 * y1)
        ea2q[0, col] = np.sum(u0 * v2)
        ea2q[1, col] = np.sum(u0 * y2)
    tr_a = 1.0
    tr_a2 = 1.0
    size_a = 1.0
    size_a2 = 1.0
    for i in range(n):
        t = modal[2, i] + modal[5, i]
        t2 = t * t - 2.0 * (modal[2, i] * modal[5, i] - modal[3, i] * modal[4, i])
        tr_a += t
        tr_a2 += t2
        size_a += abs(t)
        size_a2 += abs(t2)
    tr_eaq = eaq[0, 0] + eaq[1, 1]
    tr_eaq2 = eaq[0, 0] * eaq[0, 0] + 2.0 * eaq[0, 1] * eaq[1, 0] + eaq[1, 1] * eaq[1, 1]
    tr_ea2q = ea2q[0, 0] + ea2q[1, 1]
    sizes = (size_a + abs(eaq[0, 0]) + abs(eaq[1, 1]),
             size_a2 + 2.0 * (abs(ea2q[0, 0]) + abs(ea2q[1, 1])) + np.sum(np.abs(eaq)) ** 2)
    return tr_a - tr_eaq, tr_a2 - 2.0 * tr_ea2q + tr_eaq2, sizes[0], sizes[1]


@_jit
def _starts(kind, t, p, zeros):
    """The modal multipliers not set apart, nudged apart off the real axis, and one more
    start near 1/2 when some are (the degree is then one more than their count)."""
    n = kind.size
    m = 0
    for i in range(n):
        m += kind[i]
    m += 1 if zeros >= 0 else 0
    z = np.empty(m, dtype=np.complex128)
    k = 0
    for i in range(n):
        big, small = _modal_multipliers(t[i], p[i])
        for j in range(kind[i]):
            mu = big if j == 0 else small
            nudge = 1e-3 * np.exp(1j * (0.7 + 2.0 * math.pi * k / m))
            z[k] = mu * (1.0 + nudge) if mu != 0 else nudge
            k += 1
    if zeros >= 0:
        z[k] = 0.5 + 0.01j
    return z


@_jit
def aberth(coef, kind, t, p, lam, const, zeros, omega, R, h2, xn, z):
    """Aberth-Ehrlich iteration on every root at once (Gauss-Seidel order), in place.

    Returns whether every root converged: its correction fell to rounding level, or
    stopped shrinking (no longer below half the smallest one so far) once below
    ``_STAGNATION`` times the largest root: the noise floor of the evaluation (a
    cluster of tiny roots, e.g. from a nearly defective zero multiplier, is no better
    defined by dense eigenvalues).
    """
    m = z.size
    done = np.zeros(m, dtype=np.bool_)
    smallest = np.full(m, np.inf)
    for _ in range(_MAX_SWEEPS):
        remaining = 0
        # absolute accuracy eps * |largest root|, as for dense eigenvalues
        largest = np.max(np.abs(z))
        floor = _EPS * largest
        for k in range(m):
            if done[k]:
                continue
            L = log_derivative(z[k], coef, kind, t, p, lam, const, zeros, omega, R, h2, xn)
            if not (np.isfinite(L.real) and np.isfinite(L.imag)):
                done[k] = True  # sits on a root: nothing to correct
                continue
            if L == 0:
                return False  # a critical point of F: the iteration cannot move this root
            newton = 1.0 / L
            s = 0j
            for j in range(m):
                if j != k and z[k] != z[j]:
                    s += 1.0 / (z[k] - z[j])
            step = newton / (1.0 - newton * s)
            z[k] -= step
            size = abs(step)
            scale = abs(z[k])
            if size <= 4.0 * _EPS * scale + floor or (size <= _STAGNATION * largest
                                                         and size >= 0.5 * smallest[k]):
                done[k] = True
            else:
                remaining += 1
            smallest[k] = min(smallest[k], size)
        if remaining == 0:
            return True
    return False


@_jit
def _pair_conjugates(z):
    """Make the roots an exactly conjugate-symmetric set, as the polynomial is real.

    Each root in the upper half-plane pairs with the nearest unpaired root of the lower
    one when that is nearer to its conjugate than to the real axis; the pair becomes an
    exact conjugate pair (their mean). A root left without partner is real to rounding
    (a lone non-real root is impossible) and loses its imaginary part.
    """
    m = z.size
    used = np.zeros(m, dtype=np.bool_)
    for k in range(m):
        if used[k] or z[k].imag <= 0.0:
            continue
        best = -1
        best_d = np.inf
        for j in range(m):
            if j != k and not used[j] and z[j].imag < 0.0:
                d = abs(z[j] - np.conj(z[k]))
                if d < best_d:
                    best, best_d = j, d
        if best >= 0 and best_d < abs(z[k].imag):
            avg = 0.5 * (z[k] + np.conj(z[best]))
            z[k] = avg
            z[best] = np.conj(avg)
            used[k] = True
            used[best] = True
    for k in range(m):
        if not used[k]:
            z[k] = z[k].real


@_jit
def power_sums_agree(z, tr1, tr2, size1, size2):
    """Whether ``sum z`` and ``sum z^2`` match ``tr G``, ``tr G^2`` to ``POWER_SUM_TOL``."""
    return (abs(np.sum(z) - tr1) <= POWER_SUM_TOL * (np.sum(np.abs(z)) + size1)
            and abs(np.sum(z * z) - tr2) <= POWER_SUM_TOL * (np.sum(np.abs(z) ** 2) + size2))


@_jit
def velocity_row_error(modal, u0, ui0, omega, R, delta, sigma):
    """Rounding bound of the velocity of mass 1 in modal form, ``sum_i u_1i v_i`` with
    ``v_i = omega (beta_i cos(delta) - gamma_i sin(delta)) + kappa sigma v0_i`` (the modal
    velocities before the impact, :func:`impactcont.kernel.closed_form.jacobian_pieces`):
    ``eps`` times the terms summed, with the change of the forced ones over the rounding
    of ``delta`` (``eps (1 + |delta|)``), as :func:`impactcont.orbit.dense.velocity_errors`.
    """
    kappa = 1.0 + R
    cd, sd = math.cos(delta), math.sin(delta)
    tilt = 1.0 + abs(delta)
    total = 0.0
    for i in range(u0.size):
        gm, bt = modal[0, i], modal[1, i]
        forced = omega * (abs(bt * cd) + abs(gm * sd) + abs(gm * cd + bt * sd) * tilt)
        total += abs(u0[i]) * (forced + abs(kappa * sigma * (modal[7, i] + ui0[i])))
    return _EPS * total


@_jit
def secular_multipliers(modal, w, a, f, u0, ui0, omega, R, delta, sigma):
    """The multipliers of G (eq. 25) from the secular function, largest modulus first.

    Returns ``(multipliers, ok)``: ``ok`` is False when the velocity of mass 1 in modal
    form cancels (the guard of the module: the multipliers are then NaN), the iteration
    did not converge or the power sums disagree with ``tr G``, ``tr G^2`` (then use the
    dense path).
    """
    if not velocity_row_error(modal, u0, ui0, omega, R, delta, sigma) <= (
            VELOCITY_POLISH * abs(sigma)):
        return np.full(2 * u0.size, np.nan + 0.0j), False
    e_y, e_v, v_pre, acc = jacobian_pieces(modal, w, a, f, ui0, omega, R, delta, sigma)
    coef, kind, t, p, lam, const, zeros, h2, xn = secular_coefficients(
        modal, u0, ui0, omega, R, e_y, e_v, v_pre, acc)
    z = _starts(kind, t, p, zeros)
    ok = aberth(coef, kind, t, p, lam, const, zeros, omega, R, h2, xn, z)
    _pair_conjugates(z)
    if zeros > 0:  # the modal multipliers set apart, less M's extra zero
        z = np.concatenate((z, np.zeros(zeros, dtype=np.complex128)))
    traces = power_sums(modal, u0, ui0, omega, R, e_y, e_v, v_pre, acc, h2, xn)
    ok = ok and power_sums_agree(z, *traces)
    return by_modulus(z), ok

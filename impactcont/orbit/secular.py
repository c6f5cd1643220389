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

The accuracy guard: the result is accepted only if every root converged (a root the
noise of the evaluation leaves uncertain by more than ``_NOISE_OK`` of the largest
multiplier, or of 1, has not) and the first two power sums of the roots agree with
``tr G = tr M`` and ``tr G^2 = tr M^2`` (both O(n) in closed form) to ``POWER_SUM_TOL``
relative to the sizes of the roots and of the terms of those traces; otherwise the
caller falls back to the dense eigenvalues of G.

A guard before it: the rank-two form sees the impact velocity as the velocity of mass 1
in modal coordinates, ``h2 = sum_i u_1i v_i`` (``v = z'(T^-)``), and its zero row needs
``e_x1^T Q = [0, 1]`` exactly. Far above the lowest natural frequency the forced modal
velocities nearly vanish at the impact and ``h2`` is a small difference of their terms
(issue 19: 6e-10 relative for a 16-mass chain at ``omega = 1e4 omega_1``, R = 0.8, and
the multipliers with it), a loss no later test sees (the power sums are of the same
pieces). Where the rounding bound of that sum (:func:`velocity_row_error`) exceeds
:data:`impactcont.orbit.dense.VELOCITY_POLISH` of the motion's velocity ``sigma``, the
pole is ``sigma`` itself, as in the dense G (:func:`impactcont.orbit.periodic.
modal_jacobian`), and the mass-1 entry of the velocity column is corrected to it,
``v += (sigma - sum_i u_1i v_i) u^-1 e_1``, the sum exact (:func:`exact_dot`): the zero
row of ``M`` then holds to rounding and the multipliers are those of that G (chains of
40-100 masses at ``omega = 30 ... 1000``: within 5e-13 of LAPACK's eigenvalues of G,
relative to the largest, where the modal sum as the pole was up to 2.4e-9 off). Until
issue 29 this case fell back to the dense eigenvalues of G. Chains up to n = 200 at
ordinary frequencies stay below 1.1e-13 (relative) with the modal sum.

Plain numpy, nothing compiled (a system's first large orbit costs no compile wave): each
Aberth-Ehrlich sweep corrects all roots not yet done at once (Jacobi order), the modal
sums of ``S`` and its derivative for all of them as one matrix product, (2 x roots) x
modes by modes x 12, and the Aberth repulsion as one roots x roots array.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from impactcont.orbit.dense import VELOCITY_POLISH

__all__ = ["DEAD", "POWER_SUM_TOL", "SECULAR_MIN", "exact_dot", "jacobian_pieces", "power_sums",
           "power_sums_agree", "secular_coefficients", "secular_multipliers",
           "velocity_row_error"]

_EPS = float(np.finfo(np.float64).eps)  # unit roundoff of float64

SECULAR_MIN = 40
"""Systems with at least this many degrees of freedom get their multipliers here, below it
the dense G and its eigenvalues (LAPACK through numpy: nothing compiled either way).
Side by side the numpy sweeps (about 1 ms up to n ~ 40) are at parity with the dense path
from n = 38-44 and faster from n = 48 (``studies/performance/README.md``, "Cost against
n")."""
POWER_SUM_TOL = 1e-9
"""Largest accepted ``|sum mu^k - tr G^k| / sum |mu|^k`` (k = 1, 2) of the roots."""
_MAX_SWEEPS = 200
_BLOCK = 1 << 18  # complex entries of each scratch array of a sweep (4 MB)
_STAGNATION = 1e-9  # below this times max(largest root, 1), every correction: the noise floor
_NOISE_OK = 1e-12  # largest accepted correction (of max(largest root, 1)) of a stagnant root
DEAD = _EPS
"""Modal multipliers (eigenvalues of ``W_i(T)``, dimensionless) below this are set apart as
exact zeros: the fast decay of over-damped modes, modes that die out within the period."""


def _modal_multipliers(t: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both eigenvalues of each 2 x 2 block from its trace and determinant, without
    cancellation (the smaller of a real pair as ``p / larger``); larger modulus first."""
    disc = 0.25 * t * t - p
    root = np.sqrt(np.abs(disc))
    big = 0.5 * t + np.copysign(root, t)
    with np.errstate(divide="ignore", invalid="ignore"):
        small = np.where(big != 0.0, p / np.where(big != 0.0, big, 1.0), 0.0)
    real = disc >= 0.0
    return (np.where(real, big, 0.5 * t + 1j * root),
            np.where(real, small, 0.5 * t - 1j * root))


def jacobian_pieces(modal, w, a, f, ui0, omega, R, delta, sigma):
    """The modal ingredients of G (eq. 22-25) at a motion, each shape (n,), in numpy.

    The same quantities as the compiled
    :func:`impactcont.kernel.closed_form.jacobian_pieces` (computed here so that the
    secular path compiles nothing): ``e_y, e_v``, d/d delta of the forcing term over a
    period, ``E_delta = (I - W) P_delta`` per mode; ``v_pre, acc``, modal velocity and
    acceleration just before the impact, ``z'(T^-)`` (forced part harmonic,
    ``-omega^2 y_p``; free part by the mode's equation).
    """
    kappa = 1.0 + R
    cd, sd = np.cos(delta), np.sin(delta)
    gm, bt = modal[0], modal[1]
    py = -gm * sd + bt * cd
    pv = omega * (-bt * sd - gm * cd)
    e_y = (1.0 - modal[2]) * py - modal[3] * pv
    e_v = -modal[4] * py + (1.0 - modal[5]) * pv
    free_v = modal[7] + ui0
    v_pre = omega * (bt * cd - gm * sd) + kappa * sigma * free_v
    acc = (-omega * omega * (gm * cd + bt * sd)
           + kappa * sigma * (-w * w * modal[6] - 2.0 * a * free_v))
    return e_y, e_v, v_pre, acc


def secular_coefficients(modal, u0, ui0, omega, R, e_y, e_v, v_pre, acc, h2=None):
    """The modal pieces of ``S(mu)``: ``(coef, kind, t, p, lam, const, zeros, h2, xn)``.

    ``h2``: the pole, by default the velocity of mass 1 in modal form
    ``sum_i u_1i v_i`` (given by :func:`secular_multipliers` where that sum cancels).

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
    kappa = 1.0 + R
    h2 = float(np.sum(u0 * v_pre)) if h2 is None else float(h2)
    xn = float(np.sum(u0 * acc))
    w11, w12, w21, w22 = modal[2], modal[3], modal[4], modal[5]
    t = w11 + w22
    p = w11 * w22 - w12 * w21
    big, small = _modal_multipliers(t, p)
    kind = np.where(np.abs(small) > DEAD, 2, np.where(np.abs(big) > DEAD, 1, 0))
    zero = np.zeros_like(u0)
    # the three columns (y and v parts) in modal coordinates
    cy = np.stack((zero, v_pre / h2, e_y))
    cv = np.stack((kappa * ui0, (acc - kappa * ui0 * xn) / h2, e_v))
    coef = np.empty((6, 2, u0.size))
    coef[0::2, 0] = u0 * cv
    coef[0::2, 1] = u0 * (w21 * cy - w11 * cv)
    coef[1::2, 0] = u0 * cy
    coef[1::2, 1] = u0 * (w12 * cv - w22 * cy)
    const = coef[:, 0, kind == 0].sum(axis=1)  # mu (alpha mu + 0) / mu^2
    return coef, kind, t, p, big, const, int(np.sum(2 - kind)) - 1, h2, xn


class _Secular(NamedTuple):
    """The secular function's pieces regrouped for evaluation at many ``mu`` at once."""

    t: np.ndarray  # (n2,) trace and determinant of the modes keeping both poles
    p: np.ndarray
    C2: np.ndarray  # (n2, 12) complex: coef[:, 0] then coef[:, 1] of those modes
    lam: np.ndarray  # (n1,) the pole kept by the modes with one multiplier set apart
    C1: np.ndarray  # (n1, 12) complex
    const: np.ndarray  # (6,)
    zeros: int
    omega: float
    R: float
    h2: float
    xn: float


def _regroup(coef, kind, t, p, lam, const, zeros, omega, R, h2, xn) -> _Secular:
    both = kind == 2
    one = kind == 1
    table = np.concatenate((coef[:, 0], coef[:, 1])).T.astype(np.complex128)  # (n, 12)
    return _Secular(t[both], p[both], np.ascontiguousarray(table[both]), lam[one],
                    np.ascontiguousarray(table[one]), const, zeros, omega, R, h2, xn)


def power_sums(modal, u0, ui0, omega, R, e_y, e_v, v_pre, acc, h2, xn):
    """``tr G`` and ``tr G^2`` (equal to ``tr M``, ``tr M^2``) in O(n), with the sizes of
    the terms summed for each (the scale of their rounding errors)."""
    kappa = 1.0 + R
    w11, w12, w21, w22 = modal[2], modal[3], modal[4], modal[5]
    # the two columns of Q in modal coordinates, and A applied to them once and twice
    qy = np.stack((np.zeros_like(u0), v_pre / h2))
    qv = np.stack((kappa * ui0, (acc - kappa * ui0 * xn) / h2))
    qd = np.array([0.0, omega / h2])[:, None]
    y1 = w11 * qy + w12 * qv + e_y * qd
    v1 = w21 * qy + w22 * qv + e_v * qd
    y2 = w11 * y1 + w12 * v1 + e_y * qd
    v2 = w21 * y1 + w22 * v1 + e_v * qd
    eaq = np.stack((v1 @ u0, y1 @ u0))  # E^T A Q, rows (v, x), columns of Q
    ea2q = np.stack((v2 @ u0, y2 @ u0))  # E^T A^2 Q
    t = w11 + w22
    t2 = t * t - 2.0 * (w11 * w22 - w12 * w21)
    tr_a = 1.0 + np.sum(t)
    tr_a2 = 1.0 + np.sum(t2)
    size_a = 1.0 + np.sum(np.abs(t))
    size_a2 = 1.0 + np.sum(np.abs(t2))
    tr_eaq = eaq[0, 0] + eaq[1, 1]
    tr_eaq2 = eaq[0, 0] * eaq[0, 0] + 2.0 * eaq[0, 1] * eaq[1, 0] + eaq[1, 1] * eaq[1, 1]
    tr_ea2q = ea2q[0, 0] + ea2q[1, 1]
    return (float(tr_a - tr_eaq), float(tr_a2 - 2.0 * tr_ea2q + tr_eaq2),
            float(size_a + abs(eaq[0, 0]) + abs(eaq[1, 1])),
            float(size_a2 + 2.0 * (abs(ea2q[0, 0]) + abs(ea2q[1, 1]))
                  + np.sum(np.abs(eaq)) ** 2))


def _starts(kind, t, p, zeros):
    """The modal multipliers not set apart, nudged apart off the real axis, and one more
    start near 1/2 when some are (the degree is then one more than their count)."""
    big, small = _modal_multipliers(t, p)
    kept = np.stack((big, small), axis=1)[np.arange(2)[None, :] < kind[:, None]]
    m = kept.size + (1 if zeros >= 0 else 0)
    nudge = 1e-3 * np.exp(1j * (0.7 + 2.0 * np.pi * np.arange(kept.size) / m))
    z = np.where(kept != 0, kept * (1.0 + nudge), nudge)
    return np.append(z, 0.5 + 0.01j) if zeros >= 0 else z


def log_derivative(mu: np.ndarray, s: _Secular, work: np.ndarray | None = None) -> np.ndarray:
    """``F'(mu) / F(mu)`` at every ``mu`` (shape (m,)) at once, O(n) each.

    ``F = det(mu - A) det S(mu) / mu`` when no modal multiplier is set apart
    (``zeros = -1``); otherwise ``det(mu - A)`` without its zeros at 0, times
    ``det S(mu)``. The modal sums are one matrix product, (2m x modes) by (modes x 12):
    ``G_k = mu row_k^T (mu - A)^-1 column_k`` and its derivative ``dG_k``. Not finite
    where F has a pole or ``mu`` sits on a root (``mu`` = 0, 1, a modal multiplier, a
    zero of ``det S``). ``work``: scratch of at least ``(2m, n2)`` complex (n2 the modes
    keeping both poles), reused across calls.
    """
    m = mu.size
    x = mu[:, None]
    if work is None:
        work = np.empty((2 * m, s.t.size), dtype=np.complex128)
    inv, slope = work[:m], work[m:2 * m]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # modes keeping both poles: mu (alpha mu + beta) / d, d = mu^2 - t mu + p
        np.subtract(x, s.t, out=slope)
        slope *= x
        slope += s.p
        np.divide(1.0, slope, out=inv)  # d = 0 (on a modal multiplier): not finite
        np.subtract(2.0 * x, s.t, out=slope)  # d' = 2 mu - t
        slope *= inv
        logd = slope.sum(axis=1)
        slope *= inv  # d' / d^2
        sums = work[:2 * m] @ s.C2  # (2m, 12)
        a0, a1 = sums[:m, :6], sums[:m, 6:]
        b0, b1 = sums[m:, :6], sums[m:, 6:]
        xa0 = x * a0
        f = xa0 + a1
        G = x * f  # G_k = mu F_k, F_k = row_k^T (mu - A)^-1 column_k
        dG = f + xa0 - x * (x * b0 + b1)
        if s.lam.size:  # one pole kept: mu (alpha mu + beta) / (mu (mu - lam))
            inv1 = 1.0 / (x - s.lam)
            logd += inv1.sum(axis=1)
            sums1 = np.concatenate((inv1, inv1 * inv1)) @ s.C1
            c0, c1 = sums1[:m, :6], sums1[:m, 6:]
            e0, e1 = sums1[m:, :6], sums1[m:, 6:]
            G += x * c0 + c1
            dG += c0 - x * e0 - e1
        G += s.const
        # S = [[s11, s12], [s21, s22]]: column 1 from kappa e_v1, column 2 from D dX / h2
        # and the phase column dE, which enters with omega / (h2 (mu - 1))
        z = (1.0 / (mu - 1.0))[:, None]
        qz = (s.omega / s.h2) * z
        col2 = G[:, 2:4] + qz * G[:, 4:6]
        col2[:, 0] += s.R * s.xn / s.h2
        dcol2 = dG[:, 2:4] + qz * (dG[:, 4:6] - z * G[:, 4:6])
        s11 = G[:, 0] - s.R
        det = s11 * col2[:, 1] - col2[:, 0] * G[:, 1]
        ddet = (dG[:, 0] * col2[:, 1] + s11 * dcol2[:, 1] - dcol2[:, 0] * G[:, 1]
                - col2[:, 0] * dG[:, 1])
        out = logd + z[:, 0] + ddet / det
        if s.zeros < 0:
            out -= 1.0 / mu
    # M's extra zero root, the phase pole, a zero of det S: stop there
    out[(mu == 0) | (mu == 1) | (det == 0)] = np.inf
    return out


def _repulsion(z: np.ndarray, active: np.ndarray, work: np.ndarray) -> np.ndarray:
    """Aberth's ``sum_j 1 / (z_k - z_j)`` for each active ``k`` over the other roots, those
    equal to ``z_k`` left out. ``work``: scratch of at least ``(active.size, z.size)``."""
    gaps = np.subtract(z[active, None], z, out=work[:active.size])
    gaps[np.arange(active.size), active] = np.inf  # itself: 1 / inf = 0
    with np.errstate(divide="ignore", invalid="ignore"):
        np.divide(1.0, gaps, out=gaps)
    out = gaps.sum(axis=1)
    tie = ~np.isfinite(out)  # another root equal to z_k: left out
    if tie.any():
        gaps = z[active[tie], None] - z
        gaps[gaps == 0] = np.inf
        out[tie] = (1.0 / gaps).sum(axis=1)
    return out


def aberth(s: _Secular, z: np.ndarray) -> bool:
    """Aberth-Ehrlich iteration on every root at once (Jacobi order: each sweep corrects
    all roots not yet done from the same values, as array operations, in blocks of roots
    whose scratch stays near ``_BLOCK`` entries), in place.

    Returns whether every root converged: its correction fell to rounding level, or
    stopped shrinking (no smaller than the smallest one so far) once every correction is
    below ``_STAGNATION`` times the largest root (or 1): the noise floor of the
    evaluation. That gate keeps a small root from being taken as stagnant while large
    ones still move and push it about, and "no smaller" (not "not below half") keeps a
    pair of close roots converging linearly from being taken as noise (a 150-mass
    over-damped chain: a pair 2.2e-7 apart stopped 6e-8 off). A stagnant root whose
    best correction is above ``_NOISE_OK`` of the largest root (or 1) is not
    determined to the accuracy the path promises: False, the caller takes the dense
    eigenvalues (clusters of tiny multipliers, all of size 2e-9 for a 12-DOF system over-
    damped by ``alpha = 6``, were 6e-10 off).
    """
    done = np.zeros(z.size, dtype=bool)
    smallest = np.full(z.size, np.inf)
    # roots per block: the scratch, (2 rows) x modes and rows x roots, stays near _BLOCK
    rows = max(32, _BLOCK // max(z.size, 1))
    work = np.empty((2 * min(rows, z.size), s.t.size), dtype=np.complex128)
    pairs = np.empty((min(rows, z.size), z.size), dtype=np.complex128)
    blocks = range(0, z.size, rows)
    for _ in range(_MAX_SWEEPS):
        # absolute accuracy eps * |largest root|, as for dense eigenvalues
        largest = np.abs(z).max()
        floor = _EPS * largest
        active = np.flatnonzero(~done)
        L = np.concatenate([log_derivative(z[active[k:k + rows]], s, work) for k in blocks
                            if k < active.size])
        finite = np.isfinite(L)
        done[active[~finite]] = True  # sits on a root: nothing to correct
        active, L = active[finite], L[finite]
        if not active.size:
            return True
        if (L == 0).any():
            return False  # a critical point of F: the iteration cannot move this root
        newton = 1.0 / L
        repel = np.concatenate([_repulsion(z, active[k:k + rows], pairs) for k in blocks
                                if k < active.size])
        step = newton / (1.0 - newton * repel)
        z[active] -= step
        size = np.abs(step)
        converged = size <= 4.0 * _EPS * np.abs(z[active]) + floor
        scale = max(largest, 1.0)
        if size.max() <= _STAGNATION * scale:  # every correction small: the noise floor
            stagnant = ~converged & (size >= smallest[active])  # no longer shrinking
            if (smallest[active][stagnant] > _NOISE_OK * scale).any():
                return False  # a root the evaluation's noise leaves uncertain: refuse
            converged |= stagnant
            smallest[active] = np.minimum(smallest[active], size)
        done[active[converged]] = True
        if converged.all():
            return True
    return False


def _pair_conjugates(z: np.ndarray) -> np.ndarray:
    """The roots as an exactly conjugate-symmetric set, as the polynomial is real.

    Each root in the upper half-plane (in order) pairs with the nearest unpaired root of
    the lower one when that is nearer to its conjugate than to the real axis; the pair
    becomes an exact conjugate pair (their mean). A root left without partner is real to
    rounding (a lone non-real root is impossible) and loses its imaginary part.
    """
    z = z.copy()
    upper = np.flatnonzero(z.imag > 0.0)
    lower = np.flatnonzero(z.imag < 0.0)
    paired = np.zeros(z.size, dtype=bool)
    if upper.size and lower.size:
        dist = np.abs(z[lower][None, :] - np.conj(z[upper])[:, None])
        nearest = dist.argmin(axis=1)
        near = dist[np.arange(upper.size), nearest]
        keep = near < z[upper].imag  # a root refused at its nearest is refused at any other
        if np.unique(nearest[keep]).size == keep.sum():  # no contest: every choice is free
            ks, js = upper[keep], lower[nearest[keep]]
        else:  # in order, each takes the nearest not yet taken
            taken = np.zeros(lower.size, dtype=bool)
            ks, js = [], []
            for r, k in enumerate(upper):
                row = np.where(taken, np.inf, dist[r])
                j = int(row.argmin())
                if row[j] < z[k].imag:
                    taken[j] = True
                    ks.append(k)
                    js.append(lower[j])
            ks, js = np.array(ks, dtype=np.intp), np.array(js, dtype=np.intp)
        avg = 0.5 * (z[ks] + np.conj(z[js]))
        z[ks] = avg
        z[js] = np.conj(avg)
        paired[ks] = paired[js] = True
    z[~paired] = z[~paired].real
    return z


def power_sums_agree(z, tr1, tr2, size1, size2) -> bool:
    """Whether ``sum z`` and ``sum z^2`` match ``tr G``, ``tr G^2`` to ``POWER_SUM_TOL``."""
    size = np.abs(z)
    return bool(abs(np.sum(z) - tr1) <= POWER_SUM_TOL * (np.sum(size) + size1)
                and abs(np.sum(z * z) - tr2) <= POWER_SUM_TOL * (np.sum(size * size) + size2))


def velocity_row_error(modal, u0, ui0, omega, R, delta, sigma) -> float:
    """Rounding bound of the velocity of mass 1 in modal form, ``sum_i u_1i v_i`` with
    ``v_i = omega (beta_i cos(delta) - gamma_i sin(delta)) + kappa sigma v0_i`` (the modal
    velocities before the impact, :func:`jacobian_pieces`): ``eps`` times the terms summed,
    with the change of the forced ones over the rounding of ``delta`` (``eps (1 + |delta|)``),
    as :func:`impactcont.orbit.dense.velocity_errors`.
    """
    kappa = 1.0 + R
    cd, sd = np.cos(delta), np.sin(delta)
    gm, bt = modal[0], modal[1]
    forced = omega * (np.abs(bt * cd) + np.abs(gm * sd)
                      + np.abs(gm * cd + bt * sd) * (1.0 + abs(delta)))
    return float(_EPS * np.sum(np.abs(u0) * (forced + np.abs(kappa * sigma * (modal[7] + ui0)))))


def exact_dot(x: np.ndarray, y: np.ndarray) -> float:
    """``sum_i x_i y_i`` of float arrays rounded once: each product split exactly into
    its rounded value and its rounding error (Dekker's two-product, Veltkamp's
    splitting; no overflow for the modal sizes here), all of them summed exactly
    (:func:`math.fsum`). O(n)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    split = 134217729.0  # 2^27 + 1
    cx, cy = split * x, split * y
    xh, yh = cx - (cx - x), cy - (cy - y)
    xl, yl = x - xh, y - yh
    prod = x * y
    err = ((xh * yh - prod) + xh * yl + xl * yh) + xl * yl
    return math.fsum(np.concatenate((prod, err)).tolist())


def secular_multipliers(modal, w, a, f, u0, ui0, omega, R, delta, sigma):
    """The multipliers of G (eq. 25) from the secular function, largest modulus first.

    Returns ``(multipliers, ok)``: ``ok`` is False when the iteration did not converge or
    the power sums disagree with ``tr G``, ``tr G^2`` (then use the dense path).

    Where the velocity of mass 1 in modal form, ``sum_i u_1i v_i``, cancels (its rounding
    bound :func:`velocity_row_error` above :data:`~impactcont.orbit.dense.VELOCITY_POLISH`
    of ``sigma``, the guard of the module) the motion's own velocity ``sigma`` is the pole,
    as in the dense G (:func:`impactcont.orbit.periodic.modal_jacobian`), and the velocity
    column of ``Q`` is corrected in its mass-1 entry only, ``v += (sigma - sum_i u_1i v_i)
    u^-1 e_1`` with the sum exact (:func:`exact_dot`), so that ``e_x1^T Q = [0, 1]`` holds
    to rounding and ``M`` keeps its zero row: the multipliers are those of that G. Before
    (issue 29) this case fell back to the dense eigenvalues of G, O(n^3): 30-80 s for a
    2000-mass chain whose velocity was polished, against about 1 s here.
    """
    pieces = jacobian_pieces(modal, w, a, f, ui0, omega, R, delta, sigma)
    pole = None
    if not velocity_row_error(modal, u0, ui0, omega, R, delta, sigma) <= (
            VELOCITY_POLISH * abs(sigma)):
        if not (math.isfinite(sigma) and sigma != 0.0):
            return np.full(2 * u0.size, np.nan + 0.0j), False
        e_y, e_v, v_pre, acc = pieces
        pieces = (e_y, e_v, v_pre + (sigma - exact_dot(u0, v_pre)) * ui0, acc)
        pole = float(sigma)
    coef, kind, t, p, lam, const, zeros, h2, xn = secular_coefficients(
        modal, u0, ui0, omega, R, *pieces, h2=pole)
    z = _starts(kind, t, p, zeros)
    ok = aberth(_regroup(coef, kind, t, p, lam, const, zeros, omega, R, h2, xn), z)
    z = _pair_conjugates(z)
    if zeros > 0:  # the modal multipliers set apart, less M's extra zero
        z = np.concatenate((z, np.zeros(zeros, dtype=np.complex128)))
    ok = ok and power_sums_agree(z, *power_sums(modal, u0, ui0, omega, R, *pieces, h2, xn))
    # largest modulus first, stable among equal moduli (as kernel.stability.by_modulus)
    return z[np.argsort(-np.abs(z), kind="stable")], ok

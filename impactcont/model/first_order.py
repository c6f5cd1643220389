"""First-order complex modes: the exact flow of eq. (1) with any damping matrix C.

With a damping matrix that is not proportional (``C != alpha M + beta K``) the
undamped modes of eq. (5) no longer decouple eq. (1). The first-order form
``X' = A X + [0; M^-1 Re(F e^{i(omega t + delta)})]`` with ``X = [x; x']`` and

    A = [[0, I], [-M^-1 K, -M^-1 C]]                                      (eq. 1, first order)

is diagonalised by its eigenvectors, ``A = V diag(lambda_k) V^-1``; each complex mode
evolves as ``exp(lambda_k t)``, so the free flow of eq. (9) is, in closed form,

    Phi(t) = U W(t) U^-1 = Re(V diag(exp(lambda_k t)) V^-1)                (eq. 9, general C)

(real up to rounding, since the modes of a real A come in conjugate pairs) and the
steady forced response is ``X_p(t) = Re(Z e^{i(omega t + delta)})`` with
``Z = [x_hat; i omega x_hat]``, ``(K - omega^2 M + i omega C) x_hat = F`` (eq. 7 in
physical coordinates; complex ``F`` carries per-mass phases, see
:class:`impactcont.model.oscillator.ImpactOscillator`).

Over-damped modes are real eigenvalues, ``exp(lambda t)`` with ``lambda < 0``: no
overflow and no cancellation. Repeated eigenvalues with independent eigenvectors
(a symmetric structure) are diagonalised like any others. A free (rigid-body) mode ``u``
of K that C leaves undamped (``C u = 0``: the usual impact damper, a dashpot on the primary
and none on the free ball) makes the eigenvalue 0 defective; it decouples exactly and is
carried as its Jordan chain ``[u; 0], [0; u]``, the flow gaining the polynomial part ``t N``
(:attr:`FirstOrderBasis.nilpotent`): ``q(t) = q0 + v0 t``. Any other defective eigenvalue (an
exactly critically damped mode) has no eigenvector basis, and near one (nearly critical
damping) the basis is ill-conditioned: the error of ``Phi`` is about
``eps * cond(V)``. The 2-norm condition number of the column-normalised ``V`` of the
balanced ``A`` (LAPACK ``dgebal`` scaling, as ``dgeev`` uses: invariant to the units
of each coordinate, so that a graded chain is not charged its grading) is therefore
computed with the basis; above :data:`COND_WARN` an
:class:`~impactcont.errors.IllConditionedWarning` states the error bound, above
:data:`COND_REFUSE` the basis is refused (:class:`~impactcont.errors.ParameterError`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import warnings

import numpy as np
import scipy.linalg

from impactcont.errors import (
    IllConditionedWarning,
    NearResonanceWarning,
    ParameterError,
    ResonanceError,
)
from impactcont.kernel.arrays import FirstOrderArrays
from impactcont.model.modal import classify_modes

__all__ = ["COND_REFUSE", "COND_WARN", "FirstOrderBasis", "coth_remainder"]

_EPS = float(np.finfo(float).eps)

#: Warn when the eigenvector matrix's condition number exceeds this (error ~ 2e-11 of Phi).
COND_WARN = 1e5
#: Refuse the decomposition above this condition number (error ~ 2e-9 of Phi). An exactly
#: defective eigenvalue split by rounding gives ``cond ~ 1 / sqrt(eps) = 7e7``, either side of
#: 1e8 by the last digits of the inputs: 1e7 refuses it on any processor.
COND_REFUSE = 1e7
# warn when the forced response is known to worse than this (relative)
_RESONANCE_REL_ERROR_WARN = 1e-8


# B_2k / (2k)!: the Taylor coefficients of coth(x/2)/2 - 1/x = sum_k B_2k x^(2k-1) / (2k)!
_BERNOULLI = np.array([
    8.3333333333333333333e-2, -1.3888888888888888889e-3, 3.3068783068783068783e-5,
    -8.2671957671957671958e-7, 2.0876756987868098979e-8, -5.2841901386874931848e-10,
    1.3382536530684678833e-11, -3.3896802963225828668e-13, 8.5860620562778445641e-15,
    -2.174868698558061873e-16, 5.5090028283602295152e-18])
_SERIES_RADIUS = 1.0  # the series (radius 2 pi) has converged to 1e-19 here


def coth_remainder(x: np.ndarray, derivative: bool = False) -> np.ndarray:
    """``s(x) = 1/expm1(x) + 1/2 - 1/x = coth(x/2)/2 - 1/x`` (or ``s'(x)``), complex x.

    The free transfer over a period enters eq. (12) through ``(I - Phi(T))^-1 = -V
    diag(1/expm1(lambda T)) V^-1``, and ``1/expm1(x) = 1/x - 1/2 + s(x)``: the ``1/x``
    part sums to ``A^-1 / T`` exactly, so splitting it off leaves the bounded ``s``
    (``s(x) ~ x/12`` at small ``|x|``, a high forcing frequency), free of the
    cancellation of large ``1/(lambda T)`` terms. Taylor series (Bernoulli numbers) for
    ``|x| < 1``, the closed form (terms of order one, absolute error a few eps) beyond.
    ``s`` has poles where ``expm1(x) = 0`` (an undamped mode with ``omega_i T`` a
    multiple of 2 pi): inf/NaN there, as the equations themselves.

    Parameters
    ----------
    x : ndarray, complex
        ``lambda_k T`` (nonzero).
    derivative : bool
        Return ``s'(x) = 1/x^2 - e^x / expm1(x)^2`` instead.
    """
    x = np.asarray(x, dtype=complex)
    out = np.empty_like(x)
    near = np.abs(x) < _SERIES_RADIUS
    if np.any(near):
        xn = x[near]
        x2 = xn * xn
        acc = np.zeros_like(xn)
        if derivative:  # sum_k (2k - 1) B_2k / (2k)! x^(2k-2), Horner in x^2
            for k in range(_BERNOULLI.size, 0, -1):
                acc = acc * x2 + (2 * k - 1) * _BERNOULLI[k - 1]
            out[near] = acc
        else:
            for c in _BERNOULLI[::-1]:
                acc = acc * x2 + c
            out[near] = acc * xn
    far = ~near
    if np.any(far):
        xf = x[far]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            em1 = np.expm1(xf)
            if derivative:
                out[far] = 1.0 / (xf * xf) - (em1 + 1.0) / (em1 * em1)
            else:
                out[far] = 1.0 / em1 + 0.5 - 1.0 / xf
    return out


def _power_of_two_scale(v: np.ndarray) -> np.ndarray:
    """``2^-round(log2 v)`` where ``v > 0`` (1 elsewhere): an exact rescaling."""
    out = np.ones_like(v, dtype=float)
    pos = v > 0
    out[pos] = np.exp2(-np.round(np.log2(v[pos])))
    return out


def _rayleigh_coefficients(M: np.ndarray, K: np.ndarray, C: np.ndarray
                           ) -> tuple[float, float] | None:
    """``(alpha, beta)`` when ``C = alpha M + beta K`` to rounding (least squares over the
    entries, relative residual ``<= 1e-12``), else None."""
    basis = np.column_stack([M.ravel(), K.ravel()])
    coef, *_ = np.linalg.lstsq(basis, C.ravel(), rcond=None)
    scale = max(float(np.max(np.abs(C))), np.finfo(float).tiny)
    if np.max(np.abs(basis @ coef - C.ravel())) > 1e-12 * scale:
        return None
    return float(coef[0]), float(coef[1])


@functools.cache
def _compiled() -> types.ModuleType:
    """:mod:`impactcont.kernel.general`, imported on first use (numba loads it)."""
    from impactcont.kernel import general as general_kernel

    return general_kernel


def _check_resonance(omega: float, cond: float) -> None:
    """Refuse omega at an undamped resonance, warn near one, from the condition number
    ``cond`` of the equilibrated dynamic stiffness (:meth:`FirstOrderBasis.forced_amplitude`)."""
    if not math.isfinite(cond) or cond * _EPS >= 1.0:
        raise ResonanceError(
            f"omega={omega!r} is a natural frequency of an undamped mode (the dynamic "
            f"stiffness K - omega^2 M + i omega C is singular, condition number {cond:.3g}): "
            "the forced response of eq. (6) does not exist; choose another omega or add "
            "damping to that mode")
    if cond * _EPS > _RESONANCE_REL_ERROR_WARN:
        warnings.warn(
            f"omega={omega!r} is so close to the natural frequency of a lightly damped mode "
            f"that the forced response (eq. 7) is known only to a relative error of about "
            f"{cond * _EPS:.1g} (condition number {cond:.3g} of K - omega^2 M + i omega C)",
            NearResonanceWarning, stacklevel=4)


def _split_free(U_free: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The free modes of K that C leaves undamped, and those it damps (M-orthonormal).

    C is symmetric positive semi-definite, so a free mode ``u`` (``K u = 0``) with ``u^T C
    u = 0`` has ``C u = 0``: the eigenvectors of ``U^T C U`` (``U`` the M-orthonormal free
    modes) of eigenvalue ``<= 1e-12`` times the componentwise scale ``|U|^T |C| |U|`` span
    the undamped ones (their motion ``x = u (q0 + v0 t)`` is exact, a Jordan block of A at
    0), the others the damped ones (A's simple eigenvalue 0 and the real ``-u^T C u``).

    Returns
    -------
    undamped, damped : ndarray, shape (n, m_u), (n, m_d)
    """
    if not U_free.shape[1]:
        return U_free, U_free
    Cf = U_free.T @ C @ U_free
    scale = np.abs(U_free).T @ np.abs(C) @ np.abs(U_free)
    eig, Q = np.linalg.eigh(0.5 * (Cf + Cf.T))
    still = eig <= 1e-12 * max(float(np.max(np.abs(scale))), np.finfo(float).tiny)
    return U_free @ Q[:, still], U_free @ Q[:, ~still]


def _first_order_matrix(M: np.ndarray, K: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``A = [[0, I], [-M^-1 K, -M^-1 C]]`` (2n, 2n)."""
    n = M.shape[0]
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -np.linalg.solve(M, K)
    A[n:, n:] = -np.linalg.solve(M, C)
    return A


def _eigen(A: np.ndarray, U_free: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues, unit eigenvectors and the zero mask of ``A`` whose free modes
    ``U_free`` are all damped (a diagonalisable A), in a reproducible order."""
    n2 = A.shape[0]
    lam, V = scipy.linalg.eig(A)  # balanced dgeev: conjugate pairs exact
    zero = np.zeros(n2, dtype=bool)
    if U_free.shape[1]:
        # the free modes' eigenvalues are 0 up to rounding: exactly 0, with the exact
        # eigenvectors [u_free; 0] (a basis of the free subspace)
        nearest = np.argsort(np.abs(lam))[:U_free.shape[1]]
        zero[nearest] = True
        lam = np.where(zero, 0.0, lam)
        V = V.copy()
        V[:, nearest] = np.vstack([U_free, np.zeros_like(U_free)])
    # reproducible order: slowest decay first, then by frequency (conjugates adjacent)
    order = np.lexsort((-lam.imag, np.abs(lam.imag), -lam.real))
    lam, V, zero = lam[order], V[:, order], zero[order]
    return lam, V / np.linalg.norm(V, axis=0), zero


def _with_chains(M: np.ndarray, K: np.ndarray, C: np.ndarray, undamped: np.ndarray,
                 rest: np.ndarray, damped: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``lambda, V, V^-1``, the zero and the generalized masks of A with undamped free modes.

    With ``Q = [U | P]`` M-orthonormal (``U`` the undamped free modes, ``P`` the rest:
    the damped free modes and the held modes of K) and ``x = U q + P y``, ``C U = 0`` and
    ``K U = 0`` decouple eq. (1) exactly: ``q'' = U^T f(t)`` and ``y'' + P^T C P y' + P^T
    K P y = P^T f(t)``. Each undamped mode ``u`` is the Jordan chain ``A [0; u] = [u; 0]``,
    ``A [u; 0] = 0`` (columns ``[u; 0]``, then ``[0; u]``, both of eigenvalue 0); the rest
    are the eigenvectors ``[P y; lambda P y]`` of the reduced system, lifted. ``V^-1`` is
    exact by the same blocks: ``[U^T M, 0]``, ``[0, U^T M]`` and ``V_r^-1 [P^T M, P^T M]``.
    """
    n = M.shape[0]
    mu, r = undamped.shape[1], rest.shape[1]
    chain = np.zeros((2 * n, 2 * mu))
    chain[:n, 0::2] = undamped
    chain[n:, 1::2] = undamped
    chain_inv = np.zeros((2 * mu, 2 * n))
    chain_inv[0::2, :n] = undamped.T @ M
    chain_inv[1::2, n:] = undamped.T @ M
    lam = np.zeros(2 * mu, dtype=complex)
    zero = np.ones(2 * mu, dtype=bool)
    generalized = np.tile([False, True], mu)
    V, V_inv = chain.astype(complex), chain_inv.astype(complex)
    if r:
        Kr = rest.T @ K @ rest
        Cr = rest.T @ C @ rest
        Ir = np.eye(r)
        held = np.ones(r, dtype=bool)
        held[:damped.shape[1]] = False  # rest = [damped | held]: the damped free come first
        Kr[~held, :] = 0.0  # K P e_i = 0 for a (damped) free mode: exactly, not rounding
        Kr[:, ~held] = 0.0
        U_r = Ir[:, ~held]
        lam_r, V_r, zero_r = _eigen(_first_order_matrix(Ir, 0.5 * (Kr + Kr.T),
                                                        0.5 * (Cr + Cr.T)), U_r)
        lift = np.zeros((2 * n, 2 * r))
        lift[:n, :r] = rest
        lift[n:, r:] = rest
        V_r_inv = np.linalg.inv(V_r)
        V = np.hstack([V, lift @ V_r])
        V_inv = np.vstack([V_inv, V_r_inv @ lift.T @ np.kron(np.eye(2), M)])
        lam = np.concatenate([lam, lam_r])
        zero = np.concatenate([zero, zero_r])
        generalized = np.concatenate([generalized, np.zeros(2 * r, dtype=bool)])
    norms = np.linalg.norm(V, axis=0)
    return lam, V / norms, V_inv * norms[:, None], zero, generalized


@dataclasses.dataclass(frozen=True, eq=False)
class FirstOrderBasis:
    """Complex first-order modes ``A = V diag(lambda) V^-1`` of eq. (1) with any C.

    Attributes
    ----------
    M, K, C : ndarray, shape (n, n)
        The system matrices (C symmetric positive semi-definite).
    A : ndarray, shape (2n, 2n)
        ``[[0, I], [-M^-1 K, -M^-1 C]]``.
    eigenvalues : ndarray, shape (2n,), complex
        ``lambda_k``; real parts ``<= 0``. Conjugate pairs are exact (LAPACK ``dgeev``).
    V, V_inv : ndarray, shape (2n, 2n), complex
        Right eigenvectors (unit 2-norm columns) and their inverse (rows are the left
        eigenvectors, scaled so that ``V_inv V = I``).
    condition : float
        2-norm condition number of the eigenvectors of the balanced ``A`` (invariant to
        the units of each coordinate): the flow carries a relative error of about
        ``eps * condition``.
    zero : ndarray of bool, shape (2n,)
        The eigenvalues that are exactly 0: one per free (rigid-body) mode of K that C
        damps (its partner is the real ``-u^T C u`` rate of that mode; eigenvector
        ``[u; 0]``) and two per free mode C leaves undamped (``C u = 0``): the Jordan
        chain ``[u; 0]``, ``[0; u]`` of :attr:`generalized`.
    generalized : ndarray of bool, shape (2n,)
        The generalized eigenvectors ``[0; u] / |u|`` of the undamped free modes (``A [0;
        u] = [u; 0]``: eigenvalue 0 and a zero position part, the mark by which the compiled
        flights find them); the column before each is its eigenvector ``[u; 0] / |u|``.

    Notes
    -----
    With undamped free modes A is defective (a double eigenvalue 0 with one eigenvector
    per mode) and ``V`` holds its Jordan chains: ``A V = V (diag(lambda) + J)`` with ``J``
    the ones above the diagonal from each eigenvector's chain to its generalized vector, so

        Phi(t) = e^{A t} = Re(V diag(e^{lambda t}) V^-1) + t N,   N = V J V^-1   (eq. 9)

    exactly: the polynomial part ``t N`` (:attr:`nilpotent`, ``N = [[0, U U^T M], [0,
    0]]``, ``N^2 = 0``) is the free drift ``q(t) = q0 + v0 t`` of each undamped free
    mode ``x = U q``, which decouples from the rest (``K U = 0``, ``C U = 0``). The rest
    is the eigenvector flow of the M-orthogonal complement (which may hold damped free
    modes), with ``V^-1`` exact by the same blocks.
    """

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    A: np.ndarray
    eigenvalues: np.ndarray
    V: np.ndarray
    V_inv: np.ndarray
    condition: float
    zero: np.ndarray | None = None
    generalized: np.ndarray | None = None

    @classmethod
    def from_matrices(cls, M: np.ndarray, K: np.ndarray, C: np.ndarray) -> FirstOrderBasis:
        """Eigen-decompose the first-order matrix A, checking its conditioning.

        A free mode of K that C leaves undamped is carried exactly as a Jordan chain
        (:attr:`generalized`, :attr:`nilpotent`).

        Raises
        ------
        ParameterError
            If the eigenvector matrix is singular or its condition number exceeds
            :data:`COND_REFUSE` (a defective or nearly defective eigenvalue, e.g. a
            critically damped mode).

        Warns
        -----
        IllConditionedWarning
            If the condition number exceeds :data:`COND_WARN`.
        """
        n = M.shape[0]
        stiffness, modes = scipy.linalg.eigh(K, M)
        _, free = classify_modes(stiffness, modes, K)
        undamped, damped = _split_free(modes[:, free], C)
        A = _first_order_matrix(M, K, C)
        if undamped.shape[1]:
            lam, V, V_inv, zero, generalized = _with_chains(
                M, K, C, undamped, np.hstack([damped, modes[:, ~free]]), damped)
        else:
            lam, V, zero = _eigen(A, damped)
            V_inv = None
            generalized = np.zeros(2 * n, dtype=bool)
        # the condition of the eigenvectors of the balanced A (D^-1 A D, D a diagonal of
        # powers of two): invariant to the units of each coordinate (X -> D X)
        _, (scale, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
        balanced = V / scale[:, None]
        cond = float(np.linalg.cond(balanced / np.linalg.norm(balanced, axis=0)))
        gaps = np.abs(lam[:, None] - lam[None, :]) + np.diag(np.full(2 * n, np.inf))
        i, j = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
        closest = f"the closest eigenvalues are {complex(lam[i]):.12g} and {complex(lam[j]):.12g}"
        if not cond <= COND_REFUSE:
            rayleigh = _rayleigh_coefficients(M, K, C)
            if rayleigh is None:
                advice = ("Move the damping away from critical, or use proportional damping "
                          "(eta or alpha/beta, with a real F), whose modal path handles "
                          "critical modes exactly")
            else:  # already proportional: the first-order path was taken for a complex F
                advice = (f"This C is proportional (C = alpha M + beta K with alpha="
                          f"{rayleigh[0]:.12g}, beta={rayleigh[1]:.12g}): the modal path "
                          "handles its critical modes exactly, but only with a real F (given "
                          "as eta or alpha/beta); a complex F (per-mass phases) needs this "
                          "first-order path. Use a real F, or move the damping away from "
                          "critical")
            raise ParameterError(
                f"C={C.tolist()}: the first-order eigen-decomposition of eq. (1) is defective or "
                f"nearly so (condition number of the eigenvector matrix {cond:.3g} > "
                f"{COND_REFUSE:.0e}; {closest}), so the exact flow would carry a relative "
                f"error of about {min(cond * _EPS, 1.0):.1g}. Typical cause: a critically damped "
                f"mode. {advice}")
        if cond > COND_WARN:
            warnings.warn(
                f"the first-order eigenvector matrix of eq. (1) has condition number {cond:.3g} "
                f"(> {COND_WARN:.0e}; {closest}): the flow may carry a relative error of about "
                f"{cond * _EPS:.1g} (nearly critical damping)", IllConditionedWarning,
                stacklevel=3)
        if V_inv is None:
            V_inv = np.linalg.inv(V)
        for x in (A, lam, V, V_inv, zero, generalized):
            x.setflags(write=False)
        return cls(M=M, K=K, C=C, A=A, eigenvalues=lam, V=V, V_inv=V_inv, condition=cond,
                   zero=zero, generalized=generalized)

    @functools.cached_property
    def impact_column(self) -> np.ndarray:
        """``A^-1 e_{n+1} = [-K^-1 M e_1; 0]`` (2n,): the ``1/T`` part of the free motion
        that an impact on mass 1 starts, ``-(I - Phi(T))^-1 e_{n+1} = A^-1 e_{n+1} / T +
        O(1)`` (:func:`coth_remainder`), from ``A^-1 = [[-K^-1 C, -K^-1 M], [I, 0]]``."""
        n = self.M.shape[0]
        col = np.zeros(2 * n)
        if self.zero is not None and np.any(self.zero):  # a free mode: K singular, A^-1 none
            col[:] = np.nan  # (the N-1 closed form that uses it refuses free modes)
            col.setflags(write=False)
            return col
        col[:n] = -scipy.linalg.solve(self.K, self.M[:, 0], assume_a="pos")
        col.setflags(write=False)
        return col

    @functools.cached_property
    def scalar_pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The modes grouped in n pairs, each the two roots of one real scalar equation
        ``y'' + 2 a y' + w^2 y = 0`` (``w^2 = lambda_k lambda_j``, ``2 a = -(lambda_k +
        lambda_j)``): a complex conjugate pair, two real (over-damped) eigenvalues,
        adjacent in value, or the Jordan chain of an undamped free mode (``w = a = 0``,
        first: ``k`` its eigenvector, ``j`` its generalized vector, ``y'(0)`` the
        coefficient of ``t``). A real combination ``Re(c_k e^{lambda_k t} + c_j e^{lambda_j t})``
        of a pair is then ``W11(t) y(0) + W12(t) y'(0)`` with the exact, cancellation-free
        modal transfer of eq. (9), so the proportional kernel's interior-contact search
        (eq. 16) serves any C.

        Returns
        -------
        w, a : ndarray, shape (n,)
            ``w > 0`` and ``a >= 0`` of each pair.
        k, j : ndarray of int, shape (n,)
            Indices of the pair's two eigenvalues (``Im lambda_k >= 0``).
        """
        lam = self.eigenvalues
        upper = [int(i) for i in np.flatnonzero(lam.imag > 0)]
        lower = [int(i) for i in np.flatnonzero(lam.imag < 0)]
        # an undamped free mode's chain is one pair: y = y0 + v0 t (w = a = 0)
        gen = (np.flatnonzero(self.generalized) if self.generalized is not None
               else np.zeros(0, dtype=np.int64))
        chained = set(gen.tolist()) | set((gen - 1).tolist())
        real = sorted((int(i) for i in np.flatnonzero(lam.imag == 0) if int(i) not in chained),
                      key=lambda i: lam[i].real)
        ks, js = [int(i) - 1 for i in gen], [int(i) for i in gen]
        for k in upper:  # the exact conjugate (LAPACK), else the nearest one
            j = min(lower, key=lambda i: abs(lam[i] - lam[k].conjugate()))
            lower.remove(j)
            ks.append(k)
            js.append(j)
        ks += real[0::2]
        js += real[1::2]
        k_idx, j_idx = np.array(ks, dtype=np.int64), np.array(js, dtype=np.int64)
        prod = (lam[k_idx] * lam[j_idx]).real
        w = np.sqrt(np.maximum(prod, 0.0))
        a = -0.5 * (lam[k_idx] + lam[j_idx]).real
        return w, a, k_idx, j_idx

    @functools.cached_property
    def nilpotent(self) -> np.ndarray:
        """``N = V J V^-1`` (2n, 2n), the polynomial part of ``Phi(t) = Re(V diag(e^{lambda
        t}) V^-1) + t N``: ``sum_k [V_{n:,k}; 0] Re(V^-1_{k,:})`` over the generalized
        vectors ``k`` (:attr:`generalized`; their eigenvector ``[u; 0]`` is the velocity part
        of ``[0; u]`` moved up), ``[[0, U U^T M], [0, 0]]``; zero without undamped free modes.
        """
        n2 = self.V.shape[0]
        n = n2 // 2
        N = np.zeros((n2, n2))
        if self.generalized is not None:
            for k in np.flatnonzero(self.generalized):
                N[:n] += np.outer(self.V[n:, k].real, self.V_inv[k].real)
        N.setflags(write=False)
        return N

    @property
    def polynomial(self) -> bool:
        """Whether an undamped free mode gives the flow a polynomial part (:attr:`nilpotent`)."""
        return self.generalized is not None and bool(np.any(self.generalized))

    def transition(self, t: float) -> np.ndarray:
        """``Phi(t) = Re(V diag(exp(lambda t)) V^-1) + t N``, the free flow over time t
        (2n, 2n); ``N`` (:attr:`nilpotent`) is zero without undamped free modes."""
        t = float(t)
        out = ((self.V * np.exp(self.eigenvalues * t)) @ self.V_inv).real
        if self.polynomial:
            out += t * self.nilpotent
        return out

    @functools.cached_property
    def kernel_arrays(self) -> FirstOrderArrays:
        """The basis as the compiled first-order path takes it
        (:mod:`impactcont.kernel.general`): new contiguous, writable arrays of one
        dtype each, so that every entry point is compiled once.

        Returns
        -------
        FirstOrderArrays
            ``(lambda, V, V^-1, A, impact_column, w_p, a_p, k_p, j_p, M, K, C)`` by name, the
            scalar pairs of :attr:`scalar_pairs` as ``w_p, a_p, k_p, j_p``, then
            ``(lambda, V[0], w_p, a_p, k_p, j_p)`` again (the arguments of the contact
            search in their order, ``V[0]`` the first row of V).
        """
        w, a, k, j = self.scalar_pairs
        cplx = tuple(np.array(x, dtype=complex, order="C")
                     for x in (self.eigenvalues, self.V, self.V_inv))
        real = tuple(np.array(x, dtype=float, order="C")
                     for x in (self.A, self.impact_column, w, a))
        index = tuple(np.array(x, dtype=np.int64, order="C") for x in (k, j))
        mkc = tuple(np.array(x, dtype=float, order="C") for x in (self.M, self.K, self.C))
        search = (cplx[0], np.array(cplx[1][0]), *real[2:], *index)
        return FirstOrderArrays(*cplx, *real, *index, *mkc, *search)

    def forced_amplitude(self, F: np.ndarray, omega: float) -> np.ndarray:
        """Complex amplitude ``Z`` of the steady forced state, ``X_p = Re(Z e^{i theta})``.

        ``(K - omega^2 M + i omega C) x_hat = F`` and ``Z = [x_hat; i omega x_hat]``
        (eq. 7 in physical coordinates), with ``theta = omega t + delta``; solved after an
        exact power-of-two equilibration of rows and columns, in compiled code
        (:func:`impactcont.kernel.general.forced_response`;
        :meth:`forced_amplitude_reference` is the numpy form).

        Raises
        ------
        ResonanceError
            If the dynamic stiffness is singular (omega at an undamped resonance).

        Warns
        -----
        NearResonanceWarning
            If its condition number makes ``x_hat`` inexact beyond 1e-8 (relative): that
            of the row- and column-equilibrated stiffness (invariant to the units of each
            coordinate), which is solved.
        """
        arrays = self.kernel_arrays
        M, K, C = arrays.M, arrays.K, arrays.C
        Z, cond = _compiled().forced_response(K, M, C, np.array(F, dtype=complex),
                                              float(omega))
        _check_resonance(omega, cond)
        return Z

    def forced_amplitude_reference(self, F: np.ndarray, omega: float) -> np.ndarray:
        """:meth:`forced_amplitude` in numpy (the reference of the compiled solve)."""
        H = self.K - omega * omega * self.M + 1j * omega * self.C
        rows = _power_of_two_scale(np.max(np.abs(H), axis=1))
        H = rows[:, None] * H
        cols = _power_of_two_scale(np.max(np.abs(H), axis=0))
        H = H * cols
        cond = float(np.linalg.cond(H))
        _check_resonance(omega, cond)
        x_hat = cols * np.linalg.solve(H, rows * np.asarray(F, dtype=complex))
        return np.concatenate([x_hat, 1j * omega * x_hat])

    def forced_amplitude_derivative(self, Z: np.ndarray, omega: float) -> np.ndarray:
        """``dZ/d omega`` of :meth:`forced_amplitude` (exact):
        ``d x_hat = -H^-1 (-2 omega M + i C) x_hat``, ``Z = [x_hat; i omega x_hat]``, in
        compiled code (:func:`impactcont.kernel.general.forced_response_derivative`;
        :meth:`forced_amplitude_derivative_reference` is the numpy form)."""
        arrays = self.kernel_arrays
        M, K, C = arrays.M, arrays.K, arrays.C
        return _compiled().forced_response_derivative(K, M, C, np.array(Z, dtype=complex),
                                                      float(omega))

    def forced_amplitude_derivative_reference(self, Z: np.ndarray, omega: float
                                              ) -> np.ndarray:
        """:meth:`forced_amplitude_derivative` in numpy (the reference)."""
        n = self.M.shape[0]
        x_hat = Z[:n]
        H = self.K - omega * omega * self.M + 1j * omega * self.C
        dx = -np.linalg.solve(H, (-2.0 * omega * self.M + 1j * self.C) @ x_hat)
        return np.concatenate([dx, 1j * x_hat + 1j * omega * dx])

"""The dense closed form of eq. (12)-(25) along any exact flow.

``S`` of eq. (13) by an equilibrated LU solve with a condition estimate, and the
Jacobian G of eq. (25) from the flow's matrices and time derivative. Used where the
modal kernel does not apply: the first-order path (general damping matrix, complex F),
robust stability and the N-p motions.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.linalg import lapack, lu_solve

from impactcont.errors import IllConditionedWarning, ParameterError
from impactcont.orbit.flow import Flow

__all__ = ["impact_map_jacobian", "periodic_matrix", "pole_free_pd_matrix"]

_EPS = float(np.finfo(float).eps)
# warn when the relative error bound cond * eps of the solve of eq. (12) exceeds ~1e-6
_COND_WARN = 1e10


def _power_of_two_scale(v: np.ndarray) -> np.ndarray:
    """``2^-round(log2 v)`` where ``v > 0`` (1 elsewhere): an exact rescaling."""
    out = np.ones_like(v)
    pos = v > 0
    out[pos] = np.exp2(-np.round(np.log2(v[pos])))
    return out


def _solve(A: np.ndarray, B: np.ndarray, what: str) -> np.ndarray:
    """``A^-1 B`` by LU of the row- and column-equilibrated A, warning when ill-conditioned.

    Positions and velocities of a stiff chain differ by orders of magnitude, so the raw
    condition number of A mostly measures the units; after exact power-of-two row and
    column scaling it measures the problem. The 1-norm estimate (LAPACK ``gecon``) costs
    O(n^2) after the factorisation, against O(n^3) for the SVD of ``numpy.linalg.cond``.
    """
    r = _power_of_two_scale(np.max(np.abs(A), axis=1))
    As = r[:, None] * A
    c = _power_of_two_scale(np.max(np.abs(As), axis=0))
    As = As * c
    if not np.all(np.isfinite(As)):
        raise ParameterError(f"{what} has non-finite entries; check the parameters "
                             "(e.g. omega at an undamped resonance)")
    lu, piv, info = lapack.dgetrf(As)
    if info > 0:  # exactly singular
        cond = math.inf
    else:
        rcond, _ = lapack.dgecon(lu, np.linalg.norm(As, 1), norm="1")
        cond = 1.0 / rcond if rcond > 0 else math.inf
    if not cond <= _COND_WARN:
        warnings.warn(f"{what} is ill-conditioned (condition number {cond:.3g} after "
                      f"equilibration): the periodic motion may carry a relative error up to "
                      f"about {min(cond * _EPS, 1.0):.1g}. Typical causes: no damping with R = 1 "
                      "(a family of motions), or omega_i T close to a multiple of 2 pi for an "
                      "undamped mode (omega near N omega_i / k)", IllConditionedWarning,
                      stacklevel=3)
    if info > 0:
        return np.full((A.shape[0], B.shape[1]), np.nan)
    return c[:, None] * lu_solve((lu, piv), r[:, None] * B, check_finite=False)


def periodic_matrix(flow: Flow, N: int) -> tuple[np.ndarray, np.ndarray, float]:
    """``S`` of eq. (13) with the flow pieces at ``T``.

    Returns
    -------
    S : ndarray, shape (2n, 2)
        ``X(0) = S [cos delta; sin delta]``.
    DPhi : ndarray, shape (2n, 2n)
        ``D U W(T) U^-1``.
    T : float
    """
    osc = flow.osc
    T = 2.0 * math.pi * N / osc.omega
    d = np.ones(2 * osc.n)
    d[osc.n] = -osc.R
    transition, forcing = flow.matrices(T)
    DPhi = d[:, None] * transition
    DUE = d[:, None] * forcing
    S = _solve(np.eye(2 * osc.n) - DPhi, DUE, "I - D U W(T) U^-1 of eq. (12)")
    return S, DPhi, T


def impact_map_jacobian(flow: Flow, state: np.ndarray, delta: float, T: float,
                        DPhi: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Jacobian ``G`` of the impact map at a periodic motion, eq. (22)-(25).

    Parameters
    ----------
    flow : Flow
    state : ndarray, shape (2n,)
        State right after the impact.
    delta : float
        Forcing phase at the impact.
    T : float
        Time to the next impact.
    DPhi : ndarray, optional
        ``D U W(T) U^-1`` if already computed.

    Returns
    -------
    G : ndarray, shape (2n, 2n)
    h2 : float
        ``x1'(T^-)``, the impact velocity.
    """
    osc = flow.osc
    n = osc.n
    d = np.ones(2 * n)
    d[n] = -osc.R
    if DPhi is None:
        DPhi = d[:, None] * flow.transition_matrix(T)
    h0_p = DPhi[0, 1:]
    H0 = DPhi[1:, 1:]
    dE = d * (flow.forcing_matrix(T) @ np.array([-math.sin(delta), math.cos(delta)]))
    h1, H1 = dE[0], dE[1:]
    dX = d * flow.state_derivative(T, state, delta)[0]
    h2, H2 = dX[0], dX[1:]
    omega = osc.omega
    G = np.empty((2 * n, 2 * n))
    G[:-1, :-1] = H0 - np.outer(H2, h0_p) / h2
    G[:-1, -1] = H1 - H2 * h1 / h2
    G[-1, :-1] = -omega * h0_p / h2
    G[-1, -1] = 1.0 - omega * h1 / h2
    return G, float(h2)


def pole_free_pd_matrix(G_reg: np.ndarray, a: np.ndarray, b: np.ndarray, h2: complex
                        ) -> np.ndarray:
    """``E = [[G_reg + I, a], [b^T, -h2]]``, shape (m+1, m+1), of G's split
    ``G = G_reg + a b^T / h2`` (eq. 25).

    Finite through a zero-velocity impact; ``det E = -h2 det(G + I)`` (Schur
    complement), so ``E`` is singular exactly at a period-doubling (``h2 != 0``).
    Real or complex (a complex step) like its inputs.
    """
    m = G_reg.shape[0]
    E = np.empty((m + 1, m + 1), dtype=np.result_type(G_reg, a, b, h2))
    E[:m, :m] = G_reg + np.eye(m)
    E[:m, m] = a
    E[m, :m] = b
    E[m, m] = -h2
    return E

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

__all__ = ["COND_WARN", "VELOCITY_POLISH", "impact_map_jacobian", "impact_velocity",
           "periodic_matrix", "pole_free_pd_matrix", "polished_velocity", "second_form",
           "velocity_bound", "velocity_errors", "warn_ill_conditioned"]

_EPS = float(np.finfo(float).eps)
# warn when the relative error bound cond * eps of the solve of eq. (12) exceeds ~1e-6
_COND_WARN = COND_WARN = 1e10
#: The impact velocity is taken from its second exact form (:func:`impact_velocity`) when
#: the first is estimated to carry a relative error above this.
VELOCITY_POLISH = 1e-12
# ... and the two forms agree within this many times their rounding estimates (delta is a
# root of eq. 15 to rounding; off a root only the first form solves eq. 12)
_VELOCITY_AGREE = 16.0


def warn_ill_conditioned(omega: float, cond: float, stacklevel: int) -> None:
    """Warn that eq. (12) is ill-conditioned at omega (the closed form's condition estimate
    ``cond``, :func:`impactcont.kernel.closed_form.omega_setup`), when ``cond > COND_WARN``: the
    one message of the modal and the first-order paths."""
    if cond <= COND_WARN:
        return
    warnings.warn(
        f"eq. (12) is ill-conditioned at omega={omega!r} (condition estimate "
        f"{cond:.3g}): the periodic motion may carry a relative error up to about "
        f"{min(cond * _EPS, 1.0):.1g}. Typical cause: omega_i T close to a multiple of "
        "2 pi for an undamped or very lightly damped mode (omega near N omega_i / k), "
        "where the free motion of that mode is itself T-periodic",
        IllConditionedWarning, stacklevel=stacklevel + 1)


def velocity_errors(Gam, B, g, Delta, omega, R, b, delta, cos_d, sin_d):
    """Absolute rounding errors of the two exact forms of the impact velocity
    (:func:`impact_velocity`): ``(err_a, err_b)``, floats or arrays like the inputs.

    Each is ``eps`` times the size of the terms summed (the forced position or velocity
    of mass 1 at the phase, and its change over the rounding of ``delta``, about
    ``eps (1 + |delta|)``) over the divisor: ``|Delta|`` for the first form, ``|kappa g|``
    for the second.
    """
    tilt = 1.0 + abs(delta)  # ulp(delta) and the rounding of cos, sin
    xp = abs(Gam * cos_d + B * sin_d)  # |x1p(delta)|, the derivative of -x1p'/omega
    vp = abs(B * cos_d - Gam * sin_d)  # |x1p'(delta)| / omega
    err_a = _EPS * omega * (abs(B * cos_d) + abs(Gam * sin_d) + xp * tilt) / (abs(Delta)
                                                                           + 1e-300)
    err_b = _EPS * (abs(Gam * cos_d) + abs(B * sin_d) + abs(b) + vp * tilt) / (
        abs((1.0 + R) * g) + 1e-300)
    return err_a, err_b


def second_form(sigma_a, sigma_b, err_a, err_b):
    """Whether to take the impact velocity's second form (:func:`impact_velocity`): the
    first lost digits (relative error estimate above :data:`VELOCITY_POLISH`), the second
    lost fewer, and both agree within their rounding (``delta`` solves eq. 15)."""
    return ((err_a > VELOCITY_POLISH * abs(sigma_a)) & (err_b < err_a)
            & (abs(sigma_a - sigma_b) <= _VELOCITY_AGREE * (err_a + err_b)))


def impact_velocity(Gam, B, g, Delta, omega, R, b, delta):
    """Impact velocity ``sigma = x1'(T^-)`` (``h2`` of eq. 22) of the N-1 motion with
    impact phase ``delta`` (a root of eq. 15), and its estimated relative error.

    With ``x1p(delta) = Gam cos(delta) + B sin(delta)`` the forced motion of mass 1 and
    ``c, s = Gam - rho B, B + rho Gam``, ``rho = kappa omega g / Delta`` (eq. 14 in the
    kernel's form, :mod:`impactcont.kernel.closed_form`), a root satisfies two exact forms:

    - ``sigma = x1p'(delta) / Delta`` (eq. 12 at the velocity of mass 1);
    - ``sigma = (x1p(delta) - b) / (kappa g)`` (the impact condition ``x1(0) = b``).

    The first is a small difference of large terms when the forced velocity of mass 1
    nearly vanishes at the impact, which happens far above the lowest natural frequency
    (``|c, s| >> b``, with a small ``Delta``): its digits are lost there, while the second
    is exact. The first is used unless its error estimate (:func:`velocity_errors`)
    exceeds :data:`VELOCITY_POLISH` (relative), the second's is smaller and the two agree
    within their estimates (:func:`second_form`; off a root of eq. 15, e.g. a guess, only
    the first solves eq. 12). Vectorised over ``delta`` and ``b``.

    Returns
    -------
    sigma, rel_error : ndarray
        The velocity and ``eps`` times the cancellation of the form used.
    """
    delta = np.asarray(delta, dtype=float)
    cd, sd = np.cos(delta), np.sin(delta)
    err_a, err_b = velocity_errors(Gam, B, g, Delta, omega, R, b, delta, cd, sd)
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma_a = omega * (B * cd - Gam * sd) / Delta
        sigma_b = (Gam * cd + B * sd - b) / ((1.0 + R) * g)
        second = second_form(sigma_a, sigma_b, err_a, err_b)
        sigma = np.where(second, sigma_b, sigma_a)
        rel = np.where(second, err_b, err_a) / np.abs(sigma)
    return sigma, rel


def velocity_bound(Gam, B, Delta, omega):
    """An upper bound of the rounding error of the first form ``x1p'(delta) / Delta`` at
    any phase (:func:`velocity_errors` with ``|cos|, |sin| <= 1``, ``|delta| <= pi``): one
    cheap test per frequency that keeps the exact check off the fast path. Vectorised."""
    return _EPS * (2.0 + math.pi) * omega * (np.abs(Gam) + np.abs(B)) / (np.abs(Delta)
                                                                        + 1e-300)


def polished_velocity(Gam: float, B: float, g: float, Delta: float, omega: float, R: float,
                      b: float, delta: float, sigma: float) -> tuple[float | None, float]:
    """The impact velocity from its second exact form where the first, ``sigma``, lost
    digits (:func:`impact_velocity`, one motion).

    Returns
    -------
    better : float or None
        The second form's velocity, or None where ``sigma`` is kept.
    rel_error : float
        The estimated relative error of the velocity kept.
    """
    cd, sd = math.cos(delta), math.sin(delta)
    err_a, err_b = velocity_errors(Gam, B, g, Delta, omega, R, b, delta, cd, sd)
    if err_b < err_a:
        better = (Gam * cd + B * sd - b) / ((1.0 + R) * g)
        if second_form(sigma, better, err_a, err_b):
            return better, err_b / max(abs(better), 1e-300)
    return None, err_a / max(abs(sigma), 1e-300)


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

"""Closed-form periodic N-1 motions (eq. 11-16) and their stability (eq. 17-25)."""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings

import numpy as np
from scipy.linalg import lapack, lu_solve

from impactcont.errors import (
    IllConditionedWarning,
    LowImpactVelocityWarning,
    NearFoldWarning,
    ParameterError,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.extrema import interior_maxima, sample_times
from impactcont.orbit.flow import Flow

__all__ = [
    "IllConditionedWarning",  # defined in impactcont.errors, re-exported here
    "PeriodicOrbit",
    "impact_map_jacobian",
    "orbit_at_phase",
    "periodic_orbits",
]

log = logging.getLogger(__name__)

_EPS = float(np.finfo(float).eps)
# warn when the relative error bound cond * eps of the solve of eq. (12) exceeds ~1e-6
_COND_WARN = 1e10
# warn when G of eq. (25) may carry a relative error above ~1e-8 (eps |v| / |h2|)
_H2_REL_ERROR_WARN = 1e-8
# warn when the impact phase of eq. (15) may carry an error above ~1e-10 (eps r / sqrt(r^2-b^2))
_FOLD_ERROR_WARN = 1e-10


@dataclasses.dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """One periodic N-1 motion: one impact every N forcing periods.

    Attributes
    ----------
    oscillator : ImpactOscillator
    N : int
        Forcing periods per impact; the period is ``T = 2 pi N / omega``.
    delta : float
        Forcing phase at the impact, in ``(-pi, pi]`` (eq. 15).
    root : int
        +1 or -1: the sign in front of the square root of eq. (15)
        (``sin delta = (b s + root c r) / (c^2 + s^2)``, ``r = sqrt(c^2+s^2-b^2)``).
    state : ndarray, shape (2n,)
        ``X(0) = [x; x']`` right after the impact (eq. 13).
    period : float
        ``T``.
    G : ndarray, shape (2n, 2n)
        Jacobian of the impact map in ``z = [dx2..dxn, dx1'..dxn', d delta]`` (eq. 25).
    multipliers : ndarray of complex, shape (2n,)
        Eigenvalues of G, largest modulus first.
    impact_velocity : float
        ``x1'(T^-)``, velocity of mass 1 just before impact (``h2`` of eq. 22).
    gap_min : float
        Smallest ``b - x1`` at the interior local maxima of ``x1`` over ``(0, T)``;
        ``+inf`` when ``x1`` has none.
    gap_min_time : float
        Time of that maximum after the impact (NaN when there is none).
    physical : bool
        ``impact_velocity > 0`` (mass 1 arrives towards the stop and leaves it)
        and ``gap_min > 0`` (no contact inside the period, eq. 16).
    reason : str
        Why the motion is not physical ("" when it is).
    """

    oscillator: ImpactOscillator
    N: int
    delta: float
    root: int
    state: np.ndarray
    period: float
    G: np.ndarray
    multipliers: np.ndarray
    impact_velocity: float
    gap_min: float
    gap_min_time: float
    physical: bool
    reason: str

    @property
    def spectral_radius(self) -> float:
        """``rho(G)``, the largest multiplier modulus."""
        return float(np.abs(self.multipliers).max())

    @property
    def stable(self) -> bool:
        """Asymptotically stable by Theorem 3.1: ``rho(G) < 1``."""
        return self.spectral_radius < 1.0

    def time_series(self, num: int = 400, periods: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Exact state over ``periods`` repetitions of the motion (for plots).

        Returns
        -------
        t : ndarray, shape (periods*num,)
            Time since the reference impact.
        X : ndarray, shape (periods*num, 2n)
            State; each repetition restarts at ``self.state`` after the impact.
        """
        if periods < 1 or num < 2:
            raise ParameterError(f"need periods >= 1 and num >= 2; got periods={periods!r}, "
                                 f"num={num!r}")
        flow = Flow(self.oscillator)
        tau = np.linspace(0.0, self.period, num)
        X = flow.state(tau, self.state, self.delta)
        t = np.concatenate([k * self.period + tau for k in range(periods)])
        return t, np.tile(X, (periods, 1))

    def __repr__(self) -> str:
        return (f"PeriodicOrbit(N={self.N}, delta={self.delta:.12g}, "
                f"impact_velocity={self.impact_velocity:.6g}, gap_min={self.gap_min:.6g}, "
                f"rho={self.spectral_radius:.6g}, stable={self.stable}, "
                f"physical={self.physical})")


def _check_N(N: object) -> int:
    if isinstance(N, bool) or not isinstance(N, (int, np.integer)) or N < 1:
        raise ParameterError(f"N must be an integer >= 1 (impact every N forcing periods); "
                             f"got {N!r}")
    return int(N)


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


def orbit_at_phase(osc: ImpactOscillator, N: int, delta: float, *, root: int = 0,
                   flow: Flow | None = None, S: np.ndarray | None = None,
                   DPhi: np.ndarray | None = None) -> PeriodicOrbit:
    """The periodic N-1 motion with impact phase ``delta`` (which must satisfy eq. 14).

    Computes the state (eq. 13), G (eq. 25), multipliers, impact velocity and the
    interior-contact check of eq. (16).
    """
    N = _check_N(N)
    flow = flow or Flow(osc)
    if S is None or DPhi is None:
        S, DPhi, T = periodic_matrix(flow, N)
    else:
        T = 2.0 * math.pi * N / osc.omega
    state = S @ np.array([math.cos(delta), math.sin(delta)])
    G, h2 = impact_map_jacobian(flow, state, delta, T, DPhi)
    multipliers = np.linalg.eigvals(G)
    multipliers = multipliers[np.argsort(-np.abs(multipliers), kind="stable")]

    times, peaks = interior_maxima(flow.mass1(state, delta), sample_times(flow, 0.0, T))
    if peaks.size:
        k = int(np.argmax(peaks))
        gap_min, gap_time = float(osc.b - peaks[k]), float(times[k])
    else:
        gap_min, gap_time = math.inf, math.nan

    reasons = []
    if not h2 > 0:
        reasons.append(f"impact velocity {h2:.3g} <= 0: mass 1 does not arrive towards the stop")
    if not gap_min > 0:
        reasons.append(f"x1 reaches the stop inside the period (gap_min={gap_min:.3g} at "
                       f"t={gap_time:.6g})")
    return PeriodicOrbit(oscillator=osc, N=N, delta=float(delta), root=root, state=state,
                         period=T, G=G, multipliers=multipliers, impact_velocity=h2,
                         gap_min=gap_min, gap_min_time=gap_time, physical=not reasons,
                         reason="; ".join(reasons))


def periodic_orbits(osc: ImpactOscillator, N: int) -> list[PeriodicOrbit]:
    """Every root of eq. (15): the candidate periodic N-1 motions.

    Parameters
    ----------
    osc : ImpactOscillator
    N : int
        One impact every N forcing periods.

    Returns
    -------
    list of PeriodicOrbit
        Zero (``c^2 + s^2 < b^2``), one (a double root) or two motions. Each
        carries its ``physical`` flag and ``reason``: a root that is not a
        physical motion is reported, never silently dropped.
    """
    N = _check_N(N)
    flow = Flow(osc)
    S, DPhi, _ = periodic_matrix(flow, N)
    c, s = S[0]
    r2 = c * c + s * s
    b = osc.b
    if r2 == 0.0:
        if b == 0.0:
            raise ParameterError("c = s = 0 and b = 0: every phase satisfies eq. (14); the "
                                 "forcing does not reach mass 1 (check F)")
        return []
    disc = r2 - b * b
    if disc < 0:
        log.debug("no N=%d motion: c^2 + s^2 = %.6g < b^2 = %.6g", N, r2, b * b)
        return []
    root_r = math.sqrt(disc)
    # the phase of eq. (15) inherits the rounding of disc amplified by r / sqrt(disc)
    phase_error = _EPS * math.sqrt(r2) / root_r if root_r > 0 else math.sqrt(_EPS)
    if phase_error > _FOLD_ERROR_WARN:
        warnings.warn(f"c^2 + s^2 = {r2:.17g} is within {disc / r2:.2g} (relative) of b^2 = "
                      f"{b * b:.17g}: a fold of eq. (15), where the two roots merge; the impact "
                      f"phase is known only to about {phase_error:.1g} rad", NearFoldWarning,
                      stacklevel=2)
    out = []
    for sign in ((+1, -1) if root_r > 0 else (+1,)):
        sin_d = (b * s + sign * c * root_r) / r2
        cos_d = (b * c - sign * s * root_r) / r2
        delta = math.atan2(sin_d, cos_d)
        orbit = orbit_at_phase(osc, N, delta, root=sign, flow=flow, S=S, DPhi=DPhi)
        _warn_low_impact_velocity(orbit)
        out.append(orbit)
    return out


def _warn_low_impact_velocity(orbit: PeriodicOrbit) -> None:
    """Warn when G is inexact because the impact velocity is tiny (G ~ 1/h2, eq. 25).

    ``h2`` is a sum of terms of the size of the velocities of the motion, so it carries
    an absolute error of about ``eps * v_scale``; G inherits ``eps * v_scale / |h2|``.
    Only the single-point API warns: a branch passes through ``h2 = 0`` at a ZV point
    on purpose, and its detection evaluates G there.
    """
    osc, state, h2 = orbit.oscillator, orbit.state, orbit.impact_velocity
    n = osc.n
    v_scale = max(float(np.abs(state[n:]).max()), osc.omega * float(np.abs(state[:n]).max()))
    if not abs(h2) * _H2_REL_ERROR_WARN >= _EPS * v_scale:
        warnings.warn(f"impact velocity h2 = {h2:.3g} is tiny against the velocity scale "
                      f"{v_scale:.3g} of the motion: G of eq. (25) grows like 1/h2 and may carry "
                      f"a relative error of about {_EPS * v_scale / max(abs(h2), 1e-300):.1g} "
                      f"(root {orbit.root:+d}, delta={orbit.delta!r}, omega={osc.omega!r}, "
                      f"b={osc.b!r})", LowImpactVelocityWarning, stacklevel=3)


def amplitude_squared(osc: ImpactOscillator, N: int) -> float:
    """``c^2 + s^2`` of eq. (14)-(15): motions exist iff it is ``>= b^2``."""
    S, _, _ = periodic_matrix(Flow(osc), _check_N(N))
    return float(S[0, 0] ** 2 + S[0, 1] ** 2)

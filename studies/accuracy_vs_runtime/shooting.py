"""The scipy baselines: shooting with ``solve_ivp`` and brute-force simulation.

Independent of impactcont's closed form: the equations of motion (eq. 1) are
integrated by ``scipy.integrate.solve_ivp`` with a terminal event at the stop
(eq. 3) and the impact law of eq. (4). Periodic N-1 motions are fixed points
of the impact map ``P`` on the section ``x1 = b``,
``z = [x2..xn, x1'..xn', delta]`` (eq. 19): shooting finds them by Newton on
``P(z) - z`` with a forward-difference Jacobian; the multipliers are the
eigenvalues of a central-difference Jacobian of ``P`` at the fixed point.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
from scipy.integrate import solve_ivp

import impactcont as ic

log = logging.getLogger(__name__)

TWO_PI = 2.0 * math.pi


class ShootingError(RuntimeError):
    """Shooting did not converge or the impact map is undefined (no impact in time)."""


@dataclasses.dataclass
class ImpactMap:
    """The impact map of an oscillator, integrated by ``solve_ivp``.

    Parameters
    ----------
    osc : impactcont.ImpactOscillator
        Only its matrices and parameters are used (no closed form).
    N : int
        Forcing periods per impact (the phase is shifted back by ``2 pi N``).
    method : str
        ``"RK45"``, ``"DOP853"`` or ``"Radau"``.
    rtol : float
        Relative tolerance; ``atol = rtol * 1e-3``.
    blind : float
        Fraction of the period ``T`` during which the stop is ignored (default 0.5).
    """

    osc: ic.ImpactOscillator
    N: int
    method: str
    rtol: float
    blind: float = 0.5

    def __post_init__(self) -> None:
        osc = self.osc
        n = osc.n
        Minv = np.linalg.inv(osc.M)
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -Minv @ osc.K
        A[n:, n:] = -Minv @ osc.C
        self.A = A
        self.g = np.concatenate([np.zeros(n), Minv @ osc.F])
        self.n = n
        self.period = TWO_PI * self.N / osc.omega
        self.evaluations = 0

    def flight(self, X0: np.ndarray, delta: float, t_max: float, *, maxima: bool = False):
        """Integrate from ``X0`` at phase ``delta`` to the first impact (or ``t_max``)."""
        om, b, A, g = self.osc.omega, self.osc.b, self.A, self.g

        def rhs(t, X):
            return A @ X + g * math.cos(om * t + delta)

        t_min = self.blind * self.period

        def hit(t, X):
            # blind for the first part of the flight: a grazing contact there is not the
            # impact of the N-1 motion (this lets shooting follow the motion through a graze,
            # where gap_min < 0, as the closed form does)
            return X[0] - b if t >= t_min else -1.0

        hit.terminal, hit.direction = True, 1.0
        events = [hit]
        if maxima:
            def top(t, X):
                return X[self.n]

            top.terminal, top.direction = False, -1.0
            events.append(top)
        kwargs = {"jac": A} if self.method == "Radau" else {}
        # solve_ivp looks for events only at its step points: without a cap on the step it
        # steps over the impact of the n = 50 motion (x1 exceeds b only briefly after T)
        sol = solve_ivp(rhs, (0.0, t_max), X0, method=self.method, rtol=self.rtol,
                        atol=self.rtol * 1e-3, events=events, max_step=self.period / 64,
                        **kwargs)
        self.evaluations += 1
        if sol.status == -1:
            raise ShootingError(sol.message)
        return sol

    def __call__(self, z: np.ndarray) -> np.ndarray:
        """``P(z)``: the section point right after the next impact."""
        n = self.n
        X0 = np.concatenate([[self.osc.b], z[:-1]])
        sol = self.flight(X0, float(z[-1]), 1.5 * self.period)
        if sol.t_events[0].size == 0:
            raise ShootingError("no impact within 1.5 periods")
        t_hit = sol.t_events[0][0]
        X = sol.y_events[0][0].copy()
        X[n] *= -self.osc.R
        return np.concatenate([X[1:], [z[-1] + self.osc.omega * t_hit - TWO_PI * self.N]])

    def gap_min(self, z: np.ndarray) -> float:
        """``b - max x1`` over the interior maxima of one flight (eq. 16), by events."""
        X0 = np.concatenate([[self.osc.b], z[:-1]])
        sol = self.flight(X0, float(z[-1]), 1.5 * self.period, maxima=True)
        tops = sol.y_events[1]
        if tops.size == 0:
            return math.inf
        return float(self.osc.b - tops[:, 0].max())


def jacobian(P: ImpactMap, z: np.ndarray, Pz: np.ndarray | None = None, *,
             central: bool = False) -> np.ndarray:
    """Finite-difference Jacobian of ``P`` (forward, or central for the multipliers).

    The step balances truncation and the integration error ``rtol``:
    ``sqrt(rtol)`` forward, ``rtol^(1/3)`` central (relative to ``max(1, |z_j|)``).
    """
    m = z.size
    J = np.empty((m, m))
    base = P.rtol ** (1.0 / 3.0) if central else math.sqrt(P.rtol)
    if Pz is None and not central:
        Pz = P(z)
    for j in range(m):
        h = base * max(1.0, abs(z[j]))
        e = np.zeros(m)
        e[j] = h
        if central:
            J[:, j] = (P(z + e) - P(z - e)) / (2 * h)
        else:
            J[:, j] = (P(z + e) - Pz) / h
    return J


def shoot(P: ImpactMap, z0: np.ndarray, *, max_iter: int = 30, multipliers: bool = True
          ) -> tuple[np.ndarray, np.ndarray | None]:
    """Newton (chord: Jacobian at the start, refreshed when convergence stalls).

    Returns the fixed point ``z`` and the multipliers (central-difference
    Jacobian at ``z``), largest modulus first.
    """
    z = np.array(z0, dtype=float)
    Pz = P(z)
    J = jacobian(P, z, Pz) - np.eye(z.size)
    last = math.inf
    tol = 10.0 * P.rtol
    for _ in range(max_iter):
        r = Pz - z
        step = np.linalg.solve(J, -r)
        z = z + step
        Pz = P(z)
        size = np.abs(step).max() / max(1.0, np.abs(z).max())
        if size <= tol:
            break
        if size > 0.5 * last:  # slow chord convergence: fresh Jacobian
            J = jacobian(P, z, Pz) - np.eye(z.size)
        last = size
    else:
        raise ShootingError(f"Newton did not converge in {max_iter} iterations")
    if not multipliers:
        return z, None
    mu = np.linalg.eigvals(jacobian(P, z, central=True))
    return z, mu[np.argsort(-np.abs(mu), kind="stable")]


def iterate(P: ImpactMap, z0: np.ndarray, count: int) -> np.ndarray:
    """Brute force: apply the impact map ``count`` times (the motion settles)."""
    z = np.array(z0, dtype=float)
    for _ in range(count):
        z = P(z)
        z[-1] = math.remainder(z[-1], TWO_PI)
    return z

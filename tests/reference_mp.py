"""A high-precision reference of the closed form, independent of impactcont.

Written from the equations (EQUATIONS.md, eq. 5-25), in mpmath at 50 digits by
default, and sharing no code with impactcont. It differs from impactcont's
route wherever that is cheap, so that a shared mistake is unlikely:

- modes from a Cholesky reduction ``L^-1 K L^-T`` and ``mpmath.eigsy``
  (impactcont: ``scipy.linalg.eigh(K, M)``);
- the free modal transfer ``exp(A_i t)`` of each mode by Sylvester's formula
  on the two roots ``r_1 r_2 = omega_i^2``, ``r_1 + r_2 = -2 a_i`` (impactcont:
  one closed form per damping class);
- the steady forced response in physical coordinates,
  ``Z = (K - omega^2 M + i omega C)^-1 F`` (impactcont: modal gamma, beta);
- interior maxima of ``x1`` from sign changes of ``x1'`` on a grid four times
  finer than impactcont's, each polished by a bracketing root finder
  (impactcont: roots of ``x1''`` first, then safeguarded Newton).

Results are mpmath numbers; :func:`to_float` converts a result to floats.
The cost is pure-Python big-float arithmetic: about 0.1 s for n = 2, a few
seconds for n = 10 and a minute or two for n = 50 with the multipliers
(``mpmath.eig`` of the 2n x 2n G).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import mpmath
import numpy as np

__all__ = ["MPSystem", "closed_form", "gap_near", "matched_error", "to_float"]


def _mpf_matrix(a: Any) -> mpmath.matrix:
    a = np.atleast_2d(np.asarray(a, dtype=float))
    return mpmath.matrix([[mpmath.mpf(float(v)) for v in row] for row in a])


@dataclasses.dataclass
class MPSystem:
    """The oscillator of eq. (1)-(4) in mpmath, with its modes (eq. 5).

    Parameters
    ----------
    M, K : array_like, shape (n, n)
        Mass and stiffness (symmetric positive definite); floats taken exactly.
    F : array_like, shape (n,)
    R, b : float
    alpha, beta : float
        Rayleigh damping ``C = alpha M + beta K`` (the paper's ``eta`` is ``beta = 2 eta``).
    dps : int
        Decimal digits of the working precision.
    """

    M: Any
    K: Any
    F: Any
    R: float
    b: float
    alpha: float = 0.0
    beta: float = 0.0
    dps: int = 50

    def __post_init__(self) -> None:
        with mpmath.workdps(self.dps):
            self.n = int(np.asarray(self.M).shape[0])
            self.Mm, self.Km = _mpf_matrix(self.M), _mpf_matrix(self.K)
            self.Fm = _mpf_matrix(np.reshape(self.F, (-1, 1)))
            self.Rm, self.bm = mpmath.mpf(self.R), mpmath.mpf(self.b)
            self.am, self.bbm = mpmath.mpf(self.alpha), mpmath.mpf(self.beta)
            self.Cm = self.am * self.Mm + self.bbm * self.Km
            L = mpmath.cholesky(self.Mm)
            Li = mpmath.inverse(L)
            lam, Q = mpmath.eigsy(Li * self.Km * Li.T)
            self.u = Li.T * Q  # u^T M u = I
            self.ui = self.u.T * self.Mm
            self.w = [mpmath.sqrt(lam[i]) for i in range(self.n)]
            self.decay = [(self.am + self.bbm * lam[i]) / 2 for i in range(self.n)]
            self.Minv = mpmath.inverse(self.Mm)

    # -- the flow of eq. (9) -----------------------------------------------------------------
    def mode_transfer(self, i: int, t: Any) -> tuple[Any, Any, Any, Any]:
        """``exp([[0, 1], [-w^2, -2a]] t)`` of mode i by Sylvester's formula."""
        w, a = self.w[i], self.decay[i]
        disc = mpmath.sqrt(mpmath.mpc(a * a - w * w))
        if abs(disc) < mpmath.mpf(10) ** (-self.dps + 5):  # critical damping
            e = mpmath.exp(-a * t)
            return e * (1 + a * t), e * t, -w * w * e * t, e * (1 - a * t)
        r2 = -a - disc
        r1 = w * w / r2  # r1 r2 = w^2: no cancellation in -a + disc when a >> w
        e1, e2 = mpmath.exp(r1 * t), mpmath.exp(r2 * t)
        den = r1 - r2
        w11 = (r1 * e2 - r2 * e1) / den
        w12 = (e1 - e2) / den
        w22 = (r1 * e1 - r2 * e2) / den
        return (mpmath.re(w11), mpmath.re(w12), -w * w * mpmath.re(w12), mpmath.re(w22))

    def transition(self, t: Any) -> mpmath.matrix:
        """``Phi(t) = U W(t) U^-1``, 2n x 2n."""
        n = self.n
        blocks = [self.mode_transfer(i, t) for i in range(n)]
        out = mpmath.zeros(2 * n, 2 * n)
        for k, (r0, c0) in enumerate([(0, 0), (0, n), (n, 0), (n, n)]):
            diag = mpmath.diag([blk[k] for blk in blocks])
            part = self.u * diag * self.ui
            for i in range(n):
                for j in range(n):
                    out[r0 + i, c0 + j] = part[i, j]
        return out

    def forced_amplitude(self, omega: Any) -> mpmath.matrix:
        """``Z = (K - omega^2 M + i omega C)^-1 F`` (complex, n x 1)."""
        A = self.Km - omega * omega * self.Mm + mpmath.mpc(0, 1) * omega * self.Cm
        return mpmath.lu_solve(A, self.Fm)

    def forced_columns(self, Z: mpmath.matrix, omega: Any, t: Any) -> mpmath.matrix:
        """``P(t)``, 2n x 2: the steady response is ``P(t) [cos delta; sin delta]``."""
        n = self.n
        e = mpmath.expjpi(omega * t / mpmath.pi)
        P = mpmath.zeros(2 * n, 2)
        for i in range(n):
            z = Z[i] * e
            P[i, 0], P[i, 1] = mpmath.re(z), -mpmath.im(z)
            P[n + i, 0], P[n + i, 1] = -omega * mpmath.im(z), -omega * mpmath.re(z)
        return P

    def impact_matrix(self) -> mpmath.matrix:
        d = mpmath.eye(2 * self.n)
        d[self.n, self.n] = -self.Rm
        return d

    def vector_field(self, X: mpmath.matrix, phase: Any) -> mpmath.matrix:
        """``X' = [v; M^-1 (F cos(phase) - C v - K x)]``."""
        n = self.n
        x = mpmath.matrix([X[i] for i in range(n)])
        v = mpmath.matrix([X[n + i] for i in range(n)])
        acc = self.Minv * (self.Fm * mpmath.cos(phase) - self.Cm * v - self.Km * x)
        return mpmath.matrix([v[i] for i in range(n)] + [acc[i] for i in range(n)])


def _solve_columns(A: mpmath.matrix, B: mpmath.matrix) -> mpmath.matrix:
    out = mpmath.zeros(B.rows, B.cols)
    for j in range(B.cols):
        col = mpmath.lu_solve(A, B.column(j))
        for i in range(B.rows):
            out[i, j] = col[i]
    return out


def _mass1(system: MPSystem, Z: mpmath.matrix, omega: Any, X0: mpmath.matrix, delta: Any):
    """``t -> (x1(t), x1'(t))`` along a flight, O(n) per time via modal coordinates."""
    n = system.n
    P0 = system.forced_columns(Z, omega, 0)
    cd = mpmath.matrix([mpmath.cos(delta), mpmath.sin(delta)])
    Xp0 = P0 * cd
    dx = mpmath.matrix([X0[i] - Xp0[i] for i in range(n)])
    dv = mpmath.matrix([X0[n + i] - Xp0[n + i] for i in range(n)])
    q, qd = system.ui * dx, system.ui * dv
    u0 = [system.u[0, i] for i in range(n)]

    def x1(t: Any) -> tuple[Any, Any]:
        z = Z[0] * mpmath.expjpi((omega * t + delta) / mpmath.pi)
        pos, vel = mpmath.re(z), -omega * mpmath.im(z)
        for i in range(n):
            w11, w12, w21, w22 = system.mode_transfer(i, t)
            pos += u0[i] * (w11 * q[i] + w12 * qd[i])
            vel += u0[i] * (w21 * q[i] + w22 * qd[i])
        return pos, vel

    return x1


def _interior_maxima(system: MPSystem, x1, omega: Any, T: Any, cells_per_period: int = 64
                     ) -> list[tuple[Any, Any]]:
    """``(t, x1(t))`` at every sign change + -> - of ``x1'`` on (0, T)."""
    fastest = max([float(omega)] + [
        float(mpmath.sqrt(max(w * w - a * a, 0))) for w, a in zip(system.w, system.decay,
                                                                   strict=True)])
    count = max(16, math.ceil(float(T) * fastest * cells_per_period / (2 * math.pi)))
    grid = [T * k / count for k in range(count + 1)]
    rates = [float(a + mpmath.sqrt(max(a * a - w * w, 0)))
             for w, a in zip(system.w, system.decay, strict=True)]
    tau = 1.0 / (cells_per_period * max([*rates, 1e-300]))
    step = float(grid[1])
    if tau < step:  # fast over-damped transients after the impact: refine geometrically
        extra = [mpmath.mpf(step) * mpmath.mpf(2) ** -k
                 for k in range(1, math.ceil(math.log2(step / tau)) + 1)]
        grid = sorted(set(grid[:1] + extra + grid[1:]))
    vel = [x1(t)[1] for t in grid]
    out = []
    for k in range(len(grid) - 1):
        if vel[k] > 0 and vel[k + 1] <= 0 and 0 < grid[k + 1] < T:
            if vel[k + 1] == 0:
                tm = grid[k + 1]
            else:
                tm = mpmath.findroot(lambda s: x1(s)[1], (grid[k], grid[k + 1]),
                                     solver="anderson")
            out.append((tm, x1(tm)[0]))
    return out


def closed_form(system: MPSystem, omega: float, N: int, *, multipliers: bool = True,
                gap: bool = True, roots: tuple[int, ...] = (1, -1)) -> dict[str, Any]:
    """The periodic N-1 motions of eq. (12)-(16) and their G (eq. 25), in high precision.

    Parameters
    ----------
    system : MPSystem
    omega : float
        Forcing frequency (taken exactly).
    N : int
        Forcing periods per impact.
    multipliers : bool
        Also the eigenvalues of G (``mpmath.eig``, the costly part for large n).
    gap : bool
        Also ``gap_min`` (interior maxima of x1, eq. 16).
    roots : tuple of int
        Which signs of eq. (15) to evaluate.

    Returns
    -------
    dict
        ``c, s, amplitude_squared, cond`` (1-norm condition number of
        ``I - D Phi(T)``) and ``orbits``: one dict per root with ``root, delta,
        state, impact_velocity, G, multipliers, gap_min, gap_min_time``.
    """
    with mpmath.workdps(system.dps):
        n = system.n
        om = mpmath.mpf(omega)
        T = 2 * mpmath.pi * N / om
        Z = system.forced_amplitude(om)
        Phi = system.transition(T)
        E = system.forced_columns(Z, om, T) - Phi * system.forced_columns(Z, om, 0)
        Dm = system.impact_matrix()
        A = mpmath.eye(2 * n) - Dm * Phi
        S = _solve_columns(A, Dm * E)
        cond = mpmath.norm(A, 1) * mpmath.norm(mpmath.inverse(A), 1) if n <= 30 else None
        c, s, b = S[0, 0], S[0, 1], system.bm
        r2 = c * c + s * s
        out: dict[str, Any] = {"c": c, "s": s, "amplitude_squared": r2, "cond": cond,
                               "period": T, "orbits": []}
        if r2 < b * b:
            return out
        root_r = mpmath.sqrt(r2 - b * b)
        DPhi = Dm * Phi
        for sign in roots:
            sin_d = (b * s + sign * c * root_r) / r2
            cos_d = (b * c - sign * s * root_r) / r2
            delta = mpmath.atan2(sin_d, cos_d)
            cd = mpmath.matrix([mpmath.cos(delta), mpmath.sin(delta)])
            X0 = S * cd
            XT = Phi * X0 + E * cd
            dX = Dm * system.vector_field(XT, om * T + delta)
            dE = Dm * (E * mpmath.matrix([-mpmath.sin(delta), mpmath.cos(delta)]))
            h2 = dX[0]
            G = mpmath.zeros(2 * n, 2 * n)
            for i in range(1, 2 * n):
                for j in range(1, 2 * n):
                    G[i - 1, j - 1] = DPhi[i, j] - dX[i] * DPhi[0, j] / h2
                G[i - 1, 2 * n - 1] = dE[i] - dX[i] * dE[0] / h2
            for j in range(1, 2 * n):
                G[2 * n - 1, j - 1] = -om * DPhi[0, j] / h2
            G[2 * n - 1, 2 * n - 1] = 1 - om * dE[0] / h2
            orbit: dict[str, Any] = {"root": sign, "delta": delta, "state": X0,
                                     "impact_velocity": h2, "G": G}
            if multipliers:
                ev = mpmath.eig(G, left=False, right=False)
                orbit["multipliers"] = sorted(ev, key=lambda z: -abs(z))
            if gap:
                maxima = _interior_maxima(system, _mass1(system, Z, om, X0, delta), om, T)
                if maxima:
                    tm, xm = max(maxima, key=lambda p: p[1])
                    orbit["gap_min"], orbit["gap_min_time"] = b - xm, tm
                else:
                    orbit["gap_min"], orbit["gap_min_time"] = mpmath.inf, mpmath.nan
            out["orbits"].append(orbit)
        return out


def gap_near(system: MPSystem, omega: float, N: int, root: int, t_guess: float
             ) -> tuple[Any, Any]:
    """``b - x1(t*)`` at the interior maximum of ``x1`` nearest ``t_guess`` (grazing, eq. 16).

    Cheaper than :func:`closed_form` with ``gap=True``: one local root of ``x1'``.
    Returns ``(gap, t*)``.
    """
    with mpmath.workdps(system.dps):
        res = closed_form(system, omega, N, multipliers=False, gap=False, roots=(root,))
        orbit = res["orbits"][0]
        om = mpmath.mpf(omega)
        x1 = _mass1(system, system.forced_amplitude(om), om, orbit["state"], orbit["delta"])
        tm = mpmath.findroot(lambda s: x1(s)[1], mpmath.mpf(t_guess))
        return system.bm - x1(tm)[0], tm


def to_float(value: Any) -> Any:
    """mpmath numbers, matrices, lists and dicts of them -> floats / complex / ndarrays."""
    if isinstance(value, dict):
        return {k: to_float(v) for k, v in value.items()}
    if isinstance(value, list):
        return [to_float(v) for v in value]
    if isinstance(value, mpmath.matrix):
        return np.array([[float(value[i, j]) for j in range(value.cols)]
                         for i in range(value.rows)]).squeeze(axis=1 if value.cols == 1 else ())
    if isinstance(value, mpmath.mpc):
        return complex(value)
    if isinstance(value, mpmath.mpf):
        return float(value)
    return value


def matched_error(values: Any, reference: Any) -> float:
    """Largest ``|values_k - reference_pi(k)|`` under the best one-to-one matching.

    Multipliers of equal modulus (complex pairs) come in no canonical order;
    this compares them as sets.
    """
    from scipy.optimize import linear_sum_assignment

    a = np.asarray(values, dtype=complex).ravel()
    r = np.asarray(reference, dtype=complex).ravel()
    cost = np.abs(a[:, None] - r[None, :])
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].max())

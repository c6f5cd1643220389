"""The two-impact periodic motions of a vibro-impact energy sink (VI-NES), derived.

A primary oscillator (mass 1, stiffness 1, damping ratio ``zeta``) forced by
``cos(r t + delta)``, a free ball of mass ratio ``mu`` in a cavity of the primary,
``s = x2 - x1`` in ``[-b_low, b]``, restitution ``R`` at the upper wall (``s = b``) and
``R_low`` at the lower (``s = -b_low``); optionally gravity ``g`` along the axis (a vertical
VI-NES: ``-g`` on both masses, per unit mass). Lengths in ``F/k``, time in ``1/w_n``.

The motion sought: one impact on each wall per forcing period (``"UL"``), the upper one
at ``t = 0``, the lower one at ``t = t1`` (not assumed ``T/2``), period ``T = 2 pi / r``.
Write ``x1 = -g + Re(P e^{irt}) + h(t)`` with ``h`` the free damped oscillation, ``(h0, g0)``
after the upper impact and ``(h(t1), h'(t1-) + w)`` after the lower one (``w`` the jump of
the primary's velocity there); the ball flies on a parabola. For a fixed ``t1`` the seven
conditions

- (E1) the ball reaches the lower wall at ``t1``; (E2, E3) the two-body impact law there
  (momentum, restitution ``R_low``) gives ``w`` and the ball's velocity ``u2`` after it;
- (E4) the ball reaches the upper wall at ``T``; (E5, E6) the law there (``R``) returns
  the primary's velocity ``x1'(0+)`` and the ball's ``u1``;
- (E7) the primary's position is periodic, ``x1(T) = x1(0)``

are **linear** in ``z = (h0, g0, X, Y, u1, u2, w)`` with ``P = X + iY`` free: their
solution is the forcing phasor for which a UL motion with that ``t1`` exists. The motion
of the actual forcing (``P = A e^{i delta}``, ``A = 1/(1 - r^2 + 2 i zeta r)``) is where

    f(t1) = |P(t1)|^2 / |A|^2 - 1 = 0,                                         (F)

one scalar equation in ``(0, T)``, scanned and bracketed: every UL motion, symmetric or
not. With symmetric walls and no gravity, ``t1 = T/2`` is singular: the seven conditions
have a line of solutions there (every forcing amplitude has its symmetric motion), and the
symmetric motions are where that line meets ``|P| = |A|`` (a quadratic, two roots).

Stability: the first-return map to the upper wall (state ``(x1, x1', x2', theta)`` after
the impact, ``x2 = x1 + b``), written with the same closed-form flights and the impact
times found by bracketing; its Jacobian by central differences; the multipliers its
eigenvalues.

Independent of the package: no code is shared (numpy and scipy only).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.optimize import brentq


@dataclasses.dataclass(frozen=True)
class VINES:
    """Parameters of the VI-NES (see the module docstring)."""

    r: float
    mu: float
    zeta: float
    b: float
    b_low: float
    R: float
    R_low: float
    g: float = 0.0

    def __post_init__(self) -> None:
        for name, ok in (("r", self.r > 0), ("mu", self.mu > 0), ("zeta", 0 <= self.zeta < 1),
                         ("b + b_low", self.b + self.b_low > 0), ("R", 0 <= self.R <= 1),
                         ("R_low", 0 <= self.R_low <= 1)):
            if not ok:
                raise ValueError(f"{name} is out of range in {self}")

    @property
    def T(self) -> float:
        return 2.0 * math.pi / self.r

    @property
    def A(self) -> complex:
        """Forced response of the primary per unit force (the phasor at ``delta = 0``)."""
        return 1.0 / complex(1.0 - self.r ** 2, 2.0 * self.zeta * self.r)

    @property
    def symmetric(self) -> bool:
        return self.R_low == self.R and self.g == 0.0


@dataclasses.dataclass(frozen=True)
class Motion:
    """One UL motion: after the upper impact (``t = 0``) and the lower one (``t = t1``)."""

    p: VINES
    t1: float
    delta: float
    z: np.ndarray  # (h0, g0, X, Y, u1, u2, w)
    state_upper: np.ndarray  # (x1, x2, x1', x2') after the upper impact
    state_lower: np.ndarray  # after the lower impact
    approach_upper: float  # s' just before the upper impact (> 0: towards the wall)
    approach_lower: float  # -s' just before the lower impact (> 0: towards the wall)
    gap_min: float  # smallest clearance to either wall strictly inside the flights
    amplitude: float  # max |x1 + g| over the period (about the static position)
    multipliers: np.ndarray  # of the period map, largest modulus first

    @property
    def physical(self) -> bool:
        return self.approach_upper > 0 and self.approach_lower > 0 and self.gap_min > 0

    @property
    def stable(self) -> bool:
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    @property
    def flight_times(self) -> np.ndarray:
        return np.array([self.t1, self.p.T - self.t1])


def transition(t: float, zeta: float) -> np.ndarray:
    """``(h, h')(t) = Phi(t) (h, h')(0)`` for ``h'' + 2 zeta h' + h = 0``."""
    wd = math.sqrt(1.0 - zeta * zeta)
    e, c, s = math.exp(-zeta * t), math.cos(wd * t), math.sin(wd * t)
    return e * np.array([[c + zeta / wd * s, s / wd], [-s / wd, c - zeta / wd * s]])


def _primary(p: VINES, P: complex, hg: np.ndarray, t0: float, t: float) -> tuple[float, float]:
    """``x1, x1'`` at time t of a flight that starts at t0 with free part ``hg``."""
    w = P * complex(math.cos(p.r * t), math.sin(p.r * t))
    h = transition(t - t0, p.zeta) @ hg
    return -p.g + w.real + h[0], (1j * p.r * w).real + h[1]


def _jumps(p: VINES, R: float, ds: float) -> tuple[float, float]:
    """Velocity jumps of primary and ball at an impact with approach ``ds = s'-`` (the
    two-body law: momentum kept, ``s'+ = -R s'-``)."""
    return p.mu / (1.0 + p.mu) * (1.0 + R) * ds, -(1.0 + R) / (1.0 + p.mu) * ds


def _residuals(p: VINES, t1: float, z: np.ndarray) -> np.ndarray:
    """E1..E7 at ``z = (h0, g0, X, Y, u1, u2, w)`` (affine in z)."""
    h0, g0, X, Y, u1, u2, w = z
    P, T, g = complex(X, Y), p.T, p.g
    t2 = T - t1
    x10, v10 = _primary(p, P, np.array([h0, g0]), 0.0, 0.0)
    x1a, v1a = _primary(p, P, np.array([h0, g0]), 0.0, t1)  # before the lower impact
    hL = transition(t1, p.zeta) @ np.array([h0, g0]) + np.array([0.0, w])
    x1b, v1b = _primary(p, P, hL, t1, T)  # before the next upper impact
    x2L = x10 + p.b + u1 * t1 - 0.5 * g * t1 * t1
    uL = u1 - g * t1
    dv1L, dv2L = _jumps(p, p.R_low, uL - v1a)
    x2U = x2L + u2 * t2 - 0.5 * g * t2 * t2
    uU = u2 - g * t2
    dv1U, dv2U = _jumps(p, p.R, uU - v1b)
    return np.array([x2L - x1a + p.b_low,          # E1
                     w - dv1L,                      # E2
                     u2 - (uL + dv2L),              # E3
                     x2U - x1b - p.b,               # E4
                     v10 - (v1b + dv1U),            # E5
                     u1 - (uU + dv2U),              # E6
                     x1b - x10])                    # E7


def linear_system(p: VINES, t1: float) -> tuple[np.ndarray, np.ndarray]:
    """``L z = c`` of E1..E7 at this ``t1`` (columns read off the affine residuals)."""
    r0 = _residuals(p, t1, np.zeros(7))
    L = np.column_stack([_residuals(p, t1, e) - r0 for e in np.eye(7)])
    return L, -r0


def excess(p: VINES, t1: float) -> float:
    """``f(t1)`` of (F): ``|P|^2/|A|^2 - 1`` (NaN where the system is singular)."""
    L, c = linear_system(p, t1)
    try:
        z = np.linalg.solve(L, c)
    except np.linalg.LinAlgError:
        return math.nan
    return (z[2] ** 2 + z[3] ** 2) / abs(p.A) ** 2 - 1.0


def _symmetric_roots(p: VINES) -> list[np.ndarray]:
    """At ``t1 = T/2`` with symmetric walls: the line of solutions meets ``|P| = |A|``."""
    L, c = linear_system(p, 0.5 * p.T)
    z0 = np.linalg.lstsq(L, c, rcond=None)[0]
    _, sv, vt = np.linalg.svd(L)
    if sv[-1] > 1e-9 * sv[0]:
        raise ArithmeticError(f"t1 = T/2 is not singular (sigma {sv[-1]:.3g}): {p}")
    n = vt[-1]
    qa = n[2] ** 2 + n[3] ** 2
    qb = 2 * (z0[2] * n[2] + z0[3] * n[3])
    qc = z0[2] ** 2 + z0[3] ** 2 - abs(p.A) ** 2
    disc = qb * qb - 4 * qa * qc
    if disc < 0:
        return []
    sq = math.sqrt(disc)
    return [z0 + tt * n for tt in {(-qb - sq) / (2 * qa), (-qb + sq) / (2 * qa)}]


def ul_motions(p: VINES, scan: int = 600) -> list[Motion]:
    """Every UL motion (one impact on each wall per forcing period) at these parameters."""
    T = p.T
    found: list[tuple[float, np.ndarray]] = []
    if p.symmetric:
        found += [(0.5 * T, z) for z in _symmetric_roots(p)]
    ts = np.linspace(0.0, T, scan + 1)[1:-1]
    f = np.array([excess(p, float(t)) for t in ts])
    for i in range(ts.size - 1):
        a, c = f[i], f[i + 1]
        if not (np.isfinite(a) and np.isfinite(c)) or a * c > 0:
            continue
        if p.symmetric and ts[i] <= 0.5 * T <= ts[i + 1]:
            continue  # the singular t1 = T/2 (handled above)
        t1 = brentq(lambda t: excess(p, t), ts[i], ts[i + 1], xtol=1e-15, rtol=1e-15)
        if abs(excess(p, t1)) > 1e-8:  # a pole of f, not a root
            continue
        L, cc = linear_system(p, t1)
        found.append((t1, np.linalg.solve(L, cc)))
    return [_motion(p, t1, z) for t1, z in found]


def _motion(p: VINES, t1: float, z: np.ndarray) -> Motion:
    h0, g0, X, Y, u1, u2, w = z
    P = complex(X, Y)
    delta = math.remainder(math.atan2(Y, X) - math.atan2(p.A.imag, p.A.real), 2 * math.pi)
    x10, v10 = _primary(p, P, np.array([h0, g0]), 0.0, 0.0)
    x1a, v1a = _primary(p, P, np.array([h0, g0]), 0.0, t1)
    _, v1T = _primary(p, P, transition(t1, p.zeta) @ np.array([h0, g0]) + [0.0, w],
                        t1, p.T)
    state_upper = np.array([x10, x10 + p.b, v10, u1])
    state_lower = np.array([x1a, x1a - p.b_low, v1a + w, u2])
    approach_upper = (u2 - p.g * (p.T - t1)) - v1T
    approach_lower = v1a - (u1 - p.g * t1)
    gap, amp = _inside(p, P, z, t1)
    m = Motion(p=p, t1=t1, delta=delta, z=z, state_upper=state_upper,
               state_lower=state_lower, approach_upper=approach_upper,
               approach_lower=approach_lower, gap_min=gap, amplitude=amp,
               multipliers=np.zeros(4, complex))
    return dataclasses.replace(m, multipliers=multipliers(m))


def _inside(p: VINES, P: complex, z: np.ndarray, t1: float, num: int = 4001
            ) -> tuple[float, float]:
    """Smallest clearance ``min(b - s, s + b_low)`` strictly inside the two flights (on
    ``num`` samples each, the interior minima refined by a parabola) and ``max |x1 + g|``."""
    h0, g0, _, _, u1, u2, w = z
    gap, amp = math.inf, 0.0
    hg1 = np.array([h0, g0])
    hg2 = transition(t1, p.zeta) @ hg1 + np.array([0.0, w])
    x10 = _primary(p, P, hg1, 0.0, 0.0)[0]
    x1a = _primary(p, P, hg1, 0.0, t1)[0]
    for t0, t_end, hg, x2s, u in ((0.0, t1, hg1, x10 + p.b, u1),
                                  (t1, p.T, hg2, x1a - p.b_low, u2)):
        t = np.linspace(t0, t_end, num)
        x1 = np.array([_primary(p, P, hg, t0, tt)[0] for tt in t])
        s = x2s + u * (t - t0) - 0.5 * p.g * (t - t0) ** 2 - x1
        amp = max(amp, float(np.max(np.abs(x1 + p.g))))
        c = np.minimum(p.b - s, s + p.b_low)
        gap = min(gap, float(np.min(c[1:-1])) if np.min(c[1:-1]) < 0 else gap)  # a crossing
        ds = np.diff(s)
        for i in np.flatnonzero(np.sign(ds[:-1]) != np.sign(ds[1:])) + 1:
            a0, a1, a2 = s[i - 1], s[i], s[i + 1]  # an interior extremum of s: its vertex
            den = a0 - 2 * a1 + a2
            se = a1 - (a0 - a2) ** 2 / (8 * den) if den != 0 else a1
            gap = min(gap, float(min(p.b - se, se + p.b_low)))
    return gap, amp


# --- stability: the first-return map to the upper wall, by central differences ---

def _flight_to_wall(p: VINES, x1: float, v1: float, u: float, s0: float, theta: float,
                    wall: str, t_max: float) -> tuple[float, float, float, float, float]:
    """From ``(x1, x1', x2' = u, s = s0)`` at phase ``theta`` (time 0 of the flight, the
    forcing ``cos(r t + theta)``), the first time ``s`` reaches ``wall`` (``"U"``: ``b``,
    ``"L"``: ``-b_low``); returns ``(t, x1, x1', x2', s')`` there."""
    P = p.A * complex(math.cos(theta), math.sin(theta))
    hg = np.array([x1 + p.g - P.real, v1 + p.r * P.imag])

    def target(t: float) -> float:
        s = s0 + u * t - 0.5 * p.g * t * t - (_primary(p, P, hg, 0.0, t)[0] - x1)
        return s - p.b if wall == "U" else s + p.b_low

    ts = np.linspace(0.0, t_max, 2001)[1:]
    prev_t = 1e-9 * t_max
    for t in ts:
        cur = target(float(t))
        if (wall == "U" and cur >= 0) or (wall == "L" and cur <= 0):
            tc = brentq(target, prev_t, float(t), xtol=1e-15, rtol=1e-15)
            xa, va = _primary(p, P, hg, 0.0, tc)
            ua = u - p.g * tc
            return tc, xa, va, ua, ua - va
        prev_t = float(t)
    raise ArithmeticError("no impact within t_max")


def return_map(p: VINES, y: np.ndarray) -> np.ndarray:
    """``(x1, x1', x2', theta)`` after an upper impact -> after the next upper impact
    (through one lower impact)."""
    x1, v1, u, theta = y
    t_a, xa, va, ua, dsa = _flight_to_wall(p, x1, v1, u, p.b, theta, "L", 2 * p.T)
    dv1, dv2 = _jumps(p, p.R_low, dsa)
    th2 = theta + p.r * t_a
    t_b, xb, vb, ub, dsb = _flight_to_wall(p, xa, va + dv1, ua + dv2, -p.b_low, th2, "U",
                                           2 * p.T)
    dv1, dv2 = _jumps(p, p.R, dsb)
    return np.array([xb, vb + dv1, ub + dv2, th2 + p.r * t_b - 2 * math.pi])


def multipliers(m: Motion, h: float = 1e-6) -> np.ndarray:
    """Eigenvalues of the return map's Jacobian at the motion (central differences)."""
    p = m.p
    y0 = np.array([m.state_upper[0], m.state_upper[2], m.state_upper[3], m.delta])
    J = np.zeros((4, 4))
    try:
        for k in range(4):
            dy = np.zeros(4)
            dy[k] = h * max(1.0, abs(y0[k]))
            J[:, k] = (return_map(p, y0 + dy) - return_map(p, y0 - dy)) / (2 * dy[k])
    except ArithmeticError:
        return np.full(4, np.nan + 0j)
    mult = np.linalg.eigvals(J)
    return mult[np.argsort(-np.abs(mult))]

"""The symmetric two-impact motion of an impact damper in closed form, and its stability.

The system (Masri & Caughey 1966, nondimensional): a primary mass on a spring and a
viscous damper, forced harmonically, with a free particle of mass ratio ``mu`` in a cavity
of the primary; the particle's displacement relative to the primary is
``s = x2 - x1 in [-d/2, d/2]``. Lengths in units of the static deflection ``F/k``, time in
``1/w_n``::

    x1'' + 2 zeta x1' + x1 = cos(r t + delta),        x2'' = 0        (|x2 - x1| < d/2)

and at ``|s| = d/2`` the two-body impact (momentum conserved, relative velocity reversed
times ``e``)::

    x1'+ + mu x2'+ = x1'- + mu x2'-,        x2'+ - x1'+ = -e (x2'- - x1'-).

The motion sought (Masri & Caughey's "two symmetric impacts per cycle"): an impact on the
upper wall (``s = d/2``) at ``t = 0``, one on the lower wall half a period later, and
``X(t + pi/r) = -X(t)``. Writing ``x1 = Re(P e^{i r t}) + h(t)`` (``P = A e^{i delta}``,
``A = 1/(1 - r^2 + 2 i zeta r)`` the linear receptance, ``h`` a free damped oscillation
between impacts), the symmetry and the impact law are **linear** in the four unknowns
``(h0, g0, X, Y)`` with ``h0 = h(0)``, ``g0 = h'(0+)``, ``P = X + iY``:

* (S1) the primary's half-period symmetry: ``Phi_11 h0 + Phi_12 g0 = -h0`` with
  ``Phi = Phi(pi/r)`` the transition matrix of ``h'' + 2 zeta h' + h = 0``;
* (S2) the particle's flight: it crosses the cavity in half a period, so its velocity
  after the upper impact is ``u+ = -(2r/pi)(x1(0) + d/2)`` and before it ``u- = -u+``;
  momentum: ``x1'+ - x1'- = -2 mu u+``;
* (S3) restitution on the relative velocity.

Three linear equations in four unknowns leave a line; on it ``X^2 + Y^2 = |A|^2``
(the forcing amplitude) is a quadratic: at most **two** symmetric motions, the two
roots (Masri & Caughey's two solutions, of which at most one is stable). Everything
else (impact phase, velocities at impact, amplitude of the primary) follows in closed
form.

Stability: the motion is a fixed point of the half-period map ``H`` (flight to the
lower wall, the impact there, then the reflection ``X -> -X``, phase ``- pi``); the full
period map is ``G = H^2``. ``dH`` is written here in closed form from the flight's
transition matrix and the impact law (perturbations of the post-impact state
``(x1, x1', x2')`` and of the impact phase; the impact time moves by
``-ds / s'`` (the saltation rule)), independently of the package's code.

The formulas are derived here (the study's README says so): they restate the problem
of Masri & Caughey (1966) but are not copied from that paper.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["SymmetricMotion", "half_map_jacobian", "symmetric_motions", "transition"]


def transition(t: float | np.ndarray, zeta: float) -> np.ndarray:
    """``Phi(t)``: ``[h(t), h'(t)] = Phi(t) [h(0), h'(0)]`` for ``h'' + 2 zeta h' + h = 0``
    (``0 <= zeta < 1``), shape ``t.shape + (2, 2)``."""
    if not 0.0 <= zeta < 1.0:
        raise ValueError(f"zeta must be in [0, 1) (an under-damped primary); got {zeta!r}")
    wd = math.sqrt(1.0 - zeta * zeta)
    t = np.asarray(t, dtype=float)
    c, s, e = np.cos(wd * t), np.sin(wd * t), np.exp(-zeta * t)
    return e[..., None, None] * np.stack([np.stack([c + zeta / wd * s, s / wd], -1),
                                          np.stack([-s / wd, c - zeta / wd * s], -1)], -2)


@dataclasses.dataclass(frozen=True)
class SymmetricMotion:
    """One symmetric two-impact motion (upper-wall impact at ``t = 0``).

    Attributes
    ----------
    r, d, mu, e, zeta : float
        Frequency ratio, clearance (cavity length, ``2 b``), mass ratio, restitution,
        damping ratio of the primary.
    delta : float
        Forcing phase at the upper-wall impact, in ``(-pi, pi]``.
    x1 : float
        Primary displacement at the impact.
    v1_after, v1_before : float
        Primary velocity just after / before the upper-wall impact.
    u_after, u_before : float
        Particle velocity just after / before it.
    amplitude : float
        ``max |x1(t)|`` over the period.
    gap_min : float
        Smallest ``d/2 - |s(t)|`` inside the flight (``> 0``: no other contact).
    H : ndarray, shape (4, 4)
        Jacobian of the half-period map in ``(x1, x1', x2', theta)`` after an upper impact.
    multipliers : ndarray of complex, shape (4,)
        Eigenvalues of ``G = H^2``, largest modulus first.
    """

    r: float
    d: float
    mu: float
    e: float
    zeta: float
    delta: float
    x1: float
    v1_after: float
    v1_before: float
    u_after: float
    u_before: float
    amplitude: float
    gap_min: float
    H: np.ndarray
    multipliers: np.ndarray

    @property
    def impact_velocity(self) -> float:
        """Relative approach speed ``s'-`` at the impact (``> 0`` for a real impact)."""
        return self.u_before - self.v1_before

    @property
    def physical(self) -> bool:
        """A real impact and no contact inside the flight."""
        return self.impact_velocity > 0.0 and self.gap_min > 0.0

    @property
    def stable(self) -> bool:
        """All multipliers of ``G = H^2`` inside the unit circle."""
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    @property
    def state(self) -> np.ndarray:
        """``[x1, x2, x1', x2']`` just after the upper-wall impact (``x2 = x1 + d/2``)."""
        return np.array([self.x1, self.x1 + 0.5 * self.d, self.v1_after, self.u_after])

    def primary(self, t: np.ndarray) -> np.ndarray:
        """``x1(t)`` on the flight ``0 <= t <= pi / r`` after the upper-wall impact."""
        return _derivatives(self, t)[0]


def symmetric_motions(r: float, d: float, mu: float, e: float, zeta: float
                      ) -> list[SymmetricMotion]:
    """Every symmetric two-impact motion at these parameters (0, 1 or 2), in closed form.

    Parameters
    ----------
    r : float
        ``omega / w_n`` (``> 0``, ``!= 1`` when ``zeta = 0``).
    d : float
        Cavity length in units of ``F/k`` (``> 0``); the walls are at ``s = +-d/2``.
    mu : float
        Particle mass / primary mass (``> 0``).
    e : float
        Restitution (``0 <= e <= 1``).
    zeta : float
        Damping ratio of the primary (``0 <= zeta < 1``).
    """
    for name, value, ok in (("r", r, r > 0), ("d", d, d > 0), ("mu", mu, mu > 0),
                            ("e", e, 0 <= e <= 1)):
        if not ok:
            raise ValueError(f"{name} = {value!r} is out of range")
    T2 = math.pi / r
    Phi = transition(T2, zeta)
    A = 1.0 / complex(1.0 - r * r, 2.0 * zeta * r)
    k = 2.0 * r / math.pi  # u+ = -k (x1(0) + d/2)
    # unknowns z = (h0, g0, X, Y): x1(0) = X + h0, x1'(0+) = -r Y + g0,
    # x1'(0-) = -r Y - h'(T/2) = -r Y - Phi_21 h0 - Phi_22 g0
    L = np.array([
        [Phi[0, 0] + 1.0, Phi[0, 1], 0.0, 0.0],                                # (S1)
        [Phi[1, 0] - 2 * mu * k, 1.0 + Phi[1, 1], -2 * mu * k, 0.0],            # (S2)
        [(1 - e) * k - e * Phi[1, 0], 1.0 - e * Phi[1, 1], (1 - e) * k,       # (S3)
         -(1 + e) * r]])
    c = np.array([0.0, 2 * mu * k * 0.5 * d, -(1 - e) * k * 0.5 * d])
    z0 = np.linalg.lstsq(L, c, rcond=None)[0]
    null = np.linalg.svd(L)[2][-1]
    # (X0 + t nX)^2 + (Y0 + t nY)^2 = |A|^2
    qa = null[2] ** 2 + null[3] ** 2
    qb = 2 * (z0[2] * null[2] + z0[3] * null[3])
    qc = z0[2] ** 2 + z0[3] ** 2 - abs(A) ** 2
    disc = qb * qb - 4 * qa * qc
    if disc < 0:
        return []
    sq = math.sqrt(disc)
    roots = [(-qb - sq) / (2 * qa), (-qb + sq) / (2 * qa)] if sq > 0 else [-qb / (2 * qa)]
    out = []
    for t in roots:
        h0, g0, X, Y = z0 + t * null
        delta = math.remainder(math.atan2(Y, X) - math.atan2(A.imag, A.real), 2 * math.pi)
        x1 = X + h0
        u_after = -k * (x1 + 0.5 * d)
        hT = Phi @ (h0, g0)
        v1_before = -r * Y - hT[1]
        motion = SymmetricMotion(
            r=r, d=d, mu=mu, e=e, zeta=zeta, delta=delta, x1=x1, v1_after=-r * Y + g0,
            v1_before=v1_before, u_after=u_after, u_before=-u_after, amplitude=math.nan,
            gap_min=math.nan, H=np.zeros((4, 4)), multipliers=np.zeros(4, complex))
        amp, gap = _extrema(motion)
        H = half_map_jacobian(motion)
        mult = np.linalg.eigvals(H @ H)
        out.append(dataclasses.replace(motion, amplitude=amp, gap_min=gap, H=H,
                                       multipliers=mult[np.argsort(-np.abs(mult))]))
    return out


def _extrema(m: SymmetricMotion, num: int = 400) -> tuple[float, float]:
    """``max |x1|`` over the period (by the half-period symmetry: over one flight) and the
    smallest clearance ``d/2 - |s|`` at the interior extrema of ``s = x2 - x1`` on the
    flight (``+inf`` when ``s`` is monotone, as the package's ``flight_gap_min``); each
    extremum located on ``num`` samples and refined by Newton steps."""
    T2 = math.pi / m.r
    t = np.linspace(0.0, T2, num)
    x, v, _ = _derivatives(m, t)
    i = int(np.argmax(np.abs(x)))
    amp = max(abs(_newton(m, t[i], T2, lambda x, v, a: (v, a))), abs(x[0]), abs(x[-1]))
    ds = m.u_after - v  # s' on the flight
    gap = math.inf
    for j in np.flatnonzero(np.sign(ds[1:-2]) != np.sign(ds[2:-1])) + 1:
        tj = _newton(m, 0.5 * (t[j] + t[j + 1]), T2, lambda x, v, a: (m.u_after - v, -a),
                     time=True)
        s = m.x1 + 0.5 * m.d + m.u_after * tj - _derivatives(m, tj)[0]
        gap = min(gap, 0.5 * m.d - abs(float(s)))
    return amp, gap


def _derivatives(m: SymmetricMotion, t: float | np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``x1, x1', x1''`` at the times t of the flight after the upper-wall impact."""
    A = 1.0 / complex(1.0 - m.r ** 2, 2.0 * m.zeta * m.r)
    P = A * complex(math.cos(m.delta), math.sin(m.delta))
    t = np.asarray(t, dtype=float)
    w = P * np.exp(1j * m.r * t)
    h = transition(t, m.zeta) @ np.array([m.x1 - P.real, m.v1_after + m.r * P.imag])
    x = w.real + h[..., 0]
    v = (1j * m.r * w).real + h[..., 1]
    acc = np.cos(m.r * t + m.delta) - 2 * m.zeta * v - x
    return x, v, acc


def _newton(m: SymmetricMotion, t: float, T2: float, f, time: bool = False) -> float:
    """A few Newton steps on ``f(x, v, a) -> (g, g')`` from t in ``[0, T2]``; the value
    ``x1`` there (or the time, ``time=True``)."""
    for _ in range(8):
        g, dg = f(*(float(q) for q in _derivatives(m, t)))
        if dg == 0:
            break
        t = min(max(t - g / dg, 0.0), T2)
    return t if time else float(_derivatives(m, t)[0])


def half_map_jacobian(m: SymmetricMotion) -> np.ndarray:
    """Jacobian of the half-period map at the motion, in ``y = (x1, x1', x2', theta)``
    just after an upper-wall impact (``x2 = x1 + d/2`` on the section), shape (4, 4).

    The map: flight from ``(y, theta)`` until ``s = x2 - x1 = -d/2``, the impact there,
    then ``X -> -X`` and ``theta -> theta - pi`` (which maps the lower wall onto the
    upper). Linearised: the flight's state at the nominal time ``tau = pi/r`` moves by
    ``dX = Psi dy``, the impact time by ``dtau = -(n . dX) / (n . X'(tau-))`` with
    ``n = (-1, 1, 0, 0)`` (the section ``s = -d/2``), the pre-impact state by
    ``dX + X'(tau-) dtau``, then the impact matrix ``D`` and the reflection.
    """
    r, zeta, mu, e = m.r, m.zeta, m.mu, m.e
    tau = math.pi / r
    Phi = transition(tau, zeta)
    # the rate X' = (v1, v2, a1, 0) at tau- of the nominal flight (the mirror of 0-)
    _, v1T, a1T = (float(q) for q in _derivatives(m, tau))
    fT = np.array([v1T, m.u_after, a1T, 0.0])
    # d X(tau) / d (x1, v1, u, theta), the section's x2 = x1 + d/2 carried along
    Psi = np.zeros((4, 4))
    Psi[0, 0], Psi[2, 0] = Phi[0, 0], Phi[1, 0]
    Psi[0, 1], Psi[2, 1] = Phi[0, 1], Phi[1, 1]
    Psi[1, 0] = 1.0              # x2 = x1 + d/2 + u t
    Psi[1, 2], Psi[3, 2] = tau, 1.0
    # theta: the forcing cos(r t + theta) moves the particular solution; the
    # homogeneous part takes up the change at t = 0 (x1(0), x1'(0) fixed):
    # d x_p(t)/d theta = Re(i P e^{irt}), corrected by Phi times its value at 0
    A = 1.0 / complex(1.0 - r * r, 2.0 * zeta * r)
    P = A * complex(math.cos(m.delta), math.sin(m.delta))
    dp0 = np.array([(1j * P).real, (1j * 1j * r * P).real])
    w = P * complex(math.cos(r * tau), math.sin(r * tau))
    dpT = np.array([(1j * w).real, (1j * 1j * r * w).real])
    dth = dpT - Phi @ dp0
    Psi[0, 3], Psi[2, 3] = dth
    n = np.array([-1.0, 1.0, 0.0, 0.0])
    # pre-impact state and phase after the perturbed flight
    dtau = -(n @ Psi) / (n @ fT)            # row: d tau / d y
    dtau[3] = -(n @ Psi[:, 3]) / (n @ fT)
    dX = Psi + np.outer(fT, dtau)            # d X(tau + dtau)- / d y
    # the impact law at the lower wall (the same law: D depends on the normal only
    # through n n^T) and the velocity jump's dependence on the arrival state
    Minv = np.array([1.0, 1.0 / mu])
    nv = np.array([-1.0, 1.0])
    Dv = np.eye(2) - (1 + e) * np.outer(Minv * nv, nv) / (nv @ (Minv * nv))
    D = np.eye(4)
    D[2:, 2:] = Dv
    # the post-impact state's derivative: the map X(t_imp+) = D X(t_imp-); the
    # forcing acts equally before and after, so no extra saltation term in the
    # velocity beyond D (the acceleration jumps only through the velocity)
    dXp = D @ dX
    # reflect and keep (x1, v1, v2, theta - pi)
    J = np.zeros((4, 4))
    J[0], J[1], J[2] = -dXp[0], -dXp[2], -dXp[3]
    J[3] = r * dtau
    J[3, 3] += 1.0
    return J

"""A published closed form for the VI-NES: Weidemann, Bergman, Vakakis & Krack's
single-harmonic ("ad-hoc analytical") synchronized response, implemented as written.

Source (read in its public code; the paper's own equations were not reachable here):
T. Weidemann, L. A. Bergman, A. F. Vakakis, M. Krack, "Energy transfer and localization
in a forced cyclic chain of oscillators with vibro-impact nonlinear energy sinks",
*Nonlinear Dynamics* (2025), doi:10.1007/s11071-025-10928-4; its code, the repository
``tobiaswdm/CC`` (GPL-3.0, commit c4c8a3a4, 2025-01-31), files
``analytics/SingleSectorFRS.m`` (the clearance for a given amplitude),
``analytics/GSRInititalConditions.m`` (the phase and the absorber's triangle wave) and
``analytics/TunedBackbone.m``; the model in ``system/BuildSystem.m`` and
``integrator/MoreauIntegration.m``. This module is a re-statement of those formulas in
the source's symbols, not a copy of its code.

The source's machine, one sector (``N_s = 1``): a primary of mass ``1 - epsilon_a``,
stiffness 1 and damping ``2 D`` forced by ``Re(F e^{i r t})``, ``F = 1``, carrying a free
absorber of mass ``epsilon_a`` in a cavity ``|q - q_a| <= Gamma`` with Newton's restitution
``e_N`` (the two-body law, momentum kept). Its ansatz ("synchronized" motion, two impacts
per period): the primary harmonic, ``q = Re(Q e^{i r t})``, the absorber a triangle wave of
amplitude ``hat q_a`` (constant speed ``2 r hat q_a / pi`` between impacts). Then, with
the clearance-normalized amplitude ``xi = |Q| / Gamma``:

    rho        = (2/pi) (1 - e_N) / (1 + e_N)                                     (W1)
    Theta      = hat q_a / Gamma = (1 + sqrt((1 + rho^2) xi^2 - rho^2)) / (1 + rho^2)  (W2)
    e^{-i Delta} = (Theta - 1)/xi - i rho Theta / xi                              (W3)
    Pi         = -8 epsilon_a Theta e^{-i Delta} r^2 / pi^2                        (W4)
    H          = 1 / (-(1 - epsilon_a) r^2 + 2 i D r + 1)                          (W5)
    Gamma      = | H F / (xi + H Pi) |                                             (W6)

(W2, W3) are the absorber's kinematics on a harmonic primary (the impact at the absorber's
turning point, the restitution law with the primary's velocity unchanged by the impact);
(W4) is the fundamental harmonic of the absorber's inertia force (the triangle wave's
``8/pi^2``); (W6) is the primary's harmonic balance, solved for the clearance. The phase of
the primary (``GSRInititalConditions.m``): ``Q = F / (1/H + Pi / xi)`` (W7). The
reference amplitude is ``q_ref = 1 / (2 D)`` (the linear resonance, ``BuildSystem.m``).

It is a **single-harmonic, small-mass-ratio** closed form: it neglects the higher
harmonics of the impulses on the primary and the primary's velocity jump at an impact,
so it is exact only as ``epsilon_a -> 0`` with ``D``, ``r - 1`` of order ``epsilon_a`` and
``Gamma / q_ref`` fixed (the regime of the VI-NES literature). ``mapping`` converts this
study's machine (primary mass 1, ball mass ``mu``, damping ratio ``zeta``, time in ``1/w_n``
of the primary alone) to the source's (total mass 1): ``epsilon_a = mu / (1 + mu)``, time
scaled by ``sqrt(1 + mu)``, so ``r_source = r sqrt(1 + mu)``, ``D = zeta / sqrt(1 + mu)``;
lengths, the force and ``Gamma = b`` are unchanged.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.optimize import brentq


def rho(e_N: float) -> float:
    """(W1)."""
    if not 0.0 <= e_N <= 1.0:
        raise ValueError(f"e_N = {e_N!r} must lie in [0, 1]")
    return 2.0 / math.pi * (1.0 - e_N) / (1.0 + e_N)


def xi_min(e_N: float) -> float:
    """The smallest ``xi`` with a synchronized motion: where the root of (W2) vanishes."""
    rh = rho(e_N)
    return rh / math.sqrt(1.0 + rh * rh)


def _check_sign(sign: int) -> None:
    if sign not in (1, -1):
        raise ValueError(f"sign = {sign!r} must be +1 (the source's root of (W2)) or -1")


def theta(xi: float, e_N: float, sign: int = 1) -> float:
    """(W2): the absorber's triangle-wave amplitude over the clearance. ``sign = +1`` is
    the source's root; ``-1`` the quadratic's other root, which the source discards (kept
    here only to show which exact motion it describes)."""
    _check_sign(sign)
    rh = rho(e_N)
    if xi < xi_min(e_N):
        raise ValueError(f"xi = {xi!r} is below xi_min = {xi_min(e_N)!r}: "
                         "no synchronized motion")
    root = math.sqrt(max(0.0, (1.0 + rh * rh) * xi * xi - rh * rh))  # 0 at xi_min
    return (1.0 + sign * root) / (1.0 + rh * rh)


def exp_minus_i_delta(xi: float, e_N: float, sign: int = 1) -> complex:
    """(W3)."""
    th = theta(xi, e_N, sign)
    return complex((th - 1.0) / xi, -rho(e_N) * th / xi)


def Pi(xi: float, r: float, epsilon_a: float, e_N: float, sign: int = 1) -> complex:
    """(W4): the absorber's force, fundamental harmonic, per unit clearance."""
    return (-8.0 * epsilon_a * theta(xi, e_N, sign) * exp_minus_i_delta(xi, e_N, sign)
            * r * r / math.pi ** 2)


def H(r: float, epsilon_a: float, D: float) -> complex:
    """(W5): the primary's receptance with the absorber removed."""
    return 1.0 / complex(1.0 - (1.0 - epsilon_a) * r * r, 2.0 * D * r)


def clearance(xi: float, r: float, epsilon_a: float, D: float, e_N: float,
              F: complex = 1.0, sign: int = 1) -> float:
    """(W6): the clearance ``Gamma`` at which the synchronized motion has amplitude
    ``xi Gamma`` at frequency ``r``."""
    h = H(r, epsilon_a, D)
    return abs(h * F / (xi + h * Pi(xi, r, epsilon_a, e_N, sign)))


def phasor(xi: float, r: float, epsilon_a: float, D: float, e_N: float,
           F: complex = 1.0, sign: int = 1) -> complex:
    """(W7): the primary's complex amplitude ``Q`` (the force ``Re(F e^{irt})``)."""
    return F / (1.0 / H(r, epsilon_a, D) + Pi(xi, r, epsilon_a, e_N, sign) / xi)


def mapping(r: float, mu: float, zeta: float) -> tuple[float, float, float]:
    """This study's ``(r, mu, zeta)`` -> the source's ``(r, epsilon_a, D)`` (module docstring)."""
    for name, value in (("r", r), ("mu", mu)):
        if not value > 0:
            raise ValueError(f"{name} = {value!r} must be positive")
    if not 0.0 <= zeta < 1.0:
        raise ValueError(f"zeta = {zeta!r} must lie in [0, 1)")
    s = math.sqrt(1.0 + mu)
    return r * s, mu / (1.0 + mu), zeta / s


@dataclasses.dataclass(frozen=True)
class Synchronized:
    """One synchronized motion of the source's closed form, in this study's units."""

    xi: float  # |Q| / Gamma: the primary's fundamental harmonic over the clearance
    theta: float  # the ball's triangle-wave amplitude over the clearance (W2)
    Q: complex  # the primary's fundamental harmonic (W7), force cos(r t)


def motions(r: float, mu: float, zeta: float, b: float, e: float,
            xi_max: float = 1e3, scan: int = 4000, sign: int = 1) -> list[Synchronized]:
    """Every synchronized motion of (W1-W7) for this study's machine: the roots in ``xi``
    of ``clearance(xi) = b`` on ``[xi_min, xi_max]`` (scanned on a log grid, refined by
    Brent's method), smallest ``xi`` first. ``sign``: the root of (W2) (``+1``, the
    source's)."""
    _check_sign(sign)
    if not b > 0:
        raise ValueError(f"b = {b!r} must be positive")
    r_s, eps, D = mapping(r, mu, zeta)
    lo = xi_min(e) * (1.0 + 1e-12)
    xs = np.geomspace(lo, xi_max, scan)
    f = np.array([clearance(float(x), r_s, eps, D, e, sign=sign) - b for x in xs])
    out = []
    for i in range(xs.size - 1):
        if f[i] == 0.0 or f[i] * f[i + 1] < 0:
            x = brentq(lambda t: clearance(t, r_s, eps, D, e, sign=sign) - b, float(xs[i]),
                       float(xs[i + 1]), xtol=1e-15, rtol=1e-14)
            out.append(Synchronized(xi=x, theta=theta(x, e, sign),
                                    Q=phasor(x, r_s, eps, D, e, sign=sign)))
    return out

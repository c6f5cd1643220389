"""Roots of eq. (15): the impact phases and velocities of the N-1 motions at a gap b.

Eq. (14) in modal form is ``c cos(delta) + s sin(delta) = b`` (``c, s`` from
:func:`impactcont.kernel.closed_form.omega_setup`); its two roots (eq. 15) are
written without cancellation, with the error of a fold (a double root) estimated.
The impact velocity of a root is ``sigma = x1p'(delta) / Delta`` (eq. 12 at the
velocity of mass 1), or, for elastic impacts without damping, from the impact
condition ``x1(0) = b``.
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.jit import entry as _jit

__all__ = ["orbit_roots", "phase_sigma"]


_EPS = 2.220446049250313e-16


# -- roots of eq. (15) ----------------------------------------------------------------------
@_jit
def orbit_roots(scalars, b, omega, R):
    """Impact phases and velocities of the motions at gap b.

    Returns ``(count, delta[2], sigma[2], sign[2], fold_error)``; ``count`` is 0, 1
    (double root) or 2, ``-1`` when every phase solves eq. (14) (no forcing reaches
    mass 1) and ``-2`` for an elastic system whose forced motion of mass 1 vanishes.
    """
    Gam, B, g, Delta, c, s = scalars[1], scalars[2], scalars[3], scalars[4], scalars[5], scalars[6]
    elastic = scalars[9] != 0.0
    kappa = 1.0 + R
    delta = np.zeros(2)
    sigma = np.zeros(2)
    sign = np.array([1.0, -1.0])
    if elastic:
        amp = math.hypot(Gam, B)
        if amp == 0.0 or g == 0.0:
            return -2, delta, sigma, sign, 0.0
        d0 = math.atan2(B, Gam)
        for k in range(2):
            dk = d0 if k == 0 else d0 + math.pi
            if dk > math.pi:
                dk -= 2.0 * math.pi
            delta[k] = dk
            sigma[k] = ((amp if k == 0 else -amp) - b) / (kappa * g)
        return 2, delta, sigma, sign, 0.0
    r2 = c * c + s * s
    if r2 == 0.0:
        return (-1 if b == 0.0 else 0), delta, sigma, sign, 0.0
    disc = r2 - b * b
    if disc < 0.0:
        return 0, delta, sigma, sign, 0.0
    root_r = math.sqrt(disc)
    fold_error = _EPS * math.sqrt(r2) / root_r if root_r > 0.0 else math.sqrt(_EPS)
    count = 2 if root_r > 0.0 else 1
    for k in range(count):
        sg = sign[k]
        sin_d = (b * s + sg * c * root_r) / r2
        cos_d = (b * c - sg * s * root_r) / r2
        dk = math.atan2(sin_d, cos_d)
        delta[k] = dk
        sigma[k] = omega * (B * math.cos(dk) - Gam * math.sin(dk)) / Delta
    return count, delta, sigma, sign, fold_error


@_jit
def phase_sigma(scalars, omega, R, b, delta):
    """Impact velocity of the motion with impact phase ``delta`` (a root of eq. 14)."""
    Gam, B, g, Delta = scalars[1], scalars[2], scalars[3], scalars[4]
    cd, sd = np.cos(delta), np.sin(delta)
    if scalars[9] != 0.0:  # elastic, undamped: from the impact condition x1(0) = b
        return (Gam * cd + B * sd - b) / ((1.0 + R) * g)
    return omega * (B * cd - Gam * sd) / Delta

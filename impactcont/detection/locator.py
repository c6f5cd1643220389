"""The one locator of special and codim-2 points: a test function's zero on a step.

Every detector (N-1 branches, N-p branches, codim-1 curves) parametrises the
branch between two accepted points by one coordinate (a chord coordinate, the
parameter or the phase), evaluates a test function there (each trial point is
corrected onto the branch by :func:`impactcont.core.solve_on_hyperplane` or the
curve's augmented Newton) and hands it to :func:`locate_zero`. Whether the zero
is a bifurcation is decided from the multipliers there (:func:`is_critical`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import brentq

__all__ = ["STATUSES", "is_critical", "locate_zero"]

STATUSES = ("located", "bracketed")

_EPS = float(np.finfo(float).eps)


def locate_zero(g: Callable[[float], float], lo: float, hi: float, xtol: float
                ) -> tuple[float, str]:
    """The zero of `g` in ``[lo, hi]`` by Brent's method, and how well it is known.

    Parameters
    ----------
    g : callable
        The test function along the step (evaluations are best cached by the caller).
    lo, hi : float
        The bracket, where `g` has opposite signs.
    xtol : float
        Absolute tolerance in the coordinate.

    Returns
    -------
    s : float
        The zero, inside ``[lo, hi]``.
    status : {"located", "bracketed"}
        ``located`` when ``|g(s)|`` is at most 1e-6 of the larger end value (plus
        1e-12); else the test function jumps there (a pole) and the point is only
        bracketed.

    Raises
    ------
    ValueError
        When `g` has the same sign at both ends.
    """
    g0, g1 = g(lo), g(hi)
    s = brentq(g, lo, hi, xtol=xtol, rtol=4 * _EPS)
    scale = max(abs(g0), abs(g1))
    status = "located" if abs(g(s)) <= 1e-6 * max(scale, 1e-300) + 1e-12 else "bracketed"
    return s, status


def is_critical(label: str, multipliers: np.ndarray, unit_tol: float) -> bool:
    """Whether the multipliers at a zero of the PD or NS test make it a bifurcation.

    PD: a multiplier within `unit_tol` of -1 (``det(G + I)`` also changes sign
    through the pole of G). NS: a complex pair within ``sqrt(unit_tol)`` of the unit
    circle (a real reciprocal pair is a neutral saddle). Other labels: always.
    """
    mu = np.asarray(multipliers)
    if label == "PD":
        return bool(np.min(np.abs(mu + 1.0)) < unit_tol)
    if label == "NS":
        close = np.abs(np.abs(mu) - 1.0) < unit_tol ** 0.5
        return bool(np.any(close & (np.abs(mu.imag) > 1e-8)))
    return True

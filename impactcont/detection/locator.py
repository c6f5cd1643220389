"""The one locator of special and codim-2 points: a test function's zero on a step.

:func:`locate_zero` lives in the core (:mod:`impactcont.core.locate`) and is
re-exported here with the decision :func:`is_critical`.

Every detector (N-1 branches, N-p branches, codim-1 curves) parametrises the
branch between two accepted points by one coordinate (a chord coordinate, the
parameter or the phase), evaluates a test function there (each trial point is
corrected onto the branch by :func:`impactcont.core.solve_on_hyperplane` or the
curve's augmented Newton) and hands it to :func:`locate_zero`. Whether the zero
is a bifurcation is decided from the multipliers there (:func:`is_critical`).
"""

from __future__ import annotations

import numpy as np

from impactcont.core.locate import locate_zero
from impactcont.vocabulary import STATUSES

__all__ = ["STATUSES", "is_critical", "locate_zero"]


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

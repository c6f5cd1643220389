"""One accepted point of a continuation branch."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from impactcont.core.problem import FloatArray

__all__ = ["ContinuationPoint"]


@dataclass(frozen=True, eq=False)
class ContinuationPoint:
    """An accepted point ``(u, lam)`` of a branch with its tangent.

    Attributes
    ----------
    u : ndarray, shape (m,)
        Unknowns.
    lam : float
        Parameter value.
    tangent : ndarray, shape (m + 1,)
        Unit tangent ``(du, dlam)`` in the scaled norm, oriented in the
        direction of travel of the run that produced the point.
    ds : float
        Scaled arclength step that led to this point (0 for the start point).
    newton_iterations : int
        Newton iterations spent on the corrector of this point.
    index : int
        Position of the point in its run; 0 is the start point.
    direction : int
        Direction of the run, ``+1`` or ``-1`` (sign of ``dlam`` at the start).
    monitors : dict of str to float
        Values of the problem's monitors at the point.
    """

    u: FloatArray
    lam: float
    tangent: FloatArray
    ds: float
    newton_iterations: int
    index: int
    direction: int
    monitors: dict[str, float] = field(default_factory=dict)

    @property
    def state(self) -> FloatArray:
        """The extended state ``(u, lam)``, shape ``(m + 1,)``."""
        return np.append(self.u, self.lam)

    @property
    def dlam(self) -> float:
        """The parameter component of the tangent."""
        return float(self.tangent[-1])

"""Where the stops are and how they act: the geometry shared by the orbit code and the simulator.

The impacting mass ``j`` (``osc.stops.mass``) meets the upper stop ``x_j = b`` moving
up (restitution ``R``) and, when present, the lower stop ``x_j = -b_low`` moving down
(restitution ``R_low``); :mod:`impactcont.model.stops` defines them. Both the shooting
of N-p motions (:mod:`impactcont.orbit.multi_impact`) and the event-driven simulator
(:mod:`impactcont.simulate`, the independent witness) use these two facts, so they live
here, below both.
"""

from __future__ import annotations

import numpy as np

from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import UPPER

__all__ = ["impact_geometry", "stop_sign"]


def stop_sign(stop: str) -> float:
    """``+1`` for the upper stop (met moving up), ``-1`` for the lower (met moving down)."""
    return 1.0 if stop == UPPER else -1.0


def impact_geometry(osc: ImpactOscillator, pattern: str) -> tuple[int, np.ndarray, np.ndarray]:
    """Index of the impacting mass, stop positions and impact-law diagonals per impact.

    Parameters
    ----------
    osc : ImpactOscillator
    pattern : str
        The stop of each impact (``"U"``/``"L"``), validated.

    Returns
    -------
    j : int
        0-based index of the impacting mass.
    positions : ndarray, shape (p,)
        ``c_k``: ``b`` or ``-b_low``.
    diagonals : ndarray, shape (p, 2n)
        Diagonal of ``D_k`` (eq. 4 at the stop of impact k: ``-R_k`` on ``x_j'``).
    """
    stops = osc.stops
    j, n = stops.index, osc.n
    positions = np.array([stops.position(s, osc.b) for s in pattern], dtype=float)
    diagonals = np.ones((len(pattern), 2 * n))
    diagonals[:, n + j] = [-stops.restitution(s, osc.R) for s in pattern]
    return j, positions, diagonals

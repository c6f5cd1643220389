"""Where the stops are and how they act: the geometry shared by the orbit code and the simulator.

Both stops of an oscillator act on one stop coordinate ``s = n . x`` (``osc.stops``,
:mod:`impactcont.model.stops`): ``n = e_j`` for a stop on mass ``j`` (the paper's
``x1``), ``n = e_j - e_k`` for a clearance between masses ``j`` and ``k``. The upper
stop ``s = b`` is met moving up (``s' > 0``, restitution ``R``) and, when present, the
lower stop ``s = -b_low`` moving down (restitution ``R_low``). An impact changes the
velocities only, ``x'^+ = D x'^-`` (eq. 4 for a stop on one mass: ``-R`` on ``x_j'``;
for two masses momentum is conserved and the restitution acts on ``s'``). Both the
shooting of N-p motions (:mod:`impactcont.orbit.multi_impact`) and the event-driven
simulator (:mod:`impactcont.simulate`, the independent witness) use these facts, so
they live here, below both.
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np

from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import UPPER

__all__ = ["StopGeometry", "stop_geometry", "stop_sign"]


def stop_sign(stop: str) -> float:
    """``+1`` for the upper stop (met moving up), ``-1`` for the lower (met moving down)."""
    return 1.0 if stop == UPPER else -1.0


@dataclasses.dataclass(frozen=True, eq=False)
class StopGeometry:
    """The stops met by the p impacts of a motion, in the shooting kernel's terms.

    Attributes
    ----------
    pivot : int
        0-based index ``j`` of the position eliminated on the impact section
        ``n . x = c`` (the stop's own mass, ``n_j = 1``): the shooting unknowns ``z_k``
        are ``X_k`` without ``x_j``, and ``x_j = (c_k - sum_{i != j} n_i x_i) / n_j``.
    normals : ndarray, shape (p, n)
        Normal ``n`` of the stop coordinate of each impact.
    signs : ndarray, shape (p,)
        ``+1`` (upper stop, met with ``s' > 0``) or ``-1`` (lower stop).
    positions : ndarray, shape (p,)
        ``c_k``: ``b`` or ``-b_low``.
    matrices : ndarray, shape (p, 2n, 2n)
        Impact matrix of each impact on the state: ``X^+ = D_k X^-`` (identity on the
        positions, the velocity jump of eq. 4 on the velocities).
    normal : ndarray, shape (n,)
        Normal of the oscillator's stop coordinate (the interior-contact check).
    b : float
        Upper stop position.
    b_low : float
        ``-`` lower stop position (0 without a lower stop).
    two_sided : bool
        A lower stop is present.
    """

    pivot: int
    normals: np.ndarray
    signs: np.ndarray
    positions: np.ndarray
    matrices: np.ndarray
    normal: np.ndarray
    b: float
    b_low: float
    two_sided: bool


def _normal(osc: ImpactOscillator) -> np.ndarray:
    """``n`` of the stop coordinate ``s = n . x`` (``e_j`` for a stop on mass j)."""
    stops = osc.stops
    method = getattr(stops, "normal", None)
    if callable(method):
        return np.array(method(osc.n), dtype=float).reshape(osc.n)
    out = np.zeros(osc.n)
    out[stops.index] = 1.0
    return out


def _velocity_jump(osc: ImpactOscillator, restitution: float) -> np.ndarray:
    """``D`` of ``x'^+ = D x'^-`` at a stop of restitution `restitution` (n x n)."""
    method = getattr(osc.stops, "impact_matrix", None)
    if callable(method):
        return np.array(method(osc.M, restitution), dtype=float).reshape(osc.n, osc.n)
    # a stop on one mass: eq. (4), -R on that mass's velocity and the others unchanged
    D = np.eye(osc.n)
    D[osc.stops.index, osc.stops.index] = -restitution
    return D


def stop_geometry(osc: ImpactOscillator, pattern: str) -> StopGeometry:
    """The :class:`StopGeometry` of the impacts `pattern` (validated) of `osc`.

    Built once per oscillator and pattern and kept while the oscillator lives (as
    :func:`~impactcont.orbit.flow.flow_of`; a curve point asks for it a dozen times);
    its arrays are read-only.

    Raises
    ------
    ParameterError
        When the stop coordinate does not involve the stop's own mass (``n_j = 0``: no
        position can be eliminated on the section).
    """
    known = _GEOMETRIES.setdefault(osc, {})
    geometry = known.get(pattern)
    if geometry is None:
        geometry = known[pattern] = _stop_geometry(osc, pattern)
    return geometry


#: :func:`stop_geometry` of each live oscillator, by pattern.
_GEOMETRIES: weakref.WeakKeyDictionary[ImpactOscillator, dict[str, StopGeometry]] = \
    weakref.WeakKeyDictionary()


def _stop_geometry(osc: ImpactOscillator, pattern: str) -> StopGeometry:
    stops = osc.stops
    if getattr(stops, "extra", ()):
        raise ParameterError(f"the shooting of N-p motions handles the stops of one coordinate "
                             f"(U, L) only, not yet several stop coordinates; got stops="
                             f"{stops!r}. The simulator (impactcont.simulate) follows them all")
    n, p = osc.n, len(pattern)
    normal = _normal(osc)
    j = stops.index
    if normal[j] == 0.0:
        raise ParameterError(f"the stop coordinate n . x with n={normal.tolist()} does not "
                             f"involve mass {j + 1} (stops.mass): the section n . x = c "
                             "cannot be solved for its position")
    positions = np.array([stops.position(s, osc.b) for s in pattern], dtype=float)
    matrices = np.zeros((p, 2 * n, 2 * n))
    jumps = {}
    for k, s in enumerate(pattern):
        if s not in jumps:
            jumps[s] = _velocity_jump(osc, stops.restitution(s, osc.R))
        matrices[k, :n, :n] = np.eye(n)
        matrices[k, n:, n:] = jumps[s]
    two_sided = bool(stops.two_sided)
    geometry = StopGeometry(pivot=j, normals=np.tile(normal, (p, 1)),
                            signs=np.array([stop_sign(s) for s in pattern]),
                            positions=positions, matrices=matrices, normal=normal,
                            b=float(osc.b), b_low=float(stops.b_low) if two_sided else 0.0,
                            two_sided=two_sided)
    for array in (geometry.normals, geometry.signs, geometry.positions, geometry.matrices,
                  geometry.normal):
        array.flags.writeable = False
    return geometry

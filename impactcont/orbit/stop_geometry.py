"""Where the stops are and how they act: the geometry shared by the orbit code and the simulator.

The stops U and L of an oscillator act on one stop coordinate ``s = n . x`` (``osc.stops``,
:mod:`impactcont.model.stops`): ``n = e_j`` for a stop on mass ``j`` (the paper's
``x1``), ``n = e_j - e_k`` for a clearance between masses ``j`` and ``k``. The upper
stop ``s = b`` is met moving up (``s' > 0``, restitution ``R``) and, when present, the
lower stop ``s = -b_low`` moving down (restitution ``R_low``). An impact changes the
velocities only, ``x'^+ = D x'^-`` (eq. 4 for a stop on one mass: ``-R`` on ``x_j'``;
for two masses momentum is conserved and the restitution acts on ``s'``). Both the
shooting of N-p motions (:mod:`impactcont.orbit.multi_impact`) and the event-driven
simulator (:mod:`impactcont.simulate`, the independent witness) use these facts, so
they live here, below both.

Further stops on other coordinates (``osc.stops.extra``, e.g. a stop above mass 2 besides
``U`` above mass 1) are read through :meth:`~impactcont.model.stops.Stops.stop`: each impact
of a pattern has its own normal, sign, position, jump and pivot (its own mass), and every
flight is checked against every stop (:attr:`StopGeometry.extra_normals`).
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np

from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import LOWER, UPPER

__all__ = ["StopGeometry", "moved_stop_geometry", "stop_geometry", "stop_sign"]


def stop_sign(stop: str) -> float:
    """``+1`` for the upper stop (met moving up), ``-1`` for the lower (met moving down).

    For the stops U and L only; an extra stop's sign is its side
    (:meth:`~impactcont.model.stops.Stops.stop`, :attr:`StopGeometry.signs`)."""
    if stop not in (UPPER, LOWER):
        raise ParameterError(f"stop_sign knows the stops 'U' and 'L'; got {stop!r} (an extra "
                             "stop's sign is its side: Stops.stop(name, ...).sign)")
    return 1.0 if stop == UPPER else -1.0


@dataclasses.dataclass(frozen=True, eq=False)
class StopGeometry:
    """The stops met by the p impacts of a motion, in the shooting kernel's terms.

    Attributes
    ----------
    pivots : ndarray, shape (p,), int
        0-based index ``j_k`` of the position eliminated on the section ``n_k . x = c_k``
        of impact k (the stop's own mass, ``n_j = 1``): the shooting unknowns ``z_k``
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
    extra_normals : ndarray, shape (q, n)
        Normals of the further stops (``osc.stops.extra``), checked on every flight.
    extra_signs, extra_positions : ndarray, shape (q,)
        Their sides (``+1``/``-1``) and positions ``c`` (``s = c``).
    extra_names : str
        Their names, in that order.
    """

    pivots: np.ndarray
    normals: np.ndarray
    signs: np.ndarray
    positions: np.ndarray
    matrices: np.ndarray
    normal: np.ndarray
    b: float
    b_low: float
    two_sided: bool
    extra_normals: np.ndarray
    extra_signs: np.ndarray
    extra_positions: np.ndarray
    extra_names: str

    @property
    def pivot(self) -> int:
        """The pivot shared by every impact (a pattern of one stop, e.g. the stop a grazing
        point's new impact hits).

        Every path over a whole pattern reads :attr:`pivots` (one per impact): the
        shooting, its derivatives, the compiled map sweep.

        Raises
        ------
        ParameterError
            When the impacts hit stops of different masses: ask :attr:`pivots`.
        """
        if np.any(self.pivots != self.pivots[0]):
            raise ParameterError("StopGeometry.pivot: the impacts of this pattern hit stops "
                                 f"of different masses (pivots {(self.pivots + 1).tolist()}, "
                                 "1-based); read StopGeometry.pivots, one per impact")
        return int(self.pivots[0])


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


def moved_stop_geometry(geometry: StopGeometry, before: ImpactOscillator,
                        osc: ImpactOscillator, pattern: str) -> StopGeometry:
    """The :class:`StopGeometry` of `pattern` on `osc` from `geometry`, that of `before`.

    Where `osc` differs from `before` at most in the positions of the stops U and L
    (``b``, ``b_low``; a curve in ``b`` or ``gap``): the normals, pivots, signs and impact
    matrices of `geometry` (they depend on the masses, the stop coordinate and the
    restitutions only) with the new positions, as :func:`stop_geometry` would build them
    (the same arrays, without the stop views, the impact matrices and the checks again).
    Otherwise (another restitution, mass matrix or kind of stops, extra stops):
    :func:`stop_geometry` of `osc`. Kept as :func:`stop_geometry` keeps its geometries.
    """
    old, new = before.stops, osc.stops
    known = _GEOMETRIES.setdefault(osc, {})
    if pattern in known:
        return known[pattern]
    same = (type(new) is type(old) and not new.extra and not old.extra
            and (new.mass, new.relative_to, new.mirror, new.two_sided)
            == (old.mass, old.relative_to, old.mirror, old.two_sided)
            and osc.n == before.n and set(pattern) <= {UPPER, LOWER}
            and (osc.M is before.M or np.array_equal(osc.M, before.M))
            and all(new.restitution(s, osc.R) == old.restitution(s, before.R)
                    for s in set(pattern)))
    if not same:
        return stop_geometry(osc, pattern)
    positions = np.array([new.position(s, osc.b) for s in pattern], dtype=float)
    positions.flags.writeable = False
    moved = dataclasses.replace(
        geometry, positions=positions, b=float(osc.b),
        b_low=float(new.b_low) if new.two_sided else 0.0)
    known[pattern] = moved
    return moved


#: :func:`stop_geometry` of each live oscillator, by pattern.
_GEOMETRIES: weakref.WeakKeyDictionary[ImpactOscillator, dict[str, StopGeometry]] = \
    weakref.WeakKeyDictionary()


def _stop_geometry(osc: ImpactOscillator, pattern: str) -> StopGeometry:
    stops = osc.stops
    n, p = osc.n, len(pattern)
    normal = _normal(osc)
    j = stops.index
    if normal[j] == 0.0:
        raise ParameterError(f"the stop coordinate n . x with n={normal.tolist()} does not "
                             f"involve mass {j + 1} (stops.mass): the section n . x = c "
                             "cannot be solved for its position")
    extra = tuple(getattr(stops, "extra", ()))
    views = {}
    for s in pattern:
        if s not in views:
            if s in (UPPER, LOWER):  # the one-coordinate stops, as before
                r = stops.restitution(s, osc.R)
                views[s] = (normal, stop_sign(s), stops.position(s, osc.b),
                            _velocity_jump(osc, r), j)
            else:
                v = stops.stop(s, osc.M, osc.b, osc.R)
                views[s] = (v.normal, v.sign, v.position, v.jump, v.pivot)
    matrices = np.zeros((p, 2 * n, 2 * n))
    for k, s in enumerate(pattern):
        matrices[k, :n, :n] = np.eye(n)
        matrices[k, n:, n:] = views[s][3]
    extras = [stops.stop(e.name, osc.M, osc.b, osc.R) for e in extra]
    two_sided = bool(stops.two_sided)
    geometry = StopGeometry(
        pivots=np.array([views[s][4] for s in pattern], dtype=np.int64),
        normals=np.array([views[s][0] for s in pattern], dtype=float).reshape(p, n),
        signs=np.array([views[s][1] for s in pattern], dtype=float),
        positions=np.array([views[s][2] for s in pattern], dtype=float),
        matrices=matrices, normal=normal,
        b=float(osc.b), b_low=float(stops.b_low) if two_sided else 0.0, two_sided=two_sided,
        extra_normals=np.array([v.normal for v in extras], dtype=float).reshape(len(extras), n),
        extra_signs=np.array([v.sign for v in extras], dtype=float),
        extra_positions=np.array([v.position for v in extras], dtype=float),
        extra_names="".join(e.name for e in extra))
    for array in (geometry.pivots, geometry.normals, geometry.signs, geometry.positions,
                  geometry.matrices, geometry.normal, geometry.extra_normals,
                  geometry.extra_signs, geometry.extra_positions):
        array.flags.writeable = False
    return geometry

"""Symmetric motions of a symmetric two-sided system, their half-map and its pitchfork.

A system whose impacting mass ``j`` sits between two equal stops (``b_low = b``,
``R_low = R``) is symmetric under ``S: x -> -x, t -> t + T/2``: eq. (1) is linear
and its harmonic forcing changes sign over half a forcing period, and the impact
law (eq. 4) at ``x_j = b`` is the image of the one at ``x_j = -b``. An N-p motion
with ``N`` odd, ``p = 2h`` even and a pattern whose second half mirrors its first
(impact ``k + h`` on the other stop than impact ``k``) may be *symmetric*: mapped
onto itself by ``S`` after ``N T / 2``,

    X_{k+h} = -X_k,    tau_{k+h} = tau_k,    theta_{k+h} = theta_k + N pi.

In the section coordinates ``[z, theta]`` of eq. (25) the reflection is
``S = diag(-1, .., -1, +1)`` (``z -> -z``; the phase shift is a constant), the
flights of the second half are the reflected flights of the first
(``G_{k+h} = S G_k S``), and the impact map over the motion is the square of the
*half-map*

    H = S G_{h-1} .. G_0,        G = H^2.

A multiplier ``-1`` of ``H`` gives ``G`` a multiplier ``+1`` without a fold of the
symmetric branch: the symmetry-breaking pitchfork (label ``BP``), where a pair of
asymmetric motions, mirror images of each other, branches off. Its test function
is ``det(H + I)``, freed of the poles of the ``G_k`` at zero impact velocity as the
PD test is (:func:`pitchfork_test`). The symmetric motion itself solves the
shooting system of its first half closed by the reflection (``X_h = -X_0``); that
system is regular at the pitchfork, where the full one is singular
(:class:`HalfUnknowns` maps between the two sets of unknowns).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import LOWER, UPPER
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import MultiImpactOrbit, orbit_from_unknowns

__all__ = [
    "HalfUnknowns",
    "admits_symmetric_motions",
    "half_map",
    "is_symmetric",
    "mirror_image",
    "mirror_pattern",
    "pitchfork_critical",
    "pitchfork_noise",
    "pitchfork_test",
    "symmetric_system",
    "symmetry_defect",
]

_EPS = float(np.finfo(float).eps)
_NOISE_ULPS = 64
#: A motion is symmetric when :func:`symmetry_defect` is at most this (relative).
SYMMETRY_TOL = 1e-8


def mirror_pattern(pattern: str) -> str:
    """The pattern with every impact on the other stop (``"UUL"`` -> ``"LLU"``)."""
    return pattern.translate(str.maketrans({UPPER: LOWER, LOWER: UPPER}))


def symmetric_system(osc: ImpactOscillator) -> bool:
    """Whether ``x -> -x, t -> t + T/2`` maps the system onto itself.

    True when the impacting mass has two stops at the same distance with the same
    restitution (``b_low == b`` and ``R_low == R`` exactly) and no constant force
    ``F_static`` pushes it one way: the equations of motion are linear with harmonic
    forcing, so nothing else can break the symmetry.
    """
    stops = osc.stops
    return bool(stops.two_sided and stops.b_low == osc.b and stops.R_low == osc.R
                and not np.any(osc.F_static) and not getattr(stops, "extra", ()))


def admits_symmetric_motions(osc: ImpactOscillator, N: int, p: int, pattern: str) -> bool:
    """Whether N-p motions with this pattern can be symmetric in this system.

    ``N`` odd (half the motion is an odd number of half forcing periods, where the
    forcing has changed sign), ``p`` even and impact ``k + p/2`` on the other stop
    than impact ``k``, in a :func:`symmetric_system`.
    """
    h = p // 2
    return (N % 2 == 1 and p % 2 == 0 and len(pattern) == p
            and pattern[h:] == mirror_pattern(pattern[:h]) and symmetric_system(osc))


def symmetry_defect(orbit: MultiImpactOrbit) -> float:
    """How far a motion is from its mirror image (relative; ``inf`` if it cannot be symmetric).

    ``max(|X_{k+h} + X_k|, omega |tau_{k+h} - tau_k|) / max(1, |X|)`` over ``k < h``.
    """
    osc = orbit.oscillator
    if not admits_symmetric_motions(osc, orbit.N, orbit.p, orbit.pattern or UPPER * orbit.p):
        return math.inf
    h = orbit.p // 2
    states, taus = orbit.states, orbit.flight_times
    scale = max(1.0, float(np.max(np.abs(states))))
    return max(float(np.max(np.abs(states[h:] + states[:h]))),
               osc.omega * float(np.max(np.abs(taus[h:] - taus[:h])))) / scale


def is_symmetric(orbit: MultiImpactOrbit, tol: float = SYMMETRY_TOL) -> bool:
    """Whether the motion is symmetric (:func:`symmetry_defect` at most `tol`)."""
    return symmetry_defect(orbit) <= tol


@functools.cache
def _reflection(n: int) -> np.ndarray:
    """``S`` in the section coordinates ``[z, theta]`` (``2n - 1`` entries of z); made once
    per n (the half-map of every BP test sample multiplies by it), read-only."""
    S = np.append(-np.ones(2 * n - 1), 1.0)
    S.flags.writeable = False
    return S


def half_map(orbit: MultiImpactOrbit) -> np.ndarray:
    """``H = S G_{h-1} .. G_0``, the half-map of a symmetric motion (``G = H^2``).

    Parameters
    ----------
    orbit : MultiImpactOrbit
        A motion of :func:`admits_symmetric_motions`; on a motion that is not
        symmetric ``H^2`` is not ``G``.

    Returns
    -------
    ndarray, shape (2n, 2n)
    """
    A = np.eye(orbit.G.shape[0])
    with np.errstate(over="ignore", invalid="ignore"):
        for k in range(orbit.p // 2):
            A = orbit.jacobians[k] @ A
    return _reflection(orbit.oscillator.n)[:, None] * A


def pitchfork_test(orbit: MultiImpactOrbit) -> float:
    """``det(H + I)`` times the speeds of the half's impacts: the BP test function.

    Each ``G_k`` is affine in ``1 / h2`` of its flight (eq. 25, rank one), so the
    product with the speeds ``v_1 .. v_h`` at the impacts ending the first h
    flights is smooth through a zero-velocity impact and vanishes only where ``H``
    has a multiplier -1 (as :func:`impactcont.detection.special_points.pole_free`
    for PD). NaN when a G is not finite.
    """
    H = half_map(orbit)
    if not np.all(np.isfinite(H)):
        return math.nan
    h = orbit.p // 2
    speeds = np.asarray(orbit.impact_velocities, dtype=float)[1:h + 1]
    mu = np.linalg.eigvals(H)
    return float(np.prod(mu + 1.0).real * np.prod(speeds))


def pitchfork_noise(orbit: MultiImpactOrbit) -> float:
    """Rounding error of :func:`pitchfork_test`: its factors ``mu_i + 1`` each known to
    ``64 eps max(1, rho(H))``, relative errors summed (as the PD test's)."""
    H = half_map(orbit)
    if not np.all(np.isfinite(H)):
        return math.inf
    mu = np.linalg.eigvals(H)
    err = _NOISE_ULPS * _EPS * max(1.0, float(np.max(np.abs(mu))))
    with np.errstate(divide="ignore"):
        relative = float(np.sum(err / np.abs(mu + 1.0)))
    return abs(pitchfork_test(orbit)) * relative if math.isfinite(relative) else math.inf


def pitchfork_critical(orbit: MultiImpactOrbit, tol: float = 1e-7) -> bool:
    """Whether the half-map has a multiplier within `tol` of -1 (a zero of
    :func:`pitchfork_test` that is the pitchfork, not a pole of a ``G_k``)."""
    H = half_map(orbit)
    return bool(np.all(np.isfinite(H)) and np.min(np.abs(np.linalg.eigvals(H) + 1.0)) < tol)


def mirror_image(orbit: MultiImpactOrbit) -> MultiImpactOrbit:
    """The mirror image ``S`` of a motion, numbered so that it has the same pattern.

    Impact ``k`` of the image is the reflection of impact ``k + h`` of `orbit`:
    ``X'_k = -X_{k+h}``, ``tau'_k = tau_{k+h}``, ``theta'_k = theta_{k+h} + N pi``.
    A symmetric motion is its own image; an asymmetric one's image is the other
    motion of its pair (same multipliers, same stability).

    Raises
    ------
    ValueError
        When the motion cannot have a mirror image of its pattern
        (:func:`admits_symmetric_motions` is False).
    """
    osc = orbit.oscillator
    pattern = orbit.pattern or UPPER * orbit.p
    if not admits_symmetric_motions(osc, orbit.N, orbit.p, pattern):
        raise ValueError(f"the N={orbit.N}, p={orbit.p} motion with pattern {pattern!r} of "
                         f"{osc!r} has no mirror image of the same pattern: that needs N odd, "
                         "p even, the second half of the pattern the mirror of the first, and "
                         "b_low == b, R_low == R")
    h = orbit.p // 2
    order = np.roll(np.arange(orbit.p), -h)
    states = -orbit.states[order]
    taus = orbit.flight_times[order]
    j = osc.stops.index
    z = np.delete(states, j, axis=1)
    u = np.concatenate([[orbit.phases[h] + orbit.N * math.pi], taus[:-1], z.ravel()])
    return orbit_from_unknowns(Flow(osc), orbit.N, orbit.p, u, pattern=pattern)


@dataclasses.dataclass(frozen=True)
class HalfUnknowns:
    """The unknowns of a symmetric N-p motion's first half, and the full ones they give.

    The full shooting unknowns (:mod:`impactcont.orbit.multi_impact`) are
    ``u = [delta, tau_0 .. tau_{p-2}, z_0 .. z_{p-1}]``; a symmetric motion is
    given by ``v = [delta, tau_0 .. tau_{h-2}, z_0 .. z_{h-1}]`` (``2 n h``
    numbers) with ``tau_{h-1} = N pi / omega - (tau_0 + .. + tau_{h-2})``,
    ``tau_{k+h} = tau_k`` and ``z_{k+h} = -z_k``: ``u = E v + e(omega)``.

    Parameters
    ----------
    n : int
        Degrees of freedom.
    p : int
        Impacts of the full motion (even).
    N : int
        Forcing periods of the full motion (odd).
    """

    n: int
    p: int
    N: int

    @property
    def h(self) -> int:
        """Impacts of the half-motion."""
        return self.p // 2

    @property
    def size(self) -> int:
        """``2 n h``, the number of half unknowns."""
        return 2 * self.n * self.h

    @property
    def tau_column(self) -> int:
        """Column of ``tau_{h-1}`` among the full unknowns (it depends on omega)."""
        return self.h

    @functools.cached_property
    def embedding(self) -> np.ndarray:
        """``E = du/dv``, shape ``(2np, 2nh)`` (computed once; do not modify it)."""
        n, p, h = self.n, self.p, self.h
        q = 2 * n - 1
        E = np.zeros((2 * n * p, self.size))
        E[0, 0] = 1.0
        for k in range(p - 1):  # tau_k, k <= p - 2, from tau_{k mod h}
            i = k % h
            if i < h - 1:
                E[1 + k, 1 + i] = 1.0
            else:  # tau_{h-1} = N pi / omega - sum of the half's others
                E[1 + k, 1:h] = -1.0
        for k in range(p):  # z_k = +-z_{k mod h}
            sign = 1.0 if k < h else -1.0
            E[p + k * q:p + (k + 1) * q, h + (k % h) * q:h + (k % h + 1) * q] = sign * np.eye(q)
        return E

    def full(self, v: np.ndarray, omega: float) -> np.ndarray:
        """The full unknowns ``u = E v + e(omega)`` of the symmetric motion given by `v`."""
        u = self.embedding @ np.asarray(v, dtype=float)
        half_period = self.N * math.pi / omega
        for k in range(self.p - 1):
            if k % self.h == self.h - 1:
                u[1 + k] += half_period
        return u

    def offset_derivative(self, omega: float) -> np.ndarray:
        """``de/domega`` (the ``tau_{h-1}`` entries: ``-N pi / omega^2``)."""
        d = np.zeros(2 * self.n * self.p)
        for k in range(self.p - 1):
            if k % self.h == self.h - 1:
                d[1 + k] = -self.N * math.pi / omega ** 2
        return d

    def half(self, u: np.ndarray) -> np.ndarray:
        """The half unknowns of a symmetric motion's full unknowns `u` (its first half)."""
        u = np.asarray(u, dtype=float)
        h, q = self.h, 2 * self.n - 1
        return np.concatenate([u[:h], u[self.p:self.p + h * q]])

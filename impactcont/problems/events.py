"""Event sets: the test functions of the special points of a motion (branch problems' events).

Each label has a test function of a motion that changes sign at the special point
(the table of :mod:`impactcont.detection.special_points`); a branch problem declares
which it watches (``problem.events``, ``problem.motion_tests``) and the detectors
locate them. Here: the PD/NS products made free of the poles of G at ``h2 = 0``
(:func:`pole_free`), the test function of PD, NS, GR and ZV at a motion
(:func:`event_function`), its rounding (:func:`event_noise`), and the symmetry-breaking
pitchfork BP of a symmetric motion (:data:`PITCHFORK`, a multiplier -1 of the half-map
``H`` of :mod:`impactcont.orbit.symmetry`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from impactcont.core.locate import MotionTest
from impactcont.orbit.symmetry import pitchfork_critical, pitchfork_noise, pitchfork_test

__all__ = ["PITCHFORK", "event_function", "event_noise", "half_speeds", "pole_free"]

_EPS = float(np.finfo(float).eps)



def half_speeds(orbit: Any) -> np.ndarray:
    """The speeds that clear the BP test of its poles: those at the impacts ending the
    first half's flights (:func:`~impactcont.orbit.symmetry.pitchfork_test`)."""
    return np.asarray(orbit.impact_velocities, dtype=float)[1:orbit.p // 2 + 1]


#: BP: ``det(H + I)`` of the half-map (pole-free), its rounding, the criticality check, and
#: the speeds whose zeros are the poles it was cleared of (a step is split there).
PITCHFORK = MotionTest(pitchfork_test, pitchfork_noise, pitchfork_critical, poles=half_speeds)


def _bialternate(mu: np.ndarray) -> float:
    prod = 1.0 + 0.0j
    for i in range(mu.size):
        for j in range(i + 1, mu.size):
            prod *= mu[i] * mu[j] - 1.0
    return float(prod.real)


def pole_free(label: str, multipliers: np.ndarray, impact_velocities: np.ndarray) -> float:
    """The PD or NS test function multiplied free of the poles of G at ``h2 = 0``.

    G of eq. (25) is ``A + x y^T / h2``: a rank-one term with the pole. Hence
    ``det(G + I)`` is affine in ``1/h2`` and ``h2 det(G + I)`` is smooth through a
    zero-velocity impact, vanishing only where a multiplier is -1; the bialternate
    product ``prod_{i<j}(mu_i mu_j - 1)`` is a polynomial of degree ``m - 1`` in
    ``1/h2`` (the rank-one term's own bialternate vanishes), so ``h2^(m-1)`` clears it.
    For an N-p motion G is a product of such factors, one per impact ``k`` with its
    own ``h2_k``. Without this a PD and a ZV in one step cancelled or were discarded
    as a pole crossing, and detection depended on the step size.
    """
    mu = np.asarray(multipliers)
    h = np.asarray(impact_velocities, dtype=float)
    if label == "PD":
        return float(np.prod(mu + 1.0).real * np.prod(h))
    return _bialternate(mu) * float(np.prod(h ** (mu.size - 1)))


def event_function(label: str, orbit: Any) -> float:
    """Value of the test function of `label` (all but SN) at a motion."""
    if label in ("PD", "NS"):
        velocities = getattr(orbit, "impact_velocities", None)
        if velocities is None:
            velocities = np.array([orbit.impact_velocity])
        return pole_free(label, orbit.multipliers, velocities)
    if label == "GR":
        return orbit.gap_min
    if label == "ZV":
        return orbit.impact_velocity
    raise ValueError(f"label must be one of PD, NS, GR, ZV here; got {label!r}")


#: rounding of the GR and ZV test functions, in eps times the size of the motion
_NOISE_ULPS = 64.0


def event_noise(label: str, orbit: Any) -> float:
    """The rounding error of :func:`event_function` of `label` at a motion (0 if unknown).

    GR: ``b - x_j`` at an interior maximum, sums of terms of the size of the
    displacements; ZV: the impact velocity, sums of terms of the size of the
    velocities ``max(|x'|, omega |x|)``; both ``_NOISE_ULPS`` eps times that size.
    PD and NS: products of factors ``mu_i + 1`` and ``mu_i mu_j - 1`` of multipliers
    known to ``_NOISE_ULPS eps max(1, rho(G))`` each; the product's relative error is
    the sum of its factors'. Far above the natural frequencies (``R = 1``, light
    damping) a factor ``mu_big mu_small - 1`` is that small, and its sign rounding.
    """
    if label in ("PD", "NS"):
        mu = np.asarray(orbit.multipliers)
        if not np.all(np.isfinite(mu)):
            return math.inf
        err = _NOISE_ULPS * _EPS * max(1.0, float(np.max(np.abs(mu))))
        if label == "PD":
            factors, errors = mu + 1.0, np.full(mu.size, err)
        else:
            i, j = np.triu_indices(mu.size, 1)
            factors, errors = mu[i] * mu[j] - 1.0, err * (np.abs(mu[i]) + np.abs(mu[j]))
        with np.errstate(divide="ignore"):
            relative = float(np.sum(errors / np.abs(factors)))
        return abs(event_function(label, orbit)) * relative if math.isfinite(relative) \
            else math.inf
    # an N-p motion's states at its p impacts, or an N-1 motion's one state
    states = np.atleast_2d(np.asarray(getattr(orbit, "states", orbit.state), dtype=float))
    n = states.shape[1] // 2
    size = float(np.max(np.abs(states[:, :n])))
    if label == "GR":
        return _NOISE_ULPS * _EPS * max(size, abs(orbit.oscillator.b))
    if label == "ZV":
        omega = orbit.oscillator.omega
        return _NOISE_ULPS * _EPS * max(float(np.max(np.abs(states[:, n:]))), omega * size)
    return 0.0

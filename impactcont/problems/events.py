"""The kinds of special points as a problem declares them: test, noise, criticality.

Each kind (a :class:`~impactcont.vocabulary.Label`: its marker, words and codimension)
has a test function of a motion that changes sign at the special point (the table of
:mod:`impactcont.detection.special_points`), the rounding of that test, and a check that a
located zero is the bifurcation; here each is one :class:`~impactcont.core.locate.MotionTest`
object: :data:`PERIOD_DOUBLING`, :data:`NEIMARK_SACKER`, :data:`GRAZING`,
:data:`ZERO_VELOCITY`, the end of a flight :data:`FLIGHT_END` (a flight time through 0)
and the symmetry-breaking pitchfork :data:`PITCHFORK` (a multiplier
-1 of the half-map ``H`` of :mod:`impactcont.orbit.symmetry`). A branch problem declares
the kinds its branches have (``problem.events``) and their tests (``problem.motion_tests``:
:data:`BRANCH_TESTS`, with BP on a branch of symmetric motions); the detectors locate
them without knowing any kind by name. The fold SN is the branch's own turning point
(the parameter component of the tangent), not a function of one motion.

The PD and NS products are made free of the poles of G at ``h2 = 0`` (:func:`pole_free`)
and declare the impact velocities as their poles.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from impactcont.core.locate import MotionTest
from impactcont.orbit.symmetry import pitchfork_critical, pitchfork_noise, pitchfork_test
from impactcont.vocabulary import Label

__all__ = ["BRANCH_TESTS", "FLIGHT_END", "GRAZING", "MULTIPLIER_CRITERIA", "NEIMARK_SACKER",
           "PERIOD_DOUBLING", "PITCHFORK", "UNIT_TOL", "ZERO_VELOCITY", "event_function",
           "event_noise", "flight_end_test", "half_speeds", "impact_speeds", "ns_critical",
           "pd_critical", "pole_free"]

_EPS = float(np.finfo(float).eps)

#: How close to -1 (PD) or to the unit circle (NS) a multiplier at a located zero of a
#: branch's test must be for the zero to be the bifurcation (:func:`pd_critical`).
UNIT_TOL = 1e-7


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


def _pd_product(mu: np.ndarray, h: np.ndarray) -> float:
    return float(np.prod(mu + 1.0).real * np.prod(h))


def _ns_product(mu: np.ndarray, h: np.ndarray) -> float:
    return _bialternate(mu) * float(np.prod(h ** (mu.size - 1)))


_POLE_FREE: Mapping[str, Callable[[np.ndarray, np.ndarray], float]] = MappingProxyType(
    {Label.PD: _pd_product, Label.NS: _ns_product})


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

    Raises
    ------
    ValueError
        `label` is not PD or NS.
    """
    product = _POLE_FREE.get(label)
    if product is None:
        raise ValueError(f"label must be PD or NS here; got {label!r}")
    return product(np.asarray(multipliers), np.asarray(impact_velocities, dtype=float))


def impact_speeds(orbit: Any) -> np.ndarray:
    """The impact velocities of a motion: an N-p motion's p, an N-1 motion's one.

    The poles PD and NS were cleared of, and where the branch's own system is singular
    besides its folds (the rate of an impact condition, eq. (22), vanishes with them):
    a fold that is not located where one changes sign cannot be told from it
    (:mod:`impactcont.detection.special_points`)."""
    velocities = getattr(orbit, "impact_velocities", None)
    return np.array([orbit.impact_velocity]) if velocities is None else velocities


#: rounding of the GR and ZV test functions, in eps times the size of the motion
_NOISE_ULPS = 64.0


def _product_noise(orbit: Any, test: Callable[[Any], float],
                   factors: Callable[[np.ndarray, float], tuple[np.ndarray, np.ndarray]]
                   ) -> float:
    """The rounding of a PD or NS product: the sum of its factors' relative errors
    (``factors(mu, err)`` gives the factors and their errors) times its size."""
    mu = np.asarray(orbit.multipliers)
    if not np.all(np.isfinite(mu)):
        return math.inf
    err = _NOISE_ULPS * _EPS * max(1.0, float(np.max(np.abs(mu))))
    values, errors = factors(mu, err)
    with np.errstate(divide="ignore"):
        relative = float(np.sum(errors / np.abs(values)))
    return abs(test(orbit)) * relative if math.isfinite(relative) else math.inf


def _pd_factors(mu: np.ndarray, err: float) -> tuple[np.ndarray, np.ndarray]:
    return mu + 1.0, np.full(mu.size, err)


def _ns_factors(mu: np.ndarray, err: float) -> tuple[np.ndarray, np.ndarray]:
    i, j = np.triu_indices(mu.size, 1)
    return mu[i] * mu[j] - 1.0, err * (np.abs(mu[i]) + np.abs(mu[j]))


def _pd_test(orbit: Any) -> float:
    return _pd_product(np.asarray(orbit.multipliers), np.asarray(impact_speeds(orbit), dtype=float))


def _ns_test(orbit: Any) -> float:
    return _ns_product(np.asarray(orbit.multipliers), np.asarray(impact_speeds(orbit), dtype=float))


def _sizes(orbit: Any) -> tuple[np.ndarray, float]:
    """The states at the impacts (an N-p motion's p, an N-1 motion's one) and the
    largest displacement among them."""
    states = np.atleast_2d(np.asarray(getattr(orbit, "states", orbit.state), dtype=float))
    n = states.shape[1] // 2
    return states, float(np.max(np.abs(states[:, :n])))


def _gr_noise(orbit: Any) -> float:
    """``b - x_j`` at an interior maximum: sums of terms of the size of the displacements."""
    _, size = _sizes(orbit)
    return _NOISE_ULPS * _EPS * max(size, abs(orbit.oscillator.b))


def _zv_noise(orbit: Any) -> float:
    """The impact velocity: sums of terms of the size of the velocities
    ``max(|x'|, omega |x|)``."""
    states, size = _sizes(orbit)
    n = states.shape[1] // 2
    omega = orbit.oscillator.omega
    return _NOISE_ULPS * _EPS * max(float(np.max(np.abs(states[:, n:]))), omega * size)


def pd_critical(multipliers: np.ndarray, unit_tol: float) -> bool:
    """Whether a zero of the PD test is a period doubling: a multiplier within
    `unit_tol` of -1 (``det(G + I)`` also changes sign through the pole of G)."""
    return bool(np.min(np.abs(np.asarray(multipliers) + 1.0)) < unit_tol)


def ns_critical(multipliers: np.ndarray, unit_tol: float) -> bool:
    """Whether a zero of the NS test is a Neimark-Sacker point: a complex pair within
    `unit_tol` of the unit circle (a real reciprocal pair is a neutral saddle)."""
    mu = np.asarray(multipliers)
    close = np.abs(np.abs(mu) - 1.0) < unit_tol
    return bool(np.any(close & (np.abs(mu.imag) > 1e-8)))


#: The kinds whose located zeros are checked on the multipliers: ``kind -> criterion(mu,
#: unit_tol)`` (:func:`impactcont.detection.locator.is_critical`).
MULTIPLIER_CRITERIA: Mapping[str, Callable[[np.ndarray, float], bool]] = MappingProxyType(
    {Label.PD: pd_critical, Label.NS: ns_critical})

#: PD: ``h2 det(G + I)`` (pole-free), a multiplier -1; split at every impact's ``h2 = 0``.
PERIOD_DOUBLING = MotionTest(
    _pd_test, lambda orbit: _product_noise(orbit, _pd_test, _pd_factors),
    lambda orbit: pd_critical(orbit.multipliers, UNIT_TOL), poles=impact_speeds)

#: NS: ``h2^(m-1) prod_{i<j}(mu_i mu_j - 1)`` (pole-free), a complex pair on the unit
#: circle (not a neutral saddle); split at every impact's ``h2 = 0``.
NEIMARK_SACKER = MotionTest(
    _ns_test, lambda orbit: _product_noise(orbit, _ns_test, _ns_factors),
    lambda orbit: ns_critical(orbit.multipliers, UNIT_TOL), poles=impact_speeds)

#: GR: ``gap_min``, the smallest clearance inside the flights (eq. 16); it needs the
#: motion's interior-contact search.
GRAZING = MotionTest(lambda orbit: orbit.gap_min, _gr_noise, checks=True)

#: ZV: the impact velocity h2 of eq. (22) (the smallest of an N-p motion's).
ZERO_VELOCITY = MotionTest(lambda orbit: orbit.impact_velocity, _zv_noise)



def flight_end_test(orbit: Any) -> float:
    """The end of a flight: the shortest flight time ``min_k tau_k`` of the motion.

    Zero where two consecutive contacts merge (an impact and the next, or a release and
    the landing after it); past it the shooting continues with a negative flight time, a
    motion flagged not physical. A one-impact motion's flight lasts its period (never 0);
    with a sticking phase its flight is the period less the stick.
    """
    return float(np.min(np.asarray(orbit.flight_times, dtype=float)))


def _flight_noise(orbit: Any) -> float:
    """Rounding of a flight time: eps times the period (the last flight time closes it)."""
    return _NOISE_ULPS * _EPS * 2.0 * math.pi * orbit.N / orbit.oscillator.omega


#: FT: ``min_k tau_k``, the shortest flight (:func:`flight_end_test`). Its zero is a
#: singular point of the shooting system (:attr:`~impactcont.vocabulary.Label.singular`).
FLIGHT_END = MotionTest(flight_end_test, _flight_noise)

#: The tests of the kinds every branch of periodic motions has (besides its folds, SN);
#: a branch of symmetric motions adds :data:`PITCHFORK`, one of motions with sticking
#: phases :data:`~impactcont.problems.multi_impact_branch.STICKING_TESTS`.
BRANCH_TESTS: Mapping[str, MotionTest] = MappingProxyType({
    Label.PD: PERIOD_DOUBLING, Label.NS: NEIMARK_SACKER, Label.GR: GRAZING,
    Label.ZV: ZERO_VELOCITY, Label.FT: FLIGHT_END})


def event_function(label: str, orbit: Any) -> float:
    """Value of the test function of `label` (PD, NS, GR, ZV or FT) at a motion
    (:data:`BRANCH_TESTS`).

    Raises
    ------
    ValueError
        Another label.
    """
    test = BRANCH_TESTS.get(label)
    if test is None:
        raise ValueError(f"label must be one of {', '.join(BRANCH_TESTS)} here; got {label!r}")
    return test.test(orbit)


def event_noise(label: str, orbit: Any) -> float:
    """The rounding error of :func:`event_function` of `label` at a motion (0 if unknown).

    Notes
    -----
    GR: ``b - x_j`` at an interior maximum, sums of terms of the size of the
    displacements; ZV: the impact velocity, sums of terms of the size of the
    velocities ``max(|x'|, omega |x|)``; both ``_NOISE_ULPS`` eps times that size.
    PD and NS: products of factors ``mu_i + 1`` and ``mu_i mu_j - 1`` of multipliers
    known to ``_NOISE_ULPS eps max(1, rho(G))`` each; the product's relative error is
    the sum of its factors'. Far above the natural frequencies (``R = 1``, light
    damping) a factor ``mu_big mu_small - 1`` is that small, and its sign rounding.
    """
    test = BRANCH_TESTS.get(label)
    return 0.0 if test is None or test.noise is None else test.noise(orbit)

"""Codimension-two points on codim-1 curves: where two curves meet, or a curve ends.

Along a curve of kind A every other condition B has a test function of the
motion; a sign change between two accepted points brackets a point where the
curve A meets the curve B (label ``"A+B"``). It is located by Brent's method
on the chord between the two points, each trial point corrected back onto the
curve (Newton on the augmented system plus the hyperplane orthogonal to the
chord), as :mod:`impactcont.detection.special_points` does on branches.

=========  =====================================================  ===================
test       function of the motion                                 on curves
=========  =====================================================  ===================
``ZV``     impact velocity ``h2`` (eq. 22)                         SN, PD, NS, GR
``GR``     ``gap_min`` (eq. 16); on a GR curve the highest         SN, PD, NS, GR
           interior maximum other than the tangency (double graze)
``SN``     ``dr/d delta`` (eq. 14; zero at a fold)                 PD, NS, GR, ZV
``PD``     ``h2 det(G + I) = h2 prod (mu_i + 1)``                  SN, NS, GR
``NS``     ``h2^(m-1) prod_{i<j} (mu_i mu_j - 1)`` (bialternate)   SN, PD, GR
=========  =====================================================  ===================

The GR test is skipped on ZV curves: there the motion is the linear response
touching the stop, whose every maximum (for N >= 2) sits at ``b``. PD and NS
tests are skipped on ZV curves, where ``G`` has its pole (eq. 25). As on
branches, a PD sign change without a multiplier at -1 (through the pole) and an
NS sign change at a neutral saddle are discarded.

Curve ends, found while continuing (:func:`impactcont.analysis.curves.curve`) rather than
here: an NS curve ends at ``theta -> 0`` (``R1``, 1:1 resonance) or
``theta -> pi`` (``R2``, 1:2), the points that SN and PD curves meet as a double
multiplier +1 or -1 and name the same, a GR curve where the tangency time reaches the
impact (``t* -> 0`` or ``T``, label ``GR+ZV``).
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from impactcont.core.locate import dip_bottom, parts_beside_poles, zero_precision
from impactcont.core.stepper import NewtonConvergenceError
from impactcont.detection.locator import locate_zero, twins
from impactcont.detection.special_points import event_noise, pole_free
from impactcont.orbit.periodic import PeriodicOrbit
from impactcont.problems.codim1 import CurveProblem

__all__ = ["TESTS", "Codim2Point", "detect_codim2", "grazing_other_gap", "test_values"]

log = logging.getLogger(__name__)

#: The test functions watched on each kind of curve.
TESTS: dict[str, tuple[str, ...]] = {
    "SN": ("ZV", "GR", "PD", "NS"),
    "PD": ("ZV", "GR", "SN", "NS"),
    "NS": ("ZV", "GR", "SN", "PD"),
    "GR": ("ZV", "GR", "SN", "PD", "NS"),
    "ZV": ("SN",),
}

_UNIT_TOL = 1e-6


@dataclasses.dataclass(frozen=True, eq=False)
class Codim2Point:
    """A codim-2 point on a curve.

    Attributes
    ----------
    label : str
        ``"A+B"`` (curve kind A meets kind B), ``"R1"`` or ``"R2"``.
    x : ndarray
        ``[u, lam]`` of the curve problem at the point.
    orbit : PeriodicOrbit
    point : int
        Index of the nearest accepted curve point.
    precision : float
        Bound on the error in the plane of the two parameters.
    status : str
        ``"located"`` or ``"bracketed"``.
    """

    label: str
    x: np.ndarray
    orbit: PeriodicOrbit
    point: int
    precision: float
    status: str


def grazing_other_gap(problem: CurveProblem, orbit: PeriodicOrbit, tangency_time: float) -> float:
    """``b`` minus the highest interior maximum of x1 other than the tangency at ``t*``
    (the exact search of the curve's pieces, with the tangency excluded; inf when there
    is none)."""
    pc = problem._pieces(*_params(problem, orbit))
    return float(pc.b - pc.other_maximum(orbit.delta, float(tangency_time)))


def _params(problem: CurveProblem, orbit: PeriodicOrbit) -> tuple[float, float]:
    p1, p2 = problem.parameters
    return getattr(orbit.oscillator, p1), getattr(orbit.oscillator, p2)


def test_values(problem: CurveProblem, x: np.ndarray, orbit: PeriodicOrbit) -> dict[str, float]:
    """The test functions of :data:`TESTS` for the problem's kind at a curve point."""
    out: dict[str, float] = {}
    for test in TESTS[problem.kind]:
        if test == "ZV":
            out[test] = orbit.impact_velocity
        elif test == "GR":
            out[test] = (grazing_other_gap(problem, orbit, float(x[2])) if problem.kind == "GR"
                         else orbit.gap_min)
        elif test == "SN":
            out[test] = problem.fold_function(x[:-1], x[-1])
        else:  # PD, NS: free of the pole of G at h2 = 0
            out[test] = pole_free(test, orbit.multipliers, np.array([orbit.impact_velocity]))
    return out


def _changes(a: float, b: float) -> bool:
    """Opposite signs; ``+-inf`` by their sign (a GR test without an interior maximum is
    +inf), NaN as no sign."""
    return not (math.isnan(a) or math.isnan(b)) and (a < 0) != (b < 0)


_CRITICAL = {"SN": 1.0, "PD": -1.0}
"""The multiplier that stays on the unit circle along an SN or a PD curve."""

_RESONANCE = {"SN": "R1", "PD": "R2"}
"""The strong resonance where a second multiplier reaches the curve's critical value:
a double +1 (1:1, ``R1``) on an SN curve, a double -1 (1:2, ``R2``) on a PD curve; the
same names as the ends of an NS curve there."""


def _name(kind: str, test: str, orbit: PeriodicOrbit) -> str | None:
    """What a zero of `test` on a curve of `kind` is, or ``None`` when it is none.

    The PD test vanishes only with a multiplier at -1. The NS test (the
    bialternate product) vanishes where two multipliers have product 1: a
    complex pair on the unit circle (``kind+NS``), a second multiplier at the
    curve's own critical value (a repeated +1 on an SN curve: the 1:1
    resonance ``R1``; a repeated -1 on a PD curve: the 1:2 resonance ``R2``;
    the names of the NS curve's ends at the same points), or a real reciprocal
    pair (a neutral saddle: no bifurcation).
    The repeated multiplier is a Jordan block whose two copies split by the
    square root of rounding, possibly into a complex pair: it is recognised by
    distance, before the imaginary part is looked at.
    """
    mu = orbit.multipliers
    if test == "PD":
        return f"{kind}+PD" if np.min(np.abs(mu + 1.0)) < _UNIT_TOL else None
    if test != "NS":
        return f"{kind}+{test}"
    critical = _CRITICAL.get(kind)
    if critical is not None:
        rest = np.delete(mu, np.argmin(np.abs(mu - critical)))
        if rest.size and np.min(np.abs(rest - critical)) < _UNIT_TOL ** 0.5:
            return _RESONANCE[kind]
        mu = rest
    close = np.abs(np.abs(mu) - 1.0) < _UNIT_TOL
    return f"{kind}+NS" if np.any(close & (np.abs(mu.imag) > 1e-8)) else None


def _plane_distance(problem: CurveProblem, xa: np.ndarray, xb: np.ndarray) -> float:
    return float(math.hypot(xa[0] - xb[0], xa[-1] - xb[-1]))


class _Step:
    """The curve between two accepted points, by the chord coordinate ``s in [0, 1]``.

    A point at ``s`` is the curve's intersection with the hyperplane across the
    chord through ``xa + s (xb - xa)``; its test values are cached.
    """

    def __init__(self, problem: CurveProblem, xa: np.ndarray, xb: np.ndarray) -> None:
        self.problem, self.xa, self.xb = problem, xa, xb
        self.chord = xb - xa
        self._cache: dict[float, tuple[np.ndarray, dict[str, float]]] = {}
        self._noise: dict[tuple[float, str], float] = {}

    def point(self, sv: float) -> tuple[np.ndarray, dict[str, float]]:
        if sv not in self._cache:
            if sv == 0.0:
                x = self.xa
            elif sv == 1.0:
                x = self.xb
            else:
                guess, chord = self.xa + sv * self.chord, self.chord
                x = self.problem.solve(guess, lambda y, g=guess: float(chord @ (y - g)), chord)
            orbit = self.problem.orbit(x[:-1], x[-1])
            self._cache[sv] = (x, test_values(self.problem, x, orbit))
            for test in ("PD", "NS"):  # their rounding, for the sides of a pole
                self._noise[sv, test] = event_noise(test, orbit)
        return self._cache[sv]

    def noise(self, sv: float, test: str) -> float:
        """The rounding of the PD or NS test at ``sv`` (:func:`event_noise`)."""
        self.point(sv)
        return self._noise[sv, test]

    def value(self, sv: float, test: str) -> float:
        return self.point(sv)[1][test]

    def locate(self, test: str, lo: float = 0.0, hi: float = 1.0
               ) -> tuple[float, np.ndarray, float, str]:
        """Zero of ``test`` in ``[lo, hi]`` (Brent): ``(s, x, precision, status)``."""
        sroot, status = locate_zero(lambda sv: self.value(sv, test), lo, hi, 1e-13)
        x = self.point(sroot)[0]
        precision = zero_precision(lambda sv: self.value(sv, test),
                                   lambda sv: self.point(sv)[0][[0, -1]], sroot, 1e-13,
                                   lo, hi)
        return sroot, x, precision, status


def _intervals(step: _Step, test: str, tests_a: dict[str, float], tests_b: dict[str, float]
               ) -> list[tuple[float, float]]:
    """The parts of a step on which `test` is watched for a sign change.

    At a zero-velocity impact inside the step (``h2 = 0``, the pole of G, eq. 25)
    the pole-free PD and NS tests may vanish too, without a bifurcation (when a
    multiplier tends to 0 as another tends to infinity): the step is split there so
    that a PD or NS point in the same step is neither cancelled nor discarded, and the
    test's sign is read beside it only where it rises above its rounding (the multipliers
    lose ``1/h2^2`` of their accuracy there; :func:`~impactcont.core.locate.parts_beside_poles`).
    A sign change across the pole is the pole's: no codim-2 point.
    """
    whole = [(0.0, 1.0)]
    if test not in ("PD", "NS") or "ZV" not in tests_a or not _changes(tests_a["ZV"],
                                                                         tests_b["ZV"]):
        return whole
    step.problem.accept(step.xa[:-1], step.xa[-1])
    try:
        s_zv = step.locate("ZV")[0]
    except (ValueError, NewtonConvergenceError):
        return whole
    return parts_beside_poles(f"{step.problem.kind}+{test}",
                              lambda sv: step.value(sv, test),
                              lambda sv: step.noise(sv, test), [s_zv])


def detect_codim2(problem: CurveProblem, xs: list[np.ndarray], orbits: list[PeriodicOrbit],
                  tests: list[dict[str, float]]) -> list[Codim2Point]:
    """Locate the codim-2 points between consecutive accepted points of a curve.

    Parameters
    ----------
    problem : CurveProblem
    xs : list of ndarray
        ``[u, lam]`` of the accepted points, in curve order.
    orbits : list of PeriodicOrbit
        The motion at each point.
    tests : list of dict
        :func:`test_values` at each point.

    Returns
    -------
    list of Codim2Point
        In curve order.
    """
    found: list[Codim2Point] = []
    arclength = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(np.asarray(
        xs, dtype=float), axis=0), axis=1))]) if len(xs) > 1 else np.zeros(len(xs))
    for k in range(len(xs) - 1):
        found.extend(_without_grazing_twins(
            problem, _codim2_on_step(problem, xs, tests, k, arclength)))
    return found


def _without_grazing_twins(problem: CurveProblem, points: list[Codim2Point]
                           ) -> list[Codim2Point]:
    """The codim-2 points of one step without each ``A+GR`` that is the grazing of a
    located ``A+ZV`` there (a zero-velocity impact is a grazing contact: the GR test
    touches zero at it, as on branches, :func:`~impactcont.detection.locator.
    drop_grazing_at_zero_velocity`)."""
    kind = problem.kind
    zv = [z for z in points if z.label == f"{kind}+ZV" and z.status == "located"]
    kept = []
    for point in points:
        twin = next((z for z in zv if point.label == f"{kind}+GR" and twins(
            _plane_distance(problem, z.x, point.x), z.precision + point.precision,
            z.x[[0, -1]])), None)
        if twin is None:
            kept.append(point)
        else:
            log.info("%s at %s is the grazing of the zero-velocity impact %s: reported once",
                     point.label, point.x[[0, -1]], twin.label)
    return kept


def _codim2_on_step(problem: CurveProblem, xs: list[np.ndarray],
                    tests: list[dict[str, float]], k: int, arclength: np.ndarray
                    ) -> list[Codim2Point]:
    """The codim-2 points between accepted points `k` and ``k + 1``."""
    found: list[Codim2Point] = []
    step = _Step(problem, xs[k], xs[k + 1])
    for test in TESTS[problem.kind]:
        if _ends_at_resonance(problem, test, xs[k], xs[k + 1]):
            continue  # the multiplier +-1 of the R1/R2 end: that end itself
        parts = _intervals(step, test, tests[k], tests[k + 1])
        if parts == [(0.0, 1.0)] and not _changes(tests[k][test], tests[k + 1][test]):
            parts = _dip_parts(step, test, tests, k, arclength)
        for lo, hi in parts:
            if (lo, hi) == (0.0, 1.0):
                ga, gb = tests[k][test], tests[k + 1][test]
            else:
                problem.accept(xs[k][:-1], xs[k][-1])
                ga, gb = step.value(lo, test), step.value(hi, test)
            if not _changes(ga, gb):
                continue
            point = _codim2_in(problem, step, test, k, lo, hi, ga, gb)
            if point is not None:
                found.append(point)
    return found




def _dip_parts(step: _Step, test: str, tests: list[dict[str, float]], k: int,
               arclength: np.ndarray) -> list[tuple[float, float]]:
    """The two halves of step `k` when `test` dips through zero and back inside it
    (:func:`~impactcont.core.locate.dip_bottom`: the parabola through the test at the step
    and a neighbour has both its zeros inside the step, and the test at its bottom has the
    other sign); else none."""
    bottom = dip_bottom(lambda j: tests[j][test], arclength, k)
    if bottom is None:
        return []
    step.problem.accept(step.xa[:-1], step.xa[-1])
    try:
        low = step.value(bottom, test)
    except (ValueError, ArithmeticError, NewtonConvergenceError, np.linalg.LinAlgError):
        return []
    if not _changes(tests[k][test], low):
        return []
    log.info("the %s test dips through zero and back between curve points %d and %d",
             test, k, k + 1)
    return [(0.0, bottom), (bottom, 1.0)]


def _ends_at_resonance(problem: CurveProblem, test: str, xa: np.ndarray, xb: np.ndarray
                       ) -> bool:
    """Whether `test` (SN: a multiplier +1, PD: -1) of an NS curve's step vanishes at an
    end of the step that is the curve's 1:1 (``theta = 0``) or 1:2 (``theta = pi``) end."""
    if problem.kind != "NS" or test not in ("SN", "PD"):
        return False
    target = 0.0 if test == "SN" else math.pi
    return any(float(x[2]) == target for x in (xa, xb))


def _codim2_in(problem: CurveProblem, step: _Step, test: str, k: int, lo: float, hi: float,
               ga: float, gb: float) -> Codim2Point | None:
    """The codim-2 point where `test` changes sign in ``[lo, hi]`` of step `k`, or None."""
    xs = (step.xa, step.xb)
    problem.accept(step.xa[:-1], step.xa[-1])
    try:
        _, x, precision, status = step.locate(test, lo, hi)
    except (ValueError, NewtonConvergenceError) as exc:
        # e.g. next to h2 = 0, where G and so the PD/NS systems have a pole:
        # keep the bracket, placed by linear interpolation of the test values
        log.info("%s+%s between curve points %d and %d kept as bracketed: %s",
                 problem.kind, test, k, k + 1, exc)
        sv = lo + ga / (ga - gb) * (hi - lo)
        x = step.xa + sv * step.chord
        precision = _plane_distance(problem, *xs)
        status = "bracketed"
    orbit = problem.orbit(x[:-1], x[-1])
    label = _name(problem.kind, test, orbit) if status == "located" else \
        f"{problem.kind}+{test}"
    if label is None:
        log.debug("%s test changes sign without a critical multiplier near point %d", test, k)
        return None
    nearest = k if (_plane_distance(problem, x, xs[0])
                    <= _plane_distance(problem, x, xs[1])) else k + 1
    log.info("%s on the %s curve at %s=%.10g, %s=%.10g (%s)", label, problem.kind,
             problem.parameters[0], x[0], problem.parameters[1], x[-1], status)
    return Codim2Point(label, x, orbit, nearest, precision, status)

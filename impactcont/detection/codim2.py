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
``SE``     the shortest stick time (motions with sticking phases)  RG, SO; SN, PD, NS,
                                                                  GR of such motions
``RG``     the smallest pressing force inside the sticks           SN, PD, NS, GR of
                                                                  such motions
``SO``     the smallest pressing force at a landing                RG; SN, PD, NS, GR
                                                                  of such motions
=========  =====================================================  ===================

The GR test is skipped on ZV curves: there the motion is the linear response
touching the stop, whose every maximum (for N >= 2) sits at ``b``. PD and NS
tests are skipped on ZV curves, where ``G`` has its pole (eq. 25). As on
branches, a PD sign change without a multiplier at -1 (through the pole) and an
NS sign change at a neutral saddle are discarded.

The location is written once for both curve problems, the N-1 closed form
(:class:`~impactcont.problems.closed_form_curve.CurveProblem`) and the shooting of any N-p motion
(:class:`~impactcont.problems.codim1.ShootingCurve`), against what
both provide (:class:`Codim2Problem`): the tests watched on the curve and their values at
a point, where a point lies in the plane of the two parameters, a Newton solve of the
curve on a hyperplane, the motion at a point. On curves of N-p motions the ZV test is
the smallest impact velocity and the GR test the smallest clearance over the p impacts
and flights, the SN test the signed smallest singular value of the branch problem's
Jacobian (:func:`~impactcont.problems.codim1.signed_smallest_singular_value`),
and the PD and NS tests are made free of the poles of every impact
(:func:`~impactcont.problems.events.pole_free`); the GR test is not watched on a GR curve
of N-p motions (its second-lowest clearance is not searched yet). On a motion with
sticking phases the SE, RG and SO tests are those of its branch
(:data:`~impactcont.problems.multi_impact_branch.STICKING_TESTS`, minima over its
sticks); an SE curve watches neither RG nor SO (both vanish along it: the landing is the
release) and an SO curve not RG (:data:`impactcont.problems.codim1.SHOOTING_KINDS`).

Curve ends, found while continuing (:func:`impactcont.analysis.curves.curve`) rather than
here: an NS curve ends at ``theta -> 0`` (``R1``, 1:1 resonance) or
``theta -> pi`` (``R2``, 1:2), the points that SN and PD curves meet as a double
multiplier +1 or -1 and name the same, a GR curve where the tangency time reaches the
impact (``t* -> 0`` or ``T``, label ``GR+ZV``).
"""

from __future__ import annotations

import logging
import math
from typing import Any, Protocol

import numpy as np

from impactcont.core.locate import dip_bottom, parts_beside_poles, zero_precision
from impactcont.core.stepper import NewtonConvergenceError
from impactcont.detection.locator import locate_zero, twins
from impactcont.detection.points import SpecialPoint
from impactcont.detection.special_points import event_noise
from impactcont.vocabulary import Label

__all__ = ["TESTS", "Codim2Point", "Codim2Problem", "codim2_record", "detect_codim2",
           "grazing_other_gap", "test_values"]

log = logging.getLogger(__name__)

#: The test functions watched on each kind of curve (of N-1 motions; a problem declares
#: its own in :attr:`Codim2Problem.codim2_tests`).
TESTS: dict[Label, tuple[Label, ...]] = {
    Label.SN: (Label.ZV, Label.GR, Label.PD, Label.NS),
    Label.PD: (Label.ZV, Label.GR, Label.SN, Label.NS),
    Label.NS: (Label.ZV, Label.GR, Label.SN, Label.PD),
    Label.GR: (Label.ZV, Label.GR, Label.SN, Label.PD, Label.NS),
    Label.ZV: (Label.SN,),
}


class Codim2Problem(Protocol):
    """What a curve problem provides for its codim-2 points to be located.

    A curve point is ``x = [u, lam]``: the problem's unknowns ``u`` (which hold the first
    parameter ``p1``) and the second parameter ``lam = p2``.
    """

    kind: Label
    """The kind of the curve."""
    parameters: tuple[str, str]
    """``(p1, p2)``."""
    codim2_tests: tuple[Label, ...]
    """The other kinds whose test functions are watched along the curve."""
    last_step: float
    """The last Newton step of :meth:`on_hyperplane` (a bound on its error)."""

    def codim2_test(self, test: Label, x: np.ndarray, orbit: Any) -> float:
        """The test function of `test` at the curve point `x` with motion `orbit`."""

    def plane(self, x: np.ndarray) -> tuple[float, float]:
        """``(p1, p2)`` of a curve point."""

    def on_hyperplane(self, guess: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """The curve point on the hyperplane through `guess` normal to `normal`
        (raises :class:`~impactcont.core.stepper.NewtonConvergenceError`)."""

    def orbit(self, u: np.ndarray, lam: float) -> Any:
        """The motion at the point ``[u, lam]`` (multipliers, impact velocity, ...)."""

    def accept(self, u: np.ndarray, lam: float) -> None:
        """Renew the borders of the augmented system at an accepted point."""

    def end_resonance(self, x: np.ndarray) -> Label | None:
        """``R1``/``R2`` when `x` is a strong-resonance end of the curve (theta = 0, pi of
        an N-1 NS curve), else None."""

_UNIT_TOL = 1e-6
_POLE_FREE = (Label.PD, Label.NS)  # tests made free of G's pole at h2 = 0 (eq. 25)


#: A codim-2 point of a curve: the one special-point record (codimension 2) built from
#: ``(label, x, orbit, point, precision, status)``, ``x = [u, lam]`` of the curve problem
#: (:meth:`~impactcont.detection.points.SpecialPoint.on_curve`).
Codim2Point = SpecialPoint.on_curve


def grazing_other_gap(problem: Any, orbit: Any, tangency_time: float) -> float:
    """``b`` minus the highest interior maximum of x1 other than the tangency at ``t*`` on
    an N-1 curve (:meth:`~impactcont.problems.closed_form_curve.CurveProblem.other_gap`)."""
    return problem.other_gap(orbit, tangency_time)


def test_values(problem: Codim2Problem, x: np.ndarray, orbit: Any) -> dict[Label, float]:
    """The test functions the problem watches (:attr:`Codim2Problem.codim2_tests`) at a
    curve point."""
    return {test: problem.codim2_test(test, x, orbit) for test in problem.codim2_tests}


def _changes(a: float, b: float) -> bool:
    """Opposite signs; ``+-inf`` by their sign (a GR test without an interior maximum is
    +inf), NaN as no sign."""
    return not (math.isnan(a) or math.isnan(b)) and (a < 0) != (b < 0)


_CRITICAL = {Label.SN: 1.0, Label.PD: -1.0}
"""The multiplier that stays on the unit circle along an SN or a PD curve."""

_RESONANCE = {Label.SN: "R1", Label.PD: "R2"}
"""The strong resonance where a second multiplier reaches the curve's critical value:
a double +1 (1:1, ``R1``) on an SN curve, a double -1 (1:2, ``R2``) on a PD curve; the
same names as the ends of an NS curve there."""


def _name(kind: str, test: str, orbit: Any) -> str | None:
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
    if test in _CRITICAL and kind == Label.NS and _double(mu, _CRITICAL[test]):
        # the pair of an NS curve of N-p motions (which does not end there) meets at +-1
        return _RESONANCE[test]
    if test == Label.PD:
        return f"{kind}+PD" if np.min(np.abs(mu + 1.0)) < _UNIT_TOL else None
    if test != Label.NS:
        return f"{kind}+{test}"
    critical = _CRITICAL.get(kind)
    if critical is not None:
        if _double(mu, critical):
            return _RESONANCE[kind]
        mu = np.delete(mu, np.argmin(np.abs(mu - critical)))
    close = np.abs(np.abs(mu) - 1.0) < _UNIT_TOL
    return f"{kind}+NS" if np.any(close & (np.abs(mu.imag) > 1e-8)) else None


def _double(mu: np.ndarray, critical: float) -> bool:
    """Two multipliers at `critical` (+1 or -1): the Jordan block of a strong resonance,
    whose copies split by the square root of rounding (possibly into a complex pair)."""
    mu = np.asarray(mu)
    if mu.size < 2 or not np.all(np.isfinite(mu)):
        return False
    return bool(np.sort(np.abs(mu - critical))[1] < _UNIT_TOL ** 0.5)


def _plane_distance(problem: Codim2Problem, xa: np.ndarray, xb: np.ndarray) -> float:
    (a1, a2), (b1, b2) = problem.plane(xa), problem.plane(xb)
    return float(math.hypot(a1 - b1, a2 - b2))


class _Step:
    """The curve between two accepted points, by the chord coordinate ``s in [0, 1]``.

    A point at ``s`` is the curve's intersection with the hyperplane across the
    chord through ``xa + s (xb - xa)``; its test values are cached.
    """

    def __init__(self, problem: Codim2Problem, xa: np.ndarray, xb: np.ndarray) -> None:
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
                x = self.problem.on_hyperplane(self.xa + sv * self.chord, self.chord)
            orbit = self.problem.orbit(x[:-1], x[-1])
            self._cache[sv] = (x, test_values(self.problem, x, orbit))
            for test in (Label.PD, Label.NS):  # their rounding, for the sides of a pole
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
                                   lambda sv: np.array(self.problem.plane(self.point(sv)[0])),
                                   sroot, 1e-13, lo, hi)
        newton = self.problem.last_step  # the error of the point on the curve itself
        if math.isfinite(newton):
            precision = max(precision, newton)
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
    if test not in _POLE_FREE or Label.ZV not in tests_a or not _changes(tests_a[Label.ZV],
                                                                          tests_b[Label.ZV]):
        return whole
    step.problem.accept(step.xa[:-1], step.xa[-1])
    try:
        s_zv = step.locate(Label.ZV)[0]
    except (ValueError, NewtonConvergenceError):
        return whole
    return parts_beside_poles(f"{step.problem.kind}+{test}",
                              lambda sv: step.value(sv, test),
                              lambda sv: step.noise(sv, test), [s_zv])


def detect_codim2(problem: Codim2Problem, xs: list[np.ndarray], orbits: list[Any],
                  tests: list[dict[Label, float]], found: list[SpecialPoint] | None = None
                  ) -> list[SpecialPoint]:
    """Locate the codim-2 points between consecutive accepted points of a curve.

    Parameters
    ----------
    problem : Codim2Problem
        The curve's problem (N-1 or N-p).
    xs : list of ndarray
        ``[u, lam]`` of the accepted points, in curve order.
    orbits : list of PeriodicOrbit or MultiImpactOrbit
        The motion at each point.
    tests : list of dict
        :func:`test_values` at each point.
    found : list, optional
        Where the points are appended as they are located (the same list is returned):
        a caller interrupted during the location keeps those located before.

    Returns
    -------
    list of Codim2Point
        In curve order.
    """
    found = [] if found is None else found
    arclength = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(np.asarray(
        xs, dtype=float), axis=0), axis=1))]) if len(xs) > 1 else np.zeros(len(xs))
    for k in range(len(xs) - 1):
        found.extend(_without_grazing_twins(
            problem, _codim2_on_step(problem, xs, tests, k, arclength)))
    return found


def _without_grazing_twins(problem: Codim2Problem, points: list[SpecialPoint]
                           ) -> list[SpecialPoint]:
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
            np.array(problem.plane(z.x)))), None)
        if twin is None:
            kept.append(point)
        else:
            log.info("%s at %s is the grazing of the zero-velocity impact %s: reported once",
                     point.label, problem.plane(point.x), twin.label)
    return kept


def _codim2_on_step(problem: Codim2Problem, xs: list[np.ndarray],
                    tests: list[dict[Label, float]], k: int, arclength: np.ndarray
                    ) -> list[SpecialPoint]:
    """The codim-2 points between accepted points `k` and ``k + 1``."""
    found: list[SpecialPoint] = []
    step = _Step(problem, xs[k], xs[k + 1])
    for test in problem.codim2_tests:
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




def _dip_parts(step: _Step, test: str, tests: list[dict[Label, float]], k: int,
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


def _ends_at_resonance(problem: Codim2Problem, test: str, xa: np.ndarray, xb: np.ndarray
                       ) -> bool:
    """Whether `test` (SN: a multiplier +1, PD: -1) vanishes at an end of the step that
    is the curve's own 1:1 or 1:2 end (:meth:`Codim2Problem.end_resonance`)."""
    resonance = _RESONANCE.get(test)
    return resonance is not None and any(problem.end_resonance(x) == resonance
                                         for x in (xa, xb))


def _codim2_in(problem: Codim2Problem, step: _Step, test: str, k: int, lo: float, hi: float,
               ga: float, gb: float) -> SpecialPoint | None:
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
        fraction = ga / (ga - gb) if math.isfinite(ga) and math.isfinite(gb) else 0.5
        sv = lo + fraction * (hi - lo)  # the middle when a test is infinite (no maximum)
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
    p1, p2 = problem.plane(x)
    log.info("%s on the %s curve at %s=%.10g, %s=%.10g (%s)", label, problem.kind,
             problem.parameters[0], p1, problem.parameters[1], p2, status)
    return SpecialPoint.on_curve(label, x, orbit, nearest, precision, status)


def codim2_record(problem: Any, point: SpecialPoint) -> dict[str, Any]:
    """The fields of a codim-2 point as the dataset stores them
    (:func:`impactcont.dataset.curves.codim2_data`): label, the values of ``omega``, ``b``
    and the curve's parameters, the impact phase wrapped to ``[-pi, pi]``, the nearest
    point, the precision, the status, the multipliers (NaN on a ZV curve: G has its
    pole there, eq. 25)."""
    osc = problem.oscillator_of(point.x)
    multipliers = np.asarray(point.orbit.multipliers)
    if not problem.multipliers_defined:
        multipliers = np.full(2 * osc.n, np.nan + 0j)
    record: dict[str, Any] = {
        "label": point.label, "delta": math.remainder(problem.phase(point), 2 * math.pi),
        "point": point.point, "precision": point.precision, "status": point.status,
        "multipliers": multipliers}
    for name in dict.fromkeys(["omega", "b", *problem.parameters]):
        record[name] = problem.parameter_value(osc, name)
    return record

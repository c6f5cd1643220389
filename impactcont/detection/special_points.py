"""Special points on a branch of periodic motions, any motion: detected, then located.

The one detector of every branch problem (:mod:`impactcont.problems.motion`: the N-1
closed form and the shooting system of any N-p motion). Each kind the problem declares
has a test function of the motion (:mod:`impactcont.problems.events`) that changes sign
at the special point; GR and ZV use the minimum over the p flights and impacts, PD and
NS the multipliers of ``G = G_{p-1} .. G_0``:

========  ==========================================  =================================
label     test function                               meaning
========  ==========================================  =================================
``SN``    ``d lam / ds`` (tangent)                    fold: saddle-node, a multiplier +1
``PD``    ``h2 prod_i (mu_i + 1)`` = h2 det(G + I)    a real multiplier through -1
``NS``    ``h2^(m-1) prod_{i<j} (mu_i mu_j - 1)``     a complex pair through ``|mu| = 1``
``GR``    ``gap_min``                                 a stop touched inside a flight
``ZV``    ``impact_velocity``                         impact at zero velocity
``BP``    ``det(H + I)``, ``H = S G_{h-1} .. G_0``    symmetry-breaking pitchfork
``SE``    ``min_k s_k`` (stick times)                 end of a sticking phase
``RG``    smallest pressing force inside the sticks   release grazing
``SO``    smallest pressing force at the landings     sticking onset
``FT``    ``min_k tau_k`` (flight times)              end of a flight
========  ==========================================  =================================

SE, RG and SO are declared by a branch of motions with sticking phases only
(:data:`~impactcont.problems.multi_impact_branch.STICKING_TESTS`); an RG or SO located at
an SE is that SE (:func:`~impactcont.detection.locator.drop_twins`).

A sign change between two accepted points brackets a special point; it is
then located as an event of the core (:func:`impactcont.core.locate_events`:
Brent's method on the branch parametrised by the chord between the two
points). The problem's hooks add what its evaluator knows exactly: the closed form
locates ``SN`` by Newton on its augmented system ``r = dr/d delta = 0``
(``locate_fold``); a fold of a general N-p branch where it meets the branch of symmetric
motions is the ``BP`` it is (``fold_kind``). BP is declared only by a branch of
symmetric motions followed by their half
(:class:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem`). A point whose
location fails is kept as ``bracketed``. The NS test function also vanishes at a
neutral saddle (two real multipliers with product 1); such a point is checked and
discarded. A located point whose test function does not vanish there (a jump, e.g. of
``gap_min`` when the highest interior maximum changes, or from ``+inf`` when a flight
gains one) keeps status ``"bracketed"``.

PD and NS were multiplied free of the pole of G at ``h2 = 0``: their events declare the
impact velocity as their pole quantity, and a step in which it changes sign is split at
its zero (:func:`~impactcont.core.locate.parts_beside_poles`): a sign change across it
is the pole's, not a special point (``docs/engine.md``, *Detection that does not depend
on the step*). Where the branch cannot be followed inside such a step (e.g. where a
flight of a motion with sticking phases shrinks to nothing, its impact velocity through
0 with it) the step cannot be split at the pole, and a PD, NS or fold there that is not
located is not reported (:func:`_through_pole`; the fold SN is the one kind declared
without a test of the motion, its pole quantities :data:`FOLD_POLES`).

The end of a flight (FT, declared by every branch: a flight time through 0) is a singular
point of the shooting system (:attr:`~impactcont.vocabulary.Label.singular`): the chord
Newton cannot reach it, so its zero is interpolated from the branch on both sides
(:func:`_singular_zero`); a ZV, GR, RG or SO only bracketed on its step is that FT
(:func:`~impactcont.detection.locator.drop_twins`), and a sign change not located among
motions past it (a negative flight time at both ends of the step) is no special point
(:func:`_past_singular_bound`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import re
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.locate import Event, MotionTest, locate_events
from impactcont.detection.locator import (
    drop_twins,
    kind_event,
    last_motions,
    watched_labels,
)
from impactcont.detection.points import SpecialPoint
from impactcont.errors import ParameterError
from impactcont.problems.events import (
    BRANCH_TESTS,
    event_function,
    event_noise,
    impact_speeds,
    pole_free,
)
from impactcont.progress import take_interrupt
from impactcont.vocabulary import CODIM2_LABELS, LABELS, Label, check_labels

__all__ = ["LABELS", "BranchSample", "MultiImpactSample", "SpecialPoint", "UserEvent",
           "UserFunctions", "check_user_functions", "detect_special_points", "event_function",
           "event_noise", "locate_sample_events", "locate_user_events", "pole_free", "user_values",
           "without_detected_events"]

log = logging.getLogger(__name__)

_XTOL = 1e-13
_EPS = float(np.finfo(float).eps)


@dataclasses.dataclass(frozen=True, eq=False)
class BranchSample:
    """An accepted branch point as detection sees it: the one sample of every motion.

    Attributes
    ----------
    u : ndarray, shape (m,)
        Unknowns of the problem (``[delta]`` on the closed form's N-1 branch, the
        shooting unknowns of an N-p motion).
    lam : float
        Parameter value.
    tangent : ndarray, shape (m + 1,)
        Unit tangent along the branch order.
    orbit : Motion
        The motion there (:class:`~impactcont.problems.motion.Motion`).
    """

    u: np.ndarray
    lam: float
    tangent: np.ndarray
    orbit: Any

    @property
    def delta(self) -> float:
        """The first unknown: the forcing phase at impact 0."""
        return float(self.u[0])

    @property
    def dlam(self) -> float:
        """Parameter component of the tangent."""
        return float(self.tangent[-1])


#: The sample of an N-p branch: the one sample type.
MultiImpactSample = BranchSample


def detect_special_points(problem: Any, samples: Sequence[BranchSample],
                          labels: Sequence[str] = LABELS,
                          on_found: Callable[[SpecialPoint], None] | None = None,
                          ) -> list[SpecialPoint]:
    """Detect and locate special points between consecutive accepted points, any motion.

    Parameters
    ----------
    problem : BranchProblem
        The branch problem (:class:`~impactcont.problems.motion.BranchProblem`): its
        ``events`` (the kinds it declares) and ``motion_tests`` (their tests), its
        ``orbit(u, lam, checks=...)``; the optional hooks ``locate_fold`` (the closed
        form's exact fold), ``fold_kind`` (a fold that is a pitchfork) and
        ``separate_checks`` (:mod:`impactcont.problems.motion`).
    samples : sequence of BranchSample
        The accepted points in branch order.
    labels : sequence of str
        Which special points to look for (subset of :data:`LABELS`); GR and ZV use the
        minimum over the flights and impacts.
    on_found : callable, optional
        Called with each special point as it is located.

    Returns
    -------
    list of SpecialPoint
        In branch order.

    Notes
    -----
    A kind the problem does not declare (BP on a branch of motions that are not followed
    as symmetric ones) is not searched. The first Ctrl-C of a driver's call
    (:func:`impactcont.progress.interruptible`) during the location keeps the points
    located before it: the one being located is dropped, the rest of the branch is not
    searched, and the call is marked interrupted. With nothing located yet, or a second
    Ctrl-C, the interrupt is raised.
    """
    asked = [Label(label) for label in check_labels(labels, "labels")]
    parameter = getattr(problem, "parameter", "lam")
    declared = getattr(problem, "events", (Label.SN, *BRANCH_TESTS))
    tests: Mapping[str, MotionTest] = getattr(problem, "motion_tests", BRANCH_TESTS)
    watched = [label for label in watched_labels(asked) if label in declared]
    locate_fold = getattr(problem, "locate_fold", None)
    # only some tests (GR) need the (costly) interior-contact search of every flight
    if getattr(problem, "separate_checks", True):
        orbits = {checks: last_motions(lambda u, lam, c=checks: problem.orbit(u, lam, checks=c))
                  for checks in (False, True)}
    else:  # the closed form checks at no cost: one motion per trial point
        orbits = dict.fromkeys((False, True), last_motions(problem.orbit))
    # the kinds whose zeros are singular points of the branch's system: interpolated
    singular = [label for label in watched
                if Label(label).singular and tests.get(label) is not None]
    events = [Event(label, None) if tests.get(label) is None  # the fold: d lam / ds
              else kind_event(label, tests[label], orbits[tests[label].checks],
                              lambda k: samples[k].orbit)
              for label in watched
              if not (label == Label.SN and locate_fold is not None) and label not in singular]
    candidates: list[tuple[int, Label, np.ndarray, float, float, str, bool]] = []
    k = 0
    try:
        if locate_fold is not None and Label.SN in watched:  # the evaluator's exact folds
            for k in range(len(samples) - 1):
                left, right = samples[k], samples[k + 1]
                if (left.dlam > 0) != (right.dlam > 0):
                    candidates.append((k, Label.SN, *locate_fold(left, right)))
        k = -1  # the other kinds, step by step (the core keeps those it located)
        for ep in locate_events(problem, [s.u for s in samples], [s.lam for s in samples],
                                [s.tangent for s in samples], events, s_tol=_XTOL,
                                newton_tol=_XTOL):
            candidates.append((ep.step, Label(ep.label), np.asarray(ep.u, dtype=float),
                               ep.lam, ep.precision, ep.status, ep.failed))
        for label in singular:
            candidates.extend(_singular_points(problem, samples, Label(label), tests[label],
                                               orbits[tests[label].checks]))
    except KeyboardInterrupt:  # the first Ctrl-C of a driver's call: those located are kept
        where = "" if k < 0 else f" the fold between points {k} and {k + 1}"
        if not (candidates and take_interrupt(
                "location", "interrupted by the user (KeyboardInterrupt) while locating%s: "
                "the %d special points located before are kept", where, len(candidates))):
            raise
    order = {label: i for i, label in enumerate(watched)}
    candidates.sort(key=lambda c: (c[0], order[c[1]]))
    found: list[SpecialPoint] = []
    try:
        _classify(problem, samples, candidates, tests, found, orbits[True])
    except KeyboardInterrupt:  # the first Ctrl-C of a driver's call: those built are kept
        if not (found and take_interrupt(
                "location", "interrupted by the user (KeyboardInterrupt) while computing the "
                "motions at the special points: the %d before are kept", len(found))):
            raise
    # a companion watched but not asked (ZV for GR, SE for RG and SO) only tells which
    # points to drop as its twins
    found = [special for special in drop_twins(found, parameter)
             if special.label in asked or special.label not in watched]
    for special in found:
        log.info("%s at %s = %.12g (N=%d, p=%d, %s, precision %.1e)", special.label,
                 parameter, special.value, special.orbit.N, special.orbit.p, special.status,
                 special.precision)
        if on_found is not None:
            on_found(special)
    return found


def _classify(problem: Any, samples: Sequence[BranchSample],
              candidates: Sequence[tuple[int, Label, np.ndarray, float, float, str, bool]],
              tests: Mapping[str, MotionTest], found: list[SpecialPoint],
              orbit_at: Callable[[Any, float], Any] | None = None) -> None:
    """The records of the located zeros that are special points, appended to `found`: the
    motion there, the kind's criticality, the kind of a fold (the problem's ``fold_kind``:
    a fold of a general N-p branch where it meets the symmetric one is the BP it is).

    `orbit_at` is ``problem.orbit`` with its checks, remembering the last motions the
    locator computed (:func:`~impactcont.detection.locator.last_motions`): the motion at a
    located zero is mostly the locator's last."""
    parameter = getattr(problem, "parameter", "lam")
    fold_kind = getattr(problem, "fold_kind", None)
    if orbit_at is None:
        orbit_at = problem.orbit
    for step, label, u, lam, precision, status, failed in candidates:
        orbit = orbit_at(u, lam)
        test = tests.get(label)
        if not failed and test is not None and test.critical is not None \
                and not test.critical(orbit):
            log.debug("the %s test vanishes near %s=%.12g without a critical multiplier "
                      "(a neutral saddle, or the pole of G at h2 = 0)", label, parameter, lam)
            continue
        left, right = samples[step], samples[step + 1]
        if failed and _through_pole(label, test, left.orbit, right.orbit):
            log.info("%s between points %d and %d not located on a step where its test's "
                     "pole quantities change sign too: its sign change cannot be told from "
                     "the pole's, not a special point", label, step, step + 1)
            continue
        past = None if status == "located" else _past_singular_bound(tests, left.orbit,
                                                                      right.orbit)
        if past is not None:
            log.info("%s between points %d and %d not located among motions past the %s "
                     "(its test %s < 0 at both): not a special point of a motion", label,
                     step, step + 1, past.words, past)
            continue
        if label == Label.SN and fold_kind is not None:
            label = fold_kind(orbit, left.orbit, right.orbit)
        nearest = step if abs(lam - left.lam) <= abs(lam - right.lam) else step + 1
        # the closed form's one unknown is the phase; a shooting motion's delta is its own
        found.append(SpecialPoint(label=label, value=lam, u=u, point=nearest,
                                  bracket=(min(left.lam, right.lam), max(left.lam, right.lam)),
                                  precision=precision, status=status, orbit=orbit,
                                  delta=float(u[0]) if u.size == 1 else None))


#: The pole quantities of the fold SN, the one kind declared without a test of the motion
#: (its test is the parameter component of the branch's tangent): the impact velocities,
#: where the branch's system is singular besides its folds (the rate of an impact
#: condition, eq. 22, vanishes with them).
FOLD_POLES: Callable[[Any], Any] = impact_speeds


def _pole_quantities(label: Label, test: MotionTest | None) -> Callable[[Any], Any] | None:
    """The pole quantities of a kind: its test's (:attr:`MotionTest.poles`, None for a test
    without poles), or :data:`FOLD_POLES` for the fold SN, which has no test of the motion.

    Raises
    ------
    ValueError
        A kind other than SN without a test (none is declared so).
    """
    if test is not None:
        return test.poles
    if label is not Label.SN:
        raise ValueError(f"only the fold SN is located without a test of the motion; got "
                         f"{label!r} without one")
    return FOLD_POLES


def _through_pole(label: Label, test: MotionTest | None, left: Any, right: Any) -> bool:
    """Whether a pole quantity of kind `label` (:func:`_pole_quantities`: the impact
    velocities of PD and NS, and of the fold SN, whose `test` is None) changes sign
    between the motions `left` and `right` at a step's ends.

    Where the locator could not follow the branch inside such a step it cannot split the
    step at the pole (:func:`~impactcont.core.locate.parts_beside_poles`): a sign change of
    the test there cannot be told from the pole's, as a zero closer to a pole than where
    the test's sign can be read; a fold there cannot be told from the singularity of the
    branch's system where an impact velocity is 0 (reported as the ZV it is, or as the
    FT where a flight vanishes with it)."""
    poles = _pole_quantities(label, test)
    if poles is None:
        return False
    before = np.asarray(poles(left), dtype=float)
    after = np.asarray(poles(right), dtype=float)
    return bool(np.any(np.signbit(before) != np.signbit(after)))


def _past_singular_bound(tests: Mapping[str, MotionTest], left: Any, right: Any
                         ) -> Label | None:
    """The singular kind (:attr:`~impactcont.vocabulary.Label.singular`: FT) whose test,
    a bound of the physical motions, is negative at both motions `left` and `right` at a
    step's ends, or None.

    Past such a point (a flight of negative duration) the branch's motions are not
    physical, and the other tests (a stick longer than the period, its pressing force)
    jump among them: a sign change there that is not located is no special point."""
    for label, test in tests.items():
        kind = Label.__members__.get(str(label))  # a plugin's own kinds are none of these
        if kind is not None and kind.singular and kind.bounds and test.test(left) < 0.0 \
                and test.test(right) < 0.0:
            return kind
    return None


#: A chord point is a node of the interpolation at a singular point when its Newton's last
#: step is at most this (relative): the system's conditioning there grows as the cube of
#: the distance to the point, so Newton stalls at that level of rounding.
_NODE_STEP = 1e-9
#: Chord points tried on each side of a singular point, halving the distance to it.
_NODE_HALVINGS = 8
#: Nodes needed on each side.
_NODES_PER_SIDE = 2


Candidate = tuple[int, Label, np.ndarray, float, float, str, bool]


def _singular_points(problem: Any, samples: Sequence[BranchSample], label: Label,
                     test: MotionTest, orbit_at: Callable[[Any, float], Any]
                     ) -> list[Candidate]:
    """The zeros of the test of a kind whose zeros are singular points of the branch's
    system (:attr:`~impactcont.vocabulary.Label.singular`, FT), as candidates.

    On each step where the test changes sign between accepted points (beyond its rounding
    at both) the zero is interpolated from the branch on both sides
    (:func:`_singular_zero`); where too few branch points are reached for that, it is
    located on the chord as any kind's (:func:`~impactcont.core.locate_events` on that step,
    ``bracketed`` where that fails too). A test dipping through 0 and back inside one step
    is not searched (a flight time does not).
    """
    values = [test.test(sample.orbit) for sample in samples]
    found: list[Candidate] = []
    for k in range(len(samples) - 1):
        a, b = values[k], values[k + 1]
        if math.isnan(a) or math.isnan(b) or (a < 0.0) == (b < 0.0):
            continue
        if test.noise is not None and abs(a) <= test.noise(samples[k].orbit) \
                and abs(b) <= test.noise(samples[k + 1].orbit):
            continue  # a sign change by rounding only
        zero = _singular_zero(problem, test, samples[k], samples[k + 1])
        if zero is not None:
            x, precision = zero
            log.debug("%s between points %d and %d interpolated at %s=%.15g (precision "
                      "%.1e)", label, k, k + 1, getattr(problem, "parameter", "lam"), x[-1],
                      precision)
            found.append((k, label, x[:-1], float(x[-1]), precision, "located", False))
            continue
        pair = samples[k:k + 2]
        event = kind_event(label, test, orbit_at, lambda j, pair=pair: pair[j].orbit)
        for ep in locate_events(problem, [s.u for s in pair], [s.lam for s in pair],
                                [s.tangent for s in pair], [event], s_tol=_XTOL,
                                newton_tol=_XTOL):
            found.append((k + ep.step, label, np.asarray(ep.u, dtype=float), ep.lam,
                          ep.precision, ep.status, ep.failed))
    return found


def _singular_zero(problem: Any, test: MotionTest, left: BranchSample, right: BranchSample
                   ) -> tuple[np.ndarray, float] | None:
    """The zero of `test` between two accepted points where it is a singular point of the
    branch's system: ``(x = [u, lam], precision)``, or None with too few nodes.

    At the end of a flight (FT) the shooting system is singular: the impact condition of a
    flight of length ``tau`` is of order ``tau^3`` (the smallest singular value of
    ``[dF/du | dF/dlam]`` shrinks so), and Newton on the chord's hyperplanes stalls near
    it. The branch itself is smooth there and the test (a flight time) a regular
    coordinate of it: the branch points on the chord are found on both sides, halving the
    distance to the test's linear zero while Newton reaches them (last step at most
    :data:`_NODE_STEP`), and ``x`` is the polynomial through them as a function of the
    test, at 0. The precision is twice the largest change of ``lam`` when the nodes
    farthest from the zero are left out one by one (down to three nodes).
    """
    x0 = np.append(left.u, left.lam)
    x1 = np.append(right.u, right.lam)
    chord = x1 - x0
    g0, g1 = test.test(left.orbit), test.test(right.orbit)
    if not (math.isfinite(g0) and math.isfinite(g1)) or g0 == g1:
        return None
    s_zero = g0 / (g0 - g1)
    nodes = [(g0, x0), (g1, x1)]
    for towards in (0.0, 1.0):
        reached = 0
        for j in range(1, _NODE_HALVINGS + 1):
            s = s_zero + (towards - s_zero) * 2.0 ** -j
            try:
                found = solve_on_hyperplane(problem, x0 + s * chord, chord, tol=_XTOL)
            except (ValueError, ArithmeticError, np.linalg.LinAlgError):
                break
            if not (found.converged or found.last_step
                    <= _NODE_STEP * max(1.0, float(np.max(np.abs(found.x))))):
                break
            value = test.test(problem.orbit(found.u, found.lam, checks=test.checks))
            if not math.isfinite(value):
                break
            nodes.append((value, found.x))
            reached += 1
        if reached + 1 < _NODES_PER_SIDE:
            return None
    values = np.array([g for g, _ in nodes])
    points = np.array([x for _, x in nodes])
    nearest = np.argsort(np.abs(values), kind="stable")
    size = float(np.max(np.abs(values)))
    estimates = [_polynomial_at_zero(values[nearest[:n]] / size, points[nearest[:n]])
                 for n in range(len(nodes), 2, -1)]
    x = estimates[0]
    spread = max(abs(float(e[-1]) - float(x[-1])) for e in estimates)
    return x, 2.0 * spread + 4.0 * _EPS * max(1.0, abs(float(x[-1])))


def _polynomial_at_zero(values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The polynomial through ``(values[i], points[i])`` (one per component) at 0."""
    return np.linalg.solve(np.vander(values, values.size), points)[-1]


# -- user-defined events and monitors ----------------------------------------------------------
#: A user event's or monitor's name: a letter, then letters, digits or underscores.
_USER_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclasses.dataclass(frozen=True, eq=False)
class UserFunctions:
    """The user's events and monitors of one run, checked (:func:`check_user_functions`).

    Attributes
    ----------
    events : dict of str to callable
        ``name -> f(orbit) -> float``: the zeros of ``f`` along the branch or curve are
        located and stored as events; ``f`` is stored at every point as a monitor too.
    monitors : dict of str to callable
        ``name -> f(orbit) -> float``: evaluated and stored at every point.
    """

    events: dict[str, Callable[[Any], float]]
    monitors: dict[str, Callable[[Any], float]]

    @property
    def functions(self) -> dict[str, Callable[[Any], float]]:
        """Every function by name (events first): each is stored at every point."""
        return {**self.events, **self.monitors}

    def __bool__(self) -> bool:
        return bool(self.events or self.monitors)


def _check_mapping(what: str, value: Any) -> dict[str, Callable[[Any], float]]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise TypeError(f"{what} must be a mapping of name to function of the motion, e.g. "
                        f"{{'x2max': lambda orbit: max_displacement(orbit, 2) - 0.3}}; got "
                        f"{type(value).__name__}")
    out = {}
    for name, fn in value.items():
        if not isinstance(name, str) or not _USER_NAME.match(name):
            raise ParameterError(f"{what}: a name must be a letter followed by letters, digits "
                                 f"or underscores (it names dataset variables); got {name!r}")
        if not callable(fn):
            raise TypeError(f"{what}[{name!r}] must be a function of the motion returning a "
                            f"real number; got {type(fn).__name__}")
        out[name] = fn
    return out


def check_user_functions(events: Any = None, monitors: Any = None,
                         reserved: Iterable[str] = ()) -> UserFunctions:
    """Check a driver's ``events=`` and ``monitors=`` arguments.

    Parameters
    ----------
    events, monitors : mapping of str to callable, optional
        ``name -> f(orbit)``; ``f`` receives the motion at a point (a
        :class:`~impactcont.PeriodicOrbit` on N-1 branches and curves, a
        :class:`~impactcont.MultiImpactOrbit` on N-p ones) and returns a real number.
    reserved : iterable of str
        Names of the built-in dataset variables, refused as names.

    Returns
    -------
    UserFunctions

    Raises
    ------
    TypeError
        Not a mapping, or a value that is not callable.
    ParameterError
        A name that is not an identifier, that names a special-point label (any case:
        ``SN``, ``PD``, ..., ``R1``, ``R2``) or a built-in variable, or that is both an
        event and a monitor.
    """
    checked = UserFunctions(_check_mapping("events", events), _check_mapping("monitors", monitors))
    taken = set(reserved)
    for what, table in (("events", checked.events), ("monitors", checked.monitors)):
        for name in table:
            if name.upper() in (*LABELS, *CODIM2_LABELS):
                raise ParameterError(f"{what}: the name {name!r} is a special-point label "
                                     f"({', '.join(LABELS)}, or a codim-2 one: R1, R2; any "
                                     "case); choose another name")
            if name in taken:
                raise ParameterError(f"{what}: the name {name!r} is a built-in variable of the "
                                     "dataset; choose another name")
    both = sorted(set(checked.events) & set(checked.monitors))
    if both:
        raise ParameterError(f"events and monitors share the name(s) {both}: an event is "
                             "stored as a monitor too; give each name once")
    return checked


def without_detected_events(functions: UserFunctions | None, problem: Any,
                            labels: Sequence[str]) -> UserFunctions | None:
    """`functions` without the events that are the test of a kind `problem` detects.

    An event whose function is the very test function of a kind the problem declares
    (its ``motion_tests``) and `labels` asks for (e.g.
    :data:`~impactcont.problems.multi_impact_branch.STICKING_EVENTS` on a branch of
    motions with sticking phases: ``SE``, ``RG``, ``SO``) would locate each of those
    points twice, as a special point and as a user event: it is kept as a monitor (its
    values at every point are stored) and its zeros are the special points. A
    ``DeprecationWarning`` names the events and the labels.

    Parameters
    ----------
    functions : UserFunctions or None
        The user's checked events and monitors (:func:`check_user_functions`).
    problem : BranchProblem
        The branch problem (its ``motion_tests``).
    labels : sequence of str
        The kinds detected on the branch (the driver's ``detect``).

    Returns
    -------
    UserFunctions or None
        `functions` itself when no event duplicates a detected kind.
    """
    if not functions:
        return functions
    tests: Mapping[str, MotionTest] = getattr(problem, "motion_tests", BRANCH_TESTS)
    asked = {str(label) for label in labels}
    by_test = {id(test.test): str(label) for label, test in tests.items()
               if str(label) in asked}
    dropped = {name: by_test[id(fn)] for name, fn in functions.events.items()
               if id(fn) in by_test}
    if not dropped:
        return functions
    warnings.warn(
        f"events {sorted(dropped)} are the tests of the special points "
        f"{sorted(set(dropped.values()))} ({dropped}), which this branch locates itself "
        "(the dataset's special points): they are kept as monitors only; passing them as "
        "events (STICKING_EVENTS) is deprecated, leave events= out", DeprecationWarning,
        stacklevel=2)
    events = {name: fn for name, fn in functions.events.items() if name not in dropped}
    monitors = {**{name: functions.events[name] for name in dropped}, **functions.monitors}
    return UserFunctions(events, monitors)


class _UserFunctionFailure(Exception):  # noqa: N818 - carries the error to raise
    """A user function failed inside the locator (which would keep the point as bracketed)."""

    def __init__(self, error: Exception) -> None:
        super().__init__(str(error))
        self.error = error


def _where(orbit: Any, parameter: str | None) -> str:
    osc = orbit.oscillator
    names = dict.fromkeys(["omega", "b", *([parameter] if parameter else [])])
    return ", ".join(f"{k}={float(getattr(osc, k) or 0.0):.10g}" for k in names)


def user_value(name: str, fn: Callable[[Any], float], orbit: Any,
               parameter: str | None = None) -> float:
    """``fn(orbit)`` as a float, or a clear error naming the event or monitor.

    Raises
    ------
    ParameterError
        `fn` raised (chained), or returned a value that is not finite.
    TypeError
        `fn` returned something else than a real scalar.
    """
    try:
        value = fn(orbit)
    except Exception as exc:  # a user function: any failure, named with where it happened
        raise ParameterError(f"event or monitor {name!r} raised {type(exc).__name__}: {exc} "
                             f"(at {_where(orbit, parameter)})") from exc
    array = np.asarray(value)
    if array.ndim != 0 or array.dtype.kind not in "iuf" or isinstance(value, bool):
        raise TypeError(f"event or monitor {name!r} must return a real number; got {value!r} "
                        f"(at {_where(orbit, parameter)})")
    result = float(array)
    if not math.isfinite(result):
        raise ParameterError(f"event or monitor {name!r} must return a finite number; got "
                             f"{result!r} (at {_where(orbit, parameter)})")
    return result


def user_values(functions: UserFunctions, orbits: Sequence[Any],
                parameter: str | None = None) -> dict[str, np.ndarray]:
    """Every event and monitor function at every point: ``name -> values``, shape (npoints,).

    Raises
    ------
    ParameterError, TypeError
        As :func:`user_value`.
    """
    return {name: np.array([user_value(name, fn, orbit, parameter) for orbit in orbits],
                           dtype=float)
            for name, fn in functions.functions.items()}


#: A located zero of a user event's function: the one special-point record, its ``name``
#: the event's (:class:`~impactcont.detection.points.SpecialPoint`).
UserEvent = SpecialPoint


def locate_user_events(problem: Any, u: Any, lam: Any, tangent: Any, functions: UserFunctions,
                       values: Mapping[str, np.ndarray], orbit_at: Callable[[Any, float], Any],
                       *, position: Callable[[Any, float], Any] | None = None,
                       accept: Callable[[int], None] | None = None,
                       parameter: str | None = None) -> list[UserEvent]:
    """Locate the zeros of the user's event functions between consecutive accepted points.

    As the built-in events (:func:`~impactcont.core.locate_events`, the same locator:
    Brent's method on the branch parametrised by the chord of each step), with the
    precision and status it reports.

    Parameters
    ----------
    problem : Problem
        The problem followed (a branch's or a curve's augmented system).
    u, lam, tangent : array_like
        The accepted points in order (as for :func:`~impactcont.core.locate_events`).
    functions : UserFunctions
    values : mapping of str to ndarray
        :func:`user_values` at the accepted points.
    orbit_at : callable
        ``orbit_at(u, lam)``: the motion at a point of the problem.
    position : callable, optional
        ``position(u, lam)``: where a point is (both parameters of a curve); default
        ``lam``.
    accept : callable, optional
        ``accept(k)``: called before a step from point ``k`` is searched (a curve renews
        the borders of its augmented system there), on the searched steps only.
    parameter : str, optional
        The continued parameter, named in error messages.

    Returns
    -------
    list of UserEvent
        By step, then in the order of ``functions.events``.

    Raises
    ------
    ParameterError, TypeError
        An event function failed at a point the locator tried (:func:`user_value`).
    """
    u = np.asarray(u, dtype=float)
    lam = np.asarray(lam, dtype=float)
    tangent = np.asarray(tangent, dtype=float)
    where = position if position is not None else (lambda _u, lam_: lam_)
    events = [Event(name, _user_test(name, fn, orbit_at, parameter),
                    lambda j, v=values[name]: float(v[j]))
              for name, fn in functions.events.items()]
    try:  # every step, also where a function dips through zero and back inside one
        located = locate_events(problem, u, lam, tangent, events, s_tol=_XTOL,
                                position=position, before_step=accept)
    except _UserFunctionFailure as failure:
        raise failure.error from failure.error.__cause__
    found: list[UserEvent] = []
    for ep in located:
        k = ep.step
        ends = [np.asarray(where(u[j], lam[j]), dtype=float) for j in (k, k + 1)]
        here = np.asarray(where(ep.u, ep.lam), dtype=float)
        nearest = k if (np.max(np.abs(here - ends[0])) <= np.max(np.abs(here - ends[1]))) \
            else k + 1
        orbit = orbit_at(ep.u, ep.lam)
        # on a curve (two parameters) an event's zero is a point of codimension two
        event = SpecialPoint(label=ep.label, value=ep.lam, u=ep.u, point=nearest,
                             bracket=ep.bracket, precision=ep.precision, status=ep.status,
                             orbit=orbit, codimension=1 if position is None else 2)
        log.info("event %s at %s (%s, precision %.1e)", event.name,
                 _where(orbit, parameter), event.status, event.precision)
        found.append(event)
    return found


def _user_test(name: str, fn: Callable[[Any], float], orbit_at: Callable[[Any, float], Any],
               parameter: str | None) -> Callable[[np.ndarray, float], float]:
    def test(u: np.ndarray, lam: float) -> float:
        orbit = orbit_at(u, lam)
        try:
            return user_value(name, fn, orbit, parameter)
        except (ParameterError, TypeError) as exc:  # past the locator's own error handling
            raise _UserFunctionFailure(exc) from exc
    return test


def locate_sample_events(problem: Any, samples: Sequence[BranchSample],
                         functions: UserFunctions | None, *,
                         position: Callable[[np.ndarray, float], Any] | None = None
                         ) -> tuple[dict[str, np.ndarray], list[UserEvent]]:
    """The user's functions at every sample and the zeros of its events, located.

    :func:`locate_user_events` on a branch (or a curve: `position` gives both parameters
    of a point) of any motion: the functions receive the motion at a point
    (``problem.orbit(u, lam)``, with its contact checks; the full motion on a branch of
    symmetric motions followed by their half).

    Returns
    -------
    values : dict of str to ndarray
        Each function at every sample (empty without `functions`).
    events : list of UserEvent
        In branch order.
    """
    if not functions:
        return {}, []
    parameter = getattr(problem, "parameter", None)
    values = user_values(functions, [s.orbit for s in samples], parameter)
    events = locate_user_events(problem, [s.u for s in samples], [s.lam for s in samples],
                                [s.tangent for s in samples], functions, values,
                                lambda u, lam: problem.orbit(u, lam), position=position,
                                parameter=parameter)
    return values, events

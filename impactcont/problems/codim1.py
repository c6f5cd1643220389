"""Codim-1 curves of every motion: the motion's branch problem augmented by one test function.

A special point of a branch (:func:`impactcont.continuation` of an N-1 motion,
:func:`impactcont.multi_impact_continuation` of any N-p motion, a switched branch) is a
zero of a scalar test function ``g`` of the motion, the test of its kind
(:mod:`impactcont.problems.events`, :class:`~impactcont.vocabulary.Label`). Followed in
two parameters ``(p1, p2)`` it is the curve

    F(u, p1; p2) = 0,      g(u, p1; p2) = 0

in the unknowns ``x = [u, p1]`` with ``p2`` the continuation parameter of the core: the
branch problem of the motion augmented by one equation (a minimally augmented system).
:func:`curve_problem` builds it with one of two evaluators:

- **the closed form** (:mod:`impactcont.problems.closed_form_curve`), where the motion is
  N-1 on the paper's one stop: eq. (12)-(15) in the unknowns ``u = [p1, delta, extras]``
  with the kind's condition in closed form (exact derivatives), the fast path and the
  oracle of the tests;
- **shooting** (:class:`ShootingCurve`), for every motion: the branch problem
  (:class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem`, or
  :class:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem` for a symmetric
  motion) with ``g`` of the table below.

Both provide what the driver (:func:`impactcont.analysis.curves.curve`) and the location of
codim-2 points (:class:`~impactcont.detection.codim2.Codim2Problem`) read: the core's
``residual``, ``jacobian``, ``dparam`` and ``accept``, ``plane``, ``on_hyperplane``,
``orbit``, ``codim2_tests`` and ``codim2_test`` (shooting also the core's one-call
``linearize``: the three from one evaluation of the branch problem).

========  ========================================================  ===================
kind      g (shooting)                                              vanishes where
========  ========================================================  ===================
``SN``    ``sigma(dF/du)``                                          the branch folds
``PD``    ``sigma(G + I)``                                          G has -1
``BP``    ``sigma(H + I)``, ``H`` the half-map (symmetric motions)  H has -1
``NS``    ``prod_{i<j} (mu_i mu_j - 1)``, pole-free                 a pair crosses |mu|=1
``GR``    ``min_k gap_min_k``                                        a stop is grazed
``ZV``    ``min_k impact_velocity_k``                                an impact at rest
``SE``    ``s_k``, the stick time of one sticking phase k            a stick shrinks to 0
``RG``    ``p_k(t*)``, the pressing force at one interior minimum    it touches 0 inside
          ``t*`` of stick k (``p_k'(t*) = 0``, solved afresh)          the stick
``SO``    ``p_k(0)``, the pressing force at the landing of stick k   the landing presses 0
========  ========================================================  ===================

The last three are the kinds that bound periodic motions with sticking phases (a
pattern with lowercase letters, :class:`~impactcont.problems.multi_impact_branch.
MultiImpactBranchProblem`); they have curves of such motions only. Each follows one
sticking phase k, chosen at the start (the shortest stick, the stick with the smallest
interior minimum of its pressing force, the smallest landing pressing force): a minimum
over the sticks would have corners where two sticks change places, and on a curve of the
symmetric riding motion every stick has the same value. ``g`` is then smooth along the
curve: ``s_k`` is an unknown (its row is exact, no difference); ``p_k(0)`` is affine in
the landing state; at an interior minimum ``t*`` (a regular zero of ``p_k'``, found by
secant steps from the last accepted point's ``t*``) ``p_k(t*)`` is smooth with the
derivative of ``p_k`` at fixed ``t*`` (``p_k'(t*) = 0``), and its error is of the order
of the square of ``t*``'s (1e-13 relative), not that of a sampled minimum. The RG curve
ends where that minimum leaves the sticking phase (``t*`` reaches its landing or its
release) or stops being a minimum (``p_k'' = 0``). The kinds of every motion (SN, PD,
NS, GR, ZV) are followed on motions with sticking phases as on the others; their
derivative in ``p2`` is then the problem in ``p2``'s (:meth:`ShootingCurve.dparam`).

``sigma(A)`` is the signed smallest singular value ``sign(det A) s_min(A)``: it
changes sign with ``det A`` and, unlike the determinant, keeps the size of the
distance to the singular matrices (a regular zero where ``s_min`` is simple, as a
minimally augmented system's bordered test). The BP test and its row take both factors
and the singular vectors from one compiled SVD
(:func:`~impactcont.kernel.half_map.smallest_singular_value`: the full SVD's ``s_min``,
which differs from that of numpy's ``svd(A, compute_uv=False)`` in the last bit at most).
``dF/du`` and ``dF/dp1``, ``dF/dp2`` are the branch problems' own (exact for omega, b,
R); the row of ``g`` is a forward difference (relative step 1.5e-8, about the square root
of eps), the one finite difference of the curve: it steers Newton and the tangent only,
the points solve ``g = 0`` exactly. The BP row is exact in the unknowns and in a
parameter that moves the stops (``d sigma = sign(det(H + I)) a^T dH b`` with the singular
vectors of ``s_min`` and ``dH`` from the shot,
:meth:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem.half_map_derivative`:
one evaluation instead of one shot per unknown), and in omega as
``p1``; by forward differences in the others (R, omega as ``p2``). The row is taken
afresh at every step and reused only within that step's Newton corrections, so that the
tangent follows the curve round a fold in ``p2``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.stepper import NewtonConvergenceError
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import FREQUENCY, GAP, RESTITUTION, model_parameter
from impactcont.orbit.held_flow import held_flow
from impactcont.orbit.multi_impact import MultiImpactOrbit, _geometry
from impactcont.orbit.symmetry import half_map
from impactcont.problems.closed_form_curve import (
    CURVE_PARAMETERS,
    CurveProblem,
    FoldCurve,
    GrazingCurve,
    NeimarkSackerCurve,
    PeriodDoublingCurve,
    ZeroVelocityCurve,
    check_parameters,
    closed_form_curve,
)
from impactcont.problems.events import event_function
from impactcont.problems.multi_impact_branch import (
    MultiImpactBranchProblem,
    release_grazing_test,
    stick_end_test,
    sticking_onset_test,
)
from impactcont.problems.symmetric_branch import SymmetricBranchProblem
from impactcont.vocabulary import CURVE_KINDS, Label

__all__ = [
    "CURVE_KINDS",
    "CURVE_PARAMETERS",
    "SHOOTING_KINDS",
    "STICKING_CURVE_KINDS",
    "CurveProblem",
    "FoldCurve",
    "GrazingCurve",
    "MultiImpactCurveProblem",
    "NeimarkSackerCurve",
    "PeriodDoublingCurve",
    "ShootingCurve",
    "ZeroVelocityCurve",
    "check_parameters",
    "curve_kind",
    "curve_problem",
    "signed_smallest_singular_value",
]

_FD_STEP = 1.5e-8  # about sqrt(eps): forward differences
_CACHE_SIZE = 32
_REUSE = 1e-3
#: Points on each side of a curve's start where :meth:`ShootingCurve.test_noise` takes ``g``.
NOISE_STEPS = 4
#: A curve's default Newton tolerance is at least this many times its test's noise.
NOISE_MARGIN = 4.0
_HYPERPLANE_TOL = 1e-11  # Newton on a hyperplane (codim-2 points, crossings, the start)
#: Flight data whose parameters have exact derivatives from any branch problem's shot
#: and leave the modal basis as it is.
_EXACT = (FREQUENCY, GAP, RESTITUTION)
#: The interior minimum of a pressing force (RG): secant steps until this relative step,
#: at most this many; ``p_k''`` by this relative central difference of ``p_k'``.
_MINIMUM_TOL = 1e-13
_MINIMUM_ITER = 40
_CURVATURE_STEP = 1e-5

BranchProblem = MultiImpactBranchProblem | SymmetricBranchProblem


def _approach_sign(problem: MultiImpactBranchProblem, u: np.ndarray, lam: float) -> float:
    """The sign of the product of the p impact velocities ``h2_k`` at the shot of `u`.

    G (eq. 25) has a pole ``a_k b_k^T / h2_k`` at each: ``det(G + I)`` changes sign
    through a zero-velocity impact without a multiplier at -1, while ``s_min(G + I)``
    stays finite and continuous there (a rank-one term growing without bound leaves the
    smallest singular value to the complement). ``sign(prod h2_k) sigma(G + I)`` is then
    continuous through it and vanishes only at a period doubling, as the pole-free
    products of :func:`~impactcont.problems.events.pole_free`: a PD curve passes a
    zero-velocity impact (the codim-2 point PD+ZV) as an N-1 curve does.
    """
    sh = problem.shot(u, lam)
    # with sticking phases the stops are the pattern's letters in capitals
    geo = _geometry(problem.flow_at(lam), getattr(problem, "impacts", problem.pattern))
    n = geo.normals.shape[1]
    # the impact ending flight k - 1 begins flight k: its velocity towards the stop
    arrivals = sh.arrivals[np.arange(-1, problem.p - 1), n:]
    speeds = np.einsum("ki,ki->k", arrivals, geo.normals) * geo.signs
    return float(np.sign(np.prod(speeds))) or 1.0


def signed_smallest_singular_value(matrix: np.ndarray) -> float:
    """``sign(det A) s_min(A)``: a smooth test for the singularity of ``A`` (NaN if not finite)."""
    if not np.isfinite(matrix).all():
        return math.nan
    s = np.linalg.svd(matrix, compute_uv=False)
    sign, _ = np.linalg.slogdet(matrix)
    return float(sign * s[-1])


def _pitchfork_factors(H: np.ndarray) -> tuple[float, float, np.ndarray, np.ndarray]:
    """``sign(det(H + I))``, ``s_min(H + I)`` and the left and right singular vectors of
    ``s_min``: the BP test ``sigma(H + I)`` and what its exact row needs, from one compiled
    SVD (:func:`impactcont.kernel.half_map.smallest_singular_value`; NaN if ``H`` is not
    finite)."""
    from impactcont.kernel.half_map import smallest_singular_value  # numba on first use

    m = H.shape[0]
    left, right = np.empty(m), np.empty(m)
    sign, smallest = smallest_singular_value(H + _identity(m), left, right)
    return float(sign), float(smallest), left, right


class ShootingCurve:
    """A codim-1 curve of any motion by shooting, in ``(p1, p2)``: ``x = [u, p1]``, ``lam = p2``.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator (other parameters fixed at its values).
    N, p : int
        The motion's forcing periods and impacts.
    pattern : str
        The stop of each impact.
    kind : str
        One of ``SN, PD, NS, GR, ZV, BP, SE, RG, SO`` (see the module notes).
    parameters : (str, str)
        ``(p1, p2)``: ``p1`` is an unknown, ``p2`` the continuation parameter.
    symmetric : bool
        Follow symmetric motions by their half (needed for BP).

    Raises
    ------
    ParameterError
        An unknown kind, equal or unknown parameters, BP without ``symmetric``; SE, RG or
        SO of a motion without sticking phases; a motion with sticking phases followed by
        its half.
    """

    def __init__(self, osc: ImpactOscillator, N: int, p: int, pattern: str, kind: str,
                 parameters: tuple[str, str], *, symmetric: bool) -> None:
        kind = curve_kind(kind, kinds=tuple(_KINDS))
        if _KINDS[kind].symmetric_only and not symmetric:
            raise ParameterError(f"kind={str(kind)!r} is a curve of symmetric motions: the "
                                 "branch must be a branch of symmetric motions "
                                 "(symmetric=True)")
        p1, p2 = parameters
        if p1 == p2:
            raise ParameterError(f"parameters must be two different parameters; got {p1!r} "
                                 "twice")
        self.params = tuple(model_parameter(osc, name) for name in (p1, p2))
        self.osc, self.N, self.p, self.pattern = osc, N, p, pattern
        #: The motion has sticking phases (a pattern with lowercase letters).
        self.sticky = bool(pattern) and any(c.islower() for c in str(pattern))
        if _KINDS[kind].sticky_only and not self.sticky:
            raise ParameterError(
                f"kind={str(kind)!r} ({Label(kind).words}) bounds motions with sticking "
                f"phases: the motion must have some (a pattern with lowercase letters); got "
                f"pattern={pattern!r}")
        if self.sticky and symmetric:
            raise ParameterError(f"symmetric=True: a motion with sticking phases (pattern "
                                 f"{pattern!r}) is followed whole, not by its half")
        #: The sticking phase a curve of SE, RG or SO follows (its impact), and the time of
        #: the interior minimum of its pressing force at the last accepted point (RG).
        self.followed_stick: int | None = None
        #: RG: why the followed interior minimum was lost at a point tried since the last
        #: accepted one ("" if it was not): the reason a curve that cannot go on ends.
        self.lost_minimum = ""
        self._minimum_time = math.nan
        self._minima: dict[tuple[bytes, float], float] = {}
        self.kind, self.parameters, self.symmetric = Label(kind), (p1, p2), symmetric
        self.last_step = math.nan
        self._problems: dict[tuple[str, float, float | None], BranchProblem] = {}
        self._first: dict[str, BranchProblem] = {}  # the first problem in each parameter
        self._tests: dict[tuple[bytes, float], float] = {}
        # both parameters move only omega and the stops: every problem has the same modes
        self._same_modes = all(par.data in _EXACT for par in self.params)
        self._gradient: tuple[np.ndarray, tuple[np.ndarray, float]] | None = None
        #: The last :meth:`linearize`: its point's key, the test row it reused or took
        #: (:attr:`_gradient`), the residual and the matrix.
        self._linearization: tuple[tuple[bytes, float], Any, np.ndarray, np.ndarray] | None = \
            None
        self._directions: tuple[list[int], tuple[np.ndarray, np.ndarray, np.ndarray]] | None \
            = None  # BP: the exact row's directions (:meth:`_pitchfork_directions`)
        first = self._base(self.params[1].value(osc), p1)
        self.size = first.size + 1
        #: BP: the test row from the shot (exact in the unknowns and the stops' positions),
        #: where the problem in p1 has it (p1 = omega on a modal flow)
        self._exact_pitchfork = bool(symmetric and first.full._base_flow is not None)
        self._sticks = np.flatnonzero(getattr(first, "sticks", np.zeros(0, bool)))

    # -- the branch problems ----------------------------------------------------------------------
    def _base(self, lam: float, parameter: str, p1: float | None = None) -> BranchProblem:
        """The branch problem in `parameter` of the oscillator with ``p2 = lam`` (and p1)."""
        key = (parameter, float(lam), None if p1 is None else float(p1))
        problem = self._problems.get(key)
        if problem is None:
            if len(self._problems) > _CACHE_SIZE:
                self._problems.clear()
            osc = self.params[1].at(self.osc, float(lam))
            if p1 is not None:
                osc = self.params[0].at(osc, float(p1))
            first = self._first.get(parameter)
            if first is None or not self._same_modes:
                cls = SymmetricBranchProblem if self.symmetric else MultiImpactBranchProblem
                problem = cls(osc, self.N, self.p, parameter, pattern=self.pattern)
                self._first.setdefault(parameter, problem)
            else:  # the first one moved: the same modes, flow and checks
                problem = first.moved(osc)
            self._problems[key] = problem
        return problem

    def branch_problem(self, lam: float) -> BranchProblem:
        """The branch problem in ``p1`` at ``p2 = lam`` (its unknowns are ``x[:-1]``)."""
        return self._base(lam, self.parameters[0])

    def orbit(self, x: np.ndarray, lam: float, *, checks: bool = True) -> MultiImpactOrbit:
        """The N-p motion at the curve point ``(x, lam)``."""
        x = np.asarray(x, dtype=float)
        return self.branch_problem(lam).orbit(x[:-1], float(x[-1]), checks=checks)

    # -- the test function ----------------------------------------------------------------------
    def test(self, x: np.ndarray, lam: float) -> float:
        """``g(u, p1; p2)`` of the curve's kind (module notes).

        The last few values are kept: the residual and the test row of one Newton iterate
        take ``g`` at the same point.
        """
        x = np.asarray(x, dtype=float)
        key = (x.tobytes(), float(lam))
        value = self._tests.get(key)
        if value is None:
            if len(self._tests) > _CACHE_SIZE:
                self._tests.clear()
            value = self._tests[key] = self._test(x, lam)
        return value

    def _test(self, x: np.ndarray, lam: float) -> float:
        kind = _KINDS[self.kind]
        if kind.from_shot is not None:  # from the shot: no multipliers, no orbit
            return kind.from_shot(self, x[:-1], float(x[-1]), lam)
        return self.test_of(self.orbit(x, lam, checks=kind.contact_checks))

    def _fold_of_shot(self, u: np.ndarray, p1: float, lam: float) -> float:
        """SN: ``sigma(dF/du)`` of the branch problem."""
        return signed_smallest_singular_value(self.branch_problem(lam).jacobian(u, p1))

    def _flip_of_shot(self, u: np.ndarray, p1: float, lam: float) -> float:
        """PD: ``sign(prod h2_k) sigma(G + I)`` (:func:`_approach_sign`)."""
        base = self.branch_problem(lam)
        full = base.full if self.symmetric else base
        v = base.full_unknowns(u, p1) if self.symmetric else u
        G = full.jacobian_product(v, p1, self.p)
        return _approach_sign(full, v, p1) * signed_smallest_singular_value(
            G + _identity(G.shape[0]))

    def _pitchfork_of_shot(self, u: np.ndarray, p1: float, lam: float) -> float:
        """BP: ``sigma(H + I)`` of the half-map (:func:`_pitchfork_factors`)."""
        sign, smallest, _, _ = _pitchfork_factors(self.branch_problem(lam).half_map(u, p1))
        return sign * smallest

    # -- the kinds that bound motions with sticking phases --------------------------------------
    def _stick_column(self, k: int) -> int:
        """Where the stick time ``s_k`` of impact `k` is in ``x = [u, p1]``: after the phase
        and the p - 1 flight times, in the order of the sticking phases
        (:func:`~impactcont.orbit.multi_impact.sticky_shooting`)."""
        return self.p + int(np.flatnonzero(self._sticks == k)[0])

    def _follow(self, u: np.ndarray, p1: float, lam: float) -> int:
        """The sticking phase this curve follows, chosen at its first evaluation (the start):
        the shortest stick (SE), the smallest landing pressing force (SO), the smallest
        interior minimum of the pressing force (RG, with its time).

        Raises
        ------
        ParameterError
            RG at a motion whose pressing forces have no interior minimum.
        """
        if self.followed_stick is None:
            base = self.branch_problem(lam)
            self.followed_stick = _KINDS[self.kind].choose_stick(self, base, base.shot(u, p1),
                                                                 p1)
        return self.followed_stick

    def _shortest_stick(self, base: BranchProblem, sh: Any, p1: float) -> int:
        """SE follows the shortest sticking phase."""
        held = np.flatnonzero(base.sticks)
        return int(held[np.argmin(sh.stick_times[held])])

    def _least_landing(self, base: BranchProblem, sh: Any, p1: float) -> int:
        """SO follows the sticking phase with the smallest pressing force where its held
        phase starts (:meth:`_onset_pressing`)."""
        held = np.flatnonzero(base.sticks)
        return int(held[np.argmin([self._onset_pressing(base, sh, p1, int(j))
                                   for j in held])])

    @staticmethod
    def _onset_pressing(base: BranchProblem, sh: Any, p1: float, k: int) -> float:
        """The pressing force where the held phase of stick k starts: right after the
        plastic impact, or at the accumulation point of the chatter the impact starts
        (the shot's ``accumulations``: the landing state where there is no chatter).

        Minus its size where the held phase has no duration (the stick time does not
        exceed the chatter's), as :func:`~impactcont.problems.multi_impact_branch.
        sticking_onset_test` takes it: past the onset of complete chatter the chatter map
        may accumulate in a later period with a positive pressing force again, no stick of
        this motion.
        """
        held = held_flow(base.oscillator_at(p1), base.impacts[k])
        p = float(held.pressing(sh.accumulations[k], float(sh.accumulation_phases[k])))
        return p if float(sh.stick_times[k]) > float(sh.chatter_times[k]) else -abs(p)

    def _least_minimum(self, base: BranchProblem, sh: Any, p1: float) -> int:
        """RG follows the smallest interior minimum of a pressing force (and keeps its time)."""
        osc = base.oscillator_at(p1)
        held = np.flatnonzero(base.sticks)
        minima = {int(j): held_flow(osc, base.impacts[j]).pressing_minimum(
            float(sh.stick_times[j]), sh.starts[j], float(sh.phases[j])) for j in held}
        inner = {j: value for j, value in minima.items() if value[1] > 0.0}
        if not inner:
            raise ParameterError(
                f"kind={str(self.kind)!r}: the pressing force of no sticking phase of the "
                f"motion at the start has an interior minimum (pattern {self.pattern!r}, "
                f"stick times {sh.stick_times[held].tolist()}): the start is not a release "
                "grazing")
        k = min(inner, key=lambda j: inner[j][0])
        self._minimum_time = float(inner[k][1])
        return k

    def _stick_end_of_shot(self, u: np.ndarray, p1: float, lam: float) -> float:
        """SE: the stick time ``s_k`` of the followed sticking phase."""
        k = self._follow(u, p1, lam)
        return float(self.branch_problem(lam).shot(u, p1).stick_times[k])

    def _stick_end_row(self, x: np.ndarray, lam: float) -> tuple[np.ndarray, float]:
        """SE: ``dg/dx = e_{s_k}`` and ``dg/dp2 = 0`` (``s_k`` is an unknown)."""
        self._follow(x[:-1], float(x[-1]), lam)
        row = np.zeros(x.size)
        row[self._stick_column(self.followed_stick)] = 1.0
        return row, 0.0

    def _sticking_onset_of_shot(self, u: np.ndarray, p1: float, lam: float) -> float:
        """SO: the pressing force ``p_k(0)`` where the followed sticking phase's held phase
        starts: at its plastic landing, or at the accumulation point of its chatter (the
        onset of complete chatter; :meth:`_onset_pressing`)."""
        k = self._follow(u, p1, lam)
        base = self.branch_problem(lam)
        return self._onset_pressing(base, base.shot(u, p1), p1, k)

    def _release_grazing_of_shot(self, u: np.ndarray, p1: float, lam: float) -> float:
        """RG: the pressing force ``p_k(t*)`` at the followed interior minimum of stick k.

        ``t*`` solves ``p_k'(t) = 0`` (:meth:`~impactcont.orbit.held_flow.HeldFlow.segment`'s
        exact rate, :meth:`~impactcont.orbit.held_flow.HeldFlow.pressing_rate`) by secant
        steps from the last accepted point's; NaN where it leaves ``(0, s_k)`` or is not a
        minimum (the curve ends there, :meth:`physical_end`).
        """
        k = self._follow(u, p1, lam)
        base = self.branch_problem(lam)
        sh = base.shot(u, p1)
        osc = base.oscillator_at(p1)
        held = held_flow(osc, base.impacts[k])
        X0, theta, duration = sh.starts[k], float(sh.phases[k]), float(sh.stick_times[k])

        def rate(t: float) -> float:
            return held.pressing_rate(held.segment(t, X0, theta)[3], osc.omega * t + theta)

        t = self._minimum_time
        key = (np.append(u, p1).tobytes(), float(lam))
        if not 0.0 < t < duration:
            self._minima[key] = math.nan
            self.lost_minimum = (f"the followed minimum of the pressing force (t* = {t:.6g}) "
                                 f"lies outside sticking phase {k} (0, {duration:.6g})")
            return math.nan
        scale = max(t, 1e-3 * duration)
        t_prev, r_prev = t * (1.0 + 1e-4), rate(t * (1.0 + 1e-4))
        r = rate(t)
        for _ in range(_MINIMUM_ITER):
            if r == r_prev:
                break
            step = -r * (t - t_prev) / (r - r_prev)
            t_prev, r_prev = t, r
            t += step
            if not 0.0 < t < duration:
                break
            r = rate(t)
            if abs(step) <= _MINIMUM_TOL * scale:
                break
        h = _CURVATURE_STEP * scale
        if not (t - h > 0.0 and t + h < duration) or not rate(t + h) > rate(t - h):
            self._minima[key] = math.nan  # the minimum left the stick, or is none
            self.lost_minimum = (
                f"the interior minimum of the pressing force of sticking phase {k} reaches its "
                f"landing or its release (t* = {t:.6g} of {duration:.6g}) or stops being a "
                "minimum")
            return math.nan
        if len(self._minima) > _CACHE_SIZE:
            self._minima.clear()
        self._minima[key] = t
        return float(held.pressing(held.segment(t, X0, theta)[0], osc.omega * t + theta))

    def minimum_time(self, x: np.ndarray, lam: float) -> float:
        """RG: the time ``t*`` of the followed interior minimum of the pressing force after
        its stick's landing at the curve point ``(x, lam)`` (NaN where there is none)."""
        x = np.asarray(x, dtype=float)
        self.test(x, lam)
        return self._minima.get((x.tobytes(), float(lam)), math.nan)

    def test_noise(self, x: np.ndarray, lam: float) -> float:
        """The rounding noise of ``g`` at ``(x, lam)``: the largest deviation of ``g`` from
        its straight line over ``2 * NOISE_STEPS + 1`` points spaced ``1e-14`` (relative)
        along a fixed direction in ``x``, times 2 (peak to peak).

        The line takes out ``g``'s true slope, so what is left is how well the test is
        known there. Most tests are known to about 1e-14; the pressing force at the
        accumulation point of a complete chatter (SO of a stick entered through chatter)
        to about 1e-8, since it sums the bounces' return times, each known to
        ``eps |x| / u`` with ``u`` down to the chatter cut's speed. A Newton tolerance
        below this cannot be met there (the curve drivers raise their default to
        :data:`NOISE_MARGIN` times it).
        """
        x = np.asarray(x, dtype=float)
        direction = np.cos(1.0 + 2.0 * np.arange(x.size))  # fixed, no axis left out
        scale = 1e-14 * np.maximum(1.0, np.abs(x))
        steps = np.arange(-NOISE_STEPS, NOISE_STEPS + 1, dtype=float)
        values = np.array([self._test(x + t * scale * direction, lam) for t in steps])
        if not np.all(np.isfinite(values)):
            return math.nan
        slope, offset = np.polyfit(steps, values, 1)
        return 2.0 * float(np.max(np.abs(values - (slope * steps + offset))))

    def other_multipliers(self, mu: np.ndarray) -> np.ndarray:
        """The multipliers `mu` of a curve point but the curve's critical one(s) (all of them
        on a GR, ZV, SE, RG or SO curve): inside the unit circle, a stable motion is born or
        lost on the curve (a dataset's ``stable_side``)."""
        mu = np.asarray(mu)
        critical = _KINDS[self.kind].critical
        return mu if critical is None or mu.size == 0 else np.delete(mu, critical(mu))

    def physical_on_curve(self, x: np.ndarray, orbit: MultiImpactOrbit) -> bool:
        """The motion at the curve point ``x = [u, p1, p2]`` is physical but for the curve's
        own bound (as a closed-form GR curve leaves out the tangency itself).

        On a curve of a kind that bounds the physical motions (GR, ZV, SE, RG, SO) the
        motion's own test is zero to rounding, so ``orbit.physical`` flips from point to
        point; there the other bounding tests the curve watches decide (those of
        :data:`_BOUNDS_PHYSICAL` among :attr:`codim2_tests`, where defined; not RG on an
        SO curve, which vanishes along it too). Where it watches none (a ZV curve of a
        motion without sticking phases: GR vanishes with the impact velocity) the motion
        is not called physical. A reason for not being physical that no test counts (a
        chatter bounce reaching another stop) is not seen here; the motion's ``reason``
        names it.
        """
        if orbit.physical or _KINDS[self.kind].critical is not None:
            return bool(orbit.physical)
        values = [value for value in (self.codim2_test(test, x, orbit)
                                      for test in self.codim2_tests
                                      if test in _BOUNDS_PHYSICAL) if math.isfinite(value)]
        if not values:  # no other bound watched (a ZV curve): orbit.physical, False here
            return False
        return all(value > 0.0 for value in values)

    def test_of(self, orbit: MultiImpactOrbit) -> float:
        """The test function at a motion (all kinds but SN, which needs the problem; SE, RG
        and SO at a motion are those of its branch, over every sticking phase)."""
        return _KINDS[self.kind].of_orbit(orbit)

    def _test_gradient(self, x: np.ndarray, lam: float) -> tuple[np.ndarray, float]:
        """``dg/dx`` and ``dg/dlam`` by forward differences.

        The last gradient is reused within ``_REUSE`` (relative) of where it was taken,
        and only until the next accepted point (:meth:`accept` drops it): Newton's
        corrections on one step see a gradient that is off by their size, so they
        converge linearly at that rate instead of quadratically, for a third of the
        cost; the points themselves solve ``g = 0`` to Newton's tolerance either way.
        The tangent at a point is taken with the gradient of its own step. Reused
        across steps, the gradient froze wherever the steps were shorter than
        ``_REUSE``: every tangent was that of one old point, Newton converged slowly
        off it, the step shrank and never left the old point's neighbourhood; an
        NS curve of the impact damper crawled at steps of 1e-6 near its fold in ``b``.
        """
        exact = _KINDS[self.kind].exact_row
        if exact is not None:
            return exact(self, x, lam)
        y = np.empty(x.size + 1)
        y[:-1], y[-1] = x, lam
        if self._gradient is not None and float(np.abs(y - self._gradient[0]).max()) <= \
                _REUSE * max(1.0, float(np.abs(y).max())):
            return self._gradient[1]
        g0 = self.test(x, lam)
        grad = np.full(x.size, np.nan)
        second = math.nan
        if self.kind is Label.BP and self._exact_pitchfork:
            grad[:-1], moved = self._pitchfork_row(x, lam)
            grad[-1], second = moved
        for i in np.flatnonzero(np.isnan(grad)):
            h = _FD_STEP * max(1.0, abs(x[i]))
            e = np.zeros(x.size)
            e[i] = h
            grad[i] = (self.test(x + e, lam) - g0) / h
        if math.isnan(second):
            h = _FD_STEP * max(1.0, abs(lam))
            second = (self.test(x, lam + h) - g0) / h
        value = grad, second
        self._gradient = (y, value)
        return value

    def _pitchfork_row(self, x: np.ndarray, lam: float
                       ) -> tuple[np.ndarray, tuple[float, float]]:
        """BP: ``dg/du`` exactly, and ``dg/dp1``, ``dg/dp2`` for parameters that move the
        stops and for omega as p1 (NaN for the others, left to forward differences).

        ``g = sign(det(H + I)) s_min(H + I)``, so ``dg = sign(det(H + I)) a^T dH b`` with
        ``a``, ``b`` the left and right singular vectors of ``s_min`` (where it is simple,
        as on a regular curve) and ``dH`` exact from the shot
        (:meth:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem.
        half_map_derivative`).
        """
        base = self.branch_problem(lam)
        u, p1 = x[:-1], float(x[-1])
        size = u.size
        stops, (dv, dc, domega) = self._pitchfork_directions(base)
        H, dH = base.half_map_derivative(u, p1, dv, dc, domega)
        sign, _, left, right = _pitchfork_factors(H)
        dg = sign * np.einsum("i,dij,j->d", left, dH, right)
        moved = [math.nan, math.nan]
        for row, i in enumerate(stops):
            moved[i] = float(dg[size + row])
        return dg[:size], (moved[0], moved[1])

    def _pitchfork_directions(self, base: BranchProblem
                              ) -> tuple[list[int], tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The parameters with exact BP columns (those moving the stops, and omega as p1:
        the problem's own parameter) and the directions ``(dv, dc, domega)`` of
        :meth:`_pitchfork_row` (each half unknown, then each such parameter): the same at
        every point of the curve, made once (read only)."""
        if self._directions is None:
            size = base.size
            stops = [i for i, par in enumerate(self.params)
                     if par.data == GAP or (i == 0 and par.data == FREQUENCY)]
            dv = np.zeros((size + len(stops), size))
            dv[:size] = np.eye(size)
            dc = np.zeros((size + len(stops), base.p))
            domega = np.zeros(size + len(stops))
            for row, i in enumerate(stops):
                if self.params[i].data == GAP:
                    dc[size + row] = self.params[i].stop_rates(base.pattern)
                else:
                    domega[size + row] = 1.0
            self._directions = stops, (dv, dc, domega)
        return self._directions

    # -- what the location of codim-2 points needs (detection.codim2.Codim2Problem) ------------
    @property
    def codim2_tests(self) -> tuple[Label, ...]:
        """The other kinds whose test functions are watched along the curve (on a motion
        with sticking phases a curve of SN, PD, NS or GR also watches SE, RG and SO)."""
        tests = _KINDS[self.kind].codim2_tests
        if self.sticky and not _KINDS[self.kind].sticky_only:
            tests = (*tests, *STICKING_CURVE_KINDS)
        return tests

    def physical_end(self, xa: np.ndarray, orbit_a: Any, xb: np.ndarray, orbit_b: Any
                     ) -> str | None:
        """Why the curve leaves the physical motions between two accepted points
        ``[u, p1, p2]`` (a motion with sticking phases), or None.

        A test that bounds the physical motions (a stick time, a pressing force, a
        clearance, an impact velocity: SE, RG, SO, GR, ZV among :attr:`codim2_tests`)
        changes sign, or the followed interior minimum of an RG curve is lost. The
        crossing itself is located afterwards as the curve's codim-2 point.
        """
        if not self.sticky:
            return None
        if _KINDS[self.kind].follows_minimum and not math.isfinite(
                self.minimum_time(xb[:-1], xb[-1])):
            return ("the interior minimum of the pressing force of sticking phase "
                    f"{self.followed_stick} followed by the curve leaves the sticking phase "
                    "(it reaches the landing or the release) or stops being a minimum")
        for test in self.codim2_tests:
            if test not in _BOUNDS_PHYSICAL:
                continue
            ga = self.codim2_test(test, xa, orbit_a)
            gb = self.codim2_test(test, xb, orbit_b)
            if math.isfinite(ga) and math.isfinite(gb) and (ga > 0.0) != (gb > 0.0):
                return f"the {test.words} test ({test}) changes sign: {ga:.3g} -> {gb:.3g}"
        return None

    @property
    def multipliers_defined(self) -> bool:
        """False on a ZV curve: G has its pole at a zero impact velocity (eq. 25)."""
        return _KINDS[self.kind].multipliers_defined

    def codim2_test(self, test: Label, x: np.ndarray, orbit: MultiImpactOrbit) -> float:
        """The test function of `test` at the curve point ``x = [u, p1, p2]``: the smallest
        impact velocity (ZV) and clearance (GR) over the p impacts and flights, the signed
        smallest singular value of the branch problem's Jacobian in ``u`` (SN: the branch
        in ``p1`` folds), the PD and NS products free of the poles of every impact
        (:func:`~impactcont.problems.events.event_function`): the branch problem's own test
        of each kind but the fold (its ``motion_tests``, :mod:`impactcont.problems.events`;
        SE, RG and SO those of a branch of motions with sticking phases)."""
        if test is Label.SN:
            return self.fold_test(x)
        return float(self.branch_problem(float(x[-1])).motion_tests[test].test(orbit))

    def fold_test(self, x: np.ndarray) -> float:
        """``sigma(dF/du)`` at the curve point ``x = [u, p1, p2]`` (zero at a fold in p1)."""
        return self._fold_of_shot(x[:-2], float(x[-2]), float(x[-1]))

    def plane(self, x: np.ndarray) -> tuple[float, float]:
        """``(p1, p2)`` of a curve point ``x = [u, p1, p2]``."""
        return float(x[-2]), float(x[-1])

    def on_hyperplane(self, guess: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """The curve point on the hyperplane through `guess` normal to `normal` (Newton,
        step tolerance 1e-11; its last step in :attr:`last_step`).

        Raises
        ------
        NewtonConvergenceError
            Newton did not converge.
        """
        try:
            found = solve_on_hyperplane(self, np.asarray(guess, dtype=float),
                                        np.asarray(normal, dtype=float), tol=_HYPERPLANE_TOL,
                                        max_iter=30)
        except (ParameterError, ArithmeticError, np.linalg.LinAlgError) as exc:
            # an iterate outside the parameters' range, or a shot that failed
            raise NewtonConvergenceError(f"no curve point on the hyperplane: {exc}") from exc
        if not found.converged or not np.all(np.isfinite(found.x)):
            raise NewtonConvergenceError(f"no curve point on the hyperplane (last Newton step "
                                         f"{found.last_step:.3g})")
        self.last_step = float(found.last_step)
        return found.x

    #: Where ``p1`` is in a curve point ``x = [u, p1, p2]``.
    p1_index = -2

    def terminal_event(self, xa: np.ndarray, xb: np.ndarray) -> None:
        """None: a curve followed by shooting has no end of its own between two points
        (its codim-2 points are located after it, :mod:`impactcont.detection.codim2`)."""
        return None

    def end_resonance(self, x: np.ndarray) -> Label | None:
        """None: a curve of N-p motions has no end of its own at a strong resonance (an NS
        curve goes on as a neutral saddle; its R1/R2 are the zeros of its SN/PD tests)."""
        return None

    def oscillator_of(self, x: np.ndarray) -> ImpactOscillator:
        """The oscillator at a curve point."""
        return self.branch_problem(float(x[-1])).oscillator_at(float(x[-2]))

    def phase(self, point: Any) -> float:
        """The impact phase of a codim-2 point: its motion's first phase."""
        return float(point.orbit.delta)

    def parameter_value(self, osc: ImpactOscillator, name: str) -> float:
        """The value of parameter `name` on `osc` (by its model parameter)."""
        return model_parameter(osc, name).value(osc)

    # -- the Problem protocol ------------------------------------------------------------------
    def accept(self, x: np.ndarray, lam: float) -> None:
        """At an accepted point (the core's hook): the next step takes a fresh ``g`` row (and
        an RG curve's interior minimum is sought from this point's)."""
        self._gradient = None
        self._linearization = None
        self.lost_minimum = ""
        if _KINDS[self.kind].follows_minimum:
            t = self.minimum_time(x, lam)
            if math.isfinite(t):
                self._minimum_time = t

    def residual(self, x: np.ndarray, lam: float) -> np.ndarray:
        """``[F(u, p1; p2), g(u, p1; p2)]``, shape (m + 1,)."""
        x = np.asarray(x, dtype=float)
        out = np.empty(x.size)
        out[:-1] = self.branch_problem(lam).residual(x[:-1], float(x[-1]))
        out[-1] = self.test(x, lam)
        return out

    def jacobian(self, x: np.ndarray, lam: float) -> np.ndarray:
        """``d[F, g]/d[u, p1]``: the branch problem's exact blocks and the row of ``g``."""
        x = np.asarray(x, dtype=float)
        u, p1 = x[:-1], float(x[-1])
        base = self.branch_problem(lam)
        out = np.empty((x.size, x.size))
        out[:-1, :-1] = base.jacobian(u, p1)
        out[:-1, -1] = base.dparam(u, p1)
        out[-1] = self._test_gradient(x, lam)[0]
        return out

    def linearize(self, x: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`residual` and ``[jacobian | dparam]`` at ``(x, lam)`` in one call (the core's
        one-call evaluation, :class:`~impactcont.core.problem.Problem`), shapes (m + 1,),
        (m + 1, m + 2).

        The same values as the three methods, from one evaluation of the branch problem
        (its own ``linearize``) and one look-up of it. The last one is kept until the next
        accepted point: the corrector's converged iterate and the tangent there ask for the
        same point (while the test row is the one :meth:`jacobian` would use there). Where the
        residual is not finite the matrix is NaN and no test row is taken (the corrector
        stops on the residual, as without this method).
        """
        x = np.asarray(x, dtype=float)
        key = (x.tobytes(), float(lam))
        kept = self._linearization
        # kept while the test row it holds is the one the Jacobian would reuse
        if kept is None or kept[0] != key or kept[1] is not self._gradient:
            u, p1 = x[:-1], float(x[-1])
            base = self.branch_problem(lam)
            rows_residual, rows = base.linearize(u, p1)
            residual = np.empty(x.size)
            residual[:-1] = rows_residual
            extended = np.full((x.size, x.size + 1), np.nan)
            if not np.isfinite(rows_residual).all():
                residual[-1] = math.nan
                return residual, extended
            residual[-1] = self.test(x, lam)
            if not math.isfinite(residual[-1]):
                return residual, extended
            extended[:-1, :-1] = rows
            extended[:-1, -1] = self._second_column(base, u, p1, lam)
            extended[-1, :-1], extended[-1, -1] = self._test_gradient(x, lam)
            self._linearization = key, self._gradient, residual, extended
        _, _, residual, extended = self._linearization
        return residual.copy(), extended.copy()

    def _second_column(self, base: BranchProblem, u: np.ndarray, p1: float, lam: float
                       ) -> np.ndarray:
        """``dF/dp2`` at ``(u, p1; p2 = lam)`` (:meth:`dparam` without the test row)."""
        second = self.params[1]
        if second.data in _EXACT and not self.sticky and (second.keeps_symmetry
                                                          or not self.symmetric):
            # from the shot of the problem in p1 (a p2 that breaks the symmetry of a
            # symmetric curve is refused by the problem in p2, below)
            return base.derivative(u, p1, second)
        # with sticking phases the problem in p2: exact in omega, else its central difference
        return self._base(lam, self.parameters[1], p1).dparam(u, float(lam))

    def dparam(self, x: np.ndarray, lam: float) -> np.ndarray:
        """``d[F, g]/dp2``: the branch problem in ``p2`` (exact for omega, b, R) and ``dg/dp2``."""
        x = np.asarray(x, dtype=float)
        u, p1 = x[:-1], float(x[-1])
        out = np.empty(x.size)
        out[:-1] = self._second_column(self.branch_problem(lam), u, p1, lam)
        out[-1] = self._test_gradient(x, lam)[1]
        return out


@functools.cache
def _identity(size: int) -> np.ndarray:
    """The identity of `size` (read-only, made once): ``I`` of the tests ``sigma(A + I)``."""
    eye = np.eye(size)
    eye.flags.writeable = False
    return eye


def _flip_of_orbit(orbit: MultiImpactOrbit) -> float:
    """PD at a motion: ``sign(prod h2_k) sigma(G + I)``."""
    sign = float(np.sign(np.prod(orbit.impact_velocities))) or 1.0
    return sign * signed_smallest_singular_value(orbit.G + np.eye(orbit.G.shape[0]))


def _pitchfork_of_orbit(orbit: MultiImpactOrbit) -> float:
    """BP at a motion: ``sigma(H + I)`` of its half-map (:func:`_pitchfork_factors`)."""
    sign, smallest, _, _ = _pitchfork_factors(half_map(orbit))
    return sign * smallest


def _no_orbit_test(orbit: MultiImpactOrbit) -> float:
    raise ParameterError("the SN test of a curve needs the branch problem, not a motion")


@dataclasses.dataclass(frozen=True)
class _Kind:
    """What a kind of curve of N-p motions is: its test function and what it watches.

    Attributes
    ----------
    of_orbit : callable
        The curve's test function at a motion.
    from_shot : callable or None
        The same from the shot (a method of the problem: ``(problem, u, p1, lam)``),
        without the motion's multipliers and contact checks; None: from the motion.
    codim2_tests : tuple of Label
        The other kinds' test functions watched along the curve.
    multipliers_defined : bool
        False on a ZV curve (G has its pole there, eq. 25).
    contact_checks : bool
        The test needs the interior-contact search of the motion (GR).
    symmetric_only : bool
        A curve of symmetric motions only (BP).
    sticky_only : bool
        A curve of motions with sticking phases only (SE, RG, SO).
    exact_row : callable or None
        ``(problem, x, lam) -> (dg/dx, dg/dp2)`` exactly (SE: ``g`` is an unknown); None:
        forward differences (:meth:`ShootingCurve._test_gradient`).
    choose_stick : callable or None
        ``(problem, branch problem, shot, p1) -> k``: the sticking phase the curve follows,
        chosen at the start (SE, RG, SO).
    follows_minimum : bool
        The test follows an interior minimum of a pressing force from point to point (RG).
    critical : callable or None
        ``mu -> indices`` of the multipliers that sit on the unit circle along the curve
        (SN and BP: the one nearest +1; PD: nearest -1; NS: the pair nearest the circle);
        None: none (GR, ZV, SE, RG, SO bound motions, not multipliers).
    """

    of_orbit: Callable[[MultiImpactOrbit], float]
    from_shot: Callable[..., float] | None
    codim2_tests: tuple[Label, ...]
    multipliers_defined: bool = True
    contact_checks: bool = False
    symmetric_only: bool = False
    sticky_only: bool = False
    exact_row: Callable[..., tuple[np.ndarray, float]] | None = None
    choose_stick: Callable[..., int] | None = None
    follows_minimum: bool = False
    critical: Callable[[np.ndarray], np.ndarray] | None = None


def _nearest_plus_one(mu: np.ndarray) -> np.ndarray:
    return np.array([np.argmin(np.abs(mu - 1.0))])


def _nearest_minus_one(mu: np.ndarray) -> np.ndarray:
    return np.array([np.argmin(np.abs(mu + 1.0))])


def _pair_nearest_the_circle(mu: np.ndarray) -> np.ndarray:
    """The complex pair nearest the unit circle (the two nearest where none is complex)."""
    upper = np.flatnonzero(mu.imag > 0.0)
    if upper.size == 0:
        return np.argsort(np.abs(np.abs(mu) - 1.0), kind="stable")[:2]
    k = int(upper[np.argmin(np.abs(np.abs(mu[upper]) - 1.0))])
    mate = np.abs(mu - np.conj(mu[k]))
    mate[k] = np.inf
    return np.array([k, int(np.argmin(mate))])


def _event(label: Label) -> Callable[[MultiImpactOrbit], float]:
    return lambda orbit: float(event_function(label, orbit))


#: Each kind of curve of N-p motions. The codim-2 tests are those of the N-1 curves
#: (:data:`impactcont.detection.codim2.TESTS`) but the GR test on a GR curve, whose
#: second-lowest clearance is not searched; none on a BP curve, whose codim-2 points have
#: no label yet. On a motion with sticking phases SN, PD, NS and GR curves watch SE, RG
#: and SO too (:attr:`ShootingCurve.codim2_tests`). An SE curve does not watch RG and SO:
#: there the landing is the release, both vanish along the whole curve; an SO curve does
#: not watch RG, which counts the landing's pressing force (zero along it).
_KINDS: dict[Label, _Kind] = {
    Label.SN: _Kind(_no_orbit_test, ShootingCurve._fold_of_shot,
                    (Label.ZV, Label.GR, Label.PD, Label.NS), critical=_nearest_plus_one),
    Label.PD: _Kind(_flip_of_orbit, ShootingCurve._flip_of_shot,
                    (Label.ZV, Label.GR, Label.SN, Label.NS), critical=_nearest_minus_one),
    Label.NS: _Kind(_event(Label.NS), None, (Label.ZV, Label.GR, Label.SN, Label.PD),
                    critical=_pair_nearest_the_circle),
    Label.GR: _Kind(_event(Label.GR), None, (Label.ZV, Label.SN, Label.PD, Label.NS),
                    contact_checks=True),
    Label.ZV: _Kind(_event(Label.ZV), None, (Label.SN,), multipliers_defined=False),
    Label.BP: _Kind(_pitchfork_of_orbit, ShootingCurve._pitchfork_of_shot, (),
                    symmetric_only=True, critical=_nearest_plus_one),
    Label.SE: _Kind(stick_end_test, ShootingCurve._stick_end_of_shot,
                    (Label.ZV, Label.GR, Label.SN, Label.PD, Label.NS), sticky_only=True,
                    exact_row=ShootingCurve._stick_end_row,
                    choose_stick=ShootingCurve._shortest_stick),
    Label.RG: _Kind(release_grazing_test, ShootingCurve._release_grazing_of_shot,
                    (Label.SE, Label.SO, Label.ZV, Label.GR, Label.SN, Label.PD, Label.NS),
                    sticky_only=True, choose_stick=ShootingCurve._least_minimum,
                    follows_minimum=True),
    Label.SO: _Kind(sticking_onset_test, ShootingCurve._sticking_onset_of_shot,
                    (Label.SE, Label.ZV, Label.GR, Label.SN, Label.PD, Label.NS),
                    sticky_only=True, choose_stick=ShootingCurve._least_landing),
}

#: The kinds of curves that bound periodic motions with sticking phases (SE, RG, SO: the
#: kinds of :data:`_KINDS` with ``sticky_only``).
STICKING_CURVE_KINDS: tuple[Label, ...] = tuple(kind for kind, entry in _KINDS.items()
                                                if entry.sticky_only)

#: The codim-2 tests whose sign change takes a motion with sticking phases out of the
#: physical motions (:meth:`ShootingCurve.physical_end`): the kinds that bound them
#: (:attr:`~impactcont.vocabulary.Label.bounds`: GR, ZV, SE, RG, SO, FT).
_BOUNDS_PHYSICAL = tuple(kind for kind in Label if kind.bounds)


#: The earlier name of :class:`ShootingCurve` (``impactcont.problems.multi_impact_curve``).
MultiImpactCurveProblem = ShootingCurve

#: The kinds of N-1 curves in closed form (BP is a curve of symmetric motions only; SE,
#: RG and SO of motions with sticking phases only).
_N1_KINDS = tuple(kind for kind in CURVE_KINDS
                  if kind is not Label.BP and kind not in STICKING_CURVE_KINDS)
#: The kinds of curves followed by shooting.
SHOOTING_KINDS: tuple[Label, ...] = tuple(_KINDS)


def curve_kind(kind: object, argument: str = "kind", kinds: tuple[Label, ...] = _N1_KINDS
               ) -> Label:
    """`kind` (a :class:`~impactcont.vocabulary.Label` or its string) as the Label of a kind
    of curve.

    Parameters
    ----------
    kind : Label or str
        The kind given.
    argument : str
        The name of the argument in the messages.
    kinds : tuple of Label
        The kinds allowed; by default those of N-1 motions (every curve kind but BP,
        which is a curve of symmetric motions only).

    Returns
    -------
    Label

    Raises
    ------
    ParameterError
        `kind` is not one of `kinds` (naming `argument`, the value and the kinds allowed).
    """
    if not isinstance(kind, str) or kind not in kinds:
        label = Label.__members__.get(kind) if isinstance(kind, str) else None
        why = (f" ({label}, {label.words}, has curves of motions with sticking phases only: "
               "start from a special point of a branch of such motions, a pattern with "
               "lowercase letters)"
               if label in STICKING_CURVE_KINDS and label not in kinds else "")
        if label is not None and label.singular:
            why = (f" ({label}, {label.words}, has no curve yet: its points are singular "
                   "points of the shooting system, which the augmented system cannot follow)")
        raise ParameterError(f"{argument} must be one of {tuple(map(str, kinds))}; got "
                             f"{kind!r}{why}")
    return Label(kind)


def curve_problem(kind: Label | str, osc: ImpactOscillator, N: int,
                  parameters: tuple[str, str] = ("omega", "b"), *, p: int | None = None,
                  pattern: str | None = None, symmetric: bool = False
                  ) -> CurveProblem | ShootingCurve:
    """The problem of a codim-1 curve of `kind` in ``parameters``: the closed form or shooting.

    Parameters
    ----------
    kind : Label or str
        One of :data:`~impactcont.vocabulary.CURVE_KINDS` (BP: symmetric motions only).
    osc : ImpactOscillator
        The oscillator (other parameters fixed at its values).
    N : int
        The motion's forcing periods.
    parameters : (str, str)
        ``(p1, p2)``: ``p1`` an unknown, ``p2`` the continuation parameter.
    p : int, optional
        The motion's impacts per period. None: an N-1 motion evaluated by the closed form
        (:mod:`impactcont.problems.closed_form_curve`); given: the N-p motion with
        `pattern` evaluated by shooting (:class:`ShootingCurve`; ``p = 1`` follows an N-1
        motion by shooting, the closed form's witness).
    pattern : str, optional
        With `p`: the stop of each impact.
    symmetric : bool
        With `p`: follow symmetric motions by their half (needed for BP).

    Raises
    ------
    ParameterError
        An unknown kind, a bad parameter (named), BP without a symmetric motion,
        `pattern` or `symmetric` without `p`.
    """
    if p is None:
        if pattern is not None or symmetric:
            raise ParameterError(f"pattern and symmetric describe an N-p motion followed by "
                                 f"shooting: give p too; got pattern={pattern!r}, "
                                 f"symmetric={symmetric!r}, p=None")
        return closed_form_curve(curve_kind(kind), osc, N, parameters)
    return ShootingCurve(osc, N, p, pattern, kind, parameters, symmetric=symmetric)

"""One-parameter branches of periodic motions: the one driver (continuation, detection,
dataset) of every motion.

``continuation(start, parameter, bounds)`` = the branch problem over the motion
(:mod:`impactcont.problems.motion`) and its seed -> follow it with the pseudo-arclength
core (:func:`trace_branch`) -> the motion at every accepted point -> detect and locate
the kinds the problem declares (:func:`~impactcont.detection.special_points.detect_special_points`)
and the user's events -> one dataset (:func:`branch_to_dataset`).

The problem is the N-1 closed form (:class:`~impactcont.problems.PeriodicBranchProblem`,
eq. 14: the exact, fast evaluator) for an oscillator and N, or an N-1 motion of the
paper's system; the shooting system of any other motion
(:class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem`, or
:class:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem` for a symmetric
one). The closed form's own steps are its hooks, not a second driver: the existence scan
and both roots of eq. (15) seed every connected component
(``start_value``, ``start_root``, ``component_seeds``), its folds are located exactly
(``locate_fold``), and its datasets keep the paper's N-1 schema; a shooting branch's
dataset has the ``impact`` dimension (:mod:`impactcont.dataset.multi`), its stop rule
ends a period-doubled branch where it returns to its parent.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.core import (
    ContinuationOptions,
    ContinuationPoint,
    ContinuationStatus,
    Stop,
    follow,
)
from impactcont.core.options import (
    DRIVER_DEFAULTS,
    ContinuationOptionError,
    driver_options,
    option_keywords,
)
from impactcont.core.stepper import FOLD_DLAM_TOLERANCE, NewtonConvergenceError
from impactcont.dataset import branch_dataset
from impactcont.dataset.maps import MULTI_MAP_KIND
from impactcont.dataset.multi import (
    impacts_of,
    multi_impact_dataset,
    pattern_of,
    sticking_columns,
)
from impactcont.dataset.records import (
    orbit_columns,
    reserved_names,
    special_record,
    user_event_record,
)
from impactcont.dataset.schema import (
    USER_EVENTS_ATTR,
    USER_MONITORS_ATTR,
    add_user_functions,
    event_variable,
    oscillator_from_dataset,
    parameter_names,
    special_variable,
    validate_branch_dataset,
)
from impactcont.detection.points import SpecialPoint
from impactcont.detection.special_points import (
    BranchSample,
    UserFunctions,
    check_user_functions,
    detect_special_points,
    locate_sample_events,
    user_values,
    without_detected_events,
)
from impactcont.errors import ImpactcontError, NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import check_model_bounds, model_parameter
from impactcont.orbit.multi_impact import MultiImpactOrbit, initial_unknowns, multi_impact_orbit
from impactcont.orbit.periodic import _PHASE_TOL, PeriodicOrbit, _check_N
from impactcont.orbit.symmetry import admits_symmetric_motions, symmetry_defect
from impactcont.problems import PeriodicBranchProblem
from impactcont.problems.events import PERIOD_DOUBLING
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.problems.symmetric_branch import SymmetricBranchProblem
from impactcont.progress import (
    NothingComputed,
    ProgressOption,
    Reporter,
    check_progress,
    interrupted,
    interruptible,
    reporter,
    take_interrupt,
    until_interrupted,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import LABELS, check_labels

__all__ = ["as_multi_impact_orbit", "branch_problem", "branch_to_dataset",
           "check_continuation_arguments", "continuation", "continuation_from", "extend",
           "make_options", "multi_impact_continuation", "not_a_branch", "restart_problem",
           "run_branch", "trace_branch", "with_user_functions"]

log = logging.getLogger(__name__)

#: The problem of a branch: the N-1 closed form, any N-p motion, a symmetric one by its half.
BranchProblem = PeriodicBranchProblem | MultiImpactBranchProblem | SymmetricBranchProblem

_DEFAULTS = {"newton_tol": 1e-12}
"""The closed form is exact to rounding: a tighter Newton tolerance than the other drivers'."""
_SHOOTING_DEFAULTS = {"newton_tol": 1e-11}
"""The shooting residual of a long motion is accurate to about 1e-12."""
_SAME_ROOT = 0.05  # rad: a seed this close to a computed point of a component lies on it


def check_continuation_arguments(
        osc: ImpactOscillator, N: int = 1, parameter: str = "omega",
        bounds: Sequence[float] = (0.5, 6.0), *, detect: Sequence[str] = LABELS,
        components: str = "all", options: ContinuationOptions | None = None, **single: Any
        ) -> tuple[PeriodicBranchProblem, list[str], tuple[float, float], ContinuationOptions]:
    """The checks :func:`continuation` makes of its arguments before it computes.

    :func:`continuation` calls it first; a scene's validation (``impactcont run
    --check``) calls it on an entry's arguments, so both refuse the same input with the
    same message. The arguments are those of :func:`continuation`.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator.
    N : int
        One impact every N forcing periods.
    parameter : str
        The continued parameter.
    bounds : (float, float)
        Range of the parameter (``options.bounds`` instead when `options` gives it).
    detect : sequence of str
        Special points to detect.
    components : {"all", "start"}
        Which connected components to follow.
    options : ContinuationOptions, optional
        Continuation options.
    **single
        Single options (``ds``, ``ds_min``, ``ds_max``, ``newton_tol``, ``max_points``,
        ``both_directions``, ...; ``None`` means not given), over `options`.

    Returns
    -------
    problem : PeriodicBranchProblem
        Eq. (14) in `parameter` for `osc` and `N`.
    detect : list of str
        The labels to detect.
    bounds : (float, float)
        ``(lo, hi)``, floats.
    options : ContinuationOptions
        The options of the run (this driver's defaults, then `options`, then `single`).

    Raises
    ------
    ParameterError
        Bad `N`, `detect`, `parameter` (or one the oscillator's damping model does not
        have), `bounds` (not two numbers, or outside the parameter's allowed range),
        `components`, or a range reaching elastic impacts without damping (R = 1, no
        damping), where eq. (12) is singular.
    ContinuationOptionError
        A bad option (named; a ParameterError), or ``newton_tol`` above 1e-7, where an
        accepted point could fail eq. (14)'s check of a motion.
    """
    N = _check_N(N)
    detect = check_labels(detect)
    problem = PeriodicBranchProblem(osc, N, parameter)
    if options is not None and "bounds" in getattr(options, "given", ()):
        bounds = options.bounds
    # the shared check, then both ends on the oscillator (an element of K keeps K PSD)
    lo, hi = problem.param.check_bounds(osc, bounds)
    problem.check_bounds((lo, hi))  # the closed form's own limit: elastic without damping
    opts = driver_options(options, (lo, hi), defaults=_DEFAULTS, **single)
    _check_closed_form_tolerance(opts.newton_tol)
    if components not in ("all", "start"):
        raise ParameterError(f"components must be 'all' or 'start'; got {components!r}")
    return problem, detect, (lo, hi), opts


def _check_closed_form_tolerance(newton_tol: float) -> None:
    """Refuse a Newton tolerance whose points the closed form could not take as motions.

    A point is accepted when the residual of eq. (14), over its scale
    :func:`~impactcont.problems.periodic_branch.residual_scale` (at most
    ``max(1, |b|, sqrt(c^2 + s^2))``), is within `newton_tol`; the motion at a phase is
    built only where that relative residual is within ``_PHASE_TOL`` = 1e-7
    (:func:`~impactcont.orbit.periodic.orbit_at_phase`). Above it an accepted point could
    be no motion (``newton_tol=1.0`` failed in the motion's eq. 14 check).
    """
    if newton_tol > _PHASE_TOL:
        raise ContinuationOptionError(
            f"option newton_tol = {newton_tol!r} is invalid; the closed form of N-1 motions "
            f"takes at most {_PHASE_TOL:g} (a point accepted at newton_tol must satisfy eq. "
            f"(14) to {_PHASE_TOL:g} relative to be a motion; its default is "
            f"{_DEFAULTS['newton_tol']:g})")


def as_multi_impact_orbit(start: Any) -> MultiImpactOrbit:
    """The N-p motion a continuation or a map starts from.

    Parameters
    ----------
    start : MultiImpactOrbit or PeriodicOrbit
        The motion; an N-1 :class:`~impactcont.orbit.periodic.PeriodicOrbit` is taken
        as the N-1 multi-impact motion it is.

    Returns
    -------
    MultiImpactOrbit

    Raises
    ------
    TypeError
        `start` is neither.
    """
    if isinstance(start, MultiImpactOrbit):
        return start
    if isinstance(start, PeriodicOrbit):
        return multi_impact_orbit(start.oscillator, start.N, 1, start)
    raise TypeError(f"start must be a MultiImpactOrbit (multi_impact_orbit, special_orbit) or a "
                    f"PeriodicOrbit (periodic_orbits); got {type(start).__name__}")


def make_options(bounds: Sequence[float], options: ContinuationOptions | None = None,
                 **keywords: Any) -> ContinuationOptions:
    """The options of an N-p branch: the drivers' defaults < `options` < `keywords`.

    See :func:`impactcont.core.options.driver_options`; ``None`` keywords are not given.
    """
    lo, hi = (float(v) for v in bounds)
    return driver_options(options, (lo, hi), defaults=_SHOOTING_DEFAULTS, **keywords)


def _pd_sign_change(a: MultiImpactOrbit, b: MultiImpactOrbit) -> bool:
    """Whether the PD test changes sign between two motions, not through a pole of G.

    The pole-free PD test (:data:`~impactcont.problems.events.PERIOD_DOUBLING`) is cleared by the
    impact velocities: one of them changing sign (a zero-velocity impact, the pole of G of
    eq. 25) changes the test's sign without a multiplier through -1.
    """
    fa, fb = PERIOD_DOUBLING.test(a), PERIOD_DOUBLING.test(b)
    near = min(np.min(np.abs(a.multipliers + 1)), np.min(np.abs(b.multipliers + 1)))
    through_pole = bool(np.any((a.impact_velocities < 0) != (b.impact_velocities < 0)))
    return bool(math.isfinite(fa) and math.isfinite(fb) and (fa < 0) != (fb < 0)
                and near < 0.5 and not through_pole)


_PARENT_TOL = 1e-9


def _asymmetry(orbit: MultiImpactOrbit) -> np.ndarray | None:
    """How far an N-p motion (N, p even) is from its N/2-p/2 half repeated twice.

    ``[X_k - X_{k+p/2}, tau_k - tau_{k+p/2}, theta_k - theta_{k+p/2}]`` for
    ``k < p/2``; zero exactly on the repeated half-motion. Across the
    period-doubling of the half-motion the branch of N-p motions comes back as
    its own mirror image (halves swapped), so this vector changes sign there.
    None when N or p is odd, or when the halves hit different stops (pattern
    ``"UL"``: no repeated half-motion can be met on the branch).
    """
    if orbit.p % 2 or orbit.N % 2:
        return None
    h = orbit.p // 2
    pattern = orbit.pattern or ""
    if pattern[:h] != pattern[h:]:
        return None
    dphase = np.remainder(orbit.phases[:h] - orbit.phases[h:] + math.pi, 2 * math.pi) - math.pi
    return np.concatenate([(orbit.states[:h] - orbit.states[h:]).ravel(),
                           orbit.flight_times[:h] - orbit.flight_times[h:], dphase])


class _Watch:
    """The stop rule of one direction of a branch; keeps the orbit of every kept point.

    Stops when the branch returns to the motion it was born from (the N/2-p/2
    motion repeated twice, or its mirror image: that point is left out) and,
    with `stop_after_pd`, that many points after the first sign change of the
    PD test function. A problem whose motions are evaluated after the run
    (``motion_in_step = False``, the closed form) keeps None for each point unless a
    rule or `on_point` needs the motion. `starts` holds the motion at the start of a
    branch by :func:`_start_key`, shared by the watches of both directions (the backward
    run starts from the very point the forward run corrected).
    """

    def __init__(self, problem: BranchProblem, stop_after_pd: int | None,
                 on_point: Callable[[Any], None] | None,
                 starts: dict[tuple[bytes, float], Any] | None = None) -> None:
        self.problem = problem
        self.stop_after_pd = stop_after_pd
        self.on_point = on_point
        self.starts = {} if starts is None else starts
        self.orbits: list[Any] = []
        self.reference: np.ndarray | None = None
        self.remaining: int | None = None
        self.eager = (getattr(problem, "motion_in_step", True) or stop_after_pd is not None
                      or on_point is not None or (problem.N % 2 == 0 and problem.p % 2 == 0))

    def __call__(self, previous: ContinuationPoint | None, current: ContinuationPoint
                 ) -> Stop | None:
        problem = self.problem
        if not self.eager:
            self.orbits.append(None)  # evaluated once the branch is traced (_trace)
            return None
        if previous is None:  # the start: its motion once for both directions
            key = _start_key(current)
            orbit = self.starts.get(key)
            if orbit is None:
                orbit = self.starts[key] = problem.orbit(current.u, current.lam)
        else:
            orbit = problem.orbit(current.u, current.lam)
        asym = _asymmetry(orbit)
        if asym is not None:
            small = np.max(np.abs(asym)) <= _PARENT_TOL * max(1.0, float(np.max(np.abs(
                orbit.states))))
            if self.reference is None and not self.orbits and not small:
                self.reference = asym
            elif self.reference is not None and (float(asym @ self.reference) <= 0.0 or small):
                return Stop(ContinuationStatus.REACHED_PARENT,
                            f"the period-doubling of the {problem.N // 2}-{problem.p // 2} "
                            f"motion it was born from, near {problem.parameter}="
                            f"{current.lam:.10g} (the point there is the parent repeated twice "
                            "or its mirror image, and is left out)", keep=False)
        self.orbits.append(orbit)
        if self.on_point is not None:
            self.on_point(orbit)
        if self.remaining is not None:
            self.remaining -= 1
            if self.remaining <= 0:
                return Stop(ContinuationStatus.STOPPED_AFTER_EVENT,
                            f"{self.stop_after_pd} point(s) after the first period-doubling")
        elif self.stop_after_pd is not None and len(self.orbits) > 1 and _pd_sign_change(
                self.orbits[-2], self.orbits[-1]):
            self.remaining = self.stop_after_pd
            if self.remaining <= 0:
                return Stop(ContinuationStatus.STOPPED_AFTER_EVENT, "at the first period-doubling")
        return None


def _start_key(point: ContinuationPoint) -> tuple[bytes, float]:
    """Where :class:`_Watch` keeps the motion at the start `point`."""
    return np.asarray(point.u, dtype=float).tobytes(), float(point.lam)


def _trace(problem: BranchProblem, u0: np.ndarray, lam0: float, options: ContinuationOptions,
           *, stop_after_pd: int | None = None, on_point: Callable[[Any], None] | None = None,
           progress: Reporter | None = None) -> tuple[list[BranchSample], Any, str]:
    """Follow a branch (one or both directions): its samples in branch order, the core's
    result and the stop message (empty samples when the start could not be corrected)."""
    watches: dict[int, _Watch] = {}
    starts: dict[tuple[bytes, float], Any] = {}

    def watch(direction: int) -> _Watch:
        watches[direction] = _Watch(problem, stop_after_pd, on_point, starts)
        return watches[direction]

    options, limit = _within_limits(problem, options)
    result = follow(problem, u0, lam0, options, None if progress is None else progress.point,
                    stop=watch)
    # Ctrl-C can end a run between a watch's orbit and the core's taking of the point
    forward = watches[options.direction].orbits[:len(result) - result.start_index]
    message = result.message
    if not forward:
        return [], result, message
    if limit is not None and any(problem.param.value(o.oscillator) == limit
                                 for w in watches.values() for o in w.orbits[-1:]):
        message += (f"; the branch ends at {problem.parameter} = {limit!r}, ds_min from the "
                    f"end of its range: {problem.limit_reason()}")
    orbits = forward
    if -options.direction in watches:
        orbits = watches[-options.direction].orbits[result.start_index:0:-1] + forward
    samples = [BranchSample(u=u, lam=float(lam), tangent=t,
                            orbit=problem.orbit(u, float(lam)) if o is None else o)
               for u, lam, t, o in zip(result.u, result.lam, result.tangent, orbits, strict=True)]
    return samples, result, message


def trace_branch(problem: BranchProblem, u0: np.ndarray, lam0: float,
                 options: ContinuationOptions, *, stop_after_pd: int | None = None,
                 on_point: Callable[[Any], None] | None = None,
                 progress: Reporter | None = None,
                 ) -> tuple[list[BranchSample], list[str], str]:
    """Follow a branch (one or both directions) and return its samples in branch order.

    Parameters
    ----------
    problem : BranchProblem
        Any branch problem (:mod:`impactcont.problems.motion`).
    u0 : ndarray
        Unknowns at the start (corrected at fixed ``lam0``).
    lam0 : float
        The parameter at the start.
    options : ContinuationOptions
        ``direction`` and ``both_directions`` are honoured.
    stop_after_pd : int, optional
        Stop a direction this many points after the first sign change of the
        PD test function (saves following a cascade branch to the bound).
    on_point : callable, optional
        Called with the motion of every accepted point.
    progress : Reporter, optional
        Counts every accepted point (:mod:`impactcont.progress`).

    Returns
    -------
    samples : list of BranchSample
        The accepted points in branch order.
    statuses : list of str
        Why each direction stopped (names of
        :class:`~impactcont.core.ContinuationStatus`).
    message : str
        The stop reasons in words.

    Raises
    ------
    NothingComputed
        Ctrl-C before the first point.
    NoPeriodicMotionError
        Newton fails at the start.
    """
    samples, result, message = _trace(problem, u0, lam0, options,
                                      stop_after_pd=stop_after_pd, on_point=on_point,
                                      progress=progress)
    _require_start(problem, samples, result)
    return samples, [st.name for st in result.statuses], message


def _require_start(problem: BranchProblem, samples: Sequence[BranchSample], result: Any
                   ) -> None:
    """Raise when a branch has no point: interrupted before it, or Newton failed there."""
    if samples:
        return
    if result.interrupted:
        raise NothingComputed(f"continuation of {problem.N}-{problem.p} motions interrupted "
                              "before its first point")
    raise NoPeriodicMotionError(f"N={problem.N}, p={problem.p}: {result.message}")


def _within_limits(problem: BranchProblem, options: ContinuationOptions
                   ) -> tuple[ContinuationOptions, float | None]:
    """`options` with the bounds kept ``ds_min`` inside the problem's parameter limits.

    :func:`run_branch` refuses bounds beyond the limits; a direct caller of
    :func:`trace_branch` gets a branch that ends on the clipped bound (the limit
    itself, e.g. closed stops, has no motion) instead of steps refused until ds_min.
    Returns the options and the clipped bound (None when nothing was clipped).
    """
    lower, _ = problem.parameter_limits()  # the stops limit b from below only
    lo, hi = options.bounds
    if lo > lower:
        return options, None
    clipped = lower + options.ds_min * max(1.0, abs(lower))
    if not clipped < hi:
        raise ParameterError(f"bounds {options.bounds} of parameter {problem.parameter!r} "
                             f"leave no range: {problem.limit_reason()}")
    return dataclasses.replace(options, bounds=(clipped, hi)), clipped


@dataclasses.dataclass(frozen=True, eq=False)
class _Run:
    """One connected component (an N-p branch is one): where it started, the core's result
    and stop message, its samples, special points, the user's functions at its points
    (``values``) and located events."""

    start: float
    start_delta: float
    result: Any
    message: str
    samples: list[BranchSample]
    specials: list[SpecialPoint]
    values: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    events: list[SpecialPoint] = dataclasses.field(default_factory=list)


def _follow(problem: BranchProblem, u0: np.ndarray, lam0: float, opts: ContinuationOptions,
            detect: Sequence[str], rep: Reporter | None = None,
            functions: UserFunctions | None = None, *, stop_after_pd: int | None = None,
            required: bool = False, warn_max_points: bool = False) -> _Run:
    """Trace, detect, locate the user's events: one component of a branch, any motion.

    With `required`, a branch without a point raises (:func:`trace_branch`); otherwise its
    run has no samples (the N-1 driver warns and keeps the other components). With
    `warn_max_points`, a component that stops at ``max_points`` warns (a continuation or
    restart of any motion; a switch does not: a cascade limits its branches on purpose).
    """
    u0 = np.asarray(u0, dtype=float)
    samples, result, message = _trace(problem, u0, lam0, opts, stop_after_pd=stop_after_pd,
                                      progress=rep)
    if required:
        _require_start(problem, samples, result)
    where = (f"the {problem.N}-{problem.p} component through {problem.parameter}="
             f"{float(lam0):.10g}")
    log.info("%s: %d points (%s)", where, len(samples), message)
    if warn_max_points and ContinuationStatus.MAX_POINTS_REACHED in result.statuses:
        warnings.warn(f"{where} stopped at max_points={opts.max_points}: the rest of it is "
                      "not in the branch; raise max_points or ds_max", RuntimeWarning,
                      stacklevel=4)
    specials = until_interrupted(
        lambda: detect_special_points(problem, samples, detect), [], "location",
        "interrupted by the user (KeyboardInterrupt) while locating the special points of "
        "%s: they are dropped", where)
    values, events = user_events_until_interrupted(problem, samples, functions)
    return _Run(float(lam0), float(u0[0]), result, message, samples, specials, values, events)


def user_events_until_interrupted(problem: Any, samples: Sequence[BranchSample],
                                  functions: UserFunctions | None, **position: Any
                                  ) -> tuple[dict[str, np.ndarray], list[SpecialPoint]]:
    """The user's functions at every sample and their located events (none when Ctrl-C
    is taken while they are located: the values are kept)."""
    found = until_interrupted(
        lambda: locate_sample_events(problem, samples, functions, **position), None,
        "location", "interrupted by the user (KeyboardInterrupt) while locating the user "
        "events: they are dropped (the user's functions at the points are kept)")
    if found is not None:
        return found
    if not functions:
        return {}, []
    return user_values(functions, [s.orbit for s in samples],
                       getattr(problem, "parameter", None)), []


def _dataset(problem: Any, runs: Sequence[_Run], options: Mapping[str, Any], *,
             title: str | None = None, extra_attrs: Mapping[str, Any] | None = None,
             extra_columns: Sequence[str] = (),
             functions: UserFunctions | None = None) -> xr.Dataset:
    """The one dataset builder of a branch: every run (connected component) of any motion.

    The closed form's branches (a problem with ``component_seeds``) number their
    components (``connected_component``); a problem with ``impact_dimension`` adds the
    ``impact`` dimension (:mod:`impactcont.dataset.multi`; the p = 1 case of an N-1
    branch keeps the paper's schema, read as p = 1). `extra_columns` are further
    oscillator parameters stored per point (the first parameter of a two-parameter curve).
    """
    parameter = problem.parameter
    samples = [s for run in runs for s in run.samples]
    orbits = [s.orbit for s in samples]
    arclength, component, special_points, specials = [], [], [], []
    user_events: list[SpecialPoint] = []
    offset = 0
    for index, run in enumerate(runs):
        steps: Any = []
        if len(run.samples) > 1:
            x = np.column_stack([[s.u for s in run.samples], [s.lam for s in run.samples]])
            steps = np.sqrt(np.sum(np.diff(x, axis=0) ** 2, axis=1))
        arclength.append(np.concatenate([[0.0], np.cumsum(steps)]))
        component.append(np.full(len(run.samples), index))
        special_points += [special_record(sp, parameter, point=sp.point + offset,
                                          bracket=sp.bracket) for sp in run.specials]
        specials += run.specials
        user_events += [dataclasses.replace(ev, point=ev.point + offset) for ev in run.events]
        offset += len(run.samples)
    columns = {**orbit_columns(orbits, parameter, [s.lam for s in samples]),
               "arclength": np.concatenate(arclength)}
    if hasattr(problem, "component_seeds"):
        columns["connected_component"] = np.concatenate(component)
    for name in extra_columns:
        columns.setdefault(name, np.array([model_parameter(o.oscillator, name).value(
            o.oscillator) for o in orbits]))  # an element, an extra stop's gap: by its object
    if getattr(problem, "impact_dimension", True):
        ds = _impact_dataset(problem, orbits, specials, options, columns, special_points,
                             title, extra_attrs)
    else:
        ds = branch_dataset(parameter=parameter, N=problem.N, oscillator=problem.osc,
                            options=dict(options), columns=columns,
                            special_points=special_points, title=title)
        ds.attrs.update(extra_attrs or {})
    if options.get("interrupted"):  # Ctrl-C: as an interrupted map says it
        ds.attrs["interrupted"] = 1
    if not functions:
        return ds
    return with_user_functions(ds, functions, {
        name: np.concatenate([run.values[name] for run in runs])
        for name in functions.functions}, user_events)


def with_user_functions(ds: xr.Dataset, functions: UserFunctions,
                        values: Mapping[str, np.ndarray], found: Sequence[SpecialPoint]
                        ) -> xr.Dataset:
    """`ds` with the user's functions: each at every point (`values`) and the located zeros
    of its events (`found`), by :func:`~impactcont.dataset.schema.add_user_functions` (a
    branch of any motion, a curve of either evaluator)."""
    names = parameter_names(ds)
    return add_user_functions(ds, monitors=values, events=list(functions.events),
                              event_points=[user_event_record(ev, names) for ev in found])


def _impact_dataset(problem: Any, orbits: Sequence[Any], specials: Sequence[SpecialPoint],
                    options: Mapping[str, Any], columns: dict[str, Any],
                    special_points: list[dict[str, Any]], title: str | None,
                    extra_attrs: Mapping[str, Any] | None) -> xr.Dataset:
    """The branch schema with the ``impact`` dimension: the per-impact view of the motions
    (:class:`~impactcont.problems.motion.Motion`) at the points and special points."""
    n, p = problem.osc.n, problem.p
    impact_columns = {
        "delta_k": np.array([o.phases for o in orbits]),
        "impact_velocity_k": np.array([o.impact_velocities for o in orbits]),
        "flight_time_k": np.array([o.flight_times for o in orbits]),
        "gap_min_k": np.array([o.flight_gap_min for o in orbits]),
        "state_k": np.array([o.states for o in orbits]),
    }
    special_impact_columns = {
        "delta_k": np.array([sp.orbit.phases for sp in specials]).reshape(-1, p),
        "impact_velocity_k": np.array([sp.orbit.impact_velocities for sp in specials]
                                      ).reshape(-1, p),
        "flight_time_k": np.array([sp.orbit.flight_times for sp in specials]).reshape(-1, p),
        "state_k": np.array([sp.orbit.states for sp in specials]).reshape(-1, p, 2 * n),
    }
    # a branch of motions with sticking phases: their stick times, pressing minima, releases
    sticking = sticking_columns(orbits, p)
    if sticking:
        impact_columns.update(sticking)
        special_impact_columns.update(sticking_columns([sp.orbit for sp in specials], p,
                                                       special=True, sticky=True))
    return multi_impact_dataset(parameter=problem.parameter, N=problem.N, p=p,
                                oscillator=problem.osc, options=dict(options), columns=columns,
                                impact_columns=impact_columns, special_points=special_points,
                                special_impact_columns=special_impact_columns, title=title,
                                extra_attrs=extra_attrs, pattern=problem.pattern)


def branch_to_dataset(problem: Any, samples: Sequence[BranchSample],
                      specials: Sequence[SpecialPoint], options: Mapping[str, Any],
                      *, title: str | None = None,
                      extra_attrs: Mapping[str, Any] | None = None,
                      extra_columns: Sequence[str] = (),
                      functions: UserFunctions | None = None,
                      values: Mapping[str, np.ndarray] | None = None,
                      user_events: Sequence[SpecialPoint] = ()) -> xr.Dataset:
    """The dataset of one run of samples and special points (the one builder).

    `extra_columns` are further oscillator parameters stored per point (the first
    parameter of a two-parameter curve). With `functions` (the user's events and
    monitors), `values` (each function at every sample) and `user_events` (the located
    zeros) are stored (:func:`~impactcont.dataset.schema.add_user_functions`).
    """
    run = _Run(math.nan, math.nan, None, "", list(samples), list(specials),
               dict(values or {}), list(user_events))
    return _dataset(problem, [run], options, title=title, extra_attrs=extra_attrs,
                    extra_columns=extra_columns, functions=functions)


def run_branch(problem: BranchProblem, u0: np.ndarray, lam0: float,
               options: ContinuationOptions, *, detect: Sequence[str] = LABELS,
               stop_after_pd: int | None = None, record: Mapping[str, Any] | None = None,
               extra_attrs: Mapping[str, Any] | None = None,
               progress: ProgressOption | Reporter = None,
               functions: UserFunctions | None = None,
               warn_max_points: bool = False) -> xr.Dataset:
    """Trace, detect and assemble: the dataset of the branch through ``(u0, lam0)``.

    `progress` is a driver's ``progress=`` option or the reporter of an enclosing call
    (:func:`impactcont.progress.reporter`); `functions` the user's events and monitors
    (:func:`~impactcont.detection.special_points.check_user_functions`). With
    `warn_max_points`, a branch that stops at ``max_points`` warns (a continuation or a
    restart of any motion, as the closed form's components do; a switch does not: a
    cascade limits its branches on purpose).
    """
    labels = check_labels(detect)
    functions = without_detected_events(functions, problem, labels)  # no point twice
    problem.check_bounds(options.bounds)
    what = f"continuation of {problem.N}-{problem.p} motions in {problem.parameter}"
    with interruptible(what), reporter(progress, what, parameter=problem.parameter) as rep:
        run = _follow(problem, u0, lam0, options, labels, rep, functions,
                      stop_after_pd=stop_after_pd, required=True,
                      warn_max_points=warn_max_points)
        if interrupted():
            record = {**(record or {}), "interrupted": True}
    statuses = [st.name for st in run.result.statuses]
    log.info("N=%d p=%d branch in %s: %d points, %d special (%s)", problem.N, problem.p,
             problem.parameter, len(run.samples), len(run.specials), run.message)
    option_record = {**dataclasses.asdict(options), "N": problem.N, "p": problem.p,
                     "parameter": problem.parameter, "start": float(lam0),
                     "start_delta": float(u0[0]), "detect": labels, "status": statuses,
                     "message": run.message, **(record or {})}
    option_record["bounds"] = list(options.bounds)
    return _dataset(problem, [run], option_record, extra_attrs=extra_attrs,
                    functions=functions)


def branch_problem(orbit: MultiImpactOrbit, parameter: str, symmetric: bool | None = None
                   ) -> tuple[BranchProblem, np.ndarray]:
    """The branch problem through an N-p motion, and the motion's unknowns in it.

    Parameters
    ----------
    orbit : MultiImpactOrbit
    parameter : str
    symmetric : bool, optional
        Follow the motion as a symmetric one (its half closed by the reflection,
        :class:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem`: regular
        through the symmetry-breaking pitchfork, which is detected as ``BP``) or as a
        general N-p motion. ``None``: symmetric when the motion is symmetric
        (:func:`~impactcont.orbit.symmetry.symmetry_defect` at most 1e-8) and
        `parameter` keeps the system symmetric (not ``b`` or ``R``, unless the stops are
        mirrored: ``Stops(mirror=True)``).

    Raises
    ------
    ParameterError
        ``symmetric=True`` for a motion that is not symmetric or a parameter that breaks
        the symmetry.
    """
    pattern = orbit.pattern or None
    defect: float | None = None  # the motion's symmetry_defect, computed once
    if symmetric is None:
        symmetric = (model_parameter(orbit.oscillator, parameter).keeps_symmetry
                     and admits_symmetric_motions(orbit.oscillator, orbit.N, orbit.p,
                                                  orbit.pattern or "")
                     and (defect := symmetry_defect(orbit)) <= _SYMMETRY_TOL)
    elif not isinstance(symmetric, (bool, np.bool_)):
        raise ParameterError(f"symmetric must be True, False or None (decide from the motion); "
                             f"got {symmetric!r}")
    if not symmetric:
        problem = MultiImpactBranchProblem(orbit.oscillator, orbit.N, orbit.p, parameter,
                                           pattern=pattern)
        return problem, orbit.unknowns
    sym = SymmetricBranchProblem(orbit.oscillator, orbit.N, orbit.p, parameter,
                                 pattern=orbit.pattern)
    if defect is None:  # symmetric=True given
        defect = symmetry_defect(orbit)
    if not defect <= _SYMMETRY_TOL:
        raise ParameterError(f"symmetric=True: the N={orbit.N}, p={orbit.p} motion is not "
                             f"symmetric (X_(k+p/2) + X_k, tau_(k+p/2) - tau_k up to {defect:.3g} "
                             f"relative, allowed {_SYMMETRY_TOL:g}); give symmetric=False or a "
                             "symmetric motion")
    return sym, sym.half_unknowns(orbit.unknowns)


_SYMMETRY_TOL = 1e-8


def _motion_branch(motion: PeriodicOrbit | MultiImpactOrbit, N: int, parameter: str,
                   bounds: Sequence[float], *, start: float | None, root: int | None,
                   components: str, **keywords: Any) -> xr.Dataset:
    """The branch through a computed motion (:func:`continuation` given a motion).

    An N-1 motion of the paper's system in a parameter of eq. (14) is followed on the
    closed form (the exact, fast path: its component through the motion's root); any
    other motion or parameter on the shooting system (:func:`_shooting_branch`).
    """
    motion_N = int(motion.N)
    for name, value, allowed in (("N", N, (1, motion_N)), ("start", start, (None,)),
                                 ("root", root, (None,)),
                                 ("components", components, ("all", "start"))):
        if value not in allowed:
            raise ParameterError(
                f"{name} must be left out when continuation starts from a motion (the "
                f"motion fixes it: N = {motion_N}, its own parameter value and root, the "
                f"component through it); got {name}={value!r}")
    osc = motion.oscillator
    if isinstance(motion, PeriodicOrbit) and osc.stops.paper:
        try:
            problem = PeriodicBranchProblem(osc, motion_N, parameter)
        except ParameterError:
            problem = None  # a parameter the closed form does not continue: shooting
        if problem is not None:
            lo, hi = problem.param.check_bounds(osc, bounds)
            value = problem.param.value(osc)
            if not lo <= value <= hi:
                raise ParameterError(f"the motion's {parameter} = {value!r} lies outside "
                                     f"bounds {(lo, hi)}")
            return continuation(osc, motion_N, parameter, (lo, hi), start=value,
                                root=motion.root, components="start", **keywords)
    return _shooting_branch(motion, parameter, bounds, **keywords)


@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_DEFAULTS})
def continuation(osc: ImpactOscillator, N: int = 1, parameter: str = "omega",
                 bounds: Sequence[float] = (0.5, 6.0), *, start: float | None = None,
                 root: int | None = None, detect: Sequence[str] = LABELS,
                 components: str = "all", options: ContinuationOptions | None = None,
                 ds: float | None = None, ds_min: float | None = None,
                 ds_max: float | None = None, newton_tol: float | None = None,
                 max_points: int | None = None, both_directions: bool | None = None,
                 progress: ProgressOption = None,
                 events: dict[str, Any] | None = None, monitors: dict[str, Any] | None = None,
                 **more: Any) -> xr.Dataset:
    """Continue a branch of periodic motions in one parameter and find its special points.

    Parameters
    ----------
    osc : ImpactOscillator, PeriodicOrbit or MultiImpactOrbit
        The oscillator (other parameters fixed at its values); or a computed motion, whose
        branch is followed from it: an N-1 motion of the paper's system on the closed form
        (the component through its root), any other motion, or a parameter the closed form
        does not continue, by :func:`impactcont.multi_impact_continuation` (its keywords
        ``direction`` and ``symmetric`` then apply). `N`, `start`, `root` and
        `components` are the motion's and must be left out.
    N : int
        One impact every N forcing periods.
    parameter : str
        ``"omega"``, ``"b"``, ``"R"``, ``"eta"``, ``"alpha"``, ``"beta"`` or ``"F0"`` (the forcing
        amplitude, the largest |F_i|: F is scaled, its shape kept); from a motion, any
        parameter :func:`impactcont.multi_impact_continuation` takes.
    bounds : (float, float)
        Range of the parameter.
    start : float, optional
        Parameter value to start from; default the oscillator's value if inside
        `bounds`, else the first value of a scan of `bounds` where a motion exists.
    root : {+1, -1}, optional
        Which root of eq. (15) to start on; default the physical (then stable) one.
    detect : sequence of str
        Special points to detect, subset of :data:`impactcont.vocabulary.LABELS`.
    components : {"all", "start"}
        ``"all"`` (default): every connected component of the solution set in
        `bounds`, found by a scan of eq. (15) and followed one by one (component 0
        goes through the start; with ``both_directions=False`` it is followed from the
        start one way, the others over the whole bounds); ``"start"``: only the component
        through the start.
    options : ContinuationOptions, optional
        Continuation options with ``bounds`` from `bounds` (see ``docs/engine.md``;
        Newton tolerance 1e-12 by default: the closed form is exact to rounding; at
        most 1e-7, eq. (14)'s tolerance for a motion).
    ds, ds_min, ds_max, newton_tol, max_points, both_directions, **more
        Single options, over `options`.
    progress : None, bool or callable
        A progress bar on stderr (``None``: when stderr is a terminal, after 2 s;
        ``True``: always; ``False``: never) or a callable receiving a
        :class:`~impactcont.progress.Progress` record at every point
        (:mod:`impactcont.progress`). A call longer than a minute logs a line a minute.
    events : mapping of str to callable, optional
        User events: ``name -> f(orbit)``, a real function of the
        :class:`~impactcont.PeriodicOrbit` at a point (e.g. ``lambda o:
        max_displacement(o, 2) - 0.3``, :func:`impactcont.orbit.extrema.max_displacement`).
        Its zeros along the branch are located as the special points are and stored on
        the dimension ``event`` (``event_name``, ``event_<parameter>``,
        ``event_precision``, ``event_status``, ``event_point``); ``f`` is stored at every
        point as ``monitor_<name>`` too (``docs/engine.md``).
    monitors : mapping of str to callable, optional
        User monitors: ``name -> f(orbit)``, stored at every point as ``monitor_<name>``.

    Returns
    -------
    xarray.Dataset
        The branch (dimension ``point``) with its special points (dimension
        ``special``); schema in ``docs/dataset.md``. ``connected_component`` numbers
        the components; points are in continuation order within each.

    Warns
    -----
    RuntimeWarning
        When a component stops at ``max_points`` (naming where it started), or when the
        corrector fails at a component's seed (that component is left out).

    Raises
    ------
    NewtonConvergenceError
        When no component could be started.
    TypeError, ParameterError
        Bad `events` or `monitors` (a name that is not an identifier or is a built-in
        variable or label; not callable), or one of their functions raised, returned a
        value that is not a real number or not finite: the message names it.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the call with what it has computed: the
    component being followed stops at its last accepted point, the special points of the
    points kept are located, and the components not yet followed (and the other direction)
    are left out. The dataset's ``options`` attribute then records ``"interrupted": true``
    and the stop reason ``"interrupted by the user (KeyboardInterrupt) after K points,
    ..."`` (status ``INTERRUPTED``), also logged at WARNING. Ctrl-C while the special points
    are located keeps those already located and drops the one in progress (the log says so).
    A second Ctrl-C, or one before the first point, aborts with :class:`KeyboardInterrupt`.
    The dataset's attribute ``interrupted`` is then 1, as an interrupted map's.
    """
    if isinstance(osc, (PeriodicOrbit, MultiImpactOrbit)):
        return _motion_branch(osc, N, parameter, bounds, start=start, root=root,
                              components=components, detect=detect, options=options, ds=ds,
                              ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol,
                              max_points=max_points, both_directions=both_directions,
                              progress=progress, events=events, monitors=monitors, **more)
    if not isinstance(osc, ImpactOscillator):
        hint = (" (a computed dataset: restart or extend a branch with "
                "impactcont.analysis.branch.continuation_from or extend, or start from a "
                "motion of it, ic.special_orbit)" if isinstance(osc, xr.Dataset) else "")
        raise ParameterError(f"osc must be an ImpactOscillator, a PeriodicOrbit or a "
                             f"MultiImpactOrbit; got {type(osc).__name__}{hint}")
    problem, detect, (lo, hi), opts = check_continuation_arguments(
        osc, N, parameter, bounds, detect=detect, components=components, options=options,
        ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol, max_points=max_points,
        both_directions=both_directions, **more)
    functions = check_user_functions(events, monitors, reserved_names())
    N = problem.N
    lam0 = problem.start_value((lo, hi), start)  # the closed form's seeds: eq. (15)
    u0 = problem.start_root(lam0, root)
    record: dict[str, Any] | None = None
    with (interruptible(f"continuation in {parameter}") as call,
          reporter(progress, f"continuation in {parameter}", parameter=parameter) as rep):
        runs = [_follow(problem, u0, lam0, opts, detect, rep, functions, warn_max_points=True)]
        if components == "all" and not interrupted():
            # every further component over the whole of the bounds; with one direction the
            # start's own component is followed one way only, and a seed on its other side
            # is not another component (its run goes through the start: left out)
            whole = opts if opts.both_directions else dataclasses.replace(
                opts, both_directions=True)
            known = list(runs)
            try:
                for lam, u in problem.component_seeds((lo, hi)):
                    if not any(_passes(run, lam, float(u[0])) for run in known):
                        run = _follow(problem, u, lam, whole, detect, rep, functions,
                                      warn_max_points=True)
                        known.append(run)
                        if opts.both_directions or not _passes(run, lam0, float(u0[0])):
                            runs.append(run)
                    if interrupted():
                        break
            except (ImpactcontError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                # what is computed is kept: the branch ends here, the reason said
                reason = (f"the search for further components in {parameter} failed "
                          f"({type(exc).__name__}: {exc}); the branch holds the "
                          f"{len(runs)} component(s) followed before it")
                warnings.warn(reason, RuntimeWarning, stacklevel=3)
                record = {"message": f"{runs[0].result.message}; {reason}"}
            except KeyboardInterrupt:
                if not take_interrupt("continuation", "interrupted by the user "
                                      "(KeyboardInterrupt) in the search for further "
                                      "components; the %d component(s) followed are kept",
                                      len(runs)):
                    raise
        if interrupted():
            record = {**(record or {}), "interrupted": True}
            if not runs[0].result.interrupted:  # the first component's reason says it
                record["message"] = (
                    f"{record.get('message', runs[0].result.message)}; interrupted by the "
                    f"user (KeyboardInterrupt): the branch holds the {len(runs)} "
                    "component(s) computed before it")
    started = [run for run in runs if run.samples]
    if not started and call.interrupted:
        raise NothingComputed(f"continuation in {parameter} interrupted before its first "
                              "point")
    for run in runs:
        if not run.samples and not run.result.interrupted:  # its corrector failed at the seed
            warnings.warn(f"the N={N} component through {parameter}={run.start:.10g} "
                          f"(delta={run.start_delta:.10g}) could not be started: "
                          f"{run.result.message}; it is not in the branch", RuntimeWarning,
                          stacklevel=3)
    if not started:
        raise NewtonConvergenceError(f"no component of the N={N} branch in {parameter} over "
                                     f"[{lo:.10g}, {hi:.10g}] could be started: "
                                     f"{runs[0].result.message}")
    return _components_dataset(problem, opts, detect, started, record, functions=functions)


def _passes(run: _Run, lam: float, delta: float) -> bool:
    """Whether the component of `run` goes through ``(lam, delta)`` (delta modulo 2 pi)."""
    lams = np.array([s.lam for s in run.samples])
    deltas = np.array([s.delta for s in run.samples])
    if lams.size == 1:
        return lams[0] == lam and abs(math.remainder(deltas[0] - delta, 2 * math.pi)) < 1e-6
    side = lams - lam
    for i in np.flatnonzero(side[:-1] * side[1:] <= 0):
        span = lams[i + 1] - lams[i]
        t = 0.5 if span == 0 else (lam - lams[i]) / span
        guess = deltas[i] + t * (deltas[i + 1] - deltas[i])
        if abs(math.remainder(guess - delta, 2 * math.pi)) < _SAME_ROOT:
            return True
    return False


def _components_dataset(problem: PeriodicBranchProblem, opts: ContinuationOptions,
                        detect: Sequence[str], runs: list[_Run],
                        record: dict[str, Any] | None = None, *,
                        functions: UserFunctions | None = None) -> xr.Dataset:
    """One dataset of every component (the variable ``connected_component`` tells them apart)."""
    first = runs[0]
    option_record = {**dataclasses.asdict(opts), "N": problem.N, "parameter": problem.parameter,
                     "start": first.start, "start_delta": first.start_delta,
                     "detect": list(detect),
                     "status": [st.name for st in first.result.statuses],
                     "message": first.result.message,
                     "components": [{"start": run.start, "start_delta": run.start_delta,
                                     "points": len(run.samples),
                                     "status": [st.name for st in run.result.statuses],
                                     "message": run.result.message} for run in runs]}
    option_record["bounds"] = list(opts.bounds)
    option_record.update(record or {})
    return _dataset(problem, runs, option_record, functions=functions)


def _shooting_branch(start: MultiImpactOrbit | PeriodicOrbit, parameter: str,
                     bounds: Sequence[float], *, detect: Sequence[str] = LABELS,
                     options: ContinuationOptions | None = None, symmetric: bool | None = None,
                     progress: ProgressOption = None, events: dict[str, Any] | None = None,
                     monitors: dict[str, Any] | None = None, **single: Any) -> xr.Dataset:
    """The branch of any motion on the shooting system; the arguments are those of
    :func:`multi_impact_continuation` (`single`: the single options)."""
    orbit = as_multi_impact_orbit(start)
    check_progress(progress)
    labels = check_labels(detect)
    functions = check_user_functions(events, monitors, reserved_names())
    param = model_parameter(orbit.oscillator, parameter)
    if options is not None and "bounds" in getattr(options, "given", ()):
        bounds = options.bounds
    # the drivers' one check (as continuation's): two finite numbers lo < hi in the
    # parameter's range; then the stops' limits; then the oscillator at both ends (an
    # element of K keeps K positive semi-definite)
    bounds = check_model_bounds(parameter, bounds)
    problem, u0 = branch_problem(orbit, parameter, symmetric)
    problem.check_bounds(bounds)
    param.check_bounds(orbit.oscillator, bounds)
    lam0 = problem.param.value(orbit.oscillator)
    opts = make_options(bounds, options, **single)  # ds, ds_max, direction, ...
    problem.check_bounds(opts.bounds)
    if not opts.lam_min <= lam0 <= opts.lam_max:
        raise ParameterError(f"bounds {opts.bounds} must contain the start {parameter}="
                             f"{lam0!r} of the orbit")
    return run_branch(problem, u0, lam0, opts, detect=labels,
                      record={"symmetric": isinstance(problem, SymmetricBranchProblem)},
                      progress=progress, functions=functions, warn_max_points=True)




@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_SHOOTING_DEFAULTS, "direction": 1})
def multi_impact_continuation(start: MultiImpactOrbit | PeriodicOrbit, parameter: str = "omega",
                              bounds: Sequence[float] = (0.5, 6.0), *,
                              detect: Sequence[str] = LABELS,
                              options: ContinuationOptions | None = None,
                              ds: float | None = None, ds_min: float | None = None,
                              ds_max: float | None = None, newton_tol: float | None = None,
                              max_points: int | None = None,
                              both_directions: bool | None = None, direction: int | None = None,
                              symmetric: bool | None = None, progress: ProgressOption = None,
                              events: dict[str, Any] | None = None,
                              monitors: dict[str, Any] | None = None,
                              **more: Any) -> xr.Dataset:
    """Continue the branch of periodic N-p motions through a given motion, on the shooting
    system: :func:`continuation` of the motion (an alias kept for its users).

    Parameters
    ----------
    start : MultiImpactOrbit or PeriodicOrbit
        A motion on the branch (e.g. from :func:`impactcont.orbit.multi_impact.multi_impact_orbit`);
        its oscillator's value of `parameter` is the start.
    parameter : str
        Any continuable parameter of the oscillator
        (:func:`~impactcont.model.parameters.model_parameter`): ``"omega"``, ``"b"``,
        ``"R"``, ``"b_low"``, ``"R_low"``, ``"gap"``, ``"F0"``, a damping parameter or an
        element (``"m2"``, ``"K[1,1]"``, ``"F[2]"``), on any stops (a clearance between
        masses, free masses, a constant force). Motions whose interior contact cannot be
        checked (a constant force pushing a free mode) are reported not physical, said
        once in a log warning and in the branch's message.
    bounds : (float, float)
        Range of the parameter; must contain the start.
    detect : sequence of str
        Special points to detect, subset of :data:`impactcont.vocabulary.LABELS`; GR and
        ZV use the minimum over the flights and impacts.
    options : ContinuationOptions, optional
        Continuation options with ``bounds`` from `bounds` (see ``docs/engine.md``;
        Newton tolerance 1e-11 by default).
    ds, ds_min, ds_max, newton_tol, max_points, both_directions, direction, **more
        Single options, over `options`.
    symmetric : bool, optional
        Follow a symmetric motion of a symmetric two-sided system (``b_low == b``,
        ``R_low == R``; N odd, the pattern's second half the mirror of its first) as
        such: its half-motion closed by the reflection, regular through the
        symmetry-breaking pitchforks, which are located and labelled ``BP``
        (:func:`impactcont.analysis.switching.pitchfork_switch` follows the asymmetric pair born
        there). ``None`` (default): when the start is symmetric and `parameter` keeps
        the system symmetric (not ``b`` or ``R``, unless ``Stops(mirror=True)``).
        ``False``: as any N-p motion (its shooting Jacobian is singular at a pitchfork;
        no BP).
    progress : None, bool or callable
        A progress bar on stderr (``None``: when stderr is a terminal, after 2 s;
        ``True``: always; ``False``: never) or a callable receiving a
        :class:`~impactcont.progress.Progress` record at every point
        (:mod:`impactcont.progress`). A call longer than a minute logs a line a minute.
    events, monitors : mapping of str to callable, optional
        User events and monitors, as for :func:`impactcont.continuation`; their
        functions receive the :class:`~impactcont.MultiImpactOrbit` at a point (the
        full motion on a branch of symmetric motions followed by its half).

    Returns
    -------
    xarray.Dataset
        The branch with an ``impact`` dimension (``docs/multi_impact.md``);
        valid for :func:`impactcont.save`, :func:`impactcont.load` and the plots.

    Warns
    -----
    RuntimeWarning
        When the branch stops at ``max_points`` (in either direction): the rest of it is
        not in the dataset.

    Raises
    ------
    ParameterError
        Bad parameter; bounds not two finite numbers ``lo < hi`` inside the parameter's
        range and where the oscillator takes the parameter at both ends (checked before
        computing: an element of K must keep K positive semi-definite,
        :meth:`~impactcont.model.parameters.ModelParameter.check_bounds`), or not
        containing the start; unknown labels; bounds in ``b``
        that reach ``-b_low`` (the upper stop would meet the lower one); bad `events` or
        `monitors`, or one of their functions failed (named; a non-callable: TypeError).
    NoPeriodicMotionError
        Newton fails at the start.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the call with what it has computed: the branch
    being followed stops at its last accepted point, the special points of the points kept
    are located, and the other direction is not followed. The dataset's ``options``
    attribute then records ``"interrupted": true`` and the stop reason ``"interrupted by the
    user (KeyboardInterrupt) after K points, ..."`` (status ``INTERRUPTED``), also logged at
    WARNING. Ctrl-C while the special points are located keeps those already located and
    drops the one in progress (the log says so). A second Ctrl-C, or one before the first
    point, aborts with :class:`KeyboardInterrupt`.
    The dataset's attribute ``interrupted`` is then 1, as an interrupted map's.
    """
    return continuation(as_multi_impact_orbit(start), parameter=parameter, bounds=bounds,
                        detect=detect, options=options, ds=ds, ds_min=ds_min, ds_max=ds_max,
                        newton_tol=newton_tol, max_points=max_points,
                        both_directions=both_directions, direction=direction,
                        symmetric=symmetric, progress=progress, events=events,
                        monitors=monitors, **more)


def restart_problem(branch: xr.Dataset, row: int, *, special: bool = False
                    ) -> tuple[BranchProblem, np.ndarray, float]:
    """The problem of an N-p branch dataset and the unknowns of one of its motions.

    What a restart of the branch (:func:`impactcont.analysis.branch.continuation_from`,
    :func:`impactcont.analysis.branch.extend`) continues from: the problem the branch was
    followed on (its half system when the options record ``symmetric``) at the
    oscillator of the motion.

    Parameters
    ----------
    branch : xarray.Dataset
        An N-p branch dataset of :func:`multi_impact_continuation` or a switch.
    row : int
        Index of the point (or of the special point with `special`).
    special : bool
        Read the special point `row` (``special_state_k``, ...) instead of a point.

    Returns
    -------
    problem : MultiImpactBranchProblem or SymmetricBranchProblem
    u : ndarray
        The motion's unknowns in `problem` (corrected by the continuation's first
        Newton solve).
    lam : float
        Its value of the continued parameter.
    """
    parameter = str(branch.attrs["parameter"])
    N, p, pattern = int(branch.attrs["N"]), impacts_of(branch), pattern_of(branch)

    def at(name: str) -> Any:
        return branch[special_variable(name) if special else name].values[row]

    base = oscillator_from_dataset(branch)
    osc = base.replace(omega=float(at("omega")), b=float(at("b")))
    if parameter not in ("omega", "b"):
        osc = model_parameter(base, parameter).at(osc, float(at(parameter)))
    guess = {"delta": float(at("delta_k")[0]), "flight_times": at("flight_time_k"),
             "states": at("state_k"), "pattern": pattern}
    if (special_variable("stick_time_k") if special else "stick_time_k") in branch:
        # a motion with sticking phases: its stick times are unknowns too (NaN where no
        # stick follows an impact), as in special_orbit
        guess["stick_times"] = np.nan_to_num(np.asarray(at("stick_time_k"), dtype=float))
    u = initial_unknowns(guess, osc, N, p)
    symmetric = bool(json.loads(branch.attrs.get("options", "{}")).get("symmetric", False))
    lam = model_parameter(osc, parameter).value(osc)
    if symmetric:
        problem: BranchProblem = SymmetricBranchProblem(osc, N, p, parameter, pattern=pattern)
        return problem, problem.half_unknowns(u), lam
    return MultiImpactBranchProblem(osc, N, p, parameter, pattern=pattern or None), u, lam


# -- restart and extension ----------------------------------------------------------------------
def _check_branch(branch: Any) -> xr.Dataset:
    """`branch` if it is a branch dataset (N-1 or N-p), else a clear error."""
    if not isinstance(branch, xr.Dataset):
        raise TypeError(f"branch must be a branch xarray.Dataset (of continuation, "
                        f"multi_impact_continuation or a switch, or impactcont.load of its "
                        f"file); got {type(branch).__name__}")
    what = not_a_branch(branch.attrs)
    if what:
        raise ParameterError(f"branch must be a one-parameter branch dataset (of continuation, "
                             f"multi_impact_continuation or a switch); got {what}")
    try:
        validate_branch_dataset(branch)
    except ValueError as exc:
        raise ParameterError(f"branch is not a branch dataset: {exc}") from None
    return branch


#: What a dataset of impactcont that is not a branch is, by its ``impactcont_dataset``.
_OTHER_DATASETS = {
    "map": "a stability map of N-1 motions (impactcont.stability_map of an oscillator)",
    MULTI_MAP_KIND: "a stability map of a motion's family (impactcont.stability_map of a "
                    "motion)",
    "simulation": "a simulation dataset (impactcont.dataset.simulation.simulation_dataset)",
}


def not_a_branch(attrs: Mapping[str, Any]) -> str:
    """What a dataset with these attributes is when it is not a one-parameter branch (a
    curve, a map, a simulation, ... named by its attributes), else ``""``."""
    tag, parameters = attrs.get("impactcont_dataset"), attrs.get("parameters")
    over = f" over {parameters!r}" if parameters is not None else ""
    if "curve_kind" in attrs:
        return f"a two-parameter curve dataset ({attrs['curve_kind']} curve{over})"
    if tag is not None:
        words = _OTHER_DATASETS.get(tag, f"a dataset of kind {tag!r}")
        return f"{words}{over} (attribute impactcont_dataset={tag!r})"
    return f"a two-parameter dataset{over}" if parameters is not None else ""


def _record(branch: xr.Dataset) -> dict[str, Any]:
    return json.loads(branch.attrs.get("options", "{}"))


def _recorded_options(branch: xr.Dataset, options: ContinuationOptions | None
                      ) -> ContinuationOptions:
    """The branch's recorded options, with those `options` gives over them."""
    if options is not None and not isinstance(options, ContinuationOptions):
        raise ParameterError(f"options must be a ContinuationOptions; got "
                             f"{type(options).__name__}")
    known = {f.name for f in dataclasses.fields(ContinuationOptions) if f.init}
    values = {k: v for k, v in _record(branch).items()
              if k in known and k not in ("bounds", "direction", "both_directions")}
    if options is not None:
        values.update({name: getattr(options, name) for name in options.given})
    return ContinuationOptions(**values)


def _branch_bounds(branch: xr.Dataset) -> tuple[float, float]:
    try:
        lo, hi = _record(branch)["bounds"]
    except (KeyError, ValueError, TypeError):
        raise ParameterError("bounds must be given: the branch's options record no bounds"
                             ) from None
    return float(lo), float(hi)


def _start_row(branch: xr.Dataset, point: Any, label: Any, which: Any) -> tuple[int, bool]:
    """The row to restart from and whether it is a special point's."""
    if (point is None) == (label is None):
        raise ParameterError(f"give either point= (an index of the branch's points) or label= "
                             f"(a special point's label, with which=); got point={point!r}, "
                             f"label={label!r}")
    if point is not None:
        n = branch.sizes["point"]
        if isinstance(point, bool) or not isinstance(point, (int, np.integer)) \
                or not -n <= point < n:
            raise ParameterError(f"point must be an integer index in [{-n}, {n}) (the branch "
                                 f"has {n} points); got {point!r}")
        return int(point) % n, False
    if label not in LABELS:
        raise ParameterError(f"label must be one of {LABELS}; got {label!r}")
    labels = np.asarray(branch[special_variable("label")].values).tolist()
    rows = [k for k, lab in enumerate(labels) if lab == label]
    if isinstance(which, bool) or not isinstance(which, (int, np.integer)) \
            or not -len(rows) <= which < len(rows):
        raise ParameterError(f"which must be an integer index among the branch's "
                             f"{len(rows)} {label} point(s) (its special points: {labels}); "
                             f"got {which!r}")
    return rows[int(which)], True


#: The variables a restart reads at its point (those present: N-p branches have the last three).
_RESTART_VARIABLES = ("omega", "b", "delta", "delta_k", "flight_time_k", "state_k")


def _check_finite_row(branch: xr.Dataset, row: int, special: bool) -> None:
    """Refuse a restart at a point whose values are not finite, naming the file and the point."""
    parameter = str(branch.attrs["parameter"])
    names = dict.fromkeys((*_RESTART_VARIABLES, parameter))
    key = special_variable if special else (lambda name: name)
    bad = {}
    for name in names:
        if key(name) in branch:
            value = np.asarray(branch[key(name)].values[row], dtype=float)
            if not np.all(np.isfinite(value)):
                bad[name] = value
    if not bad:
        return
    source = branch.encoding.get("source")
    where = f" in {str(source)!r}" if source else ""
    what = f"special point {row}" if special else f"point {row}"
    shown = ", ".join(f"{name} = {value.tolist() if value.ndim else float(value)!r}"
                      for name, value in bad.items())
    good = [k for k in range(branch.sizes["special" if special else "point"])
            if all(np.all(np.isfinite(np.asarray(branch[key(n)].values[k], dtype=float)))
                   for n in bad)]
    near = sorted(good, key=lambda k: (abs(k - row), k))[:2]
    hint = f", e.g. {what.split()[0]} {' or '.join(map(str, sorted(near)))}" if near else ""
    raise ParameterError(f"{what} of the branch{where} has non-finite values ({shown}): a "
                         f"restart needs the motion there; allowed: a {what.rsplit(' ', 1)[0]} "
                         f"whose values are all finite{hint}")


def _problem_at(branch: xr.Dataset, row: int, special: bool) -> tuple[Any, np.ndarray, float]:
    """The branch's problem at a point (or special point) and the unknowns there."""
    if "impact" in branch.dims:
        return restart_problem(branch, row, special=special)
    parameter, N = str(branch.attrs["parameter"]), int(branch.attrs["N"])

    def at(name: str) -> float:
        return float(branch[special_variable(name) if special else name].values[row])

    base = oscillator_from_dataset(branch)
    osc = base.replace(omega=at("omega"), b=at("b"))
    if parameter not in ("omega", "b"):
        osc = model_parameter(base, parameter).at(osc, at(parameter))
    lam = model_parameter(osc, parameter).value(osc)
    return PeriodicBranchProblem(osc, N, parameter), np.array([at("delta")]), lam


def _component_rows(branch: xr.Dataset, row: int) -> np.ndarray:
    """The rows of the connected component of point `row` (all rows of an N-p branch)."""
    if "connected_component" not in branch:
        return np.arange(branch.sizes["point"])
    component = branch["connected_component"].values
    return np.flatnonzero(component == component[row])


def _first_step(branch: xr.Dataset, row: int, special: bool, along: int, problem: Any,
                u0: np.ndarray, lam0: float, theta: float) -> tuple[int, float | None]:
    """The core's ``direction`` that leaves the start the way `along` runs the branch, and
    the first step that lands on the branch's next point (None without one).

    The step is the scaled projection of the chord to the next point on the start's
    tangent: the core's first step then lands on that point (within the Newton
    tolerance) and the restarted branch goes on through the points of the branch.
    """
    rows = _component_rows(branch, int(branch[special_variable("point")].values[row])
                           if special else row)
    k = int(branch[special_variable("point")].values[row]) if special else row
    position = int(np.searchsorted(rows, k))
    ahead = position + along
    behind = position - along
    step_exact = not special and 0 <= ahead < rows.size
    if step_exact or (special and 0 <= ahead < rows.size):
        a, b = k, int(rows[ahead])
    elif 0 <= behind < rows.size:
        a, b = int(rows[behind]), k
    else:  # a component of one point: no way along it to follow
        return along, None
    (_, ua, la), (_, ub, lb) = _problem_at(branch, a, False), _problem_at(branch, b, False)
    chord = np.append(ub - ua, lb - la)  # along the way the restart goes
    chord[0] = math.remainder(chord[0], 2 * math.pi)  # delta, the first unknown, is a phase
    accept = getattr(problem, "accept", None)
    if accept is not None:
        accept(u0, lam0)
    extended = np.column_stack([problem.jacobian(u0, lam0), problem.dparam(u0, lam0)])
    tangent = np.linalg.svd(extended)[2][-1]
    weights = np.append(np.full(u0.size, 1.0 / u0.size), theta)
    tangent = tangent / math.sqrt(float(np.sum(weights * tangent * tangent)))
    projection = float(np.sum(weights * tangent * chord))
    if projection < 0:
        tangent, projection = -tangent, -projection
    # the core's rule (PalcStepper._oriented): the sign of dlam, or at a fold the sign of
    # the largest unknown
    if abs(tangent[-1]) > FOLD_DLAM_TOLERANCE * np.max(np.abs(tangent)):
        direction = 1 if tangent[-1] > 0 else -1
    else:
        largest = int(np.argmax(np.abs(tangent[:-1])))
        direction = 1 if tangent[largest] > 0 else -1
    return direction, projection if step_exact else None


def _restart(branch: xr.Dataset, row: int, special: bool, along: int | None,
             bounds: tuple[float, float], detect: Sequence[str] | None,
             options: ContinuationOptions | None, single: dict[str, Any],
             progress: Any, record: dict[str, Any], functions: UserFunctions) -> xr.Dataset:
    """The branch continued from a row of `branch` (one way, or both with `along=None`)."""
    problem, u0, lam0 = _problem_at(branch, row, special)
    parameter = problem.parameter
    lo, hi = bounds
    if not lo <= lam0 <= hi:
        raise ParameterError(f"bounds ({lo!r}, {hi!r}) must contain the restart point "
                             f"{parameter}={lam0!r}")
    detect = check_labels(_record(branch).get("detect", LABELS) if detect is None else detect)
    base = _recorded_options(branch, options)
    direction, step = _first_step(branch, row, special, 1 if along is None else along, problem,
                                  u0, lam0, base.theta)
    user_ds = ("ds" in single and single["ds"] is not None) or (
        options is not None and "ds" in options.given)
    record = {**record, "restart": {**record.get("restart", {}), parameter: lam0}}
    if "impact" in branch.dims:
        opts = driver_options(base, (lo, hi), direction=direction,
                              both_directions=along is None, **single)
        if step is not None and not user_ds:
            opts = dataclasses.replace(opts, ds=min(max(step, opts.ds_min), opts.ds_max))
        symmetric = _record(branch).get("symmetric", False)
        return run_branch(problem, u0, lam0, opts, detect=detect, progress=progress,
                          record={"symmetric": symmetric, **record}, functions=functions,
                          warn_max_points=True)
    _, detect, (lo, hi), opts = check_continuation_arguments(
        problem.osc, problem.N, parameter, (lo, hi), detect=detect, components="start",
        options=base, direction=direction, both_directions=along is None, **single)
    if step is not None and not user_ds:
        opts = dataclasses.replace(opts, ds=min(max(step, opts.ds_min), opts.ds_max))
    with (interruptible(f"continuation in {parameter}"),
          reporter(progress, f"continuation in {parameter}", parameter=parameter) as rep):
        run = _follow(problem, u0, lam0, opts, detect, rep, functions, warn_max_points=True)
        if interrupted():
            record = {**record, "interrupted": True}
    if not run.samples and run.result.interrupted:
        raise NothingComputed(f"continuation in {parameter} interrupted before its first "
                              "point")
    if not run.samples:
        raise NewtonConvergenceError(f"the restart at {parameter}={lam0:.10g} could not be "
                                     f"started: {run.result.message}")
    return _components_dataset(problem, opts, detect, [run], record, functions=functions)


def _check_along(along: Any) -> int | None:
    if along is None or (not isinstance(along, bool) and along in (1, -1)):
        return along
    raise ParameterError(f"along must be +1 (on the way the branch's points run), -1 (the "
                         f"other way) or None (both ways); got {along!r}")


@blas_limited
def continuation_from(branch: xr.Dataset, point: int | None = None, *, label: str | None = None,
                      which: int = 0, along: int | None = 1,
                      bounds: Sequence[float] | None = None,
                      detect: Sequence[str] | None = None,
                      options: ContinuationOptions | None = None,
                      progress: ProgressOption = None, events: dict[str, Any] | None = None,
                      monitors: dict[str, Any] | None = None, **single: Any) -> xr.Dataset:
    """Restart the continuation of a branch from one of its points or special points.

    Works on an N-1 branch (:func:`continuation`) and an N-p branch
    (:func:`~impactcont.analysis.branch.multi_impact_continuation`, a switch), computed
    now or loaded from its file (:func:`impactcont.load`). The motion there is
    corrected by Newton on the problem the branch was followed on (the half system of
    a symmetric N-p branch) and followed with the branch's recorded options (those
    given here over them). From a point the first step lands on the branch's next
    point, so the restarted branch goes through the points of the branch (within the
    Newton tolerance) until it leaves its old bounds or ends as the branch did.

    Parameters
    ----------
    branch : xarray.Dataset
        A one-parameter branch dataset.
    point : int, optional
        Index of the point to restart from (negative counts from the end: ``-1`` is
        the last point).
    label : str, optional
        Instead of `point`: restart from a special point with this label (``"PD"``,
        ``"GR"``, ...), at its located values.
    which : int
        With `label`: which of the points with that label (branch order).
    along : {+1, -1, None}
        ``+1`` (default): on the way the branch's points run (past the point towards
        higher indices; from ``point=-1``, past the end of the branch); ``-1``: the
        other way; ``None``: both ways. The points of an N-1 branch run in each
        connected component's own order.
    bounds : (float, float), optional
        Range of the parameter; default the branch's. Must contain the restart point.
    detect : sequence of str, optional
        Special points to detect; default the branch's.
    options : ContinuationOptions, optional
        Options over the branch's recorded ones.
    progress : None, bool or callable
        See :mod:`impactcont.progress`.
    events, monitors : mapping of str to callable, optional
        User events and monitors on the restarted branch (as for :func:`continuation`).
        Required when `branch` has them (its attributes ``user_events`` and
        ``user_monitors``): their names must be among those given (others may be added).
        Functions are not stored in a file, so they cannot be carried over, and a
        restart without them would lose its events without a word.
    **single
        Single options (``ds``, ``ds_max``, ``max_points``, ...) over `options`.

    Returns
    -------
    xarray.Dataset
        The restarted branch (one component: the one through the restart point), in
        the schema of `branch`; its ``options`` record ``restart`` (the row and the
        parameter value it started from).

    Warns
    -----
    RuntimeWarning
        When the restarted branch stops at ``max_points`` (N-1 or N-p).

    Raises
    ------
    TypeError
        `branch` is not an xarray.Dataset.
    ParameterError
        Not a branch dataset; neither or both of `point` and `label`; a point index out
        of range; no such special point; bad `along`, `bounds` (not containing the
        restart point), `detect` or options; bad `events` or `monitors`, or without a
        name of the branch's.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the call with what it has computed, as in
    :func:`continuation` (see its Notes): the other direction is not followed.
    """
    _check_branch(branch)
    functions = _same_user_functions(branch, events, monitors, more=True)
    along = _check_along(along)
    row, special = _start_row(branch, point, label, which)
    parameter = str(branch.attrs["parameter"])
    _check_finite_row(branch, row, special)
    lo, hi = _branch_bounds(branch) if bounds is None else check_model_bounds(parameter,
                                                                                  bounds)
    record = {"restart": {"point": None if special else row, "label": label,
                          "which": which if special else None, "along": along}}
    return _restart(branch, row, special, along, (lo, hi), detect, options, single, progress,
                    record, functions)


@blas_limited
def extend(branch: xr.Dataset, bounds: Sequence[float], *, detect: Sequence[str] | None = None,
           options: ContinuationOptions | None = None, progress: ProgressOption = None,
           events: dict[str, Any] | None = None, monitors: dict[str, Any] | None = None,
           **single: Any) -> xr.Dataset:
    """A branch continued past its bounds: the branch and its continuations joined.

    Every end of the branch (of each connected component of an N-1 branch) that lies on
    one of its bounds is continued from there (:func:`continuation_from`) until the new
    `bounds`, and the new points are joined to the branch: one dataset, the points in
    branch order, the special points of the branch and of the new parts, the point at
    the join once. Ends inside the bounds (a fold of the component, a closed loop, the
    motion a switched branch was born from, ``max_points``) are left as they are.

    Parameters
    ----------
    branch : xarray.Dataset
        A one-parameter branch dataset (N-1 or N-p), computed or loaded.
    bounds : (float, float)
        The new range of the parameter: contains the branch's bounds and goes past at
        least one of them.
    detect : sequence of str, optional
        Special points to detect on the new parts; default the branch's.
    options : ContinuationOptions, optional
        Options over the branch's recorded ones.
    progress : None, bool or callable
        See :mod:`impactcont.progress` (one bar over all the new parts).
    events, monitors : mapping of str to callable, optional
        The user events and monitors of `branch` (its attributes ``user_events`` and
        ``user_monitors``), with the same names: functions are not stored in a file,
        and the new parts need them to be joined. Required when `branch` has them.
    **single
        Single options (``ds``, ``ds_max``, ``max_points``, ...) over `options`.

    Returns
    -------
    xarray.Dataset
        The extended branch in the schema of `branch`; its ``options`` record the new
        ``bounds`` and, in ``extended``, each end continued.

    Warns
    -----
    RuntimeWarning
        When a new part stops at ``max_points`` (its end is then left there).

    Raises
    ------
    TypeError
        `branch` is not an xarray.Dataset.
    ParameterError
        Not a branch dataset; `bounds` not two numbers that contain the branch's bounds
        and reach past them; bad `detect` or options; `events` or `monitors` with other
        names than the branch's.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the part being computed at its last accepted
    point (see :func:`continuation`); the branch is returned joined with the parts
    computed, the ends not yet continued are left as they are, and its ``options``
    record ``"interrupted": true``. A second Ctrl-C aborts.
    The dataset's attribute ``interrupted`` is then 1, as an interrupted map's.
    """
    _check_branch(branch)
    functions = _same_user_functions(branch, events, monitors)
    parameter = str(branch.attrs["parameter"])
    old = _branch_bounds(branch)
    lo, hi = check_model_bounds(parameter, bounds)
    if not (lo <= old[0] and hi >= old[1] and (lo, hi) != old):
        raise ParameterError(f"bounds must contain the branch's bounds {list(old)} and reach "
                             f"past at least one of them; got {bounds!r}")
    lam = np.asarray(branch[parameter].values, dtype=float)
    parts: dict[tuple[int, int], xr.Dataset] = {}
    extended = []
    with (interruptible(f"extension in {parameter}"),
          reporter(progress, f"extension in {parameter}", parameter=parameter) as rep):
        for rows in _components(branch):
            for end, along in ((int(rows[-1]), 1), (int(rows[0]), -1)):
                if (rows.size == 1 and along == -1) or interrupted():
                    break
                if not ((lam[end] == old[1] and hi > old[1])
                        or (lam[end] == old[0] and lo < old[0])):
                    continue
                try:
                    part = _restart(branch, end, False, along, (lo, hi), detect, options,
                                    single, rep, {"restart": {"point": end, "along": along}},
                                    functions)
                except NothingComputed:  # Ctrl-C before its first point: the rest is kept
                    break
                parts[(int(rows[0]), along)] = part
                info = _record(part)
                extended.append({"from_point": end, parameter: float(lam[end]),
                                 "along": along, "points": part.sizes["point"] - 1,
                                 "status": info.get("status"), "message": info.get("message")})
        was_interrupted = interrupted()
    if not parts:
        log.info("extend: no end of the branch lies on a bound it moves past: unchanged")
    joined = _join(branch, parts)
    record = _record(branch)
    record["bounds"] = [lo, hi]
    if was_interrupted:
        record["interrupted"] = True
        joined.attrs["interrupted"] = 1
    record["extended"] = record.get("extended", []) + extended
    joined.attrs["options"] = json.dumps(record, sort_keys=True)
    return joined


def _same_user_functions(branch: xr.Dataset, events: Any, monitors: Any, *,
                         more: bool = False) -> UserFunctions:
    """The user's functions for a restart or an extension of `branch`: checked, with the
    branch's names (and others too with `more`: a restart is a new branch, an extension
    is joined to the old one)."""
    functions = check_user_functions(events, monitors, reserved_names())
    for what, attr, given in (("events", USER_EVENTS_ATTR, functions.events),
                              ("monitors", USER_MONITORS_ATTR, functions.monitors)):
        names = [name for name in str(branch.attrs.get(attr, "")).split(",") if name]
        refused = (not set(names) <= set(given)) if more else sorted(names) != sorted(given)
        if refused:
            allowed = "with those names (others may be added)" if more else "with those names"
            raise ParameterError(f"{what} must have the names of the branch's {what} {names} "
                                 f"(attribute {attr!r}: functions are not stored, the new "
                                 f"points need them); got {sorted(given)}; allowed: a mapping "
                                 f"{allowed}")
    return functions


def _components(branch: xr.Dataset) -> list[np.ndarray]:
    """The rows of each connected component, in dataset order."""
    if "connected_component" not in branch:
        return [np.arange(branch.sizes["point"])]
    component = branch["connected_component"].values
    return [np.flatnonzero(component == c) for c in dict.fromkeys(component.tolist())]


def _join(branch: xr.Dataset, parts: dict[tuple[int, int], xr.Dataset]) -> xr.Dataset:
    """`branch` with the new parts before (``along = -1``) and after (``+1``) components.

    A part starts with the point it was continued from (the component's end), which is
    left out; its special points (and user events) get the index of their nearest point
    in the join.
    """
    point_vars = [k for k, v in branch.variables.items() if "point" in v.dims and k != "point"]
    # the rows on ``special`` (and ``event``) with the variable holding their nearest point
    indexed = {dim: index for dim, index in (("special", special_variable("point")),
                                              ("event", event_variable("point")))
               if dim in branch.dims}
    row_vars = {dim: [k for k, v in branch.variables.items() if dim in v.dims and k != index]
                for dim, index in indexed.items()}
    pieces: list[tuple[xr.Dataset, np.ndarray]] = []  # (dataset, rows) in joined order
    arclength: list[np.ndarray] = []
    # per dimension: (ds, rows, new index of their nearest point)
    rows_of: dict[str, list[tuple[xr.Dataset, np.ndarray, np.ndarray]]] = {d: [] for d in indexed}
    old_index = {dim: branch[index].values for dim, index in indexed.items()}
    offset = 0
    for rows in _components(branch):
        front, back = parts.get((int(rows[0]), -1)), parts.get((int(rows[0]), 1))
        arcs = []
        if front is not None:
            nf = front.sizes["point"] - 1
            order = np.arange(nf, 0, -1)
            pieces.append((front, order))
            arcs.append(-front["arclength"].values[order])
            for dim, index in indexed.items():
                rows_of[dim].append((front, np.arange(front.sizes[dim]),
                                     offset + nf - front[index].values))
            offset += nf
        pieces.append((branch, rows))
        arcs.append(branch["arclength"].values[rows] - branch["arclength"].values[rows[0]])
        for dim in indexed:
            mine = np.flatnonzero(np.isin(old_index[dim], rows))
            rows_of[dim].append((branch, mine,
                                 offset + np.searchsorted(rows, old_index[dim][mine])))
        offset += rows.size
        if back is not None:
            nb = back.sizes["point"] - 1
            pieces.append((back, np.arange(1, nb + 1)))
            arcs.append(arcs[-1][-1] + back["arclength"].values[1:])
            for dim, index in indexed.items():
                rows_of[dim].append((back, np.arange(back.sizes[dim]),
                                     offset - 1 + back[index].values))
            offset += nb
        joined_arcs = np.concatenate(arcs)
        arclength.append(joined_arcs - joined_arcs[0])
    out = branch.drop_vars([*point_vars, *(k for names in row_vars.values() for k in names),
                            *indexed.values(), "point"])
    for name in point_vars:
        var = branch[name]
        axis = var.dims.index("point")
        data = np.concatenate([np.take(ds[name].values, rows, axis=axis)
                               for ds, rows in pieces], axis=axis)
        out[name] = xr.Variable(var.dims, data, var.attrs)
    out["arclength"] = xr.Variable(("point",), np.concatenate(arclength),
                                   branch["arclength"].attrs)
    if "connected_component" in branch:
        component = branch["connected_component"]
        ids = np.array(list(dict.fromkeys(component.values.tolist())))
        out["connected_component"] = xr.Variable(
            ("point",), np.repeat(ids, _piece_counts(branch, parts)).astype(component.dtype),
            component.attrs)
    for dim, index_var in indexed.items():
        new_index = np.concatenate([index for _, _, index in rows_of[dim]])
        order = np.argsort(new_index, kind="stable")
        for name in row_vars[dim]:
            var = branch[name]
            data = np.concatenate([np.take(ds[name].values, rows, axis=0)
                                   for ds, rows, _ in rows_of[dim]], axis=0)[order]
            out[name] = xr.Variable(var.dims, data, var.attrs)
        out[index_var] = xr.Variable((dim,), new_index[order].astype(branch[index_var].dtype),
                                     branch[index_var].attrs)
    n = out.sizes["point"]
    out = out.assign_coords(point=xr.Variable(("point",), np.arange(n), branch["point"].attrs))
    out = out.set_coords([k for k in branch.coords if k in out.data_vars])
    return out[list(branch.data_vars)].assign_attrs(branch.attrs)


def _piece_counts(branch: xr.Dataset, parts: dict[tuple[int, int], xr.Dataset]) -> list[int]:
    """Points of each component after the join."""
    return [rows.size + sum(parts[(int(rows[0]), along)].sizes["point"] - 1
                            for along in (-1, 1) if (int(rows[0]), along) in parts)
            for rows in _components(branch)]

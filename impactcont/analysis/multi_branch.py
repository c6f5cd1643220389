"""One-parameter branches of periodic N-p motions: continuation, detection, dataset.

``multi_impact_continuation(orbit, parameter, bounds)`` = start on an N-p motion
-> follow the shooting system of :mod:`impactcont.orbit.multi_impact` with the
pseudo-arclength core -> evaluate every accepted point (states, G, multipliers,
checks on every flight) -> detect and locate SN, PD, NS, GR, ZV (and BP on a
branch of symmetric motions, followed as their half-motion) -> an
:class:`xarray.Dataset` in the branch schema with an ``impact`` dimension
(:mod:`impactcont.dataset.multi`).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
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
from impactcont.core.options import DRIVER_DEFAULTS, driver_options, option_keywords
from impactcont.dataset.multi import impacts_of, multi_impact_dataset, pattern_of
from impactcont.dataset.records import (
    orbit_columns,
    reserved_names,
    special_record,
    user_event_record,
)
from impactcont.dataset.schema import (
    add_user_functions,
    oscillator_from_dataset,
    parameter_names,
    special_variable,
)
from impactcont.detection.points import SpecialPoint
from impactcont.detection.special_points import (
    BranchSample,
    UserFunctions,
    check_user_functions,
    detect_special_points,
    locate_sample_events,
    user_values,
)
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.parameters import model_parameter
from impactcont.orbit.multi_impact import MultiImpactOrbit, initial_unknowns, multi_impact_orbit
from impactcont.orbit.periodic import PeriodicOrbit
from impactcont.orbit.symmetry import admits_symmetric_motions, symmetry_defect
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
    until_interrupted,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import LABELS, check_bounds, check_labels

__all__ = ["multi_impact_continuation", "restart_problem"]

#: The sample of an N-p branch: the one sample of every motion (a name kept for its users).
MultiImpactSample = BranchSample

#: The problem of an N-p branch: any N-p motion, or a symmetric one by its half.
BranchProblem = MultiImpactBranchProblem | SymmetricBranchProblem

log = logging.getLogger(__name__)


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


_DEFAULTS = {"newton_tol": 1e-11}
"""The shooting residual of a long motion is accurate to about 1e-12."""


def make_options(bounds: Sequence[float], options: ContinuationOptions | None = None,
                 **keywords: Any) -> ContinuationOptions:
    """The options of an N-p branch: the drivers' defaults < `options` < `keywords`.

    See :func:`impactcont.core.options.driver_options`; ``None`` keywords are not given.
    """
    lo, hi = (float(v) for v in bounds)
    return driver_options(options, (lo, hi), defaults=_DEFAULTS, **keywords)


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
    """The stop rule of one direction of an N-p branch; keeps the orbit of every kept point.

    Stops when the branch returns to the motion it was born from (the N/2-p/2
    motion repeated twice, or its mirror image: that point is left out) and,
    with `stop_after_pd`, that many points after the first sign change of the
    PD test function.
    """

    def __init__(self, problem: BranchProblem, stop_after_pd: int | None,
                 on_point: Callable[[MultiImpactOrbit], None] | None) -> None:
        self.problem = problem
        self.stop_after_pd = stop_after_pd
        self.on_point = on_point
        self.orbits: list[MultiImpactOrbit] = []
        self.reference: np.ndarray | None = None
        self.remaining: int | None = None

    def __call__(self, previous: ContinuationPoint | None, current: ContinuationPoint
                 ) -> Stop | None:
        problem = self.problem
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


def trace_branch(problem: BranchProblem, u0: np.ndarray, lam0: float,
                 options: ContinuationOptions, *, stop_after_pd: int | None = None,
                 on_point: Callable[[MultiImpactOrbit], None] | None = None,
                 progress: Reporter | None = None,
                 ) -> tuple[list[BranchSample], list[str], str]:
    """Follow a branch (one or both directions) and return its samples in branch order.

    Parameters
    ----------
    problem : MultiImpactBranchProblem
    u0 : ndarray
        Unknowns at the start (corrected at fixed ``lam0``).
    lam0 : float
    options : ContinuationOptions
        ``direction`` and ``both_directions`` are honoured.
    stop_after_pd : int, optional
        Stop a direction this many points after the first sign change of the
        PD test function (saves following a cascade branch to the bound).
    on_point : callable, optional
        Called with the orbit of every accepted point.
    progress : Reporter, optional
        Counts every accepted point (:mod:`impactcont.progress`).

    Returns
    -------
    samples : list of BranchSample
    statuses : list of str
        Why each direction stopped (names of
        :class:`~impactcont.core.ContinuationStatus`).
    message : str
    """
    watches: dict[int, _Watch] = {}

    def watch(direction: int) -> _Watch:
        watches[direction] = _Watch(problem, stop_after_pd, on_point)
        return watches[direction]

    options, limit = _within_limits(problem, options)
    result = follow(problem, u0, lam0, options, None if progress is None else progress.point,
                    stop=watch)
    # Ctrl-C can end a run between a watch's orbit and the core's taking of the point
    forward = watches[options.direction].orbits[:len(result) - result.start_index]
    if not forward and result.interrupted:
        raise NothingComputed(f"continuation of {problem.N}-{problem.p} motions interrupted "
                              "before its first point")
    if not forward:
        raise NoPeriodicMotionError(f"N={problem.N}, p={problem.p}: {result.message}")
    message = result.message
    if limit is not None and any(problem.param.value(o.oscillator) == limit
                                 for w in watches.values() for o in w.orbits[-1:]):
        message += (f"; the branch ends at {problem.parameter} = {limit!r}, ds_min from the "
                    f"end of its range: {problem.limit_reason()}")
    orbits = forward
    if -options.direction in watches:
        orbits = watches[-options.direction].orbits[result.start_index:0:-1] + forward
    samples = [BranchSample(u=u, lam=float(lam), tangent=t, orbit=o)
               for u, lam, t, o in zip(result.u, result.lam, result.tangent, orbits, strict=True)]
    return samples, [st.name for st in result.statuses], message


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


def branch_to_dataset(problem: BranchProblem, samples: Sequence[BranchSample],
                      specials: Sequence[SpecialPoint], options: Mapping[str, Any],
                      *, title: str | None = None,
                      extra_attrs: Mapping[str, Any] | None = None,
                      extra_columns: Sequence[str] = (),
                      functions: UserFunctions | None = None,
                      values: Mapping[str, np.ndarray] | None = None,
                      user_events: Sequence[SpecialPoint] = ()) -> xr.Dataset:
    """The N-p branch dataset of :mod:`impactcont.dataset.multi` from samples and special points.

    `extra_columns` are further oscillator parameters stored per point (the first
    parameter of a two-parameter curve). With `functions` (the user's events and
    monitors), `values` (each function at every sample) and `user_events` (the located
    zeros) are stored (:func:`~impactcont.dataset.schema.add_user_functions`).
    """
    orbits = [s.orbit for s in samples]
    parameter = problem.parameter
    x = np.array([np.append(s.u, s.lam) for s in samples])
    steps = np.sqrt(np.sum(np.diff(x, axis=0) ** 2, axis=1)) if len(samples) > 1 else []
    columns = {**orbit_columns(orbits, parameter, [s.lam for s in samples]),
               "arclength": np.concatenate([[0.0], np.cumsum(steps)])}
    for name in extra_columns:
        columns.setdefault(name, np.array([model_parameter(o.oscillator, name).value(
            o.oscillator) for o in orbits]))  # an element, an extra stop's gap: by its object
    impact_columns = {
        "delta_k": np.array([o.phases for o in orbits]),
        "impact_velocity_k": np.array([o.impact_velocities for o in orbits]),
        "flight_time_k": np.array([o.flight_times for o in orbits]),
        "gap_min_k": np.array([o.flight_gap_min for o in orbits]),
        "state_k": np.array([o.states for o in orbits]),
    }
    special_points = [special_record(sp, parameter, point=sp.point, bracket=sp.bracket)
                      for sp in specials]
    n, p = problem.osc.n, problem.p
    special_impact_columns = {
        "delta_k": np.array([sp.orbit.phases for sp in specials]).reshape(-1, p),
        "impact_velocity_k": np.array([sp.orbit.impact_velocities for sp in specials]
                                      ).reshape(-1, p),
        "flight_time_k": np.array([sp.orbit.flight_times for sp in specials]).reshape(-1, p),
        "state_k": np.array([sp.orbit.states for sp in specials]).reshape(-1, p, 2 * n),
    }
    ds = multi_impact_dataset(parameter=parameter, N=problem.N, p=p, oscillator=problem.osc,
                              options=dict(options), columns=columns,
                              impact_columns=impact_columns, special_points=special_points,
                              special_impact_columns=special_impact_columns, title=title,
                              extra_attrs=extra_attrs, pattern=problem.pattern)
    if options.get("interrupted"):  # Ctrl-C: as an interrupted map says it
        ds.attrs["interrupted"] = 1
    if not functions:
        return ds
    names = parameter_names(ds)
    return add_user_functions(ds, monitors=dict(values or {}), events=list(functions.events),
                              event_points=[user_event_record(ev, names) for ev in user_events])


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


def run_branch(problem: BranchProblem, u0: np.ndarray, lam0: float,
           options: ContinuationOptions, *, detect: Sequence[str] = LABELS,
           stop_after_pd: int | None = None, record: Mapping[str, Any] | None = None,
           extra_attrs: Mapping[str, Any] | None = None,
           progress: ProgressOption | Reporter = None,
           functions: UserFunctions | None = None) -> xr.Dataset:
    """Trace, detect and assemble: the dataset of the branch through ``(u0, lam0)``.

    `progress` is a driver's ``progress=`` option or the reporter of an enclosing call
    (:func:`impactcont.progress.reporter`); `functions` the user's events and monitors
    (:func:`~impactcont.detection.special_points.check_user_functions`).
    """
    labels = check_labels(detect)
    problem.check_bounds(options.bounds)
    what = f"continuation of {problem.N}-{problem.p} motions in {problem.parameter}"
    with interruptible(what), reporter(progress, what, parameter=problem.parameter) as rep:
        samples, statuses, message = trace_branch(problem, u0, lam0, options,
                                                  stop_after_pd=stop_after_pd, progress=rep)
        specials = until_interrupted(
            lambda: detect_special_points(problem, samples, labels), [], "location",
            "interrupted by the user (KeyboardInterrupt) while locating the special points of "
            "the %d-%d branch: they are dropped", problem.N, problem.p)
        values, user_events = user_events_until_interrupted(problem, samples, functions)
        if interrupted():
            record = {**(record or {}), "interrupted": True}
    log.info("N=%d p=%d branch in %s: %d points, %d special (%s)", problem.N, problem.p,
             problem.parameter, len(samples), len(specials), message)
    option_record = {**dataclasses.asdict(options), "N": problem.N, "p": problem.p,
                     "parameter": problem.parameter, "start": float(lam0),
                     "start_delta": float(u0[0]), "detect": labels, "status": statuses,
                     "message": message, **(record or {})}
    option_record["bounds"] = list(options.bounds)
    return branch_to_dataset(problem, samples, specials, option_record,
                             extra_attrs=extra_attrs, functions=functions, values=values,
                             user_events=user_events)


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
    if symmetric is None:
        symmetric = (model_parameter(orbit.oscillator, parameter).keeps_symmetry
                     and admits_symmetric_motions(orbit.oscillator, orbit.N, orbit.p,
                                                  orbit.pattern or "")
                     and symmetry_defect(orbit) <= _SYMMETRY_TOL)
    elif not isinstance(symmetric, (bool, np.bool_)):
        raise ParameterError(f"symmetric must be True, False or None (decide from the motion); "
                             f"got {symmetric!r}")
    if not symmetric:
        problem = MultiImpactBranchProblem(orbit.oscillator, orbit.N, orbit.p, parameter,
                                           pattern=pattern)
        return problem, orbit.unknowns
    sym = SymmetricBranchProblem(orbit.oscillator, orbit.N, orbit.p, parameter,
                                 pattern=orbit.pattern)
    defect = symmetry_defect(orbit)
    if not defect <= _SYMMETRY_TOL:
        raise ParameterError(f"symmetric=True: the N={orbit.N}, p={orbit.p} motion is not "
                             f"symmetric (X_(k+p/2) + X_k, tau_(k+p/2) - tau_k up to {defect:.3g} "
                             f"relative, allowed {_SYMMETRY_TOL:g}); give symmetric=False or a "
                             "symmetric motion")
    return sym, sym.half_unknowns(orbit.unknowns)


_SYMMETRY_TOL = 1e-8


@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_DEFAULTS, "direction": 1})
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
    """Continue the branch of periodic N-p motions through a given motion.

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
    bounds = check_bounds(parameter, bounds)
    problem, u0 = branch_problem(orbit, parameter, symmetric)
    problem.check_bounds(bounds)
    param.check_bounds(orbit.oscillator, bounds)
    lam0 = problem.param.value(orbit.oscillator)
    opts = make_options(bounds, options, ds=ds, ds_min=ds_min, ds_max=ds_max,
                        newton_tol=newton_tol, max_points=max_points,
                        both_directions=both_directions, direction=direction, **more)
    problem.check_bounds(opts.bounds)
    if not opts.lam_min <= lam0 <= opts.lam_max:
        raise ParameterError(f"bounds {opts.bounds} must contain the start {parameter}="
                             f"{lam0!r} of the orbit")
    return run_branch(problem, u0, lam0, opts, detect=labels,
                      record={"symmetric": isinstance(problem, SymmetricBranchProblem)},
                      progress=progress, functions=functions)


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
    u = initial_unknowns({"delta": float(at("delta_k")[0]), "flight_times": at("flight_time_k"),
                          "states": at("state_k"), "pattern": pattern}, osc, N, p)
    symmetric = bool(json.loads(branch.attrs.get("options", "{}")).get("symmetric", False))
    lam = model_parameter(osc, parameter).value(osc)
    if symmetric:
        problem: BranchProblem = SymmetricBranchProblem(osc, N, p, parameter, pattern=pattern)
        return problem, problem.half_unknowns(u), lam
    return MultiImpactBranchProblem(osc, N, p, parameter, pattern=pattern or None), u, lam

"""One-parameter branches of periodic N-1 motions: continuation, detection, dataset.

``continuation(osc, N, parameter, bounds)`` = pick a start root of eq. (15)
-> follow eq. (14) with the pseudo-arclength core -> evaluate every accepted
point (state, G, multipliers, checks) -> detect and locate the special points
-> an :class:`xarray.Dataset` in the schema of :mod:`impactcont.dataset`.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from scipy.optimize import minimize_scalar

from impactcont.analysis.multi_branch import (
    multi_impact_continuation,
    restart_problem,
    run_branch,
)
from impactcont.core import ContinuationOptions, ContinuationStatus, continue_branch
from impactcont.core.options import DRIVER_DEFAULTS, driver_options, option_keywords
from impactcont.core.stepper import FOLD_DLAM_TOLERANCE, NewtonConvergenceError
from impactcont.dataset import branch_dataset
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
from impactcont.detection import BranchSample, SpecialPoint, detect_special_points
from impactcont.detection.special_points import (
    UserFunctions,
    check_user_functions,
    locate_user_events,
    user_values,
)
from impactcont.errors import ImpactcontError, NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import RESTITUTION, model_parameter
from impactcont.orbit.multi_impact import MultiImpactOrbit
from impactcont.orbit.periodic import PeriodicOrbit, _check_N, periodic_orbits
from impactcont.problems import PeriodicBranchProblem
from impactcont.progress import (
    NothingComputed,
    ProgressOption,
    Reporter,
    interrupted,
    interruptible,
    reporter,
    take_interrupt,
    until_interrupted,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import LABELS, check_bounds, check_labels

__all__ = ["check_continuation_arguments", "continuation", "continuation_from", "extend"]

log = logging.getLogger(__name__)

_DEFAULTS = {"newton_tol": 1e-12}
"""The closed form is exact to rounding: a tighter Newton tolerance than the other drivers'."""
_EXISTENCE_SCAN = 400
_SAME_ROOT = 0.05  # rad: a seed this close to a computed point of a component lies on it


def _refuse_elastic(osc: ImpactOscillator, parameter: str, lo: float, hi: float) -> None:
    """Refuse a range that reaches elastic impacts without damping (R = 1, C = 0).

    There eq. (12) is singular and eq. (14) is replaced by ``x1p'(delta) = 0``
    (``docs/kernel.md``): the branch equation changes, so a branch cannot be followed
    into that case; :func:`impactcont.periodic_orbits` solves it point by point.
    """
    if osc.general_damping:  # only whether the damping vanishes matters here
        alpha, beta = (1.0 if np.any(osc.C) else 0.0), 0.0
    else:
        alpha, beta = osc.rayleigh
    undamped = {"eta": lo == 0.0, "alpha": lo == 0.0 and beta == 0.0,
                "beta": lo == 0.0 and alpha == 0.0}.get(parameter, alpha == 0.0 and beta == 0.0)
    param = model_parameter(osc, parameter)
    # a parameter that is the stop's restitution (eq. 4) reaches R = 1 at hi >= 1
    elastic = hi >= 1.0 if param.data == RESTITUTION and param.upper else osc.R == 1.0
    if undamped and elastic:
        raise ParameterError(
            f"continuation in {parameter} over [{lo!r}, {hi!r}] reaches elastic impacts without "
            "damping (R = 1, no damping), where eq. (12) is singular and the motions obey "
            "another equation; use periodic_orbits at each value there, add damping or keep "
            "R below 1")


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
        A bad option (named; a ParameterError).
    """
    N = _check_N(N)
    detect = check_labels(detect)
    problem = PeriodicBranchProblem(osc, N, parameter)
    if options is not None and "bounds" in getattr(options, "given", ()):
        bounds = options.bounds
    # the shared check, then both ends on the oscillator (an element of K keeps K PSD)
    lo, hi = problem.param.check_bounds(osc, bounds)
    _refuse_elastic(osc, parameter, lo, hi)
    opts = driver_options(options, (lo, hi), defaults=_DEFAULTS, **single)
    if components not in ("all", "start"):
        raise ParameterError(f"components must be 'all' or 'start'; got {components!r}")
    return problem, detect, (lo, hi), opts


def _start_value(problem: PeriodicBranchProblem, bounds: tuple[float, float],
                 start: float | None) -> float:
    lo, hi = bounds
    if start is not None:
        if not lo <= start <= hi:
            raise ParameterError(f"start must lie within bounds {bounds}; got {start!r}")
        return float(start)
    current = problem.param.value(problem.osc)
    candidates = [current] if lo <= current <= hi else []
    candidates += list(np.linspace(lo, hi, _EXISTENCE_SCAN))
    for lam in candidates:
        c, s, b = problem.amplitude(float(lam))
        if c * c + s * s >= b * b:
            return float(lam)
    raise NoPeriodicMotionError(
        f"no N={problem.N} motion anywhere in {problem.parameter} in {bounds} "
        f"(c^2 + s^2 < b^2 at all {_EXISTENCE_SCAN} values scanned)")


def _start_root(problem: PeriodicBranchProblem, lam: float, root: int | None) -> float:
    orbits = periodic_orbits(problem.oscillator_at(lam), problem.N)
    if not orbits:
        raise NoPeriodicMotionError(f"no N={problem.N} motion at {problem.parameter}={lam!r}")
    if root is not None:
        if root not in (1, -1):
            raise ParameterError(f"root must be +1, -1 or None; got {root!r}")
        chosen = [o for o in orbits if o.root == root] or orbits
    else:
        chosen = sorted(orbits, key=lambda o: (not o.physical, not o.stable))
    return chosen[0].delta


def _motion_branch(motion: PeriodicOrbit | MultiImpactOrbit, N: int, parameter: str,
                   bounds: Sequence[float], *, start: float | None, root: int | None,
                   components: str, **keywords: Any) -> xr.Dataset:
    """The branch through a computed motion (:func:`continuation` given a motion).

    An N-1 motion of the paper's system in a parameter of eq. (14) is followed on the
    closed form (the exact, fast path: its component through the motion's root); any
    other motion or parameter by :func:`impactcont.multi_impact_continuation`.
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
    return multi_impact_continuation(motion, parameter, bounds, **keywords)


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
    """Continue the branch of periodic N-1 motions in one parameter and find its special points.

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
        goes through the start); ``"start"``: only the component through the start.
    options : ContinuationOptions, optional
        Continuation options with ``bounds`` from `bounds` (see ``docs/engine.md``;
        Newton tolerance 1e-12 by default: the closed form is exact to rounding).
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
    problem, detect, (lo, hi), opts = check_continuation_arguments(
        osc, N, parameter, bounds, detect=detect, components=components, options=options,
        ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol, max_points=max_points,
        both_directions=both_directions, **more)
    functions = check_user_functions(events, monitors, reserved_names())
    N = problem.N
    lam0 = _start_value(problem, (lo, hi), start)
    delta0 = _start_root(problem, lam0, root)
    record: dict[str, Any] | None = None
    with (interruptible(f"continuation in {parameter}") as call,
          reporter(progress, f"continuation in {parameter}", parameter=parameter) as rep):
        runs = [_follow(problem, lam0, delta0, opts, detect, rep, functions)]
        if components == "all" and not interrupted():
            try:
                for lam, delta in _component_seeds(problem, (lo, hi)):
                    if not any(_passes(run, lam, delta) for run in runs):
                        runs.append(_follow(problem, lam, delta, opts, detect, rep, functions))
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
    return _branch_dataset(problem, osc, opts, detect, started, record, functions=functions)


@dataclasses.dataclass(frozen=True, eq=False)
class _Run:
    """One connected component: its continuation result, samples, special points and the
    user's functions at its points (``values``) and located events."""

    start: float
    start_delta: float
    result: Any
    samples: list[BranchSample]
    specials: list[SpecialPoint]
    values: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    events: list[SpecialPoint] = dataclasses.field(default_factory=list)


def _follow(problem: PeriodicBranchProblem, lam0: float, delta0: float,
            opts: ContinuationOptions, detect: Sequence[str], rep: Reporter | None = None,
            functions: UserFunctions | None = None) -> _Run:
    result = continue_branch(problem, np.array([delta0]), lam0, opts,
                             None if rep is None else rep.point)
    log.info("N=%d branch in %s from %s=%.10g: %d points (%s)", problem.N, problem.parameter,
             problem.parameter, lam0, len(result), result.message)
    if ContinuationStatus.MAX_POINTS_REACHED in result.statuses:
        warnings.warn(f"the N={problem.N} component through {problem.parameter}={lam0:.10g} "
                      f"stopped at max_points={opts.max_points}: the rest of it is not in the "
                      "branch; raise max_points or ds_max", RuntimeWarning, stacklevel=4)
    samples = [BranchSample(u=u, lam=float(lam), tangent=t, orbit=problem.orbit(u, float(lam)))
               for u, lam, t in zip(result.u, result.lam, result.tangent, strict=True)]
    where = f"the N={problem.N} component through {problem.parameter}={lam0:.10g}"
    specials = until_interrupted(
        lambda: detect_special_points(problem, samples, detect), [], "location",
        "interrupted by the user (KeyboardInterrupt) while locating the special points of "
        "%s: they are dropped, those of the components before it kept", where)
    if not functions:
        return _Run(lam0, delta0, result, samples, specials)
    values = user_values(functions, [s.orbit for s in samples], problem.parameter)
    events = until_interrupted(
        lambda: locate_user_events(problem, [s.u for s in samples],
                                   [s.lam for s in samples], [s.tangent for s in samples],
                                   functions, values, problem.orbit,
                                   parameter=problem.parameter),
        [], "location", "interrupted by the user (KeyboardInterrupt) while locating the user "
        "events of %s: they are dropped", where)
    return _Run(lam0, delta0, result, samples, specials, values, events)


def _component_seeds(problem: PeriodicBranchProblem, bounds: tuple[float, float]
                     ) -> list[tuple[float, float]]:
    """Both roots of eq. (15) at the best-separated scan value of every existence interval.

    Motions exist where ``c^2 + s^2 >= b^2`` (eq. 15); each maximal interval of scan
    values where they do holds one or two connected components of the solution set
    (the roots join at the folds that end the interval, or run to the bounds apart).
    Between scan values the discriminant is maximised wherever it has a local maximum
    below 0, so an interval narrower than the scan step is found too.
    """
    def discriminant(lam: float) -> float:
        c, s, b = problem.amplitude(lam)
        return c * c + s * s - b * b

    lams = list(np.linspace(bounds[0], bounds[1], _EXISTENCE_SCAN))
    disc = [discriminant(float(lam)) for lam in lams]
    # a component narrower than the scan step shows as a local maximum of the
    # discriminant below 0 between scan values: maximise it there and keep it if >= 0
    for k in range(len(lams) - 2, 0, -1):
        if disc[k] < 0 and disc[k] >= disc[k - 1] and disc[k] >= disc[k + 1]:
            best = minimize_scalar(lambda x: -discriminant(x), bounds=(lams[k - 1], lams[k + 1]),
                                   method="bounded", options={"xatol": 1e-12})
            if -best.fun >= 0:
                log.info("narrow component found at %s=%.12g", problem.parameter, best.x)
                lams.insert(k + 1, float(best.x))
                disc.insert(k + 1, -float(best.fun))
    seeds = []
    exists = np.asarray(disc) >= 0
    edges = np.flatnonzero(np.diff(np.r_[0, exists.astype(int), 0]))
    for first, last in zip(edges[::2], edges[1::2], strict=True):
        k = first + int(np.argmax(disc[first:last]))
        c, s, b = problem.amplitude(float(lams[k]))
        r2, root = c * c + s * s, math.sqrt(max(disc[k], 0.0))
        for sign in (1.0, -1.0):
            seeds.append((float(lams[k]), math.atan2((b * s + sign * c * root) / r2,
                                                     (b * c - sign * s * root) / r2)))
    return seeds


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


def _branch_dataset(problem: PeriodicBranchProblem, osc: ImpactOscillator,
                    opts: ContinuationOptions, detect: Sequence[str], runs: list[_Run],
                    record: dict[str, Any] | None = None, *,
                    functions: UserFunctions | None = None) -> xr.Dataset:
    """One dataset of every component (the variable ``connected_component`` tells them apart)."""
    parameter, N = problem.parameter, problem.N
    orbits = [s.orbit for run in runs for s in run.samples]
    arclength, component, lam = [], [], []
    special_points = []
    user_events: list[SpecialPoint] = []
    offset = 0
    for index, run in enumerate(runs):
        user_events += [dataclasses.replace(ev, point=ev.point + offset) for ev in run.events]
        res = run.result
        steps = np.sqrt(np.diff(res.u[:, 0]) ** 2 + np.diff(res.lam) ** 2)
        arclength.append(np.concatenate([[0.0], np.cumsum(steps)]))
        component.append(np.full(len(run.samples), index))
        lam.append(np.asarray(res.lam, dtype=float))
        special_points += [special_record(sp, parameter, point=sp.point + offset,
                                          bracket=sp.bracket) for sp in run.specials]
        offset += len(run.samples)
    columns = {**orbit_columns(orbits, parameter, np.concatenate(lam)),
               "arclength": np.concatenate(arclength),
               "connected_component": np.concatenate(component)}
    first = runs[0]
    option_record = {**dataclasses.asdict(opts), "N": N, "parameter": parameter,
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
    ds = branch_dataset(parameter=parameter, N=N, oscillator=osc, options=option_record,
                        columns=columns, special_points=special_points)
    if option_record.get("interrupted"):  # Ctrl-C: as an interrupted map says it
        ds.attrs["interrupted"] = 1
    if not functions:
        return ds
    names = parameter_names(ds)
    return add_user_functions(
        ds, monitors={name: np.concatenate([run.values[name] for run in runs])
                      for name in functions.functions},
        events=list(functions.events),
        event_points=[user_event_record(ev, names) for ev in user_events])


# -- restart and extension ----------------------------------------------------------------------
def _check_branch(branch: Any) -> xr.Dataset:
    """`branch` if it is a branch dataset (N-1 or N-p), else a clear error."""
    if not isinstance(branch, xr.Dataset):
        raise TypeError(f"branch must be a branch xarray.Dataset (of continuation, "
                        f"multi_impact_continuation or a switch, or impactcont.load of its "
                        f"file); got {type(branch).__name__}")
    if "curve_kind" in branch.attrs or "parameters" in branch.attrs:
        raise ParameterError("branch must be a one-parameter branch; got a two-parameter curve "
                             f"dataset (parameters {branch.attrs.get('parameters')!r})")
    try:
        validate_branch_dataset(branch)
    except ValueError as exc:
        raise ParameterError(f"branch is not a branch dataset: {exc}") from None
    return branch


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
                          record={"symmetric": symmetric, **record}, functions=functions)
    _, detect, (lo, hi), opts = check_continuation_arguments(
        problem.osc, problem.N, parameter, (lo, hi), detect=detect, components="start",
        options=base, direction=direction, both_directions=along is None, **single)
    if step is not None and not user_ds:
        opts = dataclasses.replace(opts, ds=min(max(step, opts.ds_min), opts.ds_max))
    with (interruptible(f"continuation in {parameter}"),
          reporter(progress, f"continuation in {parameter}", parameter=parameter) as rep):
        run = _follow(problem, lam0, float(u0[0]), opts, detect, rep, functions)
        if interrupted():
            record = {**record, "interrupted": True}
    if not run.samples and run.result.interrupted:
        raise NothingComputed(f"continuation in {parameter} interrupted before its first "
                              "point")
    if not run.samples:
        raise NewtonConvergenceError(f"the restart at {parameter}={lam0:.10g} could not be "
                                     f"started: {run.result.message}")
    return _branch_dataset(problem, problem.osc, opts, detect, [run], record,
                           functions=functions)


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
    (:func:`~impactcont.analysis.multi_branch.multi_impact_continuation`, a switch), computed
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
        User events and monitors on the restarted branch (as for
        :func:`continuation`; functions are not stored in a file, so those of `branch`
        are not carried over).
    **single
        Single options (``ds``, ``ds_max``, ``max_points``, ...) over `options`.

    Returns
    -------
    xarray.Dataset
        The restarted branch (one component: the one through the restart point), in
        the schema of `branch`; its ``options`` record ``restart`` (the row and the
        parameter value it started from).

    Raises
    ------
    TypeError
        `branch` is not an xarray.Dataset.
    ParameterError
        Not a branch dataset; neither or both of `point` and `label`; a point index out
        of range; no such special point; bad `along`, `bounds` (not containing the
        restart point), `detect` or options; bad `events` or `monitors`.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the call with what it has computed, as in
    :func:`continuation` (see its Notes): the other direction is not followed.
    """
    _check_branch(branch)
    functions = check_user_functions(events, monitors, reserved_names())
    along = _check_along(along)
    row, special = _start_row(branch, point, label, which)
    parameter = str(branch.attrs["parameter"])
    _check_finite_row(branch, row, special)
    lo, hi = _branch_bounds(branch) if bounds is None else check_bounds(parameter, bounds)
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
    lo, hi = check_bounds(parameter, bounds)
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


def _same_user_functions(branch: xr.Dataset, events: Any, monitors: Any) -> UserFunctions:
    """The user's functions for an extension of `branch`: checked, with the branch's names."""
    functions = check_user_functions(events, monitors, reserved_names())
    for what, attr, given in (("events", USER_EVENTS_ATTR, functions.events),
                              ("monitors", USER_MONITORS_ATTR, functions.monitors)):
        names = [name for name in str(branch.attrs.get(attr, "")).split(",") if name]
        if sorted(names) != sorted(given):
            raise ParameterError(f"{what} must have the names of the branch's {what} {names} "
                                 f"(attribute {attr!r}: functions are not stored, the new "
                                 f"parts need them); got {sorted(given)}")
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

"""One-parameter branches of periodic N-1 motions: continuation, detection, dataset.

``continuation(osc, N, parameter, bounds)`` = pick a start root of eq. (15)
-> follow eq. (14) with the pseudo-arclength core -> evaluate every accepted
point (state, G, multipliers, checks) -> detect and locate the special points
-> an :class:`xarray.Dataset` in the schema of :mod:`impactcont.dataset`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from scipy.optimize import minimize_scalar

from impactcont.core import ContinuationOptions, ContinuationStatus, continue_branch
from impactcont.core.options import DRIVER_DEFAULTS, driver_options, option_keywords
from impactcont.core.stepper import NewtonConvergenceError
from impactcont.dataset import branch_dataset
from impactcont.dataset.records import orbit_columns, special_record
from impactcont.detection import BranchSample, detect_special_points
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.periodic import _check_N, periodic_orbits
from impactcont.problems import PeriodicBranchProblem
from impactcont.threads import blas_limited
from impactcont.vocabulary import LABELS, PARAMETERS, check_labels

__all__ = ["check_continuation_arguments", "continuation"]

log = logging.getLogger(__name__)

_DEFAULTS = {"newton_tol": 1e-12}
"""The closed form is exact to rounding: a tighter Newton tolerance than the other drivers'."""
_EXISTENCE_SCAN = 400
_SAME_ROOT = 0.05  # rad: a seed this close to a computed point of a component lies on it


def _check_bounds(parameter: str, bounds: object) -> tuple[float, float]:
    """``(lo, hi)`` inside the parameter's allowed range."""
    try:
        lo, hi = (float(v) for v in bounds)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise ParameterError(f"bounds must be two numbers (lo, hi); got {bounds!r}") from None
    table = PARAMETERS[parameter]
    # order and finiteness: ContinuationOptions says what is allowed
    if any(math.isfinite(v) and not table.contains(v) for v in (lo, hi)):
        raise ParameterError(f"bounds for {parameter} must lie where {parameter} is "
                             f"{table.allowed}; got {bounds!r}")
    return lo, hi


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
    elastic = hi >= 1.0 if parameter == "R" else osc.R == 1.0
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
    lo, hi = _check_bounds(parameter, bounds)
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
    current = float(getattr(problem.osc, problem.parameter) or 0.0)
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


@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_DEFAULTS})
def continuation(osc: ImpactOscillator, N: int = 1, parameter: str = "omega",
                 bounds: Sequence[float] = (0.5, 6.0), *, start: float | None = None,
                 root: int | None = None, detect: Sequence[str] = LABELS,
                 components: str = "all", options: ContinuationOptions | None = None,
                 ds: float | None = None, ds_min: float | None = None,
                 ds_max: float | None = None, newton_tol: float | None = None,
                 max_points: int | None = None, both_directions: bool | None = None,
                 **more: Any) -> xr.Dataset:
    """Continue the branch of periodic N-1 motions in one parameter and find its special points.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator (other parameters fixed at its values).
    N : int
        One impact every N forcing periods.
    parameter : str
        ``"omega"``, ``"b"``, ``"R"``, ``"eta"``, ``"alpha"``, ``"beta"`` or ``"F0"`` (the forcing
        amplitude, the largest |F_i|: F is scaled, its shape kept).
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
    """
    problem, detect, (lo, hi), opts = check_continuation_arguments(
        osc, N, parameter, bounds, detect=detect, components=components, options=options,
        ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol, max_points=max_points,
        both_directions=both_directions, **more)
    N = problem.N
    lam0 = _start_value(problem, (lo, hi), start)
    delta0 = _start_root(problem, lam0, root)
    runs = [_follow(problem, lam0, delta0, opts, detect)]
    if components == "all":
        for lam, delta in _component_seeds(problem, (lo, hi)):
            if not any(_passes(run, lam, delta) for run in runs):
                runs.append(_follow(problem, lam, delta, opts, detect))
    started = [run for run in runs if run.samples]
    for run in runs:
        if not run.samples:  # its corrector failed at the seed: say so, keep the others
            warnings.warn(f"the N={N} component through {parameter}={run.start:.10g} "
                          f"(delta={run.start_delta:.10g}) could not be started: "
                          f"{run.result.message}; it is not in the branch", RuntimeWarning,
                          stacklevel=3)
    if not started:
        raise NewtonConvergenceError(f"no component of the N={N} branch in {parameter} over "
                                     f"[{lo:.10g}, {hi:.10g}] could be started: "
                                     f"{runs[0].result.message}")
    return _branch_dataset(problem, osc, opts, detect, started)


@dataclasses.dataclass(frozen=True, eq=False)
class _Run:
    """One connected component: its continuation result, samples and special points."""

    start: float
    start_delta: float
    result: Any
    samples: list[BranchSample]
    specials: list[Any]


def _follow(problem: PeriodicBranchProblem, lam0: float, delta0: float,
            opts: ContinuationOptions, detect: Sequence[str]) -> _Run:
    result = continue_branch(problem, np.array([delta0]), lam0, opts)
    log.info("N=%d branch in %s from %s=%.10g: %d points (%s)", problem.N, problem.parameter,
             problem.parameter, lam0, len(result), result.message)
    if ContinuationStatus.MAX_POINTS_REACHED in result.statuses:
        warnings.warn(f"the N={problem.N} component through {problem.parameter}={lam0:.10g} "
                      f"stopped at max_points={opts.max_points}: the rest of it is not in the "
                      "branch; raise max_points or ds_max", RuntimeWarning, stacklevel=4)
    samples = [BranchSample(delta=float(u[0]), lam=float(lam), dlam=float(t[-1]),
                            orbit=problem.orbit(float(u[0]), float(lam)))
               for u, lam, t in zip(result.u, result.lam, result.tangent, strict=True)]
    return _Run(lam0, delta0, result, samples, detect_special_points(problem, samples, detect))


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
                    opts: ContinuationOptions, detect: Sequence[str], runs: list[_Run]
                    ) -> xr.Dataset:
    """One dataset of every component (the variable ``connected_component`` tells them apart)."""
    parameter, N = problem.parameter, problem.N
    orbits = [s.orbit for run in runs for s in run.samples]
    arclength, component, lam = [], [], []
    special_points = []
    offset = 0
    for index, run in enumerate(runs):
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
    return branch_dataset(parameter=parameter, N=N, oscillator=osc, options=option_record,
                          columns=columns, special_points=special_points)

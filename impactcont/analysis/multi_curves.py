"""Two-parameter curves of the special points of N-p motions (two stops, any C, BP).

``multi_impact_curve(branch, kind, ...)`` = take a located special point of an N-p
branch (:func:`impactcont.multi_impact_continuation`, a switched branch, ...) ->
follow it in the branch's parameter ``p1`` and a second parameter ``p2`` with the
augmented system of :mod:`impactcont.problems.multi_impact_curve` and the
pseudo-arclength core -> a dataset of the motion at every curve point.

The dataset is an N-p branch dataset (:mod:`impactcont.dataset.multi`) continued in
``p2`` that also holds the column of ``p1`` (so it loads, plots and re-solves as a
branch does), with the attributes ``curve_kind`` (the label followed), ``parameters =
"p1,p2"`` and ``born_at_value`` (``p1`` at the start), and the codim-2 points located
on the curve (:mod:`impactcont.detection.codim2`, the same location as on the N-1 curves
of :func:`impactcont.curve`) on the dimension ``codim2`` with the variables ``codim2_*`` of
an N-1 curve dataset (:func:`impactcont.dataset.curves.codim2_data`).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.multi_branch import (
    MultiImpactSample,
    branch_to_dataset,
    user_events_until_interrupted,
)
from impactcont.analysis.switching import special_orbit
from impactcont.core import ContinuationPoint, ContinuationStatus, Stop, follow
from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.locate import crossing_steps
from impactcont.core.options import DRIVER_DEFAULTS, driver_options, option_keywords
from impactcont.dataset.curves import CODIM2_LABELS, codim2_data
from impactcont.dataset.multi import impacts_of, pattern_of
from impactcont.dataset.records import reserved_names
from impactcont.dataset.schema import oscillator_from_dataset, special_variable
from impactcont.detection.codim2 import Codim2Point, codim2_record, detect_codim2, test_values
from impactcont.detection.special_points import check_user_functions
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import model_parameter
from impactcont.orbit.multi_impact import initial_unknowns
from impactcont.problems.codim1 import MultiImpactCurveProblem
from impactcont.progress import (
    NothingComputed,
    ProgressOption,
    interrupted,
    interruptible,
    reporter,
    until_interrupted,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import LABELS, Label

__all__ = ["multi_impact_curve", "multi_impact_curve_crossings"]

log = logging.getLogger(__name__)

_DEFAULTS = {"newton_tol": 1e-10, "ds": 0.01}
_START_TOL = 1e-11


def _check_box(bounds: Any, parameters: tuple[str, str]) -> dict[str, tuple[float, float]]:
    if not isinstance(bounds, Mapping) or set(bounds) != set(parameters):
        raise ParameterError(f"bounds must be a mapping with the keys {list(parameters)} "
                             f"(the box of the curve); got {bounds!r}")
    box = {}
    for name in parameters:
        try:
            lo, hi = (float(v) for v in bounds[name])
        except (TypeError, ValueError):
            raise ParameterError(f"bounds[{name!r}] must be a pair (lo, hi) of numbers; got "
                                 f"{bounds[name]!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ParameterError(f"bounds[{name!r}] must be finite with lo < hi; got "
                                 f"{bounds[name]!r}")
        box[name] = (lo, hi)
    return box


class _Box:
    """Ends a direction of the curve where ``p1`` leaves its bounds (``p1`` is an unknown:
    the core sees only the bounds of ``p2``); keeps the motion of every accepted point."""

    def __init__(self, problem: MultiImpactCurveProblem, p1_bounds: tuple[float, float]
                 ) -> None:
        self.problem, self.p1_bounds = problem, p1_bounds
        self.orbits: list[Any] = []

    def __call__(self, previous: ContinuationPoint | None, current: ContinuationPoint
                 ) -> Stop | None:
        p1 = float(current.u[-1])
        lo, hi = self.p1_bounds
        if not lo <= p1 <= hi:
            return Stop(ContinuationStatus.BOUNDS_REACHED,
                        f"{self.problem.parameters[0]} = {p1:.10g} left its bounds "
                        f"({lo:g}, {hi:g})", keep=False)
        self.orbits.append(self.problem.orbit(current.u, current.lam))
        return None


@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_DEFAULTS, "both_directions": True})
def multi_impact_curve(branch: xr.Dataset, kind: str = "PD", which: int = 0, *,
                       parameter: str = "b",
                       bounds: Mapping[str, Sequence[float]] | None = None,
                       options: Any = None, ds: float | None = None,
                       ds_min: float | None = None, ds_max: float | None = None,
                       newton_tol: float | None = None, max_points: int | None = None,
                       both_directions: bool | None = None, progress: ProgressOption = None,
                       events: dict[str, Any] | None = None,
                       monitors: dict[str, Any] | None = None,
                       detect_codim2_points: bool = True, **more: Any) -> xr.Dataset:
    """Follow a special point of an N-p branch in two parameters.

    Parameters
    ----------
    branch : xarray.Dataset
        An N-p branch (:func:`impactcont.multi_impact_continuation`, a switched branch)
        continued in ``p1``, with a special point of `kind`.
    kind : Label or str
        ``SN, PD, NS, GR, ZV`` or ``BP`` (BP: a branch of symmetric motions).
    which : int
        Which point of that kind on the branch (branch order).
    parameter : str
        ``p2``, the second parameter (``b`` or ``R`` of a symmetric motion need mirrored
        stops, ``Stops(mirror=True)``).
    bounds : mapping
        The box ``{p1: (lo, hi), p2: (lo, hi)}``; the curve stops on its edges.
    options, ds, ds_min, ds_max, newton_tol, max_points, both_directions, **more
        Continuation options (the drivers' defaults for those left out; Newton tolerance
        1e-10, first step 0.01, both directions).
    progress : None, bool or callable
        A progress bar on stderr (``None``: when stderr is a terminal, after 2 s;
        ``True``: always; ``False``: never) or a callable receiving a
        :class:`~impactcont.progress.Progress` record at every curve point, with the
        value of `parameter` (:mod:`impactcont.progress`). A call longer than a minute
        logs a line a minute.
    events, monitors : mapping of str to callable, optional
        User events and monitors, as for :func:`impactcont.continuation`: functions of
        the :class:`~impactcont.MultiImpactOrbit` at a curve point; an event's zeros on
        the curve are located on the dimension ``event`` (``event_precision`` bounds the
        error in both parameters).
    detect_codim2_points : bool
        Locate the codim-2 points on the curve (:mod:`impactcont.detection.codim2`).

    Returns
    -------
    xarray.Dataset
        The curve as an N-p branch dataset in ``p2`` with the column of ``p1`` and the
        attributes ``curve_kind``, ``parameters`` (``"p1,p2"``), ``born_at_value``; its
        codim-2 points on the dimension ``codim2`` (variables ``codim2_*``, as on a curve
        of :func:`impactcont.curve`).

    Raises
    ------
    ParameterError
        A bad argument (named in the message), no such special point; bad `events` or
        `monitors`, or one of their functions failed (named; a non-callable: TypeError).
    NoPeriodicMotionError
        The start could not be put on the curve.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the curve at its last accepted point (the
    other direction is not followed) and returns it: its ``options`` attribute records
    ``"interrupted": true`` and the stop reason ``"interrupted by the user
    (KeyboardInterrupt) after K points, ..."``, also logged at WARNING. Ctrl-C while the
    codim-2 points are located keeps those located before it (the location stops there).
    A second Ctrl-C, or one before the first point, aborts with :class:`KeyboardInterrupt`.
    The dataset's attribute ``interrupted`` is then 1, as an interrupted map's.
    """
    if not isinstance(branch, xr.Dataset):
        raise TypeError(f"branch must be a branch xarray.Dataset; got {type(branch).__name__}")
    functions = check_user_functions(events, monitors, reserved_names())
    if not isinstance(kind, str) or kind not in LABELS:
        raise ParameterError(f"kind must be one of {LABELS}; got {kind!r}")
    kind = str(Label(kind))  # a Label or its string: stored as the string
    p1 = str(branch.attrs["parameter"])
    parameters = (p1, parameter)
    if bounds is None:
        raise ParameterError(f"bounds must be given: the box {{{p1!r}: (lo, hi), "
                             f"{parameter!r}: (lo, hi)}} of the curve")
    box = _check_box(bounds, parameters)
    symmetric = bool(json.loads(branch.attrs.get("options", "{}")).get("symmetric", False))
    orbit = special_orbit(branch, kind, which)
    k = [i for i, lab in enumerate(branch[special_variable("label")].values.tolist())
         if lab == kind][which]
    if branch[special_variable("status")].values[k] != "located":
        log.warning("the %s point %d of the branch is only bracketed: the curve starts from "
                    "the motion re-solved there", kind, which)
    osc = orbit.oscillator
    N, p, pattern = int(branch.attrs["N"]), impacts_of(branch), pattern_of(branch)
    problem = MultiImpactCurveProblem(osc, N, p, pattern, kind, parameters, symmetric=symmetric)
    lam0 = model_parameter(osc, parameter).value(osc)
    if not box[parameter][0] <= lam0 <= box[parameter][1]:
        raise ParameterError(f"bounds[{parameter!r}] = {box[parameter]} must contain the "
                             f"start {parameter}={lam0!r}")
    start_p1 = model_parameter(osc, p1).value(osc)
    base = problem.branch_problem(lam0)
    u0 = base.half_unknowns(orbit.unknowns) if symmetric else orbit.unknowns
    x0 = np.append(u0, start_p1)
    # on the curve at fixed p2 (the special point is located to its precision only)
    target = np.append(x0, lam0)
    normal = np.zeros(target.size)
    normal[-1] = 1.0
    found = solve_on_hyperplane(problem, target, normal, tol=_START_TOL, max_iter=30)
    if not found.converged:
        raise NoPeriodicMotionError(f"the {kind} point at {p1}={start_p1!r} could not be put "
                                    f"on the augmented system (last step {found.last_step:.3g})")
    x0 = found.x[:-1]
    opts = driver_options(options, box[parameter], defaults=_DEFAULTS, ds=ds, ds_min=ds_min,
                          ds_max=ds_max, newton_tol=newton_tol, max_points=max_points,
                          both_directions=both_directions, **more)
    watches: dict[int, _Box] = {}

    def watch(direction: int) -> _Box:
        watches[direction] = _Box(problem, box[p1])
        return watches[direction]

    what = f"{kind} curve of {N}-{p} motions in ({p1}, {parameter})"
    with interruptible(what) as call, reporter(progress, what, parameter=parameter) as rep:
        result = follow(problem, x0, lam0, opts, rep.point, stop=watch)
        # Ctrl-C can end a run between a watch's orbit and the core's taking of the point
        orbits = watches[opts.direction].orbits[:len(result) - result.start_index]
        if -opts.direction in watches:
            orbits = watches[-opts.direction].orbits[result.start_index:0:-1] + orbits
        if not orbits and result.interrupted:
            raise NothingComputed(f"{what} interrupted before its first point")
        if not orbits:
            raise NoPeriodicMotionError(f"{kind} curve: {result.message}")
        samples = [MultiImpactSample(u=x, lam=float(lam), tangent=t, orbit=o)
                   for x, lam, t, o in zip(result.u, result.lam, result.tangent, orbits,
                                           strict=True)]
        log.info("%s curve of the %d-%d motion in (%s, %s): %d points (%s)", kind, N, p, p1,
                 parameter, len(samples), result.message)
        found: list[Codim2Point] = []
        if detect_codim2_points:
            _locate_codim2(problem, samples, found)
        # the user's events: located in both parameters (p1 is the last unknown)
        values, user_events = user_events_until_interrupted(
            problem, samples, functions, position=lambda x, lam: (x[-1], lam))
        was_interrupted, phase = interrupted(), call.where
    record = {"kind": kind, "parameters": [p1, parameter], "start": start_p1,
              "bounds": {name: list(v) for name, v in box.items()}, "symmetric": symmetric,
              "status": [st.name for st in result.statuses], "message": result.message,
              **{key: value for key, value in dataclasses.asdict(opts).items()
                 if key != "bounds"}}
    if was_interrupted:
        record["interrupted"] = True
        record["interrupted_while"] = phase
    info = {"curve_kind": kind, "parameters": f"{p1},{parameter}",
            "born_at_value": start_p1}
    view = _CurveView(problem, parameter, osc)
    ds = branch_to_dataset(view, samples, [], record,
                           title=f"{kind} curve of periodic {N}-{p} impacting motions in "
                           f"({p1}, {parameter})", extra_attrs=info, extra_columns=(p1,),
                           functions=functions, values=values, user_events=user_events)
    records = [codim2_record(problem, cp) for cp in sorted(found, key=lambda cp: cp.point)
               if cp.label in CODIM2_LABELS]
    return ds.assign(codim2_data(records, problem.parameters, osc.n))


def _locate_codim2(problem: MultiImpactCurveProblem, samples: Sequence[MultiImpactSample],
                   found: list[Codim2Point]) -> None:
    """The codim-2 points of the curve's samples, appended to `found` as they are located
    (:func:`~impactcont.detection.codim2.detect_codim2`); Ctrl-C keeps those located."""
    xs = [np.append(sample.u, sample.lam) for sample in samples]
    orbits = [sample.orbit for sample in samples]
    tests = [test_values(problem, x, orbit) for x, orbit in zip(xs, orbits, strict=True)]
    until_interrupted(
        lambda: detect_codim2(problem, xs, orbits, tests, found), None, "location",
        "interrupted by the user (KeyboardInterrupt) while locating the codim-2 points of "
        "the curve: those located before are kept")
    log.info("%s curve: %d codim-2 points", problem.kind, len(found))



def _problem_of(ds: xr.Dataset) -> MultiImpactCurveProblem:
    """The augmented problem a curve dataset of :func:`multi_impact_curve` was followed on."""
    if not isinstance(ds, xr.Dataset) or "curve_kind" not in ds.attrs:
        raise ParameterError("ds must be a curve dataset of multi_impact_curve (attribute "
                             "'curve_kind')")
    record = json.loads(ds.attrs["options"])
    p1, p2 = str(ds.attrs["parameters"]).split(",")
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    return MultiImpactCurveProblem(osc, int(ds.attrs["N"]), impacts_of(ds), pattern_of(ds),
                                   str(ds.attrs["curve_kind"]), (p1, p2),
                                   symmetric=bool(record.get("symmetric", False)))


def check_crossing_line(parameters: Sequence[str], parameter: object, value: object) -> None:
    """Check the line ``parameter = value`` a curve's crossings are asked of.

    Parameters
    ----------
    parameters : sequence of str
        The curve's two parameters.
    parameter : str
        The parameter held fixed on the line; one of `parameters`.
    value : float
        Its value on the line; a finite real number.

    Raises
    ------
    ParameterError
        `parameter` is not one of `parameters`, or `value` is not a finite real number.
    """
    if parameter not in parameters:
        raise ParameterError(f"parameter must be one of the curve's parameters "
                             f"{parameters}; got {parameter!r}")
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) \
            or not math.isfinite(value):
        raise ParameterError(f"value must be a finite real number; got {value!r}")


def multi_impact_curve_crossings(ds: xr.Dataset, parameter: str, value: float
                                 ) -> list[dict[str, float]]:
    """Exact points where a curve of :func:`multi_impact_curve` crosses ``parameter = value``.

    Each crossing between two consecutive curve points is re-solved by Newton on the
    curve's augmented system with ``parameter`` fixed (not an interpolation).

    Parameters
    ----------
    ds : xarray.Dataset
        A curve dataset of :func:`multi_impact_curve`.
    parameter : str
        One of the curve's two parameters.
    value : float

    Returns
    -------
    list of dict
        Per crossing, in curve order: the values of ``omega``, ``b`` and the curve's
        parameters, and ``point`` (index of the first of the two bracketing points).

    Raises
    ------
    ParameterError
        Not such a curve dataset, a parameter that is not the curve's, a bad value.
    NoPeriodicMotionError
        Newton fails at a crossing.
    """
    problem = _problem_of(ds)
    check_crossing_line(problem.parameters, parameter, value)
    symmetric = problem.symmetric
    values = np.asarray(ds[parameter].values, dtype=float)
    out: list[dict[str, float]] = []
    for k, t in crossing_steps(values, value):
        xs = []
        for i in (k, k + 1):  # the stored motions as unknowns of the curve problem
            lam = float(ds[problem.parameters[1]].values[i])
            osc = oscillator_from_dataset(ds, int(i))
            u = initial_unknowns({"delta": float(ds["delta_k"].values[i, 0]),
                                  "flight_times": ds["flight_time_k"].values[i],
                                  "states": ds["state_k"].values[i],
                                  "pattern": pattern_of(ds)}, osc, problem.N, problem.p)
            base = problem.branch_problem(lam)
            v = base.half_unknowns(u) if symmetric else u
            first = model_parameter(osc, problem.parameters[0])
            xs.append(np.concatenate([v, [first.value(osc)], [lam]]))
        target = xs[0] + t * (xs[1] - xs[0])
        normal = np.zeros(target.size)
        column = problem.parameters.index(parameter) - 2  # (.., p1, p2): -2 or -1
        normal[column] = 1.0
        target[column] = value
        found = solve_on_hyperplane(problem, target, normal, tol=_START_TOL, max_iter=30)
        if not found.converged:
            raise NoPeriodicMotionError(f"the crossing of {parameter} = {value!r} between "
                                        f"points {k} and {k + 1} was not found (last Newton "
                                        f"step {found.last_step:.3g})")
        x, lam = found.x[:-1], float(found.x[-1])
        osc = problem.branch_problem(lam).oscillator_at(float(x[-1]))
        crossing = {name: float(getattr(osc, name) or 0.0)
                    for name in dict.fromkeys(["omega", "b", *problem.parameters])}
        crossing["point"] = int(k)
        out.append(crossing)
    return out


class _CurveView:
    """What :func:`~impactcont.analysis.multi_branch.branch_to_dataset` reads of a problem."""

    def __init__(self, problem: MultiImpactCurveProblem, parameter: str, osc: Any) -> None:
        self.parameter, self.osc = parameter, osc
        self.N, self.p, self.pattern = problem.N, problem.p, problem.pattern

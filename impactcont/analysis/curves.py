"""Two-parameter continuation of codim-1 curves: SN, PD, NS, GR and ZV boundaries.

``curve(osc, N, kind, start=..., parameters=("omega", "b"), bounds=...)`` =
pick a start (a special point of a branch dataset, explicit values, or one
found by a one-parameter continuation) -> follow the augmented system of
:mod:`impactcont.problems.codim1` with the pseudo-arclength core in both
directions until the box ``bounds`` or a curve end -> evaluate the motion at
every point -> detect and locate the codim-2 points
(:mod:`impactcont.detection.codim2`) -> an :class:`xarray.Dataset` in the
schema of :mod:`impactcont.dataset.curves`.

:func:`curve_crossings` solves a curve exactly where it crosses a line
``parameter = value`` (used to compare with one-parameter special points and
with the grid of a map).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.branch import continuation
from impactcont.analysis.multi_curves import check_crossing_line, multi_impact_curve
from impactcont.core import (
    ContinuationOptions,
    ContinuationPoint,
    ContinuationStatus,
    Stop,
    follow,
)
from impactcont.core.locate import crossing_steps
from impactcont.core.options import DRIVER_DEFAULTS, driver_options, option_keywords
from impactcont.core.stepper import NewtonConvergenceError
from impactcont.dataset.attributes import split_parameters
from impactcont.dataset.curves import CODIM2_LABELS, curve_dataset, validate_curve_dataset
from impactcont.dataset.records import reserved_names, user_event_record
from impactcont.dataset.schema import (
    add_user_functions,
    oscillator_from_dataset,
    parameter_names,
    validate_branch_dataset,
)
from impactcont.detection.codim2 import Codim2Point, codim2_record, detect_codim2, test_values
from impactcont.detection.special_points import (
    UserFunctions,
    check_user_functions,
    locate_user_events,
    user_values,
)
from impactcont.errors import LowImpactVelocityWarning, NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import model_parameter
from impactcont.orbit.periodic import PeriodicOrbit, _check_N, periodic_orbits
from impactcont.problems.codim1 import (
    CurveProblem,
    check_parameters,
    curve_kind,
    curve_problem,
)
from impactcont.progress import (
    Interruption,
    NothingComputed,
    ProgressOption,
    interruptible,
    reporter,
    until_interrupted,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import Label, check_bounds

__all__ = ["check_curve_arguments", "crossing_steps", "curve", "curve_crossings"]

log = logging.getLogger(__name__)

_DEFAULTS = {"newton_tol": 1e-11, "ds": 0.01}
"""The augmented systems use difference Jacobians: a looser tolerance than the closed form.
The first step stays 0.01: the PD system is singular at a zero-velocity impact (the pole
of G), and a point next to one is found or not depending on the steps there."""


# -- arguments ----------------------------------------------------------------------------------
def _check_bounds(bounds: Any, parameters: tuple[str, str], osc: ImpactOscillator
                  ) -> dict[str, tuple[float, float]]:
    allowed = (f"a mapping {{{parameters[0]!r}: (lo, hi), {parameters[1]!r}: (lo, hi)}} or a "
               "pair of (lo, hi) pairs in the order of parameters, finite with lo < hi")
    if isinstance(bounds, Mapping):
        if set(bounds) != set(parameters):
            raise ParameterError(f"bounds must be {allowed}; got {bounds!r}")
        pairs = [bounds[p] for p in parameters]
    elif isinstance(bounds, Sequence) and not isinstance(bounds, str) and len(bounds) == 2:
        pairs = list(bounds)
    else:
        raise ParameterError(f"bounds must be {allowed}; got {bounds!r}")
    out = {}
    for name, pair in zip(parameters, pairs, strict=True):
        try:
            lo, hi = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ParameterError(f"bounds must be {allowed}; got {bounds!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ParameterError(f"bounds[{name!r}] must be finite with lo < hi; got {pair!r}")
        # inside the parameter's range: the drivers' one check (vocabulary.check_bounds),
        # and the oscillator at both ends (an element keeps K, M positive definite)
        out[name] = check_bounds(name, (lo, hi), argument=f"bounds[{name!r}]")
        model_parameter(osc, name).check_bounds(osc, out[name], argument=f"bounds[{name!r}]")
    return out


def _same_system(a: ImpactOscillator, b: ImpactOscillator, free: set[str]) -> bool:
    """Whether `a` and `b` are the same system but for the parameters `free` (each set on
    `a` to its value on `b` by its model parameter: an element moves its matrix)."""
    for name in free:
        param = model_parameter(a, name)
        a = param.at(a, param.value(b))
    da, db = a.to_dict(), b.to_dict()
    return all(np.allclose(da.get(k, np.nan), db.get(k, np.nan), rtol=1e-12, atol=0.0,
                           equal_nan=True) for k in set(da) | set(db))


def _set(osc: ImpactOscillator, values: Mapping[str, float]) -> ImpactOscillator:
    """`osc` with each parameter set to its value (by its model parameter)."""
    for name, value in values.items():
        osc = model_parameter(osc, name).at(osc, float(value))
    return osc


def _value(osc: ImpactOscillator, name: str) -> float:
    """The value of parameter `name` on `osc` (by its model parameter)."""
    return model_parameter(osc, name).value(osc)


def _start_from_branch(ds: xr.Dataset, kind: Label, special: int | None,
                       osc: ImpactOscillator | None, N: int | None, parameters: tuple[str, str]
                       ) -> tuple[ImpactOscillator, int, float]:
    validate_branch_dataset(ds)
    labels = np.asarray(ds["special_label"].values).tolist()
    statuses = np.asarray(ds["special_status"].values).tolist()
    if special is None:
        rows = [k for k, (lab, st) in enumerate(zip(labels, statuses, strict=True))
                if lab == kind and st == "located"]
        if not rows:
            raise ParameterError(f"start: the branch dataset has no located {kind} point; its "
                                 f"special points are {labels} ({statuses})")
        special = rows[0]
    elif isinstance(special, bool) or not isinstance(special, (int, np.integer)) \
            or not 0 <= special < len(labels):
        raise ParameterError(f"special must be an index into the branch's {len(labels)} special "
                             f"points; got {special!r}")
    elif labels[special] != kind:
        raise ParameterError(f"special={special!r} is a {labels[special]} point, not {kind}")
    ds_N = int(ds.attrs["N"])
    if N is not None and _check_N(N) != ds_N:
        raise ParameterError(f"N={N!r} differs from the branch dataset's N={ds_N}")
    row = ds.isel(special=int(special))
    base = oscillator_from_dataset(ds)
    names = dict.fromkeys(["omega", "b", ds.attrs["parameter"]])
    start_osc = _set(base, {k: float(row[f"special_{k}"]) for k in names})
    if osc is not None and not _same_system(osc, start_osc, {"omega", "b", *names, *parameters}):
        raise ParameterError("osc differs from the oscillator of the branch dataset given as "
                             f"start (other than omega, b and the parameters): {osc!r} vs "
                             f"{start_osc!r}")
    return start_osc, ds_N, float(row["special_delta"])


def _start_by_continuation(osc: ImpactOscillator, N: int, kind: Label, special: int | None,
                           parameters: tuple[str, str], bounds: dict[str, tuple[float, float]]
                           ) -> tuple[ImpactOscillator, int, float]:
    p1 = parameters[0]
    branch = continuation(osc, N, p1, bounds[p1], detect=[kind], progress=False)
    if json.loads(branch.attrs.get("options", "{}")).get("interrupted"):
        raise NothingComputed(f"{kind} curve interrupted while its start was searched")
    rows = [k for k, (lab, st) in enumerate(zip(branch["special_label"].values,
                                                branch["special_status"].values, strict=True))
            if lab == kind and st == "located"]
    if not rows:
        raise NoPeriodicMotionError(
            f"no located {kind} point on the N={N} branch in {p1} in {bounds[p1]} at "
            f"{parameters[1]}={_value(osc, parameters[1])!r}; give start explicitly")
    k = rows[0] if special is None else rows[int(special)]
    return _start_from_branch(branch, kind, k, None, N, parameters)


def _start_from_values(osc: ImpactOscillator, N: int, problem: CurveProblem,
                       values: Mapping[str, Any], root: int | None
                       ) -> tuple[ImpactOscillator, float]:
    p1, p2 = problem.parameters
    allowed = {p1, p2, "delta"}
    unknown = sorted(set(values) - allowed)
    if unknown or p1 not in values or p2 not in values:
        raise ParameterError(f"start must give {p1!r} and {p2!r} (and optionally 'delta'); got "
                             f"keys {sorted(values)}")
    start_osc = _set(osc, {p1: values[p1], p2: values[p2]})
    if "delta" in values:
        return start_osc, float(values["delta"])
    p1v, p2v = _value(start_osc, p1), _value(start_osc, p2)
    phase = problem.start_phase(start_osc)
    if phase is not None:  # known in closed form (the double root of an SN curve)
        return start_osc, phase
    with warnings.catch_warnings():
        if not problem.multipliers_defined:  # a zero-velocity impact: G's pole is expected
            warnings.simplefilter("ignore", LowImpactVelocityWarning)  # only delta is used
        orbits = periodic_orbits(start_osc, N)
    if not orbits:
        raise NoPeriodicMotionError(f"start: no N={N} motion at {dict(values)} "
                                    f"(c^2 + s^2 < b^2); give 'delta' or another start")
    if root is not None:
        if root not in (1, -1):
            raise ParameterError(f"root must be +1, -1 or None; got {root!r}")
        orbits = [o for o in orbits if o.root == root] or orbits

    def condition(orbit: PeriodicOrbit) -> float:
        try:
            u = problem.initial_unknowns(p1v, p2v, orbit.delta)
        except ParameterError:
            return math.inf
        return float(np.max(np.abs(problem.residual(u, p2v))))

    return start_osc, min(orbits, key=condition).delta


# -- continuation -------------------------------------------------------------------------------
class _CurveWatch:
    """The stop rule of one direction of a curve: its ends and the bounds of ``p1``.

    A curve ends at a codim-2 point (GR+ZV on a grazing curve, R1/R2 on a
    Neimark-Sacker curve), recorded in ``ends`` as ``(label, x, precision,
    status)``; the located end replaces the last point. ``p1`` is an unknown,
    so the core does not see its bounds: the point on the bound ends the curve.
    """

    def __init__(self, problem: CurveProblem, p1_bounds: tuple[float, float],
                 ends: list[tuple[str, np.ndarray, float, str]]) -> None:
        self.problem = problem
        self.p1_bounds = p1_bounds
        self.ends = ends

    def __call__(self, previous: ContinuationPoint | None, current: ContinuationPoint
                 ) -> Stop | None:
        if previous is None:
            return None
        problem, xa, x = self.problem, previous.state, current.state
        p1, p2 = problem.parameters
        event = problem.terminal_event(xa, x)
        if event is not None:
            label, condition = event
            ga, gb = condition(xa), condition(x)
            t = ga / (ga - gb) if ga != gb else 0.5
            try:  # ill-conditioned at a strong resonance: a looser tolerance
                # Newton stagnates at the singular end: start it from the secant
                # estimate and accept a rounding-size residual (its step is the precision)
                xe = problem.solve(xa + t * (x - xa), condition, tol=1e-9, residual_tol=1e-9)
            except NewtonConvergenceError as exc:
                # the augmented system is singular at the end itself (a Jordan block at
                # a strong resonance): keep the bracket
                log.info("%s curve end (%s) bracketed, not located: %s", problem.kind, label, exc)
                # recorded, not kept: an interpolated point is not on the curve
                xe = xa + t * (x - xa)
                self.ends.append((label, xe, float(np.hypot(x[0] - xa[0], x[-1] - xa[-1])),
                                  "bracketed"))
                return Stop(ContinuationStatus.CURVE_END, f"at {label} (bracketed): {p1}="
                            f"{xe[0]:.10g}, {p2}={xe[-1]:.10g}", keep=False)
            precision = max(problem.last_step, 1e-15)
            if label in ("R1", "R2"):
                # the NS system is singular there: locate the double multiplier +-1 on a
                # regular system; without it the end is only bracketed
                refined = problem.resonance_end(xe, label)
                if refined is None:
                    self.ends.append((label, xe, precision, "bracketed"))
                    return Stop(ContinuationStatus.CURVE_END, f"at {label} (bracketed): "
                                f"{p1}={xe[0]:.10g}, {p2}={xe[-1]:.10g}", keep=False)
                xe, precision = refined
            self.ends.append((label, xe, precision, "located"))
            return Stop(ContinuationStatus.CURVE_END, f"at {label}: {p1}={xe[0]:.10g}, "
                        f"{p2}={xe[-1]:.10g}", point=_on_curve(current, xe))
        lo, hi = self.p1_bounds
        if lo <= x[0] <= hi:
            return None
        bound = lo if x[0] < lo else hi
        try:
            xe = problem.solve(xa + (bound - xa[0]) / (x[0] - xa[0]) * (x - xa),
                               lambda y, v=bound: float(y[0] - v), np.eye(x.size)[0])
        except NewtonConvergenceError as exc:
            return Stop(ContinuationStatus.BOUNDS_REACHED, f"{p1} bound {bound:.10g} crossed, "
                        f"point on it not found ({exc})", keep=False)
        return Stop(ContinuationStatus.BOUNDS_REACHED, f"{p1} = {bound:.10g}",
                    point=_on_curve(current, xe))


def _on_curve(point: ContinuationPoint, x: np.ndarray) -> ContinuationPoint:
    """`point` moved to the extended state ``x = [u, lam]`` (same tangent)."""
    return dataclasses.replace(point, u=x[:-1].copy(), lam=float(x[-1]))


def _point_columns(problem: CurveProblem, xs: list[np.ndarray]
                   ) -> tuple[dict[str, np.ndarray], list[PeriodicOrbit], list[dict[str, float]]]:
    orbits = [problem.orbit(x[:-1], x[-1]) for x in xs]
    n2 = 2 * problem.osc.n
    tests = [test_values(problem, x, o) for x, o in zip(xs, orbits, strict=True)]
    cols: dict[str, list[Any]] = {k: [] for k in (
        "delta", "root", "impact_velocity", "gap_min", "spectral_radius", "multipliers", "state",
        "physical", "stable_side", "residual", "tangency_time", "angle")}
    defined = problem.multipliers_defined  # not on a ZV curve: G has its pole (eq. 25)
    for x, o in zip(xs, orbits, strict=True):
        mu = o.multipliers if defined else np.full(n2, np.nan + 0j)
        rest = problem.other_multipliers(mu, x)
        gap = problem.grazing_test(x, o)
        physical = bool(o.impact_velocity > 0 and gap > 0)
        cols["delta"].append(math.remainder(float(x[1]), 2 * math.pi))
        cols["root"].append(problem.root(x))
        cols["impact_velocity"].append(o.impact_velocity)
        cols["gap_min"].append(gap)
        cols["spectral_radius"].append(float(np.max(np.abs(mu))) if defined else np.nan)
        cols["multipliers"].append(mu)
        cols["state"].append(o.state)
        cols["physical"].append(physical)
        cols["stable_side"].append(bool(defined and physical and rest.size
                                        and np.all(np.abs(rest) < 1.0)))
        problem.accept(x[:-1], x[-1])  # borders / reference vector of this very point
        cols["residual"].append(float(np.max(np.abs(problem.residual(x[:-1], x[-1])))))
        for name, value in problem.angles(x).items():
            cols[name].append(value)
    out = {k: np.array(v) for k, v in cols.items()}
    p1, p2 = problem.parameters
    values = {p1: np.array([x[0] for x in xs]), p2: np.array([x[-1] for x in xs])}
    for name in dict.fromkeys(["omega", "b", p1, p2]):
        out[name] = values[name] if name in values else \
            np.full(len(xs), float(getattr(problem.osc, name)))
    steps = np.hypot(np.diff(values[p1]), np.diff(values[p2]))
    out["arclength"] = np.concatenate([[0.0], np.cumsum(steps)])
    return out, orbits, tests


def check_curve_arguments(
        osc: ImpactOscillator | None, N: int | None = 1, kind: Label | str = "PD", *,
        start: xr.Dataset | Mapping[str, float] | None = None,
        parameters: Sequence[str] = ("omega", "b"),
        bounds: Mapping[str, Sequence[float]] | Sequence[Sequence[float]] | None = None,
        options: ContinuationOptions | None = None, **single: Any
        ) -> tuple[Label, tuple[str, str], dict[str, tuple[float, float]], int | None,
                   ContinuationOptions]:
    """The checks :func:`curve` makes of its arguments before it computes.

    :func:`curve` calls it first; a scene's validation (``impactcont run --check``)
    calls it on an entry's arguments, so both refuse the same input with the same
    message. The arguments are those of :func:`curve`; `start` is only looked at to
    tell whether `osc` may be None (a branch dataset gives the oscillator).

    Parameters
    ----------
    osc : ImpactOscillator or None
        The oscillator; ``None`` only with a branch dataset as `start`.
    N : int or None
        One impact every N forcing periods.
    kind : Label or str
        The kind of curve.
    start : xarray.Dataset, mapping or None
        The start (see :func:`curve`).
    parameters : (str, str)
        ``(p1, p2)``.
    bounds : mapping or pair of pairs
        The box ``{p1: (lo, hi), p2: (lo, hi)}``.
    options : ContinuationOptions, optional
        Continuation options.
    **single
        Single options (``ds``, ``ds_max``, ...; ``None`` means not given), over `options`.

    Returns
    -------
    kind : Label
        The kind as its Label (a string given is converted).
    parameters : (str, str)
    box : dict of str to (float, float)
        The bounds of `p1` and `p2`.
    N : int or None
    options : ContinuationOptions
        The options of the run, ``bounds`` the box's range of ``p2``.

    Raises
    ------
    ParameterError
        `kind` not one of :data:`impactcont.problems.codim1.CURVE_KINDS`; `osc` None
        without a branch dataset as `start`, or not an ImpactOscillator; `parameters` not
        two different continuable parameters of the oscillator; `bounds` missing, not
        finite intervals ``lo < hi`` for exactly those parameters; `N` not an integer
        >= 1; or a bad option (:class:`ContinuationOptionError`, named).
    """
    kind = curve_kind(kind)
    if osc is None and not isinstance(start, xr.Dataset):
        raise ParameterError("osc may be None only when start is a branch dataset; got "
                             f"start={type(start).__name__}")
    if osc is not None and not isinstance(osc, ImpactOscillator):
        raise ParameterError(f"osc must be an ImpactOscillator; got {osc!r}")
    parameters = check_parameters(osc if osc is not None else oscillator_from_dataset(start),
                                  tuple(parameters) if not isinstance(parameters, str)
                                  else parameters)
    if bounds is None:
        raise ParameterError(f"bounds must be given for both parameters {parameters}; got None")
    box = _check_bounds(bounds, parameters,
                        osc if osc is not None else oscillator_from_dataset(start))
    if N is not None:
        N = _check_N(N)
    p2 = parameters[1]
    opts = driver_options(options, box[p2], defaults=_DEFAULTS,
                          **{**single, "bounds": box[p2]})
    return kind, parameters, box, N, opts


def _motion_curve(osc: ImpactOscillator | None, N: int | None, kind: str,
                  branch: xr.Dataset, *, special: int | None, parameters: Sequence[str],
                  bounds: Any, root: int | None, detect_codim2_points: bool,
                  **keywords: Any) -> xr.Dataset:
    """The curve from a branch of N-p motions (:func:`curve` given such a branch).

    Forwards to :func:`impactcont.multi_impact_curve` with ``which = special`` and
    ``parameter = p2``; ``p1`` must be the branch's parameter.
    """
    p1 = str(branch.attrs.get("parameter"))
    given = tuple(parameters) if not isinstance(parameters, str) else (parameters,)
    if len(given) != 2 or given[0] != p1:
        raise ParameterError(f"parameters must be (p1, p2) with p1 the branch's parameter "
                             f"{p1!r}; got {parameters!r}")
    for name, value, allowed in (("osc", osc, (None,)), ("root", root, (None,))):
        if value not in allowed:
            raise ParameterError(f"{name} must be left out when the curve starts from a "
                                 f"branch of N-p motions (the branch fixes it); got "
                                 f"{name}={value!r}")
    if N not in (None, 1, int(branch.attrs["N"])):
        raise ParameterError(f"N must be left out or the branch's N = "
                             f"{int(branch.attrs['N'])}; got N={N!r}")
    if bounds is not None and not isinstance(bounds, Mapping):
        try:
            bounds = dict(zip(given, bounds, strict=True))
        except (TypeError, ValueError):
            raise ParameterError(f"bounds must be a mapping {{p1: (lo, hi), p2: (lo, hi)}} or "
                                 f"two pairs; got {bounds!r}") from None
    return multi_impact_curve(branch, kind, 0 if special is None else special,
                              parameter=given[1], bounds=bounds,
                              detect_codim2_points=detect_codim2_points, **keywords)


@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_DEFAULTS})
def curve(osc: ImpactOscillator | None, N: int | None = 1, kind: Label | str = "PD", *,
          start: xr.Dataset | Mapping[str, float] | None = None, special: int | None = None,
          parameters: Sequence[str] = ("omega", "b"),
          bounds: Mapping[str, Sequence[float]] | Sequence[Sequence[float]] | None = None,
          root: int | None = None, detect_codim2_points: bool = True,
          options: ContinuationOptions | None = None, ds: float | None = None,
          ds_min: float | None = None, ds_max: float | None = None,
          newton_tol: float | None = None, max_points: int | None = None,
          both_directions: bool | None = None, progress: ProgressOption = None,
          events: dict[str, Any] | None = None, monitors: dict[str, Any] | None = None,
          **more: Any) -> xr.Dataset:
    """Continue a codim-1 curve of N-1 motions in two parameters.

    Parameters
    ----------
    osc : ImpactOscillator or None
        The oscillator (other parameters fixed at its values); ``None`` only
        with a branch dataset as ``start``, whose oscillator is then used.
    N : int or None
        One impact every N forcing periods; ``None`` takes it from a branch
        dataset given as ``start``.
    kind : Label or str
        Saddle-node, period-doubling, Neimark-Sacker, grazing or
        zero-velocity-impact curve (augmented systems in
        :mod:`impactcont.problems.codim1`).
    start : xarray.Dataset, mapping or None
        A branch dataset from :func:`impactcont.continuation` (its first
        located special point of this kind, or the one at index ``special``);
        or explicit values ``{p1: .., p2: .., "delta": ..}`` (``delta``
        optional), corrected by Newton at fixed ``p2``; or None: the first
        located point of this kind on the one-parameter branch in ``p1`` at the
        oscillator's value of ``p2`` (``special`` then counts those points).
    special : int, optional
        Which special point (see ``start``).
    parameters : (str, str)
        ``(p1, p2)``, any two of ``omega, b, R, eta, alpha, beta, F0`` (with a
        damping matrix C: ``omega, b, R, F0``) and the elements of the model (``k2``,
        ``M[1,2]``, ``K[1,2]``, ``F[2]``, ...; set by their
        :class:`~impactcont.model.parameters.ModelParameter`). ``p2`` is the continuation
        parameter of the core; ``p1`` is an unknown. From a branch of N-p motions ``p1`` is
        the branch's parameter (any parameter of :func:`impactcont.multi_impact_curve`).
    bounds : mapping or pair of pairs
        The box ``{p1: (lo, hi), p2: (lo, hi)}``; the curve stops on its edges.
    root : {+1, -1}, optional
        With explicit start values and no ``delta``: the root of eq. (15).
    detect_codim2_points : bool
        Locate the codim-2 points on the curve.
    options : ContinuationOptions, optional
        Options left out take the drivers' defaults
        (:data:`impactcont.core.options.DRIVER_DEFAULTS`), but Newton tolerance 1e-11
        and first step 0.01; ``bounds`` is the box's range of ``p2``.
    ds, ds_min, ds_max, newton_tol, max_points, both_directions, **more
        Single options, over `options` (``ds`` and ``ds_min`` adapt to a ``ds_max``
        given alone).
    progress : None, bool or callable
        A progress bar on stderr (``None``: when stderr is a terminal, after 2 s;
        ``True``: always; ``False``: never) or a callable receiving a
        :class:`~impactcont.progress.Progress` record at every curve point, with the
        value of ``p2`` (:mod:`impactcont.progress`). A call longer than a minute logs
        a line a minute.
    events, monitors : mapping of str to callable, optional
        User events and monitors, as for :func:`impactcont.continuation`: functions of
        the :class:`~impactcont.PeriodicOrbit` at a curve point; an event's zeros on the
        curve are located on the dimension ``event`` (``event_precision`` bounds the
        error in both parameters).

    Returns
    -------
    xarray.Dataset
        Dimensions ``point``, ``multiplier``, ``component``, ``codim2`` (and ``event``
        with `events`); schema in :mod:`impactcont.dataset.curves` and
        ``docs/two_parameter.md``. From a branch of N-p motions: the N-p curve dataset of
        :func:`impactcont.multi_impact_curve`, with its codim-2 points on ``codim2`` too.

    Raises
    ------
    ParameterError
        A bad argument (named in the message), bad `events` or `monitors`, or one of
        their functions failed (named; a non-callable: TypeError).
    NoPeriodicMotionError
        No start point could be found.

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) ends the call with what it has computed: the
    curve stops at its last accepted point (the other direction is not followed) and the
    codim-2 points of the points kept are located (Ctrl-C during that keeps those located
    before it and the curve's ends found). ``end_status`` and the ``options`` attribute then
    say ``"interrupted by the user (KeyboardInterrupt) after K points, ..."``, the options
    record ``"interrupted": true`` and where (``"interrupted_while": "continuation"`` or
    ``"location"``), and the log has a WARNING. A second Ctrl-C, or one
    before the first point (or while the start is searched), aborts with
    :class:`KeyboardInterrupt`.
    The dataset's attribute ``interrupted`` is then 1, as an interrupted map's.
    """
    if isinstance(start, xr.Dataset) and "impact" in start.dims:
        return _motion_curve(osc, N, kind, start, special=special, parameters=parameters,
                             bounds=bounds, root=root,
                             detect_codim2_points=detect_codim2_points, options=options,
                             ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol,
                             max_points=max_points, both_directions=both_directions,
                             progress=progress, events=events, monitors=monitors, **more)
    kind, parameters, box, N, opts = check_curve_arguments(
        osc, N, kind, start=start, parameters=parameters, bounds=bounds, options=options,
        ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol, max_points=max_points,
        both_directions=both_directions, **more)
    functions = check_user_functions(events, monitors, reserved_names())
    if isinstance(start, xr.Dataset):
        start_osc, N, delta0 = _start_from_branch(start, kind, special, osc, N, parameters)
    elif start is None:
        if N is None:
            raise ParameterError("N must be given unless start is a branch dataset; got None")
        start_osc, N, delta0 = _start_by_continuation(osc, N, kind, special, parameters, box)
    elif isinstance(start, Mapping):
        if N is None:
            raise ParameterError("N must be given unless start is a branch dataset; got None")
        start_osc, delta0 = _start_from_values(osc, N, curve_problem(kind, osc, N, parameters),
                                               start, root)
    else:
        raise ParameterError(f"start must be a branch Dataset, a mapping of values or None; "
                             f"got {type(start).__name__}")
    p1, p2 = parameters
    p1v, p2v = _value(start_osc, p1), _value(start_osc, p2)
    for name, value in ((p1, p1v), (p2, p2v)):
        lo, hi = box[name]
        if not lo <= value <= hi:
            raise ParameterError(f"the start {name}={value!r} lies outside bounds[{name!r}] = "
                                 f"{box[name]}")
    problem = curve_problem(kind, start_osc, N, parameters)
    u0 = problem.initial_unknowns(p1v, p2v, delta0)
    log.info("%s curve, N=%d, from %s=%.10g, %s=%.10g", kind, N, p1, p1v, p2, p2v)

    ends: list[tuple[str, np.ndarray, float, str]] = []
    what = f"{kind} curve in ({p1}, {p2})"
    with interruptible(what) as call, reporter(progress, what, parameter=p2) as rep:
        result = follow(problem, u0, p2v, opts, rep.point,
                        stop=lambda direction: _CurveWatch(problem, box[p1], ends))
        if result.interrupted and len(result) == 0:
            raise NothingComputed(f"{what} interrupted before its first point")
        if result.status is ContinuationStatus.NEWTON_FAILED_AT_START:
            raise NoPeriodicMotionError(f"{kind} curve: Newton failed at the start "
                                        f"({result.message})")
        xs = [np.append(u, lam) for u, lam in zip(result.u, result.lam, strict=True)]
        status = result.message
        log.info("%s curve: %d points (%s)", kind, len(xs), status)

        columns, orbits, tests = _point_columns(problem, xs)
        found: list[Codim2Point] = []  # filled as they are located: Ctrl-C keeps them
        if detect_codim2_points:
            until_interrupted(
                lambda: detect_codim2(problem, xs, orbits, tests, found), None, "location",
                "interrupted by the user (KeyboardInterrupt) while locating the codim-2 "
                "points of the curve: those located before are kept (and its ends)")
        ds = _curve_dataset(problem, kind, N, parameters, box, opts, start_osc, (p1v, p2v),
                            delta0, columns, orbits, xs, found, ends, status, call)
        ds = _with_user_functions(ds, problem, result, orbits, functions)
        if call.interrupted:  # as an interrupted map says it (also when in its events)
            record = {**json.loads(ds.attrs["options"]), "interrupted": True}
            ds.attrs["options"] = json.dumps(record, sort_keys=True)
            ds.attrs["interrupted"] = 1
        return ds


def _curve_dataset(problem: CurveProblem, kind: Label, N: int, parameters: tuple[str, str],
                   box: dict[str, tuple[float, float]], opts: ContinuationOptions,
                   start_osc: ImpactOscillator, start: tuple[float, float], delta0: float,
                   columns: dict[str, Any], orbits: list[PeriodicOrbit], xs: list[np.ndarray],
                   found: list[Codim2Point], ends: list[tuple[str, np.ndarray, float, str]],
                   status: str, call: Interruption) -> xr.Dataset:
    """The curve's dataset: its points, its codim-2 points and ends, how it stopped."""
    p1, p2 = parameters
    p1v, p2v = start
    for label, xe, precision, end_status in ends:
        k = int(np.argmin([np.linalg.norm(xe - x) for x in xs]))
        orbit = problem.orbit(xe[:-1], xe[-1]) if end_status == "located" else orbits[k]
        found.append(Codim2Point(label, xe, orbit, k, precision, end_status))
    found.sort(key=lambda cp: cp.point)
    records = [codim2_record(problem, cp) for cp in found if cp.label in CODIM2_LABELS]
    option_record = {**dataclasses.asdict(opts), "kind": str(kind), "N": N,
                     "parameters": list(parameters), "bounds": {k: list(v) for k, v in box.items()},
                     "start": {p1: p1v, p2: p2v, "delta": delta0}}
    option_record["bounds_continued"] = list(opts.bounds)
    if call.interrupted:
        option_record["interrupted"] = True
        option_record["interrupted_while"] = call.where
    return curve_dataset(kind=str(kind), N=N, parameters=parameters, oscillator=start_osc,
                         options=option_record, columns=columns, codim2_points=records,
                         end_status=status)


def _with_user_functions(ds: xr.Dataset, problem: CurveProblem, result: Any,
                         orbits: list[PeriodicOrbit], functions: UserFunctions) -> xr.Dataset:
    """`ds` with the user's monitors at every curve point and its events located on the curve.

    Each step with a sign change is searched after the augmented system's borders are
    renewed at its first point (as for the codim-2 points); the precision is in both
    parameters (``p1`` is the first unknown).
    """
    if not functions:
        return ds
    p2 = problem.parameters[1]
    values = user_values(functions, orbits, p2)
    found = until_interrupted(lambda: locate_user_events(
        problem, result.u, result.lam, result.tangent, functions, values,
        lambda u, lam: problem.orbit(u, float(lam)), position=lambda u, lam: (u[0], lam),
        accept=lambda k: problem.accept(result.u[k], result.lam[k]), parameter=p2), [],
        "location", "interrupted by the user (KeyboardInterrupt) while locating the user "
        "events of the curve: they are dropped (the user's functions at the points are kept)")
    names = parameter_names(ds)
    return add_user_functions(ds, monitors=values, events=list(functions.events),
                              event_points=[user_event_record(ev, names) for ev in found])


def curve_crossings(ds: xr.Dataset, parameter: str, value: float) -> list[dict[str, float]]:
    """Exact points where a continued curve crosses the line ``parameter = value``.

    Each crossing between two consecutive curve points is re-solved by Newton on
    the curve's augmented system with ``parameter`` fixed, so the result is as
    accurate as the closed form (not an interpolation of the polyline).

    Parameters
    ----------
    ds : xarray.Dataset
        A curve dataset from :func:`curve`.
    parameter : str
        One of the curve's two parameters.
    value : float

    Returns
    -------
    list of dict
        Per crossing, in curve order: the values of ``omega``, ``b`` (and the
        curve's parameters), ``delta``, ``root`` (of eq. 15; 0 on an SN curve)
        and ``point`` (index of the first of the two bracketing points).
    """
    validate_curve_dataset(ds)
    parameters = tuple(split_parameters(str(ds.attrs["parameters"])))
    check_crossing_line(parameters, parameter, value)
    kind = str(ds.attrs["kind"])
    base = ImpactOscillator.from_json(ds.attrs["oscillator"])
    problem = curve_problem(kind, base, int(ds.attrs["N"]), parameters)
    p = np.asarray(ds[parameter].values, dtype=float)
    index = parameters.index(parameter)
    out = []
    for k, t in crossing_steps(p, value):
        row = {name: float(ds[name].values[k] + t * (ds[name].values[k + 1]
                                                      - ds[name].values[k]))
               for name in parameters}
        delta = float(ds["delta"].values[k])
        extras = problem.stored_extras(ds, k)
        u = problem.initial_unknowns(row[parameters[0]], row[parameters[1]], delta, extras)
        x = np.append(u, row[parameters[1]])
        gradient = np.zeros(x.size)
        gradient[0 if index == 0 else -1] = 1.0
        x = problem.solve(x, lambda y, j=(0 if index == 0 else -1): float(y[j] - value),
                          gradient)
        osc = problem.oscillator_at(x[0], x[-1])
        crossing = {name: problem.parameter_value(osc, name)
                    for name in dict.fromkeys(["omega", "b", *parameters])}
        crossing["delta"] = math.remainder(float(x[1]), 2 * math.pi)
        crossing["root"] = problem.root(x)
        crossing["point"] = int(k)
        out.append(crossing)
    return out

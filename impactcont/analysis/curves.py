"""Two-parameter continuation of codim-1 curves of every motion: SN, PD, NS, GR, ZV, BP,
and SE, RG, SO of motions with sticking phases.

``curve(osc, N, kind, start=..., parameters=(p1, p2), bounds=...)`` = pick a start (a
special point of a branch dataset, N-1 or N-p; a motion; explicit values; or one found
by a one-parameter continuation) -> the curve problem of :mod:`impactcont.problems.codim1`
(the motion's branch problem plus the kind's test function; the closed form evaluates it
where the motion is N-1, shooting for every N-p motion) -> follow it with the
pseudo-arclength core in both directions until the box ``bounds`` or a curve end ->
evaluate the motion at every point -> detect and locate the codim-2 points
(:mod:`impactcont.detection.codim2`, one location for both evaluators) -> an
:class:`xarray.Dataset`: the curve schema of :mod:`impactcont.dataset.curves` for the
closed form, an N-p branch dataset in ``p2`` with the column of ``p1`` for shooting
(attributes ``curve_kind``, ``parameters = "p1,p2"``, ``born_at_value``; its codim-2
points on the dimension ``codim2`` with the variables of an N-1 curve dataset).

:func:`curve_crossings` solves a curve exactly where it crosses a line
``parameter = value`` (used to compare with one-parameter special points and
with the grid of a map). :func:`multi_impact_curve` and
:func:`multi_impact_curve_crossings` are the earlier names of the curve of an N-p branch
and of its crossings.
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

from impactcont.analysis.branch import (
    branch_to_dataset,
    continuation,
    not_a_branch,
    user_events_until_interrupted,
    with_user_functions,
)
from impactcont.analysis.switching import special_orbit
from impactcont.core import (
    ContinuationOptions,
    ContinuationPoint,
    ContinuationStatus,
    Stop,
    follow,
)
from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.locate import crossing_steps
from impactcont.core.options import DRIVER_DEFAULTS, driver_options, option_keywords
from impactcont.core.stepper import NewtonConvergenceError
from impactcont.dataset.attributes import split_parameters
from impactcont.dataset.curves import (
    CODIM2_LABELS,
    CURVE_VARIABLES,
    codim2_data,
    curve_dataset,
    validate_curve_dataset,
)
from impactcont.dataset.multi import impacts_of, pattern_of
from impactcont.dataset.records import reserved_names
from impactcont.dataset.schema import (
    oscillator_from_dataset,
    special_variable,
    validate_branch_dataset,
)
from impactcont.detection.codim2 import Codim2Point, codim2_record, detect_codim2, test_values
from impactcont.detection.special_points import (
    BranchSample,
    UserFunctions,
    check_user_functions,
    locate_user_events,
    user_values,
)
from impactcont.errors import (
    ImpactcontError,
    LowImpactVelocityWarning,
    NoPeriodicMotionError,
    ParameterError,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import check_model_bounds, model_parameter
from impactcont.orbit.multi_impact import MultiImpactOrbit, initial_unknowns
from impactcont.orbit.periodic import PeriodicOrbit, _check_N, periodic_orbits
from impactcont.problems.codim1 import (
    NOISE_MARGIN,
    SHOOTING_KINDS,
    CurveProblem,
    ShootingCurve,
    check_parameters,
    curve_kind,
    curve_problem,
)
from impactcont.progress import (
    Interruption,
    NothingComputed,
    ProgressOption,
    interrupted,
    interruptible,
    reporter,
    until_interrupted,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import Label

__all__ = ["check_curve_arguments", "crossing_steps", "curve", "curve_crossings",
           "multi_impact_curve", "multi_impact_curve_crossings"]

log = logging.getLogger(__name__)

_DEFAULTS = {"newton_tol": 1e-11, "ds": 0.01}
"""The closed form's augmented systems: a looser tolerance than its branches. The first
step stays 0.01: the PD system is singular at a zero-velocity impact (the pole of G), and
a point next to one is found or not depending on the steps there."""
_SHOOTING_DEFAULTS = {"newton_tol": 1e-10, "ds": 0.01, "both_directions": True}
"""Shooting: the row of the test function is a forward difference (problems.codim1)."""
_START_TOL = 1e-11  # Newton on the hyperplane p2 = start (shooting's start and crossings)


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
        out[name] = check_model_bounds(name, (lo, hi), argument=f"bounds[{name!r}]")
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
                           parameters: tuple[str, str], bounds: dict[str, tuple[float, float]],
                           root: int | None = None) -> tuple[ImpactOscillator, int, float]:
    p1 = parameters[0]
    # a root given: the component through the motion of that root (else every component)
    branch = continuation(osc, N, p1, bounds[p1], detect=[kind], progress=False,
                          **({} if root is None else {"root": root, "components": "start"}))
    if json.loads(branch.attrs.get("options", "{}")).get("interrupted"):
        raise NothingComputed(f"{kind} curve interrupted while its start was searched")
    rows = [k for k, (lab, st) in enumerate(zip(branch["special_label"].values,
                                                branch["special_status"].values, strict=True))
            if lab == kind and st == "located"]
    if not rows:
        raise NoPeriodicMotionError(
            f"no located {kind} point on the N={N} branch in {p1} in {bounds[p1]} at "
            f"{parameters[1]}={_value(osc, parameters[1])!r}; give start explicitly")
    if special is not None and not -len(rows) <= special < len(rows):
        raise ParameterError(f"special={special!r} is out of range: the N={N} branch in {p1} "
                             f"in {bounds[p1]} has {len(rows)} located {kind} point(s)")
    k = rows[0] if special is None else rows[special]
    return _start_from_branch(branch, kind, k, None, N, parameters)


def _check_special_and_root(special: Any, root: Any, start: Any) -> None:
    """`special` an integer index or None; `root` +1, -1 or None, and given only where it
    chooses the start (explicit values, or None: the branch searched for the start)."""
    if special is not None and (isinstance(special, bool)
                                or not isinstance(special, (int, np.integer))):
        raise ParameterError(f"special must be an integer index (or None); got {special!r}")
    if root is None:
        return
    if isinstance(root, bool) or root not in (1, -1):
        raise ParameterError(f"root must be +1, -1 or None; got {root!r}")
    if isinstance(start, xr.Dataset):
        raise ParameterError(f"root must be left out when start is a branch dataset (the "
                             f"branch's special point fixes the motion); got root={root!r}")


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
    """The stop rule of one direction of a curve (either evaluator): its ends and the
    bounds of ``p1``.

    A curve ends at a codim-2 point (GR+ZV on a grazing curve, R1/R2 on a
    Neimark-Sacker curve of the closed form), recorded in ``ends`` as ``(label, x,
    precision, status)``; the located end replaces the last point. ``p1`` is an unknown,
    so the core does not see its bounds: the point on the bound (Newton on the
    hyperplane ``p1 = bound``) ends the curve. With `orbits` (a curve followed by
    shooting), the motion at every point it sees is kept there by :func:`_orbit_key`: its
    branch problem and shot are at hand (the core has just taken the tangent there), so
    the motions of the dataset cost no new problem and no new shot after the run.
    """

    def __init__(self, problem: CurveProblem | ShootingCurve, p1_bounds: tuple[float, float],
                 ends: list[tuple[str, np.ndarray, float, str]],
                 orbits: dict[tuple[bytes, float], Any] | None = None) -> None:
        self.problem = problem
        self.p1_bounds = p1_bounds
        self.ends = ends
        self.orbits = orbits

    def __call__(self, previous: ContinuationPoint | None, current: ContinuationPoint
                 ) -> Stop | None:
        if self.orbits is not None:
            _keep_orbit(self.problem, current, self.orbits)
        if previous is None:
            return None
        problem, xa, x = self.problem, previous.state, current.state
        p1, p2 = problem.parameters
        unphysical = self._physical_end(previous, current)
        if unphysical is not None:
            return unphysical
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
        i = problem.p1_index  # where p1 is in x
        if lo <= x[i] <= hi:
            return None
        bound = lo if x[i] < lo else hi
        guess = xa + (bound - xa[i]) / (x[i] - xa[i]) * (x - xa)
        guess[i] = bound
        try:
            xe = problem.on_hyperplane(guess, np.eye(x.size)[i])
        except NewtonConvergenceError as exc:
            return Stop(ContinuationStatus.BOUNDS_REACHED, f"{p1} bound {bound:.10g} crossed, "
                        f"point on it not found ({exc})", keep=False)
        return Stop(ContinuationStatus.BOUNDS_REACHED, f"{p1} = {bound:.10g}",
                    point=_on_curve(current, xe))


    def _physical_end(self, previous: ContinuationPoint, current: ContinuationPoint
                      ) -> Stop | None:
        """The end of a curve of motions with sticking phases where its motion stops being
        physical between two accepted points
        (:meth:`~impactcont.problems.codim1.ShootingCurve.physical_end`): the point past it
        is kept, so that the crossing is located as the curve's codim-2 point."""
        check = getattr(self.problem, "physical_end", None)
        if check is None or self.orbits is None:
            return None
        orbits = [self.orbits.get(_orbit_key(point.u, point.lam))
                  for point in (previous, current)]
        if any(orbit is None for orbit in orbits):
            return None
        xa, xb = previous.state, current.state
        try:
            why = check(xa, orbits[0], xb, orbits[1])
        except (ImpactcontError, ArithmeticError, np.linalg.LinAlgError):
            return None
        if why is None:
            return None
        p1, p2 = self.problem.parameters
        return Stop(ContinuationStatus.CURVE_END,
                    f"the motion stops being physical between {p1}={xa[-2]:.10g}, "
                    f"{p2}={xa[-1]:.10g} and {p1}={xb[-2]:.10g}, {p2}={xb[-1]:.10g}: {why}")


def _orbit_key(x: np.ndarray, lam: float) -> tuple[bytes, float]:
    """Where :class:`_CurveWatch` keeps the motion at the curve point ``(x, lam)``."""
    return np.asarray(x, dtype=float).tobytes(), float(lam)


def _keep_orbit(problem: ShootingCurve, point: ContinuationPoint,
                orbits: dict[tuple[bytes, float], Any]) -> None:
    """The motion at an accepted curve point, into `orbits` (:class:`_CurveWatch`).

    A motion that cannot be evaluated is left out: it is asked for again after the run,
    where its error is raised if the point is kept. The start, seen by both directions, is
    evaluated once.
    """
    key = _orbit_key(point.u, point.lam)
    if key in orbits:
        return
    try:
        orbits[key] = problem.orbit(point.u, point.lam)
    except (ImpactcontError, ArithmeticError, np.linalg.LinAlgError):
        return


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
    # the curve's own bound is left out of `physical`, as a GR curve's gap leaves out the
    # tangency: along a ZV curve the impact velocity is zero to rounding and its sign flips
    # from point to point (+-1e-17), which drew the curve's pieces at random
    own_velocity = problem.kind is Label.ZV
    for x, o in zip(xs, orbits, strict=True):
        mu = o.multipliers if defined else np.full(n2, np.nan + 0j)
        rest = problem.other_multipliers(mu, x)
        gap = problem.grazing_test(x, o)
        physical = bool((own_velocity or o.impact_velocity > 0) and gap > 0)
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


def _from_orbit(osc: ImpactOscillator | None, N: int | None, orbit: PeriodicOrbit,
                parameters: Sequence[str]) -> tuple[ImpactOscillator, int, dict[str, float]]:
    """An N-1 motion given as start: its oscillator, its N and its values of the two
    parameters and phase, as explicit start values."""
    if osc is not None and not _same_system(osc, orbit.oscillator, set(parameters)):
        raise ParameterError(f"osc differs from the oscillator of the motion given as start "
                             f"(other than the parameters): {osc!r} vs {orbit.oscillator!r}")
    if N is not None and _check_N(N) != orbit.N:
        raise ParameterError(f"N={N!r} differs from the motion's N={orbit.N}")
    parameters = check_parameters(orbit.oscillator, tuple(parameters)
                                  if not isinstance(parameters, str) else parameters)
    values = {name: _value(orbit.oscillator, name) for name in parameters}
    return orbit.oscillator, orbit.N, {**values, "delta": float(orbit.delta)}


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


def _check_branch_start(start: xr.Dataset) -> None:
    """A dataset given as start is a one-parameter branch: a curve, a map or a simulation
    (which have impacts too) is refused, naming what it is."""
    what = not_a_branch(start.attrs)
    if what:
        raise ParameterError(f"start must be a one-parameter branch dataset (a curve starts "
                             f"from one of its special points); got {what}")
    try:
        validate_branch_dataset(start)
    except ValueError as exc:
        raise ParameterError(f"start is not a branch dataset: {exc}") from None


def _motion_curve(osc: ImpactOscillator | None, N: int | None, kind: Label | str,
                  start: xr.Dataset | MultiImpactOrbit, *, special: int | None,
                  parameters: Sequence[str], bounds: Any, root: int | None,
                  **keywords: Any) -> xr.Dataset:
    """The curve from a branch of N-p motions or an N-p motion (:func:`curve` given one).

    From a branch, ``p1`` must be the branch's parameter; the motion fixes the oscillator,
    N and the root, which must be left out.
    """
    given = tuple(parameters) if not isinstance(parameters, str) else (parameters,)
    if isinstance(start, xr.Dataset):
        _check_branch_start(start)
        p1 = str(start.attrs.get("parameter"))
        if len(given) != 2 or given[0] != p1:
            raise ParameterError(f"parameters must be (p1, p2) with p1 the branch's parameter "
                                 f"{p1!r}; got {parameters!r}")
        motion_N = int(start.attrs["N"])
    else:
        if len(given) != 2:
            raise ParameterError(f"parameters must be two names (p1, p2); got {parameters!r}")
        motion_N = start.N
    for name, value in (("osc", osc), ("root", root)):
        if value is not None:
            raise ParameterError(f"{name} must be left out when the curve starts from an N-p "
                                 f"branch or motion (it fixes it); got {name}={value!r}")
    if N not in (None, 1, motion_N):
        raise ParameterError(f"N must be left out or the motion's N = {motion_N}; got N={N!r}")
    kind = curve_kind(kind, kinds=SHOOTING_KINDS)  # before counting the points of a kind
    which = 0 if special is None else special
    if isinstance(start, xr.Dataset) and isinstance(which, (int, np.integer)) \
            and not isinstance(which, bool):
        labels = start[special_variable("label")].values.tolist()
        count = sum(lab == str(kind) for lab in labels)
        if not -count <= which < count:  # (special_orbit would name its own argument)
            raise ParameterError(f"special={which!r} is out of range: the branch has {count} "
                                 f"{kind} point(s) (its special points: {labels})")
    return _shooting_curve(kind, start, which, given, bounds, **keywords)


def _check_motion_parameters(osc: ImpactOscillator, parameters: tuple[str, ...]
                             ) -> tuple[str, str]:
    """``(p1, p2)`` of a curve followed by shooting: two different parameters of `osc`."""
    p1, p2 = parameters
    if p1 == p2:
        raise ParameterError(f"parameters must be two different parameters; got {p1!r} twice")
    for name in (p1, p2):
        model_parameter(osc, name, "parameters")
    return str(p1), str(p2)


def _shooting_start(kind: Label, start: xr.Dataset | MultiImpactOrbit, which: int
                    ) -> tuple[MultiImpactOrbit, bool]:
    """The motion a shooting curve starts from and whether it is followed by its half."""
    if isinstance(start, MultiImpactOrbit):
        return start, False
    symmetric = bool(json.loads(start.attrs.get("options", "{}")).get("symmetric", False))
    rows = [i for i, lab in enumerate(start[special_variable("label")].values.tolist())
            if lab == kind]
    orbit = special_orbit(start, kind, which)  # (refuses an index out of range)
    k = rows[which]
    if start[special_variable("status")].values[k] != "located":
        log.warning("the %s point %d of the branch is only bracketed: the curve starts from "
                    "the motion re-solved there", kind, which)
    return orbit, symmetric


def _shooting_curve(kind: Label | str, start: xr.Dataset | MultiImpactOrbit, which: int,
                    parameters: tuple[str, ...], bounds: Any, *, options: Any = None,
                    progress: ProgressOption = None, events: dict[str, Any] | None = None,
                    monitors: dict[str, Any] | None = None, detect_codim2_points: bool = True,
                    **single: Any) -> xr.Dataset:
    """A curve followed by shooting (:class:`~impactcont.problems.codim1.ShootingCurve`),
    from a special point of an N-p branch dataset or from a motion (see :func:`curve`)."""
    functions = check_user_functions(events, monitors, reserved_names())
    kind = curve_kind(kind, kinds=SHOOTING_KINDS)
    base_osc = start.oscillator if isinstance(start, MultiImpactOrbit) \
        else oscillator_from_dataset(start)
    p1, parameter = parameters = _check_motion_parameters(base_osc, parameters)
    if bounds is None:
        raise ParameterError(f"bounds must be given: the box {{{p1!r}: (lo, hi), "
                             f"{parameter!r}: (lo, hi)}} of the curve")
    box = _check_bounds(bounds, parameters, base_osc)
    orbit, symmetric = _shooting_start(kind, start, which)
    osc = orbit.oscillator
    N, p, pattern = orbit.N, orbit.p, orbit.pattern
    problem = curve_problem(kind, osc, N, parameters, p=p, pattern=pattern, symmetric=symmetric)
    lam0, start_p1 = _value(osc, parameter), _value(osc, p1)
    for name, value in ((p1, start_p1), (parameter, lam0)):  # as the closed form's curve
        if not box[name][0] <= value <= box[name][1]:
            raise ParameterError(f"bounds[{name!r}] = {box[name]} must contain the start "
                                 f"{name}={value!r}")
    base = problem.branch_problem(lam0)
    u0 = base.half_unknowns(orbit.unknowns) if symmetric else orbit.unknowns
    # on the curve at fixed p2 (the special point is located to its precision only)
    target = np.append(np.append(u0, start_p1), lam0)
    normal = np.zeros(target.size)
    normal[-1] = 1.0
    found = solve_on_hyperplane(problem, target, normal, tol=_START_TOL, max_iter=30)
    if not found.converged:
        raise NoPeriodicMotionError(f"the {kind} point at {p1}={start_p1!r} could not be put "
                                    f"on the augmented system (last step {found.last_step:.3g})")
    x0 = found.x[:-1]
    noise = problem.test_noise(x0, lam0)
    opts = driver_options(options, box[parameter], defaults=_noise_defaults(kind, noise),
                          **single)
    if opts.newton_tol < NOISE_MARGIN * noise:
        log.warning("newton_tol=%.3g is below %g times the rounding noise %.3g of the %s test "
                    "at the start: Newton may stall there", opts.newton_tol, NOISE_MARGIN,
                    noise, kind)
    what = f"{kind} curve of {N}-{p} motions in ({p1}, {parameter})"
    with interruptible(what) as call, reporter(progress, what, parameter=parameter) as rep:
        kept: dict[tuple[bytes, float], MultiImpactOrbit] = {}
        losses: list[str] = []  # an RG curve's lost minimum as each direction ended

        def watch(direction: int) -> _CurveWatch:
            losses.append(getattr(problem, "lost_minimum", ""))
            return _CurveWatch(problem, box[p1], [], kept)

        result = follow(problem, x0, lam0, opts, rep.point, stop=watch)
        losses.append(getattr(problem, "lost_minimum", ""))
        if len(result) == 0 and result.interrupted:
            raise NothingComputed(f"{what} interrupted before its first point")
        if len(result) == 0:
            below = (f" (newton_tol={opts.newton_tol:.3g} is below {NOISE_MARGIN:g} times the "
                     f"{kind} test's rounding noise {noise:.3g} at the start)"
                     if opts.newton_tol < NOISE_MARGIN * noise else "")
            raise NoPeriodicMotionError(f"{kind} curve: {result.message}{below}")
        orbits = []
        for u, lam in zip(result.u, result.lam, strict=True):
            orbit = kept.get(_orbit_key(u, lam))
            orbits.append(problem.orbit(u, float(lam)) if orbit is None else orbit)
        samples = [BranchSample(u=x, lam=float(lam), tangent=t, orbit=o)
                   for x, lam, t, o in zip(result.u, result.lam, result.tangent, orbits,
                                           strict=True)]
        log.info("%s curve of the %d-%d motion in (%s, %s): %d points (%s)", kind, N, p, p1,
                 parameter, len(samples), result.message)
        found_points: list[Codim2Point] = []
        if detect_codim2_points:
            xs = [np.append(sample.u, sample.lam) for sample in samples]
            _locate_codim2(problem, xs, [sample.orbit for sample in samples], None,
                           found_points)
        # the user's events: located in both parameters (p1 is the last unknown)
        values, user_events = user_events_until_interrupted(
            problem, samples, functions, position=lambda x, lam: (x[-1], lam))
        was_interrupted, phase = interrupted(), call.where
    message = result.message
    lost = next((why for why in losses[1:] if why), "")
    if lost and ContinuationStatus.STEP_BELOW_MINIMUM in result.statuses:
        # an RG curve that could not go on: where its minimum was lost
        message = f"{message} (the {kind} test is undefined beyond: {lost})"
    record = {"kind": str(kind), "parameters": [p1, parameter], "start": start_p1,
              "bounds": {name: list(v) for name, v in box.items()}, "symmetric": symmetric,
              "test_noise": noise,
              "status": [st.name for st in result.statuses], "message": message,
              **{key: value for key, value in dataclasses.asdict(opts).items()
                 if key != "bounds"}}
    if was_interrupted:
        record["interrupted"] = True
        record["interrupted_while"] = phase
    info = {"curve_kind": str(kind), "parameters": f"{p1},{parameter}",
            "born_at_value": start_p1, "end_status": message}
    ds = branch_to_dataset(_CurveView(problem, parameter, osc), samples, [], record,
                           title=f"{kind} curve of periodic {N}-{p} impacting motions in "
                           f"({p1}, {parameter})", extra_attrs=info, extra_columns=(p1,),
                           functions=functions, values=values, user_events=user_events)
    records = [codim2_record(problem, cp) for cp in sorted(found_points, key=lambda cp: cp.point)
               if cp.label in CODIM2_LABELS]
    physical = np.array([problem.physical_on_curve(np.append(sample.u, sample.lam), o)
                         for sample, o in zip(samples, orbits, strict=True)], dtype=bool)
    ds["physical"] = ("point", physical, CURVE_VARIABLES["physical"].attrs())
    ds["stable_side"] = ("point", _stable_sides(problem, orbits, physical),
                         CURVE_VARIABLES["stable_side"].attrs())
    return ds.assign(codim2_data(records, problem.parameters, osc.n))


def _stable_sides(problem: ShootingCurve, orbits: Sequence[MultiImpactOrbit],
                  physical: np.ndarray) -> np.ndarray:
    """``stable_side`` at each point of a shooting curve: physical (on the curve,
    :meth:`~impactcont.problems.codim1.ShootingCurve.physical_on_curve`), multipliers
    defined, and those but the critical one(s) inside the unit circle (as the closed
    form's curves have it, :func:`_point_columns`)."""
    out = np.zeros(len(orbits), dtype=bool)
    if not problem.multipliers_defined:
        return out
    for k, orbit in enumerate(orbits):
        rest = problem.other_multipliers(orbit.multipliers)
        out[k] = bool(physical[k] and np.all(np.abs(rest) < 1.0))
    return out


def _noise_defaults(kind: Label, noise: float) -> dict[str, Any]:
    """The shooting curve's default options, its Newton tolerance raised to
    :data:`~impactcont.problems.codim1.NOISE_MARGIN` times its test's rounding noise at the
    start (:meth:`~impactcont.problems.codim1.ShootingCurve.test_noise`) where that is more
    (an SO curve of a stick entered through chatter: about 3e-8)."""
    defaults = dict(_SHOOTING_DEFAULTS)
    floor = NOISE_MARGIN * noise
    if math.isfinite(floor) and floor > defaults["newton_tol"]:
        log.info("the %s test is known to %.3g at the start: Newton tolerance %.3g instead of "
                 "%g (give newton_tol to choose)", kind, noise, floor,
                 defaults["newton_tol"])
        defaults["newton_tol"] = floor
    return defaults


class _CurveView:
    """What :func:`~impactcont.analysis.branch.branch_to_dataset` reads of a shooting
    curve problem: the N-p branch it is written as (in ``p2``)."""

    def __init__(self, problem: ShootingCurve, parameter: str, osc: Any) -> None:
        self.parameter, self.osc = parameter, osc
        self.N, self.p, self.pattern = problem.N, problem.p, problem.pattern


def _locate_codim2(problem: Any, xs: list[np.ndarray], orbits: list[Any],
                   tests: list[dict[str, float]] | None, found: list[Codim2Point]) -> None:
    """The codim-2 points of a curve (either evaluator), appended to `found` as they are
    located (:func:`~impactcont.detection.codim2.detect_codim2`; `tests` the test values at
    the points, computed when None); Ctrl-C keeps those located before it."""
    if tests is None:
        tests = [test_values(problem, x, orbit) for x, orbit in zip(xs, orbits, strict=True)]
    until_interrupted(
        lambda: detect_codim2(problem, xs, orbits, tests, found), None, "location",
        "interrupted by the user (KeyboardInterrupt) while locating the codim-2 points of "
        "the curve: those located before are kept (and its ends)")
    log.info("%s curve: %d codim-2 points", problem.kind, len(found))


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
    """Continue a codim-1 curve of any motion in two parameters.

    Parameters
    ----------
    osc : ImpactOscillator, None, branch dataset or motion
        The oscillator (other parameters fixed at its values); ``None`` with a branch
        dataset or a motion as ``start``, whose oscillator is then used. A branch dataset
        or a motion given here is the start (``curve(branch, "SE", parameters=...)``:
        its N, and the kind given second).
    N : int or None
        One impact every N forcing periods; ``None`` takes it from a branch
        dataset or a motion given as ``start``.
    kind : Label or str
        Saddle-node, period-doubling, Neimark-Sacker, grazing or
        zero-velocity-impact curve; symmetry-breaking pitchfork (BP) from a branch of
        symmetric N-p motions; the end of a sticking phase (SE), release grazing (RG) or
        sticking onset (SO) from a branch of motions with sticking phases, which end
        where their motion stops being physical (the problems of
        :mod:`impactcont.problems.codim1`).
    start : xarray.Dataset, motion, mapping or None
        A branch dataset from :func:`impactcont.continuation` or of N-p motions
        (:func:`impactcont.multi_impact_continuation`, a switched branch): its first
        located special point of this kind, or the one at index ``special``; a motion at
        a special point: a :class:`~impactcont.PeriodicOrbit` (closed form) or a
        :class:`~impactcont.MultiImpactOrbit` (shooting; put on the curve by Newton at
        fixed ``p2``); or explicit values ``{p1: .., p2: .., "delta": ..}`` (``delta``
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
        the branch's parameter; an N-p motion takes any two parameters of its oscillator
        (the stops' too: ``b_low``, ``gap``, ...).
    bounds : mapping or pair of pairs
        The box ``{p1: (lo, hi), p2: (lo, hi)}``; the curve stops on its edges.
    root : {+1, -1}, optional
        With explicit start values and no ``delta``: the root of eq. (15); with ``start``
        None: the branch searched for the start is the component through the motion of
        this root. Refused with a branch dataset or a motion as ``start`` (it fixes it).
    detect_codim2_points : bool
        Locate the codim-2 points on the curve.
    options : ContinuationOptions, optional
        Options left out take the drivers' defaults
        (:data:`impactcont.core.options.DRIVER_DEFAULTS`), but Newton tolerance 1e-11
        and first step 0.01 (shooting: Newton tolerance 1e-10, both directions);
        ``bounds`` is the box's range of ``p2``.
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
        ``docs/two_parameter.md``. Followed by shooting (from an N-p branch or motion): an
        N-p branch dataset in ``p2`` (:mod:`impactcont.dataset.multi`) with the column of
        ``p1`` and the attributes ``curve_kind``, ``parameters`` (``"p1,p2"``) and
        ``born_at_value``, its codim-2 points on ``codim2`` as on the closed form's.

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
    osc, N, kind, start = _start_given_first(osc, N, kind, start)
    if (isinstance(start, xr.Dataset) and "impact" in start.dims) \
            or isinstance(start, MultiImpactOrbit):
        return _motion_curve(osc, N, kind, start, special=special, parameters=parameters,
                             bounds=bounds, root=root,
                             detect_codim2_points=detect_codim2_points, options=options,
                             ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol,
                             max_points=max_points, both_directions=both_directions,
                             progress=progress, events=events, monitors=monitors, **more)
    if isinstance(start, PeriodicOrbit):  # its values and phase, on its oscillator
        osc, N, start = _from_orbit(osc, N, start, parameters)
    _check_special_and_root(special, root, start)
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
        start_osc, N, delta0 = _start_by_continuation(osc, N, kind, special, parameters, box,
                                                      root)
    elif isinstance(start, Mapping):
        if N is None:
            raise ParameterError("N must be given unless start is a branch dataset; got None")
        start_osc, delta0 = _start_from_values(osc, N, curve_problem(kind, osc, N, parameters),
                                               start, root)
    else:
        raise ParameterError(f"start must be a branch Dataset, a motion (PeriodicOrbit or "
                             f"MultiImpactOrbit), a mapping of values or None; got "
                             f"{type(start).__name__}")
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
            _locate_codim2(problem, xs, orbits, tests, found)
        ds = _curve_dataset(problem, kind, N, parameters, box, opts, start_osc, (p1v, p2v),
                            delta0, columns, orbits, xs, found, ends, status, call)
        ds = _with_user_functions(ds, problem, result, orbits, functions)
        if call.interrupted:  # as an interrupted map says it (also when in its events)
            record = {**json.loads(ds.attrs["options"]), "interrupted": True}
            ds.attrs["options"] = json.dumps(record, sort_keys=True)
            ds.attrs["interrupted"] = 1
        return ds


def _start_given_first(osc: Any, N: Any, kind: Any, start: Any) -> tuple[Any, Any, Any, Any]:
    """``curve(branch, "SE", ...)`` or ``curve(motion, kind="PD", ...)``: a branch dataset or
    a motion given in place of the oscillator is the start (its oscillator and N are used;
    a kind given second is the kind). Other arguments are returned as they are."""
    if not isinstance(osc, (xr.Dataset, PeriodicOrbit, MultiImpactOrbit)):
        return osc, N, kind, start
    if start is not None:
        raise ParameterError(f"osc must be an ImpactOscillator or None; got a "
                             f"{type(osc).__name__} and also start: give the branch or motion "
                             f"as start only")
    if isinstance(N, (str, Label)):  # curve(branch, "SE"): the second argument is the kind
        if kind != Label.PD:  # (the default)
            raise ParameterError(f"kind is given twice: {N!r} (second argument) and {kind!r}")
        kind, N = N, None
    elif N == 1 and not isinstance(N, bool):  # the default: N is the start's
        N = None
    return None, N, kind, osc


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
    return with_user_functions(ds, functions, values, found)


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


def curve_crossings(ds: xr.Dataset, parameter: str, value: float) -> list[dict[str, float]]:
    """Exact points where a continued curve crosses the line ``parameter = value``.

    Each crossing between two consecutive curve points is re-solved by Newton on
    the curve's augmented system with ``parameter`` fixed, so the result is as
    accurate as the closed form (not an interpolation of the polyline).

    Parameters
    ----------
    ds : xarray.Dataset
        A curve dataset from :func:`curve` (either evaluator).
    parameter : str
        One of the curve's two parameters.
    value : float

    Returns
    -------
    list of dict
        Per crossing, in curve order: the values of ``omega``, ``b`` (and the
        curve's parameters) and ``point`` (index of the first of the two bracketing
        points); on a curve of the closed form also ``delta`` and ``root`` (of eq. 15; 0
        on an SN curve).

    Raises
    ------
    ParameterError
        Not a curve dataset, a parameter that is not the curve's, a bad value.
    NoPeriodicMotionError
        Newton fails at a crossing of a curve followed by shooting.
    """
    if isinstance(ds, xr.Dataset) and "curve_kind" in ds.attrs:
        return _shooting_crossings(ds, parameter, value)
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


def _shooting_problem(ds: xr.Dataset) -> ShootingCurve:
    """The problem a curve dataset followed by shooting was followed on."""
    if not isinstance(ds, xr.Dataset) or "curve_kind" not in ds.attrs:
        raise ParameterError("ds must be a curve dataset of multi_impact_curve (attribute "
                             "'curve_kind')")
    record = json.loads(ds.attrs["options"])
    p1, p2 = str(ds.attrs["parameters"]).split(",")
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    return curve_problem(str(ds.attrs["curve_kind"]), osc, int(ds.attrs["N"]), (p1, p2),
                         p=impacts_of(ds), pattern=pattern_of(ds),
                         symmetric=bool(record.get("symmetric", False)))


def _shooting_crossings(ds: xr.Dataset, parameter: str, value: float
                        ) -> list[dict[str, float]]:
    """:func:`curve_crossings` of a curve followed by shooting."""
    problem = _shooting_problem(ds)
    check_crossing_line(problem.parameters, parameter, value)
    symmetric = problem.symmetric
    values = np.asarray(ds[parameter].values, dtype=float)
    out: list[dict[str, float]] = []
    for k, t in crossing_steps(values, value):
        xs = []
        for i in (k, k + 1):  # the stored motions as unknowns of the curve problem
            lam = float(ds[problem.parameters[1]].values[i])
            osc = oscillator_from_dataset(ds, int(i))
            stored = {"delta": float(ds["delta_k"].values[i, 0]),
                      "flight_times": ds["flight_time_k"].values[i],
                      "states": ds["state_k"].values[i], "pattern": pattern_of(ds)}
            if "stick_time_k" in ds:  # a motion with sticking phases: its stick times
                stored["stick_times"] = np.nan_to_num(ds["stick_time_k"].values[i])
            u = initial_unknowns(stored, osc, problem.N, problem.p)
            base = problem.branch_problem(lam)
            v = base.half_unknowns(u) if symmetric else u
            xs.append(np.concatenate([v, [_value(osc, problem.parameters[0])], [lam]]))
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


@blas_limited
@option_keywords({**DRIVER_DEFAULTS, **_SHOOTING_DEFAULTS})
def multi_impact_curve(branch: xr.Dataset, kind: Label | str = "PD", which: int = 0, *,
                       parameter: str = "b",
                       bounds: Mapping[str, Sequence[float]] | None = None,
                       options: Any = None, ds: float | None = None,
                       ds_min: float | None = None, ds_max: float | None = None,
                       newton_tol: float | None = None, max_points: int | None = None,
                       both_directions: bool | None = None, progress: ProgressOption = None,
                       events: dict[str, Any] | None = None,
                       monitors: dict[str, Any] | None = None,
                       detect_codim2_points: bool = True, **more: Any) -> xr.Dataset:
    """Follow a special point of an N-p branch in two parameters (the earlier name).

    The same as ``curve(None, None, kind, start=branch, special=which,
    parameters=(branch's parameter, parameter), bounds=bounds, ...)``
    (:func:`curve`): the curve followed by shooting.

    Parameters
    ----------
    branch : xarray.Dataset
        A branch of N-p motions with a special point of `kind`.
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
    progress, events, monitors, detect_codim2_points
        As for :func:`curve`.

    Returns
    -------
    xarray.Dataset
        The curve as an N-p branch dataset in ``p2`` (see :func:`curve`).

    Raises
    ------
    TypeError
        `branch` is not a dataset.
    ParameterError
        A bad argument (named in the message), no such special point.
    NoPeriodicMotionError
        The start could not be put on the curve.
    """
    if not isinstance(branch, xr.Dataset):
        raise TypeError(f"branch must be a branch xarray.Dataset; got {type(branch).__name__}")
    return _shooting_curve(kind, branch, which, (str(branch.attrs["parameter"]), parameter),
                           bounds, options=options, progress=progress, events=events,
                           monitors=monitors, detect_codim2_points=detect_codim2_points,
                           ds=ds, ds_min=ds_min, ds_max=ds_max, newton_tol=newton_tol,
                           max_points=max_points, both_directions=both_directions, **more)


def multi_impact_curve_crossings(ds: xr.Dataset, parameter: str, value: float
                                 ) -> list[dict[str, float]]:
    """Exact points where a curve of N-p motions crosses ``parameter = value`` (the earlier
    name of :func:`curve_crossings` for a curve followed by shooting).

    Raises
    ------
    ParameterError
        Not a curve dataset followed by shooting, a parameter that is not the curve's, a
        bad value.
    NoPeriodicMotionError
        Newton fails at a crossing.
    """
    return _shooting_crossings(ds, parameter, value)

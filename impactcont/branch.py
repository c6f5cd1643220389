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
from collections.abc import Sequence

import numpy as np
import xarray as xr

from impactcont.continuation import ContinuationOptions, continue_branch
from impactcont.dataset import branch_dataset
from impactcont.detection import LABELS, BranchSample, detect_special_points
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.periodic import _check_N, periodic_orbits
from impactcont.problems import PeriodicBranchProblem

__all__ = ["continuation"]

log = logging.getLogger(__name__)

_EXISTENCE_SCAN = 400


_PARAMETER_RANGES = {"omega": (0.0, math.inf, "> 0"), "b": (-math.inf, math.inf, "finite"),
                     "R": (0.0, 1.0, "in [0, 1]"), "eta": (0.0, math.inf, ">= 0"),
                     "alpha": (0.0, math.inf, ">= 0"), "beta": (0.0, math.inf, ">= 0")}


def _check_bounds(parameter: str, bounds: object) -> tuple[float, float]:
    """``(lo, hi)`` inside the parameter's allowed range."""
    try:
        lo, hi = (float(v) for v in bounds)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise ParameterError(f"bounds must be two numbers (lo, hi); got {bounds!r}") from None
    low, high, allowed = _PARAMETER_RANGES[parameter]
    # order and finiteness: ContinuationOptions says what is allowed
    if lo < low or hi > high or (parameter == "omega" and lo <= 0.0):
        raise ParameterError(f"bounds for {parameter} must lie where {parameter} is {allowed}; "
                             f"got {bounds!r}")
    return lo, hi


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


def continuation(osc: ImpactOscillator, N: int = 1, parameter: str = "omega",
                 bounds: Sequence[float] = (0.5, 6.0), *, start: float | None = None,
                 root: int | None = None, detect: Sequence[str] = LABELS,
                 ds: float | None = None, ds_min: float = 1e-8, ds_max: float = 0.05,
                 newton_tol: float = 1e-12, max_points: int = 5000,
                 both_directions: bool = True, **options: float) -> xr.Dataset:
    """Continue the branch of periodic N-1 motions in one parameter and find its special points.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator (other parameters fixed at its values).
    N : int
        One impact every N forcing periods.
    parameter : str
        ``"omega"``, ``"b"``, ``"R"``, ``"eta"``, ``"alpha"`` or ``"beta"``.
    bounds : (float, float)
        Range of the parameter.
    start : float, optional
        Parameter value to start from; default the oscillator's value if inside
        `bounds`, else the first value of a scan of `bounds` where a motion exists.
    root : {+1, -1}, optional
        Which root of eq. (15) to start on; default the physical (then stable) one.
    detect : sequence of str
        Special points to detect, subset of ``("SN", "PD", "NS", "GR", "ZV")``.
    ds, ds_min, ds_max, newton_tol, max_points, both_directions, **options
        Continuation options (see :class:`impactcont.continuation.ContinuationOptions`);
        the first step ``ds`` defaults to ``min(0.02, ds_max)``.

    Returns
    -------
    xarray.Dataset
        The branch (dimension ``point``) with its special points (dimension
        ``special``); schema in ``docs/dataset.md``.
    """
    N = _check_N(N)
    unknown = sorted(set(detect) - set(LABELS))
    if unknown:
        raise ParameterError(f"detect: labels must be a subset of {LABELS}; got unknown {unknown}")
    problem = PeriodicBranchProblem(osc, N, parameter)
    lo, hi = _check_bounds(parameter, bounds)
    if ds is None:  # the first step adapts to a smaller ds_max
        positive = isinstance(ds_max, (int, float)) and ds_max > 0  # else options say why
        ds = min(0.02, ds_max) if positive else 0.02
    opts = ContinuationOptions(bounds=(lo, hi), ds=ds, ds_min=ds_min, ds_max=ds_max,
                               newton_tol=newton_tol, max_points=max_points,
                               both_directions=both_directions, **options)
    lam0 = _start_value(problem, (lo, hi), start)
    delta0 = _start_root(problem, lam0, root)
    result = continue_branch(problem, np.array([delta0]), lam0, opts)
    log.info("N=%d branch in %s: %d points (%s)", N, parameter, len(result), result.message)

    samples = [BranchSample(delta=float(u[0]), lam=float(lam), dlam=float(t[-1]),
                            orbit=problem.orbit(float(u[0]), float(lam)))
               for u, lam, t in zip(result.u, result.lam, result.tangent, strict=True)]
    specials = detect_special_points(problem, samples, detect)

    orbits = [s.orbit for s in samples]
    ds_steps = np.sqrt(np.diff(result.u[:, 0]) ** 2 + np.diff(result.lam) ** 2)
    columns = {
        "omega": np.array([o.oscillator.omega for o in orbits]),
        "b": np.array([o.oscillator.b for o in orbits]),
        "delta": np.array([o.delta for o in orbits]),
        "impact_velocity": np.array([o.impact_velocity for o in orbits]),
        "gap_min": np.array([o.gap_min for o in orbits]),
        "spectral_radius": np.array([o.spectral_radius for o in orbits]),
        "stable": np.array([o.stable for o in orbits]),
        "physical": np.array([o.physical for o in orbits]),
        "arclength": np.concatenate([[0.0], np.cumsum(ds_steps)]),
        "multipliers": np.array([o.multipliers for o in orbits]),
        "state": np.array([o.state for o in orbits]),
    }
    # the continued parameter's own column (omega and b are always there)
    columns.setdefault(parameter, np.asarray(result.lam, dtype=float))
    special_points = [{
        "label": sp.label, "omega": sp.orbit.oscillator.omega, "b": sp.orbit.oscillator.b,
        "delta": sp.delta, "point": sp.point, "bracket_lo": min(sp.bracket),
        "bracket_hi": max(sp.bracket), "precision": sp.precision, "status": sp.status,
        "multipliers": sp.orbit.multipliers,
    } for sp in specials]
    for row, sp in zip(special_points, specials, strict=True):
        row.setdefault(parameter, sp.value)
    option_record = {**dataclasses.asdict(opts), "N": N, "parameter": parameter,
                     "start": lam0, "start_delta": delta0, "detect": list(detect),
                     "status": [s.name for s in result.statuses],
                     "message": result.message}
    option_record["bounds"] = list(opts.bounds)
    return branch_dataset(parameter=parameter, N=N, oscillator=osc, options=option_record,
                          columns=columns, special_points=special_points)

"""Branch switching: period-doubling (N-p -> 2N-2p), grazing (N-p -> N-(p+1)) and the
symmetry-breaking pitchfork (symmetric -> the asymmetric pair).

Period-doubling
---------------
At a PD point the impact map ``G = G_{p-1} .. G_0`` of an N-p motion has a
multiplier -1 with eigenvector ``v`` (a perturbation ``[dz, d theta]`` of the
section state at impact 0). In the 2N-2p shooting system the N-p motion
repeated twice is a solution on both sides of the PD; at the PD its Jacobian
has the null vector ``w`` built from ``v``: the section perturbations
``zeta_0 = v``, ``zeta_{k+1} = G_k zeta_k`` (so ``zeta_p = -v``: the two halves
move in opposite directions), the flight times change by
``(d theta_{k+1} - d theta_k) / omega`` (eq. 23). The 2N-2p branch is born
tangent to ``(w, 0)``. Starting from the doubled motion at the PD displaced by
``epsilon`` along ``w`` (made orthogonal to the tangent of the doubled
branch), Newton on the shooting system plus the hyperplane orthogonal to that
direction lands on the new branch, not the old one; the new branch is then
followed away from the PD.

Grazing
-------
Where an N-p motion grazes (``gap_min -> 0`` on flight k, at time ``t_g``), the
grazing point is an impact at zero velocity: splitting flight k at ``t_g`` gives
an exact solution of the N-(p+1) shooting system. Its branch is followed in
the direction where the new impact's velocity becomes positive.

Symmetry-breaking pitchfork
---------------------------
At a BP of a branch of symmetric motions (:mod:`impactcont.orbit.symmetry`) the
full N-p shooting system has a two-dimensional null space of ``[J | F_lam]``: the
tangent of the symmetric branch and an antisymmetric direction ``e`` (the halves of
the motion move in opposite directions). The symmetric motion at the BP is solved on
its half system (regular there); ``e`` is the null vector of the full system
orthogonal to the symmetric tangent. Displaced by ``+epsilon e`` and by
``-epsilon e`` and corrected on the hyperplane orthogonal to ``e``, Newton lands on
the two asymmetric motions, mirror images of each other; each is followed away from
the BP.

Ctrl-C
------
Ctrl-C (:class:`KeyboardInterrupt`) during the continuation of a new branch (every switch
here) returns its points computed so far, marked as interrupted, as
:func:`~impactcont.analysis.branch.multi_impact_continuation` does (see its Notes); a
second one aborts. A cascade keeps the branches computed before
(:func:`period_doubling_cascade`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.branch import make_options, run_branch
from impactcont.core import ContinuationOptions
from impactcont.core.corrector import solve_on_hyperplane
from impactcont.core.options import DRIVER_DEFAULTS
from impactcont.dataset.multi import impacts_of, pattern_of
from impactcont.dataset.schema import oscillator_from_dataset, special_variable
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.parameters import FREQUENCY, model_parameter
from impactcont.orbit.multi_impact import (
    MultiImpactOrbit,
    initial_unknowns,
    multi_impact_orbit,
)
from impactcont.orbit.periodic import orbit_at_phase
from impactcont.orbit.stop_geometry import stop_geometry
from impactcont.orbit.symmetry import symmetry_defect
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.problems.symmetric_branch import SymmetricBranchProblem
from impactcont.progress import (
    NothingComputed,
    ProgressOption,
    Reporter,
    interruptible,
    reporter,
    take_interrupt,
)
from impactcont.threads import blas_limited
from impactcont.vocabulary import LABELS, check_positive_integer

__all__ = [
    "Cascade",
    "critical_direction",
    "grazing_split",
    "grazing_switch",
    "period_doubling_cascade",
    "period_doubling_switch",
    "pitchfork_branch",
    "pitchfork_switch",
    "special_orbit",
]

log = logging.getLogger(__name__)

#: Why :func:`pitchfork_branch` refuses a branch of N-1 motions (also the scenes' ``--check``).
NOT_SYMMETRIC = ("branch must be a branch of N-p motions (an N-1 motion is never symmetric: it "
                 "has one impact per period)")

_CORRECTOR_TOL = 1e-11
_STEP_TOL = 1e-8
_MAX_ITER = 30


# ------------------------------------------------------------------------------------------
# The motion at a special point of a dataset
# ------------------------------------------------------------------------------------------
def _special_index(ds: xr.Dataset, label: str, which: int) -> int:
    labels = np.asarray(ds[special_variable("label")].values).tolist()
    rows = [k for k, lab in enumerate(labels) if lab == label]
    if isinstance(which, bool) or not isinstance(which, (int, np.integer)):
        raise ParameterError(f"which must be an integer index among the {label} points; "
                             f"got {which!r}")
    if not -len(rows) <= which < len(rows):
        raise ParameterError(f"which={which!r} is out of range: the branch has {len(rows)} "
                             f"{label} point(s) (special labels: {labels})")
    return rows[which]


def special_orbit(branch: xr.Dataset, label: str = "PD", which: int = 0) -> MultiImpactOrbit:
    """The motion at a special point of a branch dataset (N-1 or N-p).

    Parameters
    ----------
    branch : xarray.Dataset
        A branch dataset of :func:`impactcont.continuation` or of
        :func:`impactcont.analysis.branch.multi_impact_continuation`.
    label : str
        ``"PD"``, ``"GR"``, ...
    which : int
        Index among the special points with that label, in branch order.

    Returns
    -------
    MultiImpactOrbit
        Re-solved by Newton at the special point's parameter value from its stored
        phases, flight times, states (and stick times, of a motion with sticking phases);
        a BP: the symmetric motion solved on its half system, where the full one is
        singular.
    """
    if not isinstance(branch, xr.Dataset):
        raise TypeError(f"branch must be a branch xarray.Dataset; got {type(branch).__name__}")
    if label not in LABELS:
        raise ParameterError(f"label must be one of {LABELS}; got {label!r}")
    if label == "BP" and "impact" in branch.dims:
        # singular for the full shooting system: solved on the half system (regular there)
        half, v, lam = _symmetric_at(branch, which)
        return half.orbit(v, lam)
    k = _special_index(branch, label, which)
    parameter = branch.attrs["parameter"]
    N, p = int(branch.attrs["N"]), impacts_of(branch)
    values = {name: float(branch[special_variable(name)].values[k])
              for name in dict.fromkeys(["omega", "b", parameter])}
    osc = oscillator_from_dataset(branch).replace(omega=values.pop("omega"), b=values.pop("b"))
    for name, value in values.items():  # as its object sets it (an element, an extra stop)
        osc = model_parameter(osc, name).at(osc, value)
    if "impact" in branch.dims:
        guess = {"delta": float(branch[special_variable("delta_k")].values[k, 0]),
                 "flight_times": branch[special_variable("flight_time_k")].values[k],
                 "states": branch[special_variable("state_k")].values[k],
                 "pattern": pattern_of(branch)}
        if special_variable("stick_time_k") in branch:
            # a motion with sticking phases: its stick times are unknowns of its shooting
            # system (NaN where no stick follows an impact)
            guess["stick_times"] = np.nan_to_num(np.asarray(
                branch[special_variable("stick_time_k")].values[k], dtype=float))
    else:
        # a guess for the shooting Newton (a bracketed point may sit off eq. 14)
        guess = orbit_at_phase(osc, N, float(branch[special_variable("delta")].values[k]),
                               check=False)
    return multi_impact_orbit(osc, N, p, guess)


# ------------------------------------------------------------------------------------------
# Period-doubling
# ------------------------------------------------------------------------------------------
def critical_direction(orbit: MultiImpactOrbit) -> tuple[np.ndarray, complex]:
    """Null vector of the doubled (2N-2p) shooting Jacobian at a PD, from the eigenvector of -1.

    Parameters
    ----------
    orbit : MultiImpactOrbit
        An N-p motion with a multiplier (close to) -1.

    Returns
    -------
    w : ndarray, shape (4np,)
        Direction in the unknowns ``[delta, tau_0..tau_{2p-2}, z_0..z_{2p-1}]`` of the
        2N-2p system, max-norm 1.
    mu : complex
        The multiplier used (the one closest to -1).
    """
    p, omega = orbit.p, orbit.oscillator.omega
    mu_all, vecs = np.linalg.eig(orbit.G)
    i = int(np.argmin(np.abs(mu_all + 1.0)))
    v = vecs[:, i]
    v = np.real(v * np.exp(-1j * np.angle(v[np.argmax(np.abs(v))])))  # real for a real mu
    zeta = [v]
    for k in range(2 * p - 1):
        zeta.append(orbit.jacobians[k % p] @ zeta[-1])
    zeta = np.array(zeta)
    dtheta = zeta[:, -1]
    w = np.concatenate([[dtheta[0]], np.diff(dtheta) / omega, zeta[:, :-1].ravel()])
    return w / np.max(np.abs(w)), complex(mu_all[i])


def _hyperplane_newton(problem: MultiImpactBranchProblem, x_pred: np.ndarray,
                       normal: np.ndarray) -> np.ndarray:
    """Solve ``F(u, lam) = 0`` on the hyperplane ``<normal, x - x_pred> = 0`` from ``x_pred``."""
    # quadratic convergence: a step this small leaves a residual at rounding level; the
    # residual is the accuracy that counts (long motions make the solve less accurate)
    found = solve_on_hyperplane(problem, x_pred, normal, tol=_STEP_TOL, max_iter=_MAX_ITER,
                                residual_tol=_CORRECTOR_TOL)
    if found.converged:
        return found.x
    x = found.x
    raise NoPeriodicMotionError(
        f"branch switching: Newton on the shooting system of the N={problem.N}, p={problem.p} "
        f"motion did not converge from the predicted point (residual "
        f"{np.max(np.abs(problem.residual(x[:-1], float(x[-1])))):.3g})")


def _pd_start(orbit: MultiImpactOrbit, parameter: str, epsilon: float
              ) -> tuple[MultiImpactBranchProblem, np.ndarray, float, int, dict[str, Any]]:
    """First point of the 2N-2p branch born at the PD ``orbit``; direction away from it."""
    osc = orbit.oscillator
    N2, p2 = 2 * orbit.N, 2 * orbit.p
    problem = MultiImpactBranchProblem(osc, N2, p2, parameter,
                                       pattern=2 * orbit.pattern if orbit.pattern else None)
    lam_pd = problem.param.value(osc)
    u_pd = initial_unknowns(orbit, osc, N2, p2)
    w, mu = critical_direction(orbit)
    J = problem.jacobian(u_pd, lam_pd)
    null_residual = float(np.max(np.abs(J @ w)) / max(np.max(np.abs(J)), 1e-300))
    log.info("PD at %s=%.12g: multiplier %.3g%+.3gj, |J w| / |J| = %.2e", parameter, lam_pd,
             mu.real, mu.imag, null_residual)
    # tangent of the doubled branch: the null vector of [J | F_lam] orthogonal to (w, 0)
    extended = np.column_stack([J, problem.dparam(u_pd, lam_pd)])
    basis = np.linalg.svd(extended)[2][-2:].T  # two smallest right singular vectors
    w_ext = np.append(w, 0.0)
    a = basis.T @ w_ext
    t_old = basis @ np.array([-a[1], a[0]])
    t_old /= np.linalg.norm(t_old)
    e = w_ext - (w_ext @ t_old) * t_old
    e /= np.max(np.abs(e[:-1]))
    x_pd = np.append(u_pd, lam_pd)
    x1 = _hyperplane_newton(problem, x_pd + epsilon * e, e)
    u1, lam1 = x1[:-1], float(x1[-1])
    first = problem.orbit(u1, lam1, checks=False)
    h = orbit.p
    split = float(np.max(np.abs(first.states[:h] - first.states[h:])))
    # the old branch has split = 0; the new one starts about epsilon * |w_z| away from it
    if not split > 0.1 * epsilon * float(np.max(np.abs(w[p2:]))):
        raise NoPeriodicMotionError(
            f"branch switching at the PD {parameter}={lam_pd:.12g}: the corrected point is the "
            f"{orbit.N}-{orbit.p} motion repeated twice (halves differ by {split:.3g}), not a "
            f"new {N2}-{p2} motion")
    if lam1 == lam_pd:
        log.warning("the switched point has the PD's parameter value exactly; going up")
    direction = 1 if lam1 >= lam_pd else -1
    info = {"born_at": "PD", "born_at_value": lam_pd, "parent_N": orbit.N,
            "parent_impacts": orbit.p, "switch_epsilon": float(epsilon),
            "switch_null_residual": null_residual, "switch_split": split}
    log.info("switched to the %d-%d branch at %s=%.12g (halves differ by %.3g), going %s",
             N2, p2, parameter, lam1, split, "up" if direction > 0 else "down")
    return problem, u1, lam1, direction, info


def _dataset_bounds(ds: xr.Dataset, bounds: Sequence[float] | None) -> tuple[float, float]:
    if bounds is not None:
        lo, hi = (float(v) for v in bounds)
        return lo, hi
    import json

    try:
        lo, hi = json.loads(ds.attrs["options"])["bounds"]
    except (KeyError, ValueError, TypeError):
        raise ParameterError("bounds must be given: the dataset's options record no bounds"
                             ) from None
    return float(lo), float(hi)


def _check_epsilon(epsilon: object) -> float:
    if isinstance(epsilon, bool) or not isinstance(epsilon, (int, float)) \
            or not 0 < epsilon < 1:
        raise ParameterError(f"epsilon must be a real number in (0, 1); got {epsilon!r}")
    return float(epsilon)


def _switch_start(branch: xr.Dataset, label: str, which: int,
                  bounds: Sequence[float] | None, epsilon: object
                  ) -> tuple[float, MultiImpactOrbit, str, float, float]:
    """What a switch at a special point of `branch` starts from.

    Parameters
    ----------
    branch : xarray.Dataset
        The parent branch.
    label : str
        The special point's label (``"PD"``, ``"GR"``).
    which : int
        Which point of that label (index among them, branch order).
    bounds : (float, float) or None
        Parameter range; None: the bounds recorded in ``branch``.
    epsilon : float
        The switch's step, checked to lie in (0, 1).

    Returns
    -------
    (float, MultiImpactOrbit, str, float, float)
        ``epsilon``, the orbit at the special point, the continuation parameter's name
        and the bounds ``lo, hi``.
    """
    epsilon = _check_epsilon(epsilon)
    orbit = special_orbit(branch, label, which)
    parameter = branch.attrs["parameter"]
    lo, hi = _dataset_bounds(branch, bounds)
    return epsilon, orbit, parameter, lo, hi


@blas_limited
def period_doubling_switch(branch: xr.Dataset, which: int = 0, *,
                           bounds: Sequence[float] | None = None, epsilon: float = 1e-3,
                           detect: Sequence[str] = LABELS, stop_after_pd: int | None = None,
                           options: ContinuationOptions | None = None,
                           progress: ProgressOption | Reporter = None,
                           **more: Any) -> xr.Dataset:
    """Start and follow the 2N-2p branch born at a period-doubling point of a branch.

    Parameters
    ----------
    branch : xarray.Dataset
        An N-1 branch (:func:`impactcont.continuation`) or an N-p branch.
    which : int
        Which PD point of the branch (index among its PD points, branch order).
    bounds : (float, float), optional
        Parameter range of the new branch; default the bounds of ``branch``.
    epsilon : float
        Size of the initial displacement along the critical direction (max-norm of
        the unknowns), in (0, 1).
    detect : sequence of str
        Special points to detect on the new branch.
    stop_after_pd : int, optional
        Stop this many points after the first PD of the new branch.
    options : ContinuationOptions, optional
        Continuation options (the drivers' defaults for those left out); the
        switch sets ``direction`` (away from the parent) and one direction only.
    progress : None, bool or callable
        A progress bar on stderr (``None``: when stderr is a terminal, after 2 s;
        ``True``: always; ``False``: never) or a callable receiving a
        :class:`~impactcont.progress.Progress` record at every point
        (:mod:`impactcont.progress`); the reporter of an enclosing call (a cascade)
        counts the points in its own bar.
    **more
        Convenience keywords for single options (``ds``, ``ds_max``, ``max_points``, ...).

    Returns
    -------
    xarray.Dataset
        The 2N-2p branch (``impact`` dimension), starting next to the PD and going
        away from it; attributes ``born_at = "PD"``, ``born_at_value`` (the PD's
        parameter value), ``parent_N``, ``parent_impacts``.

    Raises
    ------
    ParameterError
        No such PD point, bad ``epsilon`` or bounds.
    NoPeriodicMotionError
        The switched point could not be computed.

    Notes
    -----
    Ctrl-C returns the new branch as far as it was computed (module docstring, Ctrl-C).
    """
    epsilon, orbit, parameter, lo, hi = _switch_start(branch, "PD", which, bounds, epsilon)
    problem, u1, lam1, direction, info = _pd_start(orbit, parameter, epsilon)
    opts = make_options((lo, hi), options, direction=direction, both_directions=False, **more)
    if not lo <= lam1 <= hi:
        raise ParameterError(f"bounds ({lo}, {hi}) must contain the switched point "
                             f"{parameter}={lam1!r}")
    return run_branch(problem, u1, lam1, opts, detect=detect, stop_after_pd=stop_after_pd,
                      record={"switch": info}, extra_attrs=info, progress=progress)


# ------------------------------------------------------------------------------------------
# Cascades
# ------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True, eq=False)
class Cascade:
    """A followed period-doubling cascade.

    Attributes
    ----------
    branches : list of xarray.Dataset
        ``branches[0]`` the branch given, then the 2N-2p, 4N-4p, ... branches.
    pd_values : ndarray, shape (k,)
        Parameter of the PD that starts each doubling: ``pd_values[i]`` lies on
        ``branches[i]`` and gives birth to ``branches[i+1]``.
    pd_precision : ndarray, shape (k,)
        Precision of each.
    pd_physical : ndarray of bool, shape (k,)
        Whether the motion at each PD point is physical (no contact inside a
        flight, positive impact velocities). Past a grazing the cascade goes on
        for the virtual motions that pass through the stop: flagged here.
    ratios : ndarray, shape (k-2,)
        ``(pd[i+1] - pd[i]) / (pd[i+2] - pd[i+1])`` (tends to Feigenbaum's 4.669...
        for a smooth period-doubling cascade).
    message : str
        Why the cascade stopped.
    interrupted : bool
        Whether Ctrl-C stopped it (the branches are those computed before; the last may
        be interrupted itself, see its ``options`` attribute).
    """

    branches: list[xr.Dataset]
    pd_values: np.ndarray
    pd_precision: np.ndarray
    pd_physical: np.ndarray
    ratios: np.ndarray
    message: str
    interrupted: bool = False


def _first_pd(ds: xr.Dataset, after: float | None, sign: int) -> int | None:
    """Index (among PD points) of the first located PD beyond ``after`` in direction ``sign``."""
    labels = np.asarray(ds[special_variable("label")].values).tolist()
    parameter = ds.attrs["parameter"]
    values = ds[special_variable(parameter)].values
    status = ds[special_variable("status")].values
    pd_rows = [k for k, lab in enumerate(labels) if lab == "PD"]
    for j, k in enumerate(pd_rows):
        if status[k] != "located":
            continue
        if after is None or sign * (values[k] - after) > 0:
            return j
    return None


@blas_limited
def period_doubling_cascade(branch: xr.Dataset, which: int = 0, *, max_doublings: int = 6,
                            bounds: Sequence[float] | None = None, epsilon: float = 1e-3,
                            detect: Sequence[str] = LABELS, min_spacing: float = 1e-9,
                            options: ContinuationOptions | None = None,
                            progress: ProgressOption = None, **more: Any) -> Cascade:
    """Follow a period-doubling cascade: switch at a PD, find the next PD, repeat.

    Parameters
    ----------
    branch : xarray.Dataset
        The starting branch (N-1 or N-p) with at least one PD point.
    which : int
        Which PD point of ``branch`` starts the cascade.
    max_doublings : int
        Largest number of doublings (branches added).
    bounds : (float, float), optional
        Parameter range; default the bounds of ``branch``.
    epsilon : float
        Switching displacement (see :func:`period_doubling_switch`); it is
        reduced with the square root of the spacing of the PD points.
    detect : sequence of str
        Special points detected on each new branch (PD is always included).
    min_spacing : float
        Stop when successive PD points are closer than this in the parameter
        (the numbers no longer resolve the cascade).
    options : ContinuationOptions, optional
        Continuation options for the new branches (see below).
    **more
        Convenience keywords over `options`. ``ds_max`` is reduced with
        the spacing of the PD points; ``max_points`` defaults to 300 per branch. Each
        new branch after the first is confined to twice the last PD spacing around
        its PD.
    progress : None, bool or callable
        A progress bar on stderr over the points of all the new branches (``None``:
        when stderr is a terminal, after 2 s; ``True``: always; ``False``: never) or a
        callable receiving a :class:`~impactcont.progress.Progress` record at every
        point (:mod:`impactcont.progress`). A call longer than a minute logs a line a
        minute.

    Returns
    -------
    Cascade

    Notes
    -----
    Ctrl-C (:class:`KeyboardInterrupt`) stops the cascade: the branches computed before
    are returned, the last one with its points computed so far (marked as in
    :func:`~impactcont.analysis.branch.multi_impact_continuation`);
    ``Cascade.interrupted`` is True and ``message`` says after how many doublings. A
    second Ctrl-C aborts.
    """
    max_doublings = check_positive_integer("max_doublings", max_doublings)
    epsilon = _check_epsilon(epsilon)
    labels = list(dict.fromkeys([*detect, "PD"]))
    parameter = branch.attrs["parameter"]
    lo, hi = _dataset_bounds(branch, bounds)
    k0 = _special_index(branch, "PD", which)
    branches = [branch]
    pd_values = [float(branch[special_variable(parameter)].values[k0])]
    pd_precision = [float(branch[special_variable("precision")].values[k0])]
    pd_physical = [special_orbit(branch, "PD", which).physical]
    current, current_which = branch, which
    message = f"reached max_doublings={max_doublings}"
    given = {} if options is None else {k: getattr(options, k) for k in options.given}
    base_ds_max = float(more.pop("ds_max", given.get("ds_max", DRIVER_DEFAULTS["ds_max"])))
    base_ds = float(more.pop("ds", given.get("ds", DRIVER_DEFAULTS["ds"])))
    if "max_points" not in given:
        more.setdefault("max_points", 300)  # a child branch that finds no PD is not followed far
    what = f"period-doubling cascade in {parameter}"
    with interruptible(what) as call, reporter(progress, what, parameter=parameter) as rep:
        for level in range(max_doublings):
            spacing = abs(pd_values[-1] - pd_values[-2]) if len(pd_values) > 1 else None
            child_bounds = (lo, hi)
            ds_max = base_ds_max
            eps = epsilon
            if spacing is not None:
                # near a PD the new branch is a parabola, lam - lam_PD ~ a^2 in its amplitude a:
                # the next PD (about spacing / 4.67 away in lam) is ~sqrt(spacing) away in u
                ds_max = min(base_ds_max, 0.25 * math.sqrt(spacing))
                eps = min(epsilon, max(math.sqrt(spacing) * 0.05, 1e-6))
                child_bounds = (max(lo, pd_values[-1] - 2 * spacing),
                                min(hi, pd_values[-1] + 2 * spacing))
            try:
                child = period_doubling_switch(
                    current, current_which, bounds=child_bounds, epsilon=eps, detect=labels,
                    stop_after_pd=3, ds=min(base_ds, ds_max), ds_max=ds_max,
                    ds_min=min(1e-8, ds_max * 1e-4), options=options, progress=rep,
                    **more)
            except (NoPeriodicMotionError, np.linalg.LinAlgError) as exc:
                message = f"switching at the PD {parameter}={pd_values[-1]:.12g} failed: {exc}"
                break
            except NothingComputed:  # Ctrl-C taken before the new branch's first point
                message = (f"interrupted by the user (KeyboardInterrupt) after {level} "
                           "doubling(s)")
                break
            except KeyboardInterrupt:
                if not take_interrupt("continuation", "interrupted by the user "
                                      "(KeyboardInterrupt) while switching at the PD "
                                      "%s=%.12g; the %d branch(es) before are kept", parameter,
                                      pd_values[-1], len(branches)):
                    raise
                message = (f"interrupted by the user (KeyboardInterrupt) after {level} "
                           "doubling(s)")
                break
            branches.append(child)
            if call.interrupted:
                message = (f"interrupted by the user (KeyboardInterrupt) after {level + 1} "
                           "doubling(s)")
                break
            sign = 1 if float(child[parameter].values[-1]) >= pd_values[-1] else -1
            j = _first_pd(child, pd_values[-1], sign)
            if j is None:
                message = (f"the {child.attrs['N']}-{child.attrs['impacts']} branch has no located "
                           f"PD point in {parameter} in ({lo}, {hi}) ({level + 1} doubling(s))")
                break
            k = _special_index(child, "PD", j)
            value = float(child[special_variable(parameter)].values[k])
            if abs(value - pd_values[-1]) < min_spacing:
                message = f"PD spacing {abs(value - pd_values[-1]):.3g} < min_spacing"
                break
            pd_values.append(value)
            pd_precision.append(float(child[special_variable("precision")].values[k]))
            pd_physical.append(special_orbit(child, "PD", j).physical)
            log.info("cascade: %d-%d branch has its PD at %s=%.12g", int(child.attrs["N"]),
                     int(child.attrs["impacts"]), parameter, value)
            current, current_which = child, j
    pd = np.array(pd_values)
    gaps = np.diff(pd)
    ratios = gaps[:-1] / gaps[1:] if gaps.size >= 2 else np.empty(0)
    return Cascade(branches=branches, pd_values=pd, pd_precision=np.array(pd_precision),
                   pd_physical=np.array(pd_physical, dtype=bool), ratios=ratios,
                   message=message, interrupted=call.interrupted)


# ------------------------------------------------------------------------------------------
# Grazing
# ------------------------------------------------------------------------------------------
def grazing_split(orbit: MultiImpactOrbit) -> tuple[dict[str, Any], int]:
    """The grazing N-p motion as an N-(p+1) guess: the graze becomes an impact.

    Returns
    -------
    guess : dict
        ``delta``, ``flight_times`` (p+1,), ``states`` (p+1, 2n), ``pattern`` for
        :func:`impactcont.orbit.multi_impact.multi_impact_orbit`.
    index : int
        Index of the new (zero-velocity) impact in the N-(p+1) motion.

    Raises
    ------
    ParameterError
        For a motion with sticking phases: its flights start at the releases, not at the
        impact states, and a graze may lie inside a sticking phase (``flight_gap_min``
        covers the held phase and a chatter's bounces there), so the guess built here
        would be wrong.
    """
    from impactcont.orbit.flow import Flow

    pattern = orbit.pattern or "U" * orbit.p
    if any(letter.islower() for letter in pattern):
        raise ParameterError(f"grazing_switch: the motion {pattern!r} has sticking phases "
                             "(lowercase letters); switching at its grazing points is not "
                             "supported (only motions made of flights and impacts)")
    k = int(np.argmin(orbit.flight_gap_min))
    t_g = float(orbit.flight_gap_min_times[k])
    if not math.isfinite(t_g):
        raise NoPeriodicMotionError("the motion has no interior maximum of x1: it does not graze")
    osc = orbit.oscillator
    # the stop grazed: the one nearest in that flight (any stop, extra ones included)
    if len(orbit.flight_gap_stops) == orbit.p:
        stop = orbit.flight_gap_stops[k]
    else:  # not recorded: the lower one when its clearance is the smallest (two stops)
        lower = orbit.flight_gap_lower is not None and \
            orbit.flight_gap_lower[k] == orbit.flight_gap_min[k]
        stop = "L" if lower else "U"
    geo = stop_geometry(osc, stop)
    j, normal = geo.pivot, geo.normals[0]  # the coordinate of the stop grazed
    X = Flow(osc).state(t_g, orbit.states[k], orbit.phases[k])[0]
    # on the stop exactly (n . x = c, solved for x_j), then the impact law D of that stop
    X[j] += (float(geo.positions[0]) - float(normal @ X[:osc.n])) / normal[j]
    X = geo.matrices[0] @ X
    taus = list(orbit.flight_times)
    taus[k:k + 1] = [t_g, float(orbit.flight_times[k]) - t_g]
    states = list(orbit.states)
    states.insert(k + 1, X)
    return {"delta": orbit.delta, "flight_times": np.array(taus),
            "states": np.array(states),
            "pattern": pattern[:k + 1] + stop + pattern[k + 1:]}, k + 1


@blas_limited
def grazing_switch(branch: xr.Dataset, which: int = 0, *, bounds: Sequence[float] | None = None,
                   epsilon: float = 1e-4, detect: Sequence[str] = LABELS,
                   options: ContinuationOptions | None = None,
                   **more: Any) -> xr.Dataset | None:
    """Follow the motion with one more impact born at a grazing point of a branch.

    Parameters
    ----------
    branch : xarray.Dataset
        An N-1 or N-p branch with a GR point.
    which : int
        Which GR point (index among the GR points, branch order).
    bounds : (float, float), optional
        Parameter range; default the bounds of ``branch``.
    epsilon : float
        Step from the grazing point into the side where the new impact's
        velocity is positive, before continuing (max-norm of the unknowns); also
        the first continuation step unless ``ds`` or `options` is given (the
        steps then grow geometrically away from the graze).
    detect : sequence of str
        Special points to detect on the new branch.
    options : ContinuationOptions, optional
        Continuation options (the drivers' defaults for those left out); the
        switch sets ``direction`` (away from the grazing point) and one direction only.
    **more
        Convenience keywords for single options (``ds``, ``ds_max``, ``max_points``, ...).

    Returns
    -------
    xarray.Dataset or None
        The N-(p+1) branch, followed from the grazing point into the side where
        the new impact has a positive velocity (attributes ``born_at = "GR"``,
        ``born_at_value``, ``new_impact``); None when the N-(p+1) system has no
        solution branch through the grazing point (Newton fails there).

    Notes
    -----
    Ctrl-C returns the new branch as far as it was computed (module docstring, Ctrl-C).
    """
    epsilon, orbit, parameter, lo, hi = _switch_start(branch, "GR", which, bounds, epsilon)
    guess, new = grazing_split(orbit)
    osc = orbit.oscillator
    lam_g = model_parameter(osc, parameter).value(osc)
    p1 = orbit.p + 1
    try:
        graze = multi_impact_orbit(osc, orbit.N, p1, guess)
    except NoPeriodicMotionError as exc:
        log.warning("no %d-%d motion through the grazing point %s=%.12g: %s", orbit.N, p1,
                    parameter, lam_g, exc)
        return None
    problem = MultiImpactBranchProblem(osc, orbit.N, p1, parameter, pattern=graze.pattern)
    u_g = graze.unknowns
    extended = np.column_stack([problem.jacobian(u_g, lam_g), problem.dparam(u_g, lam_g)])
    t = np.linalg.svd(extended)[2][-1]
    t /= np.max(np.abs(t[:-1]))
    # velocity of the new impact = arrival velocity of the flight before it
    n = osc.n
    geo = stop_geometry(osc, graze.pattern)
    normal, sign = geo.normals[new], float(geo.signs[new])

    def new_velocity(x: np.ndarray) -> float:
        # towards the stop hit: +n . x' at an upper stop, -n . x' at a lower (its side)
        return sign * float(normal @ problem.shot(x[:-1], float(x[-1])).arrivals[new - 1,
                                                                                   n:])

    x_g = np.append(u_g, lam_g)
    h = 1e-7
    slope = (new_velocity(x_g + h * t) - new_velocity(x_g - h * t)) / (2 * h)
    if slope < 0:
        t = -t
    try:
        x1 = _hyperplane_newton(problem, x_g + epsilon * t, t)
    except (NoPeriodicMotionError, np.linalg.LinAlgError) as exc:
        log.warning("could not leave the grazing point %s=%.12g: %s", parameter, lam_g, exc)
        return None
    u1, lam1 = x1[:-1], float(x1[-1])
    direction = 1 if lam1 >= lam_g else -1
    info = {"born_at": "GR", "born_at_value": lam_g, "parent_N": orbit.N,
            "parent_impacts": orbit.p, "new_impact": int(new),
            "new_impact_velocity_slope": float(abs(slope))}
    log.info("grazing at %s=%.12g: %d-%d branch leaves going %s (new impact %d, "
             "d v / ds = %.3g)", parameter, lam_g, orbit.N, p1,
             "up" if direction > 0 else "down", new, abs(slope))
    if not lo <= lam1 <= hi:
        raise ParameterError(f"bounds ({lo}, {hi}) must contain the grazing point "
                             f"{parameter}={lam1!r}")
    if options is None and more.get("ds") is None:
        # the new motion changes fastest at its birth (its multipliers grow like
        # 1/|lam - lam_GR|): start with a step of the size of epsilon and let the core
        # grow it geometrically, so the diagram shows the motion being born
        more["ds"] = epsilon
    opts = make_options((lo, hi), options, direction=direction, both_directions=False, **more)
    return run_branch(problem, u1, lam1, opts, detect=detect, record={"switch": info},
                      extra_attrs=info)


# ------------------------------------------------------------------------------------------
# Symmetry-breaking pitchfork
# ------------------------------------------------------------------------------------------
def _symmetric_at(branch: xr.Dataset, which: int) -> tuple[SymmetricBranchProblem, np.ndarray,
                                                           float]:
    """The half problem and the symmetric motion (half unknowns, parameter) at a BP point."""
    k = _special_index(branch, "BP", which)
    parameter = branch.attrs["parameter"]
    N, p = int(branch.attrs["N"]), impacts_of(branch)
    values = {name: float(branch[special_variable(name)].values[k])
              for name in dict.fromkeys(["omega", "b", parameter])}
    base = oscillator_from_dataset(branch)
    param = model_parameter(base, parameter)
    osc = param.at(base.replace(omega=values["omega"], b=values["b"]), values[parameter])
    lam = param.value(osc)
    problem = SymmetricBranchProblem(osc, N, p, parameter, pattern_of(branch))
    guess = {"delta": float(branch[special_variable("delta_k")].values[k, 0]),
             "flight_times": branch[special_variable("flight_time_k")].values[k],
             "states": branch[special_variable("state_k")].values[k],
             "pattern": pattern_of(branch)}
    v0 = problem.half_unknowns(initial_unknowns(guess, osc, N, p))
    # the half system is regular at the BP: Newton at fixed lam (hyperplane lam = const)
    x0 = np.append(v0, lam)
    normal = np.zeros(x0.size)
    normal[-1] = 1.0
    x = _hyperplane_newton(problem, x0, normal)
    return problem, x[:-1], lam


def _pitchfork_direction(problem: SymmetricBranchProblem, v: np.ndarray, lam: float
                         ) -> tuple[np.ndarray, float, float]:
    """The antisymmetric null direction ``e`` of the full system at the BP.

    Returns ``e`` (shape ``(2np + 1,)``, max-norm 1 on the unknowns, zero-ish parameter
    part), the two smallest singular values' ratio to the largest (``s_min``: how
    singular the full system is there, ``s_next``: how well the null space is separated).
    """
    full = problem.full
    u = problem.full_unknowns(v, lam)
    extended = np.column_stack([full.jacobian(u, lam), full.dparam(u, lam)])
    _, sing, vt = np.linalg.svd(extended)
    basis = vt[-2:].T
    # the symmetric tangent in the full unknowns: du = E dv + de/dlam dlam
    half_ext = np.column_stack([problem.jacobian(v, lam), problem.dparam(v, lam)])
    t_half = np.linalg.svd(half_ext)[2][-1]
    du = problem.halves.embedding @ t_half[:-1]
    if problem.param.data == FREQUENCY:  # the half unknowns' offset moves with omega
        du = du + problem.halves.offset_derivative(lam) * t_half[-1]
    t_sym = np.append(du, t_half[-1])
    t_sym /= np.linalg.norm(t_sym)
    a = basis.T @ t_sym
    e = basis @ np.array([-a[1], a[0]])
    e /= np.max(np.abs(e[:-1]))
    return e, float(sing[-1] / sing[0]), float(sing[-2] / sing[0])


def _check_side(side: object) -> int:
    if isinstance(side, bool) or side not in (1, -1):
        raise ParameterError(f"side must be +1 or -1 (which motion of the asymmetric pair: "
                             f"the step +epsilon or -epsilon along the antisymmetric direction); "
                             f"got {side!r}")
    return int(side)


@blas_limited
def pitchfork_branch(branch: xr.Dataset, which: int = 0, side: int = 1, *,
                     bounds: Sequence[float] | None = None, epsilon: float = 1e-3,
                     detect: Sequence[str] = LABELS, options: ContinuationOptions | None = None,
                     **more: Any) -> xr.Dataset:
    """Follow one asymmetric branch born at a symmetry-breaking pitchfork (BP).

    Parameters
    ----------
    branch : xarray.Dataset
        A branch of symmetric motions with a BP point
        (:func:`impactcont.analysis.branch.multi_impact_continuation` of a symmetric motion).
    which : int
        Which BP point (index among the BP points, branch order).
    side : {1, -1}
        Which motion of the pair: the step ``+epsilon`` or ``-epsilon`` along the
        antisymmetric direction (the two are mirror images of each other).
    bounds : (float, float), optional
        Parameter range; default the bounds of ``branch``.
    epsilon : float
        Displacement from the BP along the antisymmetric direction (max-norm of the
        full unknowns), in (0, 1).
    detect : sequence of str
        Special points to detect on the new branch.
    options : ContinuationOptions, optional
        Continuation options (the drivers' defaults for those left out); the switch sets
        ``direction`` (away from the BP) and one direction only.
    **more
        Convenience keywords for single options (``ds``, ``ds_max``, ``max_points``, ...).

    Returns
    -------
    xarray.Dataset
        The asymmetric N-p branch through the step, followed away from the BP;
        attributes ``born_at = "BP"``, ``born_at_value``, ``parent_N``,
        ``parent_impacts``, ``switch_side``.

    Raises
    ------
    ParameterError
        No such BP point, bad `side`, `epsilon` or bounds.
    NoPeriodicMotionError
        The symmetric motion at the BP or the switched point could not be computed, or
        Newton fell back onto the symmetric branch.

    Notes
    -----
    Ctrl-C returns the new branch as far as it was computed (module docstring, Ctrl-C).
    """
    epsilon = _check_epsilon(epsilon)
    side = _check_side(side)
    if not isinstance(branch, xr.Dataset):
        raise TypeError(f"branch must be a branch xarray.Dataset; got {type(branch).__name__}")
    if "impact" not in branch.dims:
        raise ParameterError(NOT_SYMMETRIC)
    half, v, lam_bp = _symmetric_at(branch, which)
    parameter, full = half.parameter, half.full
    lo, hi = _dataset_bounds(branch, bounds)
    e, s_min, s_next = _pitchfork_direction(half, v, lam_bp)
    log.info("BP at %s=%.12g: [J | F_lam] of the full system has singular values %.2e and "
             "%.2e (relative) below the rest", parameter, lam_bp, s_min, s_next)
    x_bp = np.append(half.full_unknowns(v, lam_bp), lam_bp)
    x1 = _hyperplane_newton(full, x_bp + side * epsilon * e, e)
    u1, lam1 = x1[:-1], float(x1[-1])
    defect = symmetry_defect(full.orbit(u1, lam1, checks=False))
    # the symmetric branch has defect 0; the new one starts about epsilon away from it
    if not defect > 0.01 * epsilon:
        raise NoPeriodicMotionError(
            f"branch switching at the BP {parameter}={lam_bp:.12g}: the corrected point is "
            f"the symmetric motion again (asymmetry {defect:.3g})")
    if not lo <= lam1 <= hi:
        raise ParameterError(f"bounds ({lo}, {hi}) must contain the switched point "
                             f"{parameter}={lam1!r}")
    if lam1 == lam_bp:
        log.warning("the switched point has the BP's parameter value exactly; going up")
    direction = 1 if lam1 >= lam_bp else -1
    info = {"born_at": "BP", "born_at_value": lam_bp, "parent_N": half.N,
            "parent_impacts": half.p, "switch_side": side, "switch_epsilon": epsilon,
            "switch_singular_value": s_min, "switch_asymmetry": defect}
    log.info("switched to the asymmetric %d-%d branch (side %+d) at %s=%.12g "
             "(asymmetry %.3g), going %s", half.N, half.p, side, parameter, lam1, defect,
             "up" if direction > 0 else "down")
    opts = make_options((lo, hi), options, direction=direction, both_directions=False, **more)
    return run_branch(full, u1, lam1, opts, detect=detect,
                      record={"switch": info, "symmetric": False}, extra_attrs=info)


def pitchfork_switch(branch: xr.Dataset, which: int = 0, *,
                     bounds: Sequence[float] | None = None, epsilon: float = 1e-3,
                     detect: Sequence[str] = LABELS, options: ContinuationOptions | None = None,
                     **more: Any) -> tuple[xr.Dataset, xr.Dataset]:
    """Follow both asymmetric branches born at a symmetry-breaking pitchfork (BP).

    :func:`pitchfork_branch` with ``side = +1`` and ``side = -1``; the arguments are its own.

    Returns
    -------
    (xarray.Dataset, xarray.Dataset)
        The asymmetric N-p branches through ``+epsilon e`` and ``-epsilon e``, mirror
        images of each other (:func:`impactcont.orbit.symmetry.mirror_image` maps a
        motion of one onto a motion of the other), each followed away from the BP.

    Notes
    -----
    Ctrl-C returns the new branch as far as it was computed (module docstring, Ctrl-C).
    """
    kwargs = {"bounds": bounds, "epsilon": epsilon, "detect": detect, "options": options,
              **more}
    return (pitchfork_branch(branch, which, 1, **kwargs),
            pitchfork_branch(branch, which, -1, **kwargs))

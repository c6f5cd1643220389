"""The general evaluator of a stability map: one motion family followed from a seed by shooting.

:func:`impactcont.stability_map` of a motion (``stability_map(start, parameters=("omega",
"b"), grid={"omega": ..., "b": ...})``, or its alias :func:`impactcont.multi_impact_map`)
checks its arguments in :mod:`impactcont.analysis.maps` and runs :func:`family_map` here,
which solves the motion of `start` (an N-p motion of :func:`impactcont.multi_impact_orbit`,
from a simulation or a branch point, or an N-1 motion of the closed form given
``evaluator="shooting"``: :func:`impactcont.multi_impact_map` maps an N-1 motion's family
by the closed form otherwise) at every grid point it can reach: Newton on the shooting
system of :mod:`impactcont.orbit.multi_impact` at each grid point, started from a solved
neighbour (natural-parameter continuation on the grid, a secant predictor through
two solved points in line), in one compiled sweep (:mod:`impactcont.kernel.sweep`).
A motion with sticking phases (a lowercase letter in its pattern) is swept the same way
in Python over the compiled Newton of :func:`impactcont.multi_impact_orbit`
(:func:`~impactcont.orbit.sticky.sticky_newton`) on the flows of its pattern's branch
problem (:class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem`), each
motion evaluated from the Newton's shot (``_StickySetting``); its map says why a
motion found is not physical (``reason``: a stick ended, release grazing, the sticking
onset passed, or a plain check) and carries its sticks' times, releases and pressing
forces (:data:`~impactcont.dataset.maps.STICKY_MAP_VARIABLES`).
A symmetric motion of a symmetric system is solved on its half system closed by the
reflection, as :class:`~impactcont.problems.symmetric_branch.SymmetricBranchProblem`
does, which stays regular through the symmetry-breaking pitchforks where the full
shooting Jacobian is singular.

What such a map is: **one family followed from its seed**, not every motion that
exists. A grid point is "found" when Newton from a solved neighbour converges (to a
solution within ``max_change`` of the predictor). Motions of the family that are
reached only around a fold of the parameters, other motions with the same pattern
(the asymmetric pair born at a pitchfork, the other member of a saddle-node pair),
motions with another pattern, and parts of the family cut off from the seed by a
region where Newton fails are not in the map; a grid line that crosses a fold may
jump to the other member of the pair. Where the family is found it is exact (the
shooting solution to ``tol``), and its stability and physicality are those of
:func:`impactcont.multi_impact_orbit` at that point.

The sweeps run as the tasks of :class:`~impactcont.analysis.map_runner.MapRunner`, with the
executors, progress bar, memory bound and Ctrl-C of :func:`impactcont.stability_map`: a
map of up to 65536 points is one sweep from its seed; a larger one (or one given
``rows_per_task``) sweeps the seed's column first, then bands of rows of the first
parameter, each from its point on that column nearest the seed, as tasks that run at
once. The bands depend on the grid and ``rows_per_task`` only, never on the executor.

The closed form's evaluator of every N-1 motion (every root of eq. 15 at every grid
point) is the fast one, in :mod:`impactcont.analysis.maps`; both run their tasks on
:class:`~impactcont.analysis.map_runner.MapRunner`. Schema:
:mod:`impactcont.dataset.maps`; plots: :mod:`impactcont.plots.maps`; ``docs/multi_maps.md``.
"""

from __future__ import annotations

import collections
import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.map_runner import (
    _DISK_FIXED_BYTES,
    MapJob,
    MapRunner,
    _check_disk_floor,
    _require_dask,
    abandon,
    compiled_interrupts,
    fill_blocks,
    mark_computed,
    positive_int,
    positive_number,
    written_blocks,
)
from impactcont.dataset.attributes import extra_stop_names, split_parameters
from impactcont.dataset.io import open_lazy, save_blocks
from impactcont.dataset.map_storage import (
    open_temporary_map,
    remove_stale_maps,
    temporary_map_file,
)
from impactcont.dataset.maps import (
    MAP_REASONS,
    multi_impact_map_dataset,
    sticky_pattern,
    validate_multi_impact_map_dataset,
)
from impactcont.dataset.schema import _options_json
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.kernel.arrays import (
    FlowTables,
    Forcing,
    GeometryTables,
    ShootingFlow,
    SweepGrid,
    SweepMotion,
    SweepOutputs,
    SweepSettings,
    stack_flows,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import MASS, ModelParameter, model_parameter
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import MultiImpactOrbit, multi_impact_orbit
from impactcont.orbit.sticky import StickyShooting, sticky_newton, sticky_orbit_from_unknowns
from impactcont.orbit.stop_geometry import stop_geometry
from impactcont.orbit.symmetry import (
    SYMMETRY_TOL,
    HalfUnknowns,
    admits_symmetric_motions,
    symmetry_defect,
)
from impactcont.problems.multi_impact_branch import (
    MultiImpactBranchProblem,
    release_grazing_test,
    stick_end_test,
)
from impactcont.progress import ProgressOption, interruptible, reporter
from impactcont.threads import blas_limited

__all__ = ["check_sweep_options", "family_map", "multi_impact_map_orbit"]

log = logging.getLogger(__name__)

_SEED_SUBSTEPS = (1, 2, 4, 8, 16, 32)
#: Grid points of a task at least: a map of up to this many points is one sweep from its
#: seed; a larger one is cut into bands of whole rows of its first parameter.
_TASK_POINTS = 1 << 16
#: The same for a motion with sticking phases, swept in Python over its compiled Newton
#: and evaluated in Python (about 1-3 ms a point): tasks of some seconds, which a pool runs
#: at once.
_STICKY_TASK_POINTS = 1 << 11


def _decide_symmetric(orbit: MultiImpactOrbit, params: tuple[ModelParameter, ModelParameter],
                      symmetric: Any) -> bool:
    """Whether to solve on the half system (as ``branch.branch_problem`` decides)."""
    osc = orbit.oscillator
    pattern = orbit.pattern or "U" * orbit.p
    parameters = [param.name for param in params]
    keeps = all(param.keeps_symmetry for param in params)
    admits = admits_symmetric_motions(osc, orbit.N, orbit.p, pattern)
    if symmetric is None:
        return bool(keeps and admits and symmetry_defect(orbit) <= SYMMETRY_TOL)
    if not isinstance(symmetric, (bool, np.bool_)):
        raise ParameterError(f"symmetric must be True, False or None (decide from the motion); "
                             f"got {symmetric!r}")
    if symmetric:
        if not keeps:
            raise ParameterError(f"symmetric=True: parameters {parameters} move one stop "
                                 "only and break the symmetry; mirror the stops "
                                 "(Stops(mirror=True)), continue 'gap', or give "
                                 "symmetric=False")
        if not admits:
            raise ParameterError(f"symmetric=True: the N={orbit.N}, p={orbit.p} motions with "
                                 f"pattern {pattern!r} of {osc!r} cannot be symmetric (N odd, p "
                                 "even, the pattern's second half the mirror of its first, "
                                 "b_low == b, R_low == R)")
        defect = symmetry_defect(orbit)
        if not defect <= SYMMETRY_TOL:
            raise ParameterError(f"symmetric=True: the start is not symmetric (symmetry_defect "
                                 f"{defect:.3g} > {SYMMETRY_TOL:g}); give symmetric=False or a "
                                 "symmetric motion")
    return bool(symmetric)


class _Tables:
    """The flows and stop geometries of a grid, stacked for the compiled sweep.

    A flow (:meth:`~impactcont.orbit.flow.Flow.shooting_arrays` and the constant force's
    :meth:`~impactcont.orbit.flow.Flow.static_arrays`) is built once per value of the
    parameters that change it (all but those that move a stop:
    :attr:`~impactcont.model.parameters.ModelParameter.moves_stops`), a stop geometry
    (:func:`~impactcont.orbit.stop_geometry.stop_geometry`: normals, positions, impact
    matrices) once per value of those that move a stop (``b``, ``R``, ``b_low``,
    ``R_low``, ``gap``) or change the masses (the two-body impact law of a clearance
    between masses, :meth:`~impactcont.model.stops.Stops.impact_matrix`, depends on M).
    `built` keeps them by value for the next tables of the same map (its bands share their
    rows' flows and their columns' geometries).
    """

    def __init__(self, osc: ImpactOscillator, params: tuple[ModelParameter, ...],
                 grid: dict[str, np.ndarray], pattern: str, solved: int,
                 built: dict[tuple[Any, ...], Any] | None = None) -> None:
        parameters = tuple(param.name for param in params)
        self.osc, self.parameters, self.pattern, self.solved = osc, parameters, pattern, solved
        shape = tuple(grid[name].size for name in parameters)
        flow_axes = [k for k, param in enumerate(params) if not param.moves_stops]
        stop_axes = [k for k, param in enumerate(params)
                     if param.moves_stops or param.data == MASS]
        flow_values, self.flow_index = _combinations(parameters, grid, flow_axes, shape)
        geometry_values, self.geometry_index = _combinations(parameters, grid, stop_axes, shape)
        by_name = {param.name: param for param in params}
        built = {} if built is None else built

        def once(kind: str, values: dict[str, float], make: Callable[[], Any]) -> Any:
            key = (kind, pattern, *sorted(values.items()))
            if key not in built:
                built[key] = make()
            return built[key]

        self.flows = [once("flow", values, lambda v=values: Flow(_replaced(osc, by_name, v)))
                      for values in flow_values]
        geometries = [once("geometry", values,
                           lambda v=values: stop_geometry(_replaced(osc, by_name, v), pattern))
                      for values in geometry_values]
        self.flow_tables = _stack([(flow.shooting_arrays(), flow.forcing_arrays())
                                   for flow in self.flows], self.flow_index)
        # the stop coordinates, the pivot of each impact (the own mass of the stop it hits),
        # the sides and the lower stop's presence are the stops' structure, which no
        # parameter changes
        first = geometries[0]
        self.pivots = np.ascontiguousarray(first.pivots, dtype=np.int64)
        self.signs = np.ascontiguousarray(first.signs, dtype=float)
        self.two_sided = first.two_sided
        q = solved

        def column(get: Any) -> np.ndarray:
            # read-only, as the stop geometries the shooting's Python callers pass: the
            # sweep then calls the compiled shooting system with their argument types (a
            # writable table compiled it a second time, about 2 s at the first map)
            out = np.ascontiguousarray(np.array([get(geo) for geo in geometries], dtype=float))
            out.flags.writeable = False
            return out

        self.positions = column(lambda geo: geo.positions[:q])
        self.normals = column(lambda geo: geo.normals[:q])
        self.matrices = column(lambda geo: geo.matrices[:q])
        self.full_normals = column(lambda geo: geo.normals)
        self.full_positions = column(lambda geo: geo.positions)
        self.full_matrices = column(lambda geo: geo.matrices)
        self.contact_normals = column(lambda geo: geo.normal)
        self.b_upper = column(lambda geo: geo.b)
        self.b_lower = column(lambda geo: geo.b_low)
        self.extra_normals = column(lambda geo: geo.extra_normals)
        self.extra_signs = column(lambda geo: geo.extra_signs)
        self.extra_positions = column(lambda geo: geo.extra_positions)


def _replaced(osc: ImpactOscillator, params: Mapping[str, ModelParameter],
              values: dict[str, float]) -> ImpactOscillator:
    """`osc` with each parameter of `values` set as its object sets it."""
    if not values:
        return osc
    try:
        for name, value in values.items():
            osc = params[name].at(osc, value)
        return osc
    except ParameterError as exc:
        raise ParameterError(f"grid: the oscillator at {values} cannot be built: {exc}") from None


def _combinations(parameters: tuple[str, str], grid: dict[str, np.ndarray], axes: list[int],
                  shape: tuple[int, int]) -> tuple[list[dict[str, float]], np.ndarray]:
    """The distinct values of the parameters on `axes` and the index of each grid point."""
    index = np.zeros(shape, dtype=np.int64)
    if not axes:
        return [{}], index
    if len(axes) == 1:
        k = axes[0]
        name = parameters[k]
        index += np.arange(shape[k]).reshape((-1, 1) if k == 0 else (1, -1))
        return [{name: float(v)} for v in grid[name]], index
    index[:] = np.arange(shape[0] * shape[1]).reshape(shape)
    return [{parameters[0]: float(v0), parameters[1]: float(v1)} for v0 in grid[parameters[0]]
            for v1 in grid[parameters[1]]], index


def _stack(flows: list[tuple[ShootingFlow, Forcing]], index: np.ndarray) -> FlowTables:
    """The flows' arrays stacked on a new first axis (one row per flow)."""
    try:
        return stack_flows(flows, index)
    except ValueError as exc:
        raise ParameterError(f"the flows of the grid have modal arrays of different shapes "
                             f"(the first-order modes change their structure across the "
                             f"grid: {exc}); map a smaller range of the damping parameter"
                             ) from None


def _nearest(grid: dict[str, np.ndarray], parameters: tuple[str, str],
             values: tuple[float, float]) -> tuple[int, int]:
    """The grid point nearest `values`, distances in units of each axis's range."""
    out = []
    for name, value in zip(parameters, values, strict=True):
        axis = grid[name]
        out.append(int(np.argmin(np.abs(axis - value))))
    return out[0], out[1]


def _kernel() -> Any:
    from impactcont.kernel import sweep as map_kernel

    return map_kernel


class _Setting:
    """What every sweep of one map shares: the motion solved and how."""

    def __init__(self, osc: ImpactOscillator, N: int, pattern: str, half: bool, admits: bool,
                 tol: float, max_iter: int, max_change: float, max_attempts: int) -> None:
        self.osc, self.N, self.pattern, self.half, self.admits = osc, N, pattern, half, admits
        self.tol, self.max_iter, self.max_change = tol, max_iter, max_change
        self.max_attempts = max_attempts
        #: the flows and stop geometries built so far, by value (:class:`_Tables`)
        self.built: dict[tuple[Any, ...], Any] = {}

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the flows and geometries built (a worker builds its own)."""
        return {**self.__dict__, "built": {}}

    def sweep(self, tables: _Tables, axes: dict[str, np.ndarray], seed: tuple[int, int],
              x_seed: np.ndarray, checks: bool
              ) -> tuple[dict[str, np.ndarray], np.ndarray, tuple[int, int, int, bool]]:
        """:func:`impactcont.kernel.sweep.sweep_stops` over the grid `axes` from `seed`.

        Returns the flat outputs, the unknowns of every point and ``(solved, attempts,
        newton_iterations, capped)``.
        """
        names = tables.parameters
        p, m = len(self.pattern), 2 * self.osc.n
        npts = axes[names[0]].size * axes[names[1]].size
        out = _empty_outputs(npts, p, m)
        unknowns = np.full((npts, x_seed.size), np.nan)
        geometries = GeometryTables(
            positions=tables.positions, normals=tables.normals, matrices=tables.matrices,
            full_normals=tables.full_normals, full_positions=tables.full_positions,
            full_matrices=tables.full_matrices, contact_normals=tables.contact_normals,
            b_upper=tables.b_upper, b_lower=tables.b_lower, extra_normals=tables.extra_normals,
            extra_signs=tables.extra_signs, extra_positions=tables.extra_positions,
            index=tables.geometry_index)
        motion = SweepMotion(N=self.N, symmetric=self.half, admits=self.admits,
                             pivots=tables.pivots, signs=tables.signs,
                             two_sided=tables.two_sided)
        grid = SweepGrid(coord0=axes[names[0]], coord1=axes[names[1]], seed0=seed[0],
                         seed1=seed[1], x_seed=np.ascontiguousarray(x_seed, dtype=float))
        settings = SweepSettings(tol=self.tol, max_iter=self.max_iter,
                                 max_change=self.max_change, checks=bool(checks),
                                 max_attempts=self.max_attempts)
        outputs = SweepOutputs(
            unknowns=unknowns, found=out["found"], iterations=out["newton_iterations"],
            delta=out["delta"], stable=out["stable"], physical=out["physical"],
            rho=out["spectral_radius"], mu=out["critical_multiplier"], gap=out["gap_min"],
            velocity=out["impact_velocity_k"], tau=out["flight_time_k"], state=out["state_k"],
            asym=out["asymmetry"])
        stats = _kernel().sweep_stops(tuple(tables.flow_tables), tuple(geometries), tuple(motion),
                                      tuple(grid), tuple(settings), tuple(outputs))
        return out, unknowns, stats

    def solve_grid(self, params: tuple[ModelParameter, ModelParameter],
                   axes: dict[str, np.ndarray], seed: tuple[int, int], x_seed: np.ndarray,
                   checks: bool, evaluate: bool = True
                   ) -> tuple[dict[str, np.ndarray], np.ndarray, tuple[int, int, int, bool], int]:
        """:meth:`sweep` over the grid `axes` with its flows and stop geometries built:
        the flat outputs, the unknowns, the counts and the flows built (`evaluate` is for
        the sticky sweep's sake: the compiled sweep always evaluates)."""
        p = len(self.pattern)
        tables = _Tables(self.osc, params, axes, self.pattern, p // 2 if self.half else p,
                         self.built)
        out, unknowns, stats = self.sweep(tables, axes, seed, x_seed, checks)
        return out, unknowns, stats, len(tables.flows)

    def solve_at(self, params: tuple[ModelParameter, ModelParameter], values: dict[str, float],
                 x0: np.ndarray) -> np.ndarray | None:
        """Newton at one point of the two parameters (off the grid: the seed's way to its
        grid point); None when it does not converge."""
        axes = {name: np.array([value]) for name, value in values.items()}
        tables = _Tables(self.osc, params, axes, self.pattern, len(x0) // (2 * self.osc.n),
                         self.built)
        out, unknowns, _ = self.sweep(tables, axes, (0, 0), x0, False)
        return unknowns[0] if out["found"][0] else None


# -- motions with sticking phases ------------------------------------------------------------
#: What a Newton solve or a motion's evaluation at a grid point may raise where the motion
#: of the family does not exist there (the point is then not found).
_SOLVE_ERRORS = (ParameterError, NoPeriodicMotionError, np.linalg.LinAlgError,
                 FloatingPointError, ValueError, ZeroDivisionError)


#: Branch problems a sticky sweep keeps at once (one per value of the parameter that is not
#: continued), the least recently used dropped.
_PROBLEMS_KEPT = 64


def _wrap(phase: np.ndarray) -> np.ndarray:
    """Phases wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(phase, dtype=float), 2.0 * np.pi)


class _StickySetting:
    """What every sweep of the map of a motion with sticking phases shares, and the sweep.

    Each grid point is solved by the compiled Newton of the pattern's shooting system
    (:func:`~impactcont.orbit.sticky.sticky_newton`: its sticking phases, release rows and
    stick times) at fixed parameters, on the flow of
    :class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem`: one problem
    per value of one parameter, continued in the other (``omega`` when it is one of the
    two: a flow and its held systems at a new omega are the start's with new forced
    amplitudes), and evaluated from the Newton's shot at the solution
    (:func:`~impactcont.orbit.sticky.sticky_orbit_from_unknowns`, without the Jacobian: the
    map keeps no condition number).
    The sweep is the compiled sweep's (:func:`impactcont.kernel.sweep.sweep_stops`) in
    Python: breadth first from the seed, a secant predictor through two solved points in
    line, `max_attempts` per point, a solution farther than `max_change` from its predictor
    refused.
    """

    sticky = True
    half = False
    #: branch problems built by the last sweep
    built = 0

    def __init__(self, orbit: MultiImpactOrbit, params: tuple[ModelParameter, ModelParameter],
                 symmetric: Any, tol: float, max_iter: int, max_change: float,
                 max_attempts: int) -> None:
        osc = orbit.oscillator
        self.osc, self.N, self.p = osc, orbit.N, orbit.p
        self.pattern = orbit.pattern
        self.tol, self.max_iter, self.max_change = tol, max_iter, max_change
        self.max_attempts = max_attempts
        names = (params[0].name, params[1].name)
        if symmetric is not None and not isinstance(symmetric, (bool, np.bool_)):
            raise ParameterError(f"symmetric must be True, False or None (decide from the "
                                 f"motion); got {symmetric!r}")
        if symmetric:
            raise ParameterError(f"symmetric=True: the motion has sticking phases (pattern "
                                 f"{self.pattern!r}), which are solved on the full system "
                                 "only; give symmetric=None or False")
        #: the parameter each problem is continued in (omega when mapped: the compiled
        #: Newton) and the one whose values make the problems
        self.continued = names.index("omega") if "omega" in names else 1
        # the problems in both parameters: refuses one that unmakes a plastic stop (R)
        for name in names:
            problem = MultiImpactBranchProblem(osc, self.N, self.p, name, self.pattern)
        #: the impacts followed by a sticking phase
        self.sticks = problem.sticks

    def problem(self, params: tuple[ModelParameter, ModelParameter], values: tuple[float, float],
                problems: dict[float, MultiImpactBranchProblem]) -> MultiImpactBranchProblem:
        """The branch problem at the value of the parameter that is not continued, kept in
        `problems` (the last :data:`_PROBLEMS_KEPT` used: each holds its flows and shots;
        one is built again in about a millisecond)."""
        k = 1 - self.continued
        value = float(values[k])
        found = problems.pop(value, None)
        if found is None:
            param = params[k]
            osc = _replaced(self.osc, {param.name: param}, {param.name: value})
            found = MultiImpactBranchProblem(osc, self.N, self.p, params[self.continued].name,
                                             self.pattern)
            self.built += 1
            if len(problems) >= _PROBLEMS_KEPT:
                del problems[next(iter(problems))]  # the least recently used
        problems[value] = found  # the most recently used last
        return found

    def newton(self, problem: MultiImpactBranchProblem, lam: float, x0: np.ndarray
               ) -> tuple[np.ndarray | None, int, tuple[Flow, StickyShooting] | None]:
        """The compiled Newton of the pattern (:func:`~impactcont.orbit.sticky.sticky_newton`,
        the solve of :func:`impactcont.multi_impact_orbit`) on the flow of the problem at
        ``lam`` from `x0`: the solution (None where it does not converge), the iterations
        and the flow with the shot at the solution (its motion's evaluation needs no other
        shot)."""
        try:
            flow = problem.flow_at(lam)
            u, sh, iterations = sticky_newton(flow, self.N, self.pattern, x0, tol=self.tol,
                                              max_iter=self.max_iter)
        except _SOLVE_ERRORS as error:
            log.debug("Newton at %s = %r: %s", problem.parameter, lam, error)
            return None, self.max_iter, None
        if not np.all(np.isfinite(u)):
            return None, iterations, None
        return u, iterations, (flow, sh)

    def solve_at(self, params: tuple[ModelParameter, ModelParameter], values: dict[str, float],
                 x0: np.ndarray) -> np.ndarray | None:
        """Newton at one point of the two parameters (off the grid: the seed's way to its
        grid point); None when it does not converge."""
        pair = (float(values[params[0].name]), float(values[params[1].name]))
        try:
            problem = self.problem(params, pair, {})
        except _SOLVE_ERRORS:
            return None
        return self.newton(problem, pair[self.continued], x0)[0]

    def solve_grid(self, params: tuple[ModelParameter, ModelParameter],
                   axes: dict[str, np.ndarray], seed: tuple[int, int], x_seed: np.ndarray,
                   checks: bool, evaluate: bool = True
                   ) -> tuple[dict[str, np.ndarray], np.ndarray, tuple[int, int, int, bool], int]:
        """Every grid point of `axes` reachable from `seed` (solved from `x_seed`) through
        solved neighbours, and, with `evaluate`, each motion found evaluated
        (:meth:`evaluate`).

        Returns the flat outputs (:func:`_empty_outputs` with its sticky variables), the
        unknowns of every point, ``(solved, attempts, newton_iterations, False)`` and the
        problems built.
        """
        c0, c1 = axes[params[0].name], axes[params[1].name]
        n0, n1 = c0.size, c1.size
        npts = n0 * n1
        out = _empty_outputs(npts, self.p, 2 * self.osc.n, sticky=True)
        found, unknowns = out["found"], np.full((npts, x_seed.size), np.nan)
        tried = np.zeros(npts, dtype=np.int64)
        problems: dict[float, MultiImpactBranchProblem] = {}
        self.built = 0
        queue = collections.deque([(seed[0] * n1 + seed[1], -1)])
        attempts = iterations = 0
        unevaluated: list[int] = []
        while queue:
            point, parent = queue.popleft()
            if found[point] or tried[point] >= self.max_attempts:
                continue
            tried[point] += 1
            i0, i1 = divmod(point, n1)
            x0 = np.array(x_seed if parent < 0 else unknowns[parent], dtype=float)
            if parent >= 0:  # the secant through the parent and the point beyond it
                p0, p1 = divmod(parent, n1)
                g0, g1 = 2 * p0 - i0, 2 * p1 - i1
                if 0 <= g0 < n0 and 0 <= g1 < n1 and found[g0 * n1 + g1]:
                    ratio = ((c0[i0] - c0[p0]) / (c0[p0] - c0[g0]) if g0 != p0
                             else (c1[i1] - c1[p1]) / (c1[p1] - c1[g1]))
                    x0 += ratio * (unknowns[parent] - unknowns[g0 * n1 + g1])
            values = (float(c0[i0]), float(c1[i1]))
            attempts += 1
            try:
                problem = self.problem(params, values, problems)
            except _SOLVE_ERRORS:
                continue
            x, it, shot = self.newton(problem, values[self.continued], x0)
            iterations += it
            if x is None or (parent >= 0 and float(np.max(np.abs(x - x0))) > self.max_change):
                continue
            found[point] = True
            unknowns[point] = x
            out["newton_iterations"][point] = it
            # evaluated from the Newton's own shot; a motion that cannot be evaluated is not
            # found, but it seeds its neighbours as every solved point does
            if evaluate and not self.evaluate(*shot, x, checks, out, point):
                unevaluated.append(point)
            for d0, d1 in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                k0, k1 = i0 + d0, i1 + d1
                if 0 <= k0 < n0 and 0 <= k1 < n1:
                    q = k0 * n1 + k1
                    if not found[q] and tried[q] < self.max_attempts:
                        queue.append((q, point))
        for point in unevaluated:
            found[point] = False
            unknowns[point] = np.nan
            out["newton_iterations"][point] = -1
        solved = int(np.count_nonzero(found))
        return out, unknowns, (solved, attempts, iterations, False), self.built

    def evaluate(self, flow: Flow, sh: StickyShooting, u: np.ndarray, checks: bool,
                 out: dict[str, np.ndarray], point: int) -> bool:
        """Write the motion of unknowns `u` on `flow` (its G, checks and sticking phases:
        :func:`~impactcont.orbit.sticky.sticky_orbit_from_unknowns` of the shot `sh` at
        `u`, the Newton's) into `out` at `point`; False where it cannot be evaluated."""
        try:  # without the Jacobian: the map keeps no condition number
            orbit = sticky_orbit_from_unknowns(flow, self.N, self.pattern, u,
                                               sh._replace(jacobian=None),
                                               checks=checks)
        except _SOLVE_ERRORS as error:
            log.debug("the motion of %r not evaluated: %s", flow.osc, error)
            return False
        mu = np.asarray(orbit.multipliers)
        held = self.sticks
        stick = np.where(held, np.asarray(orbit.stick_times, dtype=float), np.nan)
        out["delta"][point] = math.atan2(math.sin(u[0]), math.cos(u[0]))
        out["spectral_radius"][point] = orbit.spectral_radius
        out["critical_multiplier"][point] = mu[int(np.argmax(np.abs(mu)))]
        out["stable"][point] = orbit.stable
        out["physical"][point] = orbit.physical
        out["gap_min"][point] = orbit.gap_min if checks else math.nan
        out["impact_velocity_k"][point] = orbit.impact_velocities
        out["flight_time_k"][point] = orbit.flight_times
        out["state_k"][point] = orbit.states
        out["stick_time_k"][point] = stick
        omega = flow.osc.omega
        out["release_phase_k"][point] = np.where(held, _wrap(orbit.phases + omega * stick),
                                                 np.nan)
        out["pressing_min_k"][point] = np.where(held, orbit.pressing_min, np.nan)
        out["landing_pressing_k"][point] = np.where(held, orbit.landing_pressing, np.nan)
        out["stick_time_min"][point] = stick_end_test(orbit)
        out["pressing_min"][point] = release_grazing_test(orbit)
        out["reason"][point] = 0 if orbit.physical else _reasons(orbit, held, checks)
        return True


def _reasons(orbit: MultiImpactOrbit, held: np.ndarray, checks: bool) -> int:
    """Why the motion `orbit` (with the sticking phases `held`) is not physical, as the bits
    of :data:`~impactcont.dataset.maps.MAP_REASONS`: its checks, from its numbers."""
    bits = 0
    for k in np.flatnonzero(held):  # in the order the motion checks each sticking phase
        if not orbit.stick_times[k] > 0.0:
            bits |= MAP_REASONS["stick_ended"]
        elif not orbit.landing_pressing[k] > 0.0:
            bits |= MAP_REASONS["sticking_onset"]
        elif not orbit.pressing_min[k] > 0.0:
            bits |= MAP_REASONS["release_grazing"]
    if not np.all(np.asarray(orbit.flight_times) > 0.0):
        bits |= MAP_REASONS["flight_time"]
    if not np.all(np.asarray(orbit.impact_velocities) > 0.0):
        bits |= MAP_REASONS["impact_velocity"]
    if not checks:
        bits |= MAP_REASONS["contact_not_checked"]
    elif not orbit.gap_min > 0.0:
        bits |= MAP_REASONS["interior_contact"]
    if any(chatter.reached for chatter in orbit.chatters):  # a bounce reaches a stop
        bits |= MAP_REASONS["bounce_reaches_stop"]
    return bits or MAP_REASONS["other"]


class _BandJob(MapJob):
    """The tasks of :func:`multi_impact_map`: bands of whole rows of the first parameter.

    A task ``(rows, seed row, unknowns)`` sweeps the rows ``rows`` of the grid (every
    value of the second parameter) from the seed row's point on the seed's column, solved
    from the unknowns given (:func:`_band_task`).
    """

    what = "multi_impact_map"

    def __init__(self, setting: _Setting, params: tuple[ModelParameter, ModelParameter],
                 axes: dict[str, np.ndarray], column: int, checks: bool) -> None:
        self.setting, self.names = setting, tuple(param.name for param in params)
        self.axes, self.column, self.checks = axes, column, checks

    def call(self, task: tuple[slice, int, np.ndarray]) -> tuple[Any, tuple[Any, ...]]:
        rows, row, x_seed = task
        first, second = self.names
        band = {first: self.axes[first][rows], second: self.axes[second]}
        return _band_task, (self.setting, self.names, band, (row - rows.start, self.column),
                            x_seed, self.checks)

    def points(self, task: tuple[slice, int, np.ndarray]) -> int:
        rows = task[0]
        return (rows.stop - rows.start) * self.axes[self.names[1]].size

    def describe(self, task: tuple[slice, int, np.ndarray]) -> str:
        rows = task[0]
        first = self.axes[self.names[0]][rows]
        return (f"{self.names[0]}[{rows.start}:{rows.stop}] in [{first[0]:.6g}, "
                f"{first[-1]:.6g}]")


def _band_task(setting: _Setting, names: tuple[str, str], band: dict[str, np.ndarray],
               seed: tuple[int, int], x_seed: np.ndarray, checks: bool
               ) -> tuple[dict[str, np.ndarray], tuple[int, int, int, bool], int]:
    """One task of :func:`multi_impact_map` (picklable, top level): the sweep of a band
    of the grid from its seed; its outputs, ``(solved, attempts, newton_iterations,
    capped)`` and the flows built."""
    osc = setting.osc
    params = (model_parameter(osc, names[0], "parameters"),
              model_parameter(osc, names[1], "parameters"))
    with compiled_interrupts():
        out, _, stats, flows = setting.solve_grid(params, band, seed, x_seed, checks)
    return out, stats, flows


def _bands(setting: _Setting, params: tuple[ModelParameter, ModelParameter],
           axes: dict[str, np.ndarray], seed: tuple[int, int], x_seed: np.ndarray,
           rows: int) -> list[tuple[slice, int, np.ndarray]]:
    """The tasks of a map: bands of `rows` rows of the first parameter, each seeded on the
    seed's column (the spine: swept here first, from the seed) at the row nearest the
    seed that the spine found; a band with none has no task (nothing of it is found).
    A map of one band is the one sweep from the seed."""
    first, second = params[0].name, params[1].name
    n0 = axes[first].size
    if rows >= n0:
        return [(slice(0, n0), seed[0], x_seed)]
    spine_axes = {first: axes[first], second: axes[second][seed[1]:seed[1] + 1]}
    out, unknowns, _, _ = setting.solve_grid(params, spine_axes, (seed[0], 0), x_seed, False,
                                             evaluate=False)
    tasks = []
    for start in range(0, n0, rows):
        band = slice(start, min(start + rows, n0))
        if band.start <= seed[0] < band.stop:
            tasks.append((band, seed[0], x_seed))
            continue
        found = [r for r in range(band.start, band.stop) if out["found"][r]]
        if found:
            row = min(found, key=lambda r: abs(r - seed[0]))
            tasks.append((band, row, unknowns[row].copy()))
    return tasks


def _seed(orbit: MultiImpactOrbit, setting: _Setting,
          params: tuple[ModelParameter, ModelParameter], grid: dict[str, np.ndarray],
          x_start: np.ndarray) -> tuple[tuple[int, int], np.ndarray]:
    """The seed grid point (nearest the start) and its unknowns, reached from the start in
    up to 32 equal steps of both parameters."""
    osc = orbit.oscillator
    parameters = tuple(param.name for param in params)
    start = tuple(param.value(osc) for param in params)
    i0, i1 = _nearest(grid, parameters, start)
    target = (float(grid[parameters[0]][i0]), float(grid[parameters[1]][i1]))
    for steps in _SEED_SUBSTEPS:
        x: np.ndarray | None = x_start
        for s in range(1, steps + 1):
            values = {name: a + (b - a) * s / steps
                      for name, a, b in zip(parameters, start, target, strict=True)}
            x = setting.solve_at(params, values, x)
            if x is None:
                break
        if x is not None:
            return (i0, i1), x
    raise NoPeriodicMotionError(
        f"the start motion (N={orbit.N}, p={orbit.p}, pattern {orbit.pattern!r} at "
        f"{dict(zip(parameters, start, strict=True))}) could not be followed to the nearest grid "
        f"point {dict(zip(parameters, target, strict=True))} by Newton in up to "
        f"{_SEED_SUBSTEPS[-1]} steps; start from a motion at or next to a grid point")


def check_sweep_options(*, checks: Any, tol: Any, max_iter: Any, max_change: Any,
                        max_attempts: Any) -> tuple[float, int, float, int]:
    """The options of a family's sweep checked, whichever evaluator maps the family.

    Returns
    -------
    tol, max_iter, max_change, max_attempts

    Raises
    ------
    ParameterError
        Naming the option, its value and what is allowed.
    """
    tol = positive_number("tol", tol)
    max_change = positive_number("max_change", max_change)
    max_iter = positive_int("max_iter", max_iter)
    max_attempts = positive_int("max_attempts", max_attempts)
    if not isinstance(checks, (bool, np.bool_)):
        raise ParameterError(f"checks must be True or False; got {checks!r}")
    return tol, max_iter, max_change, max_attempts


@blas_limited
def family_map(orbit: MultiImpactOrbit, params: tuple[ModelParameter, ModelParameter],
               axes: dict[str, np.ndarray], *, symmetric: bool | None = None,
               checks: bool = True, tol: float = 1e-11, max_iter: int = 12,
               max_change: float = 0.5, max_attempts: int = 4, title: str | None = None,
               executor: Any = None, max_workers: int | None = None,
               rows_per_task: int | None = None, memory_limit: float = 1e9,
               progress: ProgressOption = None, out: str | os.PathLike | None = None
               ) -> xr.Dataset:
    """The map of the motion family of `orbit` over the grid `axes` of `params`.

    What :func:`impactcont.stability_map` of a motion runs once it has checked the
    parameters, the grid and the run options (:mod:`impactcont.analysis.maps`,
    :func:`~impactcont.analysis.map_runner.check_run_options`); the options of the
    family's sweep are checked here. Every grid point is solved by Newton from a
    neighbour that was solved, starting at the grid point nearest the start (reached
    from it by Newton in a few steps): natural-parameter continuation over the grid,
    breadth first, with a secant predictor through two solved points in line; the map
    is one family followed from its seed (``docs/multi_maps.md``).

    Parameters
    ----------
    orbit : MultiImpactOrbit
        The start (an N-1 motion already as a 1-impact motion).
    params : (ModelParameter, ModelParameter)
        The two parameters of the oscillator of `orbit`, in grid order.
    axes : dict
        ``{name: strictly increasing 1-D grid}`` of both.
    symmetric, checks, tol, max_iter, max_change, max_attempts
        The sweep's options, as for :func:`impactcont.multi_impact_map` (checked here).
    title, executor, max_workers, rows_per_task
        As for :func:`impactcont.multi_impact_map`.
    memory_limit, progress, out
        As for :func:`impactcont.multi_impact_map`.

    Returns
    -------
    xarray.Dataset
        A map of the ``multi_impact_map`` layout (:mod:`impactcont.dataset.maps`).

    Raises
    ------
    ParameterError
        A bad option of the sweep, or a grid value where the oscillator cannot be built.
    NoPeriodicMotionError
        The start cannot be followed to its nearest grid point.
    """
    osc = orbit.oscillator
    names = (params[0].name, params[1].name)
    tol, max_iter, max_change, max_attempts = check_sweep_options(
        checks=checks, tol=tol, max_iter=max_iter, max_change=max_change,
        max_attempts=max_attempts)
    N, p = orbit.N, orbit.p
    pattern = orbit.pattern or "U" * p
    sticky = sticky_pattern(pattern, extra_stop_names(osc))
    if sticky:  # solved through the branch problem of its pattern (_StickySetting)
        setting: _Setting | _StickySetting = _StickySetting(
            orbit, params, symmetric, tol, max_iter, max_change, max_attempts)
        half = admits = False
    else:
        half = _decide_symmetric(orbit, params, symmetric)
        admits = bool(admits_symmetric_motions(osc, N, p, pattern)
                      and all(param.keeps_symmetry for param in params))
        setting = _Setting(osc, N, pattern, half, admits, tol, max_iter, max_change,
                           max_attempts)
    if rows_per_task is not None:
        rows_per_task = positive_int("rows_per_task", rows_per_task)
    shape = (axes[names[0]].size, axes[names[1]].size)
    npts = shape[0] * shape[1]
    rows = rows_per_task or max(1, -(-(_STICKY_TASK_POINTS if sticky else _TASK_POINTS)
                                      // shape[1]))
    point_bytes = _point_bytes(osc.n, p, half, sticky)
    in_memory = out is None and npts * point_bytes <= memory_limit
    if not in_memory:
        _require_dask()
    t0 = time.perf_counter()
    x_start = HalfUnknowns(osc.n, p, N).half(orbit.unknowns) if half else orbit.unknowns
    (s0, s1), x_seed = _seed(orbit, setting, params, axes, x_start)
    tasks = _bands(setting, params, axes, (s0, s1), x_seed, rows)
    t_setup = time.perf_counter() - t0
    job = _BandJob(setting, params, axes, s1, bool(checks))
    seed = {names[0]: float(axes[names[0]][s0]), names[1]: float(axes[names[1]][s1]),
            "index": [int(s0), int(s1)],
            "start": {param.name: param.value(osc) for param in params}}
    dataset = {"oscillator": osc, "N": N, "pattern": pattern, "parameters": names,
               "grid": axes, "symmetric": half, "seed": seed, "title": title}
    stats = _Stats()
    runner: MapRunner | None = None

    def options() -> dict[str, Any]:
        """How the map was computed, with the sweeps' counts so far."""
        t_sweep = time.perf_counter() - t1
        return {"evaluator": "shooting", "tol": tol, "max_iter": max_iter,
                "max_change": max_change, "max_attempts": max_attempts, "checks": bool(checks),
                "attempts": int(stats.attempts), "newton_iterations": int(stats.iterations),
                "flows": stats.flows, "setup_seconds": round(t_setup, 4),
                "sweep_seconds": round(t_sweep, 4), "executor": runner.name,
                "tasks": len(tasks), "rows_per_task": rows}

    t1 = time.perf_counter()
    remove_stale_maps(once=True)  # the temporary maps of killed processes (map_storage)
    temporary = False
    with interruptible("multi_impact_map"), reporter(progress, "multi_impact_map",
                                                     total=npts) as rep:
        # the pool's workers forked before the map's arrays exist (MapRunner)
        runner = MapRunner(job, executor, max_workers, rep)
        unseeded = npts - sum(job.points(task) for task in tasks)  # nothing found there
        runner.done += unseeded
        rep.advance(unseeded)
        task_bytes = rows * shape[1] * 2 * point_bytes  # its outputs, sent and copied in
        try:
            if in_memory:
                runner.limit = max(1, int((memory_limit - npts * point_bytes) // task_bytes))
                ds, computed = _family_in_memory(runner, tasks, shape, admits, dataset, stats)
            else:
                _check_disk_floor(memory_limit, runner.in_flight)
                runner.limit = max(1, int((memory_limit - _DISK_FIXED_BYTES) // task_bytes))
                temporary = out is None
                if temporary:
                    out = temporary_map_file()
                    log.warning("the map takes %.3g GB, more than memory_limit = %.3g GB: it is "
                                "written to %s (removed when the returned dataset is closed) "
                                "and returned lazily", npts * point_bytes / 1e9,
                                memory_limit / 1e9, out)
                path, computed = _family_to_file(runner, tasks, shape, admits, dataset, stats,
                                                 rows, out, options)
        except BaseException:  # a failure, or a second Ctrl-C
            abandon(runner, out if temporary else None)
            raise
        runner.close(kill=computed is not None)

    t_sweep = time.perf_counter() - t1
    if stats.capped:
        log.warning("a contact-search grid was capped at 2000000 cells on some flight of the "
                    "map: a short excursion past a stop (eq. 16) may be missed there")
    if checks and stats.unchecked:
        log.warning("%d of %d found points: interior contact not checked (the constant force "
                    "F_static moves %s by a polynomial in time through a free mode, which the "
                    "contact search does not represent); they are not physical "
                    "(contact_checked False)", stats.unchecked, stats.solved,
                    osc.stops.coordinate)
    log.info("N=%d p=%d map over %s x %s: %d of %d points found (%d Newton attempts) in "
             "%.3g s (%.3g points/s; setup %.3g s)", N, p, names[0], names[1], stats.solved,
             npts, stats.attempts, t_sweep, npts / t_sweep if t_sweep > 0 else math.inf,
             t_setup)
    if not in_memory:
        if computed is not None:
            log.warning("the interrupted map is kept in %s (interrupted = 1, the variable "
                        "'computed')", out)
        # opened once the workers are gone (a forked worker holds the file's HDF5 lock)
        return open_temporary_map(path) if temporary else open_lazy(path)
    ds.attrs["options"] = _options_json(options())
    if computed is not None:
        mark_computed(ds, computed, names)
    return ds


class _Stats:
    """What the sweeps of a map found, summed over its tasks as they finish."""

    def __init__(self) -> None:
        self.solved = self.attempts = self.iterations = self.flows = self.unchecked = 0
        self.capped = False

    def add(self, values: dict[str, np.ndarray], stats: tuple[int, int, int, bool],
            flows: int) -> None:
        """Count a finished band; its outputs get ``contact_checked``."""
        self.solved, self.attempts = self.solved + stats[0], self.attempts + stats[1]
        self.iterations, self.capped = self.iterations + stats[2], self.capped or bool(stats[3])
        self.flows += flows
        _contact_checked(values)
        self.unchecked += int(np.count_nonzero(values["found"] & ~values["contact_checked"]))


def _contact_checked(values: dict[str, np.ndarray]) -> None:
    """``contact_checked`` of a band's outputs.

    The sweep leaves ``gap_min`` NaN at a found point exactly where the contact search did
    not run (``checks=False``) or cannot represent a flight (a constant force pushing a
    free mode that the stop coordinate sees, a polynomial in time): never physical there.
    """
    values["contact_checked"] = values["found"] & ~np.isnan(values["gap_min"])


def _family_in_memory(runner: MapRunner, tasks: list[tuple[slice, int, np.ndarray]],
                      shape: tuple[int, int], admits: bool, dataset: dict[str, Any],
                      stats: _Stats) -> tuple[xr.Dataset, np.ndarray | None]:
    """The map in memory: its dataset built once with every point not found, each band
    copied in as it finishes (:func:`~impactcont.analysis.map_runner.fill_blocks`, as every
    map); and the points computed if a first Ctrl-C interrupted it (else None). Its
    attribute ``options`` is set by the caller, with the sweeps' counts."""
    osc, p = dataset["oscillator"], len(dataset["pattern"])
    values = _empty_outputs(shape, p, 2 * osc.n, _sticky(dataset))
    _contact_checked(values)
    if not admits:
        values.pop("asymmetry", None)
    ds = multi_impact_map_dataset(values=values, options={}, **dataset)
    computed = np.zeros(shape, dtype=bool)
    interrupted = fill_blocks(runner, ds, _band_blocks(runner, tasks, shape, stats, values,
                                                       dataset["parameters"]),
                              computed, dataset["parameters"])
    computed[_rows_without_task(tasks, shape[0])] = True
    return ds, (computed if interrupted else None)


def _band_blocks(runner: MapRunner, tasks: list[tuple[slice, int, np.ndarray]],
                 shape: tuple[int, int], stats: _Stats, keys: Any, names: tuple[str, str]
                 ) -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
    """Each band of the map as it finishes, counted in `stats`: its region (whole rows of
    the first parameter) and the values of the variables `keys`, shaped on the grid."""
    n1 = shape[1]
    for (band, _, _), (values, counts, nflows) in runner.results(tasks):
        stats.add(values, counts, nflows)
        count = band.stop - band.start
        yield ({names[0]: band, names[1]: slice(0, n1)},
               {key: values[key].reshape((count, n1, *values[key].shape[1:]))
                for key in keys if key in values})


def _rows_without_task(tasks: list[tuple[slice, int, np.ndarray]], rows: int) -> list[int]:
    """The rows of no band: their spine point was not found, so nothing of them is."""
    return [r for r in range(rows) if not any(t[0].start <= r < t[0].stop for t in tasks)]


def _family_to_file(runner: MapRunner, tasks: list[tuple[slice, int, np.ndarray]],
                    shape: tuple[int, int], admits: bool, dataset: dict[str, Any],
                    stats: _Stats, rows: int, out: Any, options: Any
                    ) -> tuple[Path, np.ndarray | None]:
    """The map written to a chunked, compressed NetCDF-4 file band by band as the bands
    finish (:func:`~impactcont.dataset.io.save_blocks`); nothing else of it in memory.

    The rows of no band and, after a first Ctrl-C, those of the bands not finished are
    written as not found; the attribute ``options`` (with the sweeps' counts) and, if
    interrupted, ``computed``, ``interrupted`` and ``points_computed`` are set before the
    file is moved onto `out` (never half written). Returns the file and the points computed
    if interrupted (else None).
    """
    import dask.array as da

    n0, n1 = shape
    names = dataset["parameters"]
    osc, p = dataset["oscillator"], len(dataset["pattern"])
    empty = _empty_outputs(1, p, 2 * osc.n, _sticky(dataset))
    _contact_checked(empty)
    if not admits:
        empty.pop("asymmetry", None)
    placeholders = {key: da.empty((n0, n1, *a.shape[1:]), dtype=a.dtype, chunks=-1)
                    for key, a in empty.items()}
    ds = multi_impact_map_dataset(values=placeholders, options={}, **dataset)
    encoding = {key: {"zlib": True, "complevel": 1,
                      "chunksizes": (min(rows, n0), n1, *ds[key].shape[2:])}
                for key in ds.data_vars}
    computed = np.zeros(shape, dtype=bool)
    interrupted: list[bool] = []

    def not_found(band: slice) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        # the floating-point variables are left unwritten: they read as their fill, NaN
        count = band.stop - band.start
        return ({names[0]: band, names[1]: slice(0, n1)},
                {key: np.repeat(a, count * n1, axis=0).reshape((count, n1, *a.shape[1:]))
                 for key, a in empty.items() if a.dtype.kind not in "fc"})

    def not_computed() -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
        for band, _, _ in tasks:  # the bands not finished
            if not computed[band].any():
                yield not_found(band)

    def blocks() -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
        yield from written_blocks(runner, _band_blocks(runner, tasks, shape, stats, empty,
                                                       names),
                                  computed, names, not_computed, interrupted)
        for r in _rows_without_task(tasks, n0):
            yield not_found(slice(r, r + 1))
            computed[r] = True

    def finish() -> xr.Dataset:
        marked = xr.Dataset(attrs={"options": _options_json(options())})
        if interrupted:
            mark_computed(marked, computed.copy(), names)
        return marked

    path = save_blocks(ds, out, blocks(), encoding=encoding, finish=finish)
    return path, (computed.copy() if interrupted else None)


def _sticky(dataset: dict[str, Any]) -> bool:
    """Whether the map of `dataset` (the arguments of its dataset) is of a motion with
    sticking phases."""
    return sticky_pattern(dataset["pattern"], extra_stop_names(dataset["oscillator"]))


def _point_bytes(n: int, p: int, half: bool, sticky: bool = False) -> int:
    """Bytes of a map's outputs per grid point (:func:`_empty_outputs`, the contact flag)
    and of its unknowns in a task (with sticking phases: their variables and stick
    times too)."""
    unknowns = (p // 2 if half else p) * (2 * n) + 1
    extra = 4 * p + 3 + p if sticky else 0
    return 8 * (6 + 2 * p + 2 * p * n + unknowns + extra) + 8


def _empty_outputs(npts: int | tuple[int, ...], p: int, m: int, sticky: bool = False
                   ) -> dict[str, np.ndarray]:
    """The outputs of a map of `npts` points (a count, or the grid's shape) as not found
    (NaN, False, -1, reason 0); with `sticky` those of
    :data:`~impactcont.dataset.maps.STICKY_MAP_VARIABLES` too (and no ``asymmetry``)."""
    n = (npts,) if isinstance(npts, (int, np.integer)) else tuple(npts)
    if sticky:
        out = _empty_outputs(npts, p, m)
        del out["asymmetry"]
        out.update({key: np.full((*n, p), np.nan) for key in (
            "stick_time_k", "release_phase_k", "pressing_min_k", "landing_pressing_k")})
        out.update({"stick_time_min": np.full(n, np.nan), "pressing_min": np.full(n, np.nan),
                    "reason": np.zeros(n, np.int32)})
        return out
    return {"found": np.zeros(n, bool), "newton_iterations": np.full(n, -1, np.int32),
            "delta": np.full(n, np.nan), "stable": np.zeros(n, bool),
            "physical": np.zeros(n, bool), "spectral_radius": np.full(n, np.nan),
            "critical_multiplier": np.full(n, np.nan, complex),
            "gap_min": np.full(n, np.nan),
            "impact_velocity_k": np.full((*n, p), np.nan),
            "flight_time_k": np.full((*n, p), np.nan),
            "state_k": np.full((*n, p, m), np.nan), "asymmetry": np.full(n, np.nan)}


def multi_impact_map_orbit(ds: xr.Dataset, **values: float) -> MultiImpactOrbit:
    """The motion of a map at one grid point, re-solved by Newton from what the map stored.

    Parameters
    ----------
    ds : xarray.Dataset
        A map of :func:`multi_impact_map`.
    **values : float
        The grid point: a value of each of the map's two parameters (the nearest grid
        value is taken).

    Returns
    -------
    MultiImpactOrbit
        With its G, multipliers and checks (:func:`impactcont.multi_impact_orbit`).

    Raises
    ------
    ParameterError
        Not the map's two parameters, or no motion found at that grid point.
    """
    validate_multi_impact_map_dataset(ds)
    names = tuple(split_parameters(ds.attrs["parameters"]))
    if set(values) != set(names):
        raise ParameterError(f"give a value of each of the map's parameters {list(names)}; got "
                             f"{sorted(values)}")
    index = {name: int(np.argmin(np.abs(ds[name].values - float(values[name]))))
             for name in names}
    point = ds.isel(index)
    where = {name: float(point[name]) for name in names}
    if not bool(point["found"]):
        raise ParameterError(f"no motion of the map's family was found at {where}")
    osc = ImpactOscillator.from_json(ds.attrs["oscillator"])
    for name, value in where.items():
        osc = model_parameter(osc, name, "parameters").at(osc, value)
    guess = {"delta": float(point["delta"]), "flight_times": point["flight_time_k"].values,
             "states": point["state_k"].values, "pattern": ds.attrs["pattern"]}
    if "stick_time_k" in ds:  # a motion with sticking phases: 0 after an impact without
        guess["stick_times"] = np.nan_to_num(point["stick_time_k"].values, nan=0.0)
    return multi_impact_orbit(osc, int(ds.attrs["N"]), int(ds.attrs["impacts"]), guess)

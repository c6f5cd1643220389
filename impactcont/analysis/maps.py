"""Stability maps over two parameters: the one entry of every map and its fast evaluator.

``stability_map(osc, N=[1, 2, 3, 4], omega=..., b=...)`` evaluates every root of
eq. (15) at every grid point with the batched closed form of
:mod:`impactcont.orbit.batched` (stacked numpy over ``omega x b x root``; ``S``
of eq. 13 once per ``omega``) and returns an :class:`xarray.Dataset` with dims
``(N, omega, b, root)`` (schema: :mod:`impactcont.dataset.maps`). With
``parameters=(p1, p2), grid={p1: ..., p2: ...}`` the same over any two parameters of the
oscillator (dims ``(N, p1, p2, root)``): batched along omega or b when one of them is in
the pair, else the closed form at each point on the oscillator with both parameters set.
Given a motion instead of an oscillator, the map of its family over any two parameters,
followed from it by shooting (:func:`~impactcont.analysis.family_maps.family_map`, the
general evaluator; :func:`multi_impact_map` is that map's former name), or, for an N-1
motion of :func:`impactcont.periodic_orbits`, the closed form's map kept for its root of
eq. (15) (:func:`multi_impact_map`, Notes). Both take their
parameters and grid through the one check here (:func:`map_plane`), the run options through
:func:`~impactcont.analysis.map_runner.check_run_options`, run as the tasks of a
:class:`~impactcont.analysis.map_runner.MapJob` on the same runner, and lay their
datasets out in :mod:`impactcont.dataset.maps`.

The work is split into tasks of ``(N, block of p1, block of p2)`` (at most 131072
points) run by :class:`~impactcont.analysis.map_runner.MapRunner` (the tasks of a
:class:`~impactcont.analysis.map_runner.MapJob`) on the executor named by ``executor``
(``None``/``"serial"``, ``"process"``, a dask scheduler address, an Executor or a dask
Client: :mod:`impactcont.analysis.map_runner` says what each does), as for
:func:`impactcont.multi_impact_map`, with the same progress and memory bound.

Tasks receive the oscillator as JSON and return plain arrays, so any executor
that pickles works. A process pool that breaks (a worker killed) is replaced and
the unfinished tasks are run again, one at a time (a task up to twice more), also when
the worker died sending its result and the pool did not notice
(:mod:`impactcont.analysis.pool`). The pool made for ``"process"`` is killed when the
map fails or is interrupted, and its workers end when this process is killed.

Memory: the map's arrays are made once and each task's block is copied in (or
written to the file) as it finishes, with ``2 x workers`` tasks submitted at once;
`memory_limit` bounds the peak, and a map that does not fit in it goes to a
temporary file, returned lazily and removed when closed
(:mod:`impactcont.dataset.map_storage`). ``docs/two_parameter.md`` has the measurements.

Ctrl-C (issue 31): the first one stops a map between tasks, ends the pool made for it and
returns the map computed so far: the points of the tasks not finished are NaN (False, 0
for flags and counts), False in the variable ``computed``, the attribute
``interrupted`` is 1 and ``points_computed`` counts the others; a WARNING says how many
of how many points were done. A map written to a file (``out=``, or larger than
`memory_limit`) is kept the same way: the file is finished with the tasks not done
written as not computed, ``computed`` and the attributes added, and only then moved onto
its name (a file is never left half written), and returned opened lazily. A second Ctrl-C
aborts (KeyboardInterrupt), a file being written removed.
"""
from __future__ import annotations

import functools
import json
import logging
import math
import os
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.branch import as_multi_impact_orbit
from impactcont.analysis.family_maps import (
    _decide_symmetric,
    _nearest,
    check_sweep_options,
    family_map,
    multi_impact_map_orbit,
)
from impactcont.analysis.map_runner import (
    MapJob,
    MapRunner,
    _check_disk_floor,
    _plan,
    _require_dask,
    abandon,
    check_run_options,
    compiled_interrupts,
    fill_blocks,
    mark_computed,
    positive_int,
    written_blocks,
)
from impactcont.dataset.io import open_lazy, save, save_blocks
from impactcont.dataset.map_storage import (
    open_temporary_map,
    remove_stale_maps,
    temporary_map_file,
)
from impactcont.dataset.maps import map_dataset, multi_impact_map_dataset
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import ModelParameter, model_parameter
from impactcont.model.stops import require_paper_stops
from impactcont.orbit.batched import batched_orbits
from impactcont.orbit.multi_impact import MultiImpactOrbit
from impactcont.orbit.periodic import PeriodicOrbit, _check_N, impact_states, periodic_orbits
from impactcont.progress import ProgressOption, interruptible, reporter
from impactcont.threads import blas_limited

__all__ = ["map_plane", "multi_impact_map", "multi_impact_map_orbit", "stability_map"]

log = logging.getLogger(__name__)

_OMEGA_BLOCK = 32  # omega values per task at most
_DTYPES = {"physical": bool, "stable": bool, "critical_multiplier": complex}
_ROOT_FIELDS = ("delta", "impact_velocity", "gap_min", "spectral_radius", "critical_multiplier",
                "physical", "stable")


@blas_limited
def _map_task(osc_json: str, N: int, omega: np.ndarray, b: np.ndarray,
              spectral_radius: bool = True) -> dict[str, np.ndarray]:
    """One task: every motion for one N and a block of omega values (picklable, top level)."""
    osc = _oscillator(osc_json)
    with compiled_interrupts():
        out = batched_orbits(osc, N, omega, b, spectral_radius=spectral_radius)
    return {k: out[k] for k in ("amplitude_squared", "exists", *_ROOT_FIELDS)}


@functools.lru_cache(maxsize=4)
def _oscillator(osc_json: str) -> ImpactOscillator:
    """The oscillator of a task, built (and its modes computed) once per process: a map
    sends the same one with every block."""
    return ImpactOscillator.from_json(osc_json)


def _grid(name: str, values: Any) -> np.ndarray:
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a 1-D array of finite numbers; got {values!r}"
                             ) from None
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be a non-empty 1-D array of finite numbers; got "
                             f"{values!r}")
    if a.size > 1 and not np.all(np.diff(a) > 0):
        raise ParameterError(f"{name} must be strictly increasing; got {values!r}")
    return a


#: The default N of :func:`stability_map` (a motion as the start takes none).
_ALL_N = (1, 2, 3, 4)
#: The options of :func:`impactcont.multi_impact_map` that :func:`stability_map` passes on
#: with a motion as its start.
_MOTION_OPTIONS = ("symmetric", "checks", "tol", "max_iter", "max_change", "max_attempts",
                   "title", "rows_per_task", "evaluator")
# Grid points per task at most where the closed form is evaluated per point (a map over two
# parameters other than omega and b: about 0.5 ms a point) or per line of the batched
# parameter (one of them omega or b): a task of some tenths of a second.
_POINT_TASK = 256
_LINE_TASK = 8192


@blas_limited
def stability_map(osc: Any, N: Any = _ALL_N, omega: Any = (), b: Any = (), *,
                  parameters: Sequence[str] | None = None, grid: Mapping[str, Any] | None = None,
                  executor: Any = None, max_workers: int | None = None,
                  omega_block: int | None = None, spectral_radius: bool = True,
                  out: str | os.PathLike | None = None, memory_limit: float = 1e9,
                  progress: ProgressOption = None, **others: Any) -> xr.Dataset:
    """Existence, physicality and stability of motions over a grid of two parameters.

    Given an oscillator: every N-1 motion (every root of eq. 15) at every point of an
    ``(N, omega, b)`` grid, or of ``(N, p1, p2)`` for ``parameters=(p1, p2)``, by the
    closed form (exact, no continuation: every motion that exists is in the map). On
    the (omega, b) plane the batched closed form builds ``S`` of eq. (13) once per
    ``omega`` and solves eq. (15) for every ``b`` at once (``b`` only shifts its
    right-hand side); over another pair with ``omega`` or ``b`` in it, it is batched
    along that one for each value of the other; over a pair with neither (``R``,
    ``F0``, an element such as ``k2`` or ``M[1,2]``), it is evaluated at each point on
    the oscillator with both parameters replaced
    (:meth:`~impactcont.model.parameters.ModelParameter.at`).

    Given a motion (an N-p motion of :func:`impactcont.multi_impact_orbit` or
    :func:`impactcont.special_orbit`, or an N-1 motion of :func:`impactcont.periodic_orbits`):
    the map of its family over ``parameters`` and ``grid``, followed from it
    (:func:`impactcont.multi_impact_map`, the same dataset; an N-1 motion's family by the
    closed form).

    Parameters
    ----------
    osc : ImpactOscillator, MultiImpactOrbit or PeriodicOrbit
        The oscillator (its own values of the grid's parameters are ignored), or a motion
        whose family is mapped.
    N : int or sequence of int
        Forcing periods per impact (an oscillator only).
    omega, b : 1-D array_like
        Strictly increasing grids of the forcing frequency (``> 0``) and the gap (an
        oscillator only, without `parameters`).
    parameters : (str, str), optional
        Two different continuable parameters, the grid's axes in this order (``omega``,
        ``b``, ``R``, ``eta``, ``alpha``, ``beta``, ``F0`` or an element: ``k2``,
        ``M[1,2]``, ``F[2]``, ...; :func:`impactcont.model.parameters.model_parameter`
        says which apply). Default ``("omega", "b")``.
    grid : mapping, optional
        ``{parameter: strictly increasing 1-D values}`` for both `parameters`.
    executor : None, "serial", "process", scheduler address, Executor or dask Client
        Where the tasks run (:mod:`impactcont.analysis.map_runner`):
        ``"tcp://host:8786"`` connects to that dask scheduler for the map; its workers
        need impactcont (the same version) and its dependencies installed.
    max_workers : int, optional
        Processes of the ``"process"`` pool.
    omega_block : int, optional
        Values of the first parameter per task; default: up to 32, fewer for long grids
        of the second. Tasks hold at most 131072 points (a long grid of the second
        parameter is split too; 8192 where the closed form is batched along one
        parameter only, 256 where it is evaluated per point) and fewer when the memory
        asks for it; results do not depend on the blocks or the executor.
    spectral_radius : bool
        Store ``spectral_radius`` and ``critical_multiplier`` (LAPACK eigenvalues of
        every G). Without them the map is about 3x faster: ``stable`` comes from the
        Schur-Cohn test of the characteristic polynomial of G either way.
    out : str or os.PathLike, optional
        Write the map to this NetCDF-4 file (chunked by task, compressed) as the
        blocks finish and return it opened lazily (dask-backed; ``close()`` closes
        the file). Without it, a map that does not fit in `memory_limit` goes to a
        temporary file the same way (with a warning naming it), removed when the
        returned dataset is closed (``close()`` or the end of a ``with`` block) or at
        the latest when the interpreter exits, and on SIGTERM; those of a process that
        was killed go with the next map (:mod:`impactcont.dataset.map_storage`). Needs
        the extra ``impactcont[dask]``.
    memory_limit : float
        Bytes the map may add to the memory of this process and its pool workers at
        its peak (default 1e9). A map is kept in memory when it fits with the tasks
        in flight (these take at most a quarter of the result: the peak is at most
        1.25 times the map); otherwise it goes to a file, with blocks small enough
        that the tasks in flight and the NetCDF writes stay within `memory_limit`.
        A map on disk takes at least about 33 MB (the NetCDF and HDF5 libraries about
        32 MB on their first use, and the smallest tasks in flight: 35 MB with two
        workers): a smaller limit is warned of (naming `memory_limit` and that floor)
        and exceeded. The interpreters of pool workers are not counted.
    progress : None, bool or callable
        A progress bar on stderr over the grid points (``None``: when stderr is a
        terminal, after 2 s; ``True``: always; ``False``: never) or a callable
        receiving a :class:`~impactcont.progress.Progress` record as each task
        finishes (:mod:`impactcont.progress`). A map longer than a minute logs a line
        a minute.
    **others
        With a motion: the options of :func:`impactcont.multi_impact_map`
        (``symmetric``, ``checks``, ``tol``, ``max_iter``, ``max_change``,
        ``max_attempts``, ``title``, ``rows_per_task``, ``evaluator``). With an oscillator
        none: a grid given as a keyword (``k2=[...]``) is refused, naming `parameters` and
        `grid`.

    Returns
    -------
    xarray.Dataset
        Of an oscillator: dims ``N``, the two parameters (``omega``, ``b`` by default)
        and ``root`` (``+1, -1``, eq. 15): ``exists``, ``n_physical``, ``n_stable`` on
        ``(N, p1, p2)``; ``delta``, ``impact_velocity``, ``gap_min``,
        ``spectral_radius``, ``critical_multiplier``, ``physical``, ``stable`` per root;
        ``amplitude_squared`` on ``(N, p1)`` when ``p2`` is ``b``, else on ``(N, p1,
        p2)``; the attribute ``parameters`` names a pair other than (omega, b)
        (:func:`impactcont.dataset.maps.map_variables`). Interrupted by Ctrl-C: what
        was computed, with ``computed`` on ``(N, p1, p2)`` and the attributes
        ``interrupted`` and ``points_computed`` (module docstring), in memory or in the
        file (`out`, or a temporary one) alike. Of a motion: the
        dataset of :func:`impactcont.multi_impact_map`.

    Raises
    ------
    ParameterError
        A bad grid, N, parameter, executor, block or memory limit (named in the
        message), an argument that does not apply to what is mapped (`N`, `omega`, `b`,
        `omega_block`, `spectral_radius` with a motion; a grid keyword with an
        oscillator), or a map for a file without dask installed.
    concurrent.futures.process.BrokenProcessPool
        A worker of the process pool died each time the same task ran alone (three
        times): the message names the task (N and the ranges of both parameters).
    """
    if not isinstance(osc, ImpactOscillator):
        return _motion_map(osc, N, omega, b, parameters, grid, executor=executor,
                           max_workers=max_workers, omega_block=omega_block,
                           spectral_radius=spectral_radius, out=out,
                           memory_limit=memory_limit, progress=progress, others=others)
    if others:
        raise ParameterError(
            f"stability_map takes the grid of a parameter as parameters=(p1, p2), grid={{p1: "
            f"..., p2: ...}}; got the keyword(s) {sorted(others)}")
    require_paper_stops(osc, "the N-1 stability map")  # before a pool or cluster is opened
    params, axes = map_plane(osc, parameters, grid, omega=omega, b=b)
    names = (params[0].name, params[1].name)
    w, bb = axes[names[0]], axes[names[1]]
    Ns = [N] if isinstance(N, (int, np.integer)) and not isinstance(N, bool) else list(N)
    if not Ns:
        raise ParameterError(f"N must be an integer >= 1 or a non-empty sequence of them; "
                             f"got {N!r}")
    Ns = [_check_N(k) for k in Ns]
    if len(set(Ns)) != len(Ns):
        raise ParameterError(f"N must not repeat values; got {N!r}")
    if not isinstance(spectral_radius, bool):
        raise ParameterError(f"spectral_radius must be True or False; got {spectral_radius!r}")
    max_workers, memory_limit = check_run_options(executor, max_workers, memory_limit)
    omega_block = positive_int("omega_block", omega_block, optional=True)
    shape = (len(Ns), w.size, bb.size)
    result = _result_bytes(shape, spectral_radius, names)
    remove_stale_maps(once=True)  # the temporary maps of killed processes (map_storage)
    temporary = False
    computed: np.ndarray | None = None
    job = _StabilityJob(osc, Ns, w, bb, spectral_radius, names)
    with interruptible("stability_map"), reporter(progress, "stability map",
                                                  total=math.prod(shape)) as rep:
        runner = MapRunner(job, executor, max_workers, rep)
        try:
            in_memory, points = _plan(result, float(memory_limit), runner.in_flight, out is None,
                                      w.size * bb.size)
            if not in_memory:
                _require_dask()
                _check_disk_floor(float(memory_limit), runner.in_flight)
            temporary = out is None and not in_memory
            if temporary:
                out = temporary_map_file()
                log.warning("the map takes %.3g GB, more than memory_limit = %.3g GB with its "
                            "tasks: it is written to %s (removed when the returned dataset is "
                            "closed) and returned lazily", result / 1e9, memory_limit / 1e9, out)
            if names != ("omega", "b"):
                points = min(points, _LINE_TASK if {"omega", "b"} & set(names) else _POINT_TASK)
            ob, bs = _block_shape(points, w.size, bb.size, omega_block)
            tasks = [(k, slice(i, min(i + ob, w.size)), slice(j, min(j + bs, bb.size)))
                     for k in range(len(Ns)) for i in range(0, w.size, ob)
                     for j in range(0, bb.size, bs)]
            options = {"executor": runner.name, "tasks": len(tasks), "omega_block": ob,
                       "b_block": bs, "spectral_radius": spectral_radius}
            start = time.perf_counter()
            if in_memory:
                ds, computed = _map_in_memory(runner, osc, Ns, w, bb, tasks, options, names)
            else:
                path, computed = _map_to_file(runner, osc, Ns, w, bb, tasks, options, out,
                                              (ob, bs), names)
        except BaseException:  # a failure, or a second Ctrl-C
            abandon(runner, out if temporary else None)
            raise
        runner.close(kill=computed is not None)
    elapsed = time.perf_counter() - start
    if in_memory and computed is not None:
        _mark_interrupted(ds, computed, names)
    elif computed is not None:
        log.warning("the interrupted map is kept in %s (interrupted = 1, the variable "
                    "'computed')", out)
    else:
        log.info("map of %d x %d x %d points %s in %.2f s (%d tasks, executor %s)", *shape,
                 "computed" if in_memory else f"written to {out}", elapsed, len(tasks),
                 runner.name)
    if in_memory:
        options["elapsed_seconds"] = round(elapsed, 3)
        ds.attrs["options"] = json.dumps(options, sort_keys=True)
        return ds
    # opened once the workers are gone: a worker forked while the file was being written
    # holds its HDF5 lock until it exits
    return open_temporary_map(path) if temporary else open_lazy(path)


def _given(value: Any) -> bool:
    """Whether an optional grid argument (default ``()``) was given."""
    return not (isinstance(value, tuple) and value == ())


def map_plane(osc: ImpactOscillator, parameters: Any, grid: Any, *, omega: Any = (), b: Any = ()
           ) -> tuple[tuple[ModelParameter, ModelParameter], dict[str, np.ndarray]]:
    """The two parameters of any map and their grids, checked once for every map.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator mapped (of the motion, for a family's map).
    parameters : (str, str) or None
        The two parameters in grid order; None: ``("omega", "b")`` from `omega` and `b`
        (the N-1 map of an oscillator only).
    grid : mapping or None
        ``{parameter: strictly increasing 1-D values}`` for both.
    omega, b : array_like, optional
        The (omega, b) grids without `parameters`.

    Returns
    -------
    params : (ModelParameter, ModelParameter)
        The parameters as objects of `osc`.
    axes : dict
        ``{name: grid}`` of both, checked: finite and strictly increasing, omega > 0, every
        value of a parameter other than omega and b one the oscillator takes.

    Raises
    ------
    ParameterError
        Naming the argument, the value and what is allowed.
    """
    if parameters is None:
        if grid is not None:
            raise ParameterError(f"grid needs parameters=(p1, p2), the order of its axes; got "
                                 f"grid={grid!r} without parameters")
        parameters, grid = ("omega", "b"), {"omega": omega, "b": b}
        label = {"omega": "omega", "b": "b"}
    else:
        for name, value in (("omega", omega), ("b", b)):
            if _given(value):
                raise ParameterError(f"{name}: with parameters={parameters!r} give the grid of "
                                     f"every parameter in grid=; got {name}={value!r} as well")
        label = None
    if isinstance(parameters, str) or not isinstance(parameters, Sequence) or len(
            parameters) != 2:
        raise ParameterError(f"parameters must be two parameter names, e.g. ('k2', 'b'); "
                             f"got {parameters!r}")
    params = (model_parameter(osc, parameters[0], "parameters"),
              model_parameter(osc, parameters[1], "parameters"))
    if params[0].name == params[1].name:
        raise ParameterError(f"parameters must be two different parameters; got "
                             f"{parameters!r}")
    if not isinstance(grid, Mapping) or set(grid) != set(parameters):
        raise ParameterError(f"grid must map each of the parameters {list(parameters)} to a "
                             f"1-D array of values; got {grid!r}")
    names = (params[0].name, params[1].name)
    label = label or {name: f"grid[{name!r}]" for name in names}
    return params, _axes(osc, params, {name: grid[name] for name in names}, label)


def _axes(osc: ImpactOscillator, params: tuple[ModelParameter, ModelParameter],
          grid: dict[str, Any], label: dict[str, str]) -> dict[str, np.ndarray]:
    """The grids of the two parameters (the keys of `grid`, in order), checked: strictly
    increasing, omega > 0, every value one the oscillator takes; `label` names each in
    messages."""
    axes = {name: _grid(label[name], values) for name, values in grid.items()}
    if "omega" in axes and np.any(axes["omega"] <= 0):
        raise ParameterError(f"{label['omega']} must be > 0; got {grid['omega']!r}")
    for param in params:
        name = param.name
        if name in ("omega", "b"):
            continue
        bad = [float(v) for v in axes[name] if not param.admits(osc, float(v))]
        if bad:
            raise ParameterError(f"{label[name]}: the oscillator cannot take {name} = {bad[0]!r} "
                                 f"({len(bad)} of the values; {param.info.long_name})")
    return axes


def _motion_map(start: Any, N: Any, omega: Any, b: Any, parameters: Any, grid: Any, *,
                others: dict[str, Any], **options: Any) -> xr.Dataset:
    """:func:`stability_map` of a motion: the map of its family (:func:`multi_impact_map`),
    the parameters and grid given as keywords or in the places of N and omega."""
    if not isinstance(start, (MultiImpactOrbit, PeriodicOrbit)):
        raise ParameterError(f"osc must be an ImpactOscillator, or a motion whose family is "
                             f"mapped (a MultiImpactOrbit of multi_impact_orbit or special_orbit, "
                             f"a PeriodicOrbit of periodic_orbits); got {type(start).__name__}")
    # stability_map(motion, (p1, p2), {p1: ..., p2: ...}) as multi_impact_map takes them
    if parameters is None and not isinstance(N, (int, np.integer)) and N is not _ALL_N \
            and isinstance(N, Sequence) and len(N) == 2 and all(isinstance(x, str) for x in N):
        parameters, N = N, _ALL_N
    if grid is None and isinstance(omega, Mapping):
        grid, omega = omega, ()
    for name, value, unset in (("N", N, N is _ALL_N), ("omega", omega, not _given(omega)),
                               ("b", b, not _given(b))):
        if not unset:
            raise ParameterError(f"{name}: a map of a motion's family takes parameters=(p1, "
                                 f"p2) and grid={{p1: ..., p2: ...}}, and its N from the motion; "
                                 f"got {name}={value!r}")
    for name, default in (("omega_block", None), ("spectral_radius", True)):
        if options[name] is not default:
            raise ParameterError(f"{name}: a map of a motion's family does not take it (the map "
                                 f"of an oscillator's N-1 motions does); got "
                                 f"{name}={options[name]!r}")
    unknown = sorted(set(others) - set(_MOTION_OPTIONS))
    if unknown:
        raise ParameterError(f"stability_map of a motion takes the options {list(_MOTION_OPTIONS)}"
                             f" of multi_impact_map; got {unknown}")
    if grid is None:
        raise ParameterError("grid: a map of a motion's family needs grid={p1: ..., p2: ...} "
                             "for its parameters")
    return multi_impact_map(start, ("omega", "b") if parameters is None else parameters, grid,
                            executor=options["executor"], max_workers=options["max_workers"],
                            memory_limit=options["memory_limit"],
                            progress=options["progress"], out=options["out"], **others)


@blas_limited
def multi_impact_map(start: MultiImpactOrbit | PeriodicOrbit,
                     parameters: Sequence[str] = ("omega", "b"),
                     grid: Mapping[str, Any] | None = None, *, symmetric: bool | None = None,
                     checks: bool = True, tol: float = 1e-11, max_iter: int = 12,
                     max_change: float = 0.5, max_attempts: int = 4,
                     title: str | None = None, executor: Any = None,
                     max_workers: int | None = None, rows_per_task: int | None = None,
                     memory_limit: float = 1e9, progress: ProgressOption = None,
                     out: str | os.PathLike | None = None,
                     evaluator: str | None = None) -> xr.Dataset:
    """Stability map of the motion family of `start` over a grid of two parameters.

    :func:`stability_map` of a motion under the name it had when only N-p motions had
    it: the same map, the same checks (this module), the same sweep
    (:func:`impactcont.analysis.family_maps.family_map`).

    Any system of the shooting path: stops on any mass or between two masses, stops on
    several coordinates (``Stops(extra=...)``: each impact's section ``n_k . x = c_k``
    solved for its own stop's mass, every flight checked against every stop), free masses
    and a constant force ``F_static``; each point is the motion
    :func:`impactcont.multi_impact_orbit` finds there. A motion with sticking phases (a
    lowercase letter in its pattern: a plastic impact held on its stop until the release)
    is followed through the branch problem of its pattern
    (:class:`~impactcont.problems.multi_impact_branch.MultiImpactBranchProblem`), past
    the ends of its branches (a stick time through 0, release grazing, the sticking
    onset), where its points are found and not physical with their reason
    (``docs/multi_maps.md``).

    Every grid point is solved by Newton from a neighbour that was solved, starting
    at the grid point nearest the start (reached from it by Newton in a few steps):
    natural-parameter continuation over the grid, breadth first, with a secant
    predictor through two solved points in line. A point whose Newton fails (or
    converges farther than `max_change` from its predictor) is "not found" and seeds
    no other point. The map is **one family followed from its seed**, not every
    motion that exists: motions reached only around a fold, other motions of the
    same pattern (an asymmetric pair born at a pitchfork, the other member of a
    saddle-node pair) and parts of the family cut off from the seed are not in it,
    and a grid line crossing a fold may continue on the other member of the pair
    (``docs/multi_maps.md``).

    Parameters
    ----------
    start : MultiImpactOrbit or PeriodicOrbit
        A motion of the family: :func:`impactcont.multi_impact_orbit` (from a
        simulation), :func:`impactcont.special_orbit` (a branch point), or an N-1
        motion of :func:`impactcont.periodic_orbits` (mapped by the closed form, or
        solved as a 1-impact motion: `evaluator`).
        Its oscillator is the map's; its values of the two parameters place the seed.
    parameters : (str, str)
        Two different continuable parameters of the oscillator, the grid's axes in this
        order: ``omega``, ``b``, ``R``, ``eta``, ``alpha``, ``beta``, ``F0``, ``b_low``,
        ``R_low``, ``gap`` or an element (``k2``, ``m1``, ``c1``, ``M[1,2]``, ``K[1,2]``,
        ``C[1,2]``, ``F[2]``; :func:`impactcont.model.parameters.model_parameter` says
        which apply).
    grid : mapping
        ``{parameter: strictly increasing 1-D values}`` for both parameters.
    symmetric : bool, optional
        Solve a symmetric motion of a symmetric two-sided system on its half system
        (regular through the symmetry-breaking pitchforks; refused for a motion with
        sticking phases, always solved on the full system). ``None`` (default): when
        the start is symmetric and both parameters keep the system symmetric
        (:attr:`~impactcont.model.parameters.ModelParameter.keeps_symmetry`: not ``b``,
        ``R``, ``b_low`` or ``R_low`` unless ``Stops(mirror=True)``), as
        :func:`impactcont.multi_impact_continuation` decides.
    checks : bool
        Search every flight for contact with a stop (eq. 16). Without it ``gap_min``
        is NaN, ``contact_checked`` False and no point is physical (as where the search
        cannot represent a flight: a constant force pushing a free mode).
    tol : float
        Newton tolerance (residual and last update, relative to ``max(1, |u|)``).
    max_iter : int
        Newton iterations per attempt.
    max_change : float
        Largest max-norm distance between a solution and its predictor: a solution
        farther away is taken for another motion and refused.
    max_attempts : int
        Newton attempts per grid point at most (one from each solved neighbour).
    title : str, optional
    executor : None, "serial", "process", scheduler address, Executor or dask Client
        Where the tasks run, as for :func:`impactcont.stability_map`: in this process,
        a process pool made here (``max_workers`` processes), a dask cluster
        (``"tcp://host:8786"``, or a ``dask.distributed.Client``: as many tasks at once
        as its workers have threads) or any :class:`concurrent.futures.Executor`.
    max_workers : int, optional
        Processes of the ``"process"`` pool.
    rows_per_task : int, optional
        Rows of ``parameters[0]`` per task (default: enough for 65536 grid points; 2048
        for a motion with sticking phases, swept in Python at some ms a point). A
        map of one task is the one sweep from the seed. A larger one first sweeps the
        seed's column of ``parameters[1]`` (the spine), then each band of rows from its
        spine point nearest the seed, as tasks: a band is followed within itself, so a
        part of the family that the band reaches only through another band is not
        found (and a band whose spine point was not found has none). The map depends
        on `rows_per_task`, never on the executor.
    memory_limit : float
        Bytes the map and its tasks in flight may take (default 1e9): fewer tasks are
        submitted at once when theirs would not fit, and a map that does not fit goes to a
        temporary file (with a warning naming it), returned lazily and removed when
        closed, as :func:`impactcont.stability_map` does
        (:mod:`impactcont.dataset.map_storage`).
    progress : None, bool or callable
        A progress bar over the grid points, a callback, a log line a minute (as for
        :func:`impactcont.stability_map`).
    out : str or os.PathLike, optional
        Write the map to this NetCDF-4 file (chunked by task, compressed) band by band
        as the tasks finish, and return it opened lazily (needs ``impactcont[dask]``).
    evaluator : None, "closed_form" or "shooting"
        How the family is evaluated. ``None`` (default): by the closed form where `start`
        is an N-1 motion of :func:`impactcont.periodic_orbits` (a
        :class:`~impactcont.orbit.periodic.PeriodicOrbit`), `checks` is True and the map
        fits in `memory_limit` (notes; with `out` it is made in memory, then written),
        else by shooting.
        ``"closed_form"`` refuses, saying why, where the closed form does not apply;
        ``"shooting"`` always shoots (a PeriodicOrbit as the 1-impact motion it is).

    Returns
    -------
    xarray.Dataset
        Dims ``(parameters[0], parameters[1])`` with their grids as coordinates,
        ``impact`` and ``component``: ``found``, ``newton_iterations``, ``stable``,
        ``physical``, ``contact_checked``, ``spectral_radius``, ``critical_multiplier``, ``delta``,
        ``gap_min``, ``impact_velocity_k``, ``flight_time_k``, ``state_k`` and, in a
        system that admits symmetric motions of the pattern, ``asymmetry``
        (:mod:`impactcont.dataset.maps`); for a motion with sticking phases also
        ``stick_time_k``, ``release_phase_k``, ``pressing_min_k``,
        ``landing_pressing_k``, ``stick_time_min``, ``pressing_min`` and ``reason`` (why
        a found point is not physical, as flag bits:
        :data:`~impactcont.dataset.maps.MAP_REASONS`). Values are NaN where not found.
        Round-trips through :func:`impactcont.save` / :func:`impactcont.load`.

    Raises
    ------
    TypeError, ParameterError
        A bad start, parameter, grid, option, or a grid value where the oscillator
        cannot be built (named in the message); a map for a file without dask.
    NoPeriodicMotionError
        The start cannot be followed to its nearest grid point.

    Notes
    -----
    Ctrl-C during the map (a first one) stops it between tasks and returns what was
    computed: the points of the tasks not finished are not found (NaN), False in the
    variable ``computed``, the attribute ``interrupted`` is 1, and a WARNING says how
    many points were done; a map written to a file is kept the same way, the file whole
    (written under a temporary name, then renamed). A second Ctrl-C abandons the map
    (KeyboardInterrupt), a file being written removed.

    The family of an N-1 motion of the closed form is mapped by the closed form (eq.
    12-16, 25): the closed form's map of every root on the grid (:func:`stability_map`
    of the oscillator), kept for the start's root of eq. (15) on the grid points
    connected to the seed through grid neighbours where that root exists (the points a
    sweep from the seed reaches). Each point is then exact (no Newton:
    ``newton_iterations`` 0), the root never changes at a fold (the shooting sweep may
    continue on the other member of the pair there) and no shooting kernel is
    compiled; the options of the sweep (`tol`, `max_iter`, `max_change`,
    `max_attempts`, `rows_per_task`) are checked and not used. A map for a file
    (`out`) is made in memory (it fits in `memory_limit`, or shooting maps it) and
    written at once. The attribute ``options`` names the evaluator (``"evaluator":
    "closed_form"``) and an INFO record says which ran (and, for an N-1 motion mapped
    by shooting, why).
    """
    if not isinstance(start, (MultiImpactOrbit, PeriodicOrbit)):
        as_multi_impact_orbit(start)  # refuses it, naming what is taken
    if evaluator not in _EVALUATORS:
        raise ParameterError(f"evaluator must be one of {list(_EVALUATORS)} (None: the closed "
                             f"form where it applies); got {evaluator!r}")
    params, axes = map_plane(start.oscillator, parameters, grid)
    max_workers, memory_limit = check_run_options(executor, max_workers, memory_limit)
    check_sweep_options(checks=checks, tol=tol, max_iter=max_iter, max_change=max_change,
                        max_attempts=max_attempts)
    if isinstance(start, PeriodicOrbit):
        _decide_symmetric(start, params, symmetric)  # an N-1 motion: refuses symmetric=True
    reason = ("evaluator='shooting'" if evaluator == "shooting" else
              _not_closed_form(start, params, axes, checks, memory_limit))
    if not reason:
        if out is not None:
            _require_dask()  # the file is returned opened lazily
        ds, reason = _closed_form_family(start, params, axes, title=title, executor=executor,
                                         max_workers=max_workers, memory_limit=memory_limit,
                                         progress=progress)
        if ds is not None:
            # a map for a file: made in memory (it fits), then written at once, atomically
            return ds if out is None else open_lazy(save(ds, out))
    if evaluator == "closed_form":
        raise ParameterError(f"evaluator='closed_form': the family cannot be mapped by the "
                             f"closed form here: {reason}; give evaluator=None or 'shooting'")
    if isinstance(start, PeriodicOrbit):
        log.info("the family of the N-1 motion is mapped by shooting: %s", reason)
    orbit = as_multi_impact_orbit(start)
    return family_map(orbit, params, axes, symmetric=symmetric, checks=checks, tol=tol,
                      max_iter=max_iter, max_change=max_change, max_attempts=max_attempts,
                      title=title, executor=executor, max_workers=max_workers,
                      rows_per_task=rows_per_task, memory_limit=memory_limit,
                      progress=progress, out=out)


#: How :func:`multi_impact_map` evaluates a family: None, the closed form where it applies.
_EVALUATORS = (None, "closed_form", "shooting")


def _not_closed_form(start: Any, params: tuple[ModelParameter, ModelParameter],
                     axes: dict[str, np.ndarray], checks: Any, memory_limit: float) -> str:
    """Why the family of `start` is not mapped by the closed form ("" where it is)."""
    if not isinstance(start, PeriodicOrbit):
        return (f"the start is a {type(start).__name__}, not an N-1 motion of the closed "
                "form (periodic_orbits)")
    if not checks:
        return "checks=False (the closed form always searches every flight for contact)"
    names = (params[0].name, params[1].name)
    shape = (axes[names[0]].size, axes[names[1]].size)
    need = (_result_bytes((1, *shape), True, names)
            + math.prod(shape) * _family_point_bytes(start.oscillator.n))
    if need > memory_limit:
        return (f"the map and the closed form's map of every root take {need / 1e9:.3g} GB, "
                f"more than memory_limit = {memory_limit / 1e9:.3g} GB")
    return ""


def _family_point_bytes(n: int) -> int:
    """Bytes per grid point of a map of one N-1 family (:data:`MULTI_MAP_VARIABLES`, p = 1)."""
    return 1 + 4 + 8 + 1 + 1 + 1 + 8 + 16 + 8 + 8 + 8 + 8 * 2 * n


def _closed_form_family(start: PeriodicOrbit, params: tuple[ModelParameter, ModelParameter],
                        axes: dict[str, np.ndarray], *, title: str | None, executor: Any,
                        max_workers: int | None, memory_limit: float,
                        progress: ProgressOption) -> tuple[xr.Dataset | None, str]:
    """The map of the family of an N-1 motion by the closed form: its root of eq. (15).

    The closed form's map of every root (:func:`stability_map` of the oscillator, same
    executor, progress and memory bound) restricted to the root of `start` (the sign in
    front of the square root of eq. 15, which changes only at the fold ``c^2 + s^2 =
    b^2``, where the root ends), on the grid points connected to the seed (the point
    nearest the start) through grid neighbours where it exists: the points the shooting
    sweep reaches from its seed through solved neighbours
    (:func:`~impactcont.analysis.family_maps.family_map`), each exact rather than
    Newton's. The states after the impact come from :func:`impactcont.orbit.periodic.
    impact_states`, ``newton_iterations`` is 0 at every point found (no Newton).

    Returns
    -------
    ds : xarray.Dataset or None
        The map (the ``multi_impact_map`` layout, ``options`` naming ``"evaluator":
        "closed_form"``), or None where the start's root does not exist at the seed.
    reason : str
        Why it is None ("" otherwise).
    """
    from scipy import ndimage

    osc, N = start.oscillator, start.N
    names = (params[0].name, params[1].name)
    start_values = {param.name: param.value(osc) for param in params}
    s0, s1 = _nearest(axes, names, (start_values[names[0]], start_values[names[1]]))
    at_seed = {names[0]: float(axes[names[0]][s0]), names[1]: float(axes[names[1]][s1])}
    seed_osc = osc
    for param in params:
        seed_osc = param.at(seed_osc, at_seed[param.name])
    if start.root not in [o.root for o in periodic_orbits(seed_osc, N)]:
        return None, (f"the root {start.root:+d} of eq. (15) does not exist at the grid point "
                      f"nearest the start, {at_seed}")
    t0 = time.perf_counter()
    every = stability_map(osc, [N], parameters=names, grid=axes, executor=executor,
                          max_workers=max_workers, memory_limit=memory_limit,
                          progress=progress)
    computed = every["computed"].values[0] if "computed" in every.variables else None
    root = 0 if start.root == 1 else 1
    one = {key: every[key].values[0, ..., root]
           for key in ("delta", "impact_velocity", "gap_min", "spectral_radius",
                       "critical_multiplier", "physical", "stable")}
    options = {"evaluator": "closed_form", **json.loads(every.attrs["options"])}
    every.close()  # a map that went to a temporary file: read, then removed
    exists = ~np.isnan(one["delta"])
    if computed is not None:
        exists &= computed
    labels, _ = ndimage.label(exists)  # grid neighbours: the sweep's four
    found = labels == labels[s0, s1] if labels[s0, s1] else np.zeros_like(exists)
    values = _family_values(osc, N, params, axes, found, one)
    options["elapsed_seconds"] = round(time.perf_counter() - t0, 4)
    seed = {**at_seed, "index": [int(s0), int(s1)], "start": start_values}
    ds = multi_impact_map_dataset(oscillator=osc, N=N, pattern=start.pattern,
                                  parameters=names, grid=axes, values=values, symmetric=False,
                                  seed=seed, options=options, title=title)
    if computed is not None:
        mark_computed(ds, computed, names)
    log.info("N=%d family of root %+d of eq. (15) over %s x %s by the closed form: %d of %d "
             "points found in %.3g s", N, start.root, names[0], names[1],
             int(found.sum()), found.size, options["elapsed_seconds"])
    return ds, ""


def _family_values(osc: ImpactOscillator, N: int,
                   params: tuple[ModelParameter, ModelParameter], axes: dict[str, np.ndarray],
                   found: np.ndarray, one: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The variables of a family map (:data:`~impactcont.dataset.maps.MULTI_MAP_VARIABLES`)
    from the closed form's values `one` of one root on the grid, kept where `found`."""
    names = (params[0].name, params[1].name)
    shape = found.shape

    def kept(a: np.ndarray, fill: Any) -> np.ndarray:
        return np.where(found, a, fill)

    if "omega" in names:
        w = axes["omega"][:, None] if names[0] == "omega" else axes["omega"][None, :]
    else:
        w = np.array([[osc.omega]])
    period = np.broadcast_to(2.0 * np.pi * N / w, shape)
    gap = kept(one["gap_min"], np.nan)
    return {"found": found, "newton_iterations": kept(0, -1).astype(np.int32),
            "delta": kept(one["delta"], np.nan), "stable": found & one["stable"],
            "physical": found & one["physical"], "contact_checked": found & ~np.isnan(gap),
            "spectral_radius": kept(one["spectral_radius"], np.nan),
            "critical_multiplier": kept(one["critical_multiplier"], complex(np.nan, np.nan)),
            "gap_min": gap, "impact_velocity_k": kept(one["impact_velocity"], np.nan)[..., None],
            "flight_time_k": kept(period, np.nan)[..., None],
            "state_k": _family_states(osc, N, params, axes, found, one)[:, :, None, :]}


def _family_states(osc: ImpactOscillator, N: int,
                   params: tuple[ModelParameter, ModelParameter], axes: dict[str, np.ndarray],
                   found: np.ndarray, one: dict[str, np.ndarray]) -> np.ndarray:
    """The state after the impact at every point found (NaN elsewhere), shape (n0, n1, 2n):
    :func:`~impactcont.orbit.periodic.impact_states` once per oscillator, i.e. per value of
    the parameter other than ``b`` (``b`` enters the closed form through the phase only,
    eq. 14-15), or per point where neither is ``b``."""
    names = (params[0].name, params[1].name)
    states = np.full((*found.shape, 2 * osc.n), np.nan)
    if "b" in names:
        k = 1 - names.index("b")  # the axis of the parameter that changes the oscillator
        lines = [(m, (m, slice(None)) if k == 0 else (slice(None), m))
                 for m in range(found.shape[k])]
    else:
        lines = [((i, j), (i, j)) for i, j in zip(*np.nonzero(found), strict=True)]
    for m, where in lines:
        hit = found[where]
        if not np.any(hit):
            continue
        if "b" in names:
            o = params[k].at(osc, float(axes[names[k]][m]))
        else:
            o = params[1].at(params[0].at(osc, float(axes[names[0]][m[0]])),
                             float(axes[names[1]][m[1]]))
        delta = np.atleast_1d(one["delta"][where])[np.atleast_1d(hit)]
        sigma = np.atleast_1d(one["impact_velocity"][where])[np.atleast_1d(hit)]
        block = states[where]  # a view: a line of the grid, or one point's state
        if block.ndim == 1:
            block[:] = impact_states(o, N, delta, sigma)[0]
        else:
            block[hit] = impact_states(o, N, delta, sigma)
    return states


@blas_limited
def _plane_task(osc_json: str, N: int, names: tuple[str, str], first: np.ndarray,
                second: np.ndarray, spectral_radius: bool = True) -> dict[str, np.ndarray]:
    """One task of a map over a pair other than (omega, b): every N-1 motion for one N on a
    block ``first x second`` of the grid (picklable, top level).

    The closed form is batched along ``omega`` or ``b`` where one of the two parameters is
    one of them (for each value of the other), else evaluated at each point on the
    oscillator with both parameters replaced.
    """
    osc = _oscillator(osc_json)
    params = [model_parameter(osc, name, "parameters") for name in names]
    values = (first, second)
    shape = (first.size, second.size)
    keys = ("exists", *_ROOT_FIELDS)
    out: dict[str, np.ndarray] = {}
    amplitude = np.empty(shape)

    def put(where: tuple[Any, ...], res: dict[str, np.ndarray], size: int) -> None:
        for key in keys:
            a = res[key].reshape((size, *res[key].shape[2:]))
            if key not in out:
                out[key] = np.empty((*shape, *a.shape[1:]), a.dtype)
            out[key][where] = a if any(isinstance(k, slice) for k in where) else a[0]
        r2 = res["amplitude_squared"]  # on omega
        amplitude[where] = r2[0] if r2.size == 1 else r2

    batched = [k for k, name in enumerate(names) if name in ("omega", "b")]
    with compiled_interrupts():
        if len(batched) == 2:  # (b, omega): the (omega, b) map's evaluation, transposed
            res = batched_orbits(osc, N, second, first, spectral_radius=spectral_radius)
            for key in keys:
                out[key] = np.ascontiguousarray(np.swapaxes(res[key], 0, 1))
            amplitude[:] = res["amplitude_squared"][None, :]
        elif batched:
            j = batched[0]
            i = 1 - j
            for m, x in enumerate(values[i]):
                o = params[i].at(osc, float(x))
                w = values[j] if names[j] == "omega" else np.array([o.omega])
                bb = values[j] if names[j] == "b" else np.array([o.b])
                res = batched_orbits(o, N, w, bb, spectral_radius=spectral_radius)
                put((m, slice(None)) if i == 0 else (slice(None), m), res, values[j].size)
        else:
            for m, x in enumerate(first):
                row = params[0].at(osc, float(x))
                for n, y in enumerate(second):
                    o = params[1].at(row, float(y))
                    res = batched_orbits(o, N, np.array([o.omega]), np.array([o.b]),
                                         spectral_radius=spectral_radius)
                    put((m, n), res, 1)
    out["amplitude_squared"] = amplitude[:, 0] if names[1] == "b" else amplitude
    return out


def _fields(spectral_radius: bool) -> tuple[str, ...]:
    return tuple(k for k in _ROOT_FIELDS
                 if spectral_radius or k not in ("spectral_radius", "critical_multiplier"))


def _result_bytes(shape: tuple[int, int, int], spectral_radius: bool,
                  names: tuple[str, str] = ("omega", "b")) -> int:
    """Bytes of the map's variables on the grid ``shape`` (N, first, second parameter)."""
    per_point = 1 + 2 * 8  # exists, n_physical, n_stable
    per_point += 2 * sum(np.dtype(_DTYPES.get(k, float)).itemsize
                         for k in _fields(spectral_radius))
    if names[1] != "b":
        per_point += 8  # amplitude_squared on the whole grid
    return per_point * math.prod(shape) + 8 * (shape[0] * shape[1] + sum(shape) + 2)



def _block_shape(points: int, nw: int, nb: int, omega_block: int | None) -> tuple[int, int]:
    """omega and b values per task for tasks of at most `points` points (at least 1 x 1)."""
    if omega_block is not None:
        return omega_block, max(1, min(nb, points // omega_block))
    if nb >= points:
        return 1, points
    return max(1, min(_OMEGA_BLOCK, nw, points // nb)), nb




class _StabilityJob(MapJob):
    """The tasks of :func:`stability_map`: ``(N index, omega slice, b slice)``."""

    what = "stability_map"

    def __init__(self, osc: ImpactOscillator, Ns: list[int], w: np.ndarray, bb: np.ndarray,
                 spectral_radius: bool, names: tuple[str, str] = ("omega", "b")) -> None:
        self._text, self._Ns, self._w, self._bb = osc.to_json(), Ns, w, bb
        self._spectral_radius, self._names = spectral_radius, names

    def call(self, task: tuple[int, slice, slice]) -> tuple[Any, tuple[Any, ...]]:
        k, osl, bsl = task
        # the tasks looked up now: tests replace them
        if self._names == ("omega", "b"):
            return _map_task, (self._text, self._Ns[k], self._w[osl], self._bb[bsl],
                               self._spectral_radius)
        return _plane_task, (self._text, self._Ns[k], self._names, self._w[osl],
                             self._bb[bsl], self._spectral_radius)

    def points(self, task: tuple[int, slice, slice]) -> int:
        _, osl, bsl = task
        return (osl.stop - osl.start) * (bsl.stop - bsl.start)

    def describe(self, task: tuple[int, slice, slice]) -> str:
        """`task` in words: its N and the ranges of the two parameters."""
        k, osl, bsl = task
        w, bb = self._w[osl], self._bb[bsl]
        first, second = self._names
        return (f"N = {self._Ns[k]}, {first}[{osl.start}:{osl.stop}] in [{w[0]:.6g}, "
                f"{w[-1]:.6g}], {second}[{bsl.start}:{bsl.stop}] in [{bb[0]:.6g}, "
                f"{bb[-1]:.6g}]")




def _layout(shape: tuple[int, int, int], fields: tuple[str, ...], names: tuple[str, str]
            ) -> dict[str, tuple[tuple[int, ...], Any]]:
    """Shape and dtype of every variable of a map on the grid ``shape`` (N, first, second
    parameter; :func:`~impactcont.dataset.maps.map_variables`)."""
    amplitude = shape[:2] if names[1] == "b" else shape
    return {"amplitude_squared": (amplitude, float), "exists": (shape, bool),
            "n_physical": (shape, np.int64), "n_stable": (shape, np.int64),
            **{k: ((*shape, 2), _DTYPES.get(k, float)) for k in fields}}


def _blocks(runner: MapRunner, tasks: list[tuple[int, slice, slice]], fields: tuple[str, ...],
            names: tuple[str, str]
            ) -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
    """Each task's block of the map as it finishes: its region of (N, first, second
    parameter) and values."""
    for (k, osl, bsl), res in runner.results(tasks):
        values = {key: res[key] for key in ("exists", *fields)}
        values["n_physical"] = res["physical"].sum(axis=-1)
        values["n_stable"] = (res["physical"] & res["stable"]).sum(axis=-1)
        if bsl.start == 0 or names[1] != "b":  # on (N, omega): the same for every block of b
            values["amplitude_squared"] = res["amplitude_squared"]
        del res
        yield {"N": k, names[0]: osl, names[1]: bsl}, values


def _map_in_memory(runner: MapRunner, osc: ImpactOscillator, Ns: list[int], w: np.ndarray,
                   bb: np.ndarray, tasks: list[tuple[int, slice, slice]],
                   options: dict[str, Any], names: tuple[str, str]
                   ) -> tuple[xr.Dataset, np.ndarray | None]:
    """The map in memory: its arrays allocated once, each task's block copied in as it
    finishes (no list of results, no assembled copies).

    Returns the map and, if it was interrupted by a first Ctrl-C, the (N, first, second
    parameter) points computed (else None); a second Ctrl-C raises KeyboardInterrupt.
    """
    fields = _fields(options["spectral_radius"])
    layout = _layout((len(Ns), w.size, bb.size), fields, names)
    # placeholders of no memory: fill_blocks makes the arrays, which the blocks fill
    placeholders = {k: np.broadcast_to(np.zeros((), dtype), shape)
                    for k, (shape, dtype) in layout.items()}
    ds = map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=placeholders,
                     options=options, parameters=names)
    computed = np.zeros((len(Ns), w.size, bb.size), dtype=bool)
    interrupted = fill_blocks(runner, ds, _blocks(runner, tasks, fields, names), computed,
                              ("N", *names))
    return ds, (computed if interrupted else None)


def _mark_interrupted(ds: xr.Dataset, computed: np.ndarray, names: tuple[str, str]) -> None:
    """Mark an interrupted map: the points not computed NaN (False, 0 where no NaN
    exists), the variable ``computed`` and the attribute ``interrupted`` (issue 31)."""
    for var in ds.data_vars.values():
        if var.dims == ("N", names[0]):
            where = ~computed[:, :, 0]  # the block of b = 0 writes amplitude_squared
        else:
            where = np.broadcast_to((~computed).reshape(computed.shape + (1,) * (var.ndim - 3)),
                                    var.shape)
        var.data[where] = np.nan if var.dtype.kind in "fc" else 0
    mark_computed(ds, computed, ("N", *names))


def _map_to_file(runner: MapRunner, osc: ImpactOscillator, Ns: list[int], w: np.ndarray,
                 bb: np.ndarray, tasks: list[tuple[int, slice, slice]],
                 options: dict[str, Any], out: Any, block: tuple[int, int],
                 names: tuple[str, str]) -> tuple[Path, np.ndarray | None]:
    """The map written to a chunked, compressed NetCDF-4 file, each task's block (one chunk
    of every variable) as it finishes; nothing else of the map is held in memory.

    Returns the file and, if a first Ctrl-C interrupted the map, the (N, first, second
    parameter) points computed (else None): the file is then whole, as the in-memory map
    is marked (:func:`_mark_interrupted`): the blocks of the tasks not finished written
    False and 0 (floating-point ones read as their fill value NaN), and the variable
    ``computed`` and the attributes ``interrupted`` and
    ``points_computed`` added before the file is moved onto `out`. A second Ctrl-C
    abandons the map (KeyboardInterrupt), its file removed.
    """
    import dask.array as da

    fields = _fields(options["spectral_radius"])
    layout = _layout((len(Ns), w.size, bb.size), fields, names)
    # placeholders of the right shape, never computed: the blocks are the values
    placeholders = {k: da.empty(shape, dtype=dtype, chunks=-1)
                    for k, (shape, dtype) in layout.items()}
    ds = map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=placeholders,
                     options=options, parameters=names)
    chunk = {"N": 1, names[0]: block[0], names[1]: block[1], "root": 2}
    encoding = {key: {"zlib": True, "complevel": 1,
                      "chunksizes": tuple(min(chunk[d], ds.sizes[d]) for d in ds[key].dims)}
                for key in ds.data_vars}
    computed = np.zeros((len(Ns), w.size, bb.size), dtype=bool)
    interrupted: list[bool] = []

    def not_computed() -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
        for k, osl, bsl in tasks:  # the tasks not finished
            if not computed[k, osl, bsl].any():
                yield _not_computed((k, osl, bsl), layout, names)

    blocks = written_blocks(runner, _blocks(runner, tasks, fields, names), computed,
                            ("N", *names), not_computed, interrupted)

    def finish() -> xr.Dataset | None:
        if not interrupted:
            return None
        marked = xr.Dataset(attrs={})
        mark_computed(marked, computed, ("N", *names))
        return marked

    path = save_blocks(ds, out, blocks, encoding=encoding, finish=finish)
    return path, (computed if interrupted else None)


def _not_computed(task: tuple[int, slice, slice], layout: dict[str, tuple[tuple[int, ...], Any]],
                  names: tuple[str, str]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The block of a task not computed (an interrupted map): False or 0, as
    :func:`_mark_interrupted` marks it in memory. Floating-point variables are left out:
    unwritten, they read as their fill value NaN (and a Ctrl-C on a large map finishes
    its file about 5 times sooner)."""
    k, osl, bsl = task
    region = {"N": k, names[0]: osl, names[1]: bsl}
    sizes = {names[0]: osl.stop - osl.start, names[1]: bsl.stop - bsl.start}
    values = {}
    for key, (shape, dtype) in layout.items():
        if np.dtype(dtype).kind in "fc":
            continue
        dims = (names[0], names[1], "root")[:len(shape) - 1]
        values[key] = np.zeros(tuple(sizes.get(d, 2) for d in dims), dtype=dtype)
    return region, values

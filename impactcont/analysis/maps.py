"""Maps of the (omega, b) plane: existence, physicality and stability of N-1 motions on a grid.

``stability_map(osc, N=[1, 2, 3, 4], omega=..., b=...)`` evaluates every root of
eq. (15) at every grid point with the batched closed form of
:mod:`impactcont.orbit.batched` (stacked numpy over ``omega x b x root``; ``S``
of eq. 13 once per ``omega``) and returns an :class:`xarray.Dataset` with dims
``(N, omega, b, root)`` (schema: :mod:`impactcont.dataset.curves`).

The work is split into tasks of ``(N, block of omega, block of b)`` (at most
131072 points) run through a standard :class:`concurrent.futures.Executor`:

- ``executor=None`` or ``"serial"``: in this process;
- ``"process"``: a :class:`~concurrent.futures.ProcessPoolExecutor` created and
  shut down here (``max_workers`` processes);
- the address of a dask scheduler (``"tcp://host:8786"``): a
  ``dask.distributed.Client`` connected here and closed with the map (optional extra
  ``impactcont[dask]``);
- any :class:`~concurrent.futures.Executor` instance (owned by the caller), e.g.
  ``dask.distributed.Client(...).get_executor()``; a ``dask.distributed.Client``
  itself is accepted too. On a dask cluster as many tasks run at once as its workers
  have threads (read again as workers join), not as this machine has processors.

Every map runs its tasks through :class:`~impactcont.analysis.map_runner.MapRunner` (the
tasks of a :class:`~impactcont.analysis.map_runner.MapJob`): :func:`impactcont.multi_impact_map`
too, with the same executors, progress and memory bound.

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
of how many points were done. A second Ctrl-C aborts (KeyboardInterrupt). A map written
to a file (``out=``, or larger than `memory_limit`) is abandoned at the first Ctrl-C, its
file removed.
"""

from __future__ import annotations

import functools
import json
import logging
import math
import os
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.map_runner import (
    MapJob,
    MapRunner,
    _check_disk_floor,
    _plan,
    _require_dask,
    compiled_interrupts,
    keep_interrupted,
)
from impactcont.dataset.curves import map_dataset
from impactcont.dataset.io import open_lazy, save_blocks
from impactcont.dataset.map_storage import (
    open_temporary_map,
    remove_stale_maps,
    remove_temporary_map,
    temporary_map_file,
)
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.batched import batched_orbits
from impactcont.orbit.periodic import _check_N
from impactcont.progress import ProgressOption, interruptible, reporter
from impactcont.threads import blas_limited

__all__ = ["stability_map"]

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


@blas_limited
def stability_map(osc: ImpactOscillator, N: int | Sequence[int] = (1, 2, 3, 4),
                  omega: Sequence[float] | np.ndarray = (),
                  b: Sequence[float] | np.ndarray = (), *, executor: Any = None,
                  max_workers: int | None = None, omega_block: int | None = None,
                  spectral_radius: bool = True, out: str | os.PathLike | None = None,
                  memory_limit: float = 1e9, progress: ProgressOption = None,
                  **others: Any) -> xr.Dataset:
    """Existence, physicality and stability of every N-1 motion on an (N, omega, b) grid.

    The map is of the (omega, b) plane by design: the batched closed form builds ``S``
    of eq. (13) once per ``omega`` and solves eq. (15) for every ``b`` at once (``b``
    only shifts its right-hand side). A map over another pair of parameters (``R``,
    ``F0``, ``b_low``, an element such as ``k2`` or ``M[1,2]``) is
    :func:`impactcont.multi_impact_map` of a motion of the family; another keyword
    (``k2=[...]``) is refused and says so.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator; its own ``omega`` and ``b`` are ignored.
    N : int or sequence of int
        Forcing periods per impact.
    omega, b : 1-D array_like
        Strictly increasing grids of the forcing frequency (``> 0``) and the gap.
    executor : None, "serial", "process", scheduler address, Executor or dask Client
        Where the tasks run (see the module docstring): ``"tcp://host:8786"`` connects
        to that dask scheduler for the map; its workers need impactcont (the same
        version) and its dependencies installed.
    max_workers : int, optional
        Processes of the ``"process"`` pool.
    omega_block : int, optional
        Omega values per task; default: up to 32, fewer for long b grids. Tasks hold
        at most 131072 points (a long b grid is split too) and fewer when the memory
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
        None accepted: a grid of another parameter is refused (ParameterError naming
        it and :func:`impactcont.multi_impact_map`).

    Returns
    -------
    xarray.Dataset
        Dims ``N``, ``omega``, ``b``, ``root`` (``+1, -1``, eq. 15): ``exists``,
        ``n_physical``, ``n_stable`` on ``(N, omega, b)``; ``delta``,
        ``impact_velocity``, ``gap_min``, ``spectral_radius``,
        ``critical_multiplier``, ``physical``, ``stable`` per root;
        ``amplitude_squared`` on ``(N, omega)``. Interrupted by Ctrl-C (a map in
        memory): what was computed, with ``computed`` on ``(N, omega, b)`` and the
        attributes ``interrupted`` and ``points_computed`` (module docstring).

    Raises
    ------
    ParameterError
        A bad grid, N, executor, block or memory limit (named in the message), a grid
        of a parameter other than omega and b, or a map for a file without dask
        installed.
    concurrent.futures.process.BrokenProcessPool
        A worker of the process pool died each time the same task ran alone (three
        times): the message names the task (N and the omega and b ranges).
    """
    if others:
        raise ParameterError(
            f"stability_map maps the (omega, b) plane only (the batched closed form of eq. 13-15 "
            f"takes a grid of omega and b); got {sorted(others)}: for a map over other "
            f"parameters use impactcont.multi_impact_map(start, (p1, p2), grid={{p1: ..., "
            f"p2: ...}}) from a motion of the family")
    if not isinstance(osc, ImpactOscillator):
        raise ParameterError(f"osc must be an ImpactOscillator; got {osc!r}")
    Ns = [N] if isinstance(N, (int, np.integer)) and not isinstance(N, bool) else list(N)
    if not Ns:
        raise ParameterError(f"N must be an integer >= 1 or a non-empty sequence of them; "
                             f"got {N!r}")
    Ns = [_check_N(k) for k in Ns]
    if len(set(Ns)) != len(Ns):
        raise ParameterError(f"N must not repeat values; got {N!r}")
    w = _grid("omega", omega)
    if np.any(w <= 0):
        raise ParameterError(f"omega must be > 0; got {omega!r}")
    bb = _grid("b", b)
    if not isinstance(spectral_radius, bool):
        raise ParameterError(f"spectral_radius must be True or False; got {spectral_radius!r}")
    if max_workers is not None and (isinstance(max_workers, bool)
                                    or not isinstance(max_workers, int) or max_workers < 1):
        raise ParameterError(f"max_workers must be an integer >= 1 or None; got {max_workers!r}")
    if omega_block is not None and (isinstance(omega_block, bool)
                                    or not isinstance(omega_block, int) or omega_block < 1):
        raise ParameterError(f"omega_block must be an integer >= 1 or None; got {omega_block!r}")
    if not (isinstance(memory_limit, (int, float)) and not isinstance(memory_limit, bool)
            and memory_limit > 0):
        raise ParameterError(f"memory_limit must be a number of bytes > 0; got {memory_limit!r}")
    shape = (len(Ns), w.size, bb.size)
    result = _result_bytes(shape, spectral_radius)
    remove_stale_maps(once=True)  # the temporary maps of killed processes (map_storage)
    temporary = False
    computed: np.ndarray | None = None
    job = _StabilityJob(osc, Ns, w, bb, spectral_radius)
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
            ob, bs = _block_shape(points, w.size, bb.size, omega_block)
            tasks = [(k, slice(i, min(i + ob, w.size)), slice(j, min(j + bs, bb.size)))
                     for k in range(len(Ns)) for i in range(0, w.size, ob)
                     for j in range(0, bb.size, bs)]
            options = {"executor": runner.name, "tasks": len(tasks), "omega_block": ob,
                       "b_block": bs, "spectral_radius": spectral_radius}
            start = time.perf_counter()
            if in_memory:
                ds, computed = _map_in_memory(runner, osc, Ns, w, bb, tasks, options)
            else:
                path = _map_to_file(runner, osc, Ns, w, bb, tasks, options, out, (ob, bs))
        except BaseException:
            runner.close(kill=True)  # Ctrl-C or a failure: no worker left computing
            if temporary and out is not None:
                remove_temporary_map(out)
            raise
        runner.close(kill=computed is not None)
    elapsed = time.perf_counter() - start
    if in_memory and computed is not None:
        _mark_interrupted(ds, computed)
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


def _fields(spectral_radius: bool) -> tuple[str, ...]:
    return tuple(k for k in _ROOT_FIELDS
                 if spectral_radius or k not in ("spectral_radius", "critical_multiplier"))


def _result_bytes(shape: tuple[int, int, int], spectral_radius: bool) -> int:
    """Bytes of the map's variables on the grid ``shape`` (N, omega, b)."""
    per_point = 1 + 2 * 8  # exists, n_physical, n_stable
    per_point += 2 * sum(np.dtype(_DTYPES.get(k, float)).itemsize
                         for k in _fields(spectral_radius))
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
                 spectral_radius: bool) -> None:
        self._text, self._Ns, self._w, self._bb = osc.to_json(), Ns, w, bb
        self._spectral_radius = spectral_radius

    def call(self, task: tuple[int, slice, slice]) -> tuple[Any, tuple[Any, ...]]:
        k, osl, bsl = task
        # _map_task looked up now: tests replace it
        return _map_task, (self._text, self._Ns[k], self._w[osl], self._bb[bsl],
                           self._spectral_radius)

    def points(self, task: tuple[int, slice, slice]) -> int:
        _, osl, bsl = task
        return (osl.stop - osl.start) * (bsl.stop - bsl.start)

    def describe(self, task: tuple[int, slice, slice]) -> str:
        """`task` in words: its N and its omega and b ranges."""
        k, osl, bsl = task
        w, bb = self._w[osl], self._bb[bsl]
        return (f"N = {self._Ns[k]}, omega[{osl.start}:{osl.stop}] in [{w[0]:.6g}, "
                f"{w[-1]:.6g}], b[{bsl.start}:{bsl.stop}] in [{bb[0]:.6g}, {bb[-1]:.6g}]")




def _layout(shape: tuple[int, int, int], fields: tuple[str, ...]
            ) -> dict[str, tuple[tuple[int, ...], Any]]:
    """Shape and dtype of every variable of a map on the grid ``shape`` (N, omega, b)."""
    return {"amplitude_squared": (shape[:2], float), "exists": (shape, bool),
            "n_physical": (shape, np.int64), "n_stable": (shape, np.int64),
            **{k: ((*shape, 2), _DTYPES.get(k, float)) for k in fields}}


def _blocks(runner: MapRunner, tasks: list[tuple[int, slice, slice]], fields: tuple[str, ...]
            ) -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
    """Each task's block of the map as it finishes: its region of (N, omega, b) and values."""
    for (k, osl, bsl), res in runner.results(tasks):
        values = {key: res[key] for key in ("exists", *fields)}
        values["n_physical"] = res["physical"].sum(axis=-1)
        values["n_stable"] = (res["physical"] & res["stable"]).sum(axis=-1)
        if bsl.start == 0:  # the same for every block of b
            values["amplitude_squared"] = res["amplitude_squared"]
        del res
        yield {"N": k, "omega": osl, "b": bsl}, values


def _map_in_memory(runner: MapRunner, osc: ImpactOscillator, Ns: list[int], w: np.ndarray,
                   bb: np.ndarray, tasks: list[tuple[int, slice, slice]],
                   options: dict[str, Any]) -> tuple[xr.Dataset, np.ndarray | None]:
    """The map in memory: its arrays allocated once, each task's block copied in as it
    finishes (no list of results, no assembled copies).

    Returns the map and, if it was interrupted by a first Ctrl-C, the (N, omega, b)
    points computed (else None); a second Ctrl-C raises KeyboardInterrupt.
    """
    layout = _layout((len(Ns), w.size, bb.size), _fields(options["spectral_radius"]))
    # placeholders of no memory: map_dataset makes the arrays, which the blocks fill
    placeholders = {k: np.broadcast_to(np.zeros((), dtype), shape)
                    for k, (shape, dtype) in layout.items()}
    ds = map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=placeholders,
                     options=options)
    arrays = {k: _writable(ds.variables[k]) for k in layout}
    computed = np.zeros((len(Ns), w.size, bb.size), dtype=bool)
    try:
        for region, values in _blocks(runner, tasks, _fields(options["spectral_radius"])):
            for key, block in values.items():
                arrays[key][tuple(region[d] for d in ds[key].dims if d in region)] = block
            computed[region["N"], region["omega"], region["b"]] = True
    except KeyboardInterrupt:
        if not keep_interrupted(runner, computed.size):
            raise
        return ds, computed
    return ds, None


def _mark_interrupted(ds: xr.Dataset, computed: np.ndarray) -> None:
    """Mark an interrupted map: the points not computed NaN (False, 0 where no NaN
    exists), the variable ``computed`` and the attribute ``interrupted`` (issue 31)."""
    for var in ds.data_vars.values():
        if var.dims == ("N", "omega"):
            where = ~computed[:, :, 0]  # the block of b = 0 writes amplitude_squared
        else:
            where = np.broadcast_to((~computed).reshape(computed.shape + (1,) * (var.ndim - 3)),
                                    var.shape)
        var.data[where] = np.nan if var.dtype.kind in "fc" else 0
    ds["computed"] = (("N", "omega", "b"), computed,
                      {"long_name": "point computed before the map was interrupted",
                       "units": "1"})
    ds.attrs["interrupted"] = 1
    ds.attrs["points_computed"] = int(np.count_nonzero(computed))


def _writable(var: xr.Variable) -> np.ndarray:
    """The numpy array of `var`, which the map fills in place (a new one if it cannot be)."""
    data = var.data
    if not (isinstance(data, np.ndarray) and data.flags.writeable and data.flags.owndata):
        data = np.empty(var.shape, var.dtype)
        var.data = data
    return data


def _map_to_file(runner: MapRunner, osc: ImpactOscillator, Ns: list[int], w: np.ndarray,
                 bb: np.ndarray, tasks: list[tuple[int, slice, slice]],
                 options: dict[str, Any], out: Any, block: tuple[int, int]) -> Path:
    """The map written to a chunked, compressed NetCDF-4 file, each task's block (one chunk
    of every variable) as it finishes; nothing else of the map is held in memory."""
    import dask.array as da

    layout = _layout((len(Ns), w.size, bb.size), _fields(options["spectral_radius"]))
    # placeholders of the right shape, never computed: the blocks are the values
    placeholders = {k: da.empty(shape, dtype=dtype, chunks=-1)
                    for k, (shape, dtype) in layout.items()}
    ds = map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=placeholders,
                     options=options)
    chunk = {"N": 1, "omega": block[0], "b": block[1], "root": 2}
    encoding = {key: {"zlib": True, "complevel": 1,
                      "chunksizes": tuple(min(chunk[d], ds.sizes[d]) for d in ds[key].dims)}
                for key in ds.data_vars}
    return save_blocks(ds, out, _blocks(runner, tasks, _fields(options["spectral_radius"])),
                       encoding=encoding)

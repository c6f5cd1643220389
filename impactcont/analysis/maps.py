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

Every map runs its tasks through :class:`MapRunner` (the tasks of a :class:`MapJob`):
:func:`impactcont.multi_impact_map` too, with the same executors, progress and memory
bound.

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

import collections
import concurrent.futures as cf
import contextlib
import functools
import json
import logging
import math
import os
import signal
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.pool import dead_worker, kill_pool, process_pool
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
from impactcont.progress import (
    ProgressOption,
    Reporter,
    interruptible,
    reporter,
    take_interrupt,
)
from impactcont.threads import blas_limited

__all__ = ["stability_map"]

log = logging.getLogger(__name__)

_OMEGA_BLOCK = 32  # omega values per task at most
_MAX_TASK_POINTS = 1 << 17  # omega x b points per task at most (a long b grid is split)
_MIN_TASK_POINTS = 1 << 10  # ... and at least (fewer: the per-task costs show)
# Memory of a task in flight per omega x b point: its working arrays (measured 145-148 B,
# both roots, with or without the spectral radius) and its result (101 B) while it is
# copied into the map or sent back from a worker process.
_TASK_BYTES = 256
# The same for a map written to disk: the chunks of its block encoded for the file
# (booleans as int8, complex as two floats) and compressed as well.
_DISK_TASK_BYTES = 512
# What writing to disk takes whatever the blocks (the NetCDF and HDF5 libraries: measured
# 15-25 MB, 35 MB on their first use in a process).
_DISK_FIXED_BYTES = 32_000_000
_TASK_SHARE = 0.25  # the tasks in flight of a map in memory: at most this share of it
_POLL_SECONDS = 0.25  # how often the tasks in flight and the pool's workers are looked at
_CLUSTER_SECONDS = 2.0  # how often the threads of a dask cluster's workers are read again
_STUCK_SECONDS = 2.0  # a pool with a dead worker not marked broken after this is stuck
_RETRIES = 2  # times a task that broke the pool while running alone is run again
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


@contextlib.contextmanager
def compiled_interrupts() -> Iterator[None]:
    """Ctrl-C during a compiled call raised as the KeyboardInterrupt it is.

    numba reports a KeyboardInterrupt pending in a compiled call as a SystemError
    ("returned a result with an exception set", chained once per nested call).
    """
    try:
        yield
    except SystemError as exc:
        cause: BaseException | None = exc
        while isinstance(cause, SystemError):
            cause = cause.__cause__
        if isinstance(cause, KeyboardInterrupt):
            raise KeyboardInterrupt from None
        raise


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


def _task_points(budget: float, in_flight: int, per_point: int, grid: int) -> int:
    """omega x b points per task: as many as `budget` allows for `in_flight` tasks, within
    [_MIN_TASK_POINTS, _MAX_TASK_POINTS] (and no more than one N's grid)."""
    points = int(budget // (in_flight * per_point)) if budget > 0 else 0
    return max(1, min(grid, _MAX_TASK_POINTS, max(_MIN_TASK_POINTS, points)))


def _plan(result: int, memory_limit: float, in_flight: int, may_stay: bool,
          grid: int) -> tuple[bool, int]:
    """Whether the map stays in memory, and the points per task.

    `in_flight` tasks are in memory at once (running in this process or a worker, or
    their results waiting to be copied in or written). In memory, the peak is the map
    plus these, which take at most `_TASK_SHARE` of it: the map stays if that fits in
    `memory_limit`. On disk, these and the NetCDF library's own memory fit in it.
    """
    if may_stay:
        budget = min(max(_TASK_SHARE * result, in_flight * _MIN_TASK_POINTS * _TASK_BYTES),
                     memory_limit - result)
        points = _task_points(budget, in_flight, _TASK_BYTES, grid)
        if result + in_flight * points * _TASK_BYTES <= memory_limit:
            return True, points
    return False, _task_points(memory_limit - _DISK_FIXED_BYTES, in_flight, _DISK_TASK_BYTES,
                               grid)


def _disk_floor(in_flight: int) -> float:
    """The least `memory_limit` a map written to disk keeps to: the NetCDF and HDF5
    libraries' own memory and `in_flight` tasks of the smallest size."""
    return _DISK_FIXED_BYTES + in_flight * _MIN_TASK_POINTS * _DISK_TASK_BYTES


def _check_disk_floor(memory_limit: float, in_flight: int) -> None:
    """Warn when a map written to disk cannot keep to `memory_limit` (issue 28: a limit
    below about 35 MB was exceeded without a word)."""
    floor = _disk_floor(in_flight)
    if memory_limit < floor:
        log.warning("memory_limit = %.4g bytes is below %.4g bytes (%.3g MB), the least a map "
                    "written to disk takes here (the NetCDF and HDF5 libraries about %.0f MB, "
                    "and tasks in flight: %d of at least %d points): the map will take more "
                    "than memory_limit, up to about %.3g MB", memory_limit, floor, floor / 1e6,
                    _DISK_FIXED_BYTES / 1e6, in_flight, _MIN_TASK_POINTS, floor / 1e6)


def _block_shape(points: int, nw: int, nb: int, omega_block: int | None) -> tuple[int, int]:
    """omega and b values per task for tasks of at most `points` points (at least 1 x 1)."""
    if omega_block is not None:
        return omega_block, max(1, min(nb, points // omega_block))
    if nb >= points:
        return 1, points
    return max(1, min(_OMEGA_BLOCK, nw, points // nb)), nb


def _require_dask() -> None:
    try:
        import dask  # noqa: F401
    except ImportError:
        raise ParameterError("a map written to disk (out=..., or larger than memory_limit) "
                             "needs dask: pip install 'impactcont[dask]'") from None


class MapJob:
    """The tasks of one map, as :class:`MapRunner` runs them (a base for every map).

    A task is any value the job knows; the job says which picklable top-level function
    computes it and with what arguments (:meth:`call`), how many grid points it covers
    (:meth:`points`, for the progress) and what it is in words (:meth:`describe`, for
    the errors).
    """

    #: The map's function, in messages.
    what = "map"

    def call(self, task: Any) -> tuple[Any, tuple[Any, ...]]:
        """The function computing `task` and its arguments."""
        raise NotImplementedError

    def points(self, task: Any) -> int:
        """Grid points of `task`."""
        raise NotImplementedError

    def describe(self, task: Any) -> str:
        """`task` in words."""
        return repr(task)


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


@contextlib.contextmanager
def _taking_interrupts(runner: MapRunner) -> Iterator[Any]:
    """Ctrl-C (SIGINT) taken between the tasks of a map, not inside one; a second aborts.

    A KeyboardInterrupt raised inside a compiled kernel (numba's helpers check for
    signals) can leave it in an undefined state: the process crashed with SIGSEGV
    instead of stopping. While the tasks run (in this thread, or on an executor while
    this thread waits for them), a first SIGINT only marks the interrupt, and the
    yielded ``check()`` raises it between tasks (and at the end, and at least every
    ``_POLL_SECONDS`` while an executor computes): the map then keeps what it has
    computed. A second SIGINT before that raises KeyboardInterrupt at once, with
    ``runner.aborted`` set: the map is abandoned. Outside the main thread, or with a
    handler other than Python's default installed, nothing is changed.
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield lambda: None
        return
    pending: list[int] = []

    def check() -> None:
        if pending:
            pending.clear()
            raise KeyboardInterrupt

    def take(signum: int, frame: Any) -> None:
        if pending:  # the second Ctrl-C: the user does not want to wait
            runner.aborted = True
            signal.signal(signal.SIGINT, previous)
            raise KeyboardInterrupt
        pending.append(signum)

    previous = signal.signal(signal.SIGINT, take)
    try:
        yield check
        check()
    finally:
        signal.signal(signal.SIGINT, previous)


def _dask_client(executor: Any) -> Any:
    """The dask.distributed Client of `executor` (a Client or its executor), else None."""
    if type(executor).__name__ == "Client" and callable(getattr(executor, "get_executor", None)):
        return executor
    if type(executor).__name__ == "ClientExecutor":
        return getattr(executor, "_client", None)
    return None


def _scheduler_address(executor: Any) -> bool:
    """Whether `executor` is the address of a dask scheduler (``tcp://host:8786``)."""
    return isinstance(executor, str) and executor.startswith(SCHEDULER_PROTOCOLS)


#: The address prefixes of a dask scheduler accepted as ``executor=``.
SCHEDULER_PROTOCOLS = ("tcp://", "tls://", "ucx://", "ws://", "wss://", "inproc://")


def check_executor(executor: Any, argument: str = "executor") -> None:
    """Refuse an `executor` no map accepts (before any work), naming `argument`.

    Accepted: None, ``"serial"``, ``"process"``, the address of a dask scheduler
    (``"tcp://host:8786"``; any of :data:`SCHEDULER_PROTOCOLS`), a
    :class:`concurrent.futures.Executor` or a ``dask.distributed.Client``.

    Raises
    ------
    ParameterError
        Anything else.
    """
    if (executor is None or executor in ("serial", "process") or _scheduler_address(executor)
            or isinstance(executor, cf.Executor) or _dask_client(executor) is not None):
        return
    if isinstance(executor, str) and "://" not in executor and ":" in executor:
        hint = f" (a scheduler address needs its protocol: 'tcp://{executor}')"
    else:
        hint = ""
    raise ParameterError(f"{argument} must be None, 'serial', 'process', a dask scheduler "
                         f"address ('tcp://host:8786'), a concurrent.futures.Executor or a "
                         f"dask.distributed.Client; got {executor!r}{hint}")


def _executor(executor: Any, max_workers: int | None
              ) -> tuple[cf.Executor | None, list[Any], str, Any]:
    """The executor to use, what is owned here (to end with the map), its name for the
    record and its dask client (None if not on dask)."""
    check_executor(executor)
    if executor is None or executor == "serial":
        return None, [], "serial", None
    if executor == "process":
        pool = process_pool(max_workers)
        return pool, [pool], "process", None
    if _scheduler_address(executor):
        try:
            from dask.distributed import Client
        except ImportError:
            raise ParameterError(f"executor={executor!r} (a dask scheduler) needs dask."
                                 f"distributed: pip install 'impactcont[dask]'") from None
        try:
            client = Client(executor, timeout="10s", set_as_default=False)
        except OSError as exc:
            raise ParameterError(f"executor={executor!r}: no dask scheduler answers at this "
                                 f"address ({exc})") from None
        return client.get_executor(), [client], "dask.distributed", client
    client = _dask_client(executor)
    if client is not None and not isinstance(executor, cf.Executor):
        return client.get_executor(), [], "dask.distributed", client
    return executor, [], type(executor).__name__, client


def _dask_threads(client: Any) -> int:
    """Threads of the workers of a dask cluster now (0 if they cannot be read)."""
    try:
        return int(sum(client.nthreads().values()))
    except Exception:  # a closed client, a scheduler gone: the caller falls back
        return 0


class MapRunner:
    """The tasks of one map: in this process or on an executor, as they finish.

    A process pool that breaks (one of its worker processes died: killed, out of
    memory) is replaced by a new pool of the same size and the tasks that did not
    finish are run again there, one at a time: a task that breaks the pool while it
    runs alone is the one that kills its worker; it is run again up to ``_RETRIES``
    times (a worker may be killed from outside twice), then ends the map with
    :class:`~concurrent.futures.process.BrokenProcessPool` naming it.

    A worker killed while it sends its result leaves the pool's manager thread waiting
    forever for the rest (:mod:`impactcont.analysis.pool`): the futures are waited for
    ``_POLL_SECONDS`` at a time, and a pool with a dead worker that is still not marked
    broken ``_STUCK_SECONDS`` later is ended (:func:`~impactcont.analysis.pool.kill_pool`)
    and treated as broken. The pools made here end with the map: shut down when it ends,
    killed when it fails or is interrupted (Ctrl-C), and their workers end when this
    process is killed (:func:`~impactcont.analysis.pool.process_pool`).

    On a dask cluster the tasks running at once are the threads of its workers
    (``Client.nthreads``, read again every ``_CLUSTER_SECONDS``: workers that join are
    used), not the processors of this machine.

    Ctrl-C: the first stops the map between tasks (:func:`_taking_interrupts`): the
    results raise KeyboardInterrupt with ``aborted`` False, and the map keeps what it
    has; a second before that raises it with ``aborted`` True.
    """

    def __init__(self, job: MapJob, executor: Any, max_workers: int | None,
                 reporter: Reporter) -> None:
        self.job, self.reporter = job, reporter
        self.pool, self._owned, self.name, self._client = _executor(executor, max_workers)
        self._renewals = 0
        self._dead_since: dict[int, float] = {}  # id(pool): when a dead worker was seen
        self._killed: list[Any] = []  # pools ended as stuck
        self._threads = (0, -math.inf)  # a dask cluster's threads, and when they were read
        self.aborted = False  # a second Ctrl-C: the map is abandoned
        self.limit: int | None = None  # tasks submitted at once at most (memory), if set
        self.done = 0  # points of the tasks finished
        if isinstance(self.pool, cf.ProcessPoolExecutor):
            # the workers forked now, before the map's arrays exist: a worker forked later
            # would keep the pages it shares with this process as this process fills them
            # (copy on write), up to a second copy of the map
            try:
                self._start_workers()
            except BaseException:
                self.close(kill=True)
                raise

    def _start_workers(self) -> None:
        """Start the pool's workers with a task of nothing, watched as the map's tasks are
        (a pool that is broken or stuck already is replaced, up to 3 times)."""
        while True:
            pool = self.pool
            try:
                future = pool.submit(int)
                while True:
                    try:
                        future.result(timeout=_POLL_SECONDS)
                        return
                    except cf.TimeoutError:
                        self._end_stuck({future: (None, pool, False)})
            except cf.BrokenExecutor as exc:
                self._renew(pool, exc, None, 3)

    @property
    def workers(self) -> int:
        """Tasks running at once: 1 in this process, the pool's workers, the threads of a
        dask cluster's workers, else the processors of this machine."""
        if self.pool is None:
            return 1
        size = getattr(self.pool, "_max_workers", None)
        if size:
            return int(size)
        if self._client is not None:
            threads, when = self._threads
            now = time.monotonic()
            if now - when >= _CLUSTER_SECONDS:
                threads = _dask_threads(self._client)
                self._threads = threads, now
            if threads:
                return threads
        return int(os.cpu_count() or 1)

    @property
    def submitted(self) -> int:
        """Tasks submitted to the executor at once: ``2 x workers`` (each worker has the
        next at hand), at most :attr:`limit`."""
        most = 2 * self.workers
        return most if self.limit is None else max(1, min(most, self.limit))

    @property
    def in_flight(self) -> int:
        """Tasks in memory at once at most: submitted, and the result being copied into
        the map or written."""
        return 1 if self.pool is None else self.submitted + 1

    def describe(self, task: Any) -> str:
        """`task` in words (:meth:`MapJob.describe`)."""
        return self.job.describe(task)

    def _renew(self, pool: Any, exc: BaseException, task: Any, most: int) -> None:
        """Replace the broken `pool` (if it is still the one in use) by a new one; `most`
        pools in all (a pool that breaks before running anything must not loop)."""
        if pool is not self.pool:
            return
        if not isinstance(pool, cf.ProcessPoolExecutor) or self._renewals >= most:
            doing = ("starting its workers" if task is None
                     else f"computing the task {self.describe(task)}")
            raise type(exc)(f"{self.job.what}: the executor broke ({exc}) while {doing}"
                            ) from exc
        self._renewals += 1
        log.warning("a worker process of the pool died (%s: %s): the unfinished tasks are "
                    "run again in a new pool, one at a time", type(exc).__name__, exc)
        if any(p is pool for p in self._owned):
            kill_pool(pool)  # its workers may wait on a lock the dead one held
        self.pool = process_pool(getattr(pool, "_max_workers", None),
                                 getattr(pool, "_mp_context", None))
        self._owned.append(self.pool)

    def _end_stuck(self, running: dict[cf.Future, tuple[Any, Any, bool]]) -> None:
        """End each pool of `running` whose dead worker it has not noticed for
        ``_STUCK_SECONDS``, and fail its unfinished futures as broken."""
        now = time.monotonic()
        pools = {id(pool): pool for _, pool, _ in running.values()}
        for key, pool in pools.items():
            if not dead_worker(pool):
                self._dead_since.pop(key, None)
                continue
            if now - self._dead_since.setdefault(key, now) < _STUCK_SECONDS:
                continue
            log.warning("a worker process of the pool died and the pool did not notice it "
                        "in %.3g s (its manager thread is stuck on the dead worker's "
                        "half-sent result): the pool is ended", _STUCK_SECONDS)
            self._killed.append(pool)
            kill_pool(pool)
            broken = cf.process.BrokenProcessPool(
                "a worker process died while sending its result; the pool was ended")
            for future, (_, owner, _) in running.items():
                if owner is pool and not future.done():
                    with contextlib.suppress(cf.InvalidStateError):
                        future.set_exception(broken)

    def results(self, tasks: Sequence[Any]) -> Iterator[tuple[Any, Any]]:
        """Every task with its result, as they finish (``2 x workers`` submitted at once).

        Raises
        ------
        KeyboardInterrupt
            Ctrl-C (:func:`_taking_interrupts`): the tasks not finished are cancelled;
            ``aborted`` says whether it was the second.
        """
        with _taking_interrupts(self) as check:
            if self.pool is None:
                for task in tasks:
                    function, args = self.job.call(task)
                    result = function(*args)
                    yield task, result  # a task finished is kept, Ctrl-C or not
                    self._done(task)
                    check()
                return
            yield from self._pooled(tasks, check)

    def _pooled(self, tasks: Sequence[Any], check: Any) -> Iterator[tuple[Any, Any]]:
        """:meth:`results` on the executor; `check` raises a pending Ctrl-C."""
        most = len(tasks) * (1 + _RETRIES)
        waiting = collections.deque(range(len(tasks)))
        retry: collections.deque[int] = collections.deque()
        failures: collections.Counter[int] = collections.Counter()
        running: dict[cf.Future, tuple[int, Any, bool]] = {}
        try:
            while waiting or retry or running:
                # after a break, the unfinished tasks one by one: a task that breaks the
                # new pool is then the one that kills its worker
                while (retry and not running) or (not retry and waiting
                                                  and len(running) < self.submitted):
                    alone = bool(retry)
                    index = retry.popleft() if alone else waiting.popleft()
                    pool = self.pool
                    function, args = self.job.call(tasks[index])
                    try:
                        running[pool.submit(function, *args)] = index, pool, alone
                    except cf.BrokenExecutor as exc:  # broken by a task that ran before
                        (retry if alone else waiting).appendleft(index)
                        self._renew(pool, exc, tasks[index], most)
                done, _ = cf.wait(running, timeout=_POLL_SECONDS,
                                  return_when=cf.FIRST_COMPLETED)
                check()
                if not done:
                    self._end_stuck(running)
                    continue
                for future in done:
                    index, pool, alone = running.pop(future)
                    task = tasks[index]
                    try:
                        res = future.result()
                    except (cf.BrokenExecutor, cf.CancelledError) as exc:
                        if isinstance(exc, cf.CancelledError) and not any(
                                p is pool for p in self._killed):
                            raise
                        if alone:
                            failures[index] += 1
                            if failures[index] > _RETRIES:
                                raise cf.process.BrokenProcessPool(
                                    f"{self.job.what}: a worker process died computing the "
                                    f"task {self.describe(task)}, and again each of the "
                                    f"{_RETRIES} times the task was run again alone in a "
                                    f"new process pool ({exc})") from exc
                        self._renew(pool, exc, task, most)
                        retry.append(index)
                        continue
                    yield task, res
                    del res
                    self._done(task)
                    check()
        finally:
            for future in running:
                future.cancel()

    def _done(self, task: Any) -> None:
        """Count the points of a task whose results are in the map."""
        points = self.job.points(task)
        self.done += points
        self.reporter.advance(points)

    def close(self, kill: bool = False) -> None:
        """End the pools (and the dask client) created here: shut down, or with `kill`
        (the map failed or was interrupted) killed at once
        (:func:`~impactcont.analysis.pool.kill_pool`). With `kill`, the caller's process
        pool too if a worker of it died unnoticed: it is broken, and its stuck manager
        thread would hold the interpreter's exit."""
        owned, self._owned = self._owned, []
        for pool in owned:
            if not isinstance(pool, cf.Executor):  # a dask client made here
                with contextlib.suppress(Exception):
                    pool.close()
            elif kill or any(p is pool for p in self._killed):
                kill_pool(pool)
            else:
                pool.shutdown(cancel_futures=True)
        if kill and not any(p is self.pool for p in owned) and dead_worker(self.pool):
            log.warning("a worker process of the executor given died unnoticed: the pool "
                        "is ended")
            kill_pool(self.pool)


def keep_interrupted(runner: MapRunner, total: int) -> bool:
    """In an ``except KeyboardInterrupt`` of a map: whether the map keeps what it computed.

    True for the first Ctrl-C of the call (:func:`~impactcont.progress.take_interrupt`,
    which logs a WARNING of how many of the `total` points were done); False for a second
    (``runner.aborted``, or the enclosing call interrupted already): the caller re-raises.
    """
    if runner.aborted:
        return False
    done = runner.done
    return take_interrupt("map", "%d of %d points computed (%.0f %%); the others are NaN, "
                          "not found, False in the variable 'computed'", done, total,
                          100.0 * done / total if total else 0.0)


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

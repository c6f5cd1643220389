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
- any :class:`~concurrent.futures.Executor` instance (owned by the caller), e.g.
  ``dask.distributed.Client(...).get_executor()``; a ``dask.distributed.Client``
  itself is accepted too (optional extra ``impactcont[dask]``).

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
from impactcont.progress import ProgressOption, Reporter, reporter
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
    try:
        out = batched_orbits(osc, N, omega, b, spectral_radius=spectral_radius)
    except SystemError as exc:
        # Ctrl-C during a compiled call: numba reports the pending KeyboardInterrupt as
        # "returned a result with an exception set" (chained once per nested call)
        cause: BaseException | None = exc
        while isinstance(cause, SystemError):
            cause = cause.__cause__
        if isinstance(cause, KeyboardInterrupt):
            raise KeyboardInterrupt from None
        raise
    return {k: out[k] for k in ("amplitude_squared", "exists", *_ROOT_FIELDS)}


@contextlib.contextmanager
def _interrupt_between_tasks() -> Iterator[Any]:
    """Ctrl-C (SIGINT) taken between the tasks of a serial map, not inside one.

    A KeyboardInterrupt raised inside a compiled kernel (numba's helpers check for
    signals) can leave it in an undefined state: the process crashed with SIGSEGV
    instead of stopping. While the tasks run in this (main) thread, SIGINT only marks
    the interrupt, and the yielded ``check()`` raises it between tasks (and at the
    end). A handler other than Python's default is left as it is.
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

    previous = signal.signal(signal.SIGINT, lambda signum, frame: pending.append(signum))
    try:
        yield check
        check()
    finally:
        signal.signal(signal.SIGINT, previous)


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


def _executor(executor: Any, max_workers: int | None) -> tuple[cf.Executor | None, bool, str]:
    """The executor to use, whether it is owned here, and its name for the record."""
    if executor is None or executor == "serial":
        return None, False, "serial"
    if executor == "process":
        return process_pool(max_workers), True, "process"
    if isinstance(executor, cf.Executor):
        return executor, False, type(executor).__name__
    get_executor = getattr(executor, "get_executor", None)  # a dask.distributed.Client
    if callable(get_executor) and type(executor).__name__ == "Client":
        return get_executor(), False, "dask.distributed"
    raise ParameterError(f"executor must be None, 'serial', 'process', a concurrent.futures."
                         f"Executor or a dask.distributed.Client; got {executor!r}")


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
    executor : None, "serial", "process", Executor or dask.distributed.Client
        Where the tasks run (see the module docstring).
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
        ``amplitude_squared`` on ``(N, omega)``.

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
    with reporter(progress, "stability map", total=math.prod(shape)) as rep:
        runner = _Runner(osc, Ns, w, bb, spectral_radius, executor, max_workers, rep)
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
                ds = _map_in_memory(runner, osc, Ns, w, bb, tasks, options)
            else:
                path = _map_to_file(runner, osc, Ns, w, bb, tasks, options, out, (ob, bs))
        except BaseException:
            runner.close(kill=True)  # Ctrl-C or a failure: no worker left computing
            if temporary and out is not None:
                remove_temporary_map(out)
            raise
        runner.close()
    elapsed = time.perf_counter() - start
    log.info("map of %d x %d x %d points %s in %.2f s (%d tasks, executor %s)", *shape,
             "computed" if in_memory else f"written to {out}", elapsed, len(tasks), runner.name)
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


class _Runner:
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
    """

    def __init__(self, osc: ImpactOscillator, Ns: list[int], w: np.ndarray, bb: np.ndarray,
                 spectral_radius: bool, executor: Any, max_workers: int | None,
                 reporter: Reporter) -> None:
        self.reporter = reporter
        self.pool, owned, self.name = _executor(executor, max_workers)
        self._owned = [self.pool] if owned else []
        self._text, self._Ns, self._w, self._bb = osc.to_json(), Ns, w, bb
        self._spectral_radius = spectral_radius
        self._renewals = 0
        self._dead_since: dict[int, float] = {}  # id(pool): when a dead worker was seen
        self._killed: list[Any] = []  # pools ended as stuck
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
        """Tasks running at once."""
        if self.pool is None:
            return 1
        return int(getattr(self.pool, "_max_workers", None) or os.cpu_count() or 1)

    @property
    def in_flight(self) -> int:
        """Tasks in memory at once at most: submitted (``2 x workers``), and the result
        being copied into the map or written."""
        return 1 if self.pool is None else 2 * self.workers + 1

    def _args(self, task: tuple[int, slice, slice]) -> tuple[Any, ...]:
        k, osl, bsl = task
        return self._text, self._Ns[k], self._w[osl], self._bb[bsl], self._spectral_radius

    def describe(self, task: tuple[int, slice, slice]) -> str:
        """`task` in words: its N and its omega and b ranges."""
        k, osl, bsl = task
        w, bb = self._w[osl], self._bb[bsl]
        return (f"N = {self._Ns[k]}, omega[{osl.start}:{osl.stop}] in [{w[0]:.6g}, "
                f"{w[-1]:.6g}], b[{bsl.start}:{bsl.stop}] in [{bb[0]:.6g}, {bb[-1]:.6g}]")

    def _renew(self, pool: Any, exc: BaseException, task: tuple[int, slice, slice] | None,
               most: int) -> None:
        """Replace the broken `pool` (if it is still the one in use) by a new one; `most`
        pools in all (a pool that breaks before running anything must not loop)."""
        if pool is not self.pool:
            return
        if not isinstance(pool, cf.ProcessPoolExecutor) or self._renewals >= most:
            doing = ("starting its workers" if task is None
                     else f"computing the task {self.describe(task)}")
            raise type(exc)(f"stability_map: the executor broke ({exc}) while {doing}"
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

    def results(self, tasks: list[tuple[int, slice, slice]]
                ) -> Iterator[tuple[tuple[int, slice, slice], dict[str, np.ndarray]]]:
        """Every task with its result, as they finish (``2 x workers`` submitted at once)."""
        if self.pool is None:
            with _interrupt_between_tasks() as check:
                for task in tasks:
                    result = _map_task(*self._args(task))
                    check()
                    yield task, result
                    self._done(task)
                    check()
            return
        most = len(tasks) * (1 + _RETRIES)
        waiting = collections.deque(tasks)
        retry: collections.deque[tuple[int, slice, slice]] = collections.deque()
        failures: collections.Counter[tuple[int, int, int]] = collections.Counter()
        running: dict[cf.Future, tuple[tuple[int, slice, slice], Any, bool]] = {}
        try:
            while waiting or retry or running:
                # after a break, the unfinished tasks one by one: a task that breaks the
                # new pool is then the one that kills its worker
                while (retry and not running) or (not retry and waiting
                                                  and len(running) < 2 * self.workers):
                    alone = bool(retry)
                    task = retry.popleft() if alone else waiting.popleft()
                    pool = self.pool
                    try:
                        running[pool.submit(_map_task, *self._args(task))] = task, pool, alone
                    except cf.BrokenExecutor as exc:  # broken by a task that ran before
                        (retry if alone else waiting).appendleft(task)
                        self._renew(pool, exc, task, most)
                done, _ = cf.wait(running, timeout=_POLL_SECONDS,
                                  return_when=cf.FIRST_COMPLETED)
                if not done:
                    self._end_stuck(running)
                    continue
                for future in done:
                    task, pool, alone = running.pop(future)
                    try:
                        res = future.result()
                    except (cf.BrokenExecutor, cf.CancelledError) as exc:
                        if isinstance(exc, cf.CancelledError) and not any(
                                p is pool for p in self._killed):
                            raise
                        key = (task[0], task[1].start, task[2].start)
                        if alone:
                            failures[key] += 1
                            if failures[key] > _RETRIES:
                                raise cf.process.BrokenProcessPool(
                                    f"stability_map: a worker process died computing the "
                                    f"task {self.describe(task)}, and again each of the "
                                    f"{_RETRIES} times the task was run again alone in a "
                                    f"new process pool ({exc})") from exc
                        self._renew(pool, exc, task, most)
                        retry.append(task)
                        continue
                    yield task, res
                    del res
                    self._done(task)
        finally:
            for future in running:
                future.cancel()

    def _done(self, task: tuple[int, slice, slice]) -> None:
        """Count the points of a task whose block is in the map."""
        _, osl, bsl = task
        self.reporter.advance((osl.stop - osl.start) * (bsl.stop - bsl.start))

    def close(self, kill: bool = False) -> None:
        """End the pools created here: shut down, or with `kill` (the map failed or was
        interrupted) killed at once (:func:`~impactcont.analysis.pool.kill_pool`). With
        `kill`, the caller's process pool too if a worker of it died unnoticed: it is
        broken, and its stuck manager thread would hold the interpreter's exit."""
        owned, self._owned = self._owned, []
        for pool in owned:
            if kill or any(p is pool for p in self._killed):
                kill_pool(pool)
            else:
                pool.shutdown(cancel_futures=True)
        if kill and not any(p is self.pool for p in owned) and dead_worker(self.pool):
            log.warning("a worker process of the executor given died unnoticed: the pool "
                        "is ended")
            kill_pool(self.pool)


def _layout(shape: tuple[int, int, int], fields: tuple[str, ...]
            ) -> dict[str, tuple[tuple[int, ...], Any]]:
    """Shape and dtype of every variable of a map on the grid ``shape`` (N, omega, b)."""
    return {"amplitude_squared": (shape[:2], float), "exists": (shape, bool),
            "n_physical": (shape, np.int64), "n_stable": (shape, np.int64),
            **{k: ((*shape, 2), _DTYPES.get(k, float)) for k in fields}}


def _blocks(runner: _Runner, tasks: list[tuple[int, slice, slice]], fields: tuple[str, ...]
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


def _map_in_memory(runner: _Runner, osc: ImpactOscillator, Ns: list[int], w: np.ndarray,
                   bb: np.ndarray, tasks: list[tuple[int, slice, slice]],
                   options: dict[str, Any]) -> xr.Dataset:
    """The map in memory: its arrays allocated once, each task's block copied in as it
    finishes (no list of results, no assembled copies)."""
    layout = _layout((len(Ns), w.size, bb.size), _fields(options["spectral_radius"]))
    # placeholders of no memory: map_dataset makes the arrays, which the blocks fill
    placeholders = {k: np.broadcast_to(np.zeros((), dtype), shape)
                    for k, (shape, dtype) in layout.items()}
    ds = map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=placeholders,
                     options=options)
    arrays = {k: _writable(ds.variables[k]) for k in layout}
    for region, values in _blocks(runner, tasks, _fields(options["spectral_radius"])):
        for key, block in values.items():
            arrays[key][tuple(region[d] for d in ds[key].dims if d in region)] = block
    return ds


def _writable(var: xr.Variable) -> np.ndarray:
    """The numpy array of `var`, which the map fills in place (a new one if it cannot be)."""
    data = var.data
    if not (isinstance(data, np.ndarray) and data.flags.writeable and data.flags.owndata):
        data = np.empty(var.shape, var.dtype)
        var.data = data
    return data


def _map_to_file(runner: _Runner, osc: ImpactOscillator, Ns: list[int], w: np.ndarray,
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

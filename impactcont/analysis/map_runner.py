"""The tasks of a map, run in this process or on an executor: every map's machinery.

:class:`MapRunner` runs the tasks of a :class:`MapJob` (a base each map derives its
tasks from: :func:`impactcont.stability_map`'s blocks of the closed form,
:func:`impactcont.multi_impact_map`'s bands of grid rows) through a standard
:class:`concurrent.futures.Executor`, with the same executors, progress, memory bound and
Ctrl-C for every map:

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

A process pool that breaks (a worker killed) is replaced and the unfinished tasks are
run again, one at a time (a task up to twice more), also when the worker died sending its
result and the pool did not notice (:mod:`impactcont.analysis.pool`).

Memory: :func:`_plan` decides whether a map of a given size stays in memory with its tasks
in flight or goes to a file, and how many grid points a task holds; :func:`_check_disk_floor`
warns of a `memory_limit` below what writing to disk takes.

Ctrl-C (issue 31): :func:`_taking_interrupts` takes the first between tasks (the map keeps
what it computed, :func:`keep_interrupted`, marked by :func:`mark_computed`), a second
aborts; :func:`compiled_interrupts` turns numba's report of a Ctrl-C in compiled code back
into a KeyboardInterrupt.

The options every map takes are checked here once (:func:`check_run_options`,
:func:`positive_int`, :func:`positive_number`).
"""

from __future__ import annotations

import collections
import concurrent.futures as cf
import contextlib
import logging
import math
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from impactcont.analysis.pool import dead_worker, kill_pool, manager_ended, process_pool
from impactcont.dataset.map_storage import remove_temporary_map
from impactcont.errors import ParameterError
from impactcont.progress import Reporter, take_interrupt
from impactcont.vocabulary import check_positive_integer

__all__ = [
    "SCHEDULER_PROTOCOLS",
    "MapJob",
    "MapRunner",
    "abandon",
    "check_executor",
    "check_run_options",
    "compiled_interrupts",
    "fill_blocks",
    "keep_interrupted",
    "mark_computed",
    "positive_int",
    "positive_number",
    "written_blocks",
]

log = logging.getLogger(__name__)

_MAX_TASK_POINTS = 1 << 17  # grid points per task at most (a long grid line is split)
_MIN_TASK_POINTS = 1 << 10  # ... and at least (fewer: the per-task costs show)
# Memory of a task in flight per grid point of the N-1 map: its working arrays (measured
# 145-148 B, both roots, with or without the spectral radius) and its result (101 B) while
# it is copied into the map or sent back from a worker process.
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
        except Exception as exc:  # no answer (OSError), or one that is not dask's protocol
            raise ParameterError(f"executor={executor!r}: no dask scheduler answers at this "
                                 f"address ({type(exc).__name__}: {exc})") from None
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
        ``_STUCK_SECONDS`` (or whose manager thread has ended: nothing would complete its
        futures), and fail its unfinished futures as broken."""
        now = time.monotonic()
        pools = {id(pool): pool for _, pool, _ in running.values()}
        for key, pool in pools.items():
            if not (dead_worker(pool) or manager_ended(pool)):
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


def fill_blocks(runner: MapRunner, ds: Any, blocks: Iterable[tuple[dict[str, Any], dict[str, Any]]],
                computed: np.ndarray, dims: Sequence[str]) -> bool:
    """Copy each block of a map into the arrays of `ds` as it finishes: every map in memory.

    The map's dataset is built once (:mod:`impactcont.dataset.maps`) and its arrays filled
    in place, with no list of results and no assembled copies.

    Parameters
    ----------
    runner : MapRunner
        The map's runner (for a Ctrl-C: :func:`keep_interrupted`).
    ds : xarray.Dataset
        The map; a variable whose array cannot be written (a placeholder of no memory) gets
        a new one, which the blocks fill.
    blocks : iterable
        ``(region, values)`` per finished task: ``region`` maps each of `dims` to an index
        or a slice, ``values`` a variable of `ds` to its block (the region of its dims).
    computed : ndarray of bool
        On `dims`: each block's region is set True.
    dims : sequence of str
        The dims of `computed`, those the regions index.

    Returns
    -------
    bool
        Whether a first Ctrl-C interrupted the map (what was computed is kept); a second
        re-raises KeyboardInterrupt.
    """
    arrays = {key: _writable(ds.variables[key]) for key in ds.data_vars}
    try:
        for region, values in blocks:
            for key, block in values.items():
                arrays[key][tuple(region[d] for d in ds[key].dims if d in region)] = block
            computed[tuple(region[d] for d in dims)] = True
    except KeyboardInterrupt:
        if not keep_interrupted(runner, computed.size):
            raise
        return True
    return False


def _writable(var: Any) -> np.ndarray:
    """The numpy array of `var`, which the map fills in place (a new one if it cannot be)."""
    data = var.data
    if not (isinstance(data, np.ndarray) and data.flags.writeable and data.flags.owndata):
        data = np.empty(var.shape, var.dtype)
        var.data = data
    return data


def written_blocks(runner: MapRunner, blocks: Iterable[tuple[dict[str, Any], dict[str, Any]]],
                   computed: np.ndarray, dims: Sequence[str],
                   not_computed: Callable[[], Iterable[tuple[dict[str, Any], dict[str, Any]]]],
                   interrupted: list[bool]
                   ) -> Iterator[tuple[dict[str, Any], dict[str, Any]]]:
    """The blocks of a map written to a file (:func:`~impactcont.dataset.io.save_blocks`) as
    they finish, each marked in `computed` (on `dims`) once written: every map on disk.

    After a first Ctrl-C (:func:`keep_interrupted`) `interrupted` gets True and the blocks
    of `not_computed()` follow (the tasks not finished, written as not computed), so that
    the file is whole; a second re-raises KeyboardInterrupt.
    """
    try:
        for region, values in blocks:
            yield region, values
            computed[tuple(region[d] for d in dims)] = True
    except KeyboardInterrupt:
        if not keep_interrupted(runner, computed.size):
            raise
        interrupted.append(True)
        yield from not_computed()


def positive_int(name: str, value: Any, *, optional: bool = False) -> int | None:
    """`value` as an integer >= 1 (None kept if `optional`), refused naming `name`.

    Raises
    ------
    ParameterError
        Not an integer >= 1 (a bool is none), naming the argument and the value.
    """
    if optional and value is None:
        return None
    return check_positive_integer(name, value, "or None" if optional else "")


def positive_number(name: str, value: Any) -> float:
    """`value` as a finite number > 0, refused naming `name`.

    Raises
    ------
    ParameterError
        Not a finite number > 0 (a bool is none), naming the argument and the value.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not (value > 0 and math.isfinite(value)):
        raise ParameterError(f"{name} must be a finite number > 0; got {value!r}")
    return float(value)


def check_run_options(executor: Any, max_workers: Any, memory_limit: Any
                      ) -> tuple[int | None, float]:
    """The run options of every map, checked: where it runs, the pool's processes, and the
    bytes it may take (:class:`MapRunner`, :func:`_plan`); returns ``(max_workers,
    memory_limit)``.

    Raises
    ------
    ParameterError
        Naming the argument, its value and what is allowed.
    """
    check_executor(executor)
    return (positive_int("max_workers", max_workers, optional=True),
            positive_number("memory_limit", memory_limit))


def mark_computed(ds: Any, computed: np.ndarray, dims: Sequence[str]) -> None:
    """Mark a map interrupted by a first Ctrl-C (issue 31): the variable ``computed`` on
    `dims` (True where a task finished) and the attributes ``interrupted`` (1) and
    ``points_computed``."""
    ds["computed"] = (tuple(dims), computed,
                      {"long_name": "point computed before the map was interrupted",
                       "units": "1"})
    ds.attrs["interrupted"] = 1
    ds.attrs["points_computed"] = int(np.count_nonzero(computed))


def abandon(runner: MapRunner, temporary: Any = None) -> None:
    """A map that failed or was abandoned (a second Ctrl-C): no worker left computing (the
    pool made for it killed), and its temporary file, if it had one, removed."""
    runner.close(kill=True)
    if temporary is not None:
        remove_temporary_map(temporary)

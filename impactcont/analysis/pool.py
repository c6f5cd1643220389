"""A process pool for the maps that survives a dead worker and does not outlive its parent.

:class:`concurrent.futures.ProcessPoolExecutor` has two faults under load that this module
covers for :func:`impactcont.stability_map` (``executor="process"``):

- **A worker killed while it sends its result** (by a signal, the out-of-memory killer, a
  scheduler) leaves half a message in the pool's result pipe. The pool's manager thread
  then waits in ``recv`` for the rest forever: it never looks at the dead worker, no
  future completes, the map waits forever, and ``shutdown`` and the interpreter's exit
  wait for that thread too (issue 28: 2 of 4 runs hung with the parent stalled 1.5 s
  while one worker was killed). :func:`dead_worker` tells a pool with a dead worker,
  :func:`kill_pool` ends it in every case: SIGKILL to every worker, then the missing
  bytes of the half message written into the result pipe (zeros: the manager thread gets
  a message that does not unpickle, marks the pool broken, fails its futures with
  :class:`~concurrent.futures.process.BrokenProcessPool` and ends), then ``shutdown``.
- **A parent that is killed** (SIGKILL: no ``atexit``, no ``finally``) left its workers
  running, adopted by init, holding their memory. The workers of :func:`process_pool`
  watch their parent (:func:`_watch_parent`): on Linux the kernel sends them SIGKILL when
  the parent ends (``prctl(PR_SET_PDEATHSIG)``), and everywhere a daemon thread of each
  worker polls its parent twice a second and ends the worker (``os._exit``) once the
  parent is gone.

Only private attributes of ``ProcessPoolExecutor`` that every CPython from 3.9 has are
read (``_processes``, ``_broken``, ``_result_queue``, ``_executor_manager_thread``); each
use falls back to doing nothing if one is missing.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import ctypes.util
import logging
import multiprocessing.connection
import os
import signal
import sys
import threading
import time
from typing import Any

__all__ = ["PARENT_POLL_SECONDS", "dead_worker", "kill_pool", "manager_ended", "process_pool"]

log = logging.getLogger(__name__)

#: How often a worker of :func:`process_pool` looks whether its parent still runs (seconds).
PARENT_POLL_SECONDS = 0.5
_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def _parent_running(parent: int) -> bool:
    """Whether process `parent` still exists (POSIX; elsewhere assumed so)."""
    if os.name != "posix":
        return True  # os.kill(pid, 0) would end the process on Windows
    try:
        os.kill(parent, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process of that pid: it exists
        return True
    return True


def _watch_parent(parent: int) -> None:
    """Initializer of the workers of :func:`process_pool`: end this worker when `parent` ends.

    On Linux ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` has the kernel kill the worker as soon
    as the process (thread) that forked it ends; the worker's parent may have ended
    before that call, so the parent is checked after it. Everywhere (and as well on
    Linux, where ``prctl`` may be refused), a daemon thread looks twice a second whether
    the worker's parent changed (a worker whose parent ended is adopted by another
    process) or, when the worker was not forked by `parent` itself (a fork server),
    whether `parent` still runs, and ends the worker with ``os._exit``.

    Ctrl-C (SIGINT, sent by a terminal to the whole process group) is ignored: the
    parent takes it and kills its workers (:func:`kill_pool`), instead of every worker
    printing its own ``KeyboardInterrupt``.
    """
    with contextlib.suppress(ValueError, OSError):
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        with contextlib.suppress(Exception):  # no libc, a refused call: the thread does it
            libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    first = os.getppid()
    if first != parent and not _parent_running(parent):
        os._exit(1)

    def watch() -> None:
        while os.getppid() == first and (first == parent or _parent_running(parent)):
            time.sleep(PARENT_POLL_SECONDS)
        os._exit(1)

    threading.Thread(target=watch, name="impactcont-parent-watch", daemon=True).start()


def process_pool(max_workers: int | None = None,
                 mp_context: Any = None) -> cf.ProcessPoolExecutor:
    """A :class:`~concurrent.futures.ProcessPoolExecutor` whose workers end with this process.

    Parameters
    ----------
    max_workers : int, optional
        Worker processes (default: the number of processors).
    mp_context : multiprocessing context, optional
        As for ``ProcessPoolExecutor``.

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        Each worker ends within :data:`PARENT_POLL_SECONDS` (at once on Linux) of the end
        of the process that made the pool, however it ends (SIGKILL included).
    """
    return cf.ProcessPoolExecutor(max_workers=max_workers, mp_context=mp_context,
                                  initializer=_watch_parent, initargs=(os.getpid(),))


def _processes(pool: Any) -> list[Any]:
    """The worker processes of a ProcessPoolExecutor (empty if it has none or is not one)."""
    processes = getattr(pool, "_processes", None)
    return list(processes.values()) if isinstance(processes, dict) else []


def dead_worker(pool: Any) -> bool:
    """Whether a worker process of `pool` has ended while the pool is not marked broken.

    The pool's manager thread marks the pool broken within milliseconds of a worker's
    death, unless it is stuck reading the worker's half-sent result: a pool for which
    this stays True is stuck (:func:`kill_pool`).
    """
    if not isinstance(pool, cf.ProcessPoolExecutor) or getattr(pool, "_broken", False):
        return False
    sentinels = []
    for process in _processes(pool):
        with contextlib.suppress(ValueError, AttributeError):  # closed process objects
            sentinels.append(process.sentinel)
    return bool(sentinels) and bool(multiprocessing.connection.wait(sentinels, timeout=0))


def manager_ended(pool: Any) -> bool:
    """Whether the manager thread of `pool` has ended while the pool is not marked broken.

    Only that thread completes the futures of a process pool: a pool with futures
    submitted and no manager thread alive never completes them (seen once in CI, a
    caller's fork pool after one of its workers was killed, at load 4 on 2 cores: the
    map waited on it for good).
    """
    if not isinstance(pool, cf.ProcessPoolExecutor) or getattr(pool, "_broken", False):
        return False
    thread = getattr(pool, "_executor_manager_thread", None)
    return thread is not None and not thread.is_alive()


def _unstick(pool: Any, timeout: float) -> bool:
    """Let the manager thread of `pool` (its workers dead) finish a half-read message.

    Zeros are written into the result pipe (the write end the pool keeps in this
    process) until the thread ends: the message it reads then does not unpickle, and the
    thread marks the pool broken, fails its futures and ends. The pipe is made
    non-blocking first (its workers, the only other writers, are dead), so that no write
    waits once the thread stops reading.

    Returns
    -------
    bool
        The thread has ended (or there is none).
    """
    thread = getattr(pool, "_executor_manager_thread", None)
    if thread is None or not thread.is_alive():
        return True
    deadline = time.monotonic() + timeout
    try:
        fd = pool._result_queue._writer.fileno()
        os.set_blocking(fd, False)
    except (AttributeError, OSError, ValueError):
        thread.join(timeout)
        return not thread.is_alive()
    zeros = bytes(1 << 16)
    while thread.is_alive() and time.monotonic() < deadline:
        try:
            os.write(fd, zeros)
        except BlockingIOError:
            thread.join(0.02)  # the pipe is full: the thread reads it, or has ended
        except OSError:
            break
    thread.join(max(0.0, deadline - time.monotonic()))
    return not thread.is_alive()


def kill_pool(pool: Any, timeout: float = 5.0) -> bool:
    """End a process pool now, whatever state it is in; its futures fail or are cancelled.

    Every worker gets SIGKILL (the queues and their locks may be held by a dead worker,
    so no worker could end cleanly), the manager thread is released if it is stuck
    (:func:`_unstick`) and the pool is shut down without waiting for its tasks.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
        Anything else is left alone.
    timeout : float
        Seconds to wait for the workers and for the manager thread to end.

    Returns
    -------
    bool
        Every worker and the manager thread have ended.
    """
    if not isinstance(pool, cf.ProcessPoolExecutor):
        return True
    processes = _processes(pool)
    for process in processes:
        with contextlib.suppress(Exception):
            process.kill()
    deadline = time.monotonic() + timeout
    for process in processes:
        with contextlib.suppress(Exception):
            process.join(max(0.0, deadline - time.monotonic()))
    ended = _unstick(pool, max(0.1, deadline - time.monotonic()))
    with contextlib.suppress(Exception):
        pool.shutdown(wait=False, cancel_futures=True)
    alive = [p.pid for p in processes if _alive(p)]
    if alive or not ended:
        log.warning("a process pool could not be ended within %.3g s (workers %s still "
                    "running, manager thread %s)", timeout, alive,
                    "ended" if ended else "still running")
    return not alive and ended


def _alive(process: Any) -> bool:
    try:
        return bool(process.is_alive())
    except (ValueError, AssertionError):  # closed, or not a child of this process
        return False

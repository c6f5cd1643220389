"""The maps' process pool: a pool stuck on a dead worker's half-sent result is ended, and
the workers watch their parent (issue 28).

The stuck state is made exactly as a worker killed in the middle of sending its result
leaves it: a message header and part of its body in the pool's result pipe, which the
pool's manager thread reads and then waits on for the rest. The whole map under these
faults (a worker killed while the parent is stalled, Ctrl-C, the parent killed) is in
``tests/integration/test_pool_faults.py``.
"""

from __future__ import annotations

import concurrent.futures as cf
import ctypes
import multiprocessing
import os
import signal
import struct
import sys
import threading
import time

import pytest

from impactcont.analysis import pool as pool_module
from impactcont.analysis.pool import dead_worker, kill_pool, process_pool

posix = pytest.mark.skipif(os.name != "posix", reason="signals and fork (POSIX)")


def _threads() -> list[str]:
    return [t.name for t in threading.enumerate()]


def _sigint() -> object:
    return signal.getsignal(signal.SIGINT)


def _pdeathsig() -> int:
    libc = ctypes.CDLL(None, use_errno=True)
    value = ctypes.c_int(-1)
    libc.prctl(2, ctypes.byref(value), 0, 0, 0)  # PR_GET_PDEATHSIG
    return value.value


def _stick(pool: cf.ProcessPoolExecutor) -> None:
    """Half a message of 1 MB in the result pipe: the manager thread waits for the rest."""
    os.write(pool._result_queue._writer.fileno(), struct.pack("!i", 1 << 20) + bytes(100))


@posix
def test_a_pool_stuck_on_a_half_sent_result_is_ended_and_its_futures_fail():
    pool = process_pool(2)
    assert pool.submit(int).result() == 0
    assert not dead_worker(pool)  # a healthy pool
    workers = list(pool._processes.values())
    _stick(pool)
    future = pool.submit(time.sleep, 30)
    os.kill(workers[0].pid, signal.SIGKILL)
    time.sleep(0.5)
    # the manager thread is stuck in recv: it does not see the dead worker
    manager = pool._executor_manager_thread
    assert dead_worker(pool) and manager.is_alive() and not pool._broken
    start = time.monotonic()
    assert kill_pool(pool, timeout=5.0)
    assert time.monotonic() - start < 5.0
    assert not any(w.is_alive() for w in workers)
    assert not manager.is_alive()
    with pytest.raises(cf.process.BrokenProcessPool):
        future.result(timeout=1.0)
    with pytest.raises(cf.process.BrokenProcessPool):  # and no task goes to it any more
        pool.submit(int)


@posix
def test_kill_pool_ends_a_busy_healthy_pool_at_once():
    # Ctrl-C during a map: the workers are killed, not waited for
    pool = process_pool(2)
    futures = [pool.submit(time.sleep, 30) for _ in range(3)]
    time.sleep(0.5)
    start = time.monotonic()
    assert kill_pool(pool)
    assert time.monotonic() - start < 5.0
    assert all(f.done() for f in futures)
    assert kill_pool(object()) and kill_pool(pool)  # anything else, or again: nothing to do


def test_the_workers_of_a_process_pool_watch_their_parent():
    with process_pool(1) as pool:
        assert "impactcont-parent-watch" in pool.submit(_threads).result()
        assert pool.submit(_sigint).result() == signal.SIG_IGN  # Ctrl-C: the parent's
        if sys.platform.startswith("linux"):
            assert pool.submit(_pdeathsig).result() == signal.SIGKILL


@posix
def test_a_worker_whose_parent_is_gone_ends_at_once():
    # the parent ended before the worker started watching it (or a fork server made it)
    dead = multiprocessing.get_context("fork").Process(target=int)
    dead.start()
    dead.join()
    child = multiprocessing.get_context("fork").Process(target=pool_module._watch_parent,
                                                        args=(dead.pid,))
    child.start()
    child.join(10.0)
    assert child.exitcode == 1


@posix
def test_a_worker_ends_when_its_parent_changes(monkeypatch):
    # the portable watch (no prctl): a thread polls os.getppid()
    monkeypatch.setattr(pool_module, "PARENT_POLL_SECONDS", 0.01)
    monkeypatch.setattr(sys, "platform", "no-prctl")
    ppid = iter([os.getpid()] * 3 + [1] * 1000)
    exited = threading.Event()
    monkeypatch.setattr(os, "getppid", lambda: next(ppid))
    monkeypatch.setattr(os, "_exit", lambda code: exited.set())
    monkeypatch.setattr(signal, "signal", lambda *args: None)  # this process keeps Ctrl-C
    pool_module._watch_parent(os.getpid())
    assert exited.wait(5.0)


def test_a_pool_whose_manager_thread_ended_is_told():
    """Only the manager thread completes a process pool's futures: with it ended (and the
    pool not marked broken) nothing ever would, and a map must not wait on such a pool."""
    import concurrent.futures as cf

    from impactcont.analysis.pool import manager_ended

    pool = cf.ProcessPoolExecutor(1)
    assert not manager_ended(pool)  # no thread before the first task
    assert pool.submit(int).result(timeout=60) == 0
    assert not manager_ended(pool)  # running
    thread = pool._executor_manager_thread
    pool.shutdown(wait=True)  # ends the thread and forgets it
    assert not manager_ended(pool)
    pool._executor_manager_thread = thread  # the state seen in the hung map: ended, kept
    assert manager_ended(pool)
    assert not manager_ended(object())

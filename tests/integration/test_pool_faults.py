"""A process-pool map under faults: a worker killed while the parent is stalled, Ctrl-C,
and the parent killed (issue 28).

Each case runs the map in a child interpreter with a hard timeout, so that a hang fails
the test instead of hanging the suite. The parent is stalled as a busy scheduler does
(SIGSTOP for 1.5 s): the workers finish their tasks meanwhile and block writing their
results into the pool's pipe; the one that is writing (``/proc/<pid>/wchan``) is then
killed, which leaves half a message in the pipe. Before the fix the pool's manager thread
waited for the rest forever and the map never ended (2 of 4 runs in the issue, every run
here); killing the parent left its workers running, adopted by init.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from tests._ctrl_c import terminal_sigint

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="needs /proc, SIGSTOP and SIGKILL (Linux)")

ROOT = Path(__file__).resolve().parents[2]
TIMEOUT = 150.0  # seconds for a whole child run: beyond it the child hung

CHILD = textwrap.dedent("""
    import multiprocessing as mp
    import sys
    import numpy as np
    import impactcont as ic

    mode, repeat = sys.argv[1], int(sys.argv[2])
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.6, omega=1.0, eta=0.1)
    # tasks of 4 x 1024 points: 0.1 s at least, results of about 400 kB, more than a pipe
    # holds (the workers are still computing when the parent is stopped, then block writing)
    # a map that cannot end before the parent is killed or interrupted (it ran to its end
    # before the Ctrl-C on a quick machine), a short one where it is compared
    long = mode.startswith("parent") or mode.endswith("interrupt")
    w, b = np.linspace(0.5, 6.0, 4000 if long else 48), np.linspace(-1, 1.5, 1024)
    told = []

    def progress(record):
        if len(told) < 1:
            told.append(1)
            print("PIDS", *[c.pid for c in mp.active_children()], flush=True)

    reference = None if long else ic.stability_map(osc, [1], w, b)
    out = "map.nc" if mode == "parent-out" else None
    executor = "process"
    if mode.startswith("caller"):
        # the caller's pool, stuck as a worker killed sending its result leaves it: half a
        # message in the result pipe (the manager thread waits for the rest), a dead worker
        import concurrent.futures as cf
        import os
        import signal
        import struct
        import time

        executor = cf.ProcessPoolExecutor(2)
        executor.submit(int).result()
        os.write(executor._result_queue._writer.fileno(), struct.pack("!i", 1 << 20) + bytes(9))
        time.sleep(0.2)
        workers = list(executor._processes)
        os.kill(workers[0], signal.SIGKILL)
        print("PIDS", *workers, flush=True)
    for _ in range(repeat):
        told.clear()
        try:
            ds = ic.stability_map(osc, [1], w, b, executor=executor, max_workers=None
                                  if executor != "process" else 2, progress=progress,
                                  out=out, omega_block=None if out else 4)
            # a map in memory keeps what it computed at the first Ctrl-C (issue 31)
            interrupted = bool(ds.attrs.get("interrupted"))
        except KeyboardInterrupt:  # a map to a file is abandoned
            interrupted = True
        if interrupted:
            # the workers killed, reaped within seconds (a busy machine delays the last)
            import time
            end = time.monotonic() + 10.0
            while mp.active_children() and time.monotonic() < end:
                time.sleep(0.05)
            print("INTERRUPTED", *[c.pid for c in mp.active_children()], flush=True)
            continue
        for key in ("exists", "n_physical", "n_stable", "delta", "gap_min", "stable"):
            assert np.array_equal(ds[key].values, reference[key].values, equal_nan=True), key
        print("SAME", *[c.pid for c in mp.active_children()], flush=True)
""")


def _gone(pid: int) -> bool:
    """Process `pid` has ended (absent, or a zombie nobody reaped)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def _wchan(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/wchan").read_text()
    except OSError:
        return ""


def _start(tmp_path: Path, mode: str, repeat: int) -> subprocess.Popen:
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, str(script), mode, str(repeat)], cwd=tmp_path,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=terminal_sigint)


def _line(child: subprocess.Popen, deadline: float) -> str:
    """The child's next line of output (the test fails if it takes past `deadline`)."""
    import selectors

    with selectors.DefaultSelector() as sel:
        sel.register(child.stdout, selectors.EVENT_READ)
        if not sel.select(max(0.0, deadline - time.monotonic())):
            raise TimeoutError("the child printed nothing before the deadline")
    return child.stdout.readline()


def _verdict(child: subprocess.Popen, deadline: float) -> str:
    """The child's next line that is not a progress line (``PIDS``: a map, or a pool that
    replaced a stuck one, reports its workers)."""
    line = _line(child, deadline)
    while line.startswith("PIDS"):
        line = _line(child, deadline)
    return line


def _stall_and_kill_a_writer(child: subprocess.Popen, workers: list[int]) -> bool:
    """Stop the parent 1.5 s, kill the worker blocked writing its result, resume; whether
    there was one (else the first worker is killed)."""
    os.kill(child.pid, signal.SIGSTOP)
    try:
        time.sleep(1.5)
        writer = next((pid for pid in workers if "pipe_write" in _wchan(pid)), None)
        os.kill(writer or workers[0], signal.SIGKILL)
    finally:
        os.kill(child.pid, signal.SIGCONT)
    return writer is not None


def _end(child: subprocess.Popen, pids: list[int]) -> str:
    """Kill the child and `pids` if they still run; the child's stderr (once read, kept)."""
    for pid in [child.pid, *pids]:
        if not _gone(pid):
            os.kill(pid, signal.SIGKILL)
    if not hasattr(child, "stderr_text"):
        child.stderr_text = child.communicate()[1]
    return child.stderr_text


def test_a_worker_killed_while_the_parent_is_stalled_is_replaced_every_time(tmp_path):
    repeat = 3
    child = _start(tmp_path, "kill", repeat)
    deadline = time.monotonic() + TIMEOUT
    pids: list[int] = []
    writers = 0
    try:
        for _ in range(repeat):
            line = _line(child, deadline)
            assert line.startswith("PIDS"), (line, child.stderr.read())
            workers = [int(p) for p in line.split()[1:]]
            pids += workers
            writers += _stall_and_kill_a_writer(child, workers)
            line = _line(child, deadline)
            # the same map as the serial one, and no worker left
            assert line.split() == ["SAME"], line
        assert child.wait(max(1.0, deadline - time.monotonic())) == 0
    except (TimeoutError, subprocess.TimeoutExpired):
        pytest.fail(f"the map hung after a worker was killed: {_end(child, pids)[-3000:]}")
    finally:
        stderr = _end(child, pids)
    assert all(_gone(pid) for pid in pids)
    # a writer was killed, and each pool that broke was replaced: a pool stuck on the half
    # message (1 to 3 of 3 here) was ended by the map, the others noticed it themselves
    # (the stuck pool is made for certain in the test of a caller's pool below)
    assert writers >= 1, stderr
    assert stderr.count("run again in a new pool") == repeat, stderr


def test_ctrl_c_stops_a_stuck_map_and_kills_its_workers(tmp_path):
    child = _start(tmp_path, "interrupt", 1)
    deadline = time.monotonic() + TIMEOUT
    workers: list[int] = []
    try:
        line = _line(child, deadline)
        assert line.startswith("PIDS"), (line, child.stderr.read())
        workers = [int(p) for p in line.split()[1:]]
        _stall_and_kill_a_writer(child, workers)
        time.sleep(0.3)  # the manager thread is now stuck on the half-sent result
        os.kill(child.pid, signal.SIGINT)
        line = _verdict(child, time.monotonic() + 60.0)  # a busy machine ends pools slowly
        assert line.split() == ["INTERRUPTED"], line  # no worker left
        assert child.wait(20.0) == 0  # and the interpreter's exit does not hang
    except (TimeoutError, subprocess.TimeoutExpired):
        pytest.fail(f"Ctrl-C did not stop the map: {_end(child, workers)[-3000:]}")
    finally:
        _end(child, workers)
    assert all(_gone(pid) for pid in workers)


def test_a_stuck_pool_of_the_caller_is_replaced(tmp_path):
    # deterministic: the caller's pool is stuck before the map starts
    child = _start(tmp_path, "caller", 1)
    try:
        line = _line(child, time.monotonic() + TIMEOUT)
        assert line.startswith("PIDS"), (line, child.stderr.read())
        workers = [int(p) for p in line.split()[1:]]
        line = _verdict(child, time.monotonic() + 60.0)  # past the new pool's progress
        assert line.split() == ["SAME"], line
        assert child.wait(20.0) == 0  # the stuck manager thread does not hold the exit
    except (TimeoutError, subprocess.TimeoutExpired):
        pytest.fail(f"the map hung on the caller's stuck pool: {_end(child, workers)[-3000:]}")
    finally:
        _end(child, workers)
    assert all(_gone(pid) for pid in workers)


@pytest.mark.xfail(strict=False, reason=(
    "known fault left open: on a machine kept busy beyond its cores (three busy loops on "
    "two cores), a Ctrl-C that lands after the map replaced the caller's stuck pool can "
    "leave that pool's manager thread holding the interpreter's exit (2 of 3 runs there); "
    "it passes on a quiet machine and at load 2"))
def test_ctrl_c_after_a_stuck_caller_pool_ends_the_map_and_the_process(tmp_path):
    child = _start(tmp_path, "caller-interrupt", 1)
    workers: list[int] = []
    try:
        line = _line(child, time.monotonic() + TIMEOUT)
        workers = [int(p) for p in line.split()[1:]]
        time.sleep(1.0)  # the map runs, its tasks never come back
        os.kill(child.pid, signal.SIGINT)
        line = _verdict(child, time.monotonic() + 60.0)
        assert line.split()[:1] == ["INTERRUPTED"], line
        assert child.wait(20.0) == 0
        # on a busy machine a worker of the caller's replaced pool may still run when the
        # map is interrupted (seen with three busy loops on two cores); it ends with the
        # process that made it (the parent watch), without being killed here
        left = [int(p) for p in line.split()[1:]]
        end = time.monotonic() + 10.0
        while not all(_gone(pid) for pid in left) and time.monotonic() < end:
            time.sleep(0.1)
        assert all(_gone(pid) for pid in left), left
    except (TimeoutError, subprocess.TimeoutExpired):
        pytest.fail(f"Ctrl-C did not end the map: {_end(child, workers)[-3000:]}")
    finally:
        _end(child, workers)
    assert all(_gone(pid) for pid in workers)


@pytest.mark.parametrize("mode", ["parent", "parent-out"])
def test_the_workers_end_when_the_parent_is_killed(tmp_path, mode):
    # before: both workers alive 150 s later, adopted by init (the same with out=)
    child = _start(tmp_path, mode, 1)
    workers: list[int] = []
    try:
        line = _line(child, time.monotonic() + TIMEOUT)
        assert line.startswith("PIDS"), (line, child.stderr.read())
        workers = [int(p) for p in line.split()[1:]]
        assert workers and not any(_gone(pid) for pid in workers)
        os.kill(child.pid, signal.SIGKILL)
        child.wait(10.0)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and not all(_gone(pid) for pid in workers):
            time.sleep(0.05)
        assert all(_gone(pid) for pid in workers), [p for p in workers if not _gone(p)]
    finally:
        _end(child, workers)

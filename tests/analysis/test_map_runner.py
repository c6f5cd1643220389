"""The runner of every map: tasks in this process or on an executor, memory planning, Ctrl-C.

The maps themselves are tested through their runner in ``tests/analysis/test_maps.py``,
``tests/analysis/test_multi_maps.py`` and ``tests/integration/test_map_executors.py``; here
the runner alone, on a job of plain arithmetic.
"""

from __future__ import annotations

import concurrent.futures as cf

import pytest

from impactcont.analysis import map_runner
from impactcont.analysis.map_runner import MapJob, MapRunner, check_executor, keep_interrupted
from impactcont.errors import ParameterError
from impactcont.progress import interruptible, reporter


def _square(x: int) -> int:
    return x * x


def _interrupting(after: int, x: int) -> int:
    if x == after:
        raise KeyboardInterrupt
    return x * x


class _Squares(MapJob):
    """Tasks 0..n-1, each worth x + 1 points; the task x computes x * x."""

    what = "squares"

    def __init__(self, function=_square) -> None:
        self.function = function

    def call(self, task):
        return self.function, (task,)

    def points(self, task):
        return task + 1


def _run(executor, tasks, job=None):
    with interruptible("test"), reporter(False, "test", total=sum(t + 1 for t in tasks)) as rep:
        runner = MapRunner(job or _Squares(), executor, 2, rep)
        try:
            return dict(runner.results(tasks)), runner
        finally:
            runner.close()


@pytest.mark.parametrize("executor", [None, "serial", "process"])
def test_every_task_is_run_once_and_counted(executor):
    results, runner = _run(executor, list(range(7)))
    assert results == {x: x * x for x in range(7)}
    assert runner.done == sum(x + 1 for x in range(7))
    assert runner.name == ("process" if executor == "process" else "serial")


def test_an_executor_of_the_caller_is_used_and_left_open():
    with cf.ThreadPoolExecutor(2) as pool:
        results, runner = _run(pool, list(range(5)))
        assert results == {x: x * x for x in range(5)}
        assert runner.name == "ThreadPoolExecutor" and runner.workers == 2
        assert pool.submit(_square, 3).result() == 9  # not shut down by the map


def test_a_first_ctrl_c_keeps_the_tasks_finished():
    tasks = list(range(6))
    with interruptible("test"), reporter(False, "test", total=21) as rep:
        runner = MapRunner(_Squares(lambda x: _interrupting(3, x)), None, None, rep)
        got = {}
        with pytest.raises(KeyboardInterrupt):
            for task, value in runner.results(tasks):
                got[task] = value
        assert got == {0: 0, 1: 1, 2: 4}
        assert runner.done == 1 + 2 + 3
        assert keep_interrupted(runner, 21)  # the first of the call: kept
        runner.aborted = True
        assert not keep_interrupted(runner, 21)  # a second: abandoned


@pytest.mark.parametrize("bad", ["threads", "localhost:8786", 3, object()])
def test_an_executor_no_map_takes_is_refused_naming_the_argument(bad):
    with pytest.raises(ParameterError, match="scene executor must be None, 'serial'"):
        check_executor(bad, "scene executor")


def test_memory_planning_keeps_a_small_map_in_memory_and_sends_a_large_one_to_disk():
    stays, points = map_runner._plan(10**6, 1e9, 4, True, 10**5)
    assert stays and map_runner._MIN_TASK_POINTS <= points <= map_runner._MAX_TASK_POINTS
    stays, points = map_runner._plan(2 * 10**9, 1e9, 4, True, 10**6)
    assert not stays
    # written to disk, the tasks in flight and the NetCDF library fit in the limit
    assert 4 * points * map_runner._DISK_TASK_BYTES + map_runner._DISK_FIXED_BYTES <= 1e9
    assert not map_runner._plan(10**3, 1e9, 4, False, 100)[0]  # out=: always a file


def test_the_least_memory_of_a_map_on_disk():
    # issue 28: a limit below about 35 MB was exceeded without a word
    floor = map_runner._disk_floor(1)
    assert 3.2e7 < floor < 3.5e7 and map_runner._disk_floor(5) < 3.5e7

"""The runner of every map: tasks in this process or on an executor, memory planning, Ctrl-C.

The maps themselves are tested through their runner in ``tests/analysis/test_maps.py``,
``tests/analysis/test_multi_maps.py`` and ``tests/integration/test_map_executors.py``; here
the runner alone, on a job of plain arithmetic.
"""

from __future__ import annotations

import concurrent.futures as cf

import numpy as np
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


def _square_blocks(runner, tasks):
    """Each task's result as a block of a map on (x, y): row x of ``square`` and one point
    of ``flag``."""
    for task, value in runner.results(tasks):
        yield {"x": slice(task, task + 1)}, {"square": np.full((1, 3), float(value)),
                                             "flag": np.array([True])}


def test_fill_blocks_fills_every_map_in_memory_and_keeps_an_interrupted_one():
    """fill_blocks, the in-memory assembly of every map: each block copied into the
    dataset's arrays (a placeholder of no memory replaced), its region marked computed; a
    first Ctrl-C keeps the blocks finished (True), a second re-raises."""
    import xarray as xr

    from impactcont.analysis.map_runner import fill_blocks

    def empty():
        return xr.Dataset({"square": (("x", "y"), np.broadcast_to(np.zeros(()), (6, 3))),
                           "flag": (("x",), np.zeros(6, bool))})

    with interruptible("test"), reporter(False, "test", total=21) as rep:
        ds, computed = empty(), np.zeros(6, bool)
        runner = MapRunner(_Squares(), None, None, rep)
        assert not fill_blocks(runner, ds, _square_blocks(runner, range(6)), computed, ("x",))
        np.testing.assert_array_equal(ds["square"].values,
                                      np.repeat(np.arange(6.0)[:, None] ** 2, 3, axis=1))
        assert ds["flag"].values.all() and computed.all()
        ds, computed = empty(), np.zeros(6, bool)
        runner = MapRunner(_Squares(lambda x: _interrupting(3, x)), None, None, rep)
        assert fill_blocks(runner, ds, _square_blocks(runner, range(6)), computed, ("x",))
        np.testing.assert_array_equal(computed, [True, True, True, False, False, False])
        np.testing.assert_array_equal(ds["flag"].values, computed)
        runner.aborted = True  # a second Ctrl-C
        with pytest.raises(KeyboardInterrupt):
            fill_blocks(runner, empty(), _square_blocks(runner, range(6)), np.zeros(6, bool),
                        ("x",))


def test_written_blocks_end_an_interrupted_map_with_its_blocks_not_computed():
    """written_blocks, the blocks of every map written to a file: each marked computed once
    handed on; after a first Ctrl-C the blocks of what was not computed follow (the file is
    whole) and the interruption is recorded; a second re-raises."""
    from impactcont.analysis.map_runner import written_blocks

    def rest(computed):
        def not_computed():
            for k in np.flatnonzero(~computed):
                yield {"x": slice(k, k + 1)}, {"flag": np.array([False])}
        return not_computed

    with interruptible("test"), reporter(False, "test", total=21) as rep:
        runner = MapRunner(_Squares(lambda x: _interrupting(4, x)), None, None, rep)
        computed, interrupted = np.zeros(6, bool), []
        got = list(written_blocks(runner, _square_blocks(runner, range(6)), computed, ("x",),
                                  rest(computed), interrupted))
        assert interrupted == [True]
        assert [region["x"].start for region, _ in got] == [0, 1, 2, 3, 4, 5]
        assert [bool(values["flag"][0]) for _, values in got] == [True] * 4 + [False] * 2
        np.testing.assert_array_equal(computed, [True] * 4 + [False] * 2)
        runner = MapRunner(_Squares(lambda x: _interrupting(1, x)), None, None, rep)
        runner.aborted = True
        with pytest.raises(KeyboardInterrupt):
            list(written_blocks(runner, _square_blocks(runner, range(6)), np.zeros(6, bool),
                                ("x",), rest(np.zeros(6, bool)), []))

"""BLAS threads (:mod:`impactcont.threads`, issue 13): limited inside the library and
restored after; a scene runs with one BLAS thread."""

from __future__ import annotations

from pathlib import Path

import pytest

from impactcont.scene import run_scene
from tests._scene_data import ORBITS_SCENE, write


# -- BLAS threads (issue 13) --------------------------------------------------------------------
def test_blas_threads_are_limited_inside_the_library_and_restored(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from threadpoolctl import threadpool_info, threadpool_limits

    from impactcont.threads import blas_limited, limit_blas_threads

    def blas_threads() -> set[int]:
        return {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}

    with threadpool_limits(limits=2, user_api="blas"):
        if blas_threads() != {2}:
            pytest.skip("the BLAS here does not run 2 threads, so no limit can be seen")
        seen = []
        work = blas_limited(lambda: seen.append(blas_threads()) or 42)
        assert work() == 42 and seen == [{1}]
        with limit_blas_threads():
            with limit_blas_threads():  # nested: one limit, lifted by the outermost only
                assert blas_threads() == {1}
            assert blas_threads() == {1}
        assert blas_threads() == {2}
        monkeypatch.setenv("IMPACTCONT_BLAS_THREADS", "none")
        with limit_blas_threads():
            assert blas_threads() == {2}
        monkeypatch.setenv("IMPACTCONT_BLAS_THREADS", "lots")
        with pytest.raises(ValueError, match="IMPACTCONT_BLAS_THREADS must be a positive "
                                             "integer or 'none'; got 'lots'"):
            limit_blas_threads().__enter__()
        assert blas_threads() == {2}


def test_the_blas_libraries_are_scanned_again_only_after_an_import(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The scan of the loaded libraries (about 1 ms) is done once, not at every entry: again
    only when a module has been imported since (a new BLAS comes with a new extension
    module). Before, every entry scanned."""
    import sys
    import types

    import threadpoolctl

    import impactcont.threads as threads

    scans = []

    class Counting(threadpoolctl.ThreadpoolController):
        def __init__(self) -> None:
            scans.append(1)
            super().__init__()

    monkeypatch.setattr(threadpoolctl, "ThreadpoolController", Counting)
    monkeypatch.setattr(threads, "_controller", None)
    for _ in range(3):
        with threads.limit_blas_threads():
            pass
    assert len(scans) == 1
    monkeypatch.setitem(sys.modules, "_impactcont_new_extension", types.ModuleType("x"))
    with threads.limit_blas_threads():
        pass
    assert len(scans) == 2
    monkeypatch.setattr(threads, "_controller", None)  # not the counting one for the others


def test_a_scene_runs_with_one_blas_thread(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                           ) -> None:
    from threadpoolctl import threadpool_info, threadpool_limits

    from impactcont.scene import tasks

    seen = []
    compute = tasks.Orbits.compute

    def spy(self, entry, context=None):
        seen.append({lib["num_threads"] for lib in threadpool_info()
                     if lib["user_api"] == "blas"})
        return compute(self, entry, context)

    monkeypatch.setattr(tasks.Orbits, "compute", spy)
    with threadpool_limits(limits=2, user_api="blas"):
        run_scene(write(tmp_path, ORBITS_SCENE), output=tmp_path / "o")
    assert seen == [{1}, {1}]

"""A fixture that fakes the entry points of the group ``impactcont.problems``."""

from __future__ import annotations

import importlib.metadata
import sys
import types
from collections.abc import Callable, Iterator

import pytest

from impactcont.problems import plugins


class GoodProblem:
    """A problem from a plugin.

    More text that list-problems does not show.
    """


def fake_entry_points(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., None]]:
    """Fixture body: ``install((name, "module:attr"), ...)`` makes those the group's entry points.

    Use in a test module as ``fake_entry_points = pytest.fixture(_fake_plugins.fake_entry_points)``.

    ``tests_fake_plugin:GoodProblem`` is importable; the discovery cache is
    cleared before and after.
    """
    module = types.ModuleType("tests_fake_plugin")
    module.GoodProblem = GoodProblem
    monkeypatch.setitem(sys.modules, "tests_fake_plugin", module)

    def install(*pairs: tuple[str, str]) -> None:
        eps = [importlib.metadata.EntryPoint(name=name, value=value,
                                             group=plugins.ENTRY_POINT_GROUP)
               for name, value in pairs]

        def entry_points(**params: str) -> list[importlib.metadata.EntryPoint]:
            assert params == {"group": plugins.ENTRY_POINT_GROUP}
            return eps

        monkeypatch.setattr(importlib.metadata, "entry_points", entry_points)
        plugins.refresh_problems()

    plugins.refresh_problems()
    yield install
    plugins.refresh_problems()

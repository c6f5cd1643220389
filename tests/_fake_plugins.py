"""A fixture that fakes the entry points of the group ``impactcont.problems``."""

from __future__ import annotations

import dataclasses
import importlib.metadata
import sys
import types
from collections.abc import Callable, Iterator
from typing import ClassVar

import numpy as np
import pytest
import xarray as xr

from impactcont.scene import plugins
from impactcont.scene.entries import EntrySpec
from impactcont.scene.keys import Integer, declare

BUILTINS = ["orbits", "branches", "robust", "simulations", "multi_impact", "switches",
            "curves", "maps"]


class GoodProblem:
    """A problem from a plugin.

    More text that list-problems does not show.
    """


@dataclasses.dataclass(frozen=True, kw_only=True)
class TallyEntry(EntrySpec):
    """``[[tally]]``: count up to a number (a plugin's section)."""

    section: ClassVar[str] = "tally"

    upto: int = declare(Integer(1, 10), "how far to count", required=True)


def tally(entry: TallyEntry, context: object) -> xr.Dataset:
    """The driver of ``[[tally]]``."""
    return xr.Dataset({"k": ("k", np.arange(entry.upto))}, attrs={"name": entry.name})


TALLY = plugins.SceneSection("tally", TallyEntry, tally, "Tallies")
#: A malformed section: its key is reserved.
RESERVED = plugins.SceneSection("plots", TallyEntry, tally, "Plots")


def fake_entry_points(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[..., None]]:
    """Fixture body: ``install((name, "module:attr"), ...)`` makes those the group's entry points.

    Use in a test module as ``fake_entry_points = pytest.fixture(_fake_plugins.fake_entry_points)``.

    ``tests_fake_plugin:GoodProblem``, ``tests_fake_plugin:TALLY`` (a scene
    section) and ``tests_fake_plugin:RESERVED`` (a malformed one) are
    importable; the discovery cache is cleared before and after.
    """
    module = types.ModuleType("tests_fake_plugin")
    module.GoodProblem = GoodProblem
    module.TALLY = TALLY
    module.RESERVED = RESERVED
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

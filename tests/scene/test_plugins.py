"""The problem registry: built-in sections and plugins of the group ``impactcont.problems``."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from impactcont.errors import ParameterError
from impactcont.problems import PeriodicBranchProblem
from impactcont.scene import SceneError, load_scene, read_output, run_scene
from impactcont.scene.plugins import (
    PluginWarning,
    SceneSection,
    get_problem,
    list_problems,
    load_target,
    plot_kinds,
    refresh_problems,
    scene_sections,
)
from tests import _fake_plugins
from tests._fake_plugins import BUILTINS, TALLY, GoodProblem
from tests._scene_data import OSCILLATOR, write

fake_entry_points = pytest.fixture(_fake_plugins.fake_entry_points)


def test_builtin_problems_without_plugins(fake_entry_points) -> None:
    fake_entry_points()
    problems = list_problems()
    assert list(problems) == BUILTINS
    assert all(p.origin == "built-in" and isinstance(p.obj, SceneSection)
               for p in problems.values())
    assert list(scene_sections()) == BUILTINS  # the scene format reads the same registry
    branches = problems["branches"]
    assert load_target(branches.section.problem) is PeriodicBranchProblem
    assert "one-parameter branch" in branches.summary
    assert {k.section for k in plot_kinds().values()} == set(BUILTINS)  # each draws its own


def test_one_loader() -> None:
    assert load_target("impactcont.problems:PeriodicBranchProblem") is PeriodicBranchProblem
    assert load_target("impactcont.scene.sections:BRANCHES.title") == "Branches"
    assert load_target(len) is len  # objects pass through
    with pytest.raises(ModuleNotFoundError):
        load_target("tests_no_such_module_xyz:f")


def test_plugin_is_discovered_and_listed_after_builtins(fake_entry_points) -> None:
    fake_entry_points(("good", "tests_fake_plugin:GoodProblem"),
                      ("tally", "tests_fake_plugin:TALLY"))
    problems = list_problems()
    assert list(problems) == [*BUILTINS, "good", "tally"]
    assert problems["good"].obj is GoodProblem and problems["good"].section is None
    assert problems["good"].origin == "plugin"  # an entry point without a distribution
    assert problems["good"].summary == "A problem from a plugin."
    assert get_problem("good") is GoodProblem
    assert get_problem("tally") is TALLY and problems["tally"].section is TALLY
    assert list(scene_sections()) == [*BUILTINS, "tally"]  # a bare class brings no section


def test_plugin_section_runs_in_a_scene(fake_entry_points, tmp_path: Path) -> None:
    fake_entry_points(("tally", "tests_fake_plugin:TALLY"))
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, OSCILLATOR + "[[tally]]\nupto = 11\n"))
    err = info.value
    assert err.key == "tally[0].upto" and err.allowed == "an integer in [1, 10]"
    result = run_scene(write(tmp_path, OSCILLATOR + "[[tally]]\nupto = 3\n"),
                       output=tmp_path / "o")
    assert result.ok
    out = read_output(tmp_path / "o" / "tally.nc")
    assert out.kind == "tally" and out.datasets["tally1"].sizes["k"] == 3
    summary = (tmp_path / "o" / "summary.md").read_text(encoding="utf-8")
    assert "## Tallies" in summary and "| tally1 | k=3 | - |" in summary


def test_broken_plugin_warns_and_the_rest_works(fake_entry_points, tmp_path: Path) -> None:
    fake_entry_points(("broken", "tests_no_such_module_xyz:Problem"),
                      ("good", "tests_fake_plugin:GoodProblem"),
                      ("missing_attr", "tests_fake_plugin:Nothing"),
                      ("reserved", "tests_fake_plugin:RESERVED"),
                      ("tally", "tests_fake_plugin:TALLY"))
    with pytest.warns(PluginWarning) as record:
        problems = list_problems()
    messages = [str(w.message) for w in record]
    assert any("'broken'" in m and "ModuleNotFoundError" in m for m in messages)
    assert any("'missing_attr'" in m and "AttributeError" in m for m in messages)
    assert any("'reserved'" in m and "'plots' is reserved" in m for m in messages)
    assert list(problems) == [*BUILTINS, "good", "tally"]
    assert load_target(get_problem("branches").problem) is PeriodicBranchProblem
    result = run_scene(write(tmp_path, OSCILLATOR + "[[tally]]\nupto = 2\n"),
                       output=tmp_path / "o")
    assert result.ok


def test_discovery_is_cached_and_warns_once(fake_entry_points) -> None:
    fake_entry_points(("broken", "tests_no_such_module_xyz:Problem"))
    with pytest.warns(PluginWarning):
        list_problems()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert "broken" not in list_problems()  # cached: no second warning
    refresh_problems()
    with pytest.warns(PluginWarning):
        list_problems()


def test_name_and_key_clashes_warn(fake_entry_points) -> None:
    fake_entry_points(("branches", "tests_fake_plugin:GoodProblem"),
                      ("good", "tests_fake_plugin:GoodProblem"),
                      ("good", "tests_no_such_module_xyz:Other"),
                      ("tally", "tests_fake_plugin:TALLY"),
                      ("tally2", "tests_fake_plugin:TALLY"))
    with pytest.warns(PluginWarning) as record:
        problems = list_problems()
    messages = " ".join(str(w.message) for w in record)
    assert "name of a built-in problem" in messages and "more than once" in messages
    assert "'tally2'" in messages and "brings the scene section [[tally]] of 'tally'" in messages
    assert problems["branches"].origin == "built-in"
    assert problems["good"].obj is GoodProblem
    assert "tally2" not in problems


def test_unknown_problem_names_the_available_ones(fake_entry_points) -> None:
    fake_entry_points(("good", "tests_fake_plugin:GoodProblem"))
    with pytest.raises(ParameterError, match=r"did you mean 'orbits'\?.*available: "
                                             r"orbits, branches, .*, maps, good"):
        get_problem("orbit")


def test_a_driver_that_fails_fails_its_entry_only(tmp_path: Path) -> None:
    from impactcont.scene.plugins import register_problem, unregister_problem
    from tests._fake_plugins import TallyEntry

    register_problem("odd", SceneSection("odd", TallyEntry, lambda entry, context: {"k": 1},
                                         "Odd"))
    try:
        text = OSCILLATOR + '[[odd]]\nupto = 2\n\n[[orbits]]\nname = "o"\n'
        result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    finally:
        unregister_problem("odd")
    assert [(f.section, f.name) for f in result.failures] == [("odd", "odd1")]
    assert "returned dict" in result.failures[0].error and "xarray.Dataset" in \
        result.failures[0].error
    assert (tmp_path / "o" / "orbits.nc").exists() and not (tmp_path / "o" / "odd.nc").exists()

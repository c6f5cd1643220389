"""Problem plugins: the entry-point group ``impactcont.problems``; broken plugins warn."""

from __future__ import annotations

import _fake_plugins
import pytest
from _fake_plugins import GoodProblem

from impactcont.errors import ParameterError
from impactcont.problems import PeriodicBranchProblem
from impactcont.problems.plugins import (
    PluginWarning,
    get_problem,
    list_problems,
    refresh_problems,
)

fake_entry_points = pytest.fixture(_fake_plugins.fake_entry_points)


def test_builtin_problem_without_plugins(fake_entry_points) -> None:
    fake_entry_points()
    problems = list_problems()
    assert list(problems) == ["periodic_n1"]
    info = problems["periodic_n1"]
    assert info.obj is PeriodicBranchProblem and info.origin == "built-in"
    assert "Eq. (14)" in info.summary


def test_plugin_is_discovered_and_listed_after_builtins(fake_entry_points) -> None:
    fake_entry_points(("good", "tests_fake_plugin:GoodProblem"))
    problems = list_problems()
    assert list(problems) == ["periodic_n1", "good"]
    assert problems["good"].obj is GoodProblem
    assert problems["good"].origin == "plugin"  # an entry point without a distribution
    assert problems["good"].summary == "A problem from a plugin."
    assert get_problem("good") is GoodProblem


def test_broken_plugin_warns_and_the_rest_works(fake_entry_points) -> None:
    fake_entry_points(("broken", "tests_no_such_module_xyz:Problem"),
                      ("good", "tests_fake_plugin:GoodProblem"),
                      ("missing_attr", "tests_fake_plugin:Nothing"))
    with pytest.warns(PluginWarning) as record:
        problems = list_problems()
    messages = [str(w.message) for w in record]
    assert any("'broken'" in m and "ModuleNotFoundError" in m for m in messages)
    assert any("'missing_attr'" in m and "AttributeError" in m for m in messages)
    assert list(problems) == ["periodic_n1", "good"]
    assert get_problem("periodic_n1") is PeriodicBranchProblem


def test_discovery_is_cached_and_warns_once(fake_entry_points) -> None:
    fake_entry_points(("broken", "tests_no_such_module_xyz:Problem"))
    with pytest.warns(PluginWarning):
        list_problems()
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert "broken" not in list_problems()  # cached: no second warning
    refresh_problems()
    with pytest.warns(PluginWarning):
        list_problems()


def test_name_clashes_warn(fake_entry_points) -> None:
    fake_entry_points(("periodic_n1", "tests_fake_plugin:GoodProblem"),
                      ("good", "tests_fake_plugin:GoodProblem"),
                      ("good", "tests_no_such_module_xyz:Other"))
    with pytest.warns(PluginWarning) as record:
        problems = list_problems()
    messages = " ".join(str(w.message) for w in record)
    assert "name of a built-in problem" in messages and "more than once" in messages
    assert problems["periodic_n1"].obj is PeriodicBranchProblem
    assert problems["good"].obj is GoodProblem


def test_unknown_problem_names_the_available_ones(fake_entry_points) -> None:
    fake_entry_points(("good", "tests_fake_plugin:GoodProblem"))
    with pytest.raises(ParameterError, match=r"did you mean 'periodic_n1'\?.*available: "
                                             r"periodic_n1, good"):
        get_problem("periodic_n2")

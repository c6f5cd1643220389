"""Options of the continuation (:mod:`impactcont.core.options`): one shape for every
continuation entry point, keyword-only ``options=`` (issue 12); bad option values are named
with what is allowed, and options are frozen."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.core.options import (
    DRIVER_DEFAULTS,
    ContinuationOptionError,
    ContinuationOptions,
    driver_options,
)


@pytest.fixture(scope="module")
def paper():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.5, eta=0.1)


def test_options_exported_and_core_subpackage_named_core():
    import impactcont.core

    assert ic.ContinuationOptions is impactcont.core.ContinuationOptions
    assert callable(ic.continuation)  # the function, not a subpackage
    from impactcont.continuation import ContinuationOptions  # the former path still works

    assert ContinuationOptions is ic.ContinuationOptions


def test_defaults_adapt_to_a_small_ds_max():
    opts = ic.ContinuationOptions(ds_max=0.001)
    assert opts.ds == 0.001 and opts.ds_min <= opts.ds and opts.given == {"ds_max"}
    merged = driver_options(ic.ContinuationOptions(max_points=7), (0.0, 1.0), ds_max=0.004)
    assert merged.ds == 0.004 and merged.max_points == 7 and merged.bounds == (0.0, 1.0)
    assert merged.both_directions is DRIVER_DEFAULTS["both_directions"]
    with pytest.raises(ic.ParameterError, match="options must be a ContinuationOptions"):
        driver_options({"ds": 0.1}, (0.0, 1.0))  # type: ignore[arg-type]


def test_every_entry_point_takes_options(paper):
    opts = ic.ContinuationOptions(ds_max=0.01, max_points=400)
    n1 = ic.continuation(paper, 1, "omega", (1.4, 2.0), components="start", options=opts)
    assert n1.sizes["point"] <= 800  # two directions of at most 400 points
    same = ic.continuation(paper, 1, "omega", (1.4, 2.0), components="start", ds_max=0.01,
                           max_points=400)
    np.testing.assert_array_equal(n1.omega.values, same.omega.values)
    # a convenience keyword overrides the same option given in options
    coarse = ic.continuation(paper, 1, "omega", (1.4, 2.0), components="start", options=opts,
                             ds_max=0.05)
    assert coarse.sizes["point"] < n1.sizes["point"]
    child = ic.period_doubling_switch(n1, bounds=(1.6, 1.9), options=opts)
    assert child.attrs["impacts"] == 2
    np_branch = ic.multi_impact_continuation(ic.special_orbit(n1, "PD"), "omega", (1.6, 1.9),
                                             options=ic.ContinuationOptions(max_points=20))
    assert np_branch.sizes["point"] <= 40
    pd = ic.curve(paper, None, "PD", start=n1, bounds={"omega": (1.4, 2.0), "b": (0.0, 0.2)},
                  options=ic.ContinuationOptions(max_points=5))
    assert pd.sizes["point"] <= 10


def test_former_submodule_paths_are_the_same_modules():
    from impactcont.continuation.options import ContinuationOptions
    from impactcont.continuation.stepper import NewtonConvergenceError

    from impactcont.core.stepper import NewtonConvergenceError as Same

    assert ContinuationOptions is ic.ContinuationOptions and NewtonConvergenceError is Same


def test_unknown_keyword_arguments_are_refused_with_the_options_listed():
    """A misspelt or foreign keyword (here `special`, which belongs to `curve`) reached the
    options dataclass and failed with a bare TypeError."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.0, omega=1.0, eta=0.1)
    with pytest.raises(ContinuationOptionError, match=r"unknown keyword argument\(s\) 'special'"
                       r".*ds_max"):
        ic.continuation(osc, 1, "omega", (0.5, 2.0), special=0)
    with pytest.raises(ContinuationOptionError, match="'dsmax'"):
        ic.continuation(osc, 1, "omega", (0.5, 2.0), dsmax=0.01)


@pytest.mark.parametrize(
    ("overrides", "pattern"),
    [
        ({"ds": -0.1}, r"ds = -0\.1 .*> 0"),
        ({"ds": 0.5, "ds_max": 0.1}, r"ds = 0\.5 .*ds_min <= ds <= ds_max"),
        ({"ds_min": 0.2, "ds": 0.2, "ds_max": 0.1}, r"ds_min = 0\.2 .*<= ds_max"),
        ({"newton_tol": 0.0}, r"newton_tol = 0\.0 .*> 0"),
        ({"newton_max_iter": 0}, r"newton_max_iter = 0 .*integer >= 1"),
        ({"newton_max_iter": 2.5}, r"newton_max_iter = 2\.5 .*integer"),
        ({"max_points": 1}, r"max_points = 1 .*integer >= 2"),
        ({"direction": 0}, r"direction = 0 .*\+1 or -1"),
        ({"both_directions": "yes"}, r"both_directions = 'yes' .*bool"),
        ({"max_angle": 2.0}, r"max_angle = 2\.0 .*\(0, pi/2\]"),
        ({"target_newton_iter": 0}, r"target_newton_iter = 0 .*integer >= 1"),
        ({"theta": 0.0}, r"theta = 0\.0 .*\(0, 1\]"),
        ({"theta": math.nan}, r"theta = nan .*finite"),
        ({"bounds": (1.0, -1.0)}, r"bounds = \(1\.0, -1\.0\) .*lam_min < lam_max"),
        ({"bounds": (0.0, math.inf)}, r"bounds = \(0\.0, inf\) .*finite"),
        ({"bounds": 3.0}, r"bounds = 3\.0 .*pair"),
    ],
)
def test_bad_option_names_option_value_and_allowed_values(
    overrides: dict[str, object], pattern: str
) -> None:
    arguments = {"bounds": (-1.0, 1.0), **overrides}

    with pytest.raises(ContinuationOptionError, match=pattern):
        ContinuationOptions(**arguments)


def test_option_error_is_a_value_error_and_options_are_frozen() -> None:
    assert issubclass(ContinuationOptionError, ValueError)
    options = ContinuationOptions(bounds=(-1, 1))
    assert options.bounds == (-1.0, 1.0)
    with pytest.raises(AttributeError):
        options.ds = 1.0  # type: ignore[misc]

"""Restart a branch from a point of a saved branch and extend it past its bounds."""

from __future__ import annotations

import json

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.branch import continuation_from, extend
from impactcont.errors import ParameterError

TOL = 1e-9  # the branches' Newton tolerance is 1e-12 (N-1) and 1e-11 (N-p)


@pytest.fixture(scope="module")
def system() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def branch(system):
    return ic.continuation(system, 1, "omega", (0.5, 3.0), progress=False)


@pytest.fixture(scope="module")
def switched(branch):
    return ic.period_doubling_switch(branch, bounds=(1.0, 2.0), max_points=40, progress=False)


def _phase(a: np.ndarray) -> np.ndarray:
    return np.remainder(a + np.pi, 2 * np.pi) - np.pi


def _same_specials(a, b, parameter: str = "omega") -> None:
    assert a.special_label.values.tolist() == b.special_label.values.tolist()
    precision = np.maximum(a.special_precision.values, b.special_precision.values)
    np.testing.assert_array_less(np.abs(a[f"special_{parameter}"].values
                                        - b[f"special_{parameter}"].values),
                                 np.maximum(10 * precision, TOL))


def _start_row(ds, rows):
    """Where the component's continuation started (the run there was computed outward)."""
    start = json.loads(ds.attrs["options"])["start"]
    return int(np.flatnonzero(ds.omega.values[rows] == start)[0])


@pytest.mark.parametrize("along", [1, -1])
def test_restart_reproduces_the_points_beyond_the_restart_point(branch, along):
    rows = np.flatnonzero(branch.connected_component.values == 0)
    k = _start_row(branch, rows) + 10 * along  # inside the run computed the way of along
    restarted = continuation_from(branch, int(rows[k]), along=along, progress=False)
    ahead = rows[k:] if along == 1 else rows[k::-1]
    assert restarted.sizes["point"] == ahead.size
    np.testing.assert_allclose(restarted.omega.values, branch.omega.values[ahead], rtol=0,
                               atol=TOL)
    assert np.max(np.abs(_phase(restarted.delta.values - branch.delta.values[ahead]))) < TOL
    record = json.loads(restarted.attrs["options"])
    assert record["restart"]["point"] == int(rows[k])
    assert record["status"] == ["BOUNDS_REACHED"]


def test_restart_from_a_special_point_by_label(branch):
    restarted = continuation_from(branch, label="PD", which=0, along=None, progress=False)
    k = next(i for i, lab in enumerate(branch.special_label.values) if lab == "PD")
    start = json.loads(restarted.attrs["options"])["start"]
    assert start == float(branch.special_omega.values[k])
    # the located PD is found again on the restarted branch
    pd = restarted.special_omega.values[restarted.special_label.values == "PD"]
    assert np.min(np.abs(pd - branch.special_omega.values[k])) < TOL


def test_extended_branch_equals_the_branch_computed_with_the_wider_bounds(system, branch):
    wide = ic.continuation(system, 1, "omega", (0.4, 4.0), progress=False)
    extended = extend(branch, (0.4, 4.0), progress=False)
    _same_specials(extended, wide)
    assert extended.omega.min() == 0.4 and extended.omega.max() == 4.0
    for c in (0, 1):
        old = branch.omega.values[branch.connected_component.values == c]
        new = extended.omega.values[extended.connected_component.values == c]
        # the branch inside, once (the points at the join are not repeated), then the rest
        first = int(np.flatnonzero(new == old[0])[0])
        np.testing.assert_array_equal(new[first:first + old.size], old)
        assert np.all(np.diff(new) > 0)
        np.testing.assert_allclose(new[[0, -1]], [0.4, 4.0])
    assert extended.arclength.values[0] == 0.0
    record = json.loads(extended.attrs["options"])
    assert record["bounds"] == [0.4, 4.0] and len(record["extended"]) == 4
    # every special point sits next to the point it names
    p = extended.special_point.values
    lam = extended.omega.values
    assert np.all(np.abs(lam[p] - extended.special_omega.values)
                  <= np.abs(np.diff(lam)).max())


def test_np_branch_restarted_and_extended(branch, switched):
    k = 10
    restarted = continuation_from(switched, k, progress=False)
    assert restarted.sizes["point"] == switched.sizes["point"] - k
    np.testing.assert_allclose(restarted.omega.values, switched.omega.values[k:], rtol=0,
                               atol=TOL)
    np.testing.assert_allclose(restarted.state_k.values, switched.state_k.values[k:], rtol=0,
                               atol=TOL)
    assert restarted.attrs["pattern"] == switched.attrs["pattern"]
    wide = ic.period_doubling_switch(branch, bounds=(1.0, 2.3), max_points=80, progress=False)
    extended = extend(switched, (1.0, 2.3), progress=False)
    _same_specials(extended, wide)
    n = switched.sizes["point"]
    np.testing.assert_array_equal(extended.omega.values[:n], switched.omega.values)
    assert np.all(np.diff(extended.omega.values) > 0)
    assert extended.omega.values[-1] == 2.3
    assert extended.attrs["born_at"] == "PD"


def test_restart_from_a_saved_file(tmp_path, branch, switched):
    for ds in (branch, switched):
        path = tmp_path / f"{ds.attrs['N']}.nc"
        ic.save(ds, path)
        loaded = ic.load(path)
        a = continuation_from(loaded, label="PD", which=-1, progress=False)
        b = continuation_from(ds, label="PD", which=-1, progress=False)
        np.testing.assert_allclose(a.omega.values, b.omega.values, rtol=0, atol=TOL)
        extended = extend(loaded, (0.4, 3.0) if ds is branch else (1.0, 2.2), progress=False)
        ic.save(extended, tmp_path / "extended.nc")
        assert ic.load(tmp_path / "extended.nc").sizes["point"] == extended.sizes["point"]


def test_bad_arguments_are_refused(branch, switched):
    with pytest.raises(TypeError, match=r"branch must be a branch xarray\.Dataset"):
        continuation_from({"omega": 1.0}, 0)
    with pytest.raises(ParameterError, match=r"either point= .* or label="):
        continuation_from(branch)
    with pytest.raises(ParameterError, match=r"either point= .* or label="):
        continuation_from(branch, 3, label="PD")
    with pytest.raises(ParameterError, match=r"point must be an integer index in \[-316"):
        continuation_from(branch, 316)
    with pytest.raises(ParameterError, match="label must be one of"):
        continuation_from(branch, label="XX")
    with pytest.raises(ParameterError, match="which must be an integer index among the "
                                             "branch's 2 PD"):
        continuation_from(branch, label="PD", which=2)
    with pytest.raises(ParameterError, match="along must be"):
        continuation_from(branch, 3, along=0)
    with pytest.raises(ParameterError, match="must contain the restart point"):
        continuation_from(branch, 3, bounds=(2.0, 3.0))
    with pytest.raises(ParameterError, match="bounds must contain the branch's bounds"):
        extend(branch, (0.6, 4.0))
    with pytest.raises(ParameterError, match="bounds must contain the branch's bounds"):
        extend(switched, (1.0, 2.0))
    with pytest.raises(ParameterError, match="bounds must be two numbers"):
        extend(branch, 4.0)
    with pytest.raises(ParameterError, match="not a branch dataset"):
        extend(branch.drop_vars("delta"), (0.4, 4.0))

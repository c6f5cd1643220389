"""The public verbs take a computed motion or an N-p branch as their start (issue 29).

``continuation(motion, ...)`` follows the branch through the motion: an N-1 motion of the
paper's system on the closed form, any other motion (or a parameter the closed form does
not continue) on the N-p path; ``curve(..., start=branch)`` follows a special point of an
N-p branch. Each must give what the specific driver gives, and refuse what the motion
fixes.
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.curves import multi_impact_curve
from impactcont.orbit.multi_impact import MultiImpactOrbit, multi_impact_orbit

BOUNDS = (0.9, 1.7)


@pytest.fixture(scope="module")
def osc() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, eta=0.1, b=0.1, omega=1.2)


@pytest.fixture(scope="module")
def orbit(osc: ic.ImpactOscillator) -> ic.PeriodicOrbit:
    return next(o for o in ic.periodic_orbits(osc, 1) if o.physical)


@pytest.fixture(scope="module")
def motion(osc: ic.ImpactOscillator, orbit: ic.PeriodicOrbit) -> MultiImpactOrbit:
    return multi_impact_orbit(osc, 1, 1, orbit)


@pytest.fixture(scope="module")
def np_branch(motion: MultiImpactOrbit):
    return ic.continuation(motion, parameter="omega", bounds=BOUNDS, progress=False)


def test_an_n1_motion_is_followed_on_the_closed_form(osc, orbit):
    branch = ic.continuation(orbit, parameter="omega", bounds=BOUNDS, progress=False)
    direct = ic.continuation(osc, 1, "omega", BOUNDS, start=osc.omega, root=orbit.root,
                             components="start", progress=False)
    assert "impact" not in branch.dims
    np.testing.assert_array_equal(branch["omega"].values, direct["omega"].values)
    np.testing.assert_array_equal(branch["delta"].values, direct["delta"].values)


def test_an_np_motion_is_followed_on_the_np_path(motion, np_branch):
    direct = multi_impact_continuation(motion, "omega", BOUNDS, progress=False)
    assert "impact" in np_branch.dims
    np.testing.assert_array_equal(np_branch["omega"].values, direct["omega"].values)
    assert list(np_branch["special_label"].values) == list(direct["special_label"].values)


def test_an_element_parameter_of_an_n1_motion_stays_on_the_closed_form(orbit):
    branch = ic.continuation(orbit, parameter="K[1,1]", bounds=(0.9, 1.1), progress=False,
                             max_points=20)
    assert "impact" not in branch.dims
    assert branch.attrs["parameter"] == "K[1,1]"
    at_start = np.flatnonzero(branch["K[1,1]"].values == 1.0)
    assert at_start.size >= 1
    np.testing.assert_allclose(branch["delta"].values[at_start[0]], orbit.delta, rtol=0,
                               atol=1e-12)


@pytest.mark.parametrize(("keyword", "value"), [("N", 2), ("start", 1.2), ("root", 1),
                                                ("components", "other")])
def test_what_the_motion_fixes_is_refused(orbit, keyword, value):
    with pytest.raises(ic.ParameterError, match=keyword):
        ic.continuation(orbit, parameter="omega", bounds=BOUNDS, progress=False,
                        **{keyword: value})


def test_a_motion_outside_the_bounds_is_refused(orbit):
    with pytest.raises(ic.ParameterError, match="outside"):
        ic.continuation(orbit, parameter="omega", bounds=(1.3, 1.7), progress=False)


def test_a_curve_starts_from_an_np_branch(np_branch):
    box = {"omega": BOUNDS, "b": (0.0, 0.3)}
    curve = ic.curve(None, None, "PD", start=np_branch, parameters=("omega", "b"), bounds=box,
                     detect_codim2_points=False, progress=False, max_points=20)
    direct = multi_impact_curve(np_branch, "PD", 0, parameter="b", bounds=box,
                                progress=False, max_points=20)
    np.testing.assert_array_equal(curve["b"].values, direct["b"].values)
    np.testing.assert_array_equal(curve["omega"].values, direct["omega"].values)


def test_a_curve_from_an_np_branch_refuses_another_first_parameter(np_branch):
    with pytest.raises(ic.ParameterError, match="parameters"):
        ic.curve(None, None, "PD", start=np_branch, parameters=("b", "omega"),
                 progress=False)


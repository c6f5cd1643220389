"""Curves in two parameters of the points that bound periodic motions with sticking phases
(issue 30): SE (a stick time through 0), RG (the pressing force touching 0 inside a stick)
and SO (the pressing force 0 at a landing), followed by shooting from a special point of a
branch of such motions (:func:`impactcont.curve`, :class:`~impactcont.problems.codim1.
ShootingCurve`).

Witnesses: the riding damper's SE curve in (omega, eta) against the closed form's end of
the rides at each eta (``studies/sticking_motions/curves.py``: mpmath at 30 digits, the
package's values only as Newton's seed); points of its RG curve against the motion solved
alone there (its smallest pressing force 0) and the simulator (on one side of the curve
it rides the whole stick, on the other it releases early, where the pressing force dips);
an NS curve and an SO curve of the lightly damped damper against the motion solved alone.

About 50 s with the kernels compiled: the branch to the end of the rides (7 s), the SE
curve (3 s), four closed forms; the branch at low omega (5 s) and the RG curve (15 s); the
lightly damped branch (4 s), its NS and SO curves (8 s).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import impactcont as ic
from impactcont.problems.codim1 import ShootingCurve, curve_problem
from impactcont.problems.multi_impact_branch import (
    release_grazing_test,
    stick_end_test,
    sticking_onset_test,
)
from tests._study_files import study_file

#: The end of the rides in omega at eta = 0.3 (closed form, the study's README).
RIDING_END = 2.393422959745478


@pytest.fixture(scope="module")
def study():
    """``studies/sticking_motions/curves.py`` (the closed form's end at any eta, b, m)."""
    with study_file("sticking_motions", "curves.py") as module:
        yield module


@pytest.fixture(scope="module")
def se_curve(study):
    branch = study.ride_branch()
    assert list(branch.special_label.values) == ["SE"]
    return study.se_curve(branch, "eta", (0.25, 0.35), ds_max=0.02)


def test_the_se_curve_is_the_closed_form_end_of_the_rides(study, se_curve):
    """The SE curve of the riding damper in (omega, eta) from the branch's SE point: at
    every fourth point the closed form's end of the rides at that eta (mpmath, 30 digits)
    is the curve's omega to 1e-9 (the curve's Newton tolerance is 1e-10 on a quadratically
    converging step; seen: 4.4e-16). The curve starts at the branch's SE (omega
    2.393422959745478 at eta 0.3) and runs to both edges of the eta box; the stick time
    it follows is 0 at every point (the other one too: the motion is symmetric), and so is
    the landing pressing force (the landing is the release)."""
    ds = se_curve
    assert ds.attrs["curve_kind"] == "SE" and ds.attrs["parameters"] == "omega,eta"
    message = json.loads(ds.attrs["options"])["message"]
    assert message.count("parameter bound reached") == 2, message
    eta = ds["eta"].values
    assert eta.min() == pytest.approx(0.25, abs=1e-12)
    assert eta.max() == pytest.approx(0.35, abs=1e-12)
    start = int(np.argmin(np.abs(eta - 0.3)))
    assert eta[start] == pytest.approx(0.3, abs=1e-14)
    assert ds["omega"].values[start] == pytest.approx(RIDING_END, abs=1e-9)
    assert np.abs(ds["stick_time_k"].values).max() < 1e-10
    for k in range(0, ds.sizes["point"], 4):
        omega, value = float(ds["omega"].values[k]), float(eta[k])
        end = study.riding_end_at("eta", value, (*study.upper_release(ds, k), omega))
        assert omega == pytest.approx(float(end), abs=1e-9), (value, omega, float(end))
    # the omega of the end falls as the damping grows (the rides end earlier)
    order = np.argsort(eta)
    assert np.all(np.diff(ds["omega"].values[order]) < 0)
    # its crossing of eta = 0.31 solved on the curve (from the stored stick times) is the
    # closed form's end there
    (crossing,) = ic.curve_crossings(ds, "eta", 0.31)
    k = crossing["point"]
    end = study.riding_end_at("eta", 0.31, (*study.upper_release(ds, k), crossing["omega"]))
    assert crossing["omega"] == pytest.approx(float(end), abs=1e-9)


def test_the_se_curve_point_is_a_zero_of_the_branch_tests(study, se_curve):
    """At a point of the SE curve the motion solved alone (multi_impact_orbit) has its
    sticks of length 0 (stick_end_test) and its landings pressing 0 (sticking_onset_test,
    the landing is the release) to 1e-9."""
    ds = se_curve
    k = ds.sizes["point"] - 1
    osc = study.damper(float(ds["omega"].values[k]), eta=float(ds["eta"].values[k]))
    orbit = ic.multi_impact_orbit(osc, 1, 2, {
        "delta": float(ds["delta_k"].values[k, 0]), "flight_times": ds["flight_time_k"].values[k],
        "stick_times": ds["stick_time_k"].values[k], "states": ds["state_k"].values[k],
        "pattern": ds.attrs["pattern"]})
    assert stick_end_test(orbit) == pytest.approx(0.0, abs=1e-9)
    assert sticking_onset_test(orbit) == pytest.approx(0.0, abs=1e-9)


@pytest.fixture(scope="module")
def rg_curve(study):
    """The RG curve of the riding damper in (omega, eta) near omega 0.052, from the branch
    in omega started on the closed form's motion at omega = 0.055."""
    cf = study.closed_form()
    motion = cf.riding_damper_motion(0.055)
    start = ic.multi_impact_orbit(study.damper(0.055), 1, 2, {
        "delta": float(motion.floats("phases")[0]),
        "flight_times": np.array(motion.floats("flight_times")),
        "stick_times": np.array(motion.floats("stick_times")),
        "states": np.array(motion.floats("landing_states")), "pattern": motion.pattern})
    branch = ic.continuation(start, parameter="omega", bounds=(0.05, 0.056), ds=0.5,
                             ds_max=2.0)
    assert list(branch.special_label.values) == ["RG"]
    return ic.curve(None, None, "RG", start=branch, parameters=("omega", "eta"),
                    bounds={"omega": (0.02, 0.2), "eta": (0.295, 0.315)}, ds_max=0.02)


def _motion(study, ds, k: int, factor: float = 1.0):
    """The motion solved alone at curve point `k` (omega scaled by `factor`)."""
    osc = study.damper(float(ds["omega"].values[k]) * factor, eta=float(ds["eta"].values[k]))
    return osc, ic.multi_impact_orbit(osc, 1, 2, {
        "delta": float(ds["delta_k"].values[k, 0]), "flight_times": ds["flight_time_k"].values[k],
        "stick_times": ds["stick_time_k"].values[k], "states": ds["state_k"].values[k],
        "pattern": ds.attrs["pattern"]})


def test_on_the_rg_curve_the_pressing_force_touches_zero(study, rg_curve):
    """At three points of the RG curve the motion solved alone (multi_impact_orbit, whose
    pressing minimum is the sampled and refined one of the held flow) has its smallest
    pressing force 0 to 1e-9 (its scale: 5e-8 at omega moved by 1e-4), with rides of
    about 30 time units."""
    ds = rg_curve
    message = json.loads(ds.attrs["options"])["message"]
    assert message.count("parameter bound reached") == 2, message
    assert ds.sizes["point"] >= 5
    assert np.abs(ds["pressing_min_k"].values).max() < 1e-9
    for k in (0, ds.sizes["point"] // 2, ds.sizes["point"] - 1):
        _, orbit = _motion(study, ds, k)
        assert release_grazing_test(orbit) == pytest.approx(0.0, abs=1e-9)
        assert np.all(orbit.stick_times > 20.0)
        _, off = _motion(study, ds, k, 1.0 + 1e-4)
        assert release_grazing_test(off) > 1e-8  # the dip is the curve's own zero


def test_the_simulator_releases_early_on_one_side_of_the_rg_curve(study, rg_curve):
    """The simulator (its own sticking model, no shooting code) from the landing of the
    motion near the middle of the RG curve: with omega 1e-4 above the curve it rides the
    whole stick the shooting solved (to 1e-6); 1e-4 below it releases where the pressing
    force dips through 0, long before (at the followed interior minimum's time within 2%:
    the dip's zeros are sqrt(1e-4) apart around it), lands again and rides on."""
    ds = rg_curve
    k = ds.sizes["point"] // 2
    problem = curve_problem("RG", study.damper(float(ds["omega"].values[k]),
                                               eta=float(ds["eta"].values[k])), 1,
                            ("omega", "eta"), p=2, pattern=ds.attrs["pattern"])
    for factor, whole in ((1.0 + 1e-4, True), (1.0 - 1e-4, False)):
        osc, orbit = _motion(study, ds, k, factor)
        res = ic.simulate(osc, orbit.states[0], orbit.phases[0], periods=1.0)
        first = res.sticking[0]
        assert first.start == 0.0 and first.ended_by == "release"
        if whole:
            assert first.end == pytest.approx(orbit.stick_times[0], rel=1e-6)
        else:
            x = np.append(orbit.unknowns, osc.omega)
            t_star = problem.minimum_time(x, osc.eta)
            assert first.end < 0.5 * orbit.stick_times[0]
            assert first.end == pytest.approx(t_star, rel=2e-2)


def test_sticking_kinds_are_refused_on_motions_without_sticking_phases():
    """SE, RG and SO bound motions with sticking phases: a curve of a plain N-p motion or
    of an N-1 motion in closed form is refused, naming where their curves are; a motion
    with sticking phases is not followed by its half."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.6,
                              omega=1.0, eta=0.1)
    with pytest.raises(ic.ParameterError, match="bounds motions with sticking phases"):
        ShootingCurve(osc, 1, 1, "U", "SE", ("omega", "b"), symmetric=False)
    for kind in ("SE", "RG", "SO"):
        with pytest.raises(ic.ParameterError, match="curves of motions with sticking phases"):
            ic.curve(osc, 1, kind, start={"omega": 1.0, "b": 0.6}, bounds={
                "omega": (0.5, 2.0), "b": (0.1, 1.0)})


@pytest.fixture(scope="module")
def light_branch(study):
    """The lightly damped riding damper (eta = 0.02) from its simulated steady state at
    omega 0.5, followed down in omega: SO (with RG: the landing's pressing force is the
    smallest) near 0.3245 and 0.3184, NS near 0.2952."""
    osc = study.damper(0.5, eta=0.02)
    start = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.array([0.0, 0.3, 0.0, 0.0]),
                                                          0.0, 60.0))
    assert start.pattern == "ul" and start.physical
    return ic.continuation(start, parameter="omega", bounds=(0.28, 0.5), ds_max=0.05,
                           both_directions=False, direction=-1)


def test_an_ns_curve_of_a_motion_with_sticking_phases(study, light_branch):
    """An NS curve of the sticky motion comes for free (the sticky G, its exact dF/du, the
    column in eta from the problem in eta): from the branch's NS in (omega, eta), eta in
    (0.018, 0.022), the motion solved alone at three of its points has its complex pair on
    the unit circle to 1e-7 (the stick's multipliers 0 to 1e-12)."""
    ds = ic.curve(None, None, "NS", start=light_branch, parameters=("omega", "eta"),
                  bounds={"omega": (0.1, 1.0), "eta": (0.018, 0.022)}, ds_max=0.02)
    message = json.loads(ds.attrs["options"])["message"]
    assert message.count("parameter bound reached") == 2, message
    for k in (0, ds.sizes["point"] // 2, ds.sizes["point"] - 1):
        _, orbit = _motion(study, ds, k)
        mu = np.sort(np.abs(orbit.multipliers))[::-1]
        assert mu[:2] == pytest.approx([1.0, 1.0], abs=1e-7)
        assert abs(orbit.multipliers[0].imag) > 0.1 and mu[2:].max() < 1e-12


def test_an_so_curve_has_its_landing_pressing_zero(study, light_branch):
    """The SO curve from the branch's first SO (eta 0.018 to 0.022): the motion solved alone
    at three of its points lands with pressing force 0 (sticking_onset_test) to 1e-9."""
    ds = ic.curve(None, None, "SO", start=light_branch, parameters=("omega", "eta"),
                  bounds={"omega": (0.1, 1.0), "eta": (0.018, 0.022)}, ds_max=0.02)
    message = json.loads(ds.attrs["options"])["message"]
    assert "parameter bound reached" in message, message
    for k in (0, ds.sizes["point"] // 2, ds.sizes["point"] - 1):
        _, orbit = _motion(study, ds, k)
        assert sticking_onset_test(orbit) == pytest.approx(0.0, abs=1e-9)

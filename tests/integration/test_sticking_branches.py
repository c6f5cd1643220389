"""Branches of periodic motions with sticking phases (issue 30 item 4): continuation of
the impact damper whose plastic ball rides each wall (pattern ``"lu"``), held against the
closed form of ``studies/sticking_motions/closed_form.py`` (mpmath, imports nothing from
the package) and against :func:`impactcont.multi_impact_orbit` solved alone.

The branch in omega (from 0.2) costs about 3 s; each closed-form motion about 1 s.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.problems.multi_impact_branch import (
    STICKING_EVENTS,
    STICKING_TESTS,
    MultiImpactBranchProblem,
    release_grazing_test,
)
from tests._study_files import study_file

#: Where the closed form puts the end of the ride in omega (the landing is a release;
#: studies/sticking_motions/README.md, closed_form.riding_end).
RIDING_END = 2.393422959745478


@pytest.fixture(scope="module")
def cf():
    with study_file("sticking_motions", "closed_form.py") as module:
        yield module


def damper(omega: float, **more) -> ic.ImpactOscillator:
    """Case (c) of the study: primary 1 on spring 1 (eta 0.3), plastic ball 0.2 in
    |x2 - x1| <= 0.3."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True), **more)


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


@functools.cache
def riding(omega: float = 0.2):
    osc = damper(omega)
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 12.0))


@functools.cache
def branch():
    """The riding motion followed in omega from 0.2 past the end of its ride (its special
    points by default: SE, RG and SO among them)."""
    return ic.continuation(riding(), parameter="omega", bounds=(0.19, 2.45), ds_max=0.1,
                           both_directions=False)


def test_the_branch_in_omega_is_the_closed_form_and_the_solve_alone(cf):
    """Points of the branch: the closed form (two omegas) and multi_impact_orbit solved
    alone from a simulated steady state (two omegas), every quantity to 1e-9; the
    stick time falls to 0 at the end of the ride, and the motion is physical up to it."""
    ds = branch()
    assert ds.attrs["pattern"] == "lu"
    omega = ds.omega.values
    assert omega[0] == pytest.approx(0.2) and omega[-1] == pytest.approx(2.45)
    physical = ds.physical.values
    inside = omega < RIDING_END - 1e-3
    assert physical[inside].all() and not physical[omega > RIDING_END + 1e-3].any()
    for target in (0.5, 1.2):
        i = int(np.argmin(np.abs(omega - target)))
        motion = cf.riding_damper_motion(float(omega[i]))
        assert np.abs(np.remainder(ds.delta_k.values[i] - np.array(motion.floats("phases"))
                                   + np.pi, 2 * np.pi) - np.pi).max() < 1e-9
        assert ds.flight_time_k.values[i] == pytest.approx(motion.floats("flight_times"),
                                                           abs=1e-9)
        assert ds.state_k.values[i] == pytest.approx(np.array(motion.floats("landing_states")),
                                                     abs=1e-9)
        exact = sorted((complex(z) for z in motion.multipliers), key=lambda z: -abs(z))
        assert np.sort(np.abs(ds.multipliers.values[i]))[::-1][:2] == pytest.approx(
            [abs(z) for z in exact[:2]], abs=1e-9)
    for target in (0.7, 2.3):  # from the simulated steady state, its impacts rolled
        i = int(np.argmin(np.abs(omega - target)))
        osc = damper(float(omega[i]))
        alone = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0,
                                                             16.0))
        assert sorted(alone.pattern) == ["l", "u"] and alone.physical, alone.reason
        k = -alone.pattern.index("l")  # impact 0 of the branch is on the lower wall
        assert ds.flight_time_k.values[i] == pytest.approx(np.roll(alone.flight_times, k),
                                                           abs=1e-9)
        assert ds.state_k.values[i] == pytest.approx(np.roll(alone.states, k, axis=0),
                                                     abs=1e-9)
        assert np.sort_complex(ds.multipliers.values[i]) == pytest.approx(
            np.sort_complex(alone.multipliers), abs=1e-9)
        assert ds.impact_velocity_k.values[i] == pytest.approx(
            np.roll(alone.impact_velocities, k), abs=1e-9)
        period = 2 * math.pi / omega[i]
        assert np.sum(ds.flight_time_k.values[i]) < period  # the rest is the two rides


def test_the_branch_saves_and_loads_with_its_pattern(tmp_path):
    """A branch of motions with sticking phases round-trips through NetCDF, its lowercase
    pattern kept (the dataset checks refused it before)."""
    ds = branch()
    path = tmp_path / "riding.nc"
    ic.save(ds, path)
    back = ic.load(path)
    assert back.attrs["pattern"] == "lu"
    for name in ("flight_time_k", "stick_time_k", "pressing_min_k", "release_state_k"):
        assert np.array_equal(back[name].values, ds[name].values, equal_nan=True), name


def test_the_branch_stores_the_stick_times_and_pressing_minima(cf):
    """stick_time_k, pressing_min_k and release_state_k per point: each period is the two
    rides and the two flights, and at omega near 1.2 they are the closed form's."""
    ds = branch()
    omega = ds.omega.values
    period = ds.stick_time_k.values.sum(axis=1) + ds.flight_time_k.values.sum(axis=1)
    assert period == pytest.approx(2 * np.pi / omega, rel=1e-13)
    i = int(np.argmin(np.abs(omega - 1.2)))
    motion = cf.riding_damper_motion(float(omega[i]))
    for name, theirs in (("stick_time_k", "stick_times"), ("pressing_min_k", "pressing_min"),
                         ("release_state_k", "release_states")):
        assert ds[name].values[i] == pytest.approx(np.array(motion.floats(theirs)),
                                                   abs=1e-9), name


def test_a_parameter_that_unmakes_the_plastic_stop_is_refused():
    """R moves the restitution of both (mirrored) walls the ball sticks on: the held system
    exists at R = 0 only; b and eta are continued."""
    with pytest.raises(ParameterError, match=r"parameter 'R' changes the restitution of "
                       r"stop\(s\) \['L', 'U'\].*on which the motion sticks"):
        MultiImpactBranchProblem(damper(1.0), 1, 2, "R", pattern="lu")
    for parameter in ("b", "eta"):
        problem = MultiImpactBranchProblem(damper(1.0), 1, 2, parameter, pattern="lu")
        assert problem.size == 2 * 2 * 2 + 2


def test_the_ride_ends_at_the_closed_forms_omega():
    """(a) The stick time through 0, located on the branch as its special point SE without
    events=: omega* = 2.393422959745478 of the closed form (landing = release) within the
    locator's precision. The landing's pressing force and the smallest one inside the
    stick vanish there too (the landing is a release: one point, three tests), reported
    once, as SE."""
    ds = branch()
    labels = list(ds.special_label.values)
    assert labels == ["SE"]
    assert ds.special_status.values[0] == "located"
    precision = float(ds.special_precision.values[0])
    assert precision < 1e-11
    assert abs(float(ds.special_omega.values[0]) - RIDING_END) <= max(2 * precision, 1e-13)
    shortest = ds.stick_time_k.values.min(axis=1)
    i = int(ds.special_point.values[0])
    assert abs(shortest[i]) < 0.05  # the nearest point's shortest stick
    assert np.all(shortest[ds.omega.values < RIDING_END] > 0)
    assert np.all(shortest[ds.omega.values > RIDING_END] < 0)
    assert float(ds.special_stick_time_k.values[0].min()) == pytest.approx(0.0, abs=1e-9)


def test_the_sticking_events_are_not_located_twice():
    """STICKING_EVENTS passed as events= on a branch that detects SE, RG and SO: kept as
    monitors (their values at every point) with a DeprecationWarning, the point reported
    once, as the special point SE; with detect=[] they are still the user's events."""
    start = riding_at(2.3)
    with pytest.warns(DeprecationWarning, match=r"events \['release_grazing', 'stick_end', "
                      r"'sticking_onset'\] are the tests of the special points"):
        ds = ic.continuation(start, parameter="omega", bounds=(2.29, 2.45),
                             both_directions=False, events=STICKING_EVENTS)
    assert list(ds.special_label.values) == ["SE"]
    assert "event_name" not in ds or ds.sizes.get("event", 0) == 0
    assert np.array_equal(ds.monitor_stick_end.values, ds.stick_time_k.values.min(axis=1))
    only = ic.continuation(start, parameter="omega", bounds=(2.29, 2.45),
                           both_directions=False, events=STICKING_EVENTS, detect=[])
    assert only.sizes.get("special", 0) == 0
    names = list(only.event_name.values)
    assert sorted(names) == ["release_grazing", "stick_end", "sticking_onset"]
    assert abs(float(only.event_omega.values[names.index("stick_end")]) - RIDING_END) < 1e-11


def test_release_grazing_where_the_pressing_force_touches_zero_inside_a_ride(cf):
    """(b) Below omega = 0.1 the wall's pressing force dips inside each ride: it touches
    0 at a release grazing, located on the branch (from the closed form's motion at
    omega = 0.055) as its special point RG without events= (the zero of
    release_grazing_test), the stick time still long; the
    closed form there has its smallest pressing force 0 (to 1e-9, against 3e-5 at 0.055
    and 1e-2 at omega = 0.2)."""
    motion = cf.riding_damper_motion(0.055)
    start = ic.multi_impact_orbit(damper(0.055), 1, 2, {
        "delta": float(motion.floats("phases")[0]),
        "flight_times": np.array(motion.floats("flight_times")),
        "stick_times": np.array(motion.floats("stick_times")),
        "states": np.array(motion.floats("landing_states")), "pattern": motion.pattern})
    assert start.physical, start.reason
    ds = ic.continuation(start, parameter="omega", bounds=(0.05, 0.056), ds=0.5, ds_max=2.0)
    assert list(ds.special_label.values) == ["RG"]
    omega = float(ds.special_omega.values[0])
    assert 0.05 < omega < 0.055 and ds.special_status.values[0] == "located"
    assert release_grazing_test(ic.multi_impact_orbit(damper(omega), 1, 2, start)) \
        == pytest.approx(0.0, abs=1e-9)
    i = int(ds.special_point.values[0])
    assert np.all(ds.stick_time_k.values[i] > 20)
    assert not ds.physical.values[ds.omega.values < omega].any()
    assert ds.physical.values[ds.omega.values > omega].all()
    there = cf.riding_damper_motion(omega)
    assert np.abs(np.array(there.floats("pressing_min"), dtype=float)).max() < 1e-9
    problem = MultiImpactBranchProblem(damper(0.2), 1, 2, "omega", pattern="lu")
    assert set(problem.motion_tests) >= set(STICKING_TESTS)
    assert set(problem.events) >= set(STICKING_TESTS)  # declared: located by default
    assert not set(MultiImpactBranchProblem.events) & set(STICKING_TESTS)  # plain branches


def test_neimark_sacker_on_a_branch_with_sticking_phases():
    """The lightly damped impact damper (eta = 0.02) riding each wall: a complex pair of
    the sticky G crosses the unit circle near omega = 0.295, detected and located as NS
    on the branch; multi_impact_orbit solved alone there has that pair on the circle."""
    osc = damper(0.5).replace(eta=0.02)
    start = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.array([0.0, 0.3, 0.0,
                                                                          0.0]), 0.0, 60.0))
    assert start.pattern == "ul" and start.physical
    ds = ic.continuation(start, parameter="omega", bounds=(0.28, 0.5), ds_max=0.05,
                         both_directions=False, direction=-1)
    labels = list(ds.special_label.values)
    assert "NS" in labels
    k = labels.index("NS")
    at = float(ds.special_omega.values[k])
    assert 0.29 < at < 0.30 and ds.special_status.values[k] == "located"
    i = int(ds.special_point.values[k])
    seed = {"delta": float(ds.delta_k.values[i, 0]), "flight_times": ds.flight_time_k.values[i],
            "stick_times": ds.stick_time_k.values[i], "states": ds.state_k.values[i],
            "pattern": "ul"}
    alone = ic.multi_impact_orbit(osc.replace(omega=at), 1, 2, seed)
    mu = np.sort(np.abs(alone.multipliers))[::-1]
    assert mu[:2] == pytest.approx([1.0, 1.0], abs=1e-7)
    assert np.abs(alone.multipliers[0].imag) > 0.1 and mu[2:].max() < 1e-12


@functools.cache
def riding_at(omega: float):
    osc = damper(omega)
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 16.0))


@pytest.mark.parametrize(("parameter", "bounds"), [("b", (0.27, 0.33)), ("eta", (0.27, 0.33)),
                                                   ("m2", (0.19, 0.21))])
def test_the_riding_motion_in_other_parameters_is_the_solve_alone(parameter, bounds):
    """The walls' position (both move: mirrored stops), the damping and the ball's mass:
    each branch's points are multi_impact_orbit solved alone at their parameter, seeded by
    the branch's start (1e-10)."""
    start = riding_at(1.2)
    ds = ic.continuation(start, parameter=parameter, bounds=bounds)
    values = ds[parameter].values
    assert values.min() == pytest.approx(bounds[0]) and values.max() == pytest.approx(bounds[1])
    assert ds.physical.values.all()
    param = model_parameter(start.oscillator, parameter)
    for i in (0, len(values) - 1):
        alone = ic.multi_impact_orbit(param.at(start.oscillator, float(values[i])), 1, 2,
                                      start)
        assert alone.pattern == ds.attrs["pattern"] and alone.physical, alone.reason
        for name, mine in (("flight_time_k", alone.flight_times),
                           ("stick_time_k", alone.stick_times), ("state_k", alone.states)):
            assert ds[name].values[i] == pytest.approx(mine, abs=1e-10), name


def test_the_end_of_a_ride_is_drawn_with_its_marker_and_named_in_the_legend():
    """The SE of a branch near the end of the ride (from omega 2.3): located as detect=
    asks, drawn in the bifurcation diagram with its own marker (X) and named in the
    legend in its words."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from impactcont.plots import bifurcation_diagram

    ds = ic.continuation(riding_at(2.3), parameter="omega", bounds=(2.29, 2.45),
                         both_directions=False, detect=["SE"])
    assert list(ds.special_label.values) == ["SE"]
    ax = bifurcation_diagram(ds)
    try:
        markers = [line.get_marker() for line in ax.get_lines()]
        assert markers.count("X") == 1
        legend = [text.get_text() for text in ax.get_legend().get_texts()]
        assert "SE end of a sticking phase" in legend
    finally:
        plt.close(ax.figure)

"""User-defined events and monitors on branches and curves (``events=``, ``monitors=``),
located by :mod:`impactcont.detection.special_points`.

Every located event is checked independently: the closed form (``periodic_orbits``) or a
Newton re-solve of the N-p motion at the located parameters, and a dense time series for
displacement events. Tolerances are what the locator claims (``event_precision``) times
the slope of the function, never the last digits. Every location, folds included, lies
in its bracket.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.branch import continuation_from
from impactcont.analysis.curves import multi_impact_curve
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.extrema import max_displacement, min_displacement

K2 = [[1.0, -1.0], [-1.0, 2.0]]


V_LEVEL = 0.7   # impact velocity of the events below


X2_LEVEL = 0.0  # largest x2 of the N-1 displacement event


def paper(**kw) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, **kw)


def velocity_event(orbit) -> float:
    return orbit.impact_velocity - V_LEVEL


def x2_event(orbit) -> float:
    return max_displacement(orbit, 2) - X2_LEVEL


@pytest.fixture(scope="module")
def n1_branch():
    return ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 2.0), components="start",
                           events={"v07": velocity_event, "x2top": x2_event},
                           monitors={"omega_again": lambda o: o.oscillator.omega,
                                     "x1min": lambda o: min_displacement(o, 1)},
                           progress=False)


@pytest.fixture(scope="module")
def symmetric_branch():
    """Symmetric 1-2 motions between mirrored stops (followed by their half)."""
    osc = paper(b=0.5, omega=1.6, stops=Stops(mirror=True))
    start = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    return ic.multi_impact_continuation(
        start, "omega", (1.3, 1.7), both_directions=True, ds_max=0.02, progress=False,
        events={"v07": velocity_event, "x2top": lambda o: max_displacement(o, 2) - 0.6},
        monitors={"x2max": lambda o: max_displacement(o, 2)})


def rows(ds, name):
    return np.flatnonzero(ds["event_name"].values == name)


def crossings(values, level):
    """The steps k where the stored values cross `level` between points k and k + 1."""
    side = np.asarray(values) < level
    return np.flatnonzero(side[:-1] != side[1:])


def nearest_root(osc, delta):
    return min(ic.periodic_orbits(osc, 1),
               key=lambda o: abs(math.remainder(o.delta - delta, 2 * math.pi)))


# -- N-1 branches -------------------------------------------------------------------------------
def test_velocity_event_on_an_n1_branch_is_where_the_closed_form_crosses(n1_branch):
    ds = n1_branch
    assert ds.attrs["user_events"] == "v07,x2top"
    steps = crossings(ds["impact_velocity"].values, V_LEVEL)
    found = rows(ds, "v07")
    assert steps.size >= 1 and found.size == steps.size
    omega = ds["omega"].values
    for k, row in zip(steps, found, strict=True):
        w = float(ds["event_omega"].values[row])
        precision = float(ds["event_precision"].values[row])
        assert ds["event_status"].values[row] == "located" and precision < 1e-9
        assert min(omega[k], omega[k + 1]) <= w <= max(omega[k], omega[k + 1])
        assert ds["event_point"].values[row] in (k, k + 1)
        # the closed form at the located frequency: impact velocity at the level, within
        # the slope times the precision claimed
        orbit = nearest_root(paper(b=0.0, omega=w), float(ds["event_delta"].values[row]))
        slope = abs((ds["impact_velocity"].values[k + 1] - ds["impact_velocity"].values[k])
                    / (omega[k + 1] - omega[k]))
        assert abs(orbit.impact_velocity - V_LEVEL) <= 10 * slope * precision + 1e-12


def test_displacement_event_on_an_n1_branch_against_a_dense_evaluation(n1_branch):
    ds = n1_branch
    steps = crossings(ds["monitor_x2top"].values, 0.0)
    found = rows(ds, "x2top")
    assert steps.size >= 1 and found.size == steps.size
    for row in found:
        assert ds["event_status"].values[row] == "located"
        w = float(ds["event_omega"].values[row])
        orbit = nearest_root(paper(b=0.0, omega=w), float(ds["event_delta"].values[row]))
        _, X = orbit.time_series(num=40001)
        # the sampled maximum is below the true one by at most h^2/8 |x2''|
        h = orbit.period / 40000
        assert -2 * h * h <= X[:, 1].max() - X2_LEVEL <= 1e-9


def test_monitors_are_stored_at_every_point(n1_branch):
    ds = n1_branch
    assert ds.attrs["user_monitors"] == "omega_again,x1min"
    np.testing.assert_array_equal(ds["monitor_omega_again"].values, ds["omega"].values)
    # an event function is a monitor too
    np.testing.assert_array_equal(ds["monitor_v07"].values,
                                  ds["impact_velocity"].values - V_LEVEL)
    for i in (0, ds.sizes["point"] // 2, -1):
        orbit = nearest_root(paper(b=0.0, omega=float(ds["omega"].values[i])),
                             float(ds["delta"].values[i]))
        assert ds["monitor_x1min"].values[i] == pytest.approx(min_displacement(orbit, 1),
                                                              abs=1e-9)
    assert ic.dataset.point_table(ds)["monitor_x1min"].size == ds.sizes["point"]


def test_a_branch_without_user_functions_has_no_event_dimension(n1_branch):
    plain = ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 1.5),
                            components="start", progress=False)
    assert "event" not in plain.dims and "user_events" not in plain.attrs
    none_found = ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 1.5),
                                 components="start", progress=False,
                                 events={"never": lambda o: 1.0})
    assert none_found.sizes["event"] == 0 and none_found.attrs["user_events"] == "never"


# -- N-p branches ------------------------------------------------------------------------------
def test_events_on_a_symmetric_n_p_branch_against_newton_re_solves(symmetric_branch):
    ds = symmetric_branch
    assert ds.attrs["impacts"] == 2 and '"symmetric": true' in ds.attrs["options"]
    for name, column, level in (("v07", ds["impact_velocity"].values, V_LEVEL),
                                ("x2top", ds["monitor_x2max"].values, 0.6)):
        steps, found = crossings(column, level), rows(ds, name)
        assert steps.size >= 1 and found.size == steps.size
        for k, row in zip(steps, found, strict=True):
            w = float(ds["event_omega"].values[row])
            precision = float(ds["event_precision"].values[row])
            assert ds["event_status"].values[row] == "located" and precision < 1e-9
            # the full motion re-solved by Newton at the located frequency
            osc = ic.dataset.oscillator_from_dataset(ds, int(k)).replace(omega=w)
            motion = ic.multi_impact_orbit(osc, 1, 2, {
                "delta": float(ds["delta_k"].values[k, 0]),
                "flight_times": ds["flight_time_k"].values[k],
                "states": ds["state_k"].values[k], "pattern": ds.attrs["pattern"]})
            slope = abs((column[k + 1] - column[k]) / (ds["omega"].values[k + 1]
                                                       - ds["omega"].values[k]))
            if name == "v07":
                assert abs(motion.impact_velocity - V_LEVEL) <= 10 * slope * precision + 1e-10
            else:
                _, X = motion.time_series(num=20001)
                h = float(np.max(motion.flight_times)) / 20000
                assert -2 * h * h - 1e-10 <= X[:, 1].max() - 0.6 <= 10 * slope * precision \
                    + 1e-10


def test_n_p_branch_of_n1_motions_locates_the_n1_event():
    """The N-1 motions followed by shooting (p = 1): the same event as the closed form's."""
    osc = paper(b=0.0, omega=1.5)
    closed = ic.continuation(osc, 1, "omega", (1.4, 2.0), components="start",
                             events={"v07": velocity_event}, progress=False)
    start = ic.multi_impact_orbit(osc, 1, 1, next(o for o in ic.periodic_orbits(osc, 1)
                                                  if o.physical))
    shot = ic.multi_impact_continuation(start, "omega", (1.4, 2.0), both_directions=True,
                                        events={"v07": velocity_event}, progress=False)
    assert closed.sizes["event"] == shot.sizes["event"] >= 1
    np.testing.assert_allclose(np.sort(shot["event_omega"].values),
                               np.sort(closed["event_omega"].values), rtol=0, atol=1e-9)
    # restarted from its first point both ways: the same event
    again = continuation_from(shot, point=0, along=None, events={"v07": velocity_event},
                              progress=False)
    np.testing.assert_allclose(np.sort(again["event_omega"].values),
                               np.sort(closed["event_omega"].values), rtol=0, atol=1e-9)


# -- curves ------------------------------------------------------------------------------------
def test_events_on_the_pd_curves_of_n1_and_n_p_motions():
    osc = paper(b=0.0, omega=1.75)
    box = {"omega": (1.0, 3.0), "b": (-0.2, 0.3)}
    events = {"v06": lambda o: o.impact_velocity - 0.6}
    branch = ic.continuation(osc, 1, "omega", (1.6, 1.9), detect=("PD",), progress=False)
    cv = ic.curve(None, None, "PD", start=branch, bounds=box, events=events,
                  monitors={"v": lambda o: o.impact_velocity}, progress=False)
    np.testing.assert_array_equal(cv["monitor_v"].values, cv["impact_velocity"].values)
    assert cv.sizes["event"] == crossings(cv["impact_velocity"].values, 0.6).size == 1
    assert cv["event_status"].values[0] == "located"
    precision = float(cv["event_precision"].values[0])
    w, b = float(cv["event_omega"].values[0]), float(cv["event_b"].values[0])
    assert precision < 1e-9
    # the closed form there: a motion with that impact velocity and a multiplier -1
    orbit = nearest_root(paper(b=b, omega=w), float(cv["event_delta"].values[0]))
    assert abs(orbit.impact_velocity - 0.6) < 1e-8
    assert np.min(np.abs(orbit.multipliers + 1.0)) < 1e-6
    # the same curve followed by shooting (p = 1) meets it at the same point
    physical = next(q for q in ic.periodic_orbits(osc, 1) if q.physical)
    shot = ic.multi_impact_continuation(ic.multi_impact_orbit(osc, 1, 1, physical), "omega",
                                        (1.6, 1.9), detect=("PD",), both_directions=True,
                                        progress=False)
    mc = multi_impact_curve(shot, "PD", 0, parameter="b", bounds=box, events=events,
                            progress=False)
    assert mc.sizes["event"] == 1 and mc["event_status"].values[0] == "located"
    assert abs(float(mc["event_omega"].values[0]) - w) < 1e-8
    assert abs(float(mc["event_b"].values[0]) - b) < 1e-8


# -- files -------------------------------------------------------------------------------------
def test_save_load_round_trip(n1_branch, symmetric_branch, tmp_path):
    for name, ds in (("n1", n1_branch), ("np", symmetric_branch)):
        path = tmp_path / f"{name}.nc"
        ic.save(ds, path)
        back = ic.load(path)
        assert back.attrs["user_events"] == ds.attrs["user_events"]
        assert back.attrs["user_monitors"] == ds.attrs["user_monitors"]
        for var in [k for k in ds.variables if str(k).startswith(("event_", "monitor_"))]:
            np.testing.assert_array_equal(back[var].values, ds[var].values)
            assert back[var].dims == ds[var].dims
        ic.dataset.validate_branch_dataset(back)


def test_validation_refuses_bad_user_variables(n1_branch):
    bad = n1_branch.copy()
    bad["event_status"] = ("event", np.full(bad.sizes["event"], "unknown"))
    with pytest.raises(ValueError, match="event_status"):
        ic.dataset.validate_branch_dataset(bad)
    bad = n1_branch.copy()
    bad["event_name"] = ("event", np.full(bad.sizes["event"], "other"))
    with pytest.raises(ValueError, match="event_name"):
        ic.dataset.validate_branch_dataset(bad)
    with pytest.raises(ValueError, match="monitor_x1min"):
        ic.dataset.validate_branch_dataset(n1_branch.drop_vars("monitor_x1min"))


def test_extend_keeps_the_events_in_branch_order(n1_branch):
    short = ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 1.7),
                            components="start", events={"v07": velocity_event}, progress=False)
    longer = ic.extend(short, (1.4, 2.0), events={"v07": velocity_event}, progress=False)
    np.testing.assert_allclose(np.sort(longer["event_omega"].values),
                               np.sort(n1_branch["event_omega"].values[rows(n1_branch, "v07")]),
                               rtol=0, atol=1e-9)
    omega = longer["omega"].values
    for row, k in enumerate(longer["event_point"].values):  # the nearest point, re-indexed
        assert abs(omega[k] - longer["event_omega"].values[row]) <= np.max(np.diff(omega))
    with pytest.raises(ParameterError, match=r"events must have the names .*\['v07'\]"):
        ic.extend(short, (1.4, 2.0), progress=False)


# -- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize(("events", "monitors", "error", "match"), [
    ({"PD": velocity_event}, None, ParameterError, "'PD' is a special-point label"),
    ({"gr": velocity_event}, None, ParameterError, "'gr' is a special-point label"),
    (None, {"R1": velocity_event}, ParameterError, "'R1' is a special-point label"),
    (None, {"impact_velocity": velocity_event}, ParameterError, "built-in variable"),
    (None, {"omega": velocity_event}, ParameterError, "built-in variable"),
    ({"x 2": velocity_event}, None, ParameterError, "a name must be a letter"),
    ({"v": velocity_event}, {"v": velocity_event}, ParameterError, "share the name"),
    ([velocity_event], None, TypeError, "events must be a mapping"),
    (None, {"v": 0.7}, TypeError, r"monitors\['v'\] must be a function"),
])
def test_bad_names_and_functions_are_refused(events, monitors, error, match):
    with pytest.raises(error, match=match):
        ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 1.5), events=events,
                        monitors=monitors, progress=False)


def _boom(orbit):
    raise ZeroDivisionError("no")


@pytest.mark.parametrize(("function", "error", "match"), [
    (_boom, ParameterError, "'bad' raised ZeroDivisionError: no"),
    (lambda o: math.nan, ParameterError, "'bad' must return a finite number; got nan"),
    (lambda o: np.array([1.0, 2.0]), TypeError, "'bad' must return a real number"),
    (lambda o: 1j, TypeError, "'bad' must return a real number"),
])
@pytest.mark.parametrize("kind", ["events", "monitors"])
def test_a_failing_function_is_named(function, error, match, kind):
    with pytest.raises(error, match=match):
        ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 1.5), components="start",
                        progress=False, **{kind: {"bad": function}})


def test_a_function_failing_inside_the_locator_is_named_not_bracketed(n1_branch):
    """The locator keeps a failed location as bracketed; a user function's failure there is
    an error naming it instead."""
    calls = {"n": 0}
    npoints = n1_branch.sizes["point"]

    def later(orbit):
        calls["n"] += 1
        if calls["n"] > npoints:  # fine at every accepted point, not in between
            raise RuntimeError("between points")
        return orbit.impact_velocity - V_LEVEL

    with pytest.raises(ParameterError, match="'late' raised RuntimeError: between points"):
        ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 2.0), components="start",
                        events={"late": later}, progress=False)


def test_every_location_lies_in_its_bracket_folds_included():
    """At b = 0.5 the SN points used to lie outside their parameter brackets (issue 11)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.5, omega=1.0, eta=0.1)
    branch = ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 6.0))
    labels = branch.special_label.values.tolist()
    assert labels.count("SN") == 2
    value = branch.special_omega.values
    assert np.all(branch.special_bracket_lo.values <= value)
    assert np.all(value <= branch.special_bracket_hi.values)
    # the fold is the end of its bracket: the branch turns there
    for k in np.flatnonzero(np.array(labels) == "SN"):
        assert value[k] in (branch.special_bracket_lo.values[k],
                            branch.special_bracket_hi.values[k])


def test_a_user_event_with_two_zeros_inside_one_step_is_located_twice():
    """Issue 28, 1.4 for user events: ``(omega - 1.415)(omega - 1.42)`` has the same sign
    at the points 1.40715 and 1.43184 around both its zeros; it was watched only at sign
    changes between two points, now also where it dips through zero inside a step."""
    def dip(orbit):
        omega = orbit.oscillator.omega
        return (omega - 1.415) * (omega - 1.42)

    branch = ic.continuation(paper(b=0.0, omega=1.5), 1, "omega", (1.4, 2.0),
                             components="start", events={"dip": dip}, progress=False)
    omega = branch.omega.values
    assert not np.any((omega > 1.414) & (omega < 1.421))  # both zeros inside one step
    located = branch.event_omega.values
    assert branch.event_status.values.tolist() == ["located", "located"]
    np.testing.assert_allclose(np.sort(located), [1.415, 1.42], atol=1e-12)


def test_the_n1_detector_locates_the_kinds_its_problem_declares(n1_branch):
    """Issue 29, 2: the detector knows no kind by name; a problem that declares ZV with its
    own test (the impact velocity at V_LEVEL) gets it located where the user event is."""
    from types import MappingProxyType

    from impactcont.core import ContinuationOptions, continue_branch
    from impactcont.core.locate import MotionTest
    from impactcont.detection import BranchSample, detect_special_points
    from impactcont.problems import PeriodicBranchProblem
    from impactcont.problems.events import BRANCH_TESTS
    from impactcont.vocabulary import Label

    class Declared(PeriodicBranchProblem):
        motion_tests = MappingProxyType({**BRANCH_TESTS, Label.ZV: MotionTest(velocity_event)})

    osc = paper(b=0.0, omega=1.5)
    problem = Declared(osc, 1, "omega")
    delta0 = float(n1_branch["delta"].values[0])
    result = continue_branch(problem, np.array([delta0]), float(n1_branch["omega"].values[0]),
                             ContinuationOptions(bounds=(1.4, 2.0)))
    samples = [BranchSample(u, float(lam), t, problem.orbit(u, lam))
               for u, lam, t in zip(result.u, result.lam, result.tangent, strict=True)]
    found = detect_special_points(problem, samples, ["ZV"])
    expected = np.sort(n1_branch["event_omega"].values[rows(n1_branch, "v07")])
    assert expected.size >= 1
    assert [point.kind for point in found] == [Label.ZV] * expected.size
    np.testing.assert_allclose([point.value for point in found], expected, atol=1e-9)
    assert all(abs(point.orbit.impact_velocity - V_LEVEL) < 1e-9 for point in found)


def test_ctrl_c_while_locating_the_second_fold_keeps_the_first(monkeypatch):
    """Issue 31: Ctrl-C while the second saddle-node of a branch is located returned the
    branch without any special point; it keeps the fold located before, marked interrupted."""
    import json

    from impactcont.problems import PeriodicBranchProblem

    osc = paper(b=0.0, omega=1.1)  # the branch in b: SN at b = +-0.782, one component
    full = ic.continuation(osc, 1, "b", (-2.0, 2.0), detect=["SN"], progress=False)
    folds = full["special_b"].values
    assert list(full["special_label"].values) == ["SN", "SN"]
    locate_fold, calls = PeriodicBranchProblem.locate_fold, []

    def interrupted_fold(self, *args):  # the closed form's fold hook
        calls.append(args)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return locate_fold(self, *args)

    monkeypatch.setattr(PeriodicBranchProblem, "locate_fold", interrupted_fold)
    ds = ic.continuation(osc, 1, "b", (-2.0, 2.0), detect=["SN"], progress=False)
    assert ds.sizes["point"] == full.sizes["point"]  # the branch was computed
    assert list(ds["special_label"].values) == ["SN"]
    assert np.min(np.abs(folds - float(ds["special_b"][0]))) < 1e-12
    assert json.loads(ds.attrs["options"])["interrupted"] is True
    assert ds.attrs["interrupted"] == 1


def test_a_user_event_is_the_one_record_codimension_two_on_a_curve():
    """Issue 29, 2: a user event's zero is a SpecialPoint; on a curve (a position in two
    parameters) it is a point of codimension two."""
    from impactcont.core import ContinuationOptions, continue_branch
    from impactcont.detection import SpecialPoint
    from impactcont.detection.special_points import (
        check_user_functions,
        locate_user_events,
        user_values,
    )
    from impactcont.problems import PeriodicBranchProblem

    osc = paper(b=0.0, omega=1.5)
    problem = PeriodicBranchProblem(osc, 1, "omega")
    delta0 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical).delta
    result = continue_branch(problem, np.array([delta0]), 1.5,
                             ContinuationOptions(bounds=(1.4, 2.0)))
    functions = check_user_functions({"v07": velocity_event})
    orbits = [problem.orbit(u[0], lam) for u, lam in zip(result.u, result.lam, strict=True)]
    values = user_values(functions, orbits)
    tangent = [[0.0, t[-1]] for t in result.tangent]

    def at(u, lam):
        return problem.orbit(u[0], lam)

    on_branch = locate_user_events(problem, result.u, result.lam, tangent, functions, values, at)
    on_plane = locate_user_events(problem, result.u, result.lam, tangent, functions, values, at,
                                  position=lambda u, lam: (lam, 0.0))
    assert on_branch and all(isinstance(e, SpecialPoint) for e in on_branch + on_plane)
    assert {e.codimension for e in on_branch} == {1}
    assert {e.codimension for e in on_plane} == {2}
    assert [e.name for e in on_branch] == ["v07"] * len(on_branch)
    assert all(abs(e.orbit.impact_velocity - V_LEVEL) < 1e-9 for e in on_branch)


def test_the_fold_is_the_one_kind_without_a_test_of_the_motion():
    """Review item: ``test None`` is the fold by name: its pole quantities are the impact
    velocities (:data:`FOLD_POLES`); any other kind without a test is refused."""
    from types import SimpleNamespace

    from impactcont.core.locate import MotionTest
    from impactcont.detection.special_points import (
        FOLD_POLES,
        _pole_quantities,
        _through_pole,
    )
    from impactcont.problems.events import BRANCH_TESTS, impact_speeds
    from impactcont.vocabulary import Label

    assert FOLD_POLES is impact_speeds and _pole_quantities(Label.SN, None) is impact_speeds
    assert _pole_quantities(Label.PD, BRANCH_TESTS[Label.PD]) is impact_speeds
    assert _pole_quantities(Label.ZV, BRANCH_TESTS[Label.ZV]) is None
    with pytest.raises(ValueError, match="only the fold SN"):
        _pole_quantities(Label.ZV, None)
    left = SimpleNamespace(impact_velocity=2.0, impact_velocities=np.array([2.0, -1e-3]))
    right = SimpleNamespace(impact_velocity=2.0, impact_velocities=np.array([2.0, 1e-3]))
    assert _through_pole(Label.SN, None, left, right)
    assert not _through_pole(Label.GR, MotionTest(lambda m: 0.0), left, right)


def test_points_among_motions_past_the_end_of_a_flight_are_none():
    """A step whose two motions both fly for a negative time (FT's test < 0) lies past the
    end of the physical motion: the bound it passes is named, none elsewhere."""
    from types import SimpleNamespace

    from impactcont.detection.special_points import _past_singular_bound
    from impactcont.problems.events import BRANCH_TESTS
    from impactcont.vocabulary import Label

    def motion(*flights):
        return SimpleNamespace(flight_times=np.array(flights))

    assert _past_singular_bound(BRANCH_TESTS, motion(2.0, -0.1), motion(-0.3, 2.0)) is Label.FT
    assert _past_singular_bound(BRANCH_TESTS, motion(2.0, -0.1), motion(0.3, 2.0)) is None


def test_a_singular_kinds_zero_is_interpolated_from_the_branch_on_both_sides():
    """_singular_zero on a branch known in closed form, u = lam + lam^3 / 10, with the test
    u - 0.3: the zero is where lam + lam^3 / 10 = 0.3, found within its stated precision;
    the candidates of such a kind are its interpolated zeros, located."""
    from types import SimpleNamespace

    from scipy.optimize import brentq

    from impactcont.core.locate import MotionTest
    from impactcont.detection.special_points import (
        BranchSample,
        _singular_points,
        _singular_zero,
    )
    from impactcont.vocabulary import Label

    class Cubic:
        def residual(self, u, lam):
            return np.array([u[0] - lam - lam**3 / 10])

        def jacobian(self, u, lam):
            return np.array([[1.0]])

        def dparam(self, u, lam):
            return np.array([-1.0 - 3 * lam**2 / 10])

        def orbit(self, u, lam, *, checks=True):
            return SimpleNamespace(u=float(u[0]))

    problem = Cubic()
    test = MotionTest(lambda motion: motion.u - 0.3)

    def sample(lam):
        u = np.array([lam + lam**3 / 10])
        tangent = np.array([1.0 + 3 * lam**2 / 10, 1.0]) / np.hypot(1.0 + 3 * lam**2 / 10, 1)
        return BranchSample(u=u, lam=lam, tangent=tangent, orbit=problem.orbit(u, lam))

    left, right = sample(0.2), sample(0.45)
    x, precision = _singular_zero(problem, test, left, right)
    exact = brentq(lambda lam: lam + lam**3 / 10 - 0.3, 0.0, 1.0, xtol=1e-15)
    assert precision < 1e-10
    assert abs(x[-1] - exact) <= precision and abs(x[0] - 0.3) < 1e-10
    found = _singular_points(problem, [sample(0.0), left, right, sample(0.7)], Label.FT, test,
                             problem.orbit)
    assert [(k, label, status) for k, label, _, _, _, status, _ in found] == [
        (1, Label.FT, "located")]

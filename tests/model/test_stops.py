"""Stops on several masses at once (issue 21, item 2): a stop above mass 1 (``U``) and one
above mass 2 (``A``) of a two-mass chain (the layout of Wagg's two-degree-of-freedom impact
oscillator with constraints on two masses; illustrative numbers). The model's validation,
the simulator against solve_ivp and each stop's own impact law."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.dataset import oscillator_from_dataset
from impactcont.errors import ParameterError
from impactcont.model.stops import Stop, Stops, check_pattern, require_forcing
from impactcont.orbit.flow import Flow
from tests.orbit.test_flow import _ivp

M = np.eye(2)
K = np.array([[2.0, -1.0], [-1.0, 1.0]])  # a chain: wall - k - m1 - k - m2


def _wagg(omega=0.8, gap=0.6, **kw):
    params = {"M": M, "K": K, "F": [1.0, 0.0], "R": 0.8, "b": 0.3, "omega": omega,
              "eta": 0.05,
              "stops": Stops(extra=(Stop("A", mass=2, gap=gap, restitution=0.7),))}
    return ic.ImpactOscillator(**{**params, **kw})


# -- the model -----------------------------------------------------------------------------
def test_stop_record_views_and_round_trip():
    osc = _wagg()
    assert ic.Stop is Stop
    assert osc.stops.names == "UA" and not osc.stops.paper
    view = osc.stops.stop("A", osc.M, osc.b, osc.R)
    np.testing.assert_array_equal(view.normal, [0.0, 1.0])
    assert (view.sign, view.position, view.restitution, view.pivot) == (1.0, 0.6, 0.7, 1)
    np.testing.assert_array_equal(view.jump, np.diag([1.0, -0.7]))
    up = osc.stops.stop("U", osc.M, osc.b, osc.R)
    assert (up.sign, up.position, up.restitution, up.pivot) == (1.0, 0.3, 0.8, 0)
    low = Stop("B", mass=2, relative_to=1, gap=0.4, restitution=0.5, side=-1)
    assert low.position == -0.4 and "side=-1" in repr(low) and "relative_to=1" in repr(low)
    again = ic.ImpactOscillator.from_dict(osc.to_dict())
    assert again.stops == osc.stops and "extra=" in repr(osc)
    assert Stops.from_dict({"extra": [low.to_dict()]}).extra == (low,)
    assert check_pattern("AUA", 3, osc.stops) == "AUA"
    with pytest.raises(ParameterError, match=r"stop names.*\['U', 'A'\]"):
        check_pattern("UB", 2, osc.stops)
    with pytest.raises(ParameterError, match="has none"):
        check_pattern("UL", 2, osc.stops)
    # a sticking phase on a path of flights and impacts alone: where it is solved instead
    assert check_pattern("uA", 2, osc.stops, sticking=True) == "uA"
    with pytest.raises(ParameterError, match=r"'u'.*multi_impact_orbit solves them.*'UA'") as err:
        check_pattern("uA", 2, osc.stops)
    assert "not supported" not in str(err.value)
    with pytest.raises(ParameterError, match="one of"):
        osc.stops.stop("B", osc.M, osc.b, osc.R)
    with pytest.raises(TypeError, match="sequence of Stop"):
        Stops(extra=low)


def test_a_bad_sticking_pattern_is_named_as_given():
    """A lowercase pattern of the wrong length was named in capitals ('got 'UU'' for
    pattern='uu', p = 1, as '1 letters'); a one-sided oscillator's pattern named 'L' as
    allowed, and neither said that lowercase marks a sticking phase."""
    one = Stops()
    with pytest.raises(ParameterError, match=r"pattern='uu' \(lowercase: an impact followed by "
                                             r"a sticking phase.*must be 1 letter \(.*got 'UU'"):
        check_pattern("uu", 1, one, sticking=True)
    with pytest.raises(ParameterError) as err:
        check_pattern("x", 1, one)
    assert "'L'" not in str(err.value) and "lowercase where a sticking phase" in str(err.value)
    with pytest.raises(ParameterError, match=r"'U' \(upper stop\) and 'L' \(lower stop\)"):
        check_pattern("UX", 2, Stops(b_low=0.5))


@pytest.mark.parametrize("make, match", [
    (lambda: Stop("U", mass=2, gap=1.0, restitution=0.5), "'U' and 'L'"),
    (lambda: Stop("AB", mass=2, gap=1.0, restitution=0.5), "one letter"),
    (lambda: Stop("A", mass=2, relative_to=2, gap=1.0, restitution=0.5), "mass and itself"),
    (lambda: Stop("A", mass=0, gap=1.0, restitution=0.5), "mass must be an integer >= 1"),
    (lambda: Stop("A", mass=2, gap=1.0, restitution=1.5), r"restitution must be in \[0, 1\]"),
    (lambda: Stop("A", mass=2, gap=1.0, restitution=0.5, side=0), "side must be"),
    (lambda: Stops(extra=(Stop("A", mass=2, gap=1.0, restitution=0.5),
                          Stop("A", mass=2, gap=1.0, restitution=0.5, side=-1))), "duplicate"),
    (lambda: Stops.from_dict({"extra": [{"name": "A", "mass": 2}]}), "missing key"),
    (lambda: _wagg(stops=Stops(extra=(Stop("A", mass=3, gap=1.0, restitution=0.5),))),
     r"mass must be in 1\.\.2"),
    # a second upper stop on mass 1 shadows U
    (lambda: _wagg(stops=Stops(extra=(Stop("A", mass=1, gap=1.0, restitution=0.5),))),
     "shadows"),
    # a lower stop on mass 1 above U: the clearance closes
    (lambda: _wagg(stops=Stops(extra=(Stop("A", mass=1, gap=-0.5, restitution=0.5,
                                          side=-1),))), "closes"),
    # x1 - x2 >= 0.2 (A) against x2 - x1 >= ... (B, read on the same coordinate): no room
    (lambda: _wagg(stops=Stops(extra=(
        Stop("A", mass=2, relative_to=1, gap=-0.3, restitution=0.5),
        Stop("B", mass=1, relative_to=2, gap=-0.4, restitution=0.5)))), "closes"),
])
def test_bad_stops_are_refused_clearly(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


# -- the simulator -------------------------------------------------------------------------
def test_simulator_meets_both_stops_with_each_stops_law():
    osc = _wagg()
    res = ic.simulate(osc, np.zeros(4), 0.0, 30.0)
    assert res.success and set(res.impact_stops) == {"U", "A"}
    flow = Flow(osc)
    start, phase, t0 = np.zeros(4), 0.0, 0.0
    for k, stop in enumerate(res.impact_stops[:8]):
        tau = res.impact_times[k] - t0
        before = _ivp(osc, start, phase, tau)(tau)  # independent witness of the flight
        after = res.impact_states[k]
        np.testing.assert_allclose(flow.state(tau, start, phase)[0], before, rtol=0,
                                   atol=1e-8)
        hit, other = (0, 1) if stop == "U" else (1, 0)
        level, restitution = (osc.b, osc.R) if stop == "U" else (0.6, 0.7)
        assert after[hit] == level  # the coordinate of the stop hit sits on it
        assert before[2 + hit] > 0  # met moving up
        np.testing.assert_allclose(before[:2], after[:2], rtol=0, atol=1e-8)
        assert after[2 + hit] == pytest.approx(-restitution * before[2 + hit], abs=1e-7)
        assert after[2 + other] == pytest.approx(before[2 + other], abs=1e-7)
        # no crossing of either stop inside the flight (the witness, sampled finely)
        inner = _ivp(osc, start, phase, tau)(np.linspace(0.0, tau, 400)[1:-1])
        assert np.all(inner[0] < osc.b + 1e-9) and np.all(inner[1] < 0.6 + 1e-9)
        start, phase, t0 = after, res.impact_phases[k], res.impact_times[k]


def test_simulator_refuses_a_start_beyond_an_extra_stop():
    with pytest.raises(ParameterError, match=r"x2 = 0\.7.*beyond stop 'A'"):
        ic.simulate(_wagg(), [0.0, 0.7, 0.0, 0.0], 0.0, 1.0)
    from impactcont.simulate.simulator import next_impact

    with pytest.raises(ParameterError, match=r"follows one stop.*\['U', 'A'\]"):
        next_impact(Flow(_wagg()), np.zeros(4), 0.0, 10.0)



# -- shooting, G and continuation ----------------------------------------------------------
@pytest.fixture(scope="module")
def two_mass_motion():
    """The 1-2 motion with one impact on each stop (U above mass 1, A above mass 2)."""
    osc = _wagg()
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 100.0))
    assert sorted(orbit.pattern) == ["A", "U"] and orbit.physical and orbit.residual < 1e-12
    return orbit


def test_motion_on_two_masses_repeats_in_the_simulator(two_mass_motion):
    orbit = two_mass_motion
    osc = _wagg()  # a fresh oscillator
    res = ic.simulate(osc, orbit.states[0], orbit.phases[0], 1.0)
    assert res.impact_stops == orbit.pattern[1:] + orbit.pattern[0]
    np.testing.assert_allclose(res.impact_times, np.cumsum(orbit.flight_times), rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(res.impact_states[-1], orbit.states[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.impact_velocities[[1, 0]], orbit.impact_velocities,
                               rtol=1e-8)


def _impact_map(osc, orbit, z):
    """The simulated map from impact 0 over the p impacts, in G's coordinates ``z``:
    ``X`` without the position of the stop's own mass, and the phase."""
    j = 1 if orbit.pattern[0] == "A" else 0
    X = np.insert(z[:-1], j, orbit.states[0][j])
    res = ic.simulate(osc, X, z[-1], 1.5, max_impacts=orbit.p)
    assert res.impact_stops == orbit.pattern[1:] + orbit.pattern[0]
    phase = orbit.phases[0] + np.remainder(res.impact_phases[-1] - orbit.phases[0] + np.pi,
                                           2 * np.pi) - np.pi
    return np.append(np.delete(res.impact_states[-1], j), phase)


def test_G_of_a_motion_on_two_masses_matches_finite_differences(two_mass_motion):
    orbit = two_mass_motion
    osc = _wagg()
    j = 1 if orbit.pattern[0] == "A" else 0
    z0 = np.append(np.delete(orbit.states[0], j), orbit.phases[0])
    h = 1e-6
    fd = np.column_stack([(_impact_map(osc, orbit, z0 + h * e)
                           - _impact_map(osc, orbit, z0 - h * e)) / (2 * h)
                          for e in np.eye(z0.size)])
    np.testing.assert_allclose(orbit.G, fd, rtol=0, atol=1e-6 * np.abs(fd).max())


def test_a_branch_on_one_stop_grazes_the_stop_on_the_other_mass():
    osc = _wagg(omega=1.5)
    start = ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, np.zeros(4), 0.0, 100.0))
    assert start.pattern == "U" and start.physical
    assert start.flight_gap_min[0] == pytest.approx(0.6 - _max_x2(start), abs=1e-9)
    branch = ic.multi_impact_continuation(start, "omega", (1.18, 1.5), direction=-1,
                                          both_directions=False, detect=("GR",))
    labels = list(branch["special_label"].values)
    assert labels == ["GR"] and start.flight_gap_stops == "A"  # A is the stop grazed
    w = float(branch["special_omega"].values[0])
    assert 1.18 < w < 1.2
    # re-solved on a fresh oscillator: x2 touches stop A (0.6) inside the flight, x1 stays
    # below U
    fresh = _wagg(omega=w)
    graze = ic.multi_impact_orbit(fresh, 1, 1, {
        "delta": float(branch["special_delta_k"].values[0, 0]),
        "flight_times": branch["special_flight_time_k"].values[0],
        "states": branch["special_state_k"].values[0]})
    assert _max_x2(graze) == pytest.approx(0.6, abs=1e-7)
    # on each side, the simulator: clear of A above the grazing, A met below it
    for dw, first in ((+0.01, "U"), (-0.01, "A")):
        near = _wagg(omega=w + dw)
        orbit = ic.multi_impact_orbit(near, 1, 1, graze)
        res = ic.simulate(near, orbit.states[0], orbit.phases[0], 1.0, max_impacts=1)
        assert res.impact_stops == first
        assert orbit.physical == (dw > 0)
        assert (dw > 0) or "stop 'A'" in orbit.reason


def _max_x2(orbit):
    """Largest x2 over the flight, from solve_ivp (the independent witness)."""
    tau = orbit.flight_times[0]
    sol = _ivp(orbit.oscillator, orbit.states[0], orbit.phases[0], tau)
    return float(np.max(sol(np.linspace(0.0, tau, 20001))[1]))


def test_a_branch_of_a_motion_on_two_masses_is_stored_and_loaded(two_mass_motion, tmp_path):
    # the dataset's pattern names the extra stop ("A"): it was refused as not U/L
    branch = ic.multi_impact_continuation(two_mass_motion, "omega", (0.75, 0.85),
                                          max_points=15)
    assert set(branch.attrs["pattern"]) == set(two_mass_motion.pattern)
    ic.save(branch, tmp_path / "b.nc")
    back = ic.load(tmp_path / "b.nc")
    assert back.attrs["pattern"] == branch.attrs["pattern"]
    osc = oscillator_from_dataset(back, 0)
    assert [s.name for s in osc.stops.extra] == ["A"]


def test_extra_stops_do_not_move_with_the_lower_stop_and_break_the_mirror():
    from impactcont.model.parameters import model_parameter
    from impactcont.orbit.symmetry import symmetric_system

    mirrored = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.6, b=0.5, omega=0.8, eta=0.05,
                                   stops=ic.Stops(mirror=True, extra=(
                                       ic.Stop(name="A", mass=2, gap=0.7, restitution=0.5),)))
    assert not symmetric_system(mirrored)
    rates = model_parameter(mirrored, "b").stop_rates("ULA")
    np.testing.assert_array_equal(rates, [1.0, -1.0, 0.0])


def test_extra_stops_in_a_scene(tmp_path):
    from impactcont.scene import SceneError, load_scene

    table = ('[oscillator]\nK = [[2.0, -1.0], [-1.0, 1.0]]\nF = [1.0, 0.0]\nR = 0.8\n'
             'b = 0.3\nomega = 0.8\neta = 0.05\n'
             'extra_stops = [{ name = "A", mass = 2, gap = 0.6, restitution = 0.7 }]\n'
             '[[simulations]]\nstart = "state"\nstate = [0.0, 0.0, 0.0, 0.0]\ndelta = 0.0\n'
             'periods = 2\n')
    path = tmp_path / "scene.toml"
    path.write_text(table, encoding="utf-8")
    osc = load_scene(path).oscillator.build()
    assert osc.stops == _wagg().stops
    path.write_text(table.replace('name = "A"', 'name = "U"'), encoding="utf-8")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert "extra_stops" in info.value.key


def test_require_forcing_refuses_only_an_unforced_machine(paper):
    """F = 0 is a machine (simulated from a state), but has no periodic motion to find."""
    require_forcing(paper, "a path")  # forced: nothing to say
    require_forcing(paper.replace(F=[0.0, 1e-300]), "a path")  # any nonzero entry forces it
    with pytest.raises(ParameterError, match=r"^a path: F = \[0.0, 0.0\] \(no harmonic "
                                             r"forcing\).* Allowed: F with a nonzero entry"):
        require_forcing(paper.replace(F=[0.0, 0.0]), "a path")

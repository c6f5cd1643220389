"""Stops on several masses at once (issue 21, item 2): a stop above mass 1 (``U``) and one
above mass 2 (``A``) of a two-mass chain (Wagg's two-degree-of-freedom impact oscillator
with constraints on two masses). The model's validation, the simulator against solve_ivp
and each stop's own impact law."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stop, Stops, check_pattern
from impactcont.orbit.flow import Flow
from tests.test_static_force import _ivp

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
    with pytest.raises(ParameterError, match="one of"):
        osc.stops.stop("B", osc.M, osc.b, osc.R)
    with pytest.raises(TypeError, match="sequence of Stop"):
        Stops(extra=low)


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


def test_shooting_refuses_several_stop_coordinates_for_now():
    res = ic.simulate(_wagg(), np.zeros(4), 0.0, 60.0)
    with pytest.raises(ParameterError, match="not yet several stop coordinates"):
        ic.multi_impact_orbit(_wagg(), 1, 2, res)

"""Free masses (K positive semi-definite, issue 21): what holds each free mode, the exact
flow of zero-frequency modes against solve_ivp, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from tests.test_static_force import _ivp

# a primary mass on a spring to the ground and a free ball (an impact damper)
M2 = np.diag([1.0, 0.2])
K2 = np.diag([1.0, 0.0])
PAIR = Stops(mass=2, relative_to=1, mirror=True)


def test_chain_with_a_zero_spring_has_a_free_mode_with_zero_frequency():
    osc = ic.ImpactOscillator.chain(masses=[1.0, 0.5], springs=[2.0, 0.0], F=[1.0, 0.0],
                                    R=0.5, b=0.1, omega=1.3, eta=0.05)
    assert osc.free_modes.shape == (2, 1)
    np.testing.assert_allclose(osc.free_modes[:, 0] / osc.free_modes[0, 0], [1.0, 1.0],
                               rtol=1e-12)
    modes = osc.modes
    assert modes.free.tolist() == [True, False]
    assert modes.natural_frequencies[0] == 0.0  # clamped, not rounding of either sign
    np.testing.assert_allclose(modes.natural_frequencies[1] ** 2, 2.0 / 1.0 + 2.0 / 0.5,
                               rtol=1e-12)


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"alpha": 0.3, "beta": 0.02},
                                     {"C": [[0.1, 0.0], [0.0, 0.05]]}])
@pytest.mark.parametrize("static", [None, [0.1, -0.05]])
def test_free_mode_flow_matches_solve_ivp(damping, static):
    """Undamped free mode (eta: g t^2/2), damped by alpha (drift g t/(2a)) and by a damping
    matrix (the first-order basis with an exact zero eigenvalue)."""
    osc = ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.3], R=0.5, b=0.3, omega=1.3,
                              stops=PAIR, F_static=static, **damping)
    flow = Flow(osc)
    X0 = np.array([0.1, -0.2, 0.3, 0.05])
    t = np.linspace(0.0, 15.0, 6)
    ref = _ivp(osc, X0, 0.7, 15.0)(t).T
    np.testing.assert_allclose(flow.state(t, X0, 0.7), ref, rtol=0, atol=1e-8)
    motion = flow.motion(X0, 0.7, 1, -1.0, osc.stops.normal(2))  # -(x2 - x1)
    s, sv, sa = motion(t)
    np.testing.assert_allclose(s, -(ref[:, 1] - ref[:, 0]), rtol=0, atol=1e-8)
    np.testing.assert_allclose(sv, -(ref[:, 3] - ref[:, 2]), rtol=0, atol=1e-8)
    acc = flow.state_derivative(t, X0, 0.7)[:, 2:]
    np.testing.assert_allclose(sa, -(acc[:, 1] - acc[:, 0]), rtol=0, atol=1e-12)


def test_a_free_mode_nothing_holds_is_refused():
    with pytest.raises(ParameterError, match=r"free mode u = \[0.0, 1.0\] is held by nothing"):
        ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.0], R=0.5, b=0.1, omega=1.3, eta=0.05)
    # two free masses, one stop coordinate: the common motion of both is free
    with pytest.raises(ParameterError, match="2 free"):
        ic.ImpactOscillator(M=np.eye(2), K=np.zeros((2, 2)), F=[1.0, 0.0], R=0.5, b=0.1,
                            omega=1.3, stops=PAIR)
    with pytest.raises(ParameterError, match="K must be positive semi-definite"):
        ic.ImpactOscillator(M=M2, K=[[1.0, 0.0], [0.0, -1e-3]], F=[1.0, 0.0], R=0.5, b=0.1,
                            omega=1.3, stops=PAIR)


def test_undamped_free_mode_on_the_first_order_path_is_refused_naming_the_modal_path():
    osc = ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.0], R=0.5, b=0.1, omega=1.3, stops=PAIR,
                              C=[[0.1, 0.0], [0.0, 0.0]])
    with pytest.raises(ParameterError, match=r"undamped by C.*modal path"):
        osc.first_order  # noqa: B018


def test_closed_form_paths_refuse_free_masses():
    osc = ic.ImpactOscillator.chain(masses=[1.0, 0.5], springs=[2.0, 0.0], F=[1.0, 0.0],
                                    R=0.5, b=0.1, omega=1.3, eta=0.05)
    with pytest.raises(ParameterError, match=r"free mode.*multi_impact_orbit"):
        ic.periodic_orbits(osc, 1)


def test_a_free_ball_between_walls_simulates_against_solve_ivp():
    """An impact damper's ball alone would be refused; here a primary on a spring carries a
    ball in a clearance: each simulated flight against solve_ivp of the equations."""
    osc = ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.0], R=0.6, b=0.3, omega=0.9, eta=0.02,
                              stops=PAIR, F_static=[0.0, -0.05])
    res = ic.simulate(osc, np.zeros(4), 0.0, 6.0)
    assert res.impact_times.size >= 4  # (the ball comes to rest on the lower stop later)
    flow = Flow(osc)
    start, phase, t0 = np.zeros(4), 0.0, 0.0
    for k in range(4):
        tau = res.impact_times[k] - t0
        X_minus = _ivp(osc, start, phase, tau)(tau)
        s = X_minus[1] - X_minus[0]
        level = osc.b if res.impact_stops[k] == "U" else -osc.stops.b_low
        assert abs(s - level) < 1e-8
        np.testing.assert_allclose(X_minus[:2], res.impact_states[k, :2], rtol=0, atol=1e-8)
        np.testing.assert_allclose(flow.state(tau, start, phase)[0], X_minus, rtol=0,
                                   atol=1e-8)
        start, phase, t0 = res.impact_states[k], res.impact_phases[k], res.impact_times[k]

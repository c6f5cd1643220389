"""A constant force F_static (issue 21): the exact flow against solve_ivp, and the identity
'a constant force on a system held by springs = the stops shifted by K^-1 F_static'."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow

M = np.diag([1.0, 0.5])
K = np.array([[1.0, -1.0], [-1.0, 2.0]])
FS = np.array([-0.3, 0.2])


def _ivp(osc, X0, delta, t_end):
    """Independent witness: M x'' + C x' + K x = Re(F e^{i(omega t + delta)}) + F_static."""
    n = osc.n
    Minv = np.linalg.inv(osc.M)
    F = np.asarray(osc.F, dtype=complex)

    def rhs(t, X):
        force = (F * np.exp(1j * (osc.omega * t + delta))).real + osc.F_static
        acc = Minv @ (force - osc.C @ X[n:] - osc.K @ X[:n])
        return np.concatenate([X[n:], acc])

    sol = solve_ivp(rhs, (0.0, t_end), X0, method="DOP853", rtol=1e-10, atol=1e-12,
                    dense_output=True)
    return sol.sol


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"C": [[0.3, -0.1], [-0.1, 0.1]]},
                                     {"eta": 0.05, "F": [1.0, 0.4j]}])
def test_flow_with_a_constant_force_matches_solve_ivp(damping):
    params = {"F": [1.0, 0.0], **damping}
    osc = ic.ImpactOscillator(M=M, K=K, R=0.5, b=1.0, omega=1.3, F_static=FS, **params)
    flow = Flow(osc)
    X0 = np.array([0.1, -0.2, 0.3, 0.05])
    t = np.linspace(0.0, 12.0, 7)
    ref = _ivp(osc, X0, 0.4, 12.0)(t).T
    np.testing.assert_allclose(flow.state(t, X0, 0.4), ref, rtol=0, atol=1e-8)
    # matrices(static=True) and state_derivative agree with the same flow
    Phi, E, S = flow.matrices(12.0, static=True)
    np.testing.assert_allclose(Phi @ X0 + E @ [np.cos(0.4), np.sin(0.4)] + S, ref[-1],
                               rtol=0, atol=1e-8)
    h = 1e-6
    fd = (flow.state(5.0 + h, X0, 0.4) - flow.state(5.0 - h, X0, 0.4)) / (2 * h)
    np.testing.assert_allclose(flow.state_derivative(5.0, X0, 0.4), fd, rtol=0, atol=1e-7)


def test_a_constant_force_equals_shifting_the_stops():
    """K positive definite: x = x_s + K^-1 F_static, so the system with F_static and stops
    at b, -b_low is the system without it and stops at b - c, -b_low - c, c = (K^-1 F_s)_j;
    two simulations, one identity."""
    stops = Stops(mass=1, b_low=0.4, R_low=0.7)
    shift = np.linalg.solve(K, FS)
    c = shift[0]
    with_force = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.1,
                                     eta=0.05, stops=stops, F_static=FS)
    shifted = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.6, b=0.5 - c, omega=1.1,
                                  eta=0.05, stops=Stops(mass=1, b_low=0.4 + c, R_low=0.7))
    X0 = np.array([0.0, 0.0, 0.0, 0.0])
    a = ic.simulate(with_force, X0, 0.0, 30.0)
    b = ic.simulate(shifted, X0 - np.concatenate([shift, [0, 0]]), 0.0, 30.0)
    assert a.impact_times.size > 10 and a.impact_stops == b.impact_stops
    np.testing.assert_allclose(a.impact_times, b.impact_times, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(a.impact_states[:, :2] - shift, b.impact_states[:, :2],
                               rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.impact_states[:, 2:], b.impact_states[:, 2:], rtol=0,
                               atol=1e-8)


def test_static_force_is_validated_and_serialised():
    base = {"M": M, "K": K, "F": [1.0, 0.0], "R": 0.5, "b": 1.0, "omega": 1.3, "eta": 0.05}
    with pytest.raises(ParameterError, match=r"F_static must have shape \(2,\)"):
        ic.ImpactOscillator(**base, F_static=[1.0, 2.0, 3.0])
    with pytest.raises(ParameterError, match="F_static must be finite"):
        ic.ImpactOscillator(**base, F_static=[np.nan, 0.0])
    with pytest.raises(TypeError, match="F_static must be"):
        ic.ImpactOscillator(**base, F_static=[1j, 0.0])
    osc = ic.ImpactOscillator(**base, F_static=FS)
    assert "F_static=[-0.3, 0.2]" in repr(osc)
    again = ic.ImpactOscillator.from_json(osc.to_json())
    np.testing.assert_array_equal(again.F_static, FS)
    assert "F_static" not in ic.ImpactOscillator(**base).to_dict()
    np.testing.assert_array_equal(osc.replace(omega=2.0).F_static, FS)
    np.testing.assert_array_equal(osc.replace(F_static=[0.0, 1.0]).F_static, [0.0, 1.0])


def test_closed_form_paths_refuse_a_constant_force():
    osc = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.5, b=1.0, omega=1.3, eta=0.05,
                              F_static=FS)
    assert not osc.paper_form
    with pytest.raises(ParameterError, match=r"constant force.*multi_impact_orbit"):
        ic.periodic_orbits(osc, 1)

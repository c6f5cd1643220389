"""The shooting path on the machines of issue 21: a clearance between masses (an impact
damper: a free ball in a cavity of the primary mass), a constant force.

Witnesses: central finite differences of the residual (the exact Jacobian), finite
differences of the simulated Poincare map (G), the event-driven simulator over many
periods, and the exact identity "a constant force on a system held by springs is the
stops shifted by K^-1 F_static"."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.orbit.flow import flow_of
from impactcont.orbit.multi_impact import multi_impact_orbit, shooting, stop_geometry

MU = 0.2  # mass ratio ball / primary


@pytest.fixture(scope="module")
def damper():
    """A symmetric two-impact (UL) motion of an impact damper: primary on a spring, a free
    ball of mass ratio MU in a cavity of half-width b (s = x2 - x1 in [-b, b])."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]], F=[1.0, 0.0],
                              R=0.8, b=1.0, omega=1.5, eta=0.05,
                              stops=Stops(mass=2, relative_to=1, mirror=True))
    res = ic.simulate(osc, np.array([0.0, 0.0, 0.0, 1.0]), 0.0, 150.0)
    return multi_impact_orbit(osc, 1, 2, res)


def _fd_jacobian(flow, N, p, u, pattern, h=1e-6):
    J = np.empty((u.size, u.size))
    for c in range(u.size):
        e = np.zeros(u.size)
        e[c] = h * max(1.0, abs(u[c]))
        J[:, c] = (shooting(flow, N, p, u + e, jacobian=False, pattern=pattern).residual
                   - shooting(flow, N, p, u - e, jacobian=False, pattern=pattern).residual
                   ) / (2 * e[c])
    return J


def test_impact_damper_motion_is_physical_symmetric_and_two_body(damper):
    osc = damper.oscillator
    assert damper.physical and damper.stable and damper.residual < 1e-12
    assert damper.pattern in ("UL", "LU")
    s = damper.states[:, 1] - damper.states[:, 0]  # on the stops of s = x2 - x1
    np.testing.assert_allclose(np.abs(s), osc.b, rtol=0, atol=1e-12)
    # symmetric: the second impact is the mirror of the first, half a period later
    np.testing.assert_allclose(damper.states[1], -damper.states[0], rtol=0, atol=1e-9)
    assert damper.flight_times[0] == pytest.approx(damper.period / 2, abs=1e-9)
    # the two-body law conserves momentum
    geo = stop_geometry(osc, damper.pattern)
    M = np.diag([1.0, MU])
    for D in geo.matrices:
        np.testing.assert_allclose(np.ones(2) @ M @ D[2:, 2:], np.ones(2) @ M, atol=1e-15)
        np.testing.assert_allclose(geo.normal @ D[2:, 2:], -osc.R * geo.normal, atol=1e-15)


def test_pair_clearance_jacobian_matches_finite_differences(damper):
    """The exact Jacobian (section n . x = c with n = e2 - e1, full impact matrices) against
    central differences at a point off the solution."""
    flow = flow_of(damper.oscillator)
    u = damper.unknowns + 0.01 * np.linspace(-1.0, 1.0, damper.unknowns.size)
    J = shooting(flow, 1, 2, u, pattern=damper.pattern).jacobian
    fd = _fd_jacobian(flow, 1, 2, u, damper.pattern)
    np.testing.assert_allclose(J, fd, rtol=0, atol=1e-7 * max(1.0, np.abs(J).max()))


def _section_map(osc, X0, theta, p, periods):
    """State and phase after p impacts of the simulator from (X0, theta)."""
    res = ic.simulate(osc, X0, theta, periods)
    return res.impact_states[p - 1], res.impact_phases[p - 1]


def test_pair_clearance_G_matches_the_simulated_poincare_map(damper):
    """G (product of the flight Jacobians and two-body impact matrices) against central
    differences of the simulator's map from impact 0 to impact p (section coordinates
    ``[z, theta]``, z = X without x2; x2 = x1 + c on the section)."""
    osc, p = damper.oscillator, damper.p
    X0, th0 = damper.states[0], damper.phases[0]
    j, m = osc.stops.index, 2 * osc.n
    rest = np.delete(np.arange(m), j)
    h = 1e-6
    fd = np.empty((m, m))
    for c in range(m):
        out = []
        for sgn in (1.0, -1.0):
            X, th = X0.copy(), th0
            if c < m - 1:
                X[rest[c]] += sgn * h
                X[j] = X0[j] + (X[0] - X0[0])  # stay on the section s = x2 - x1 = c_0
            else:
                th += sgn * h
            Xp, thp = _section_map(osc, X, th, p, 1.5 * damper.N)
            out.append(np.append(Xp[rest], thp))
        d = out[0] - out[1]
        d[-1] = math.remainder(d[-1], 2 * math.pi)
        fd[:, c] = d / (2 * h)
    np.testing.assert_allclose(damper.G, fd, rtol=0, atol=1e-5 * max(1.0, np.abs(fd).max()))


def test_stable_pair_clearance_motion_stays_under_simulation(damper):
    """Re-simulated from its impact 0 over 40 periods, the stable motion repeats its
    impacts (the multipliers say stable: rounding does not grow)."""
    osc = damper.oscillator
    res = ic.simulate(osc, damper.states[0], damper.delta, 40.0)
    assert res.impact_stops[:8] == (damper.pattern * 4)[1:9] or res.impact_stops[:2] in (
        "LU", "UL")
    for k in range(res.impact_times.size):
        np.testing.assert_allclose(res.impact_states[k], damper.states[(k + 1) % 2],
                                   rtol=0, atol=1e-7)


def test_constant_force_equals_shifted_stops():
    """K positive definite: F_static moves the equilibrium by x_s = K^-1 F_static; the motion
    with the force is the motion without it with the stops shifted by n . x_s, displaced by
    x_s (exact identity)."""
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    Fs = np.array([0.3, -0.2])
    xs = np.linalg.solve(K, Fs)
    base = dict(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.7, omega=1.6, eta=0.05)
    stops = Stops(mass=2, relative_to=1, b_low=0.4, R_low=0.7)
    with_force = ic.ImpactOscillator(**base, b=0.5, F_static=Fs, stops=stops)
    shift = xs[1] - xs[0]
    shifted = ic.ImpactOscillator(**base, b=0.5 - shift,
                                  stops=Stops(mass=2, relative_to=1, b_low=0.4 + shift,
                                              R_low=0.7))
    res = ic.simulate(shifted, np.array([0.0, 0.0, 0.0, 0.5]), 0.0, 200.0)
    ref = multi_impact_orbit(shifted, 1, 2, res)
    guess = {"delta": ref.delta, "flight_times": ref.flight_times,
             "states": ref.states + np.append(xs, [0.0, 0.0]), "pattern": ref.pattern}
    orb = multi_impact_orbit(with_force, 1, 2, guess)
    np.testing.assert_allclose(orb.states, ref.states + np.append(xs, [0.0, 0.0]), rtol=0,
                               atol=1e-10)
    np.testing.assert_allclose(orb.flight_times, ref.flight_times, rtol=0, atol=1e-10)
    np.testing.assert_allclose(orb.G, ref.G, rtol=0, atol=1e-9 * max(1.0, abs(ref.G).max()))
    assert orb.physical == ref.physical
    np.testing.assert_allclose(orb.flight_gap_min, ref.flight_gap_min, rtol=0, atol=1e-9)


def test_free_mass_under_a_constant_force_jacobian_and_flight():
    """A free ball under gravity bouncing on the primary (the bouncing ball on a vibrating
    table): the flight with the polynomial particular solution of the free mode and its
    exact Jacobian, against finite differences and the simulator's flight."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, MU]), K=[[1.0, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], F_static=[0.0, -MU * 0.5], R=0.7, b=5.0,
                              omega=1.3, eta=0.05,
                              stops=Stops(mass=2, relative_to=1, b_low=0.0, R_low=0.7))
    flow = flow_of(osc)
    X0 = np.array([0.1, 0.1, 0.0, 0.9])  # on the lower stop s = 0, leaving it
    u = np.concatenate([[0.4], np.delete(X0, 1)])
    sh = shooting(flow, 1, 1, u, pattern="L")
    fd = _fd_jacobian(flow, 1, 1, u, "L")
    np.testing.assert_allclose(sh.jacobian, fd, rtol=0, atol=1e-7 * max(1.0, abs(fd).max()))
    # the flight itself against an independent integration of eq. (1) with the constant force
    from scipy.integrate import solve_ivp

    M, K = np.diag([1.0, MU]), np.array([[1.0, 0.0], [0.0, 0.0]])
    C, F, Fs = 2 * 0.05 * K, np.array([1.0, 0.0]), np.array([0.0, -MU * 0.5])

    def rhs(t, X):
        acc = np.linalg.solve(M, F * math.cos(osc.omega * t + 0.4) + Fs - C @ X[2:] - K @ X[:2])
        return np.concatenate([X[2:], acc])

    tau = sh.flight_times[0]
    ref = solve_ivp(rhs, (0.0, tau), sh.starts[0], rtol=1e-11, atol=1e-12).y[:, -1]
    np.testing.assert_allclose(sh.arrivals[0], ref, rtol=0, atol=1e-8)
    np.testing.assert_allclose(sh.arrival_rates[0], rhs(tau, ref), rtol=0, atol=1e-8)

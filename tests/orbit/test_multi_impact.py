"""N-p motions (p impacts in N periods) by shooting (:mod:`impactcont.orbit.multi_impact`).

The shooting path on the machines of issue 21: a clearance between masses (an impact
damper: a free ball in a cavity of the primary mass), a constant force.

Witnesses: central finite differences of the residual (the exact Jacobian), finite
differences of the simulated Poincare map (G), the event-driven simulator over many
periods, and the exact identity "a constant force on a system held by springs is the
stops shifted by K^-1 F_static".
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.switching import grazing_switch, period_doubling_switch
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow, flow_of
from impactcont.orbit.multi_impact import (
    multi_impact_orbit,
    primitive_orbit,
    shooting,
    stop_geometry,
)
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from tests._multi_impact_cases import assert_reproduced_by_simulator, wrap

# the fixtures paper_b0 and branch_n1: tests/_multi_impact_cases.py


# ---------------------------------------------------------------------------------------------
# The solver
# ---------------------------------------------------------------------------------------------
N1_CASES = [
    # (n, params, N)
    (2, {"omega": 1.0, "b": 0.6}, 1),
    (2, {"omega": 1.2, "b": 0.0}, 1),
    (2, {"omega": 2.4, "b": 0.0}, 2),
    (3, {"omega": 1.1, "b": 0.1}, 1),
    (1, {"omega": 1.3, "b": 0.2, "R": 0.8, "eta": 0.05}, 1),
]


@pytest.mark.parametrize("case", range(len(N1_CASES)))
def test_n1_special_case_is_the_closed_form(case, paper, make_chain):
    n, params, N = N1_CASES[case]
    osc = paper.replace(**params) if n == 2 else make_chain(n, **params)
    closed = ic.periodic_orbits(osc, N)
    assert closed
    for orbit in closed:
        # start Newton visibly away from the closed form
        guess = {"delta": orbit.delta + 1e-3, "flight_times": [orbit.period],
                 "states": (orbit.state + 1e-3 * np.r_[0.0, np.ones(2 * n - 1)])[None, :]}
        m = multi_impact_orbit(osc, N, 1, guess)
        assert abs(wrap(m.delta - orbit.delta)) < 1e-12
        np.testing.assert_allclose(m.state, orbit.state, rtol=0, atol=1e-12)
        np.testing.assert_allclose(m.multipliers, orbit.multipliers, rtol=0, atol=1e-12)
        np.testing.assert_allclose(m.G, orbit.G, rtol=0, atol=1e-12 * max(1, abs(orbit.G).max()))
        assert m.impact_velocity == pytest.approx(orbit.impact_velocity, abs=1e-12)
        assert m.physical == orbit.physical


def test_two_two_motion_from_simulation_is_reproduced(paper_b0):
    osc = paper_b0.replace(omega=1.75)
    n1 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    assert not n1.stable  # beyond the PD
    X = n1.state.copy()
    X[1] += 1e-4
    res = ic.simulate(osc, X, n1.delta, 300.0)
    m = multi_impact_orbit(osc, 2, 2, res)
    assert m.physical and m.stable and m.residual < 1e-13
    assert abs(m.impact_velocities[0] - m.impact_velocities[1]) > 0.1
    assert m.flight_times.sum() == pytest.approx(m.period, rel=1e-14)
    assert_reproduced_by_simulator(m, 30)


def test_liouville_determinant_of_the_product(paper_b0, make_chain):
    """det G = R^(2p) exp(-T tr(M^-1 C)): each impact contributes R^2 (see docs/theory.md)."""
    osc = paper_b0.replace(omega=1.75)
    n1 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    for m in (multi_impact_orbit(osc, 2, 2, ic.simulate(osc, n1.state, n1.delta + 1e-3, 200.0)),
              multi_impact_orbit(osc, 3, 3, n1)):  # the N-1 motion thrice: p = 3 on itself
        trace = np.trace(np.linalg.solve(osc.M, osc.C))
        expected = osc.R ** (2 * m.p) * math.exp(-m.period * trace)
        assert np.linalg.det(m.G) == pytest.approx(expected, rel=1e-9)


def test_primitive_orbit_undoes_a_repetition(paper_b0):
    osc = paper_b0.replace(omega=1.75)
    n1 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    twice = multi_impact_orbit(osc, 2, 2, n1)  # the N-1 motion is also a 2-2 solution
    prim = primitive_orbit(twice)
    assert (prim.N, prim.p) == (1, 1)
    assert abs(wrap(prim.delta - n1.delta)) < 1e-12
    np.testing.assert_allclose(prim.multipliers, n1.multipliers, atol=1e-12)
    genuine = multi_impact_orbit(osc, 2, 2, ic.simulate(osc, n1.state, n1.delta + 1e-3, 200.0))
    assert primitive_orbit(genuine) is genuine


@pytest.mark.parametrize(("n", "N", "p"), [(2, 2, 2), (3, 3, 3), (2, 1, 1)])
def test_shooting_jacobian_against_central_differences(n, N, p, paper_b0, make_chain):
    osc = paper_b0.replace(omega=1.75) if n == 2 else make_chain(3, omega=1.1, b=0.1)
    flow = Flow(osc)
    rng = np.random.default_rng(7)
    T = 2 * math.pi * N / osc.omega
    u = np.concatenate([[0.4], np.full(p - 1, T / p), 0.3 * rng.normal(size=p * (2 * n - 1))])
    J = shooting(flow, N, p, u).jacobian
    h = 1e-6
    fd = np.empty_like(J)
    for j in range(u.size):
        e = np.zeros_like(u)
        e[j] = h
        fd[:, j] = (shooting(flow, N, p, u + e).residual
                    - shooting(flow, N, p, u - e).residual) / (2 * h)
    assert np.abs(fd - J).max() < 1e-7 * max(1.0, np.abs(J).max())


@pytest.mark.parametrize("parameter", ["omega", "b", "R", "eta"])
def test_parameter_derivative_against_central_differences(parameter, paper_b0):
    osc = paper_b0.replace(omega=1.75, b=0.05)
    problem = MultiImpactBranchProblem(osc, 2, 2, parameter)
    rng = np.random.default_rng(3)
    T = 2 * math.pi * 2 / osc.omega
    u = np.concatenate([[0.9], [0.55 * T], 0.3 * rng.normal(size=6)])
    lam = float(getattr(osc, parameter))
    h = 1e-6
    fd = (problem.residual(u, lam + h) - problem.residual(u, lam - h)) / (2 * h)
    np.testing.assert_allclose(problem.dparam(u, lam), fd, rtol=0, atol=1e-7)


def test_bad_inputs_raise_clear_errors(paper_b0, branch_n1):
    osc = paper_b0
    n1 = ic.periodic_orbits(osc, 1)[0]
    for bad in (0, -1, 1.5, "2", True):
        with pytest.raises(ic.ParameterError, match="p must be an integer >= 1"):
            multi_impact_orbit(osc, 1, bad, n1)
        with pytest.raises(ic.ParameterError, match="N must be an integer >= 1"):
            multi_impact_orbit(osc, bad, 1, n1)
    with pytest.raises(TypeError, match="guess must be a MultiImpactOrbit"):
        multi_impact_orbit(osc, 1, 1, [0.0, 1.0])
    with pytest.raises(ic.ParameterError, match="can seed an N-p motion"):
        multi_impact_orbit(osc, 3, 2, n1)
    with pytest.raises(ic.ParameterError, match=r"flight_times must have shape \(2,\)"):
        multi_impact_orbit(osc, 2, 2, {"delta": 0.0, "flight_times": [1.0],
                                       "states": np.zeros((2, 4))})
    with pytest.raises(ic.ParameterError, match="needs keys"):
        multi_impact_orbit(osc, 2, 2, {"delta": 0.0})
    with pytest.raises(ic.ParameterError, match="tol must be"):
        multi_impact_orbit(osc, 1, 1, n1, tol=0.0)
    with pytest.raises(ic.ParameterError, match="parameter must be one of"):
        MultiImpactBranchProblem(osc, 1, 1, "gap")
    with pytest.raises(ic.ParameterError, match="must contain the start"):
        multi_impact_continuation(n1, "omega", (2.0, 3.0))
    with pytest.raises(ic.ParameterError, match="out of range: the branch has 1 PD"):
        period_doubling_switch(branch_n1, which=3)
    with pytest.raises(ic.ParameterError, match="epsilon must be"):
        period_doubling_switch(branch_n1, epsilon=2.0)
    with pytest.raises(ic.ParameterError, match="0 GR point"):
        grazing_switch(branch_n1)
    with pytest.raises(ic.NoPeriodicMotionError, match="did not converge"):
        multi_impact_orbit(osc, 2, 2, {"delta": 0.0, "flight_times": [0.1, 0.1],
                                       "states": np.full((2, 4), 50.0)}, max_iter=5)


def test_a_phase_that_runs_off_does_not_loosen_newton_s_test():
    # A bouncing ball (free mass, gravity as F_static, the table's motion as F) from a
    # poor guess: Newton drove the phase to ~-3e14 and the test tol * max(1, |u|) then
    # passed with a residual of 0.95. The phase now counts at most pi in the scale.
    from impactcont.orbit.multi_impact import unknowns_scale

    assert unknowns_scale(np.array([-3e14, 2.0, 0.5])) == math.pi
    assert unknowns_scale(np.array([0.5, 2.0, -7.0])) == 7.0
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[1.06], F_static=[-1.0], omega=1.0,
                              R=0.5, b=1000.0, stops=ic.Stops(b_low=0.0, R_low=0.5))
    guess = {"delta": -math.pi / 2, "flight_times": [2 * math.pi], "states": [[0.0, math.pi]]}
    try:
        orbit = ic.multi_impact_orbit(osc, 1, 1, guess=guess, pattern="L")
    except ic.NoPeriodicMotionError:
        return
    assert orbit.residual < 1e-9


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


# -- motions with sticking phases (issue 30, item 4) -------------------------------------------
def _sticky_damper():
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.0,
                               b=0.3, omega=0.5, eta=0.02,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


@pytest.mark.parametrize("pattern", ["ul", "uL", "u"])
def test_the_sticky_jacobian_is_exact(pattern):
    """The Jacobian of the shooting system with sticking phases (the release rows, the
    held flights, the phases and the period's last flight) against central differences."""
    from impactcont.orbit.sticky import sticky_shooting

    osc = _sticky_damper()
    flow = flow_of(osc)
    p = len(pattern)
    q = sum(c.islower() for c in pattern)
    rng = np.random.default_rng(3)
    u = np.concatenate([[0.4], np.full(p - 1, 2.5), np.full(q, 1.7),
                        rng.normal(scale=0.2, size=p * 3)])
    J = sticky_shooting(flow, 1, pattern, u).jacobian
    h = 1e-6
    fd = np.empty_like(J)
    for c in range(u.size):
        e = np.zeros(u.size)
        e[c] = h
        fd[:, c] = (sticky_shooting(flow, 1, pattern, u + e, jacobian=False).residual
                    - sticky_shooting(flow, 1, pattern, u - e, jacobian=False).residual) / (2 * h)
    np.testing.assert_allclose(J, fd, atol=1e-7 * max(1.0, np.max(np.abs(fd))))


def _sticky_machines(kind, omega):
    """Motions with sticking phases of every held system: the damper (the pair held on a
    wall; a modal flow, and a general one with the dashpot on the primary only), one mass
    preloaded on its stop (nothing left to move) and two masses, the first held on a frame
    stop under a constant force."""
    if kind == "damper":
        return _sticky_damper().replace(omega=omega)
    if kind == "damper, C on the primary":
        return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0],
                                   C=[[0.3, 0.0], [0.0, 0.0]], R=0.0, b=0.3, omega=omega,
                                   stops=Stops(mass=2, relative_to=1, mirror=True))
    if kind == "preloaded":
        return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0,
                                   b=0.0, omega=omega, eta=0.1)
    return ic.ImpactOscillator(M=np.diag([1.0, 0.5]), K=[[2.0, -1.0], [-1.0, 1.0]],
                               F=[1.0, 0.3], F_static=[0.2, 0.1], R=0.0, b=0.1, omega=omega,
                               eta=0.05)


@pytest.mark.parametrize(("kind", "pattern"), [("damper", "ul"), ("damper", "uL"),
                                               ("damper, C on the primary", "ul"),
                                               ("preloaded", "u"), ("frame stop", "uU")])
def test_the_sticky_omega_column_is_exact(kind, pattern):
    """``dr/d omega`` of the shooting system with sticking phases (the phases, the last
    flight, the flights' and the held systems' forced states, the release rows) against
    central differences of the residual in omega at fixed unknowns, each omega's
    oscillator and held systems built afresh."""
    from impactcont.orbit.sticky import sticky_omega_column, sticky_shooting

    omega, h = 0.5, 1e-6
    osc = _sticky_machines(kind, omega)
    p, n = len(pattern), osc.n
    q = sum(c.islower() for c in pattern)
    rng = np.random.default_rng(3)
    u = np.concatenate([[0.4], np.full(p - 1, 2.5), np.full(q, 1.7),
                        rng.normal(scale=0.2, size=p * (2 * n - 1))])
    column = sticky_omega_column(flow_of(osc), 1, pattern, u)
    fd = (sticky_shooting(flow_of(_sticky_machines(kind, omega + h)), 1, pattern, u,
                          jacobian=False).residual
          - sticky_shooting(flow_of(_sticky_machines(kind, omega - h)), 1, pattern, u,
                            jacobian=False).residual) / (2 * h)
    assert np.max(np.abs(fd[2 * n * p:])) > 0.1  # the release rows move with omega
    np.testing.assert_allclose(column, fd, rtol=0, atol=1e-7 * max(1.0, np.max(np.abs(fd))))


def test_sticking_patterns_outside_multi_impact_orbit_are_refused():
    from impactcont.orbit.multi_impact import shooting

    osc = _sticky_damper()
    with pytest.raises(ic.ParameterError, match=r"letter\(s\) 'u'.*multi_impact_orbit"):
        shooting(flow_of(osc), 1, 2, np.zeros(8), pattern="uL")
    with pytest.raises(ic.ParameterError, match="pattern must be"):
        ic.multi_impact_orbit(osc, 1, 2, {"delta": 0.0, "flight_times": [1.0, 1.0],
                                           "states": np.zeros((2, 4))}, pattern="ux")


def test_a_sticking_motion_against_the_physics_is_flagged_with_its_reasons():
    """The preloaded oscillator's sticky 1-1 system has a second solution: landing at a
    phase where the pressing force is negative (no sticking onset) and released where the
    force rises through zero (the coordinate would not leave). It is returned flagged."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.0,
                              omega=0.7, eta=0.1)
    period = 2 * math.pi / 0.7
    stick = ((-math.acos(-1 / 3) - 2.07) % (2 * math.pi)) / 0.7
    orbit = ic.multi_impact_orbit(osc, 1, 1, {"delta": 2.07, "flight_times": [period - stick],
                                              "states": [[0.0, 0.0]], "stick_times": [stick],
                                              "pattern": "u"})
    assert orbit.residual < 1e-12 and not orbit.physical
    assert "sticking onset" in orbit.reason and "does not fall through zero" in orbit.reason
    assert orbit.pressing_min[0] == pytest.approx(-3.0 + 1.0, abs=1e-9)  # F cos(pi) + F_static
    assert math.cos(orbit.phases[0] + 0.7 * orbit.stick_times[0]) == pytest.approx(-1 / 3)


def test_the_accuracy_calls_lapack_as_numpy_linalg_does():
    """shooting_accuracy's singular values and J^-1 r (LAPACK's gufuncs called directly) are
    np.linalg.svd's and np.linalg.solve's own, a singular matrix refused as solve refuses it."""
    from impactcont.orbit.multi_impact import _singular_values, _solve, shooting_accuracy

    rng = np.random.default_rng(3)
    for scale in (1e-6, 1.0, 1e6):
        a, b = scale * rng.standard_normal((8, 8)), rng.standard_normal(8)
        assert np.array_equal(_singular_values(a), np.linalg.svd(a, compute_uv=False))
        assert np.array_equal(_solve(a, b), np.linalg.solve(a, b))
    with pytest.raises(np.linalg.LinAlgError):
        _solve(np.zeros((3, 3)), np.ones(3))
    assert shooting_accuracy(np.zeros((3, 3)), np.ones(3), np.ones(3)) == (math.inf, math.inf)

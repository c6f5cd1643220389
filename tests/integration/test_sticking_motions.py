"""Periodic motions with sticking phases by shooting, held against the simulator.

The simulator (:mod:`impactcont.simulate`, its own sticking model and flow, no code shared
with :mod:`impactcont.orbit.held_flow`) is run to the steady state of each machine; the
motion solved by :func:`impactcont.multi_impact_orbit` from it must repeat its landings,
sticking phases and releases to rounding, and G must be the derivative of the simulated
return map on impact 0's section (central differences). Each solve is a few
milliseconds; the simulations are short (60 periods; the impact damper's from its ball
at rest on a wall).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops

TWO_PI = 2.0 * math.pi


def _preloaded() -> ic.ImpactOscillator:
    """A one-mass oscillator preloaded into its stop b = 0, plastic (R = 0)."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.0,
                               omega=0.7, eta=0.1)


def _ball_on_table(amplitude: float = 2.0) -> ic.ImpactOscillator:
    """A completely inelastic ball on a table vibrating as ``-A cos``, in the table's frame:
    a free mass under ``-g`` (g = 1) and the frame force ``A w^2 cos``, the table the lower
    stop at 0 (R_low = 0); the upper stop far away."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[amplitude], F_static=[-1.0], R=0.5,
                               b=100.0, omega=1.0, stops=Stops(b_low=0.0, R_low=0.0))


def _damper(omega: float = 0.5) -> ic.ImpactOscillator:
    """The impact damper of docs/machines.md with a plastic ball (R = 0 on both walls)."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.0,
                               b=0.3, omega=omega, eta=0.02,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


CASES = {
    "preloaded": (_preloaded, [0.0, 0.0], 60.0, 1, 1, "u"),
    "ball_on_table": (_ball_on_table, [0.0, 0.0], 60.0, 1, 1, "l"),
    "impact_damper": (_damper, [0.0, 0.3, 0.0, 0.0], 60.0, 1, 2, "ul"),
}


@functools.cache
def _solve(case: str):
    make, start, periods, N, p, pattern = CASES[case]
    osc = make()
    res = ic.simulate(osc, np.array(start, float), 0.0, periods)
    orbit = ic.multi_impact_orbit(osc, N, p, res)
    return osc, res, orbit, pattern


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_motion_repeats_the_simulated_steady_state(case):
    osc, res, orbit, pattern = _solve(case)
    assert orbit.pattern == pattern  # inferred from the simulation's sticking phases
    assert orbit.physical, orbit.reason
    p = orbit.p
    assert np.all(orbit.stick_times > 0) and np.all(orbit.pressing_min > 0)
    period = TWO_PI * orbit.N / osc.omega
    assert np.sum(orbit.stick_times) + np.sum(orbit.flight_times) == pytest.approx(period,
                                                                                     rel=1e-14)
    # the simulation's last p complete impact-stick-release-flight segments
    times = res.impact_times[-(p + 1):]
    phases = {ph.start: ph for ph in res.sticking}
    for k in range(p):
        held = min(res.sticking, key=lambda ph, t=times[k]: abs(ph.start - t))
        assert held.ended_by == "release" and abs(held.start - times[k]) < 1e-9
        assert held.duration == pytest.approx(orbit.stick_times[k], abs=1e-8)
        assert times[k + 1] - held.end == pytest.approx(orbit.flight_times[k], abs=1e-8)
        dphase = math.remainder(res.impact_phases[-(p + 1) + k] - orbit.phases[k], TWO_PI)
        assert abs(dphase) < 1e-8
        np.testing.assert_allclose(orbit.states[k], res.impact_states[-(p + 1) + k], atol=1e-8)
        force = held.contact_force(np.array([held.start]))[0, 0]
        assert orbit.pressing_min[k] <= force + 1e-7
    assert len(phases) == len(res.sticking)
    # the motion's own time series starts and ends on impact 0's state
    t, X = orbit.time_series(20)
    assert t[-1] == pytest.approx(period, rel=1e-12)
    np.testing.assert_allclose(X[-1, :osc.n], orbit.states[0, :osc.n], atol=1e-9)


def test_one_mass_held_collapses_every_direction():
    """n = 1: the release fixes the phase and the state, so G = 0 exactly."""
    _, _, orbit, _ = _solve("preloaded")
    assert np.all(orbit.G == 0.0) and orbit.spectral_radius == 0.0 and orbit.stable
    # the release: F cos(theta_r) = K c - F_static (c = 0): cos(theta_r) = -1/3
    release = orbit.phases[0] + 0.7 * orbit.stick_times[0]
    assert math.cos(release) == pytest.approx(-1.0 / 3.0, abs=1e-13)
    assert math.sin(release) > 0  # the pressing force falls through zero


def _simulated_return(osc, orbit, z, theta):
    """The simulated return map on impact 0's section: from ``[z, theta]`` to the state
    and phase of the impact N periods later (the p-th impact after the start)."""
    p = orbit.p
    X = np.insert(np.asarray(z, float), 1, 0.0)  # the pivot x_2 from the section
    normal = np.array([-1.0, 1.0])
    X[1] = (0.3 - normal[0] * X[0]) / normal[1]
    res = ic.simulate(osc, X, theta, orbit.N * 1.3)
    k = p - 1 if abs(res.impact_times[0]) > 1e-12 else p
    out = res.impact_states[k]
    return np.concatenate([np.delete(out, 1), [theta + osc.omega * res.impact_times[k]]])


def test_G_is_the_derivative_of_the_simulated_return_map():
    """Along the directions a plastic impact leaves (the relative velocity 0: x1, the
    common velocity, the phase), G is the central difference of the simulated return map
    (the other side of the relative velocity is a hop off the wall, not this motion); along
    the relative velocity at fixed momentum (which a plastic impact removes) G is zero."""
    osc, _, orbit, _ = _solve("impact_damper")
    assert orbit.pattern == "ul"
    z0 = np.delete(orbit.states[0], 1)  # [x1, x1', x2'], x2 on the section
    theta0 = orbit.phases[0]
    h = 1e-6
    for direction in ([1.0, 0, 0, 0], [0, 1.0, 1.0, 0], [0, 0, 0, 1.0]):
        e = h * np.array(direction)
        hi = _simulated_return(osc, orbit, z0 + e[:3], theta0 + e[3])
        lo = _simulated_return(osc, orbit, z0 - e[:3], theta0 - e[3])
        fd = (hi - lo) / (2 * h)
        np.testing.assert_allclose(orbit.G @ np.array(direction), fd, atol=1e-6)
    # a relative velocity at the momentum of the pair (m1 dx1' + m2 dx2' = 0) is what the
    # plastic impact removes: the sticks hold the relative position and velocity
    np.testing.assert_allclose(orbit.G @ np.array([0, -0.2, 1.0, 0]), 0.0, atol=1e-13)
    assert np.sum(np.abs(orbit.multipliers) < 1e-12) == 2
    assert 0 < orbit.spectral_radius < 1


def test_bad_sticking_patterns_are_refused_with_the_reason():
    osc = _preloaded()
    res = ic.simulate(osc, np.zeros(2), 0.0, 30.0)
    # restitution 1: the impacts do not accumulate (0 < R < 1 enters through complete
    # chatter: tests/integration/test_chatter_entered_motions.py)
    with pytest.raises(ic.ParameterError, match=r"stop 'U'.*restitution is 1\.0.*do not "
                       r"accumulate"):
        ic.multi_impact_orbit(osc.replace(R=1.0), 1, 1, res, pattern="u")
    orbit = ic.multi_impact_orbit(osc, 1, 1, res)
    # a branch in R would leave the plastic impact that enters the sticking phase
    with pytest.raises(ic.ParameterError, match=r"parameter 'R' changes the restitution of "
                       r"stop\(s\) \['U'\] \(now \[0\.0\]\), on which the motion sticks"):
        ic.continuation(orbit, parameter="R", bounds=(0.0, 0.5))

"""Sticking phases of the simulator (:mod:`impactcont.simulate.sticking`): the exact flow
with stop coordinates held, the contact force along it and the release where it falls to
zero, against closed forms and an independent matrix exponential."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

import impactcont as ic
from impactcont import ParameterError, SimulationStatus, simulate
from impactcont.simulate.sticking import HeldFlight, holding, impact_with_held

EPS = float(np.finfo(float).eps)


def _preloaded(**changes):
    """One mass on a spring, forced 3 cos(omega t) and pushed by F_static = 1 into its stop
    at b = 0: at rest there it sticks while 3 cos(omega t) + 1 > 0."""
    params = {"M": [[1.0]], "K": [[1.0]], "F": [3.0], "F_static": [1.0], "R": 0.5, "b": 0.0,
              "omega": 0.7, "eta": 0.05}
    return ic.ImpactOscillator(**{**params, **changes})


def test_preloaded_oscillator_sticks_at_once_and_releases_in_closed_form():
    """Witness (b): F_static into the stop, b = 0, from rest: held from t = 0 with the
    pressing force 3 cos(omega t) + 1 (M = 1, x = 0, x' = 0), released where the forcing
    overcomes the preload, omega t_r = arccos(-1/3). It used to stop at once (STICKING)."""
    osc = _preloaded()
    res = simulate(osc, [0.0, 0.0], 0.0, 1.0, trajectory=True)
    assert res.success
    first = res.sticking[0]
    assert (first.start, first.stops, first.ended_by) == (0.0, "U", "release")
    t_r = math.acos(-1.0 / 3.0) / osc.omega
    assert abs(first.end - t_r) <= 8 * EPS * t_r
    np.testing.assert_allclose(first.forces[:, 0], 3 * np.cos(osc.omega * first.times) + 1,
                               rtol=0, atol=1e-14)
    assert first.forces[-1, 0] == pytest.approx(0.0, abs=1e-14)
    assert first.contact_force([0.0])[0, 0] == pytest.approx(4.0, rel=1e-15)
    # held: x = 0, x' = 0 throughout; then a flight that stays behind the stop
    held = res.t < first.end
    assert np.all(res.X[held] == 0.0)
    assert res.X[:, 0].max() <= 1e-15
    assert res.impact_times.size and res.impact_times[0] > first.end


def test_stop_at_sticking_stops_where_a_phase_would_start():
    res = simulate(_preloaded(), [0.0, 0.0], 0.0, 1.0, stop_at=("sticking",))
    assert res.status is SimulationStatus.STICKING and res.final_time == 0.0
    assert "stop_at" in res.message
    for bad in (("chatter", "sticky"), 3, ("STICKING",)):
        with pytest.raises(ParameterError, match="stop_at must be a tuple of the ends"):
            simulate(_preloaded(), [0.0, 0.0], 0.0, 1.0, stop_at=bad)


def test_locked_ball_releases_where_the_table_acceleration_is_minus_g():
    """Witness (a): Luck & Mehta 1993 (Phys. Rev. E 48, 3988), the locked motion of the
    bouncing ball. In the table's frame the ball's height y obeys y'' = -g + A w^2 cos(theta)
    (table z = A cos(theta)); locked on the table (y = 0) it leaves where the table's
    acceleration reaches -g: A w^2 cos(theta_r) = g, theta_r = -arccos(1 / Gamma),
    Gamma = A w^2 / g. The free ball (K = 0, no damping) is the defective flow."""
    g, A, om = 1.0, 2.0, 1.3
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[A * om**2], F_static=[-g], R=0.5,
                              b=100.0, omega=om, eta=0.0, stops=ic.Stops(b_low=0.0, R_low=0.5))
    delta = -0.5 * math.pi
    res = simulate(osc, [0.0, 0.0], delta, 0.5)
    t_r = (-math.acos(g / (A * om**2)) - delta) / om
    first = res.sticking[0]
    assert first.stops == "L" and first.start == 0.0
    assert abs(first.end - t_r) <= 16 * EPS * (1 + t_r)
    # the pressing force is the table's push g - A w^2 cos(theta) on the unit mass
    np.testing.assert_allclose(first.forces[:, 0],
                               g - A * om**2 * np.cos(om * first.times + delta), atol=1e-14)


def _damper(**changes):
    """An impact damper: a free ball (mass 2, m = 0.2) in a clearance |x2 - x1| <= 1."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.0,
                              b=1.0, omega=1.5, eta=0.05,
                              stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    return osc.replace(**changes)


def test_plastic_clearance_masses_move_together():
    """Witness (c): R = 0 on a clearance between masses. The plastic impact conserves the
    total momentum and leaves no relative speed; held, the pair moves as one mass
    m1 + m2 on the primary's spring and damper (checked against an independent matrix
    exponential of that one-degree-of-freedom system), x2 - x1 stays on the stop, and the
    contact force is the ball's inertia m2 |x1''|."""
    osc = _damper()
    res = simulate(osc, np.array([0, 0, 0, 1.0]), 0.0, 3.0, trajectory=True)
    assert res.success and res.sticking
    m1, m2 = 1.0, 0.2
    for k, t_k in enumerate(res.impact_times[:3]):
        before = res.X[np.flatnonzero(res.t == t_k)[0]]
        after = res.impact_states[k]
        assert m1 * after[2] + m2 * after[3] == pytest.approx(m1 * before[2] + m2 * before[3],
                                                              rel=1e-14, abs=1e-15)
        assert after[3] - after[2] == 0.0
    phase = res.sticking[0]
    assert phase.ended_by == "release" and phase.duration > 0.1
    inside = (res.t > phase.start) & (res.t < phase.end)
    s = res.X[inside, 1] - res.X[inside, 0]
    np.testing.assert_allclose(s, osc.stops.position(phase.stops, osc.b), rtol=0, atol=4e-16)
    np.testing.assert_allclose(res.X[inside, 3] - res.X[inside, 2], 0.0, atol=1e-15)
    # the pair as one mass: (m1 + m2) y'' + c1 y' + k1 y = cos(omega t + delta)
    mass, c1, k1 = m1 + m2, float(osc.C[0, 0]), 1.0
    A = np.array([[0, 1, 0, 0], [-k1 / mass, -c1 / mass, 1 / mass, 0],
                  [0, 0, 0, -osc.omega], [0, 0, osc.omega, 0]])
    X0 = phase.start_state
    Y0 = np.array([X0[0], X0[2], math.cos(phase.start_phase), math.sin(phase.start_phase)])
    for t, X in zip(res.t[inside][::7], res.X[inside][::7], strict=False):
        Y = scipy.linalg.expm(A * (t - phase.start)) @ Y0
        assert X[0] == pytest.approx(Y[0], abs=1e-13) and X[2] == pytest.approx(Y[1],
                                                                                  abs=1e-13)
        # the ball is pushed by the wall with m2 |x1''|
        acc = (math.cos(osc.omega * t + 0.0) - k1 * Y[0] - c1 * Y[1]) / mass
        force = phase.contact_force([t])[0, 0]
        assert force == pytest.approx(m2 * abs(acc), abs=1e-13)


def test_plastic_clearance_never_passes_the_wall():
    """Issue 28, 1.2 passed through: a plastic impact on x2 - x1 used to end the run
    (STICKING); now the ball rides on the wall and leaves it, every sample behind it."""
    for osc in (_damper(), _damper(omega=0.7), _damper(K=np.diag([1.0, 0.01]))):
        res = simulate(osc, np.array([0, 0, 0, 1.0]), 0.0, 8.0, trajectory=True)
        assert res.success and len(res.sticking) >= 3
        assert np.max(np.abs(res.X[:, 1] - res.X[:, 0])) <= 1.0 + 1e-14
        assert all(p.ended_by == "release" for p in res.sticking[:-1])
        assert all(np.all(p.forces >= -1e-14) for p in res.sticking)


def _two_stops():
    """Mass 1 under U (x1 <= 0), mass 2 under the extra stop A (x2 <= 0), both plastic and
    pushed up by F_static: at rest at x = 0 both hold, with forces 3 cos(omega t) + 1 on U
    and 0.5 on A (x = 0: the springs carry nothing)."""
    return ic.ImpactOscillator(
        M=np.eye(2), K=[[2, -1], [-1, 2]], F=[3.0, 0], F_static=[1.0, 0.5], R=0.0, b=0.0,
        omega=0.7, eta=0.05, stops=ic.Stops(extra=(ic.Stop("A", mass=2, gap=0.0,
                                                           restitution=0.0),)))


def test_two_stops_held_at_once():
    osc = _two_stops()
    assert holding(osc, np.zeros(4), 0.0, ["U", "A"]) == ("U", "A")
    assert holding(osc, np.zeros(4), math.pi, ["U", "A"]) == ("A",)  # 3 cos(pi) + 1 < 0
    res = simulate(osc, np.zeros(4), 0.0, 1.5, trajectory=True)
    both = res.sticking[0]
    assert both.stops == "UA" and both.ended_by == "release"
    t_r = math.acos(-1.0 / 3.0) / osc.omega
    assert abs(both.end - t_r) <= 8 * EPS * t_r
    np.testing.assert_allclose(both.forces[:, 1], 0.5, atol=1e-14)
    assert res.sticking[1].stops == "A" and res.sticking[1].start == both.end
    # mass 2 released where its own force 0.5 - K21 x1 - C21 x1' (the spring and the
    # damper of the link) reaches zero
    second = res.sticking[1]
    X = res.X[np.searchsorted(res.t, second.end)]
    force = 0.5 - osc.K[1, 0] * X[0] - osc.C[1, 0] * X[2]
    assert force == pytest.approx(0.0, abs=1e-13)
    assert second.contact_force([second.start])[0, 0] == pytest.approx(
        0.5 - osc.K[1, 0] * second.start_state[0] - osc.C[1, 0] * second.start_state[2])
    # never above the stops, to rounding of the state's size (1.2e-15 on some processors)
    rounding = 64 * EPS * float(np.abs(res.X).max())
    assert res.X[:, 0].max() <= rounding and res.X[:, 1].max() <= rounding
    # an impact of mass 1 (plastic) while mass 2 is held: both held afterwards
    later = [p for p in res.sticking if p.start in set(res.impact_times)]
    assert later and all(np.all(p.forces >= -1e-14) for p in later)


def test_held_flight_against_an_independent_reduction():
    """The reduced flow of a relative stop x2 - x1 = 1 (held) equals the matrix exponential
    of the constrained system written by hand in the coordinate x1 (x2 = x1 + 1)."""
    osc = _damper(K=np.diag([1.0, 0.3]), F=[1.0, 0.4], F_static=[0.1, -0.2])
    hf = HeldFlight(osc, ["U"])
    X0 = np.array([0.2, 1.2, -0.3, -0.3])
    t = np.array([0.0, 0.4, 1.7, 5.0])
    got = hf.samples(t, X0, 0.3)
    m, c, k = 1.2, float(osc.C[0, 0] + osc.C[1, 1]), 1.3  # x2 = x1 + 1: k2 (x1 + 1)
    A = np.array([[0, 1, 0, 0, 0], [-k / m, -c / m, 1.4 / m, 0, (-0.1 - 0.3) / m],
                  [0, 0, 0, -osc.omega, 0], [0, 0, osc.omega, 0, 0], [0, 0, 0, 0, 0]])
    Y0 = np.array([0.2, -0.3, math.cos(0.3), math.sin(0.3), 1.0])
    for tk, row in zip(t, got, strict=True):
        Y = scipy.linalg.expm(A * tk) @ Y0
        np.testing.assert_allclose(row, [Y[0], Y[0] + 1.0, Y[1], Y[1]], atol=1e-13)


def test_impact_with_held_keeps_the_pressed_stop():
    osc = _two_stops()
    v, kept = impact_with_held(osc, np.array([0.5, 0.0]), "U", ["A"])
    assert kept == ("A",) and v[1] == 0.0 and v[0] == pytest.approx(0.0, abs=1e-16)
    # an impact on U that would lift mass 2 off A (a coupled mass matrix) releases it
    coupled = _two_stops().replace(M=[[1.0, 0.4], [0.4, 1.0]])
    v, kept = impact_with_held(coupled, np.array([0.5, 0.0]), "U", ["A"])
    assert v[1] <= 0.0


def test_a_result_with_sticking_phases_pickles():
    """A result travels between processes (parallel sweeps): its phases keep their exact
    contact force."""
    import pickle

    res = simulate(_preloaded(), [0.0, 0.0], 0.0, 1.0)
    back = pickle.loads(pickle.dumps(res))
    phase = back.sticking[0]
    assert phase.contact_force([phase.start])[0, 0] == pytest.approx(4.0, rel=1e-15)
    with pytest.raises(ValueError, match="t must lie in the phase"):
        phase.contact_force([phase.end + 1.0])

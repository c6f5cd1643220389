"""The held flow: the exact motion with a stop coordinate held, and its pressing force."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.held_flow import held_flow, held_flow_at, held_frame


def test_the_frame_keeps_the_mass_matrix_diagonal():
    np.testing.assert_array_equal(held_frame([0.0, 1.0, 0.0]), [[1, 0], [0, 0], [0, 1]])
    P = held_frame([-1.0, 1.0, 0.0])  # a clearance x2 - x1: x3 and the pair together
    np.testing.assert_array_equal(P, [[0, 1], [0, 1], [1, 0]])
    M = np.diag([1.0, 0.2, 3.0])
    reduced = P.T @ M @ P
    assert reduced[0, 1] == 0.0 and reduced[1, 1] == pytest.approx(1.2)


def _damper() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.0,
                               b=0.3, omega=0.5, eta=0.02,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def test_the_held_pair_moves_as_one_mass_and_its_force_is_the_ball_s():
    """A ball (mass 0.2) held on the upper wall of its primary (mass 1, spring 1, dashpot
    0.04): the pair is one mass 1.2 on the spring, and the wall presses the ball with
    ``-m2 x2''`` (the ball's only force is the wall's)."""
    osc = _damper()
    held = held_flow(osc, "U")
    X0 = np.array([0.1, 0.4, 0.05, 0.05])  # x2 - x1 = 0.3, at rest relative to the wall
    t = np.linspace(0.0, 3.0, 7)
    X = held.state(t, X0, 0.2)
    np.testing.assert_allclose(X[:, 1] - X[:, 0], 0.3, atol=1e-15)
    np.testing.assert_allclose(X[:, 3] - X[:, 2], 0.0, atol=1e-15)
    # the pair's own equation: 1.2 x'' + 0.04 x' + x = cos(0.5 t + 0.2)
    rate = np.array([held.segment(s, X0, 0.2)[3] for s in t])
    np.testing.assert_allclose(1.2 * rate[:, 2] + 0.04 * X[:, 2] + X[:, 0],
                               np.cos(0.5 * t + 0.2), atol=1e-12)
    pressing = held.pressing(X, 0.5 * t + 0.2)
    np.testing.assert_allclose(pressing, -0.2 * rate[:, 3], atol=1e-12)


def test_the_segment_derivatives_are_those_of_the_state():
    osc = _damper()
    held = held_flow(osc, "L")
    X0 = np.array([0.1, -0.2, 0.05, 0.05])
    X, dX0, dth, rate = held.segment(1.3, X0, 0.7)
    np.testing.assert_allclose(X, held.state(1.3, X0, 0.7)[0], rtol=1e-14)
    h = 1e-6
    np.testing.assert_allclose(rate, (held.state(1.3 + h, X0, 0.7)[0]
                                      - held.state(1.3 - h, X0, 0.7)[0]) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(dth, (held.state(1.3, X0, 0.7 + h)[0]
                                     - held.state(1.3, X0, 0.7 - h)[0]) / (2 * h), atol=1e-8)
    e = np.array([1.0, 1.0, 0.0, 0.0]) * h  # along the held section
    np.testing.assert_allclose(dX0 @ (e / h), (held.state(1.3, X0 + e, 0.7)[0]
                                               - held.state(1.3, X0 - e, 0.7)[0]) / (2 * h),
                               atol=1e-8)


def test_one_mass_held_stays_and_its_force_follows_the_forcing():
    osc = ic.ImpactOscillator(M=[[2.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.5,
                              omega=0.7, eta=0.1)
    held = held_flow(osc, "U")
    X = held.state(np.array([0.0, 1.0]), [0.5, 0.0], 0.3)
    np.testing.assert_array_equal(X, [[0.5, 0.0], [0.5, 0.0]])
    # the stop presses down with F cos + F_static - K c
    assert held.pressing(X[0], 0.3) == pytest.approx(3.0 * np.cos(0.3) + 1.0 - 0.5, rel=1e-15)
    low, when = held.pressing_minimum(6.0, X[0], 0.3)  # the interior minimum at phase pi
    assert low == pytest.approx(-3.0 + 1.0 - 0.5, abs=1e-12)
    assert 0.7 * when + 0.3 == pytest.approx(np.pi, abs=1e-6)
    # without an interior minimum: the start
    assert held.pressing_minimum(2.0, X[0], 0.3) == (held.pressing(X[0], 0.3), 0.0)


def test_the_held_flow_at_another_omega_is_the_one_built_there():
    """held_flow_at (a branch in omega: the start's held flow with the reduced flow at the
    new omega) gives the kernel rows, states and pressing forces of held_flow built afresh
    at that omega (the same arithmetic but the forced amplitudes: 1e-13 relative), and is
    what held_flow returns for that oscillator afterwards; another machine is refused."""
    from impactcont.problems.multi_impact_branch import _flow_at_frequency

    osc = _damper()
    base = held_flow(osc, "U")
    base.kernel_rows()  # its omega-free parts (the lift, the force rows) cached: passed on
    moved = osc.replace(omega=1.37)
    fresh = held_flow(osc.replace(omega=1.37), "U")  # another object: built afresh
    reduced = _flow_at_frequency(base.reduced, base.reduced.osc.replace(omega=1.37))
    made = held_flow_at(base, moved, "U", reduced)
    assert held_flow(moved, "U") is made
    for mine, theirs in zip(made.kernel_rows(), fresh.kernel_rows(), strict=True):
        assert np.asarray(mine) == pytest.approx(np.asarray(theirs), rel=1e-13, abs=1e-13)
    X0 = np.array([0.1, 0.1 + osc.b, 0.2, 0.2])
    t = np.linspace(0.0, 3.0, 7)
    assert made.state(t, X0, 0.4) == pytest.approx(fresh.state(t, X0, 0.4), rel=1e-13,
                                                   abs=1e-13)
    with pytest.raises(ParameterError, match="osc must be the held flow's oscillator at "
                                             "another omega only"):
        held_flow_at(base, osc.replace(b=0.4, omega=1.37), "U", reduced)


@pytest.mark.parametrize("damping", [{"eta": 0.05},
                                     {"C": np.diag([0.1, 0.0, 0.02])}])
def test_other_stops_are_searched_along_the_held_flow_at_their_turning_points(damping):
    """A chain of three masses held on a stop of mass 2 (the held system: masses 1 and 3
    through their springs to the held mass, a constant force on it; modal and first-order
    flows): for stops on ``x1`` and ``x3 - x1`` met from either side, stop_clearances gives
    the clearance at the turning point of the coordinate nearest the stop inside a stick of
    7 time units: there ``s' = 0`` and the held state has that clearance (1e-12), and
    against 200,001 samples of the held state it is the smallest interior clearance (the
    samples' error at an extremum is below 1e-9 here); the held coordinate's own other
    stop has no turning point."""
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    osc = ic.ImpactOscillator(M=np.diag([1.0, 0.5, 2.0]), K=K, F=[1.0, 0.0, 0.3], R=0.0,
                              b=0.2, omega=0.9, stops=Stops(mass=2, b_low=0.5),
                              F_static=[0.0, 0.1, 0.0], **damping)
    held = held_flow(osc, "U")
    X0 = np.array([0.3, 0.2, -0.1, 0.4, 0.0, -0.2])
    t = np.linspace(0.0, 7.0, 200_001)
    sampled = held.state(t, X0, 0.4)[:, :3]
    normals = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 1.0],
                        [-1.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
    signs = np.array([1.0, -1.0, 1.0, -1.0, -1.0])
    positions = np.array([2.0, -2.0, 1.5, -1.5, -0.5])
    gaps, times = held.stop_clearances(7.0, X0, 0.4, (normals, signs, positions))
    for i in range(4):
        clearance = signs[i] * (positions[i] - sampled @ normals[i])
        inner = clearance[1:-1]
        assert 0.0 < times[i] < 7.0
        X, _, _, rate = held.segment(times[i], X0, 0.4)
        assert normals[i] @ rate[:3] == pytest.approx(0.0, abs=1e-13)
        assert signs[i] * (positions[i] - normals[i] @ X[:3]) == pytest.approx(gaps[i],
                                                                               abs=1e-12)
        assert gaps[i] >= inner.min() - 1e-9
        if 0 < np.argmin(clearance) < t.size - 1:  # the smallest clearance inside
            assert gaps[i] <= inner.min() + 1e-14
    assert gaps[4] == np.inf and np.isnan(times[4])

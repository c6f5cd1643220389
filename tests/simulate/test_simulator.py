"""The event-driven simulator: no missed impact, precise impact times, clear stops."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq

from impactcont import Flow, ParameterError, SimulationStatus, periodic_orbits, simulate
from impactcont.orbit.extrema import interior_maxima, sample_times


def _free_flight_peak(osc, X0, delta, t_max):
    flow = Flow(osc)
    times, peaks = interior_maxima(flow.mass1(X0, delta), sample_times(flow, 0.0, t_max))
    k = int(np.argmax(peaks))
    return times[k], peaks[k]


@pytest.mark.parametrize("depth", [1e-6, 1e-9])
def test_short_excursion_past_the_stop_is_caught(paper, depth):
    X0 = np.array([-1.0, 0.0, 0.0, 0.0])
    far = paper.replace(b=100.0)
    t_peak, x_peak = _free_flight_peak(far, X0, 0.0, 6.0)
    # an excursion of height `depth` lasts ~ 2 sqrt(2 depth / |x1''|) << one sampling cell
    osc = paper.replace(b=float(x_peak - depth))
    res = simulate(osc, X0, 0.0, 6.0 * osc.omega / (2 * math.pi))
    assert res.impact_times.size >= 1
    assert res.impact_times[0] == pytest.approx(t_peak, abs=10 * math.sqrt(depth))
    assert 0 < res.impact_velocities[0] < 10 * math.sqrt(depth)
    cell = np.diff(sample_times(Flow(osc), 0.0, 6.0)).max()
    assert 2 * math.sqrt(2 * depth) < 0.05 * cell  # the excursion really is inside one cell
    # just above the peak: no impact in that flight
    miss = simulate(paper.replace(b=float(x_peak + depth)), X0, 0.0, t_peak * 1.01 / (2 * math.pi))
    assert miss.impact_times.size == 0


def test_impact_time_against_expm_reference(paper):
    X0 = np.array([0.0, 0.1, 0.3, -0.2])
    delta = 0.3
    res = simulate(paper, X0, delta, 2.0)
    tc = res.impact_times[0]

    n = paper.n
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -paper.K
    A[n:2 * n, n:2 * n] = -paper.C
    A[n:2 * n, 2 * n] = paper.F
    A[2 * n, 2 * n + 1] = -paper.omega
    A[2 * n + 1, 2 * n] = paper.omega
    Y0 = np.concatenate([X0, [math.cos(delta), math.sin(delta)]])

    def x1(t):
        return (scipy.linalg.expm(A * t) @ Y0)[0] - paper.b

    ref = brentq(x1, tc - 1e-3, tc + 1e-3, xtol=1e-15)
    assert tc == pytest.approx(ref, abs=1e-12)
    assert res.impact_phases[0] == pytest.approx(
        math.remainder(delta + paper.omega * ref, 2 * math.pi), abs=1e-12)
    # state right after impact obeys eq. (4)
    X_after = res.impact_states[0]
    assert X_after[0] == paper.b
    v_before = res.impact_velocities[0]
    assert X_after[n] == pytest.approx(-paper.R * v_before, rel=1e-15)


def test_trajectory_stays_behind_the_stop(paper):
    res = simulate(paper.replace(b=0.0, omega=2.6), [-0.5, 0, 0, 0], 0.0, 30.0, trajectory=True)
    assert res.success
    assert res.t.shape[0] == res.X.shape[0]
    assert np.all(np.diff(res.t) >= 0)
    assert res.X[:, 0].max() <= 1e-12
    assert res.impact_times.size > 5


def test_sticking_with_zero_restitution_is_reported(paper):
    osc = paper.replace(R=0.0, b=0.0, omega=0.5)
    res = simulate(osc, [-0.5, 0.0, 0.0, 0.0], 0.0, 20.0)
    assert res.status is SimulationStatus.STICKING
    assert "sticks" in res.message
    assert res.impact_velocities[-1] > 0


def test_start_on_the_stop(paper):
    """On the stop moving into it: impact at t = 0; at rest pressed into it: sticking."""
    res = simulate(paper.replace(b=0.0), [0.0, 0.0, 0.5, 0.0], 0.0, 1.0)
    assert res.impact_times[0] == 0.0
    assert res.impact_velocities[0] == 0.5
    res = simulate(paper.replace(b=0.0), [0.0, 0.0, 0.0, 0.0], 0.0, 1.0)
    assert res.status is SimulationStatus.STICKING


def test_bad_inputs(paper):
    with pytest.raises(ParameterError, match=r"x1 = 0.7 is beyond the stop b = 0.6"):
        simulate(paper, [0.7, 0, 0, 0], 0.0, 1.0)
    with pytest.raises(ParameterError, match="state must be a finite vector"):
        simulate(paper, [0.0, 0.0, 0.0], 0.0, 1.0)
    with pytest.raises(ParameterError, match="periods must be a finite number > 0; got -1"):
        simulate(paper, np.zeros(4), 0.0, -1)
    with pytest.raises(ParameterError, match="delta must be a finite"):
        simulate(paper, np.zeros(4), math.nan, 1.0)


def test_plastic_impact_motion_is_followed(paper):
    """R = 0: mass 1 stops dead on the stop and leaves it again (no sticking, no chatter)."""
    osc = paper.replace(R=0.0)
    orbit = next(o for o in periodic_orbits(osc, 1) if o.physical)
    assert orbit.state[osc.n] == 0.0
    res = simulate(osc, orbit.state, orbit.delta, 10.5)
    assert res.success
    np.testing.assert_allclose(np.diff(res.impact_times), orbit.period, rtol=1e-12)
    np.testing.assert_allclose(res.impact_velocities, orbit.impact_velocity, rtol=1e-10)


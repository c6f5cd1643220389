"""Issue 19: motions at the edge of the model (a forcing far slower than the natural
motion, stops that would cross, a symmetry-breaking pitchfork) end with a correct
result or a clear message, never a hang or a silently inexact number."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq

import impactcont as ic
from impactcont import Flow, SimulationStatus, simulate
from impactcont.orbit.flow import Mass1Motion
from impactcont.simulate import next_impact

# ------------------------------------------------------------------------------------------
# 7. The simulator at a forcing frequency far below the natural ones
# ------------------------------------------------------------------------------------------
# The search for the next contact used to cut each flight into windows of one forcing
# period, each on a grid fine for the natural motion: at omega = 1e-8 one window was
# 6.3e8 time units, i.e. 2.5e9 grid cells (capped at 2e6 with a warning) for every
# impact. Its cost now follows the natural time scales. The tests count the times at
# which the motion is evaluated (wall time is noisy) and stop a run that exceeds a
# budget far above what the motion needs.

_BUDGET = 500_000  # evaluated times per run; the old search used 2e6 per window


class _OverBudgetError(Exception):
    pass


@pytest.fixture
def evaluations(monkeypatch):
    """Count the times at which any flight's motion is evaluated; stop past the budget."""
    count = {"times": 0}
    original = Mass1Motion.derivatives

    def counted(self, t):
        count["times"] += np.size(t)
        if count["times"] > _BUDGET:
            raise _OverBudgetError(f"more than {_BUDGET} evaluated times")
        return original(self, t)

    monkeypatch.setattr(Mass1Motion, "derivatives", counted)
    return count


def _slow(**params):
    """The paper's system forced at omega = 1e-8 (quasi-static forcing)."""
    values = {"R": 0.6, "b": 0.6, "omega": 1e-8, "eta": 0.1, **params}
    return ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], **values)


def _first_crossing_expm(osc, X0, delta, t_lo, t_hi):
    """First impact time from the matrix exponential of the forced system (independent)."""
    n = osc.n
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -osc.K
    A[n:2 * n, n:2 * n] = -osc.C
    A[n:2 * n, 2 * n] = osc.F
    A[2 * n, 2 * n + 1] = -osc.omega
    A[2 * n + 1, 2 * n] = osc.omega
    Y0 = np.concatenate([X0, [math.cos(delta), math.sin(delta)]])
    return brentq(lambda t: (scipy.linalg.expm(A * t) @ Y0)[0] - osc.b, t_lo, t_hi, xtol=1e-14)


def test_slow_forcing_chatter_ends_in_bounded_cost(evaluations, caplog):
    """The issue's call: constant force beyond the stop, chatter at t = 4.39; it hung."""
    osc = _slow()
    res = simulate(osc, np.zeros(4), 0.0, 1.0)
    assert evaluations["times"] < _BUDGET
    assert res.status is SimulationStatus.CHATTER
    assert "accumulating impacts" in res.message
    assert "simulation stopped at t=4.385" in caplog.text and "impacts" in caplog.text
    # the same motion on a horizon of 628 time units (one window of the old search)
    short = simulate(osc, np.zeros(4), 0.0, 1e-6)
    assert short.status is SimulationStatus.CHATTER
    k = 10  # chatter amplifies rounding impact after impact: compare the first ones
    np.testing.assert_allclose(res.impact_times[:k], short.impact_times[:k], rtol=1e-9)
    np.testing.assert_allclose(res.impact_velocities[:k], short.impact_velocities[:k],
                               rtol=1e-7)
    assert res.final_time == pytest.approx(short.final_time, rel=1e-6)
    first = _first_crossing_expm(osc, np.zeros(4), 0.0, 1.0, 1.4)
    assert res.impact_times[0] == pytest.approx(first, abs=1e-9)


def test_slow_forcing_quasi_static_approach(evaluations):
    """Forcing from zero at omega = 1e-8: the first impact is where the forced (quasi-static)
    motion reaches the stop, 8.5e7 time units later; it used to need 2e6 grid cells per
    forcing period (with an UnresolvedMotionWarning)."""
    osc = _slow(b=1.5)
    delta = -0.5 * math.pi  # F cos(omega t + delta) starts at zero
    res = simulate(osc, np.zeros(4), delta, 1.0)
    assert evaluations["times"] < _BUDGET
    assert res.status is SimulationStatus.CHATTER  # pressed onto the stop ever harder
    # the start's transient has decayed (exp(-0.038 t)): x1 is the forced response
    # Re(Z1 e^{i(omega t + delta)}) with Z = (K - omega^2 M + i omega C)^-1 F
    Z = np.linalg.solve(osc.K - osc.omega**2 * osc.M + 1j * osc.omega * osc.C, osc.F)
    A, phi = abs(Z[0]), math.atan2(Z[0].imag, Z[0].real)
    t_star = (-math.acos(osc.b / A) - phi - delta) / osc.omega
    assert res.impact_times[0] == pytest.approx(t_star, abs=1e-3)
    assert res.impact_velocities[0] == pytest.approx(A * osc.omega * math.sin(
        math.acos(osc.b / A)), rel=1e-6)


@pytest.mark.parametrize("general", [False, True])
def test_slow_forcing_flight_without_contact(evaluations, general):
    """A stop never reached over one forcing period of 6.3e8 time units: the search skips
    what the envelope of the motion keeps clear of the stop (modal and first-order flow)."""
    extra = {"C": [[0.2, 0.0], [0.0, 0.0]]} if general else {"eta": 0.1}
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=3.7,
                              omega=1e-8, **extra)
    assert Flow(osc).__class__.__name__ == ("GeneralFlow" if general else "Flow")
    X0 = np.array([0.0, 0.0, 0.5, 0.0])
    res = simulate(osc, X0, 0.0, 1.0)
    assert evaluations["times"] < _BUDGET
    assert res.status is SimulationStatus.COMPLETED and res.impact_times.size == 0
    # one forcing period later the motion is its forced response again: x = K^-1 F, x' = 0
    np.testing.assert_allclose(res.final_state[:2], [2.0, 1.0], atol=1e-6)
    np.testing.assert_allclose(res.final_state[2:], 0.0, atol=1e-6)


def test_slow_forcing_next_impact(evaluations):
    """next_impact (the paper's stop) searches the same way: bounded cost, same impact."""
    osc = _slow()
    hit = next_impact(Flow(osc), np.zeros(4), 0.0, 1e8)
    assert evaluations["times"] < _BUDGET
    assert hit is not None
    assert hit[0] == pytest.approx(_first_crossing_expm(osc, np.zeros(4), 0.0, 1.0, 1.4),
                                   abs=1e-9)

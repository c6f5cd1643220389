"""Issue 19: motions at the edge of the model (a forcing far slower than the natural
motion, stops that would cross, a symmetry-breaking pitchfork) end with a correct
result or a clear message, never a hang or a silently inexact number."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq, fsolve

import impactcont as ic
from impactcont import Flow, SimulationStatus, simulate
from impactcont.analysis.branch import make_options, multi_impact_continuation, trace_branch
from impactcont.errors import IllConditionedWarning, NoPeriodicMotionError, ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.multi_impact import multi_impact_orbit, orbit_from_unknowns, shooting
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.simulate import next_impact
from impactcont.simulate.flight import StopMotion
from tests.orbit.test_general import _augmented

# ------------------------------------------------------------------------------------------
# 7. The simulator at a forcing frequency far below the natural ones
# ------------------------------------------------------------------------------------------
# The search for the next contact used to cut each flight into windows of one forcing
# period, each on a grid fine for the natural motion: at omega = 1e-8 one window was
# 6.3e8 time units, i.e. 2.5e9 grid cells (capped at 2e6 with a warning) for every
# impact. Its cost now follows the natural time scales. The tests count the times at
# which the motion is evaluated (wall time is noisy) and stop a run that exceeds a
# budget far above what the motion needs.

_BUDGET = 100_000  # evaluated times per test; the old search used 2e6 per window (about 5e3 now)


class _OverBudgetError(Exception):
    pass


@pytest.fixture
def evaluations(monkeypatch):
    """Count the times at which the simulator evaluates a flight (its own evaluator, issue
    29); stop past the budget; a test that evaluated nothing counted nothing: an error."""
    count = {"times": 0}
    original = StopMotion.derivatives

    def counted(self, t):
        count["times"] += np.size(t)
        if count["times"] > _BUDGET:
            raise _OverBudgetError(f"more than {_BUDGET} evaluated times")
        return original(self, t)

    monkeypatch.setattr(StopMotion, "derivatives", counted)
    yield count
    assert count["times"] > 0, "the simulator's evaluations were not counted"


def _slow(**params):
    """The paper's system forced at omega = 1e-8 (quasi-static forcing)."""
    values = {"R": 0.6, "b": 0.6, "omega": 1e-8, "eta": 0.1, **params}
    return ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], **values)


def _first_crossing_expm(osc, X0, delta, t_lo, t_hi):
    """First impact time from the matrix exponential of the forced system (independent)."""
    A = _augmented(osc)
    Y0 = np.concatenate([X0, [math.cos(delta), math.sin(delta)]])
    return brentq(lambda t: (scipy.linalg.expm(A * t) @ Y0)[0] - osc.b, t_lo, t_hi, xtol=1e-14)


def test_slow_forcing_chatter_ends_in_bounded_cost(evaluations, caplog):
    """The issue's call: constant force beyond the stop, chatter at t = 4.39; it hung."""
    osc = _slow()
    res = simulate(osc, np.zeros(4), 0.0, 1.0, stop_at=("chatter",))
    assert evaluations["times"] < _BUDGET
    assert res.status is SimulationStatus.CHATTER
    assert "accumulating impacts" in res.message
    assert "simulation stopped at t=4.385" in caplog.text and "impacts" in caplog.text
    # the same motion on a horizon of 628 time units (one window of the old search)
    short = simulate(osc, np.zeros(4), 0.0, 1e-6, stop_at=("chatter",))
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
    res = simulate(osc, np.zeros(4), delta, 1.0, stop_at=("chatter",))
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


# ------------------------------------------------------------------------------------------
# The symmetric two-sided system of studies/backlash (b = b_low = 0.5, R = R_low = 0.6)
# ------------------------------------------------------------------------------------------
def _backlash(omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                               omega=omega, eta=0.1, stops=Stops(b_low=0.5, R_low=0.6))


@pytest.fixture(scope="module")
def symmetric_motion():
    """The symmetric 1-2 motion (one impact on each stop) at omega = 1.6, from rest."""
    osc = _backlash(1.6)
    return multi_impact_orbit(osc, 1, 2, simulate(osc, np.zeros(4), 0.0, 30.0))


# 8. Bounds in b that close the clearance between the stops
def test_bounds_in_b_that_close_the_clearance_are_refused(symmetric_motion):
    """b <= -b_low puts the upper stop on or below the lower one: refused at the start,
    naming the parameter, the bounds and the stops (it ran until 'step size fell below
    ds_min')."""
    with pytest.raises(ParameterError, match=r"bounds \(-2.0, 1.0\) of parameter 'b' reach "
                       r"b = -0.5.*Stops\(mass=1, b_low=0.5, R_low=0.6\).*clearance"):
        multi_impact_continuation(symmetric_motion, "b", (-2, 1))
    with pytest.raises(ParameterError, match=re.escape("b > -0.5")):
        multi_impact_continuation(symmetric_motion, "b", (-0.5, 1))


def test_branch_traced_to_the_closing_clearance_says_so(symmetric_motion):
    """Traced directly (no start check), the branch ends ds_min short of b = -b_low with a
    reason naming the stops, not with steps refused until ds_min."""
    problem = MultiImpactBranchProblem(symmetric_motion.oscillator, 1, 2, "b",
                                       pattern=symmetric_motion.pattern)
    options = make_options((-2.0, 1.0), direction=-1, both_directions=False, ds_max=0.1)
    samples, statuses, message = trace_branch(problem, symmetric_motion.unknowns, 0.5, options)
    assert statuses == ["BOUNDS_REACHED"]
    assert samples[-1].lam == pytest.approx(-0.5, abs=1e-7) and samples[-1].lam > -0.5
    assert "upper stop x1 = b meets the lower stop x1 = -b_low" in message
    assert "Stops(mass=1, b_low=0.5, R_low=0.6)" in message
    assert "ds_min" not in message.split(";")[0]  # the core's own reason is the bound


# ------------------------------------------------------------------------------------------
# 3. The symmetric motion near its symmetry-breaking pitchfork
# ------------------------------------------------------------------------------------------
# On the symmetric motion (X_1 = -X_0, tau_0 = tau_1 = T/2) G is the square of the half-map
# H = S G_0; the pitchfork where the asymmetric pair is born is det(H + I) = 0 (studies/
# backlash: omega = 1.3378193721). The 1-2 shooting system is singular there; the half-map
# fixed point below (2n equations in delta and z_0) is regular, and is the reference.
_S = np.diag([-1.0, -1.0, -1.0, 1.0])  # the reflection in [z, theta]


def _symmetric_reference(omega: float, seed: np.ndarray) -> tuple[np.ndarray, object]:
    """The symmetric motion at omega as a fixed point of the half-map: (seed, orbit)."""
    osc = _backlash(omega)
    flow = Flow(osc)
    T = 2 * math.pi / omega
    Phi, E = flow.matrices(T / 2)
    d = np.array([1.0, 1.0, -osc.stops.R_low, 1.0])  # lower-stop impact law

    def half(v):  # flight from the upper stop, impact below, reflection: back to the start
        X = np.concatenate([[osc.b], v[1:]])
        return -(d * (Phi @ X + E @ np.array([math.cos(v[0]), math.sin(v[0])]))) - X

    v = fsolve(half, seed, xtol=1e-14, full_output=True)[0]
    assert np.max(np.abs(half(v))) < 1e-13
    X0 = np.concatenate([[osc.b], v[1:]])
    u = np.concatenate([[v[0], T / 2], X0[1:], -X0[1:]])
    return v, orbit_from_unknowns(flow, 1, 2, u, pattern="UL")


@pytest.fixture(scope="module")
def pitchfork(symmetric_motion):
    """(omega at the pitchfork, half-map seed) of the symmetric motion."""
    orbit = symmetric_motion
    for omega in (1.5, 1.42, 1.36):
        orbit = multi_impact_orbit(_backlash(omega), 1, 2, orbit)
    k = orbit.pattern.index("U")
    seed = np.concatenate([[orbit.phases[k]], orbit.states[k][1:]])

    def test(omega):
        H = _S @ _symmetric_reference(omega, seed)[1].jacobians[0]
        return np.linalg.det(H + np.eye(4))

    omega = brentq(test, 1.3378, 1.3379, xtol=1e-15)
    assert omega == pytest.approx(1.3378193721, abs=1e-9)  # studies/backlash
    return omega, seed


def _guess(orbit):
    return {"delta": orbit.delta, "flight_times": orbit.flight_times, "states": orbit.states,
            "pattern": orbit.pattern}


def test_at_the_pitchfork_the_motion_is_reported_singular(pitchfork):
    """From the exact motion at the pitchfork: the motion comes back (it used to be moved
    off by 8e-6 silently, or Newton failed blaming the guess's impact sequence), with a
    warning naming the bifurcation point and an error estimate that covers the error."""
    omega, seed = pitchfork
    exact = _symmetric_reference(omega, seed)[1]
    with pytest.warns(IllConditionedWarning,
                      match=rf"singular: a bifurcation point at omega={re.escape(repr(omega))}"):
        orbit = multi_impact_orbit(_backlash(omega), 1, 2, _guess(exact))
    assert orbit.error_estimate > 1e-6
    assert np.linalg.norm(orbit.unknowns - exact.unknowns) <= orbit.error_estimate


def test_next_to_the_pitchfork_the_error_estimate_is_stated(pitchfork):
    """1e-11 from the pitchfork, from the motion 1e-4 away: the condition number (1.3e11)
    allows errors of ~1e-5 in the motion; the warning says so and the estimate covers the
    actual error (no warning before: the threshold was a condition number of 1e12)."""
    omega, seed = pitchfork
    guess = _guess(_symmetric_reference(omega + 1e-4, seed)[1])
    target = omega + 1e-11
    exact = _symmetric_reference(target, seed)[1]
    with pytest.warns(IllConditionedWarning, match=r"bifurcation point at omega=.*condition "
                      r"number [0-9.e+]+.*error of about"):
        orbit = multi_impact_orbit(_backlash(target), 1, 2, guess)
    assert np.linalg.norm(orbit.unknowns - exact.unknowns) <= orbit.error_estimate
    assert orbit.condition_number > 1e10


def test_away_from_the_pitchfork_no_warning_and_accurate(pitchfork):
    """1e-6 from the pitchfork the motion is accurate to its (small) error estimate."""
    omega, seed = pitchfork
    target = omega + 1e-6
    exact = _symmetric_reference(target, seed)[1]
    with warnings.catch_warnings():
        warnings.simplefilter("error", IllConditionedWarning)
        orbit = multi_impact_orbit(_backlash(target), 1, 2,
                                   _guess(_symmetric_reference(omega + 1e-4, seed)[1]))
    scale = max(1.0, float(np.max(np.abs(orbit.unknowns))))
    assert orbit.error_estimate <= 1e-6 * scale
    assert np.linalg.norm(orbit.unknowns - exact.unknowns) <= max(orbit.error_estimate, 1e-12)


def test_newton_stalled_at_the_pitchfork_names_the_bifurcation(pitchfork):
    """Newton cut short next to the singular point (1e-4 off along the null vector, two
    iterations: it converges only linearly there) names the bifurcation point and its
    parameters; it used to ask whether the guess has the right sequence of stops. (From
    1e-5 off, two iterations converge or not by the last bits of the pitchfork's omega:
    a seed scaled by 1 - 1e-15 changed the outcome.)"""
    omega, seed = pitchfork
    exact = _symmetric_reference(omega, seed)[1]
    flow = Flow(_backlash(omega))
    J = shooting(flow, 1, 2, exact.unknowns, pattern="UL").jacobian
    null = np.linalg.svd(J)[2][-1]
    null = null * np.sign(null[0])  # the SVD's sign is arbitrary: rounding may flip it
    guess = orbit_from_unknowns(flow, 1, 2, exact.unknowns + 1e-4 * null, pattern="UL",
                                checks=False)
    with pytest.raises(NoPeriodicMotionError, match=rf"singular: a bifurcation point at "
                       rf"omega={re.escape(repr(omega))}, b=0.5, b_low=0.5") as info:
        multi_impact_orbit(flow.osc, 1, 2, _guess(guess), max_iter=2)
    assert "is the guess" not in str(info.value)


# ------------------------------------------------------------------------------------------
# Issue 28, 1.6: a constant force that pushes a free mode away from every stop holding it
# ------------------------------------------------------------------------------------------
# M = I2, K = diag(1, 0), one stop above the free mass 2 (Stops(mass=2)) and F_static =
# [0, -1]: the force pulls mass 2 down, away from its only stop, for ever; simulate returned
# COMPLETED with no impact and x2 = -7896. It is refused at construction, naming the mode and
# the force. A force into the stop, or a mode held on both sides, is a machine.

def _free_ball(F_static, **stops):
    return ic.ImpactOscillator(M=np.eye(2), K=np.diag([1.0, 0.0]), F=[1.0, 0.0], R=0.8, b=1.0,
                               omega=1.3, eta=0.05, F_static=F_static,
                               stops=Stops(mass=2, **stops))


def test_a_constant_force_pulling_a_free_mass_off_its_only_stop_is_refused():
    with pytest.raises(ParameterError, match=re.escape(
            "F_static = [0.0, -1.0] pushes the free (rigid-body) mode u = [0.0, -1.0] away from "
            "every stop")) as err:
        _free_ball([0.0, -1.0])
    message = str(err.value)
    assert "'U'" in message and "Allowed:" in message


def test_a_constant_force_pushing_a_free_mass_into_its_stop_is_a_machine():
    osc = _free_ball([0.0, 1.0])  # pressed into U (a ball under gravity on a ceiling... or
    assert osc.free_modes.shape[1] == 1  # a floor met moving down, below)
    _free_ball([0.0, -1.0], b_low=0.5)  # held on both sides: the lower stop takes it
    _free_ball([0.3, -1.0], mirror=True)
    # a ball under gravity on a floor: a lower extra stop below it takes the weight
    ic.ImpactOscillator(M=np.eye(2), K=np.diag([1.0, 0.0]), F=[1.0, 0.0], R=0.8, b=1.0,
                        omega=1.3, F_static=[0.0, -9.81],
                        stops=Stops(extra=(ic.Stop("A", mass=2, gap=0.5, side=-1,
                                                   restitution=0.7),)))


def test_a_constant_force_on_two_free_modes_is_checked_along_every_escape():
    """Two free masses 2 and 3, U on x2 and an extra stop A on x3 - x2 (x3 above x2 by at most
    0.5): a force pushing both masses up is held (x2 by U, x3 by A over x2); one pulling mass
    3 down is not (nothing holds x3 from below)."""
    def two(F_static):
        return ic.ImpactOscillator(
            M=np.eye(3), K=np.diag([1.0, 0.0, 0.0]), F=[1.0, 0.0, 0.0], R=0.8, b=1.0,
            omega=1.3, eta=0.05, F_static=F_static,
            stops=Stops(mass=2, extra=(ic.Stop("A", mass=3, relative_to=2, gap=0.5,
                                               restitution=0.5),)))
    two([0.0, 0.2, 0.5])
    with pytest.raises(ParameterError, match=r"pushes the free \(rigid-body\) mode u = "
                                             r"\[0\.0, 0\.0, -1\.0\]"):
        two([0.0, 0.2, -0.5])


# ------------------------------------------------------------------------------------------
# Issue 28, 4: F = 0 was refused as "gives no motion at all", false with gravity or an
# initial velocity. An unforced machine is simulated; the periodic-motion paths, which need
# the forcing's period and phase, refuse it saying so.
# ------------------------------------------------------------------------------------------

def test_a_ball_bouncing_on_a_still_table_is_simulated():
    """Gravity 1 (F_static), no forcing, a floor below the free ball (lower stop at 0, R
    0.8): from x' = 2 the flights are 2 v / g with v = 2, 1.6, 1.28, ... (closed form)."""
    ball = ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[0.0], F_static=[-1.0], R=0.8,
                               b=100.0, omega=1.0, stops=Stops(b_low=0.0, R_low=0.8))
    res = simulate(ball, [0.0, 2.0], 0.0, 3.0)
    speeds = 2.0 * 0.8 ** np.arange(5)
    np.testing.assert_allclose(res.impact_times[:5], np.cumsum(2.0 * speeds), rtol=1e-12)
    np.testing.assert_allclose(res.impact_velocities[:5], speeds, rtol=1e-12)
    assert set(res.impact_stops) == {"L"}


def test_an_unforced_chain_is_simulated_from_a_state(paper):
    osc = paper.replace(F=[0.0, 0.0], b=0.3)
    res = simulate(osc, [0.0, 0.0, 1.0, 0.0], 0.0, 3.0)
    assert res.impact_times.size >= 1 and res.impact_velocities[0] > 0
    still = simulate(osc, np.zeros(4), 0.0, 3.0)  # at rest, unforced: stays at rest
    assert still.impact_times.size == 0 and np.all(still.final_state == 0.0)


def test_periodic_motions_of_an_unforced_machine_are_refused(paper):
    osc = paper.replace(F=[0.0, 0.0])
    with pytest.raises(ParameterError, match=re.escape(
            "F = [0.0, 0.0] (no harmonic forcing): periodic motions have the forcing's period")):
        ic.periodic_orbits(osc, 1)
    guess = {"delta": 0.0, "flight_times": [2 * np.pi], "states": [[0.6, 0.0, 0.1, 0.0]]}
    with pytest.raises(ParameterError, match=re.escape(  # not "singular Jacobian"
            "multi_impact_orbit: F = [0.0, 0.0] (no harmonic forcing)")):
        ic.multi_impact_orbit(osc, 1, 1, guess)
    with pytest.raises(ParameterError, match=r"F0=2\.0 scales the oscillator's F, which is 0"):
        osc.replace(F0=2.0)

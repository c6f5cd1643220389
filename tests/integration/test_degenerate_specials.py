"""Special points not reported where a motion with sticking phases degenerates.

Two branches of a new user's: past the onset of complete chatter of the preloaded
one-mass oscillator the chatter no longer accumulates inside the stick (and over an
interval of omega not at all: incomplete chatter), which is no held phase; and the ball
on a table, whose one flight shrinks to nothing as the forcing just lifts it (F0 -> 1),
where the impact velocity (the pole of G that PD and NS were cleared of, and where the
branch's system is singular) changes sign in a step the locator cannot follow.
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.problems.multi_impact_branch import release_grazing_test, sticking_onset_test


def _preloaded(omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                               omega=omega, eta=0.05)


@pytest.fixture(scope="module")
def chatter_entered() -> ic.MultiImpactOrbit:
    osc = _preloaded(0.7)
    return ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, [0.0, 0.0], 0.0, 60.0))


def test_an_incomplete_chatter_enters_no_held_phase(chatter_entered):
    # at omega = 1.16 the landing's chatter does not accumulate: no stick, whatever the
    # pressing force at the landing (positive there)
    prev = chatter_entered
    for omega in np.linspace(0.72, 1.16, 23):
        prev = ic.multi_impact_orbit(_preloaded(float(omega)), 1, 1, prev)
    assert "incomplete chatter" in prev.reason and not prev.chatters
    assert prev.landing_pressing[0] > 0.0
    assert sticking_onset_test(prev) < 0.0
    assert release_grazing_test(prev) < 0.0


def test_the_onset_of_complete_chatter_is_the_one_special_point(chatter_entered):
    branch = ic.continuation(chatter_entered, parameter="omega", bounds=(0.5, 1.2))
    assert list(branch.special_label.values) == ["SO"]
    assert branch.special_status.values[0] == "located"
    assert branch.special_omega.values[0] == pytest.approx(0.92769, abs=1e-5)


def _ball_on_a_table(F0: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[F0], F_static=[-1.0], R=0.5, b=100.0,
                               omega=1.0, stops=Stops(b_low=0.0, R_low=0.0))


@pytest.fixture(scope="module")
def ball_branch():
    osc = _ball_on_a_table(2.0)
    start = ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, [0.0, 0.0], 0.0,
                                                          60 * 2 * np.pi))
    return ic.continuation(start, parameter="F0", bounds=(1.0, 3.0))


def test_no_fold_or_period_doubling_where_a_flight_vanishes(ball_branch):
    branch = ball_branch
    assert np.all(branch.multipliers.values == 0.0)  # a stick forgets the state: G = 0
    labels = set(branch.special_label.values.tolist())
    assert not labels & {"SN", "PD", "NS"}


def test_the_end_of_the_flight_is_the_one_special_point(ball_branch):
    """As F0 -> 1 the ball's one flight shrinks to nothing and the branch turns there: the
    end of the flight (FT) is the one point, located although the shooting system is
    singular there; no bracketed ZV (the flight's landing at rest) or RG (a pressing force
    among the motions past it, whose flight time is negative) besides it."""
    branch = ball_branch
    assert list(branch.special_label.values) == ["FT"]
    assert branch.special_status.values[0] == "located"
    value, precision = float(branch.special_F0.values[0]), float(
        branch.special_precision.values[0])
    assert precision < 1e-10
    # the forcing lifts the ball when its amplitude exceeds the weight: F0 = 1 exactly
    assert abs(value - 1.0) <= precision
    assert abs(float(branch.special_flight_time_k.values[0, 0])) < 1e-9
    # the whole period is the stick there
    assert float(branch.special_stick_time_k.values[0, 0]) == pytest.approx(2 * np.pi,
                                                                            abs=1e-8)
    # the branch's flights are physical on one side of it, negative on the other
    flights = branch.flight_time_k.values[:, 0]
    physical = branch.physical.values
    assert np.all(physical[flights > 1e-3]) and not np.any(physical[flights < 0.0])


def test_the_simulated_flights_vanish_where_the_end_of_the_flight_is(ball_branch):
    """The simulator's flight times (an independent witness) at F0 = 1.005 .. 1.04
    extrapolate to 0 at the located FT: F0 as a cubic in the flight time squared."""
    amplitudes = 1.0 + np.array([0.005, 0.01, 0.02, 0.04])
    flights = []
    for F0 in amplitudes:
        sim = ic.simulate(_ball_on_a_table(float(F0)), [0.0, 0.0], -1.0, 2.0)
        releases = [phase.end for phase in sim.sticking if phase.ended_by == "release"]
        flights.append(sim.impact_times[1] - releases[1])
    at_zero = np.polyfit(np.square(flights), amplitudes, 3)[-1]
    assert abs(at_zero - float(ball_branch.special_F0.values[0])) < 1e-8

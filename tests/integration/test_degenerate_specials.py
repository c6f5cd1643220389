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


def test_no_fold_or_period_doubling_where_a_flight_vanishes():
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[2.0], F_static=[-1.0], R=0.5, b=100.0,
                              omega=1.0, stops=Stops(b_low=0.0, R_low=0.0))
    start = ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, [0.0, 0.0], 0.0,
                                                          60 * 2 * np.pi))
    branch = ic.continuation(start, parameter="F0", bounds=(1.0, 3.0))
    assert np.all(branch.multipliers.values == 0.0)  # a stick forgets the state: G = 0
    labels = set(branch.special_label.values.tolist())
    assert not labels & {"SN", "PD", "NS"}

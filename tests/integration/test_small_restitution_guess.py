"""A simulation that sticks every period read as a guess, at any restitution.

A preloaded one-mass oscillator lands on its stop every period and sticks until the
contact force lets go. With R > 0 the landing starts a complete chatter whose impacts
accumulate (:mod:`impactcont.simulate.chatter`); with a small R the accumulation point
lies within the guess reader's time tolerance of the last impact resolved (R = 1e-3:
3.4e-9 after it, the tolerance 4.6e-7), and the stick was read as starting at that
impact as a plastic landing would: the chatter's bounces stayed in the guess as impacts
and a 1-1 guess read as the flight between two of them (pattern 'U', a flight of
3.3e-6) instead of the sticky motion 'u' the simulation shows.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.orbit.multi_impact import landing_impacts


def _preloaded(R: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=R, b=0.0,
                               omega=0.7, eta=0.05)


@pytest.mark.parametrize("R", [1e-2, 1e-3, 1e-6])
def test_a_stick_entered_through_a_short_chatter_is_read_as_a_sticking_phase(R):
    osc = _preloaded(R)
    run = ic.simulate(osc, [0.0, 0.0], 0.0, 60.0)
    assert len(run.chatter) >= 50  # the simulation chatters and sticks every period
    kept, landings = landing_impacts(run)
    # every stick's chatter left out but its landing: each kept impact but the last lands
    assert len(landings) == kept.size - 1
    motion = ic.multi_impact_orbit(osc, 1, 1, run)
    assert motion.pattern == "u" and motion.physical
    # the stick lasts from the landing (the first impact after the release before it) to
    # its release, as simulated (the motion is the simulation's attractor)
    before, phase = run.sticking[-3], run.sticking[-2]
    landing = run.impact_times[np.searchsorted(run.impact_times, before.end, side="right")]
    assert motion.stick_times[0] == pytest.approx(phase.end - landing, rel=0, abs=1e-6)
    assert motion.flight_times[0] + motion.stick_times[0] == pytest.approx(
        2 * math.pi / osc.omega, rel=1e-12)

def test_the_plastic_and_the_well_resolved_chatter_read_the_same_motion():
    """R = 0 (a plastic landing) and R = 0.5 (a chatter of about 20 resolved impacts) read
    'u' already: the stick time from the landing agrees with the simulation's."""
    for R in (0.0, 0.5):
        osc = _preloaded(R)
        run = ic.simulate(osc, [0.0, 0.0], 0.0, 60.0)
        motion = ic.multi_impact_orbit(osc, 1, 1, run)
        assert motion.pattern == "u"
        assert motion.physical

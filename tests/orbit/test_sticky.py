"""Motions with sticking phases (:mod:`impactcont.orbit.sticky`): how a sticking phase is
entered (plastic impact or complete chatter) and how a simulation's chatter is folded into
its landing (:func:`impactcont.orbit.multi_impact.landing_impacts`)."""

from __future__ import annotations

import math
import re
from typing import NamedTuple

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops, sticking_pattern
from impactcont.orbit.multi_impact import landing_impacts
from impactcont.orbit.sticky import (
    CHATTER_SPEED,
    chatter_entered,
    chatter_impacts,
    chatter_restitution,
)


def _damper(R: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=R, b=0.3, omega=0.2, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


@pytest.mark.parametrize("R", [0.1, 0.3, 0.5, 0.9])
def test_the_chatter_is_resolved_until_its_speed_is_chatter_speed_of_the_landings(R):
    K = chatter_impacts(R)
    assert R**K <= CHATTER_SPEED < R ** (K - 1)
    assert chatter_impacts(0.0) == 0


def test_a_stick_on_a_stop_with_restitution_is_entered_through_chatter():
    assert chatter_entered(_damper(0.3), "lu") and not chatter_entered(_damper(0.0), "lu")
    assert not chatter_entered(_damper(0.3), "LU")
    assert chatter_restitution(_damper(0.3), "L") == pytest.approx(0.3)
    impacts, sticks = sticking_pattern(_damper(0.3), "lU")
    assert impacts == "LU" and list(sticks) == [True, False]
    with pytest.raises(ic.ParameterError, match=r"restitution >= 1 they do not accumulate"):
        sticking_pattern(_damper(1.0), "lu")


class _Phase(NamedTuple):
    start: float
    end: float
    stops: str
    ended_by: str


class _Run(NamedTuple):
    impact_times: np.ndarray
    impact_stops: str
    sticking: tuple[_Phase, ...]


def test_a_chatters_impacts_are_folded_into_its_landing():
    """L lands at 1 and chatters (1.5, 1.7) to its accumulation at 1.8, released at 3; U
    lands at 4 plastically (the stick starts at the impact); L lands at 6 and chatters on
    (6.5) to the end of the run: kept are the landings and the impact U at 0."""
    run = _Run(np.array([0.0, 1.0, 1.5, 1.7, 4.0, 6.0, 6.5]), "ULLLULL",
               (_Phase(1.8, 3.0, "L", "release"), _Phase(4.0, 5.0, "U", "release")))
    kept, landings = landing_impacts(run)
    assert list(kept) == [0, 1, 4, 5]
    assert landings[1].start == 1.8 and landings[4].start == 4.0 and set(landings) == {1, 4}


def test_a_plastic_run_keeps_every_impact():
    """R = 0: sticking phases start at their impacts; impacts on one stop in a row (an
    impact, a flight, a landing) stay separate."""
    run = _Run(np.array([0.0, 1.0, 2.0, 3.0]), "UUUU", (_Phase(1.0, 1.5, "U", "release"),))
    kept, landings = landing_impacts(run)
    assert list(kept) == [0, 1, 2, 3] and set(landings) == {1}
    assert math.isfinite(landings[1].end)


def test_a_chatter_entered_ride_is_searched_from_its_accumulation_point():
    """The riding damper with R = 0.3 at omega 0.8 and a stop A on the primary at x1 =
    -1.80: its chatter's bounces (x1 down to -1.824) and the ride after them (from -1.802
    at the accumulation point, rising) both reach A, each named. The ride is searched from
    the accumulation point: its clearance is there (its time from the landing the chatter's
    duration, x1 at the accumulation point the stop less the clearance); the segment's
    smallest clearance, ``flight_gap_min[0]``, is the bounces' (-0.024, inside the
    chatter: GR sees a bounce reaching another stop)."""
    osc = _damper(0.3).replace(omega=0.8)
    start = np.array([-0.5, -0.2, 0.0, 0.0])
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, start, 0.0, 8.0))
    assert motion.physical and motion.pattern == "lu", motion.reason
    extra = (ic.Stop("A", mass=1, gap=1.80, restitution=0.5, side=-1),)
    capped = osc.replace(stops=Stops(mass=2, relative_to=1, mirror=True, extra=extra))
    shot = ic.multi_impact_orbit(capped, 1, 2, motion)
    assert "impact 0: a bounce of the chatter on stop 'L' reaches stop 'A'" in shot.reason
    ride = re.search(r"sticking phase 0 \(stop 'L'\): x1 reaches stop 'A' while 'L' holds "
                     r"\(clearance (\S+) at t=(\S+) after impact 0\)", shot.reason)
    assert ride is not None, shot.reason
    chatter = shot.chatters[0]
    gap, when = float(ride[1]), float(ride[2])
    assert when == pytest.approx(chatter.duration, rel=1e-6)
    assert chatter.accumulation[0] == pytest.approx(-1.80 + gap, abs=1e-5)  # 3 digits
    bounces = float(shot.flight_gap_min[0])
    assert shot.flight_gap_stops[0] == "A" and bounces < gap < 0.0
    assert 0.0 < shot.flight_gap_min_times[0] + shot.stick_times[0] < chatter.duration


@pytest.mark.parametrize("R", [0.0, 0.3])
def test_held_segments_at_a_new_omega_reuse_the_start_s_and_equal_those_built_afresh(R):
    """A branch in omega (the flow and held flows at a new omega made from the start's, as
    MultiImpactBranchProblem.flow_at does) reuses the start's omega-free held tables and
    takes the forced amplitudes and release shifts anew: the arrays equal those of the
    oscillator built afresh at that omega (the same arithmetic: 1e-13 relative); another
    stop position is built afresh."""
    from impactcont.orbit.flow import flow_of
    from impactcont.orbit.held_flow import held_flow, held_flow_at
    from impactcont.orbit.sticky import held_segments
    from impactcont.problems.multi_impact_branch import _at_frequency, _flow_at_frequency

    osc = _damper(R)
    base = held_segments(flow_of(osc), "lu")
    moved = osc.replace(omega=0.23)
    for name in "UL":
        start = held_flow(osc, name)
        held_flow_at(start, moved, name, _flow_at_frequency(
            start.reduced, start.reduced.osc.replace(omega=moved.omega)))
    made = held_segments(_at_frequency(flow_of(osc), moved), "lu")
    fresh = held_segments(flow_of(_damper(R).replace(omega=0.23)), "lu")
    for mine, theirs in zip(made, fresh, strict=True):
        assert np.asarray(mine) == pytest.approx(np.asarray(theirs), rel=1e-13, abs=1e-13)
    assert made[1] is base[1] and fresh[1] is not base[1]  # the lifts: shared, not rebuilt
    assert not np.allclose(made[9], base[9])  # Z moves with omega
    other = held_segments(flow_of(osc.replace(b=0.35)), "lu")
    assert not np.allclose(other[3], base[3])  # the stop's offset moves with it

"""Other stops along a motion with sticking phases (issue 30): while the ball of the impact
damper rides a wall of the primary (pattern ``"lu"``, R = 0), the primary moves with it and
may reach a stop of its own; and a flight from a release may graze it.

The machine: the riding damper of ``tests/integration/test_sticking_branches.py`` (primary 1
on spring 1, eta 0.3; plastic ball 0.2 in ``|x2 - x1| <= 0.3``) with a stop ``A`` on the
primary, ``x1 >= -gap`` (met moving down). Along the ride on the lower wall (sticking
phase 0) the pair swings lower than in any flight for omega below about 1.2 (omega 1.0: x1
down to -1.453 held, -1.389 in the flights) and higher above it (omega 1.5: -0.394 held,
-0.481 in the flight from the upper wall's release). So ``gap = 1.42`` at omega 1.0 is
crossed only while the ball is held, by 0.033, and ``gap = 0.55`` near omega 1.42 is grazed
by a flight first.

Witness: the simulator (:func:`impactcont.simulate`: its own flow, contact search and
sticking model, no code shared with the shooting path), at the motion's impact state: the
impact on A inside the sticking phase, the held ride otherwise, and the extremum of x1 from
its trajectory sampled at 20,000 points a period (its sampling error at an extremum,
``h^2 |x1''| / 8`` with ``h = 2 pi / (20000 omega)``, is below 1e-7 here: checked to 1e-6).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stops
from tests.integration.test_sticking_branches import riding_start

#: Samples per forcing period of the simulated trajectories sampled for an extremum.
DENSE = 20_000


def damper(omega: float, gap: float | None = None) -> ic.ImpactOscillator:
    """The riding damper; with `gap`, the stop A at ``x1 = -gap`` (met moving down)."""
    extra = () if gap is None else (ic.Stop("A", mass=1, gap=gap, restitution=0.5, side=-1),)
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True, extra=extra))


@functools.cache
def riding(omega: float) -> ic.MultiImpactOrbit:
    """The riding motion of the damper without A, impact 0 the landing on the lower wall."""
    osc = damper(omega)
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 30.0))
    assert motion.physical and sorted(motion.pattern) == ["l", "u"], motion.reason
    if motion.pattern == "ul":
        motion = ic.multi_impact_orbit(osc, 1, 2, {
            "delta": float(motion.phases[1]), "pattern": "lu",
            "flight_times": np.roll(motion.flight_times, -1),
            "stick_times": np.roll(motion.stick_times, -1),
            "states": np.roll(motion.states, -1, axis=0)})
    return motion


def with_stop(motion: ic.MultiImpactOrbit, gap: float, omega: float | None = None
              ) -> ic.MultiImpactOrbit:
    """`motion` solved again on the machine with A at `gap` (at `omega`: seeded by it)."""
    osc = damper(motion.oscillator.omega if omega is None else omega, gap)
    return ic.multi_impact_orbit(osc, 1, 2, motion)


def dense_x1(motion: ic.MultiImpactOrbit, start: float, end: float) -> np.ndarray:
    """The simulator's x1 on ``[start, end]`` after impact 0 of `motion`, on the machine
    without A (the simulated motion rides the wall as the motion does), DENSE samples a
    period."""
    osc = damper(motion.oscillator.omega)
    run = ic.simulate(osc, motion.states[0], float(motion.phases[0]),
                      end * osc.omega / (2 * np.pi) * 1.01, trajectory=True,
                      samples_per_period=DENSE)
    inside = (run.t >= start) & (run.t <= end)
    return run.X[inside, 0]


def first_impact_on_A(motion: ic.MultiImpactOrbit, gap: float) -> float:
    """When the simulator from impact 0 of `motion` on the machine with A at `gap` first
    hits A within one period (NaN: not at all)."""
    osc = damper(motion.oscillator.omega, gap)
    run = ic.simulate(osc, motion.states[0], float(motion.phases[0]), 1.0)
    hits = [t for t, s in zip(run.impact_times, run.impact_stops, strict=True) if s == "A"]
    return hits[0] if hits else np.nan


def test_the_primary_crossing_its_stop_while_the_ball_rides_is_not_physical():
    """Omega 1.0, A at x1 = -1.42: the motion (its flights clear of A by 0.03) is not
    physical, the reason naming the sticking phase, the coordinate, the stop and the time
    of the deepest point; the simulator from impact 0 rides the wall and hits A inside the
    ride, where the held flow has x1 = -1.42, and without A its lowest x1 in the ride is
    the reported clearance below the stop."""
    free = riding(1.0)
    motion = with_stop(free, 1.42)
    assert not motion.physical
    assert "flight" not in motion.reason  # only the held phase reaches A
    assert "sticking phase 0 (stop 'L'): x1 reaches stop 'A' while 'L' holds" in motion.reason
    gap, when = float(motion.flight_gap_min[0]), float(motion.flight_gap_min_times[0])
    stick = float(motion.stick_times[0])
    assert motion.flight_gap_stops[0] == "A" and gap < -0.03 and -stick < when < 0.0
    assert f"at t={when + stick:.6g} after impact 0" in motion.reason
    hit = first_impact_on_A(motion, 1.42)
    assert 0.0 < hit < when + stick  # inside the ride, before its deepest point
    held = ic.orbit.held_flow.held_flow(motion.oscillator, "L")
    assert held.state(hit, motion.states[0], float(motion.phases[0]))[0, 0] == pytest.approx(
        -1.42, abs=1e-9)
    x1 = dense_x1(free, 0.0, stick)
    assert x1.min() == pytest.approx(-1.42 + gap, abs=1e-6)


def test_a_stop_clear_of_the_ride_leaves_the_motion_physical():
    """A at x1 = -1.46, 0.0066 below the ride's lowest point: physical, the segment's
    smallest clearance the ride's (stop A, inside the stick), and the simulator on that
    machine rides the wall for the whole stick time, its lowest x1 the held one."""
    free = riding(1.0)
    motion = with_stop(free, 1.46)
    assert motion.physical, motion.reason
    gap, stick = float(motion.flight_gap_min[0]), float(motion.stick_times[0])
    assert motion.flight_gap_stops[0] == "A" and 0.006 < gap < 0.007
    assert -stick < float(motion.flight_gap_min_times[0]) < 0.0
    osc = damper(1.0, 1.46)
    run = ic.simulate(osc, motion.states[0], float(motion.phases[0]), 1.0)
    assert "A" not in run.impact_stops
    ride = run.sticking[0]
    assert ride.stops == "L" and ride.ended_by == "release"
    assert ride.end - ride.start == pytest.approx(stick, abs=1e-8)
    assert dense_x1(free, 0.0, stick).min() == pytest.approx(-1.46 + gap, abs=1e-6)
    # without A: the other wall, 0.6 away all along each ride (the ball's own coordinate)
    assert free.flight_gap_min == pytest.approx([0.6, 0.6], abs=1e-6)


@functools.cache
def grazing_branch(gap: float, start: float, bounds: tuple[float, float]):
    """The riding motion on the machine with A at `gap`, followed in omega from `start`
    down to ``bounds[0]``."""
    motion = with_stop(riding(start), gap)
    assert motion.physical, motion.reason
    return ic.continuation(motion, parameter="omega", bounds=bounds, both_directions=False,
                           direction=-1)


def _located(ds) -> tuple[float, int]:
    """The one special point of the branch: GR, located; its omega and nearest point."""
    assert list(ds.special_label.values) == ["GR"]
    assert ds.special_status.values[0] == "located"
    precision = float(ds.special_precision.values[0])
    assert precision < 1e-10
    return float(ds.special_omega.values[0]), int(ds.special_point.values[0])


def _solved(ds, i: int, gap: float, omega: float) -> ic.MultiImpactOrbit:
    seed = {"delta": float(ds.delta_k.values[i, 0]), "pattern": ds.attrs["pattern"],
            "flight_times": ds.flight_time_k.values[i], "stick_times": ds.stick_time_k.values[i],
            "states": ds.state_k.values[i]}
    return ic.multi_impact_orbit(damper(omega, gap), 1, 2, seed)


def test_a_grazing_inside_a_ride_is_located_as_GR():
    """A at x1 = -1.42, omega from 1.1 down to 1.0: the ride's lowest point reaches A at
    the branch's GR (the held phase's clearance is part of gap_min); the motion solved
    alone there has gap_min 0 inside the stick, and the simulator sampled densely there
    has its lowest x1 in the ride at -1.42; 1e-4 below that omega the simulator from the
    motion's impact state hits A inside the ride, 1e-4 above it does not."""
    ds = grazing_branch(1.42, 1.1, (1.0, 1.1))
    omega, i = _located(ds)
    assert 1.0 < omega < 1.1
    assert ds.physical.values[ds.omega.values > omega].all()
    assert not ds.physical.values[ds.omega.values < omega].any()
    there = _solved(ds, i, 1.42, omega)
    assert there.gap_min == pytest.approx(0.0, abs=1e-9)
    k = int(np.argmin(there.flight_gap_min))
    stick = float(there.stick_times[k])
    assert there.flight_gap_stops[k] == "A" and -stick < there.flight_gap_min_times[k] < 0.0
    assert dense_x1(_solved(ds, i, 1.42, omega), 0.0, stick).min() == pytest.approx(
        -1.42, abs=1e-6)
    below, above = (_solved(ds, i, 1.42, omega * (1 + d)) for d in (-1e-4, 1e-4))
    hit = first_impact_on_A(below, 1.42)
    assert 0.0 < hit < float(below.stick_times[0])
    assert np.isnan(first_impact_on_A(above, 1.42))


def test_a_flight_grazing_another_stop_on_a_sticky_branch_is_located_as_GR():
    """A at x1 = -0.55, omega from 1.5 down to 1.4: the flight from the upper wall's
    release reaches A first (the rides stay above it), located as the branch's GR; there
    the motion solved alone has gap_min 0 inside that flight (its sticking phases clear of
    A), the simulator sampled densely has its lowest x1 in the flight at -0.55, and 1e-4
    below that omega the simulator from the motion's impact state hits A inside the
    flight, 1e-4 above it does not."""
    ds = grazing_branch(0.55, 1.5, (1.4, 1.5))
    omega, i = _located(ds)
    assert 1.4 < omega < 1.5
    there = _solved(ds, i, 0.55, omega)
    assert there.gap_min == pytest.approx(0.0, abs=1e-9)
    k = int(np.argmin(there.flight_gap_min))
    flight = float(there.flight_times[k])
    when = float(there.flight_gap_min_times[k])
    assert there.flight_gap_stops[k] == "A" and 0.0 < when < flight
    assert "sticking phase" not in there.reason
    released = float(np.sum(there.stick_times[:k + 1]) + np.sum(there.flight_times[:k]))
    x1 = dense_x1(there, released, released + flight)
    assert x1.min() == pytest.approx(-0.55, abs=1e-6)
    below, above = (_solved(ds, i, 0.55, omega * (1 + d)) for d in (-1e-4, 1e-4))
    hit = first_impact_on_A(below, 0.55)
    assert released < hit < released + flight
    assert np.isnan(first_impact_on_A(above, 0.55))


def test_a_simulation_holding_two_stops_at_once_is_refused_as_a_guess():
    """A chain whose steady motion holds mass 1 on U and mass 2 on A at once (the simulator
    holds several stops): a periodic motion's sticking phase holds one stop, from the
    impact on it to its release, so the guess is refused saying so. Before, it was read as
    the flights-only pattern 'AU' without stick times and solved to a motion that is not
    physical, without a word of the two held stops."""
    from impactcont.errors import ParameterError
    from impactcont.model.stops import Stop

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, -1.0], [-1.0, 1.0]], F=[1.5, 0.5],
                              F_static=[0.5, 0.3], R=0.0, b=0.0, omega=0.5, eta=0.05,
                              stops=Stops(extra=(Stop("A", mass=2, gap=0.1,
                                                      restitution=0.0),)))
    res = ic.simulate(osc, np.zeros(4), 0.0, 60 * 2 * np.pi / 0.5)
    assert any(phase.stops == "UA" for phase in res.sticking)  # both held at once
    with pytest.raises(ParameterError, match=r"holds the stops 'UA' at once.*one stop at a "
                                             r"time"):
        ic.multi_impact_orbit(osc, 1, 2, res)
    with pytest.raises(ParameterError, match="ends by 'impact', not by its release"):
        ic.multi_impact_orbit(osc, 1, 1, res)

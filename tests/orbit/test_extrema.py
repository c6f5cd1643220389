"""Displacement extrema of a motion (:mod:`impactcont.orbit.extrema`) against a dense time
series, over every flight of an N-p motion."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.extrema import displacement_extrema, max_displacement

K2 = [[1.0, -1.0], [-1.0, 2.0]]


V_LEVEL = 0.7   # impact velocity of the events below


def paper(**kw) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, **kw)


def velocity_event(orbit) -> float:
    return orbit.impact_velocity - V_LEVEL


@pytest.fixture(scope="module")
def symmetric_branch():
    """Symmetric 1-2 motions between mirrored stops (followed by their half)."""
    osc = paper(b=0.5, omega=1.6, stops=Stops(mirror=True))
    start = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    return ic.multi_impact_continuation(
        start, "omega", (1.3, 1.7), both_directions=True, ds_max=0.02, progress=False,
        events={"v07": velocity_event, "x2top": lambda o: max_displacement(o, 2) - 0.6},
        monitors={"x2max": lambda o: max_displacement(o, 2)})


# -- the displacement helper -----------------------------------------------------------------
def test_displacement_extrema_against_a_dense_time_series():
    osc = paper(b=0.6, omega=1.0)
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    _, X = orbit.time_series(num=40001)
    h = orbit.period / 40000
    for mass in (1, 2):
        lo, hi = displacement_extrema(orbit, mass)
        # the located extrema bound the samples and are within the grid's reach of them
        # (h^2/8 |x''| with |x''| <= 10 here)
        assert hi >= X[:, mass - 1].max() - 1e-12 and hi - X[:, mass - 1].max() < 2 * h * h
        assert lo <= X[:, mass - 1].min() + 1e-12 and X[:, mass - 1].min() - lo < 2 * h * h
    assert max_displacement(orbit, 1) == pytest.approx(osc.b, abs=1e-12)  # the stop
    for bad in (0, 3, 1.0, True):
        with pytest.raises(ParameterError, match=r"mass must be an integer in 1 \.\. 2"):
            max_displacement(orbit, bad)
    with pytest.raises(TypeError, match="PeriodicOrbit or MultiImpactOrbit"):
        max_displacement(osc, 1)


def test_displacement_extrema_of_an_n_p_motion_over_every_flight(symmetric_branch):
    osc = ic.dataset.oscillator_from_dataset(symmetric_branch, 10)
    motion = ic.multi_impact_orbit(osc, 1, 2, {
        "delta": float(symmetric_branch["delta_k"].values[10, 0]),
        "flight_times": symmetric_branch["flight_time_k"].values[10],
        "states": symmetric_branch["state_k"].values[10],
        "pattern": symmetric_branch.attrs["pattern"]})
    _, X = motion.time_series(num=20001)
    h = float(np.max(motion.flight_times)) / 20000
    for mass in (1, 2):
        lo, hi = displacement_extrema(motion, mass)
        assert 0 <= hi - X[:, mass - 1].max() + 1e-12 < 2 * h * h
        assert 0 <= X[:, mass - 1].min() - lo + 1e-12 < 2 * h * h
    # the motion is symmetric: mass 1 reaches both stops
    assert displacement_extrema(motion, 1) == pytest.approx((-osc.b, osc.b), abs=1e-10)

"""The paper's system at b = 0 and its period-doubling cascade (N = 1 -> 2-2 -> 4-4), with
the checks of an N-p motion the tests of the shooting, the N-p branches and the
switches share (fixtures registered by tests/conftest.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.switching import period_doubling_switch
from impactcont.dataset.multi import impacts_of
from impactcont.orbit.multi_impact import multi_impact_orbit

__all__ = ["assert_reproduced_by_simulator", "branch_22", "branch_44", "branch_n1",
           "orbit_at_point", "paper_b0", "wrap"]


@pytest.fixture(scope="module")
def paper_b0():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.5, eta=0.1)


@pytest.fixture(scope="module")
def branch_n1(paper_b0):
    return ic.continuation(paper_b0, N=1, parameter="omega", bounds=(1.4, 2.0),
                           components="start")


@pytest.fixture(scope="module")
def branch_22(branch_n1):
    return period_doubling_switch(branch_n1, bounds=(1.6, 1.9))


@pytest.fixture(scope="module")
def branch_44(branch_22):
    return period_doubling_switch(branch_22, bounds=(1.79, 1.83), ds_max=0.005)


def wrap(a):
    return np.remainder(np.asarray(a) + math.pi, 2 * math.pi) - math.pi


def orbit_at_point(ds, i):
    """The N-p motion stored at point i of a dataset, re-solved (one Newton polish)."""
    osc = ic.dataset.oscillator_from_dataset(ds, i)
    guess = {"delta": float(ds.delta_k.values[i, 0]), "flight_times": ds.flight_time_k.values[i],
             "states": ds.state_k.values[i]}
    return multi_impact_orbit(osc, int(ds.attrs["N"]), impacts_of(ds), guess)


def assert_reproduced_by_simulator(orbit, repeats, tol=1e-9):
    """Simulate from impact 0 for `repeats` periods: same phases and velocities per impact."""
    forcing_period = 2 * math.pi / orbit.oscillator.omega
    extra = 0.5 * orbit.flight_times.min() / forcing_period  # past impact 0, before impact 1
    res = ic.simulate(orbit.oscillator, orbit.state, orbit.delta, repeats * orbit.N + extra)
    assert res.success
    p = orbit.p
    assert res.impact_times.size == repeats * p
    k = np.arange(res.impact_times.size)
    # impact j of the simulation is impact (j + 1) mod p of the motion
    idx = (k + 1) % p
    np.testing.assert_allclose(res.impact_velocities, orbit.impact_velocities[idx], rtol=0,
                               atol=tol * max(1.0, orbit.impact_velocities.max()))
    assert np.abs(wrap(res.impact_phases - orbit.phases[idx])).max() < tol
    assert np.abs(res.impact_states[p - 1::p] - orbit.states[0]).max() < tol

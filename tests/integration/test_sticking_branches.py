"""Branches of periodic motions with sticking phases (issue 30 item 4): continuation of
the impact damper whose plastic ball rides each wall (pattern ``"lu"``), held against the
closed form of ``studies/sticking_motions/closed_form.py`` (mpmath, imports nothing from
the package) and against :func:`impactcont.multi_impact_orbit` solved alone.

The branch in omega (from 0.2) costs about 3 s; each closed-form motion about 1 s.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

STUDY = Path(__file__).resolve().parents[2] / "studies" / "sticking_motions"

#: Where the closed form puts the end of the ride in omega (the landing is a release;
#: studies/sticking_motions/README.md, closed_form.riding_end).
RIDING_END = 2.393422959745478


@pytest.fixture(scope="module")
def cf():
    spec = importlib.util.spec_from_file_location("sticking_closed_form_b",
                                                  STUDY / "closed_form.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look the module up by name
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(spec.name, None)


def damper(omega: float, **more) -> ic.ImpactOscillator:
    """Case (c) of the study: primary 1 on spring 1 (eta 0.3), plastic ball 0.2 in
    |x2 - x1| <= 0.3."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True), **more)


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


@functools.cache
def riding(omega: float = 0.2):
    osc = damper(omega)
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 12.0))


@functools.cache
def branch():
    """The riding motion followed in omega from 0.2 past the end of its ride."""
    return ic.continuation(riding(), parameter="omega", bounds=(0.19, 2.45), ds_max=0.1,
                           both_directions=False)


def test_the_branch_in_omega_is_the_closed_form_and_the_solve_alone(cf):
    """Points of the branch: the closed form (two omegas) and multi_impact_orbit solved
    alone from a simulated steady state (two omegas), every quantity to 1e-9; the
    stick time falls to 0 at the end of the ride, and the motion is physical up to it."""
    ds = branch()
    assert ds.attrs["pattern"] == "lu"
    omega = ds.omega.values
    assert omega[0] == pytest.approx(0.2) and omega[-1] == pytest.approx(2.45)
    physical = ds.physical.values
    inside = omega < RIDING_END - 1e-3
    assert physical[inside].all() and not physical[omega > RIDING_END + 1e-3].any()
    for target in (0.5, 1.2):
        i = int(np.argmin(np.abs(omega - target)))
        motion = cf.riding_damper_motion(float(omega[i]))
        assert np.abs(np.remainder(ds.delta_k.values[i] - np.array(motion.floats("phases"))
                                   + np.pi, 2 * np.pi) - np.pi).max() < 1e-9
        assert ds.flight_time_k.values[i] == pytest.approx(motion.floats("flight_times"),
                                                           abs=1e-9)
        assert ds.state_k.values[i] == pytest.approx(np.array(motion.floats("landing_states")),
                                                     abs=1e-9)
        exact = sorted((complex(z) for z in motion.multipliers), key=lambda z: -abs(z))
        assert np.sort(np.abs(ds.multipliers.values[i]))[::-1][:2] == pytest.approx(
            [abs(z) for z in exact[:2]], abs=1e-9)
    for target in (0.7, 2.3):  # from the simulated steady state, its impacts rolled
        i = int(np.argmin(np.abs(omega - target)))
        osc = damper(float(omega[i]))
        alone = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0,
                                                             16.0))
        assert sorted(alone.pattern) == ["l", "u"] and alone.physical, alone.reason
        k = -alone.pattern.index("l")  # impact 0 of the branch is on the lower wall
        assert ds.flight_time_k.values[i] == pytest.approx(np.roll(alone.flight_times, k),
                                                           abs=1e-9)
        assert ds.state_k.values[i] == pytest.approx(np.roll(alone.states, k, axis=0),
                                                     abs=1e-9)
        assert np.sort_complex(ds.multipliers.values[i]) == pytest.approx(
            np.sort_complex(alone.multipliers), abs=1e-9)
        assert ds.impact_velocity_k.values[i] == pytest.approx(
            np.roll(alone.impact_velocities, k), abs=1e-9)
        period = 2 * math.pi / omega[i]
        assert np.sum(ds.flight_time_k.values[i]) < period  # the rest is the two rides


def test_the_branch_saves_and_loads_with_its_pattern(tmp_path):
    """A branch of motions with sticking phases round-trips through NetCDF, its lowercase
    pattern kept (the dataset checks refused it before)."""
    ds = branch()
    path = tmp_path / "riding.nc"
    ic.save(ds, path)
    back = ic.load(path)
    assert back.attrs["pattern"] == "lu"
    for name in ("flight_time_k", "stick_time_k", "pressing_min_k", "release_state_k"):
        assert np.array_equal(back[name].values, ds[name].values, equal_nan=True), name


def test_the_branch_stores_the_stick_times_and_pressing_minima(cf):
    """stick_time_k, pressing_min_k and release_state_k per point: each period is the two
    rides and the two flights, and at omega near 1.2 they are the closed form's."""
    ds = branch()
    omega = ds.omega.values
    period = ds.stick_time_k.values.sum(axis=1) + ds.flight_time_k.values.sum(axis=1)
    assert period == pytest.approx(2 * np.pi / omega, rel=1e-13)
    i = int(np.argmin(np.abs(omega - 1.2)))
    motion = cf.riding_damper_motion(float(omega[i]))
    for name, theirs in (("stick_time_k", "stick_times"), ("pressing_min_k", "pressing_min"),
                         ("release_state_k", "release_states")):
        assert ds[name].values[i] == pytest.approx(np.array(motion.floats(theirs)),
                                                   abs=1e-9), name


def test_a_parameter_that_unmakes_the_plastic_stop_is_refused():
    """R moves the restitution of both (mirrored) walls the ball sticks on: the held system
    exists at R = 0 only; b and eta are continued."""
    with pytest.raises(ParameterError, match=r"parameter 'R' changes the restitution of "
                       r"stop\(s\) \['L', 'U'\].*on which the motion sticks"):
        MultiImpactBranchProblem(damper(1.0), 1, 2, "R", pattern="lu")
    for parameter in ("b", "eta"):
        problem = MultiImpactBranchProblem(damper(1.0), 1, 2, parameter, pattern="lu")
        assert problem.size == 2 * 2 * 2 + 2

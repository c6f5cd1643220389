"""Branch switching (:mod:`impactcont.analysis.switching`): at a period doubling (the
critical direction, the doubled branch against the simulator) and at a grazing (an impact
added, steps growing geometrically away from the graze)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.switching import (
    critical_direction,
    grazing_split,
    grazing_switch,
    special_orbit,
)
from impactcont.dataset.multi import impacts_of
from impactcont.orbit.multi_impact import initial_unknowns
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from tests._multi_impact_cases import assert_reproduced_by_simulator, orbit_at_point

PD_OMEGA = 1.70038303473  # N = 1 PD of the paper's system at b = 0 (test_branch finds it too)


# the fixtures paper_b0, branch_n1, branch_22, branch_44: tests/_multi_impact_cases.py


def test_critical_direction_is_a_null_vector_of_the_doubled_system(branch_n1):
    orbit = special_orbit(branch_n1, "PD")
    assert np.min(np.abs(orbit.multipliers + 1)) < 1e-8
    w, mu = critical_direction(orbit)
    assert abs(mu + 1) < 1e-8
    problem = MultiImpactBranchProblem(orbit.oscillator, 2, 2, "omega")
    u2 = initial_unknowns(orbit, orbit.oscillator, 2, 2)  # Newton would drift along w
    J = problem.jacobian(u2, orbit.oscillator.omega)
    assert np.abs(J @ w).max() < 1e-7 * np.abs(J).max()


def test_switched_branch_starts_alone_and_agrees_with_simulator(branch_22):
    ds = branch_22
    assert ds.attrs["born_at"] == "PD" and ds.attrs["N"] == 2 and impacts_of(ds) == 2
    assert ds.attrs["born_at_value"] == pytest.approx(PD_OMEGA, abs=1e-9)
    om = ds.omega.values
    assert om[0] - PD_OMEGA < 1e-5 and np.all(np.diff(om[:10]) > 0)  # leaves the PD upwards
    v = ds.impact_velocity_k.values
    assert abs(v[0, 0] - v[0, 1]) < 0.01 < abs(v[8, 0] - v[8, 1])  # two impacts split apart
    for i in (0, 1, 2, 5):
        orbit = orbit_at_point(ds, i)
        assert orbit.physical and orbit.stable
        assert_reproduced_by_simulator(orbit, 20)
    # the branch has its own PD (the next doubling), located
    assert "PD" in ds.special_label.values.tolist()


def test_grazing_switch_adds_an_impact(branch_44):
    ds = grazing_switch(branch_44, bounds=(1.79, 1.83), max_points=25, ds_max=0.002)
    assert ds is not None
    assert ds.attrs["born_at"] == "GR" and impacts_of(ds) == 5 and ds.attrs["N"] == 4
    new = int(ds.attrs["new_impact"])
    v_new = ds.impact_velocity_k.values[:, new]
    assert 0 < v_new[0] < 1e-3 and v_new[5] > v_new[0]  # born at zero velocity, then grows
    gr = float(branch_44.special_omega.values[branch_44.special_label.values == "GR"][0])
    assert abs(ds.omega.values[0] - gr) < 1e-3
    orbit = orbit_at_point(ds, 5)
    assert orbit.physical
    assert_reproduced_by_simulator(orbit, 1, tol=1e-8)  # unstable: one period only


def test_grazing_switch_steps_geometrically_away_from_the_graze():
    """Its multipliers grow like 1/|omega - omega_GR|: the steps start at epsilon's size and
    grow by a bounded factor (the first stored step used to jump 3.9e-6 -> 1.3e-3)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.0, omega=1.5, eta=0.1)
    branch = ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 3.0), detect=("GR",),
                             components="start")
    gr = float(branch.special_omega.values[0])
    switched = grazing_switch(branch, bounds=(0.5, 3.0), max_points=40)
    distance = np.abs(switched.omega.values[:12] - gr)
    assert distance[0] < 1e-5
    assert np.all(np.diff(distance) > 0)
    assert np.all(distance[1:] / distance[:-1] < 3.0)  # no jump: the birth is resolved
    rho = switched.spectral_radius.values[:12]
    assert rho[0] > 1e3 and np.all(np.diff(rho) < 0)  # 1/|omega - omega_GR| decay seen
    assert_reproduced_by_simulator(orbit_at_point(switched, 6), 1, tol=1e-8)


def test_grazing_split_refuses_a_motion_with_sticking_phases():
    """A sticky motion's flights start at its releases and its graze may lie inside a
    sticking phase: the guess of the N-(p+1) motion would be wrong, so it is refused."""
    from tests.integration.test_sticking_branches import riding

    orbit = riding()
    assert orbit.pattern == "lu" and orbit.physical
    with pytest.raises(ic.ParameterError, match=r"'lu' has sticking phases"):
        grazing_split(orbit)

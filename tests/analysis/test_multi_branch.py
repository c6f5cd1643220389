"""Branches of N-p motions (:mod:`impactcont.analysis.multi_branch`): the N-1 branch
through the shooting problem matches the closed form's, the physical stable motions of
switched branches are reproduced by the simulator, their special points are located,
and the branches survive NetCDF and plots."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.multi_branch import multi_impact_continuation
from impactcont.analysis.switching import period_doubling_switch, special_orbit
from impactcont.dataset.multi import impacts_of, validate_multi_impact_dataset
from impactcont.orbit.multi_impact import multi_impact_orbit


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


# ---------------------------------------------------------------------------------------------
# Branches and switching
# ---------------------------------------------------------------------------------------------
def test_n1_branch_through_the_shooting_problem_matches_continuation(paper_b0, branch_n1):
    start = next(o for o in ic.periodic_orbits(paper_b0, 1) if o.physical)
    ds = multi_impact_continuation(start, "omega", (1.4, 2.0), ds_max=0.05)
    assert impacts_of(ds) == 1 and ds.sizes["impact"] == 1
    pd = ds.special_omega.values[ds.special_label.values == "PD"]
    ref = branch_n1.special_omega.values[branch_n1.special_label.values == "PD"]
    assert pd.size == 1 and ref.size == 1
    assert abs(pd[0] - ref[0]) < 1e-10


def test_physical_stable_orbits_of_a_branch_are_reproduced(branch_22, branch_44):
    checked = 0
    for ds in (branch_22, branch_44):
        idx = np.flatnonzero(ds.physical.values & ds.stable.values)
        for i in idx[:: max(1, idx.size // 4)]:
            assert_reproduced_by_simulator(orbit_at_point(ds, int(i)), 60 // int(ds.attrs["N"]))
            checked += 1
    assert checked >= 6


def test_second_doubling_and_grazing_are_located(branch_44):
    labels = branch_44.special_label.values.tolist()
    assert "GR" in labels and "PD" in labels
    gr = branch_44.special_omega.values[labels.index("GR")]
    pd = branch_44.special_omega.values[labels.index("PD")]
    # the 4-4 motion grazes before its own period-doubling: that PD is virtual
    assert gr < pd
    assert special_orbit(branch_44, "GR").gap_min == pytest.approx(0.0, abs=1e-9)
    assert not special_orbit(branch_44, "PD").physical


def test_netcdf_round_trip(branch_22, tmp_path):
    path = tmp_path / "b22.nc"
    ic.save(branch_22, path)
    back = ic.load(path)
    validate_multi_impact_dataset(back)
    xr.testing.assert_identical(back, branch_22)
    assert impacts_of(back) == 2
    orbit = special_orbit(back, "PD")
    assert np.min(np.abs(orbit.multipliers + 1)) < 1e-8
    ic.save({"n22_head": branch_22.isel(point=slice(0, 3)), "n22": branch_22}, tmp_path / "tree.nc")
    tree = ic.load(tmp_path / "tree.nc")
    xr.testing.assert_identical(tree["n22"].to_dataset(), branch_22)


def test_plots_accept_np_branches(branch_n1, branch_22):
    import matplotlib

    matplotlib.use("Agg")
    from impactcont.plots import bifurcation_diagram
    from impactcont.plots.impacts import impact_diagram

    ax = impact_diagram({"N1": branch_n1, "N2": branch_22})
    assert len(ax.lines) >= 3
    bifurcation_diagram([branch_n1, branch_22])
    with pytest.raises(ValueError, match="y must be one of"):
        impact_diagram(branch_22, y="state")

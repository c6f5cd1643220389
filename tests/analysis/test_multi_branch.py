"""Branches of N-p motions (:mod:`impactcont.analysis.multi_branch`): the N-1 branch
through the shooting problem matches the closed form's, the physical stable motions of
switched branches are reproduced by the simulator, their special points are located,
and the branches survive NetCDF and plots."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.multi_branch import multi_impact_continuation
from impactcont.analysis.switching import special_orbit
from impactcont.dataset.multi import impacts_of, validate_multi_impact_dataset
from tests._multi_impact_cases import assert_reproduced_by_simulator, orbit_at_point

# the fixtures paper_b0, branch_n1, branch_22, branch_44: tests/_multi_impact_cases.py


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

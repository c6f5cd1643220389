"""Branches of N-p motions (the one driver, :mod:`impactcont.analysis.branch`): the N-1 branch
through the shooting problem matches the closed form's, the physical stable motions of
switched branches are reproduced by the simulator, their special points are located,
and the branches survive NetCDF and plots."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
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


# -- issue 28: the arguments are checked as continuation checks them, before computing --------
@pytest.fixture(scope="module")
def damper_ul():
    """The UL motion of the impact damper of issue 28 (a free ball, K[2,2] = 0, in a cavity)."""
    D = ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.8,
                            b=1.0, omega=1.5, eta=0.05,
                            stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    # the attractor of simulate(D, [0, 0, 0, 1], 0, 150), to 6 digits (Newton refines it)
    guess = {"delta": -3.053639, "pattern": "UL", "flight_times": [2.094395, 2.094395],
             "states": [[0.339684, 1.339684, 0.085287, -1.279304],
                        [-0.339684, -1.339684, -0.085287, 1.279304]]}
    return ic.multi_impact_orbit(D, 1, 2, guess)


@pytest.mark.parametrize(("parameter", "bounds", "message"), [
    ("omega", "0.5,3", "bounds must be two numbers (lo, hi); got '0.5,3'"),
    ("omega", (0.5, 2.0, 3.0), "bounds must be two numbers (lo, hi); got (0.5, 2.0, 3.0)"),
    ("omega", (3.0, 0.5), "bounds must be two finite numbers with lo < hi; got (3.0, 0.5)"),
    ("R", (0.5, 1.5), "bounds for R must lie where R is in [0, 1]; got (0.5, 1.5)"),
    ("m2", (-0.5, 1.0), "bounds for m2 must lie where m2 is finite and > 0; got (-0.5, 1.0)"),
    ("K[2,2]", (-0.1, 0.1), "bounds (-0.1, 0.1) for K[2,2]: at K[2,2] = -0.1 the oscillator is "
                            "refused: K must be positive semi-definite"),
])
def test_bad_bounds_are_refused_before_computing(damper_ul, parameter, bounds, message):
    with pytest.raises(ic.ParameterError) as info:
        multi_impact_continuation(damper_ul, parameter, bounds)
    assert str(info.value).startswith(message), str(info.value)


def test_a_progress_callable_without_the_record_is_refused_by_name(damper_ul):
    with pytest.raises(TypeError, match="progress must be a callable taking one Progress"):
        multi_impact_continuation(damper_ul, "omega", (1.4, 1.6), progress=lambda: None)


def test_a_branch_in_a_stiffness_entry_reaches_the_edge_of_its_range(damper_ul):
    # K[2,2] = 0 is the edge of K >= 0: the finite difference is one-sided there
    ds = multi_impact_continuation(damper_ul, "K[2,2]", (0.0, 0.1), progress=False)
    values = ds["K[2,2]"].values
    assert values.min() == 0.0 and values.max() == 0.1
    # from inside, the branch runs down to the edge (it stopped 6e-6 above it)
    osc = damper_ul.oscillator.replace(K=np.diag([1.0, 0.05]))
    start = ic.multi_impact_orbit(osc, 1, 2, damper_ul)
    ds = multi_impact_continuation(start, "K[2,2]", (0.0, 0.1), progress=False)
    assert ds["K[2,2]"].values.min() == 0.0 and ds["K[2,2]"].values.max() == 0.1


def test_stop_after_pd_is_not_triggered_through_the_pole_of_g() -> None:
    """A zero-velocity impact between two points changes the sign of the pole-free PD test
    (it is cleared by the impact velocities) with no multiplier through -1: the branch's
    ``stop_after_pd`` rule must not count it as the period-doubling (issue 28, 1.3)."""
    from types import SimpleNamespace

    from impactcont.analysis.branch import _pd_sign_change

    def motion(mu, h):
        return SimpleNamespace(multipliers=np.array(mu, dtype=complex),
                               impact_velocities=np.array(h, dtype=float))

    # the same multipliers on both sides (one 0.4 from -1), an impact velocity through 0
    assert not _pd_sign_change(motion([-0.6, 0.2], [0.3, 1e-3]), motion([-0.6, 0.2], [0.3, -1e-3]))
    # a multiplier through -1 with the velocities keeping their sign is a PD
    assert _pd_sign_change(motion([-0.9, 0.2], [0.3, 0.2]), motion([-1.1, 0.2], [0.3, 0.2]))

"""What the built-in scene sections compute (:mod:`impactcont.scene.tasks`): each handler's
dataset holds what the public API computes for the entry (periodic_orbits, continuation,
robust_stability, simulate), every variable with its long_name and units, and its Markdown
tables show those numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.dataset.attributes import check_attributes
from impactcont.scene import entries as e
from impactcont.scene import tasks as t
from impactcont.scene.keys import Where

OSC = {"K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "eta": 0.1, "b": 0.6,
       "omega": 1.0}
AT = Where("s.toml", "entry")


@pytest.fixture(scope="module")
def base() -> ic.ImpactOscillator:
    return e.OscillatorSpec.parse(OSC, AT).build()


def _entry(cls, base, **raw):
    return cls.parse(raw, AT, base, 0)


def _cf(ds: xr.Dataset) -> None:
    for name, var in ds.data_vars.items():
        assert isinstance(var.attrs.get("long_name"), str) and var.attrs["long_name"], name
        assert isinstance(var.attrs.get("units"), str), name


# -- helpers ---------------------------------------------------------------------------------
def test_g_labels_name_the_coordinates_of_z_eq_19() -> None:
    assert t.g_labels(2) == ["dx2", "dv1", "dv2", "ddelta"]
    assert t.g_labels(3) == ["dx2", "dx3", "dv1", "dv2", "dv3", "ddelta"]
    assert len(t.g_labels(5)) == 2 * 5


def test_markdown_tables_format_numbers_to_six_digits() -> None:
    lines = t.markdown_table(["a", "b", "c", "d", "e", "f"],
                             [[1, math.pi, True, math.nan, -math.inf, "text"]])
    assert lines == ["| a | b | c | d | e | f |", "|---|---|---|---|---|---|",
                     "| 1 | 3.14159 | yes | - | -inf | text |"]
    assert t.points_table([]) == []
    assert t.points_table([{"x": 1.0, "y": 2}, {"y": 3}]) == [
        "| x | y |", "|---|---|", "| 1 | 2 |", "| - | 3 |"]


# -- [[orbits]] ------------------------------------------------------------------------------
def test_orbits_are_the_roots_of_eq_15_at_the_entry(base) -> None:
    ds = t.ORBITS.compute(_entry(e.OrbitSpec, base, name="o1"))
    orbits = ic.periodic_orbits(base, 1)
    assert ds.sizes["orbit"] == len(orbits) == 2
    for k, orbit in enumerate(orbits):
        assert int(ds["root"][k]) == orbit.root
        assert float(ds["delta"][k]) == orbit.delta
        assert float(ds["period"][k]) == pytest.approx(2 * np.pi / base.omega, rel=1e-14)
        assert bool(ds["physical"][k]) == orbit.physical
        np.testing.assert_array_equal(ds["G"].values[k], orbit.G)
        np.testing.assert_array_equal(ds["multipliers"].values[k], orbit.multipliers)
    assert float(ds["amplitude_squared"]) == ic.amplitude_squared(base, 1)
    assert ds["g_row"].values.tolist() == t.g_labels(2)
    assert (ds.attrs["name"], ds.attrs["which"], ds.attrs["N"]) == ("o1", "all", 1)
    _cf(ds)
    check_attributes(ds, "orbits", in_section=True)
    table = t.ORBITS.describe({"o1": ds})
    assert table[0].startswith("| entry | N | at | c^2+s^2 | root |")
    assert len(table) == 2 + 2 and "| o1 | 1 | omega=1, b=0.6 | 1.74355 | -1 | 1.1603 |" in \
        "\n".join(table)
    assert t.ORBITS.special_points({"o1": ds}) == []


def test_which_keeps_the_physical_roots_and_says_why_none_is_kept(base) -> None:
    physical = t.ORBITS.compute(_entry(e.OrbitSpec, base, which="physical"))
    assert physical["root"].values.tolist() == [o.root for o in ic.periodic_orbits(base, 1)
                                                if o.physical] == [-1]
    # the stop out of reach: c^2 + s^2 < b^2 (eq. 15), no root at all
    reach = math.sqrt(ic.amplitude_squared(base, 1))
    far = t.ORBITS.compute(_entry(e.OrbitSpec, base, b=1.01 * reach))
    assert far.sizes["orbit"] == 0
    assert far.attrs["note"].startswith("no motion: c^2 + s^2 = 1.74355 < b^2 = ")
    assert f"b between {-reach:.6g} and {reach:.6g}" in far.attrs["note"]
    assert ic.periodic_orbits(base.replace(b=0.99 * reach), 1)  # just inside: motions
    assert far.attrs["note"] in t.ORBITS.describe({"far": far})[2]


# -- [[branches]] ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def branch(base) -> tuple[e.BranchSpec, xr.Dataset]:
    entry = _entry(e.BranchSpec, base, name="br", b=0.5, bounds=[1.1, 1.3], ds_max=0.05)
    return entry, t.BRANCHES.compute(entry)


def test_a_branch_is_the_continuation_of_its_entry(base, branch) -> None:
    entry, ds = branch
    direct = ic.continuation(base.replace(b=0.5), **entry.continuation_kwargs())
    xr.testing.assert_identical(ds.drop_attrs(), direct.drop_attrs())
    assert ds.attrs["name"] == "br"


def test_the_special_points_of_a_branch_are_its_rows(branch) -> None:
    _, ds = branch
    points = t.BRANCHES.special_points({"br": ds})
    assert [p["label"] for p in points] == ds["special_label"].values.tolist()
    for k, p in enumerate(points):
        assert p["value"] == p["omega"] == float(ds["special_omega"][k])
        assert p["rho"] == float(np.abs(ds["special_multipliers"].values[k]).max())
        assert p["physical"] == bool(ds["physical"][int(ds["special_point"][k])])
    table = t.special_points_table(points)
    assert len(table) == 2 + len(points)
    assert table[2].startswith(f"| br | 1 | {points[0]['label']} | omega = ")
    summary = t.BRANCHES.describe({"br": ds})[2]
    assert summary.startswith(f"| br | 1 | omega | [1.1, {float(ds['omega'].max()):.6g}] | "
                              f"{ds.sizes['point']} |")


def test_a_branch_out_of_reach_says_how_far(base) -> None:
    reach = math.sqrt(ic.amplitude_squared(base, 1))
    entry = _entry(e.BranchSpec, base, b=3.0, bounds=[0.9, 1.1])
    with pytest.raises(ic.NoPeriodicMotionError, match=r"closest at omega = .*against b\^2 = "
                                                       r"9 \(eq. 15\): the stop is out of "
                                                       r"reach"):
        t.BRANCHES.compute(entry)
    assert reach < 3.0


# -- [[robust]] ------------------------------------------------------------------------------
def test_robust_stability_of_the_entry(base) -> None:
    entry = _entry(e.RobustSpec, base, name="rb", vary={"b": [0.5, 0.7]}, samples=5)
    ds = t.ROBUST.compute(entry)
    rs = ic.robust_stability(base, 1, vary={"b": (0.5, 0.7)}, samples=5)
    assert float(ds["epsilon"]) == rs.epsilon and float(ds["epsilon0"]) == rs.epsilon0
    assert bool(ds["robust"]) == rs.robust is True
    np.testing.assert_array_equal(ds["G0"].values, rs.G0)
    np.testing.assert_array_equal(ds["Gamma"].values, rs.Gamma)
    assert float(ds["epsilon"]) == pytest.approx(float(ds["theta"].max()), rel=1e-14)
    _cf(ds)
    check_attributes(ds, "robust", in_section=True)
    row = t.ROBUST.describe({"rb": ds})[2]
    assert row.startswith("| rb | 1 | b in [0.5, 0.7] | b = 0.6 |") and row.endswith("| yes |")


# -- [[simulations]] -------------------------------------------------------------------------
def test_a_simulation_from_the_stable_motion_repeats_its_impact(base) -> None:
    ds = t.SIMULATIONS.compute(_entry(e.SimulationSpec, base, name="sim", periods=3.5,
                                      trajectory=True))
    orbit = next(o for o in ic.periodic_orbits(base, 1) if o.physical and o.stable)
    assert ds.attrs["start"] == f"N=1 motion, root {orbit.root:+d}"
    np.testing.assert_allclose(ds["impact_times"], 2 * np.pi * np.arange(1, 4), rtol=1e-10)
    np.testing.assert_allclose(ds["impact_velocities"], orbit.impact_velocity, rtol=1e-9)
    np.testing.assert_array_equal(ds["start_state"], orbit.state)
    assert ds.attrs["impact_stops"] == "UUU" and ds.attrs["status"] == "COMPLETED"
    assert ds["X"].dims == ("sample", "component") and ds["t"].values[-1] == pytest.approx(
        3.5 * 2 * np.pi)
    _cf(ds)
    check_attributes(ds, "simulation", in_section=True)
    assert t.SIMULATIONS.describe({"sim": ds})[2].endswith("| 0 | 0 | yes | COMPLETED | UUU |")


def test_the_simulations_table_counts_sticking_phases_and_accumulation_points() -> None:
    """`impactcont info` of a run that chatters and sticks said nothing of either (only the
    impacts, whose last speed was a chatter's last resolved bounce)."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                              omega=0.7, eta=0.05)
    res = ic.simulate(osc, [0.0, 0.0], 0.0, 3.0)
    assert res.sticking and res.chatter
    ds = ic.dataset.simulation.simulation_dataset(res, name="run")
    row = t.SIMULATIONS.describe({"run": ds})[2]
    assert f"| {len(res.sticking)} | {len(res.chatter)} | no | COMPLETED |" in row


def test_a_simulation_from_a_state_is_the_simulators(base) -> None:
    entry = _entry(e.SimulationSpec, base, start="state", state=[0.0, 0.1, 0.0, 0.2],
                   delta=0.4, periods=4.0, perturbation=0.05)
    ds = t.SIMULATIONS.compute(entry)
    res = ic.simulate(base, np.array([0.0, 0.1, 0.05, 0.25]), 0.4, 4.0)
    np.testing.assert_array_equal(ds["start_state"], [0.0, 0.1, 0.05, 0.25])
    np.testing.assert_array_equal(ds["impact_times"], res.impact_times)
    np.testing.assert_array_equal(ds["impact_states"], res.impact_states)
    assert "X" not in ds and ds.attrs["start"] == "state"


def test_a_simulation_stores_its_sticking_phases_and_chatter(base, tmp_path) -> None:
    """Issue 30: at rest on the stop b = 0 and pushed into it (x1'' = cos(delta) > 0), the
    run is held from t = 0; its sticking phases, contact forces and chatter points are
    variables of the dataset, as the simulator returns them, and survive a netCDF file."""
    entry = _entry(e.SimulationSpec, base, start="state", state=[0.0, 0.0, 0.0, 0.0],
                   delta=0.0, periods=3.0, b=0.0)
    ds = t.SIMULATIONS.compute(entry)
    res = ic.simulate(base.replace(b=0.0), np.zeros(4), 0.0, 3.0)
    assert ds.sizes["sticking"] == len(res.sticking) >= 1
    assert float(ds["sticking_start"][0]) == 0.0 and str(ds["sticking_stops"].values[0]) == "U"
    np.testing.assert_array_equal(ds["sticking_end"], [p.end for p in res.sticking])
    first = ds["force_phase"].values == 0
    np.testing.assert_array_equal(ds["contact_force"].values[first], res.sticking[0].forces[:, 0])
    np.testing.assert_array_equal(ds["chatter_time"], [c.time for c in res.chatter])
    check_attributes(ds, "simulation", in_section=True)
    ds.to_netcdf(tmp_path / "sim.nc")
    with xr.open_dataset(tmp_path / "sim.nc") as back:
        assert list(back["sticking_ended_by"].values) == [p.ended_by for p in res.sticking]


def test_no_motion_to_start_from_is_named(base) -> None:
    entry = _entry(e.SimulationSpec, base, name="s", periods=2, b=3.0)
    with pytest.raises(ic.NoPeriodicMotionError, match=r"simulation s: no N=1 motion at "
                                                       r"omega=1, b=3 to start from"):
        t.SIMULATIONS.compute(entry)

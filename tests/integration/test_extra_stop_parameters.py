"""An extra stop's own gap and restitution as continuable parameters (issue 21, item 4):
``gap[A]`` and ``R[A]`` of the stop named ``A`` (U above mass 1, A above mass 2 of a
two-mass chain). Exact derivatives of the shooting residual against central differences;
branches, curves and maps in them against ``multi_impact_orbit`` on fresh oscillators
and the event-driven simulator."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.maps import multi_impact_map_orbit
from impactcont.analysis.switching import special_orbit
from impactcont.dataset import oscillator_from_dataset
from impactcont.errors import ParameterError
from impactcont.model.parameters import GAP, RESTITUTION, model_parameter
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.vocabulary import PARAMETERS, check_parameter, stop_parameter_name

M = np.eye(2)
K = np.array([[2.0, -1.0], [-1.0, 1.0]])  # a chain: wall - k - m1 - k - m2


def _wagg(omega=0.8, gap=0.6, restitution=0.7, **kw):
    params = {"M": M, "K": K, "F": [1.0, 0.0], "R": 0.8, "b": 0.3, "omega": omega,
              "eta": 0.05, "stops": ic.Stops(extra=(
                  ic.Stop("A", mass=2, gap=gap, restitution=restitution),))}
    return ic.ImpactOscillator(**{**params, **kw})


@pytest.fixture(scope="module")
def motion():
    """The 1-2 motion with one impact on U (mass 1) and one on A (mass 2)."""
    osc = _wagg()
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 100.0))
    assert sorted(orbit.pattern) == ["A", "U"] and orbit.physical
    return orbit


def _fresh(orbit, osc):
    """`orbit` re-solved by Newton on `osc` (a fresh oscillator)."""
    return ic.multi_impact_orbit(osc, orbit.N, orbit.p, orbit)


# -- the names -----------------------------------------------------------------------------
def test_names_resolve_and_set_the_stop():
    osc = _wagg()
    assert stop_parameter_name("gap[A]") == ("gap[S]", "A")
    assert stop_parameter_name("R[B]") == ("R[S]", "B")
    assert stop_parameter_name("gap[AB]") is None and stop_parameter_name("k2") is None
    assert "gap[A]" in PARAMETERS and PARAMETERS["R[A]"].domain == (0.0, 1.0)
    assert check_parameter(osc, "gap[A]") == "gap[A]"
    gap, r = model_parameter(osc, "gap[A]"), model_parameter(osc, "R[A]")
    assert (gap.data, r.data) == (GAP, RESTITUTION) and gap.moves_stops and r.moves_stops
    assert gap.value(osc) == 0.6 and r.value(osc) == 0.7
    moved = gap.at(osc, 0.65)
    assert moved.stops.extra_stop("A").gap == 0.65 and moved.b == osc.b
    assert r.at(osc, 0.5).stops.extra_stop("A").restitution == 0.5
    # each moves its own stop only; no mirror image
    np.testing.assert_array_equal(gap.stop_rates("UAU"), [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(model_parameter(osc, "b").stop_rates("UAU"), [1.0, 0.0, 1.0])
    assert not gap.keeps_symmetry and not r.keeps_symmetry
    below = _wagg(stops=ic.Stops(extra=(ic.Stop("B", mass=2, gap=0.5, restitution=0.6,
                                                 side=-1),)))
    np.testing.assert_array_equal(model_parameter(below, "gap[B]").stop_rates("B"), [-1.0])


@pytest.mark.parametrize("name, match", [
    ("gap[B]", r"no extra stop 'B'.*\['gap\[A\]'\]"),
    ("R[U]", r"continue 'R' \(U\), 'R_low' \(L\)"),
    ("gap[L]", r"continue 'b' \(U\), 'b_low' \(L\)"),
    ("gap[1]", r"extra stop's \('gap\[S\]', 'R\[S\]'\)"),
])
def test_bad_names_are_refused_clearly(name, match):
    with pytest.raises(ParameterError, match=match):
        model_parameter(_wagg(), name)


def test_values_outside_the_stops_rules_are_refused():
    osc = _wagg()
    with pytest.raises(ParameterError, match=r"restitution must be in \[0, 1\]"):
        model_parameter(osc, "R[A]").at(osc, 1.5)
    below = _wagg(stops=ic.Stops(extra=(
        ic.Stop("A", mass=1, gap=0.2, restitution=0.6, side=-1),)))  # x1 = -0.2 below U
    with pytest.raises(ParameterError, match="leave no room"):
        model_parameter(below, "gap[A]").at(below, -0.35)  # x1 = 0.35, above U at b = 0.3


def test_restitution_slope_of_each_stop_matches_finite_differences():
    from impactcont.model.stops import Stops

    Mc = np.array([[1.0, 0.2], [0.2, 0.5]])
    stops = Stops(mass=1, b_low=0.4, extra=(
        ic.Stop("A", mass=2, relative_to=1, gap=0.3, restitution=0.6),
        ic.Stop("B", mass=2, gap=0.9, restitution=0.5)))
    for name in "ULAB":
        def jump(R, name=name):
            if name == "U":
                return stops.impact_matrix(Mc, R)
            if name == "L":
                return Stops(mass=1, b_low=0.4, R_low=R).impact_matrix(Mc, R)
            return stops.with_extra(name, restitution=R).stop(name, Mc, 0.3, 0.7).jump
        fd = (jump(0.7) - jump(0.3)) / 0.4  # affine: any step
        np.testing.assert_allclose(stops.restitution_slope(name, Mc), fd, rtol=0, atol=1e-14)


# -- exact derivatives ---------------------------------------------------------------------
@pytest.mark.parametrize("name", ["gap[A]", "R[A]", "b", "R"])
def test_exact_dparam_matches_central_differences(motion, name):
    """``gap[A]``, ``R[A]`` and, on this motion with impacts on two masses, ``b`` (refused
    before: one pivot for all impacts) are exact on the shooting residual."""
    osc = motion.oscillator
    problem = MultiImpactBranchProblem(osc, motion.N, motion.p, name, pattern=motion.pattern)
    lam = model_parameter(osc, name).value(osc)
    u = motion.unknowns
    exact = problem.dparam(u, lam)
    h = 1e-5
    fd = (-problem.residual(u, lam + 2 * h) + 8 * problem.residual(u, lam + h)
          - 8 * problem.residual(u, lam - h) + problem.residual(u, lam - 2 * h)) / (12 * h)
    assert np.max(np.abs(fd)) > 0.1
    np.testing.assert_allclose(exact, fd, rtol=0, atol=1e-8 * np.max(np.abs(fd)))


# -- a branch in the extra stop's gap -------------------------------------------------------
@pytest.fixture(scope="module")
def gap_branch(motion):
    return ic.multi_impact_continuation(motion, "gap[A]", (0.3, 1.2), max_points=60)


def test_a_branch_in_the_extra_stops_gap_is_the_shooting_motion_there(gap_branch, motion):
    br = gap_branch
    assert br.attrs["parameter"] == "gap[A]" and br.attrs["pattern"] == motion.pattern
    values = br["gap[A]"].values
    assert values.min() <= 0.31 and values.max() >= 1.19
    for k in range(0, br.sizes["point"], 4):
        fresh = ic.multi_impact_orbit(_wagg(gap=float(values[k])), 1, 2, {
            "delta": float(br["delta_k"].values[k, 0]),
            "flight_times": br["flight_time_k"].values[k], "states": br["state_k"].values[k],
            "pattern": motion.pattern})
        np.testing.assert_allclose(fresh.states, br["state_k"].values[k], rtol=0, atol=1e-8)
        assert bool(br["physical"].values[k]) == fresh.physical
        assert float(br["spectral_radius"].values[k]) == pytest.approx(
            abs(fresh.multipliers[0]), rel=1e-7)
        # the stop A of the motion sits at the branch's value
        a = motion.pattern.index("A")
        assert fresh.states[a][1] == pytest.approx(values[k], abs=1e-12)


def test_the_extra_stops_gap_branch_grazes_where_the_simulator_says(gap_branch, motion):
    br = gap_branch
    labels = list(br["special_label"].values)
    assert "GR" in labels
    graze = special_orbit(br, "GR", 0)
    g = float(br["special_gap[A]"].values[labels.index("GR")])
    assert min(graze.flight_gap_min) == pytest.approx(0.0, abs=1e-8)
    pattern = motion.pattern[1:] + motion.pattern[0]
    sides = {}
    for dg in (-0.01, 0.01):
        osc = _wagg(gap=g + dg)
        near = _fresh(graze, osc)
        res = ic.simulate(osc, near.states[0], near.phases[0], 1.5, max_impacts=near.p)
        follows = (res.impact_stops == pattern
                   and np.allclose(res.impact_states[-1], near.states[0], rtol=0, atol=1e-8))
        assert follows == near.physical
        sides[dg] = near.physical
    assert sides[-0.01] != sides[0.01]  # the motion stops being physical at the graze


def test_a_branch_in_the_extra_stops_gap_round_trips(gap_branch, tmp_path):
    ic.save(gap_branch, tmp_path / "b.nc")
    with xr.open_dataset(tmp_path / "b.nc") as raw:  # CF name on disk, the name kept
        assert "gap_A" in raw.variables
        assert raw["gap_A"].attrs["impactcont_name"] == "gap[A]"
    back = ic.load(tmp_path / "b.nc")
    np.testing.assert_array_equal(back["gap[A]"].values, gap_branch["gap[A]"].values)
    osc = oscillator_from_dataset(back, 3)
    assert osc.stops.extra_stop("A").gap == gap_branch["gap[A]"].values[3]


# -- curves and maps -----------------------------------------------------------------------
def test_a_curve_in_omega_and_the_extra_stops_restitution(motion):
    with pytest.warns(RuntimeWarning, match="stopped at max_points=80"):  # past its PD
        br = ic.multi_impact_continuation(motion, "omega", (0.6, 1.2), max_points=80)
    assert "PD" in list(br["special_label"].values)
    cv = ic.multi_impact_curve(br, "PD", 0, parameter="R[A]",
                               bounds={"omega": (0.6, 1.2), "R[A]": (0.3, 1.0)},
                               max_points=12)
    assert cv.sizes["point"] >= 5 and np.ptp(cv["R[A]"].values) > 0.05
    for k in (0, cv.sizes["point"] // 2, cv.sizes["point"] - 1):
        osc = _wagg(omega=float(cv["omega"].values[k]), restitution=float(cv["R[A]"].values[k]))
        fresh = ic.multi_impact_orbit(osc, 1, 2, {
            "delta": float(cv["delta_k"].values[k, 0]),
            "flight_times": cv["flight_time_k"].values[k], "states": cv["state_k"].values[k],
            "pattern": motion.pattern})
        # a period doubling: a multiplier -1 there
        assert np.min(np.abs(fresh.multipliers + 1.0)) < 1e-6


def test_a_map_in_the_extra_stops_gap(motion, tmp_path):
    gaps = np.linspace(0.5, 0.9, 5)
    ds = ic.multi_impact_map(motion, ("omega", "gap[A]"),
                             {"omega": [0.78, 0.8, 0.82], "gap[A]": gaps})
    assert ds["found"].values.all()
    assert ds["physical"].values.any() and not ds["physical"].values.all()
    for w in (0.78, 0.82):
        for g in gaps[::2]:
            cell = ds.sel(omega=w, **{"gap[A]": g})
            fresh = ic.multi_impact_orbit(_wagg(omega=w, gap=float(g)), 1, 2, {
                "delta": float(cell["delta"]), "flight_times": cell["flight_time_k"].values,
                "states": cell["state_k"].values, "pattern": motion.pattern})
            np.testing.assert_allclose(cell["state_k"].values, fresh.states, rtol=0, atol=1e-9)
            assert bool(cell["physical"]) == fresh.physical
            assert float(cell["gap_min"]) == pytest.approx(float(np.min(fresh.flight_gap_min)),
                                                           abs=1e-8)
    ic.save(ds, tmp_path / "m.nc")
    back = ic.load(tmp_path / "m.nc")
    again = multi_impact_map_orbit(back, omega=0.8, **{"gap[A]": 0.7})
    assert again.oscillator.stops.extra_stop("A").gap == pytest.approx(0.7)


# -- the grazing switch onto an extra stop (switching.py: its coordinate and side) ----------
def test_grazing_switch_onto_the_extra_stop_gives_the_physical_motion():
    osc = _wagg(omega=1.5)
    start = ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, np.zeros(4), 0.0, 100.0))
    branch = ic.multi_impact_continuation(start, "omega", (1.18, 1.5), direction=-1,
                                          both_directions=False, detect=("GR",))
    assert list(branch["special_label"].values) == ["GR"] and start.flight_gap_stops == "A"
    switched = ic.grazing_switch(branch, 0, bounds=(1.0, 1.3), max_points=10)
    assert sorted(switched.attrs["pattern"]) == ["A", "U"]
    assert switched["physical"].values.all()  # the side where A's impact velocity is > 0
    k = switched.sizes["point"] // 2
    osc = _wagg(omega=float(switched["omega"].values[k]))
    near = ic.multi_impact_orbit(osc, 1, 2, {
        "delta": float(switched["delta_k"].values[k, 0]),
        "flight_times": switched["flight_time_k"].values[k],
        "states": switched["state_k"].values[k], "pattern": switched.attrs["pattern"]})
    res = ic.simulate(osc, near.states[0], near.phases[0], 1.5, max_impacts=2)
    assert res.impact_stops == near.pattern[1:] + near.pattern[0]
    np.testing.assert_allclose(res.impact_states[-1], near.states[0], rtol=0, atol=1e-8)


# -- a scene with an extra stop, continued in its gap (scene/switches.py, scene/entries.py) --
SCENE = '''title = "extra stop gap"
[oscillator]
K = [[2.0, -1.0], [-1.0, 1.0]]
F = [1.0, 0.0]
R = 0.8
b = 0.3
omega = 0.8
eta = 0.05
extra_stops = [{ name = "A", mass = 2, gap = 0.6, restitution = 0.7 }]

[[simulations]]
name = "sim"
start = "state"
state = [0.0, 0.0, 0.0, 0.0]
delta = 0.0
periods = 20

[[multi_impact]]
name = "mi"
start = "sim"
N = 1
p = 2
parameter = "gap[A]"
bounds = [0.5, 0.7]
max_points = 10
'''


def test_a_scene_continues_the_extra_stops_gap(tmp_path, motion):
    from impactcont.scene import read_output, run_scene

    path = tmp_path / "scene.toml"
    path.write_text(SCENE, encoding="utf-8")
    result = run_scene(path, output=tmp_path / "o")
    assert result.ok, result.failures
    mi = read_output(tmp_path / "o" / "multi_impact.nc").datasets["mi"]
    assert mi.attrs["parameter"] == "gap[A]" and sorted(mi.attrs["pattern"]) == ["A", "U"]
    values = mi["gap[A]"].values
    assert values.min() == pytest.approx(0.5) and values.max() == pytest.approx(0.7)
    k = int(np.argmin(np.abs(values - 0.6)))
    fresh = ic.multi_impact_orbit(_wagg(gap=float(values[k])), 1, 2, {
        "delta": float(mi["delta_k"].values[k, 0]), "flight_times": mi["flight_time_k"].values[k],
        "states": mi["state_k"].values[k], "pattern": mi.attrs["pattern"]})
    np.testing.assert_allclose(fresh.states, mi["state_k"].values[k], rtol=0, atol=1e-8)

"""Continuation of N-1 branches: special points located, then checked independently.

Restart a branch from a point of a saved branch and extend it past its bounds.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.branch import continuation_from, extend
from impactcont.core import ContinuationOptionError
from impactcont.errors import ParameterError
from impactcont.orbit.periodic import orbit_at_phase


@pytest.fixture(scope="module")
def paper_system():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def branch_b0(paper_system):
    return ic.continuation(paper_system, N=1, parameter="omega", bounds=(0.5, 6.0))


@pytest.fixture(scope="module")
def branch_b05(paper_system):
    return ic.continuation(paper_system.replace(b=0.5), N=1, parameter="omega",
                           bounds=(0.5, 3.0))


def special(ds, label):
    rows = np.flatnonzero(ds.special_label.values == label)
    assert rows.size >= 1, f"no {label} found: {ds.special_label.values}"
    return ds.isel(special=int(rows[0]))


def orbit_at(osc, N, delta_guess):
    orbits = ic.periodic_orbits(osc, N)
    return min(orbits, key=lambda o: abs(math.remainder(o.delta - delta_guess, 2 * math.pi)))


def test_points_lie_on_the_closed_form(branch_b0, paper_system):
    assert branch_b0.attrs["parameter"] == "omega"
    assert branch_b0.omega.min() == 0.5 and branch_b0.omega.max() == 6.0
    for i in range(0, branch_b0.sizes["point"], 37):
        pt = branch_b0.isel(point=i)
        orbit = orbit_at(paper_system.replace(omega=float(pt.omega)), 1, float(pt.delta))
        assert math.remainder(orbit.delta - float(pt.delta), 2 * math.pi) == pytest.approx(
            0.0, abs=1e-10)
        assert orbit.impact_velocity == pytest.approx(float(pt.impact_velocity), rel=1e-9)
        np.testing.assert_allclose(np.sort_complex(orbit.multipliers),
                                   np.sort_complex(pt.multipliers.values), atol=1e-9)


def test_period_doubling_confirmed_by_simulation(branch_b0, paper_system):
    pd = special(branch_b0, "PD")
    w = float(pd.special_omega)
    assert pd.special_status == "located"
    assert np.min(np.abs(pd.special_multipliers.values + 1)) < 1e-8
    for side, w_side in (("below", w - 0.02), ("above", w + 0.02)):
        osc = paper_system.replace(omega=w_side)
        orbit = orbit_at(osc, 1, float(pd.special_delta))
        assert orbit.physical
        X = orbit.state.copy()
        X[1] += 1e-6
        res = ic.simulate(osc, X, orbit.delta, 400.0)
        v = res.impact_velocities[-20:]
        spread = v.max() - v.min()
        if side == "below":  # stable N = 1 motion: one impact velocity
            assert orbit.stable
            assert spread < 1e-9
        else:  # beyond PD: period-2 impacts, alternating velocities
            assert not orbit.stable
            assert spread > 1e-3
            np.testing.assert_allclose(v[2::2], v[:-2:2], atol=1e-8)


def test_grazing_confirmed_by_simulation(branch_b0, paper_system):
    gr = special(branch_b0, "GR")
    w = float(gr.special_omega)
    k = int(gr.special_point)
    orbit = orbit_at(paper_system.replace(omega=w), 1, float(gr.special_delta))
    assert abs(orbit.gap_min) < 1e-9
    # the physical side of the graze keeps its motion; the other side hits the stop early
    outcomes = {}
    for w_side in (w - 0.01, w + 0.01):
        osc = paper_system.replace(omega=w_side)
        o = orbit_at(osc, 1, float(gr.special_delta))
        res = ic.simulate(osc, o.state, o.delta, 1.5)
        outcomes[o.physical] = res.impact_times[0] / o.period
    assert set(outcomes) == {True, False}
    assert outcomes[True] == pytest.approx(1.0, abs=1e-9)
    assert outcomes[False] < 0.99
    assert bool(branch_b0.physical[k - 3]) != bool(branch_b0.physical[k + 3])


def test_fold_matches_closed_form_existence_limit(branch_b05, paper_system):
    sn = special(branch_b05, "SN")
    w = float(sn.special_omega)
    osc = paper_system.replace(b=0.5, omega=w)
    assert ic.amplitude_squared(osc, 1) == pytest.approx(0.25, abs=1e-10)
    assert np.min(np.abs(sn.special_multipliers.values - 1)) < 1e-6
    assert len(ic.periodic_orbits(osc.replace(omega=w + 1e-4), 1)) == 0
    assert len(ic.periodic_orbits(osc.replace(omega=w - 1e-4), 1)) == 2


def test_zero_velocity_impact_is_the_linear_response_touching_the_stop(branch_b05,
                                                                       paper_system):
    zv = special(branch_b05, "ZV")
    w = float(zv.special_omega)
    osc = paper_system.replace(b=0.5, omega=w)
    # independent: steady linear response amplitude (K - w^2 M + i w C)^-1 F
    X = np.linalg.solve(osc.K - w**2 * osc.M + 1j * w * osc.C, osc.F)
    assert abs(X[0]) == pytest.approx(0.5, abs=1e-9)


def test_neimark_sacker_confirmed_by_simulation(branch_b05, paper_system):
    ns = special(branch_b05, "NS")
    w = float(ns.special_omega)
    mu = ns.special_multipliers.values
    critical = mu[np.argmin(np.abs(np.abs(mu) - 1))]
    assert abs(abs(critical) - 1) < 1e-8 and abs(critical.imag) > 1e-3
    growth = {}
    for w_side in (w - 2e-3, w + 5e-4):
        osc = paper_system.replace(b=0.5, omega=w_side)
        o = orbit_at(osc, 1, float(ns.special_delta))
        X = o.state.copy()
        X[1] += 1e-7
        res = ic.simulate(osc, X, o.delta, 300.5)
        v = res.impact_velocities
        growth[o.stable] = abs(v[-1] - o.impact_velocity) / abs(v[0] - o.impact_velocity)
    assert set(growth) == {True, False}
    assert growth[True] < 1e-3 and growth[False] > 10


@pytest.mark.parametrize("label", ["SN", "NS", "ZV"])
def test_located_values_stable_when_the_step_is_halved(branch_b05, paper_system, label):
    fine = ic.continuation(paper_system.replace(b=0.5), N=1, parameter="omega",
                           bounds=(0.5, 3.0), ds=0.01, ds_max=0.025)
    a = float(special(branch_b05, label).special_omega)
    b = float(special(fine, label).special_omega)
    assert a == pytest.approx(b, abs=1e-9)


def test_special_points_lie_in_their_brackets(branch_b0, branch_b05):
    for ds in (branch_b0, branch_b05):
        for i in range(ds.sizes["special"]):
            sp = ds.isel(special=i)
            if str(sp.special_label.values) == "SN":
                continue  # a fold is an extremum of the parameter: outside its bracket
            lo, hi = float(sp.special_bracket_lo), float(sp.special_bracket_hi)
            assert lo - 1e-12 <= float(sp.special_omega) <= hi + 1e-12
            assert float(sp.special_precision) < 1e-9


def test_continuation_in_the_gap(paper_system):
    ds = ic.continuation(paper_system.replace(omega=1.0), N=1, parameter="b",
                         bounds=(-1.0, 2.0))
    sn = special(ds, "SN")
    assert float(sn.special_b) ** 2 == pytest.approx(ic.amplitude_squared(
        paper_system.replace(omega=1.0), 1), rel=1e-12)


def test_netcdf_round_trip_of_a_real_branch(branch_b05, tmp_path):
    path = ic.save(branch_b05, tmp_path / "branch.nc")
    back = ic.load(path)
    xr.testing.assert_identical(back, branch_b05)
    osc = ic.ImpactOscillator.from_json(back.attrs["oscillator"])
    assert osc.b == 0.5


def test_bad_options_raise(paper_system):
    with pytest.raises(ic.ParameterError, match="parameter must be one of"):
        ic.continuation(paper_system, parameter="gap", bounds=(0, 1))
    # the drivers' one bounds check (issue 28): a ParameterError naming bounds and the value
    with pytest.raises(ic.ParameterError, match=r"bounds must be two finite numbers with lo < "
                                                r"hi; got \(6\.0, 0\.5\)"):
        ic.continuation(paper_system, bounds=(6.0, 0.5))
    with pytest.raises(ContinuationOptionError, match="ds_max"):
        ic.continuation(paper_system, bounds=(0.5, 6.0), ds_max=-1.0)
    with pytest.raises(ic.ParameterError, match="N must be an integer"):
        ic.continuation(paper_system, N=0, bounds=(0.5, 6.0))
    with pytest.raises(ValueError, match="labels must be a subset"):
        ic.continuation(paper_system, bounds=(0.5, 6.0), detect=["XX"])
    with pytest.raises(ic.NoPeriodicMotionError, match="no N=1 motion anywhere"):
        ic.continuation(paper_system.replace(b=50.0), bounds=(0.5, 6.0))


def test_a_component_that_cannot_start_is_reported_not_fatal(monkeypatch):
    """A component whose seed sits where the corrector fails (here where eq. (15) has no
    root): the branch keeps the components that started and warns about the one that did
    not (it crashed with an IndexError in the event search before). The undamped chain's
    own second seed failed until eq. (14) was scaled by |c, s| (issue 19); it starts now."""
    from impactcont.orbit.periodic import amplitude_squared, orbit_at_phase
    from impactcont.problems import PeriodicBranchProblem

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.5, omega=1.0, eta=0.0)
    assert amplitude_squared(osc.replace(omega=1.45), 1) < osc.b ** 2  # no motion there
    seeds = PeriodicBranchProblem.component_seeds  # the closed form's hook: eq. (15)
    monkeypatch.setattr(PeriodicBranchProblem, "component_seeds",
                        lambda problem, bounds: [*seeds(problem, bounds),
                                                 (1.45, np.array([0.0]))])
    with pytest.warns(RuntimeWarning, match="could not be started"):
        branch = ic.continuation(osc, 1, "omega", (0.5, 1.5))
    assert branch.sizes["point"] > 100
    for k in range(1, branch.sizes["point"], 97):
        orbit = orbit_at_phase(osc.replace(omega=float(branch.omega[k])), 1,
                               float(branch.delta[k]))
        assert abs(orbit.state[0] - osc.b) < 1e-9  # a motion of eq. (14): x1(0) = b


def test_one_direction_follows_the_start_one_way_and_every_other_component_whole(
        paper_system, branch_b0):
    """both_directions=False with every component: the start's component from the start
    forward only, the others over the whole bounds, no component twice. Before, a seed on
    the start's other side was followed forward as a further component: it ran over the
    start's points again (524 points against 398 both ways, the PD at 1.7004 twice) and
    omega 0.5-0.61 was missing."""
    one = ic.continuation(paper_system, N=1, parameter="omega", bounds=(0.5, 6.0),
                          both_directions=False)
    comp = one.connected_component.values
    assert sorted(set(comp)) == [0, 1]
    start = one.omega.values[comp == 0]
    assert start[0] == 1.0 and start.min() == 1.0 and start.max() == 6.0
    whole = one.isel(point=comp == 1).omega.values
    assert (whole.min(), whole.max()) == (0.5, 6.0)
    # each special point once: the two-way branch's, less the GR behind the start
    found = list(zip(one.special_label.values, one.special_omega.values,
                     one.special_delta.values, strict=True))
    expected = [(lab, w, d) for lab, w, d in zip(
        branch_b0.special_label.values, branch_b0.special_omega.values,
        branch_b0.special_delta.values, strict=True) if w > 1.0]
    assert len(found) == len(expected) == 2
    for lab, w, d in expected:  # the located points agree to far below their spacing
        assert sum(lab == f[0] and abs(w - f[1]) < 1e-8 and abs(d - f[2]) < 1e-6
                   for f in found) == 1


def test_a_dataset_given_as_the_oscillator_is_refused_naming_what_to_call(branch_b0):
    with pytest.raises(ParameterError, match=r"osc must be an ImpactOscillator.*got "
                                             r"Dataset.*continuation_from or extend"):
        ic.continuation(branch_b0, N=1, parameter="omega", bounds=(0.5, 6.0))
    with pytest.raises(ParameterError, match="got str"):
        ic.continuation("paper", N=1, parameter="omega", bounds=(0.5, 6.0))


TOL = 1e-9  # the branches' Newton tolerance is 1e-12 (N-1) and 1e-11 (N-p)


@pytest.fixture(scope="module")
def system() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def branch(system):
    return ic.continuation(system, 1, "omega", (0.5, 3.0), progress=False)


@pytest.fixture(scope="module")
def switched(branch):
    return ic.period_doubling_switch(branch, bounds=(1.0, 2.0), max_points=40, progress=False)


def _phase(a: np.ndarray) -> np.ndarray:
    return np.remainder(a + np.pi, 2 * np.pi) - np.pi


def _same_specials(a, b, parameter: str = "omega") -> None:
    assert a.special_label.values.tolist() == b.special_label.values.tolist()
    precision = np.maximum(a.special_precision.values, b.special_precision.values)
    np.testing.assert_array_less(np.abs(a[f"special_{parameter}"].values
                                        - b[f"special_{parameter}"].values),
                                 np.maximum(10 * precision, TOL))


def _start_row(ds, rows):
    """Where the component's continuation started (the run there was computed outward)."""
    start = json.loads(ds.attrs["options"])["start"]
    return int(np.flatnonzero(ds.omega.values[rows] == start)[0])


@pytest.mark.parametrize("along", [1, -1])
def test_restart_reproduces_the_points_beyond_the_restart_point(branch, along):
    rows = np.flatnonzero(branch.connected_component.values == 0)
    k = _start_row(branch, rows) + 10 * along  # inside the run computed the way of along
    restarted = continuation_from(branch, int(rows[k]), along=along, progress=False)
    ahead = rows[k:] if along == 1 else rows[k::-1]
    assert restarted.sizes["point"] == ahead.size
    np.testing.assert_allclose(restarted.omega.values, branch.omega.values[ahead], rtol=0,
                               atol=TOL)
    assert np.max(np.abs(_phase(restarted.delta.values - branch.delta.values[ahead]))) < TOL
    record = json.loads(restarted.attrs["options"])
    assert record["restart"]["point"] == int(rows[k])
    assert record["status"] == ["BOUNDS_REACHED"]


def test_restart_from_a_special_point_by_label(branch):
    restarted = continuation_from(branch, label="PD", which=0, along=None, progress=False)
    k = next(i for i, lab in enumerate(branch.special_label.values) if lab == "PD")
    start = json.loads(restarted.attrs["options"])["start"]
    assert start == float(branch.special_omega.values[k])
    # the located PD is found again on the restarted branch
    pd = restarted.special_omega.values[restarted.special_label.values == "PD"]
    assert np.min(np.abs(pd - branch.special_omega.values[k])) < TOL


def test_extended_branch_equals_the_branch_computed_with_the_wider_bounds(system, branch):
    wide = ic.continuation(system, 1, "omega", (0.4, 4.0), progress=False)
    extended = extend(branch, (0.4, 4.0), progress=False)
    _same_specials(extended, wide)
    assert extended.omega.min() == 0.4 and extended.omega.max() == 4.0
    for c in (0, 1):
        old = branch.omega.values[branch.connected_component.values == c]
        new = extended.omega.values[extended.connected_component.values == c]
        # the branch inside, once (the points at the join are not repeated), then the rest
        first = int(np.flatnonzero(new == old[0])[0])
        np.testing.assert_array_equal(new[first:first + old.size], old)
        assert np.all(np.diff(new) > 0)
        np.testing.assert_allclose(new[[0, -1]], [0.4, 4.0])
    assert extended.arclength.values[0] == 0.0
    record = json.loads(extended.attrs["options"])
    assert record["bounds"] == [0.4, 4.0] and len(record["extended"]) == 4
    # every special point sits next to the point it names
    p = extended.special_point.values
    lam = extended.omega.values
    assert np.all(np.abs(lam[p] - extended.special_omega.values)
                  <= np.abs(np.diff(lam)).max())


def test_np_branch_restarted_and_extended(branch, switched):
    k = 10
    restarted = continuation_from(switched, k, progress=False)
    assert restarted.sizes["point"] == switched.sizes["point"] - k
    np.testing.assert_allclose(restarted.omega.values, switched.omega.values[k:], rtol=0,
                               atol=TOL)
    np.testing.assert_allclose(restarted.state_k.values, switched.state_k.values[k:], rtol=0,
                               atol=TOL)
    assert restarted.attrs["pattern"] == switched.attrs["pattern"]
    wide = ic.period_doubling_switch(branch, bounds=(1.0, 2.3), max_points=80, progress=False)
    extended = extend(switched, (1.0, 2.3), progress=False)
    _same_specials(extended, wide)
    n = switched.sizes["point"]
    np.testing.assert_array_equal(extended.omega.values[:n], switched.omega.values)
    assert np.all(np.diff(extended.omega.values) > 0)
    assert extended.omega.values[-1] == 2.3
    assert extended.attrs["born_at"] == "PD"


def test_a_branch_of_any_motion_that_stops_at_max_points_warns(system, switched):
    """As the closed form's components do: an N-p branch (and its restart) cut at
    max_points says so; the rest of it is not in the dataset."""
    motion = ic.multi_impact_orbit(system, 1, 1, next(o for o in ic.periodic_orbits(system, 1)
                                                       if o.physical))
    with pytest.warns(RuntimeWarning, match=r"the 1-1 component through omega=1 stopped at "
                                            r"max_points=5: the rest of it is not in"):
        ds = ic.continuation(motion, parameter="omega", bounds=(0.5, 3.0), max_points=5,
                             progress=False)
    assert "MAX_POINTS_REACHED" in json.loads(ds.attrs["options"])["status"]
    with pytest.warns(RuntimeWarning, match=r"the 2-2 component .* stopped at max_points=4"):
        restarted = continuation_from(switched, 0, max_points=4, progress=False)
    assert restarted.sizes["point"] == 4


def test_restart_from_a_saved_file(tmp_path, branch, switched):
    for ds in (branch, switched):
        path = tmp_path / f"{ds.attrs['N']}.nc"
        ic.save(ds, path)
        loaded = ic.load(path)
        a = continuation_from(loaded, label="PD", which=-1, progress=False)
        b = continuation_from(ds, label="PD", which=-1, progress=False)
        np.testing.assert_allclose(a.omega.values, b.omega.values, rtol=0, atol=TOL)
        extended = extend(loaded, (0.4, 3.0) if ds is branch else (1.0, 2.2), progress=False)
        ic.save(extended, tmp_path / "extended.nc")
        assert ic.load(tmp_path / "extended.nc").sizes["point"] == extended.sizes["point"]


def test_bad_arguments_are_refused(branch, switched):
    with pytest.raises(TypeError, match=r"branch must be a branch xarray\.Dataset"):
        continuation_from({"omega": 1.0}, 0)
    with pytest.raises(ParameterError, match=r"either point= .* or label="):
        continuation_from(branch)
    with pytest.raises(ParameterError, match=r"either point= .* or label="):
        continuation_from(branch, 3, label="PD")
    with pytest.raises(ParameterError, match=r"point must be an integer index in \[-316"):
        continuation_from(branch, 316)
    with pytest.raises(ParameterError, match="label must be one of"):
        continuation_from(branch, label="XX")
    with pytest.raises(ParameterError, match="which must be an integer index among the "
                                             "branch's 2 PD"):
        continuation_from(branch, label="PD", which=2)
    with pytest.raises(ParameterError, match="along must be"):
        continuation_from(branch, 3, along=0)
    with pytest.raises(ParameterError, match="must contain the restart point"):
        continuation_from(branch, 3, bounds=(2.0, 3.0))
    with pytest.raises(ParameterError, match="bounds must contain the branch's bounds"):
        extend(branch, (0.6, 4.0))
    with pytest.raises(ParameterError, match="bounds must contain the branch's bounds"):
        extend(switched, (1.0, 2.0))
    with pytest.raises(ParameterError, match="bounds must be two numbers"):
        extend(branch, 4.0)
    with pytest.raises(ParameterError, match="not a branch dataset"):
        extend(branch.drop_vars("delta"), (0.4, 4.0))


def test_a_restart_needs_the_branchs_user_functions(system):
    """continuation_from requires the branch's events and monitors, as extend does
    (functions are not stored: without them the restart lost its events silently); it may
    add others."""
    def v07(o):
        return o.impact_velocity - 0.7

    short = ic.continuation(system, 1, "omega", (1.4, 2.0), components="start",
                            events={"v07": v07}, monitors={"v": lambda o: o.impact_velocity},
                            progress=False)
    assert short.sizes["event"] >= 1
    with pytest.raises(ParameterError, match=r"events must have the names of the branch's "
                                             r"events \['v07'\] .*got \[\]; allowed: a mapping "
                                             r"with those names \(others may be added\)"):
        continuation_from(short, 0, progress=False)
    with pytest.raises(ParameterError, match=r"monitors must have the names .*\['v'\]"):
        continuation_from(short, 0, events={"v07": v07}, progress=False)
    again = continuation_from(short, 0, events={"v07": v07, "v06": lambda o:
                                                o.impact_velocity - 0.6},
                              monitors={"v": lambda o: o.impact_velocity}, progress=False)
    assert set(again["event_name"].values.tolist()) >= {"v07"}
    np.testing.assert_allclose(np.sort(again["event_omega"].values[
        again["event_name"].values == "v07"]), np.sort(short["event_omega"].values), rtol=0,
        atol=TOL)


def test_a_dataset_that_is_not_a_branch_is_refused_naming_what_it_is(system, branch):
    """A map, a family map or a simulation given to continuation_from or extend is named
    (a family map was called a two-parameter curve)."""
    closed = ic.stability_map(system, N=[1], omega=np.linspace(1.0, 1.2, 3),
                              b=np.linspace(0.0, 0.1, 2), progress=False)
    motion = ic.multi_impact_orbit(system.replace(omega=1.5), 1, 1, next(
        o for o in ic.periodic_orbits(system.replace(omega=1.5), 1) if o.physical))
    family = ic.stability_map(motion, parameters=("omega", "b"),
                              grid={"omega": [1.5, 1.55], "b": [0.0, 0.05]}, progress=False)
    run = ic.simulate(system, motion.states[0], float(motion.phases[0]), 2)
    from impactcont.dataset.simulation import simulation_dataset
    for ds, what in ((closed, r"a stability map of N-1 motions .*impactcont_dataset='map'"),
                     (family, r"a stability map of a motion's family .* over 'omega,b' "
                              r"\(attribute impactcont_dataset='multi_impact_map'\)"),
                     (simulation_dataset(run), r"a simulation dataset .*'simulation'")):
        refused = r"branch must be a one-parameter branch dataset .*; got " + what
        with pytest.raises(ParameterError, match=refused):
            continuation_from(ds, 0)
        with pytest.raises(ParameterError, match=refused):
            extend(ds, (0.5, 4.0))
    cv = branch.assign_attrs(curve_kind="PD", parameters="omega,b")
    with pytest.raises(ParameterError, match=r"got a two-parameter curve dataset \(PD curve "
                                             r"over 'omega,b'\)"):
        continuation_from(cv, 0)


@pytest.mark.parametrize("newton_tol", [1.0, 1e-5, 2e-7])
def test_a_newton_tolerance_the_closed_form_cannot_keep_is_refused(system, branch, newton_tol):
    """Above 1e-7, eq. (14)'s tolerance for a motion, an accepted point could be no motion:
    refused naming newton_tol (1.0 failed inside the motion's eq. 14 check)."""
    match = (rf"option newton_tol = {newton_tol!r} is invalid; the closed form of N-1 motions "
             r"takes at most 1e-07")
    with pytest.raises(ContinuationOptionError, match=match):
        ic.continuation(system, 1, "omega", (1.4, 2.0), newton_tol=newton_tol, progress=False)
    with pytest.raises(ContinuationOptionError, match=match):
        continuation_from(branch, 3, newton_tol=newton_tol, progress=False)


def test_the_largest_newton_tolerance_of_the_closed_form_keeps_every_point(system):
    ds = ic.continuation(system, 1, "omega", (0.5, 3.0), newton_tol=1e-7, progress=False)
    for k in range(0, ds.sizes["point"], 7):  # each point a motion (eq. 14 checked)
        orbit = orbit_at_phase(system.replace(omega=float(ds.omega.values[k])), 1,
                                  float(ds.delta.values[k]))
        assert orbit.impact_velocity == pytest.approx(float(ds.impact_velocity.values[k]),
                                                      rel=1e-5)


# -- issue 28: bounds of an element checked up front; a failure keeps what was computed ------
def test_bounds_of_a_stiffness_entry_are_refused_before_computing(paper_system) -> None:
    import time

    t0 = time.perf_counter()
    with pytest.raises(ParameterError) as info:
        ic.continuation(paper_system, 1, "K[1,1]", (-1, 3))
    assert time.perf_counter() - t0 < 1.0  # nothing computed (it took 6.6 s to fail)
    text = str(info.value)
    assert text.startswith("bounds (-1, 3) for K[1,1]: at K[1,1] = -1.0 the oscillator is "
                           "refused: K must be positive semi-definite"), text
    assert "allowed: bounds inside K[1,1] in [0.5, inf), where K stays positive " \
           "semi-definite with its other entries" in text


def test_a_failure_while_searching_components_keeps_the_branch(paper_system, monkeypatch
                                                               ) -> None:
    from impactcont.problems import PeriodicBranchProblem

    def failing(problem, bounds):
        raise ParameterError("K must be positive semi-definite (at K[1,1] = 0.1)")

    monkeypatch.setattr(PeriodicBranchProblem, "component_seeds", failing)
    with pytest.warns(RuntimeWarning, match="the search for further components in omega "
                                            "failed .*K must be positive"):
        ds = ic.continuation(paper_system, 1, "omega", (1.5, 2.0))
    assert ds.sizes["point"] > 3  # the component through the start is kept
    message = json.loads(ds.attrs["options"])["message"]
    assert "the branch holds the 1 component(s) followed before it" in message


def test_a_restart_at_a_non_finite_point_names_the_file_and_the_point(
        branch_b05, tmp_path) -> None:
    broken = branch_b05.copy(deep=True)
    broken["delta"].values[4] = np.nan
    with pytest.raises(ParameterError, match=r"point 4 of the branch has non-finite values "
                                             r"\(delta = nan\)"):
        continuation_from(broken, point=4)
    path = tmp_path / "broken.nc"
    ic.save(broken, path)
    loaded = ic.load(path)
    with pytest.raises(ParameterError) as info:
        continuation_from(loaded, point=4)
    assert f"point 4 of the branch in {str(path)!r} has non-finite values" in str(info.value)
    assert "allowed: a point whose values are all finite, e.g. point 3 or 5" in str(info.value)


def test_one_driver_runs_the_closed_form_problem(paper_system):
    """Issue 29: the driver of every motion (trace_branch, run_branch) follows the N-1
    closed form as it follows a shooting problem: the same points and special points as
    continuation's component through the start, in the paper's N-1 schema."""
    from impactcont.analysis.branch import check_continuation_arguments, run_branch, trace_branch

    osc = paper_system.replace(b=0.5, omega=1.0)
    want = ic.continuation(osc, 1, "omega", (0.5, 3.0), components="start", progress=False)
    problem, _, _, opts = check_continuation_arguments(osc, 1, "omega", (0.5, 3.0))
    u0 = problem.start_root(1.0, None)
    samples, statuses, _ = trace_branch(problem, u0, 1.0, opts)
    assert len(samples) == want.sizes["point"] and len(statuses) == 2
    assert isinstance(samples[0].orbit, ic.PeriodicOrbit)
    np.testing.assert_array_equal([s.lam for s in samples], want["omega"].values)
    got = run_branch(problem, u0, 1.0, opts)
    assert "impact" not in got.dims and "connected_component" in got
    for name in ("omega", "delta", "impact_velocity", "special_label", "special_omega",
                 "special_precision", "special_status"):
        np.testing.assert_array_equal(got[name].values, want[name].values, err_msg=name)



def test_the_motion_at_the_start_of_a_branch_is_evaluated_once(paper_system, monkeypatch):
    """Issue 29 (the fixed costs of a short branch): the watches of both directions share
    the motion at the start (the backward run starts from the very point the forward run
    corrected); before, each evaluated it, with its contact checks."""
    from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

    osc = paper_system.replace(omega=1.5)
    physical = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    start = ic.multi_impact_orbit(osc, 1, 1, physical)
    seen = []
    orbit = MultiImpactBranchProblem.orbit

    def counted(self, u, lam, **kwargs):
        seen.append(float(lam))
        return orbit(self, u, lam, **kwargs)

    monkeypatch.setattr(MultiImpactBranchProblem, "orbit", counted)
    ds = ic.multi_impact_continuation(start, "omega", (1.45, 1.55), detect=(),
                                      both_directions=True)
    assert ds.sizes["point"] >= 3 and np.any(ds.omega.values < 1.5) and np.any(
        ds.omega.values > 1.5)
    assert seen.count(1.5) == 1, seen

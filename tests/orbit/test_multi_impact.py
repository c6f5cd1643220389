"""N-p motions (p impacts in N periods), their branches and branch switching."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.multi_branch import multi_impact_continuation
from impactcont.analysis.switching import (
    critical_direction,
    grazing_switch,
    period_doubling_switch,
    special_orbit,
)
from impactcont.dataset.multi import impacts_of, validate_multi_impact_dataset
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import (
    initial_unknowns,
    multi_impact_orbit,
    primitive_orbit,
    shooting,
)
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

PD_OMEGA = 1.70038303473  # N = 1 PD of the paper's system at b = 0 (test_branch finds it too)


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
# The solver
# ---------------------------------------------------------------------------------------------
N1_CASES = [
    # (n, params, N)
    (2, {"omega": 1.0, "b": 0.6}, 1),
    (2, {"omega": 1.2, "b": 0.0}, 1),
    (2, {"omega": 2.4, "b": 0.0}, 2),
    (3, {"omega": 1.1, "b": 0.1}, 1),
    (1, {"omega": 1.3, "b": 0.2, "R": 0.8, "eta": 0.05}, 1),
]


@pytest.mark.parametrize("case", range(len(N1_CASES)))
def test_n1_special_case_is_the_closed_form(case, paper, make_chain):
    n, params, N = N1_CASES[case]
    osc = paper.replace(**params) if n == 2 else make_chain(n, **params)
    closed = ic.periodic_orbits(osc, N)
    assert closed
    for orbit in closed:
        # start Newton visibly away from the closed form
        guess = {"delta": orbit.delta + 1e-3, "flight_times": [orbit.period],
                 "states": (orbit.state + 1e-3 * np.r_[0.0, np.ones(2 * n - 1)])[None, :]}
        m = multi_impact_orbit(osc, N, 1, guess)
        assert abs(wrap(m.delta - orbit.delta)) < 1e-12
        np.testing.assert_allclose(m.state, orbit.state, rtol=0, atol=1e-12)
        np.testing.assert_allclose(m.multipliers, orbit.multipliers, rtol=0, atol=1e-12)
        np.testing.assert_allclose(m.G, orbit.G, rtol=0, atol=1e-12 * max(1, abs(orbit.G).max()))
        assert m.impact_velocity == pytest.approx(orbit.impact_velocity, abs=1e-12)
        assert m.physical == orbit.physical


def test_two_two_motion_from_simulation_is_reproduced(paper_b0):
    osc = paper_b0.replace(omega=1.75)
    n1 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    assert not n1.stable  # beyond the PD
    X = n1.state.copy()
    X[1] += 1e-4
    res = ic.simulate(osc, X, n1.delta, 300.0)
    m = multi_impact_orbit(osc, 2, 2, res)
    assert m.physical and m.stable and m.residual < 1e-13
    assert abs(m.impact_velocities[0] - m.impact_velocities[1]) > 0.1
    assert m.flight_times.sum() == pytest.approx(m.period, rel=1e-14)
    assert_reproduced_by_simulator(m, 30)


def test_liouville_determinant_of_the_product(paper_b0, make_chain):
    """det G = R^(2p) exp(-T tr(M^-1 C)): each impact contributes R^2 (see docs/theory.md)."""
    osc = paper_b0.replace(omega=1.75)
    n1 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    for m in (multi_impact_orbit(osc, 2, 2, ic.simulate(osc, n1.state, n1.delta + 1e-3, 200.0)),
              multi_impact_orbit(osc, 3, 3, n1)):  # the N-1 motion thrice: p = 3 on itself
        trace = np.trace(np.linalg.solve(osc.M, osc.C))
        expected = osc.R ** (2 * m.p) * math.exp(-m.period * trace)
        assert np.linalg.det(m.G) == pytest.approx(expected, rel=1e-9)


def test_primitive_orbit_undoes_a_repetition(paper_b0):
    osc = paper_b0.replace(omega=1.75)
    n1 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    twice = multi_impact_orbit(osc, 2, 2, n1)  # the N-1 motion is also a 2-2 solution
    prim = primitive_orbit(twice)
    assert (prim.N, prim.p) == (1, 1)
    assert abs(wrap(prim.delta - n1.delta)) < 1e-12
    np.testing.assert_allclose(prim.multipliers, n1.multipliers, atol=1e-12)
    genuine = multi_impact_orbit(osc, 2, 2, ic.simulate(osc, n1.state, n1.delta + 1e-3, 200.0))
    assert primitive_orbit(genuine) is genuine


@pytest.mark.parametrize(("n", "N", "p"), [(2, 2, 2), (3, 3, 3), (2, 1, 1)])
def test_shooting_jacobian_against_central_differences(n, N, p, paper_b0, make_chain):
    osc = paper_b0.replace(omega=1.75) if n == 2 else make_chain(3, omega=1.1, b=0.1)
    flow = Flow(osc)
    rng = np.random.default_rng(7)
    T = 2 * math.pi * N / osc.omega
    u = np.concatenate([[0.4], np.full(p - 1, T / p), 0.3 * rng.normal(size=p * (2 * n - 1))])
    J = shooting(flow, N, p, u).jacobian
    h = 1e-6
    fd = np.empty_like(J)
    for j in range(u.size):
        e = np.zeros_like(u)
        e[j] = h
        fd[:, j] = (shooting(flow, N, p, u + e).residual
                    - shooting(flow, N, p, u - e).residual) / (2 * h)
    assert np.abs(fd - J).max() < 1e-7 * max(1.0, np.abs(J).max())


@pytest.mark.parametrize("parameter", ["omega", "b", "R", "eta"])
def test_parameter_derivative_against_central_differences(parameter, paper_b0):
    osc = paper_b0.replace(omega=1.75, b=0.05)
    problem = MultiImpactBranchProblem(osc, 2, 2, parameter)
    rng = np.random.default_rng(3)
    T = 2 * math.pi * 2 / osc.omega
    u = np.concatenate([[0.9], [0.55 * T], 0.3 * rng.normal(size=6)])
    lam = float(getattr(osc, parameter))
    h = 1e-6
    fd = (problem.residual(u, lam + h) - problem.residual(u, lam - h)) / (2 * h)
    np.testing.assert_allclose(problem.dparam(u, lam), fd, rtol=0, atol=1e-7)


def test_bad_inputs_raise_clear_errors(paper_b0, branch_n1):
    osc = paper_b0
    n1 = ic.periodic_orbits(osc, 1)[0]
    for bad in (0, -1, 1.5, "2", True):
        with pytest.raises(ic.ParameterError, match="p must be an integer >= 1"):
            multi_impact_orbit(osc, 1, bad, n1)
        with pytest.raises(ic.ParameterError, match="N must be an integer >= 1"):
            multi_impact_orbit(osc, bad, 1, n1)
    with pytest.raises(TypeError, match="guess must be a MultiImpactOrbit"):
        multi_impact_orbit(osc, 1, 1, [0.0, 1.0])
    with pytest.raises(ic.ParameterError, match="can seed an N-p motion"):
        multi_impact_orbit(osc, 3, 2, n1)
    with pytest.raises(ic.ParameterError, match=r"flight_times must have shape \(2,\)"):
        multi_impact_orbit(osc, 2, 2, {"delta": 0.0, "flight_times": [1.0],
                                       "states": np.zeros((2, 4))})
    with pytest.raises(ic.ParameterError, match="needs keys"):
        multi_impact_orbit(osc, 2, 2, {"delta": 0.0})
    with pytest.raises(ic.ParameterError, match="tol must be"):
        multi_impact_orbit(osc, 1, 1, n1, tol=0.0)
    with pytest.raises(ic.ParameterError, match="parameter must be one of"):
        MultiImpactBranchProblem(osc, 1, 1, "gap")
    with pytest.raises(ic.ParameterError, match="must contain the start"):
        multi_impact_continuation(n1, "omega", (2.0, 3.0))
    with pytest.raises(ic.ParameterError, match="out of range: the branch has 1 PD"):
        period_doubling_switch(branch_n1, which=3)
    with pytest.raises(ic.ParameterError, match="epsilon must be"):
        period_doubling_switch(branch_n1, epsilon=2.0)
    with pytest.raises(ic.ParameterError, match="0 GR point"):
        grazing_switch(branch_n1)
    with pytest.raises(ic.NoPeriodicMotionError, match="did not converge"):
        multi_impact_orbit(osc, 2, 2, {"delta": 0.0, "flight_times": [0.1, 0.1],
                                       "states": np.full((2, 4), 50.0)}, max_iter=5)


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


def test_a_phase_that_runs_off_does_not_loosen_newton_s_test():
    # A bouncing ball (free mass, gravity as F_static, the table's motion as F) from a
    # poor guess: Newton drove the phase to ~-3e14 and the test tol * max(1, |u|) then
    # passed with a residual of 0.95. The phase now counts at most pi in the scale.
    from impactcont.orbit.multi_impact import unknowns_scale

    assert unknowns_scale(np.array([-3e14, 2.0, 0.5])) == math.pi
    assert unknowns_scale(np.array([0.5, 2.0, -7.0])) == 7.0
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[1.06], F_static=[-1.0], omega=1.0,
                              R=0.5, b=1000.0, stops=ic.Stops(b_low=0.0, R_low=0.5))
    guess = {"delta": -math.pi / 2, "flight_times": [2 * math.pi], "states": [[0.0, math.pi]]}
    try:
        orbit = ic.multi_impact_orbit(osc, 1, 1, guess=guess, pattern="L")
    except ic.NoPeriodicMotionError:
        return
    assert orbit.residual < 1e-9

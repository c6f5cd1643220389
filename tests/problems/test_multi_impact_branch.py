"""The N-p branch problem (:mod:`impactcont.problems.multi_impact_branch`): the shooting
residual vanishes at known motions (the closed-form N-1 motion, and a 2-2 motion the
event-driven simulator repeats), its Jacobian and parameter derivatives agree with central
differences, its product of impact maps is the motion's G, and it refuses what it cannot
follow by name."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.0, omega=1.75, eta=0.1)


@pytest.fixture(scope="module")
def two() -> xr.Dataset:
    """The 2-2 branch born at the period doubling of the paper's N-1 branch at b = 0."""
    n1 = ic.continuation(PAPER, N=1, bounds=(1.6, 1.9), detect=("PD",))
    return ic.period_doubling_switch(n1, 0, ds_max=0.05, detect=())


def _unknowns(ds: xr.Dataset, i: int) -> np.ndarray:
    """``[delta, tau_0, z_0, z_1]`` of point i (z_k: the state after impact k without x1,
    which is b at the stop)."""
    states = ds["state_k"].values[i]
    return np.concatenate([[ds["delta_k"].values[i, 0]], ds["flight_time_k"].values[i, :-1],
                           states[:, 1:].ravel()])


def _central_jacobian(f, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = []
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h * max(1.0, abs(x[i]))
        cols.append((f(x + e) - f(x - e)) / (2 * e[i]))
    return np.column_stack(cols)


def test_the_residual_vanishes_at_the_closed_form_n1_motion() -> None:
    osc = PAPER.replace(omega=1.5)
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    problem = MultiImpactBranchProblem(osc, 1, 1, "omega")
    u = np.concatenate([[orbit.delta], orbit.state[1:]])
    assert problem.size == u.size == 4
    assert np.max(np.abs(problem.residual(u, 1.5))) < 1e-12
    motion = problem.orbit(u, 1.5)
    np.testing.assert_allclose(motion.G, orbit.G, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(problem.jacobian_product(u, 1.5, 1), orbit.G, rtol=1e-9,
                               atol=1e-11)
    assert np.max(np.abs(problem.residual(u + 1e-3, 1.5))) > 1e-5


def test_the_residual_vanishes_at_a_2_2_motion_the_simulator_repeats(two) -> None:
    i = two.sizes["point"] // 2
    omega = float(two["omega"][i])
    u = _unknowns(two, i)
    problem = MultiImpactBranchProblem(PAPER, 2, 2, "omega")
    assert np.max(np.abs(problem.residual(u, omega))) < 1e-10
    np.testing.assert_array_equal(problem.orbit(u, omega).unknowns, u)
    # the witness: the event-driven simulator from the state after impact 0, over the
    # motion's N = 2 forcing periods (and a little more, to see the impact that closes it)
    osc = PAPER.replace(omega=omega)
    run = ic.simulate(osc, two["state_k"].values[i, 0], float(two["delta_k"][i, 0]), 2.1)
    np.testing.assert_allclose(run.impact_times, np.cumsum(two["flight_time_k"].values[i]),
                               rtol=1e-8)
    np.testing.assert_allclose(run.impact_states[0], two["state_k"].values[i, 1], atol=1e-8)
    np.testing.assert_allclose(run.impact_states[1], two["state_k"].values[i, 0], atol=1e-8)


@pytest.mark.parametrize(("parameter", "value"), [
    ("omega", None), ("b", 0.0), ("R", 0.6), ("eta", 0.1), ("F0", 1.0), ("k2", 1.0),
])
def test_the_derivatives_agree_with_central_differences(two, parameter, value) -> None:
    i = two.sizes["point"] // 2
    omega = float(two["omega"][i])
    osc = PAPER.replace(omega=omega)
    lam = omega if value is None else value
    problem = MultiImpactBranchProblem(osc, 2, 2, parameter)
    u = _unknowns(two, i)
    J = problem.jacobian(u, lam)
    np.testing.assert_allclose(J, _central_jacobian(lambda v: problem.residual(v, lam), u),
                               rtol=1e-5, atol=1e-7)
    h = 1e-6 * max(1.0, abs(lam))
    fd = (problem.residual(u, lam + h) - problem.residual(u, lam - h)) / (2 * h)
    np.testing.assert_allclose(problem.dparam(u, lam), fd, rtol=1e-5, atol=1e-7)
    residual, extended = problem.linearize(u, lam)
    np.testing.assert_array_equal(residual, problem.residual(u, lam))
    np.testing.assert_allclose(extended, np.column_stack([J, problem.dparam(u, lam)]),
                               rtol=1e-12, atol=1e-14)


def test_the_product_of_impact_maps_is_G_of_the_motion(two) -> None:
    i = two.sizes["point"] // 2
    omega = float(two["omega"][i])
    problem = MultiImpactBranchProblem(PAPER, 2, 2, "omega")
    u = _unknowns(two, i)
    G = problem.jacobian_product(u, omega, 2)
    np.testing.assert_allclose(G, problem.orbit(u, omega).G, rtol=1e-10, atol=1e-12)
    mu = np.sort_complex(np.linalg.eigvals(G))
    np.testing.assert_allclose(mu, np.sort_complex(two["multipliers"].values[i]), atol=1e-8)


def test_bounds_that_close_the_clearance_between_the_stops_are_refused() -> None:
    two_sided = PAPER.replace(b=0.5, stops=Stops(b_low=0.3))
    problem = MultiImpactBranchProblem(two_sided, 1, 2, "b", pattern="UL")
    assert problem.parameter_limits() == (pytest.approx(-0.3, abs=1e-15), np.inf)
    assert "the clearance b + b_low between them closes" in problem.limit_reason()
    problem.check_bounds((0.0, 1.0))
    with pytest.raises(ParameterError, match=r"bounds \(-0.5, 1.0\) of parameter 'b' reach "
                                             r"b = -0.3.*: .*; give bounds with b > -0.3"):
        problem.check_bounds((-0.5, 1.0))
    assert MultiImpactBranchProblem(PAPER, 1, 1, "omega").parameter_limits() == (-np.inf,
                                                                                 np.inf)


def test_bad_arguments_are_named() -> None:
    with pytest.raises(TypeError, match=r"osc must be an ImpactOscillator; got str"):
        MultiImpactBranchProblem("paper", 1, 1, "omega")
    problem = MultiImpactBranchProblem(PAPER, 2, 2, "omega")
    with pytest.raises(ParameterError, match=r"u must have shape \(8,\) = \(2 n p,\); got "
                                             r"\(3,\)"):
        problem.residual(np.zeros(3), 1.7)
    with pytest.raises(ParameterError, match="pattern"):
        MultiImpactBranchProblem(PAPER, 1, 2, "omega", pattern="UL")  # no lower stop
    with pytest.raises(ParameterError, match=r"derivative: parameter 'eta' changes the"):
        problem.derivative(np.zeros(8), 1.7, MultiImpactBranchProblem(PAPER, 1, 1,
                                                                      "eta").param)

"""The half system of symmetric N-p motions (:mod:`impactcont.problems.symmetric_branch`): at
the symmetric 1-2 motion the simulator settles on (mirrored stops), the half unknowns give
back the full ones, the half residual vanishes, its Jacobian and parameter derivative agree
with central differences, and the half-map squared is G; parameters and motions that cannot
be symmetric are refused by name."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.problems.symmetric_branch import SymmetricBranchProblem

OMEGA = 1.6


def _mirrored(**changes) -> ic.ImpactOscillator:
    base = {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6,
            "eta": 0.1, "b": 0.5, "omega": OMEGA, "stops": Stops(mirror=True)}
    return ic.ImpactOscillator(**{**base, **changes})


@pytest.fixture(scope="module")
def motion():
    """The symmetric 1-2 motion the simulator settles on at omega = 1.6, b = 0.5."""
    osc = _mirrored()
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))


def _central_jacobian(f, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = []
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h * max(1.0, abs(x[i]))
        cols.append((f(x + e) - f(x - e)) / (2 * e[i]))
    return np.column_stack(cols)


def test_the_motion_is_symmetric(motion) -> None:
    """The witness of the symmetry: the second half mirrors the first (x -> -x)."""
    assert motion.pattern in ("UL", "LU")
    np.testing.assert_allclose(motion.flight_times, math.pi / OMEGA, rtol=1e-9)
    np.testing.assert_allclose(motion.states[1], -motion.states[0], atol=1e-9)


def test_the_half_residual_vanishes_and_the_unknowns_round_trip(motion) -> None:
    problem = SymmetricBranchProblem(_mirrored(), 1, 2, "omega", pattern=motion.pattern)
    u = motion.unknowns
    v = problem.half_unknowns(u)
    assert problem.size == v.size == u.size // 2 == 4
    np.testing.assert_allclose(problem.full_unknowns(v, OMEGA), u, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(problem.residual(v, OMEGA))) < 1e-10
    assert np.max(np.abs(problem.residual(v + 1e-3, OMEGA))) > 1e-5
    orbit = problem.orbit(v, OMEGA)
    np.testing.assert_allclose(orbit.states, motion.states, atol=1e-10)


@pytest.mark.parametrize(("parameter", "lam"), [("omega", OMEGA), ("b", 0.5), ("R", 0.6),
                                                ("eta", 0.1)])
def test_the_derivatives_agree_with_central_differences(motion, parameter, lam) -> None:
    problem = SymmetricBranchProblem(_mirrored(), 1, 2, parameter, pattern=motion.pattern)
    v = problem.half_unknowns(motion.unknowns)
    np.testing.assert_allclose(problem.jacobian(v, lam),
                               _central_jacobian(lambda x: problem.residual(x, lam), v),
                               rtol=1e-5, atol=1e-7)
    h = 1e-6 * max(1.0, abs(lam))
    fd = (problem.residual(v, lam + h) - problem.residual(v, lam - h)) / (2 * h)
    np.testing.assert_allclose(problem.dparam(v, lam), fd, rtol=1e-5, atol=1e-7)
    residual, extended = problem.linearize(v, lam)
    np.testing.assert_allclose(residual, problem.residual(v, lam), atol=1e-15)
    np.testing.assert_allclose(extended[:, -1], problem.dparam(v, lam), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(extended[:, :-1], problem.jacobian(v, lam), rtol=1e-9,
                               atol=1e-12)


def test_the_half_map_squared_is_G(motion) -> None:
    problem = SymmetricBranchProblem(_mirrored(), 1, 2, "omega", pattern=motion.pattern)
    H = problem.half_map(problem.half_unknowns(motion.unknowns), OMEGA)
    np.testing.assert_allclose(H @ H, motion.G, rtol=1e-8, atol=1e-10)


def test_what_cannot_be_symmetric_is_refused(motion) -> None:
    one_sided = _mirrored(stops=Stops(b_low=0.5))  # b moves the upper stop only
    with pytest.raises(ParameterError, match=r"parameter 'b' moves one stop only and breaks "
                                             r"the symmetry"):
        SymmetricBranchProblem(one_sided, 1, 2, "b", pattern="UL")
    with pytest.raises(ParameterError, match=r"cannot be symmetric: that needs N odd, p even"):
        SymmetricBranchProblem(_mirrored(), 2, 2, "omega", pattern="UL")
    with pytest.raises(ParameterError, match=r"cannot be symmetric"):
        SymmetricBranchProblem(_mirrored(), 1, 2, "omega", pattern="UU")
    problem = SymmetricBranchProblem(_mirrored(), 1, 2, "omega", pattern=motion.pattern)
    with pytest.raises(ParameterError, match=r"v must have shape \(4,\) = \(2 n p/2,\); got "
                                             r"\(8,\)"):
        problem.residual(motion.unknowns, OMEGA)
    assert "BP" in problem.events and problem.symmetric


@pytest.mark.parametrize(("stops", "b", "omega", "moving"), [
    (Stops(mirror=True), 0.5, OMEGA, "b"),      # b moves both stops
    (Stops(b_low=0.8), 0.8, 0.8, "gap"),        # the backlash: gap moves both
])
def test_the_half_map_derivative_agrees_with_central_differences(stops, b, omega, moving):
    """``dH`` in the half unknowns, a parameter moving the stops and omega (eq. 25
    differentiated on the flights' exact derivatives, compiled) against central differences of
    :meth:`half_map` (a new shot each; the moved stops by a problem on the moved
    oscillator), within what differences of step 1e-5 give (1e-7 relative)."""
    osc = _mirrored(stops=stops, b=b, omega=omega)
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 200.0))
    problem = SymmetricBranchProblem(osc, 1, 2, "omega", pattern=motion.pattern)
    v = problem.half_unknowns(motion.unknowns)
    param = model_parameter(osc, moving)
    dv = np.vstack([np.eye(v.size), np.zeros(v.size)])
    dc = np.zeros((v.size + 1, problem.p))
    dc[-1] = param.stop_rates(problem.pattern)
    H, dH = problem.half_map_derivative(v, omega, dv, dc)
    np.testing.assert_allclose(H, problem.half_map(v, omega), rtol=1e-13, atol=1e-14)
    for i in range(v.size):
        h = 1e-5 * max(1.0, abs(v[i]))
        e = np.zeros(v.size)
        e[i] = h
        fd = (problem.half_map(v + e, omega) - problem.half_map(v - e, omega)) / (2 * h)
        np.testing.assert_allclose(dH[i], fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max())
    value, h = param.value(osc), 1e-5

    def moved(c: float) -> np.ndarray:
        return problem.moved(param.at(osc, c)).half_map(v, omega)

    fd = (moved(value + h) - moved(value - h)) / (2 * h)
    np.testing.assert_allclose(dH[-1], fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max())
    assert np.abs(dH[-1]).max() > 1e-3  # the stops' position moves H
    # omega, the problem's parameter, at fixed v (through e(omega), the phases, the forced
    # parts and G's last row)
    _, dH = problem.half_map_derivative(v, omega, np.zeros((1, v.size)),
                                        np.zeros((1, problem.p)), np.ones(1))
    h = 1e-5
    fd = (problem.half_map(v, omega + h) - problem.half_map(v, omega - h)) / (2 * h)
    np.testing.assert_allclose(dH[0], fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max())


def test_the_half_map_derivative_needs_the_problem_in_omega(motion):
    problem = SymmetricBranchProblem(_mirrored(), 1, 2, "b", pattern=motion.pattern)
    v = problem.half_unknowns(motion.unknowns)
    with pytest.raises(ParameterError, match="a problem in 'b' on"):
        problem.half_map_derivative(v, 0.5, np.eye(v.size), np.zeros((v.size, 2)))

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

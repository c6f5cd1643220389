"""The N-1 branch problem (:mod:`impactcont.problems.periodic_branch`): eq. (14) vanishes at
every motion of the closed form (``periodic_orbits``), its Jacobian and parameter derivative
agree with central differences in every kind of parameter, the fold system vanishes at a
located fold, and its helpers (residual scale, the root's phase) do what they say."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.problems.periodic_branch import (
    PeriodicBranchProblem,
    residual_scale,
    root_phase,
    scaled_derivative,
)

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.5, omega=1.2, eta=0.1)


def _central(f, x: float, h: float) -> np.ndarray:
    return (np.asarray(f(x + h)) - np.asarray(f(x - h))) / (2 * h)


@pytest.mark.parametrize("omega", [0.8, 1.2, 2.5])
def test_the_residual_vanishes_at_every_motion_of_the_closed_form(omega) -> None:
    osc = PAPER.replace(omega=omega)
    problem = PeriodicBranchProblem(osc, 1, "omega")
    orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2
    for orbit in orbits:
        assert abs(problem.residual(np.array([orbit.delta]), omega)[0]) < 1e-12
        again = problem.orbit(orbit.delta, omega)
        np.testing.assert_allclose(again.state, orbit.state, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(again.multipliers, orbit.multipliers, rtol=1e-10,
                                   atol=1e-12)
    assert abs(problem.residual(np.array([orbits[0].delta + 0.1]), omega)[0]) > 1e-3


@pytest.mark.parametrize(("parameter", "lam"), [
    ("omega", 1.2), ("b", 0.5), ("R", 0.6), ("eta", 0.1), ("F0", 1.0), ("k2", 1.0),
    ("M[1,1]", 1.0), ("F[2]", 0.0),
])
def test_the_derivatives_agree_with_central_differences(parameter, lam) -> None:
    problem = PeriodicBranchProblem(PAPER, 1, parameter)
    for delta in (-2.0, 0.4, 2.8):
        u = np.array([delta])
        J = problem.jacobian(u, lam)
        fd = _central(lambda d: problem.residual(np.array([d]), lam), delta, 1e-6)
        np.testing.assert_allclose(J[:, 0], fd, rtol=1e-7, atol=1e-9)
        dp = problem.dparam(u, lam)
        fd = _central(lambda p, u=u: problem.residual(u, p), lam, 1e-6 * max(1.0, abs(lam)))
        np.testing.assert_allclose(dp, fd, rtol=1e-6, atol=1e-8)


def test_the_residual_at_N_2_vanishes_at_its_motions() -> None:
    osc = PAPER.replace(b=0.0, omega=2.4)
    problem = PeriodicBranchProblem(osc, 2, "omega")
    for orbit in ic.periodic_orbits(osc, 2):
        assert abs(problem.residual(np.array([orbit.delta]), 2.4)[0]) < 1e-12


def test_the_fold_system_vanishes_at_the_located_fold() -> None:
    branch = ic.continuation(PAPER, N=1, bounds=(1.1, 1.3), detect=("SN",))
    (k,) = np.flatnonzero(branch["special_label"].values == "SN")
    omega, delta = float(branch["special_omega"][k]), float(branch["special_delta"][k])
    problem = PeriodicBranchProblem(PAPER, 1, "omega")
    np.testing.assert_allclose(problem.fold_residual(delta, omega), 0.0, atol=1e-9)
    c, s, b = problem.amplitude(omega)
    assert math.hypot(c, s) == pytest.approx(b, rel=1e-8)  # c^2 + s^2 = b^2 there (eq. 15)
    J = problem.fold_jacobian(delta, omega)
    fd_delta = _central(lambda d: problem.fold_residual(d, omega), delta, 1e-6)
    fd_lam = _central(lambda w: problem.fold_residual(delta, w), omega, 1e-6)
    np.testing.assert_allclose(J, np.column_stack([fd_delta, fd_lam]), rtol=1e-6, atol=1e-8)


def test_the_gap_leaves_c_and_s_alone() -> None:
    problem = PeriodicBranchProblem(PAPER, 1, "b")
    c0, s0, b0 = problem.amplitude(0.5)
    c1, s1, b1 = problem.amplitude(0.7)
    assert (c0, s0) == (c1, s1) and (b0, b1) == (0.5, 0.7)
    assert problem.oscillator_at(0.7).b == 0.7


def test_the_residual_is_scaled_far_above_the_natural_frequencies() -> None:
    assert residual_scale(3.0, 4.0) == 1.0
    assert residual_scale(300.0, 400.0) == pytest.approx(500.0 / 64)
    assert residual_scale(3.0 + 1e-20j, 4.0) == 1.0
    big = residual_scale(300.0 + 1e-20j, 400.0)
    assert big.real == pytest.approx(500.0 / 64) and big.imag == pytest.approx(
        300.0 * 1e-20 / 500.0 / 64)  # the analytic derivative along the complex step
    c, s, dc, ds, f, df = 300.0, 400.0, 2.0, -1.0, 5.0, 0.5

    def scaled(t: float) -> float:
        return (f + t * df) / residual_scale(c + t * dc, s + t * ds)

    assert scaled_derivative(f, df, c, s, dc, ds) == pytest.approx(
        float(_central(scaled, 0.0, 1e-6)), rel=1e-7)
    assert scaled_derivative(f, df, 3.0, 4.0, dc, ds) == df


def test_root_phase_takes_one_newton_step_onto_eq_14() -> None:
    c, s, b = 0.9, 1.1, 0.5
    root = math.atan2(s, c) + math.acos(b / math.hypot(c, s))
    assert abs(c * math.cos(root) + s * math.sin(root) - b) < 1e-15
    assert root_phase(c, s, b, root + 1e-9) == pytest.approx(root, abs=1e-15)
    assert root_phase(c, s, b, root + 1e-3) == root + 1e-3  # too far: left as it is


def test_a_parameter_outside_its_range_is_refused_by_name() -> None:
    problem = PeriodicBranchProblem(PAPER, 1, "omega")
    with pytest.raises(ParameterError, match=r"omega=-1.0 is outside its allowed range"):
        problem.residual(np.array([0.0]), -1.0)
    with pytest.raises(ParameterError, match="the N-1 branch"):
        PeriodicBranchProblem(PAPER.replace(stops=ic.Stops(mirror=True)), 1, "omega")

"""Robust stability, eq. (26)-(29): the matrix bound and the maximum of |dG| over a box."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import scipy.linalg

from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.flow import Flow
from impactcont.orbit.periodic import impact_map_jacobian, periodic_matrix, periodic_orbits
from impactcont.orbit.robust import (
    RobustStability,
    lyapunov_matrix,
    robust_bound,
    robust_stability,
)

# The paper's worked example (section 4; EQUATIONS.md section 6).
PAPER_G0 = np.array([
    [-0.177445, 0.039713, -0.070643, 0.345996],
    [-0.020169, 0.323905, 0.144022, -0.213799],
    [0.262554, -0.049062, -0.179735, -0.154322],
    [0.090393, 0.292730, 0.161324, 0.112559],
])
PAPER_GAMMA = np.array([
    [0.019349, 0.062658, 0.034531, 0.196054],
    [0.067327, 0.218037, 0.120160, 1.000000],
    [0.099814, 0.323237, 0.178136, 0.854205],
    [0.039599, 0.128237, 0.070672, 0.530487],
])
PAPER_EPS0 = 0.343455

# Our own value of epsilon for the paper's box (regression; the paper prints 0.313974,
# see the module report: the paper's Gamma is not max|dG| over b in [0.2, 1.0]).
OUR_EPSILON = 0.24546166615079387
OUR_EPSILON0 = 0.31917660081540383


@pytest.fixture(scope="module")
def osc() -> ImpactOscillator:
    return ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.6,
                            omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def paper(osc: ImpactOscillator) -> RobustStability:
    return robust_stability(osc, 1, {"b": (0.2, 1.0)})


def fast_G(osc: ImpactOscillator, N: int, root: int, **params: float) -> np.ndarray:
    """G (eq. 25) of the given root of eq. (15), written here independently of robust.py."""
    o = osc.replace(**params)
    flow = Flow(o)
    S, DPhi, T = periodic_matrix(flow, N)
    c, s = S[0]
    r2 = c * c + s * s
    r = math.sqrt(r2 - o.b ** 2)
    delta = math.atan2((o.b * s + root * c * r) / r2, (o.b * c - root * s * r) / r2)
    G, h2 = impact_map_jacobian(flow, S @ [math.cos(delta), math.sin(delta)], delta, T, DPhi)
    assert h2 > 0
    return G


def orbit_G(osc: ImpactOscillator, N: int, root: int, **params: float) -> np.ndarray:
    """G of the given root through the public periodic_orbits, with its physical check."""
    (orbit,) = [o for o in periodic_orbits(osc.replace(**params), N) if o.root == root]
    assert orbit.physical, orbit.reason
    return orbit.G


# -- eq. (27), (29) -------------------------------------------------------------------------------
def test_robust_bound_reproduces_paper_eps0():
    assert robust_bound(PAPER_G0, PAPER_GAMMA) == pytest.approx(PAPER_EPS0, abs=5e-7)


def test_lyapunov_matrix_solves_eq27_and_is_positive_definite():
    P = lyapunov_matrix(PAPER_G0)
    residual = PAPER_G0.T @ P @ PAPER_G0 - P + np.eye(4)
    assert np.max(np.abs(residual)) < 1e-12
    assert np.array_equal(P, P.T)
    assert np.linalg.eigvalsh(P).min() > 0
    # The other transpose solves a different equation: the residual check discriminates.
    wrong = scipy.linalg.solve_discrete_lyapunov(PAPER_G0, np.eye(4))
    assert np.max(np.abs(PAPER_G0.T @ wrong @ PAPER_G0 - wrong + np.eye(4))) > 1e-6


def test_robust_bound_scaling_and_zero_perturbation():
    eps0 = robust_bound(PAPER_G0, PAPER_GAMMA)
    assert robust_bound(PAPER_G0, 2.0 * PAPER_GAMMA) == pytest.approx(eps0 / 2, rel=1e-13)
    assert robust_bound(PAPER_G0, np.zeros((4, 4))) == math.inf


def test_robust_bound_perturbations_below_it_stay_stable():
    eps0 = robust_bound(PAPER_G0, PAPER_GAMMA)
    rng = np.random.default_rng(1)
    for _ in range(200):
        signs = rng.choice([-1.0, 1.0], size=(4, 4))
        dG = 0.999 * eps0 * PAPER_GAMMA * signs
        assert np.abs(np.linalg.eigvals(PAPER_G0 + dG)).max() < 1.0


@pytest.mark.parametrize(("G0", "Gamma", "pattern"), [
    (1.5 * np.eye(2), np.ones((2, 2)), "spectral radius 1.5"),
    (0.5 * np.eye(2), -np.ones((2, 2)), "Gamma must be entrywise >= 0"),
    (0.5 * np.eye(2), np.ones((3, 3)), r"shape \(3, 3\)"),
    (np.ones((2, 3)), np.ones((2, 3)), r"G0 must be a non-empty square matrix; got shape \(2, 3\)"),
    ([[0.5, np.nan], [0, 0.5]], np.ones((2, 2)), "G0 must be finite"),
])
def test_robust_bound_rejects_bad_input(G0, Gamma, pattern):
    with pytest.raises(ParameterError, match=pattern):
        robust_bound(G0, Gamma)


# -- the paper's example: b in [0.2, 1.0] ----------------------------------------------------
def test_paper_nominal_motion(paper: RobustStability):
    assert paper.nominal == {"b": 0.6}
    assert np.max(np.abs(paper.G0 - PAPER_G0)) < 5e-7
    assert paper.orbit.physical and paper.orbit.stable
    assert paper.root == paper.orbit.root == -1
    P = paper.P
    assert np.max(np.abs(paper.G0.T @ P @ paper.G0 - P + np.eye(4))) < 1e-12


def test_paper_gamma_and_epsilon(paper: RobustStability):
    assert paper.Gamma.max() == 1.0
    np.testing.assert_allclose(paper.Gamma * paper.epsilon, paper.theta, rtol=0, atol=1e-15)
    assert paper.epsilon == pytest.approx(OUR_EPSILON, abs=1e-9)
    assert paper.epsilon0 == pytest.approx(OUR_EPSILON0, abs=1e-8)
    assert paper.epsilon0 == pytest.approx(robust_bound(paper.G0, paper.Gamma), rel=1e-14)
    assert paper.robust
    assert paper.refinement_gain >= 0 and np.all(paper.refinement >= 0)


def test_paper_theta_is_an_upper_bound_at_random_b(osc, paper: RobustStability):
    rng = np.random.default_rng(2024)
    for b in rng.uniform(0.2, 1.0, 200):
        dG = np.abs(orbit_G(osc, 1, paper.root, b=float(b)) - paper.G0)
        assert np.all(dG <= paper.theta + 1e-10), (b, (dG - paper.theta).max())


def test_paper_theta_matches_dense_scan_and_argmax(osc, paper: RobustStability):
    bs = np.linspace(0.2, 1.0, 2001)
    dense = np.max([np.abs(fast_G(osc, 1, paper.root, b=float(b)) - paper.G0) for b in bs],
                   axis=0)
    assert np.all(paper.theta >= dense - 1e-12)
    assert np.all(paper.theta - dense <= 1e-6)
    assert paper.epsilon == pytest.approx(dense.max(), abs=1e-6)
    for (i, j), where in paper.argmax.items():
        G = orbit_G(osc, 1, paper.root, **where)
        assert abs(G[i, j] - paper.G0[i, j]) == pytest.approx(paper.theta[i, j], abs=1e-14)


def test_repr_and_summary(paper: RobustStability):
    text = paper.summary()
    assert "epsilon0 = 0.319177" in text and "robust: True" in text
    assert "epsilon=0.245462" in repr(paper)


# -- the refinement ------------------------------------------------------------------------------
def test_refinement_finds_an_interior_maximum(osc):
    # dG[0, 3](b) peaks inside the box, near b = 1.08, between the grid points of samples=5.
    res = robust_stability(osc, 1, {"b": (0.5, 1.25)}, nominal={"b": 0.6}, samples=5)
    assert res.refinement[0, 3] > 1e-5
    assert res.theta[0, 3] == res.grid_theta[0, 3] + res.refinement[0, 3]
    bs = np.linspace(0.5, 1.25, 751)
    scan = np.array([abs(fast_G(osc, 1, res.root, b=float(b))[0, 3] - res.G0[0, 3])
                     for b in bs])
    assert res.theta[0, 3] >= scan.max() - 1e-12
    assert res.theta[0, 3] - scan.max() < 1e-5
    assert res.argmax[(0, 3)]["b"] == pytest.approx(bs[scan.argmax()], abs=2e-3)
    assert 0.5 < res.argmax[(0, 3)]["b"] < 1.25


def test_two_parameter_box(osc):
    vary = {"b": (0.5, 1.25), "omega": (0.99, 1.01)}
    res = robust_stability(osc, 1, vary, nominal={"b": 0.6, "omega": 1.0}, samples=5)
    assert res.nominal == {"b": 0.6, "omega": 1.0}
    assert res.vary == vary
    assert res.Gamma.max() == 1.0
    assert all(set(w) == {"b", "omega"} for w in res.argmax.values())
    # The grid misses the peak of dG[0, 3]; the refinement must find it.
    assert res.refinement[0, 3] > 1e-5
    bs = np.linspace(0.9, 1.1, 41)
    ws = np.linspace(0.99, 1.01, 5)
    scan = max(abs(fast_G(osc, 1, res.root, b=float(b), omega=float(w))[0, 3] - res.G0[0, 3])
               for b in bs for w in ws)
    assert res.theta[0, 3] >= scan - 1e-12
    rng = np.random.default_rng(7)
    for b, w in zip(rng.uniform(0.5, 1.25, 30), rng.uniform(0.99, 1.01, 30), strict=True):
        dG = np.abs(orbit_G(osc, 1, res.root, b=float(b), omega=float(w)) - res.G0)
        assert np.all(dG <= res.theta + 1e-10)


def test_small_box_in_b_and_omega_is_robust(osc):
    res = robust_stability(osc, 1, {"b": (0.55, 0.65), "omega": (0.98, 1.02)}, samples=3)
    assert res.robust and res.epsilon < res.epsilon0
    assert res.theta.max() == res.epsilon > 0


def test_vary_forcing_entry(osc):
    res = robust_stability(osc, 1, {"F[1]": (0.95, 1.05)}, samples=3)  # mass 1, 1-based
    assert res.nominal == {"F[1]": 1.0}
    assert res.epsilon > 0
    G = orbit_G(osc, 1, res.root, F=[1.05, 0.0])
    assert np.all(np.abs(G - res.G0) <= res.theta + 1e-12)


def test_vary_elements_against_the_corners_recomputed(osc):
    """A spring and the forcing of mass 2 (1-based elements, the parameter objects'
    names): with two samples the grid is the box's four corners, so ``grid_theta`` is
    the largest ``|G - G0|`` over oscillators built here by hand at the corners
    (``k2`` the spring from mass 2 to the ground: ``K[2,2] = k1 + k2``)."""
    res = robust_stability(osc, 1, {"k2": (0.9, 1.1), "F[2]": (-0.1, 0.1)}, samples=2)
    assert res.nominal == {"k2": 1.0, "F[2]": 0.0}

    def by_hand(k2: float, f2: float) -> ImpactOscillator:
        return ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 1.0 + k2]], F=[1.0, f2],
                                R=0.6, b=0.6, omega=1.0, eta=0.1)

    np.testing.assert_allclose(res.G0, orbit_G(by_hand(1.0, 0.0), 1, res.root),
                               rtol=1e-10, atol=1e-12)
    corners = [np.abs(orbit_G(by_hand(k2, f2), 1, res.root) - res.G0)
               for k2 in (0.9, 1.1) for f2 in (-0.1, 0.1)]
    np.testing.assert_allclose(res.grid_theta, np.max(corners, axis=0), rtol=1e-9, atol=1e-12)
    assert np.all(res.theta >= res.grid_theta) and res.epsilon == res.theta.max() > 0
    for q in res.argmax.values():  # the refined maxima lie in the box, at values of G
        assert 0.9 <= q["k2"] <= 1.1 and -0.1 <= q["F[2]"] <= 0.1


def test_two_sided_system_is_refused(osc):
    from impactcont.model.stops import Stops

    two = osc.replace(stops=Stops(b_low=0.6))
    with pytest.raises(ParameterError, match="robust_stability: the closed form"):
        robust_stability(two, 1, {"b": (0.5, 0.7)})


# -- where the motion does not exist or is not physical ------------------------------------------
def test_box_where_motion_ceases_to_exist_raises(osc):
    # c^2 + s^2 = 1.74355, so no motion for b > 1.3204.
    with pytest.raises(NoPeriodicMotionError, match=r"does not exist .* at b=1\.3"):
        robust_stability(osc, 1, {"b": (0.6, 1.5)}, nominal={"b": 0.6})


def test_unphysical_root_at_nominal_raises(osc):
    with pytest.raises(NoPeriodicMotionError, match=r"root \+1 .* not a physical motion"):
        robust_stability(osc, 1, {"b": (0.2, 1.0)}, root=+1)


# -- bad arguments ---------------------------------------------------------------------------------
@pytest.mark.parametrize(("vary", "pattern"), [
    ({"gap": (0.2, 1.0)}, "'gap' moves a lower stop; robust_stability follows an N-1 motion"),
    ({"b_low": (0.2, 1.0)}, "'b_low' moves a lower stop"),
    ({"x1": (0.2, 1.0)}, r"'x1' is not a parameter robust_stability can vary; allowed: one of "
                         r"\['omega', 'b', 'R', 'eta', 'F0'\] or an element"),
    ({"F[0]": (0.9, 1.1)}, re.escape("(F[j] is 1-based: 'F[1]' is the forcing of mass 1)")),
    ({"c1": (0.0, 0.1)}, "'c1' is an element of a damping matrix C"),
    ({"k2": (-0.5, 1.0)}, re.escape("k2 must be finite and > 0; got -0.5")),
    ({"F0": (0.9, 1.1), "F[2]": (-0.1, 0.1)}, "'F0' and 'F\\[2\\]' both set F"),
    ({"k1": (0.9, 1.1), "K[1,2]": (-1.1, -0.9)}, "'k1' and 'K\\[1,2\\]' both set K"),
    ({"M[1,2]": (0.0, 0.1), "M[2,1]": (0.0, 0.1)}, "both set M \\(the same entry\\)"),
    ({"b": (1.0, 0.2)}, re.escape("lo < hi; got (1.0, 0.2)")),
    ({"b": (0.6, 0.6)}, re.escape("lo < hi; got (0.6, 0.6)")),
    ({"b": (0.2, float("nan"))}, "upper end must be a finite real number; got nan"),
    ({"b": (-float("inf"), 1.0)}, "lower end must be a finite real number; got -inf"),
    ({"b": (0.2,)}, re.escape("must be an interval (lo, hi); got (0.2,)")),
    ({"F[3]": (0.9, 1.1)}, re.escape("'F[3]' names an element past the oscillator's n=2")),
    ({"alpha": (0.0, 0.1)}, "use 'eta' instead"),
    ({"R": (0.5, 1.2)}, "R must be in \\[0, 1\\]; got 1.2"),
    ({"omega": (-1.0, 1.0)}, "omega must be finite and > 0; got -1.0"),
    ({}, "non-empty"),
])
def test_bad_vary_raises_with_the_value(osc, vary, pattern):
    with pytest.raises(ParameterError, match=pattern):
        robust_stability(osc, 1, vary)


@pytest.mark.parametrize(("kwargs", "pattern"), [
    ({"nominal": {"b": 1.5}}, re.escape("nominal['b'] must lie in the box [0.2, 1.0]; got 1.5")),
    ({"nominal": {"omega": 1.0}}, "not in vary: \\['omega'\\]"),
    ({"root": 2}, "root must be None, \\+1 or -1.*got 2"),
    ({"samples": 1}, "samples must be an integer >= 2.*got 1"),
])
def test_bad_options_raise(osc, kwargs, pattern):
    with pytest.raises(ParameterError, match=pattern):
        robust_stability(osc, 1, {"b": (0.2, 1.0)}, **kwargs)

"""The compiled kernel against the dense implementation of eq. (12)-(16), (25).

The dense path (``periodic_matrix``: ``I - D U W(T) U^-1`` solved by equilibrated LU;
``impact_map_jacobian`` from the physical transition matrix; the interior maxima
of ``x1`` by :mod:`impactcont.orbit.extrema` along :class:`Flow`) is independent
of the kernel's modal form (Sherman-Morrison scalars, per-frequency time grid,
pruned maximum search). Random oscillators, every damping class, n = 1..12.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import closed_form
from impactcont.orbit import periodic
from impactcont.orbit.extrema import interior_maxima, sample_times
from impactcont.orbit.periodic import impact_map_jacobian, periodic_matrix
from impactcont.problems import PeriodicBranchProblem

EPS = float(np.finfo(float).eps)


DAMPING = {
    "undamped": {},
    "paper": {"eta": 0.05},
    "rayleigh": {"alpha": 0.2, "beta": 0.03},
    "mass-proportional over-damped": {"alpha": 6.0, "beta": 0.0},
    "heavy": {"eta": 3.0},
}


def _random_oscillator(rng: np.random.Generator, n: int, damping: dict) -> ic.ImpactOscillator:
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    M = np.diag(0.5 + rng.random(n))
    F = rng.standard_normal(n)
    return ic.ImpactOscillator(M=M, K=K, F=F, R=float(rng.uniform(0.1, 0.95)),
                               b=float(rng.uniform(-0.2, 0.2)),
                               omega=float(rng.uniform(0.4, 3.0)), **damping)


def _dense(osc: ic.ImpactOscillator, N: int, delta: float):
    flow = ic.Flow(osc)
    S, DPhi, T = periodic_matrix(flow, N)
    state = S @ np.array([math.cos(delta), math.sin(delta)])
    G, h2 = impact_map_jacobian(flow, state, delta, T, DPhi)
    times, peaks = interior_maxima(flow.mass1(state, delta), sample_times(flow, 0.0, T))
    keep = (times > 1e-12 * T) & (times < (1 - 1e-12) * T)
    gap = osc.b - peaks[keep].max() if keep.any() else math.inf
    return S[0], state, G, h2, gap


@pytest.mark.parametrize("damping", list(DAMPING))
@pytest.mark.parametrize("n", [1, 2, 3, 5, 8, 12])
def test_kernel_matches_the_dense_path(n, damping):
    rng = np.random.default_rng(1000 * n + len(damping))
    checked = 0
    for trial in range(6):
        osc = _random_oscillator(rng, n, DAMPING[damping])
        N = 1 + trial % 3
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                # a gap inside the range of the motion, so that both roots exist
                r = math.sqrt(ic.amplitude_squared(osc, N))
                osc = osc.replace(b=float(rng.uniform(-0.9, 0.9)) * r)
                orbits = ic.periodic_orbits(osc, N)
                cs, *_ = _dense(osc, N, 0.0)
            except ic.ParameterError:
                continue
        arrays = periodic.modal_arrays(osc)
        w, a, f, err, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.eig_err, arrays.u0, arrays.ui0
        _, sc = closed_form.omega_setup(w, a, f, u0, ui0, err, osc.R, osc.omega, N)
        if not sc[7] < 1e8:
            continue  # near a free-mode resonance both paths are inexact (and warn)
        scale = np.abs(cs).max()
        # both paths are exact to their condition estimate sc[7] (up to 1e8 admitted here):
        # 1e-12 plus 10 cond eps (undamped n = 8, 12 reach cond eps ~ 2e-12)
        tol = 1e-12 + 10 * EPS * float(sc[7])
        assert abs(sc[5] - cs[0]) <= tol * scale and abs(sc[6] - cs[1]) <= tol * scale
        for orbit in orbits:
            _, state, G, h2, gap = _dense(osc, N, orbit.delta)
            assert np.abs(orbit.state - state).max() <= tol * np.abs(state).max()
            assert abs(orbit.impact_velocity - h2) <= tol * np.abs(state).max() * max(
                1.0, osc.omega)
            if abs(h2) > 1e-3 * np.abs(state).max():
                assert np.abs(orbit.G - G).max() <= tol * max(1.0, np.abs(G).max()) / min(
                    1.0, abs(h2) / np.abs(state).max())
                mu = np.linalg.eigvals(G)
                assert orbit.stable == (np.abs(mu).max() < 1.0) or abs(
                    np.abs(mu).max() - 1.0) < 1e-9
            if math.isinf(gap):
                assert math.isinf(orbit.gap_min)
            else:
                assert abs(orbit.gap_min - gap) <= tol * max(1.0, np.abs(state[:n]).max())
            checked += 1
    assert checked > 0


@pytest.mark.parametrize("parameter", ["omega", "R", "eta"])
def test_exact_derivative_matches_finite_differences(paper, parameter):
    problem = PeriodicBranchProblem(paper, 1, parameter)
    lam = float(getattr(paper, parameter))
    exact = problem._amplitude_derivative(lam)
    h = 1e-6
    up, down = problem.amplitude(lam + h), problem.amplitude(lam - h)
    for k in range(2):
        assert exact[k] == pytest.approx((up[k] - down[k]) / (2 * h), rel=1e-7, abs=1e-9)


@pytest.mark.parametrize("omega", [0.3, 1.2, 2.5, 40.0])
@pytest.mark.parametrize("damping", list(DAMPING))
@pytest.mark.parametrize("n", [1, 3, 8])
def test_exact_slope_matches_the_complex_step(n, damping, omega):
    """``setup_slope`` (the chain rule in real arithmetic) against the complex step of
    ``amplitude_derivative``, in omega and R, every damping class (elastic impacts too),
    up to 40 times the forcing frequencies of the paper: both are exact, the difference
    is the rounding of ``c, s`` and of their derivative, whose terms grow like
    ``|c, s| / omega``."""
    rng = np.random.default_rng(n)
    for R in (0.7, 1.0):
        osc = _random_oscillator(rng, n, DAMPING[damping]).replace(omega=omega, R=R)
        ar = periodic.modal_arrays(osc)
        args = (ar.w, ar.a, ar.f, ar.u0, ar.ui0, osc.R, osc.omega, 1)
        c, s = closed_form.amplitude(*args)
        for which in (0, 1):
            exact = closed_form.setup_slope(*args, which)[1][5:7]
            stepped = np.array(closed_form.amplitude_derivative(*args, which, np.zeros(n)))
            scale = np.abs(stepped).max() + (abs(c) + abs(s)) / (omega if which == 0 else 1.0)
            assert np.abs(exact - stepped).max() <= 1e-11 * scale


@pytest.mark.parametrize("n", [33, 60])
def test_large_system_jacobian_by_matrix_products_matches_the_dense_path(n):
    """Above 32 degrees of freedom G's transition blocks come from BLAS products."""
    F = np.zeros(n)
    F[0] = 1.0
    osc = ic.ImpactOscillator.chain(masses=np.linspace(1.0, 2.0, n), springs=np.ones(n), F=F,
                                    R=0.7, b=0.1, omega=1.1, eta=0.05)
    orbits = ic.periodic_orbits(osc, 1)
    assert orbits
    for orbit in orbits:
        G = _dense(osc, 1, orbit.delta)[2]
        assert np.abs(orbit.G - G).max() <= 1e-10 * max(1.0, np.abs(G).max())


def test_the_kernel_entry_points_take_the_modal_arrays(paper):
    arrays = periodic.modal_arrays(paper)
    out = closed_form.point_orbits(arrays.as_tuple(), paper.R, paper.omega, 1, paper.b)
    modal, sc = closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                        arrays.eig_err, paper.R, paper.omega, 1)
    np.testing.assert_array_equal(out[0], modal)
    np.testing.assert_array_equal(out[1], sc)
    delta = out[3][0]
    phase = closed_form.phase_orbit(arrays.as_tuple(), paper.R, paper.omega, 1, paper.b, delta)
    assert phase[2] == out[4][0]  # the same impact velocity from the phase
    block = closed_form.block_map(arrays.as_tuple(), paper.R, 1, np.array([paper.omega]),
                                  np.array([paper.b]), False)
    assert block[3][0, 0, 0] == delta

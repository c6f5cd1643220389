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
from impactcont.kernel import closed_form, contact, roots, stability
from impactcont.kernel.arrays import ModalArrays, modal_arrays
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


def test_schur_cohn_agrees_with_eigenvalues():
    rng = np.random.default_rng(3)
    for m in (1, 2, 4, 7, 10):
        for _ in range(200):
            A = rng.standard_normal((m, m)) * rng.uniform(0.1, 0.6)
            rho = np.abs(np.linalg.eigvals(A)).max()
            if abs(rho - 1.0) < 1e-6:
                continue
            assert stability.schur_stable(stability.charpoly(A)) == (rho < 1.0), (m, rho)


def test_characteristic_polynomial_matches_numpy():
    rng = np.random.default_rng(4)
    for m in (1, 3, 6, 9):
        A = rng.standard_normal((m, m))
        np.testing.assert_allclose(stability.charpoly(A)[::-1], np.poly(A), rtol=1e-9, atol=1e-9)


def test_lapack_eigenvalues_come_in_exact_conjugate_pairs():
    A = np.random.default_rng(5).standard_normal((8, 8))
    mu = stability.eigvals(A)
    np.testing.assert_allclose(np.sort_complex(mu), np.sort_complex(np.linalg.eigvals(A)),
                               atol=1e-12)
    complex_ones = mu[mu.imag != 0]
    assert set(complex_ones.conj().tolist()) == set(complex_ones.tolist())


@pytest.mark.parametrize("parameter", ["omega", "R", "eta"])
def test_complex_step_derivative_matches_finite_differences(paper, parameter):
    problem = PeriodicBranchProblem(paper, 1, parameter)
    lam = float(getattr(paper, parameter))
    exact = problem._amplitude_derivative(lam)
    h = 1e-6
    up, down = problem.amplitude(lam + h), problem.amplitude(lam - h)
    for k in range(2):
        assert exact[k] == pytest.approx((up[k] - down[k]) / (2 * h), rel=1e-7, abs=1e-9)


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


@pytest.mark.parametrize("omega, b, N",
                         [(0.8, 0.3, 2), (0.6, 0.5, 2), (1.25, 0.3, 1), (0.45, 0.2, 3)])
def test_polish_roots_and_taylor_values_are_exact(omega, b, N):
    """Every root the interior-contact search polishes (of x1' for maxima, of x1'' for the
    cells it splits) agrees with bisection to rounding, and the values it returns from
    its last Taylor step agree with a direct evaluation at the root."""
    from scipy.optimize import brentq

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=b, omega=omega, eta=0.1)
    arrays = periodic.modal_arrays(osc)
    w, a, f, eig_err, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.eig_err, arrays.u0, arrays.ui0
    modal, sc = closed_form.omega_setup(w, a, f, u0, ui0, eig_err, osc.R, omega, N)
    count, dl, sg, _, _ = roots.orbit_roots(sc, b, omega, osc.R)
    assert count > 0
    times, _, _, _, _, dy, dv, _ = contact.flight_tables(w, a, u0, modal, omega, sc[0])
    checked = 0
    for k in range(count):
        ks = (1.0 + osc.R) * sg[k]
        args = (sc[1], sc[2], omega, dl[k], ks, w, a, u0, dy, dv)

        def d(t, args=args):
            return contact.x1_derivatives(t, *args)

        for order in (1, 2):
            g = np.array([d(t)[order] for t in times])
            for j in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0):
                lo, hi = times[j], times[j + 1]
                e_lo, e_hi = d(lo), d(hi)
                snap = [contact._x1_derivs(t, *args)[4] for t in (lo, hi)]
                ddg = (e_lo[3], e_hi[3]) if order == 1 else tuple(snap)
                r, x, v, acc, jerk = contact._polish(
                    np.int64(order), lo, hi, e_lo[order], e_hi[order], e_lo[order + 1],
                    e_hi[order + 1], ddg[0], ddg[1], *args)
                ref = brentq(lambda t, o=order: d(t)[o], lo, hi, xtol=1e-15, rtol=1e-15)
                assert abs(r - ref) <= 1e-13 * max(1.0, ref)
                direct = d(r)
                # the difference is rounding of sums of modal terms (up to 0.77 of 1e-13 here,
                # above it for 7.5 % of omegas within 100 ulp): 1e-12 of the bracket's scale
                scale = np.max(np.abs(np.array([d(t) for t in (lo, hi)])), axis=0)
                assert np.all(np.abs(np.array([x, v, acc, jerk]) - direct) <= 1e-12 * scale)
                checked += 1
    assert checked >= 4


# -- the typed modal arrays (impactcont.kernel.arrays) -----------------------------------------
def _three_masses(**stops) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.diag([1.0, 2.0, 1.5]),
                               K=[[3.0, -1.0, 0.0], [-1.0, 2.5, -1.2], [0.0, -1.2, 1.7]],
                               F=[1.0, 0.3, 0.0], R=0.7, b=0.4, omega=1.1, eta=0.04,
                               **({"stops": ic.Stops(**stops)} if stops else {}))


def test_modal_arrays_take_the_impacting_mass_from_the_model():
    # u0, ui0 are x_j = u_j. y and y = u^-1 x, checked from M and the modes themselves
    for mass in (1, 2, 3):
        osc = _three_masses(mass=mass)
        arrays = periodic.modal_arrays(osc)
        u = osc.modes.u
        x = np.array([0.3, -1.1, 0.7])
        y = np.linalg.solve(u, x)
        assert math.isclose(arrays.u0 @ y, x[mass - 1], rel_tol=1e-12)
        e = np.zeros(3)
        e[mass - 1] = 1.0
        np.testing.assert_allclose(arrays.ui0, np.linalg.solve(u, e), rtol=1e-12, atol=1e-14)
        for field in arrays:
            assert field.dtype == np.float64 and field.flags.c_contiguous
    assert periodic.modal_arrays(osc) is periodic.modal_arrays(osc)  # built once per basis


def test_modal_arrays_are_the_one_form_of_the_modal_basis(paper):
    """The named fields are the basis's arrays (the positional tuple of the basis is gone);
    ``as_tuple`` keeps the order the compiled entry points unpack."""
    arrays = periodic.modal_arrays(paper)
    basis = paper.modes
    assert isinstance(arrays, ModalArrays) and not hasattr(basis, "kernel_arrays")
    for name, source in (("w", basis.natural_frequencies), ("a", basis.decay_rates),
                         ("f", basis.modal_forces), ("u", basis.u), ("ui", basis.u_inv),
                         ("eig_err", basis.eigenvalue_errors), ("u0", basis.u[0]),
                         ("ui0", basis.u_inv[:, 0])):
        np.testing.assert_array_equal(getattr(arrays, name), source)
    order = ("w", "a", "f", "u", "ui", "eig_err", "u0", "ui0")
    assert all(x is getattr(arrays, k) for x, k in zip(arrays.as_tuple(), order, strict=True))


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


@pytest.mark.parametrize(("change", "error", "pattern"), [
    ({"w": [1.0, 2.0]}, TypeError, r"w must be a one-dimensional numpy array"),
    ({"w": np.ones((2, 1))}, ValueError, r"w must be a one-dimensional numpy array"),
    ({"a": np.ones(2, dtype=complex)}, TypeError, r"a must hold real numbers .* complex128"),
    ({"f": np.array([True, False])}, TypeError, r"f must hold real numbers .* bool"),
    ({"u": np.eye(3)}, ValueError, r"u must have shape \(2, 2\) .* got shape \(3, 3\)"),
    ({"ui": np.ones(2)}, ValueError, r"ui must have shape \(2, 2\)"),
    ({"eig_err": np.zeros(3)}, ValueError, r"eig_err must have shape \(2,\)"),
    ({"u": [[1.0, 0.0], [0.0, 1.0]]}, TypeError, r"u must be a numpy array .* list"),
    ({"mass": 2}, ValueError, r"mass must be in 0\.\.1 .* got 2"),
    ({"mass": -1}, ValueError, r"mass must be in 0\.\.1"),
    ({"mass": True}, TypeError, r"mass must be an integer"),
    ({"mass": 0.0}, TypeError, r"mass must be an integer"),
])
def test_modal_arrays_refuse_wrong_shapes_and_dtypes(change, error, pattern):
    args = {"w": np.array([1.0, 2.0]), "a": np.zeros(2), "f": np.ones(2), "u": np.eye(2),
            "ui": np.eye(2), "eig_err": np.zeros(2), "mass": 0}
    args.update(change)
    with pytest.raises(error, match=pattern):
        modal_arrays(**args)


def test_modal_arrays_convert_real_input_to_contiguous_float():
    u = np.asfortranarray(np.array([[1, 2], [3, 4]]))  # integers, column-major
    arrays = modal_arrays(np.array([1, 2]), np.zeros(2), np.ones(2), u, np.eye(2), mass=1)
    assert all(x.dtype == np.float64 and x.flags.c_contiguous for x in arrays)
    np.testing.assert_array_equal(arrays.u0, [3.0, 4.0])
    np.testing.assert_array_equal(arrays.eig_err, [0.0, 0.0])


def test_first_order_arrays_name_the_basis_fields():
    """The first-order basis of a damping matrix, read by name: each field is the basis's
    array (the contact search's copies included), and a length other than the basis's
    tuple is refused."""
    from impactcont.kernel.arrays import FirstOrderArrays

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              C=[[0.3, 0.0], [0.0, 0.0]], b=0.6, omega=1.0)
    basis = osc.first_order
    fa = FirstOrderArrays._make(basis.kernel_arrays)
    assert FirstOrderArrays._make(fa) == fa
    np.testing.assert_array_equal(fa.lam, basis.eigenvalues)
    np.testing.assert_array_equal(fa.V_inv, basis.V_inv)
    np.testing.assert_array_equal(fa.impact_column, basis.impact_column)
    np.testing.assert_array_equal(fa.C, osc.C)
    w, a, k, j = basis.scalar_pairs
    for got, want in ((fa.w_p, w), (fa.a_p, a), (fa.k_p, k), (fa.j_p, j)):
        np.testing.assert_array_equal(got, want)
    lam, v0, *pairs = fa.contact_arguments()
    np.testing.assert_array_equal(lam, basis.eigenvalues)
    np.testing.assert_array_equal(v0, basis.V[0])
    for got, want in zip(pairs, (w, a, k, j), strict=True):
        np.testing.assert_array_equal(got, want)
    with pytest.raises(TypeError):
        FirstOrderArrays._make(basis.kernel_arrays[:12])

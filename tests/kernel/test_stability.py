"""The kernel's multiplier tests (:mod:`impactcont.kernel.stability`): the Schur-Cohn test
and the characteristic polynomial against numpy's eigenvalues, and LAPACK's eigenvalues in
exact conjugate pairs."""

from __future__ import annotations

import numpy as np

from impactcont.kernel import stability


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

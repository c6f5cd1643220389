"""The kernel's small dense linear algebra (:mod:`impactcont.kernel.linalg`): one pivoted
elimination for real and complex systems, numpy's complex division and the small
product, against numpy (the functions are compiled-only: called here through njit)."""

from __future__ import annotations

import numba as nb
import numpy as np
import pytest

from impactcont.kernel import linalg


@nb.njit(cache=False)
def _solve(M, x):
    return linalg._solve_in_place(M, x)


@nb.njit(cache=False)
def _divide(a, b):
    return linalg._cdiv(a, b)


@nb.njit(cache=False)
def _product(A, B, out):
    linalg._product_into(A, B, out)


@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
@pytest.mark.parametrize("size", [1, 2, 5, 12])
def test_the_solve_is_numpys_within_rounding(dtype, size):
    rng = np.random.default_rng(size)
    A = rng.standard_normal((size, size)) + np.eye(size)
    b = rng.standard_normal(size)
    if dtype is np.complex128:
        A = A + 1j * rng.standard_normal((size, size))
        b = b + 1j * rng.standard_normal(size)
    M, x = A.astype(dtype), b.astype(dtype)
    assert _solve(M, x)
    expected = np.linalg.solve(A, b)
    bound = 64 * np.finfo(float).eps * np.linalg.cond(A) * np.abs(expected).max()
    assert np.abs(x - expected).max() <= bound
    assert np.abs(A @ x - b).max() <= 64 * np.finfo(float).eps * np.abs(A).max() * (
        np.abs(x).max() * size + 1)


@pytest.mark.parametrize("dtype", [np.float64, np.complex128])
def test_a_zero_pivot_is_reported_not_divided(dtype):
    A = np.array([[1.0, 2.0], [2.0, 4.0]], dtype=dtype)  # rank 1: the second pivot is 0
    assert not _solve(A.copy(), np.ones(2, dtype=dtype))
    assert not _solve(np.zeros((3, 3), dtype=dtype), np.ones(3, dtype=dtype))


def test_the_pivot_is_the_largest_entry_of_its_column():
    # without pivoting the first step divides by 1e-20 and loses the answer
    A = np.array([[1e-20, 1.0], [1.0, 1.0]])
    x = np.array([1.0, 2.0])
    assert _solve(A.copy(), x)
    np.testing.assert_allclose(x, np.linalg.solve(A, [1.0, 2.0]), rtol=1e-15)


def test_the_complex_division_is_numpys():
    rng = np.random.default_rng(3)
    a = rng.standard_normal(200) + 1j * rng.standard_normal(200)
    b = rng.standard_normal(200) * 10.0 ** rng.integers(-150, 150, 200) \
        + 1j * rng.standard_normal(200) * 10.0 ** rng.integers(-150, 150, 200)
    ours = np.array([_divide(p, q) for p, q in zip(a, b, strict=True)])
    np.testing.assert_allclose(ours, a / b, rtol=4 * np.finfo(float).eps, atol=0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        by_zero = (1.0 + 1.0j) / np.complex128(0.0)
    ours = _divide(1.0 + 1.0j, 0.0j)  # inf/NaN as numpy gives, no exception
    assert np.isnan(ours.real) == np.isnan(by_zero.real)
    assert np.isinf(ours.real) == np.isinf(by_zero.real)


def test_the_product_is_numpys_within_rounding():
    rng = np.random.default_rng(4)
    A, B = rng.standard_normal((3, 5)), rng.standard_normal((5, 4))
    out = np.empty((3, 4))
    _product(A, B, out)
    np.testing.assert_allclose(out, A @ B, rtol=0.0, atol=16 * np.finfo(float).eps * 5)

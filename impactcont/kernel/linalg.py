"""Small dense linear algebra of the kernel: products and solves of a few unknowns.

The kernel's systems are small (a shooting system of 2np unknowns, G of size 2n, the
bordered system of the N-1 closed form, a dynamic stiffness of n masses): Gaussian
elimination with partial pivoting written out is faster than a LAPACK call through
numba and adds nothing to the first compilation (numba's ``np.linalg.solve`` would add
seconds). One elimination serves real and complex systems: the pivot is the entry of
largest ``|Re| + |Im|`` (LAPACK's choice in ``zgesv``; ``|x|`` for a real x) and a complex
division is numpy's (:func:`_cdiv`: Smith's algorithm, inf/NaN for a zero divisor
instead of numba's exception).
"""

from __future__ import annotations

import numba as nb
from numba.extending import overload

from impactcont.kernel.jit import inner as _inner

__all__: list[str] = []


@_inner
def _cdiv(a, b):
    """``a / b`` by numpy's algorithm (Smith's), inf/NaN for ``b = 0`` instead of raising."""
    ar, ai, br, bi = a.real, a.imag, b.real, b.imag
    abs_r, abs_i = abs(br), abs(bi)
    if abs_r >= abs_i:
        if abs_r == 0.0 and abs_i == 0.0:
            return complex(ar / abs_r, ai / abs_r)
        rat = bi / br
        scl = 1.0 / (br + bi * rat)
        return complex((ar + ai * rat) * scl, (ai - ar * rat) * scl)
    rat = br / bi
    scl = 1.0 / (bi + br * rat)
    return complex((ar * rat + ai) * scl, (ai * rat - ar) * scl)


def _divide(a, b):  # pragma: no cover - replaced by the overload inside compiled code
    return a / b


@overload(_divide)
def _divide_overload(a, b):
    """``a / b``: :func:`_cdiv` when either is complex, else the float division."""
    if isinstance(a, nb.types.Complex) or isinstance(b, nb.types.Complex):
        def complex_impl(a, b):
            return _cdiv(a, b)
        return complex_impl

    def real_impl(a, b):
        return a / b
    return real_impl


@_inner
def _pivot_size(z):
    """``|Re z| + |Im z|``, the size a pivot is chosen by (``|z|`` for a real z)."""
    return abs(z.real) + abs(z.imag)


@_inner
def _solve_in_place(M, x):
    """Solve ``M y = x`` by Gaussian elimination with partial pivoting, overwriting ``M``
    (its elimination) and ``x`` (the right-hand side on entry, ``y`` on return); False
    when a pivot is exactly zero (a singular matrix, as LAPACK's ``getrf`` reports it:
    ``x`` is then not the solution). Real or complex (:func:`_pivot_size`,
    :func:`_divide`)."""
    size = x.size
    for c in range(size):
        piv = c
        big = _pivot_size(M[c, c])
        for r in range(c + 1, size):
            if _pivot_size(M[r, c]) > big:
                big = _pivot_size(M[r, c])
                piv = r
        if big == 0.0:
            return False
        if piv != c:
            for k in range(size):
                M[c, k], M[piv, k] = M[piv, k], M[c, k]
            x[c], x[piv] = x[piv], x[c]
        for r in range(c + 1, size):
            factor = _divide(M[r, c], M[c, c])
            if factor != 0.0:
                for k in range(c + 1, size):
                    M[r, k] -= factor * M[c, k]
                x[r] -= factor * x[c]
    for c in range(size - 1, -1, -1):
        s = x[c]
        for k in range(c + 1, size):
            s -= M[c, k] * x[k]
        x[c] = _divide(s, M[c, c])
    return True


@_inner
def _product_into(A, B, out):
    """``out = A B`` (each entry summed over the inner index in order, from 0)."""
    for r in range(A.shape[0]):
        for c in range(B.shape[1]):
            s = 0.0
            for i in range(A.shape[1]):
                s += A[r, i] * B[i, c]
            out[r, c] = s

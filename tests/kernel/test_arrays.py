"""The kernel's input arrays (:mod:`impactcont.kernel.arrays`): the one modal form of the
modal basis (the impacting mass taken from the model), what the kernel entry points take,
shapes and dtypes refused or converted, and the first-order basis' field names."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel.arrays import ModalArrays, modal_arrays
from impactcont.orbit import periodic


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

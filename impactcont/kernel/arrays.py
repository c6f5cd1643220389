"""The modal arrays the kernel's entry points take, as one typed structure.

The modal form of eq. (5)-(7): mass-normalised modes ``u`` (``u^T M u = I``), their
inverse ``u^-1 = u^T M``, the natural frequencies ``omega_i``, the decay rates ``a_i``
of proportional damping (eq. 6), the modal forces ``u^T F`` and the rounding scale of
``omega_i^2``; with them the row of ``u`` and the column of ``u^-1`` of the impacting
mass, which is all of the modes the impact law of eq. (4) sees (``q = [0; u_j.]``,
``p = [0; (u^-1)_.j]`` of the rank-one impact map). :class:`ModalArrays` is a
:class:`typing.NamedTuple`, so numba passes it to compiled code as one argument (its
fields typed once: C-contiguous float64 arrays) and Python unpacks it by name. A compiled
call takes its fields as a plain tuple (:meth:`ModalArrays.as_tuple`): numba types an exact
tuple in its C dispatcher, a named one through its Python ``typeof`` (about 1 us more per
call, a tenth of the kernel call of an N-1 orbit of two masses; ``docs/kernel.md``).

:func:`modal_arrays` is the one place it is built and checked; this module imports
neither numba nor anything of impactcont's.

:class:`FirstOrderArrays` names the fields of the first-order basis of any damping
matrix C (:attr:`impactcont.model.first_order.FirstOrderBasis.kernel_arrays`), the
inputs of :mod:`impactcont.kernel.general`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["FirstOrderArrays", "ModalArrays", "modal_arrays"]


class ModalArrays(NamedTuple):
    """The modal arrays of one oscillator, as the compiled kernel takes them.

    Every field is a C-contiguous float64 array (:func:`modal_arrays` checks it). The
    order is that of the positional tuple it replaces, so ``w, a, f, u, ui, eig_err,
    u0, ui0 = arrays`` still reads it.
    """

    w: np.ndarray
    """Natural frequencies ``omega_i``, shape (n,)."""
    a: np.ndarray
    """Decay rates ``a_i = xi_i omega_i`` (eq. 6), shape (n,)."""
    f: np.ndarray
    """Modal forces ``u^T F`` (eq. 7), shape (n,)."""
    u: np.ndarray
    """Mass-normalised modes, columns ``u_.i``, shape (n, n)."""
    ui: np.ndarray
    """``u^-1 = u^T M``, shape (n, n)."""
    eig_err: np.ndarray
    """Rounding-error scale of ``omega_i^2``, shape (n,)."""
    u0: np.ndarray
    """Row of ``u`` of the impacting mass (``u_j.``), shape (n,)."""
    ui0: np.ndarray
    """Column of ``u^-1`` of the impacting mass (``(u^-1)_.j``), shape (n,)."""

    def as_tuple(self) -> tuple[np.ndarray, ...]:
        """The fields as a plain tuple, in this order: the argument of the compiled entry
        points (:func:`impactcont.kernel.closed_form.point_orbits`, ``phase_orbit``,
        ``block_map``), which unpack it as ``w, a, f, u, ui, eig_err, u0, ui0``."""
        return tuple(self)


def _real_array(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """`value` as a C-contiguous float64 array of `shape`, or a clear refusal."""
    if not isinstance(value, np.ndarray):
        raise TypeError(f"modal_arrays: {name} must be a numpy array of real numbers; got "
                        f"{type(value).__name__} {value!r}")
    if value.dtype.kind not in "fiu":
        raise TypeError(f"modal_arrays: {name} must hold real numbers (float or integer "
                        f"dtype); got dtype {value.dtype}")
    if value.shape != shape:
        raise ValueError(f"modal_arrays: {name} must have shape {shape} (n = {shape[0]} "
                         f"modes, from w); got shape {value.shape}")
    return np.ascontiguousarray(value, dtype=np.float64)


def modal_arrays(w: np.ndarray, a: np.ndarray, f: np.ndarray, u: np.ndarray, ui: np.ndarray,
                 eig_err: np.ndarray | None = None, *, mass: int = 0) -> ModalArrays:
    """Check the modal arrays and build :class:`ModalArrays`.

    Parameters
    ----------
    w, a, f : ndarray, shape (n,)
        Natural frequencies, decay rates (eq. 6), modal forces (eq. 7).
    u, ui : ndarray, shape (n, n)
        Mass-normalised modes and their inverse ``u^T M`` (eq. 5).
    eig_err : ndarray, shape (n,), optional
        Rounding-error scale of ``omega_i^2`` (zero when not given).
    mass : int
        The impacting mass, 0-based (the row of ``u``, the column of ``u^-1`` the impact
        law of eq. 4 sees): the model's, ``stops.mass - 1``.

    Returns
    -------
    ModalArrays
        C-contiguous float64 copies where needed (the inputs themselves when they
        already are).

    Raises
    ------
    TypeError
        If an array is not a numpy array of real numbers (complex, bool, object), or
        `mass` is not an integer.
    ValueError
        If a shape does not match ``n = w.size`` or `mass` is not in ``0..n-1``.
    """
    if not isinstance(w, np.ndarray) or w.ndim != 1:
        raise (TypeError if not isinstance(w, np.ndarray) else ValueError)(
            f"modal_arrays: w must be a one-dimensional numpy array (the natural "
            f"frequencies); got {type(w).__name__} of shape {np.shape(w)}")
    n = w.shape[0]
    vec, mat = (n,), (n, n)
    w = _real_array("w", w, vec)
    a = _real_array("a", a, vec)
    f = _real_array("f", f, vec)
    u = _real_array("u", u, mat)
    ui = _real_array("ui", ui, mat)
    eig_err = (np.zeros(n) if eig_err is None else _real_array("eig_err", eig_err, vec))
    if isinstance(mass, (bool, np.bool_)) or not isinstance(mass, (int, np.integer)):
        raise TypeError(f"modal_arrays: mass must be an integer (the impacting mass, 0-based); "
                        f"got {mass!r}")
    if not 0 <= mass < n:
        raise ValueError(f"modal_arrays: mass must be in 0..{n - 1} (0-based, n = {n} "
                         f"masses); got {mass!r}")
    return ModalArrays(w, a, f, u, ui, eig_err, np.ascontiguousarray(u[mass]),
                       np.ascontiguousarray(ui[:, mass]))


class FirstOrderArrays(NamedTuple):
    """The first-order basis of any damping matrix C as the compiled first-order path
    takes it (:mod:`impactcont.kernel.general`), by name.

    The order is that of
    :attr:`impactcont.model.first_order.FirstOrderBasis.kernel_arrays`;
    ``FirstOrderArrays._make(basis.kernel_arrays)`` reads it (and returns it unchanged
    when it already is one). The last six fields are the arguments of the contact search
    in their order (:meth:`contact_arguments`).
    """

    lam: np.ndarray
    """Eigenvalues ``lambda_k`` of the first-order system, complex, shape (2n,)."""
    V: np.ndarray
    """Eigenvectors (columns), complex, shape (2n, 2n)."""
    V_inv: np.ndarray
    """``V^-1``, complex, shape (2n, 2n)."""
    A: np.ndarray
    """The first-order system matrix, shape (2n, 2n)."""
    impact_column: np.ndarray
    """The column the impact law of eq. (4) adds to the state, shape (2n,)."""
    w_p: np.ndarray
    """Frequencies of the scalar pairs (:attr:`FirstOrderBasis.scalar_pairs`)."""
    a_p: np.ndarray
    """Decay rates of the scalar pairs."""
    k_p: np.ndarray
    """First eigenvalue index of each pair (int64)."""
    j_p: np.ndarray
    """Second eigenvalue index of each pair (int64)."""
    M: np.ndarray
    """Mass matrix, shape (n, n)."""
    K: np.ndarray
    """Stiffness matrix, shape (n, n)."""
    C: np.ndarray
    """Damping matrix, shape (n, n)."""
    search_lam: np.ndarray
    """``lambda`` again, for the contact search."""
    search_v0: np.ndarray
    """The first row of ``V`` (mass 1's displacement), for the contact search."""
    search_w_p: np.ndarray
    """``w_p`` again, for the contact search."""
    search_a_p: np.ndarray
    """``a_p`` again, for the contact search."""
    search_k_p: np.ndarray
    """``k_p`` again, for the contact search."""
    search_j_p: np.ndarray
    """``j_p`` again, for the contact search."""

    def contact_arguments(self) -> tuple[np.ndarray, ...]:
        """``(lambda, V[0], w_p, a_p, k_p, j_p)``: the arguments of the contact search."""
        return (self.search_lam, self.search_v0, self.search_w_p, self.search_a_p,
                self.search_k_p, self.search_j_p)

"""The product of flight Jacobians of eq. (25) and its exact derivatives, compiled.

The half-map ``H = S G_{h-1} .. G_0`` of a symmetric N-p motion (its multiplier -1 is a
symmetry-breaking pitchfork, BP) moves with the motion's unknowns, omega and the stops'
positions only through each flight's shot data: the transition ``Phi_k = e^{A tau_k}``,
the phase column ``dX_k^-/dtheta_k`` and the arrival rate ``X_k'^-`` (the impact matrices
and the stops' normals stay). :func:`jacobian_product_derivative` carries the derivatives
of these along given directions through ``G_k`` (eq. 25: rational in them) and the product,
forward mode, from one shot (``SymmetricBranchProblem.half_map_derivative`` of
:mod:`impactcont.problems.symmetric_branch`, the exact row of the BP test of a curve).

The product itself is :func:`impactcont.kernel.shooting.jacobian_product`'s, operation for
operation (each ``G_k`` from the shooting kernel's own flight Jacobian).

:func:`smallest_singular_value` gives the two factors of the test function of a BP curve,
``sigma(H + I) = sign(det(H + I)) s_min(H + I)``, with the singular vectors of ``s_min``
that its exact row needs, in one compiled call (numpy's ``svd`` and ``slogdet`` cost
three times as much on a 4 x 4 matrix, in their Python wrappers).
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.arrays import Forcing, ImpactSequence, ShotFlights
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.linalg import _product_into
from impactcont.kernel.shooting import (
    _apply,
    _apply_matrix,
    _flight_jacobian,
    omega_partials,
)

__all__ = ["jacobian_product_derivative", "smallest_singular_value"]


@_jit
def jacobian_product_derivative(flow, forcing, derivatives, impacts, shot, state_matrix,
                                forcing_rate, du, dc, domega, count, dG):
    """``G_{count-1} .. G_0`` (eq. 25) and its derivatives along `d` directions, exactly.

    Parameters
    ----------
    flow, forcing, derivatives
        The plain tuples of :class:`~impactcont.kernel.arrays.ShootingFlow`,
        :class:`~impactcont.kernel.arrays.Forcing` and
        :class:`~impactcont.kernel.arrays.ForcingDerivatives` of the motion's (modal) flow
        at its omega, as :func:`~impactcont.kernel.shooting.branch_linearization` takes them.
    impacts, shot
        The plain tuples of :class:`~impactcont.kernel.arrays.ImpactSequence` (all p
        impacts) and :class:`~impactcont.kernel.arrays.ShotFlights` at the unknowns.
    state_matrix : ndarray, shape (2n, 2n)
        ``A = [[0, I], [-M^-1 K, -M^-1 C]]`` of the flight ``X' = A X + B f``.
    forcing_rate : ndarray, shape (n,)
        ``M^-1 F`` (real harmonic forcing ``F cos(phi)``, no constant force).
    du : ndarray, shape (d, 2np)
        Each direction's change of the shooting unknowns
        ``u = [delta, tau_0..tau_{p-2}, z_0..z_{p-1}]``.
    dc : ndarray, shape (d, p)
        Each direction's change of the stops' positions ``c_k`` at the p impacts.
    domega : ndarray, shape (d,)
        Each direction's change of omega.
    count : int
        The flights of the product, ``1 <= count <= p - 1`` (the half-map's ``p / 2``;
        ``tau_{p-1}`` is no unknown).
    dG : ndarray, shape (d, 2n, 2n)
        Filled with the derivatives of the product.

    Returns
    -------
    ndarray, shape (2n, 2n)
        The product, as :func:`~impactcont.kernel.shooting.jacobian_product` gives it.

    Notes
    -----
    Along a direction flight k moves by its start ``dX_k`` (``z_k`` and ``c_k`` on the
    section), phase ``dtheta_k = ddelta + omega (dtau_0 + .. + dtau_{k-1}) + (tau_0 + ..
    + tau_{k-1}) domega``, time ``dtau_k`` and omega. Then ``dPhi = A Phi dtau``,
    ``d(dX^-/dtheta) = (A dX^-/dtheta + B f') dtau - X_f dtheta + (dX_f/domega)(theta +
    pi/2) domega`` (``X_f = X^- - Phi X_0`` the forced part, harmonic in the phase; its
    omega partials at fixed start, phase and time from
    :func:`~impactcont.kernel.shooting.omega_partials`), ``dX^- = Phi dX_0 + dX^-/dtheta
    dtheta + X'^- dtau + (dX_f/domega) domega`` and ``dX'^- = A dX^- + B f' (dtheta +
    omega dtau + tau domega)`` with ``B f' = [0; -M^-1 F sin(phi)]`` at the arrival
    ``phi = theta + omega tau``. ``G_k`` (``B = Phi dX/dz - X'^- h / h2`` with
    ``h = n . [Phi dX/dz | dX^-/dtheta]``, ``h2 = n . X'^-``; rows ``D B`` and
    ``-omega h / h2 + e``) is differentiated by the quotient rule: at a fixed arrival rate
    ``G_k`` is affine in ``(Phi, dX^-/dtheta)`` (the constant ``e`` aside), so the
    shooting kernel's ``G_k`` of ``(dPhi, d(dX^-/dtheta))`` is their part of ``dG_k``;
    the rate's adds ``-(D w) h / h2`` to the rows, ``w = dX'^- - X'^- dh2 / h2``, and
    ``omega h dh2 / h2^2 - domega h / h2`` to the last row (``h`` from ``G_k``'s last row).
    """
    impacts, flights = ImpactSequence(*impacts), ShotFlights(*shot)
    omega = Forcing(*forcing).omega
    pivots, normals, matrices = impacts.pivots, impacts.normals, impacts.matrices
    p = pivots.size
    m = matrices.shape[1]
    n = m // 2
    d = du.shape[0]
    # the forced part's omega partials at each flight's phase and a quarter period on
    partials = omega_partials(flow, forcing, derivatives, shot)
    shifted = flights.phases + 0.5 * math.pi
    quarter = omega_partials(flow, forcing, derivatives, (
        shifted, flights.flight_times, flights.starts, flights.arrivals,
        flights.arrival_rates, flights.transitions, flights.phase_columns, flights.residual,
        flights.jacobian))
    G = np.empty((m, m))
    for r in range(m):
        for c in range(m):
            G[r, c] = 1.0 if r == c else 0.0
    for i in range(d):
        for r in range(m):
            for c in range(m):
                dG[i, r, c] = 0.0
    Gk = np.empty((m, m))
    dGk = np.empty((m, m))
    tmp = np.empty((m, m))
    Atr = np.empty((m, m))
    dtr = np.empty((m, m))
    h = np.empty(m)
    Apcol = np.empty(m)
    rate_of = np.zeros(m)  # B f' at the arrival
    forced = np.empty(m)
    dX0 = np.empty(m)
    dXm = np.empty(m)
    dpcol = np.empty(m)
    drate = np.empty(m)
    w = np.empty(m)
    Dw = np.empty(m)
    tau_sum = np.zeros(d)  # dtau_0 + .. + dtau_{k-1} of each direction
    elapsed = 0.0  # tau_0 + .. + tau_{k-1}
    for k in range(count):
        nxt = (k + 1) % p
        j, j_end = pivots[k], pivots[nxt]
        n_start, n_end, D = normals[k], normals[nxt], matrices[nxt]
        tr, pcol, rate = (flights.transitions[k], flights.phase_columns[k],
                          flights.arrival_rates[k])
        X0, tau = flights.starts[k], flights.flight_times[k]
        h2 = _flight_jacobian(tr, pcol, rate, D, j, j_end, n_start, n_end, omega, Gk)
        for c in range(m):  # G_k's last row is -omega h / h2 + e
            h[c] = -Gk[m - 1, c] * h2 / omega
        h[m - 1] = (1.0 - Gk[m - 1, m - 1]) * h2 / omega
        _apply(state_matrix, pcol, Apcol)
        _apply_matrix(state_matrix, tr, Atr)
        _apply(tr, X0, forced)
        for r in range(m):
            forced[r] = flights.arrivals[k, r] - forced[r]
        phi = flights.phases[k] + omega * tau
        for r in range(n):
            rate_of[n + r] = -math.sin(phi) * forcing_rate[r]
        for i in range(d):
            dw = domega[i]
            dtheta = du[i, 0] + omega * tau_sum[i] + elapsed * dw
            dtau = du[i, 1 + k]
            col = 0
            off = p + k * (m - 1)
            for c in range(m):
                if c != j:
                    dX0[c] = du[i, off + col]
                    col += 1
            s = 0.0
            for c in range(n):
                if c != j:
                    s += dX0[c] * n_start[c]
            dX0[j] = (dc[i, k] - s) / n_start[j]
            for r in range(m):
                s = 0.0
                for c in range(m):
                    s += tr[r, c] * dX0[c]
                dXm[r] = s + dtheta * pcol[r] + dtau * rate[r] + dw * partials[k, r]
                dpcol[r] = (dtau * (Apcol[r] + rate_of[r]) - dtheta * forced[r]
                            + dw * quarter[k, r])
                for c in range(m):
                    dtr[r, c] = dtau * Atr[r, c]
            speed = dtheta + omega * dtau + tau * dw
            dh2 = 0.0
            _apply(state_matrix, dXm, drate)
            for r in range(m):
                drate[r] += speed * rate_of[r]
                if r < n:
                    dh2 += n_end[r] * drate[r]
            # the part of (dPhi, d(dX^-/dtheta)): G_k is affine in them at a fixed rate
            _flight_jacobian(dtr, dpcol, rate, D, j, j_end, n_start, n_end, omega, dGk)
            dGk[m - 1, m - 1] -= 1.0
            # the rate's part
            for r in range(m):
                w[r] = drate[r] - rate[r] * dh2 / h2
            _apply(D, w, Dw)
            for row in range(m - 1):  # every row of D w but the next section's (j_end)
                r = row if row < j_end else row + 1
                for c in range(m):
                    dGk[row, c] -= Dw[r] * h[c] / h2
            for c in range(m):
                dGk[m - 1, c] += (omega * dh2 / h2 - dw) * h[c] / h2
            # d(G_k G) = dG_k G + G_k dG
            _product_into(Gk, dG[i], tmp)
            for r in range(m):
                for c in range(m):
                    s = 0.0
                    for q in range(m):
                        s += dGk[r, q] * G[q, c]
                    dG[i, r, c] = s + tmp[r, c]
            tau_sum[i] += dtau
        _product_into(Gk, G, tmp)
        G[:, :] = tmp
        elapsed += tau
    return G


@_jit
def smallest_singular_value(matrix, left, right):
    """``sign(det A)``, ``s_min(A)`` of a square `matrix` ``A`` and the singular vectors of
    ``s_min``; NaN (and NaN vectors) if ``A`` is not finite.

    Parameters
    ----------
    matrix : ndarray, shape (m, m)
        ``A``.
    left, right : ndarray, shape (m,)
        Filled with the left and right singular vectors ``a``, ``b`` of ``s_min``
        (``A b = s_min a``; their common sign is LAPACK's).

    Returns
    -------
    sign : float
        ``sign(det A)`` from the LU factors (as ``numpy.linalg.slogdet``), 0 if singular.
    smallest : float
        ``s_min(A)`` from the full SVD (``gesdd``, as ``numpy.linalg.svd(A)``).
    """
    m = matrix.shape[0]
    for r in range(m):
        for c in range(m):
            if not math.isfinite(matrix[r, c]):
                left[:] = math.nan
                right[:] = math.nan
                return math.nan, math.nan
    u, s, vh = np.linalg.svd(matrix)
    sign, _ = np.linalg.slogdet(matrix)
    for r in range(m):
        left[r] = u[r, m - 1]
        right[r] = vh[m - 1, r]
    return sign, s[m - 1]

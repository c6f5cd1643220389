"""Periodic N-1 motions with any damping matrix C or complex F: the dense exact path.

The proportional system's closed form (:mod:`impactcont.orbit.kernel`) relies on the
real 2x2 modal blocks of eq. (9). With a general damping matrix C, or with forcing
phases that differ between masses (complex F), the same equations are solved densely
from the first-order complex modes (:class:`impactcont.orbit.flow.GeneralFlow`), still
in closed form:

- eq. (12)-(13): ``S = (I - D Phi(T))^-1 D (I - Phi(T)) Z_c`` with ``Phi(T) = Re(V
  diag(exp(lambda T)) V^-1)`` and ``Z_c = [Re Z, -Im Z]`` the forced state's columns
  (``omega T = 2 pi N`` makes ``P(T) = P(0)``);
- eq. (15) for the phases, ``h2 = x1'(T^-)`` from the exact time derivative;
- G of eq. (25) by :func:`impactcont.orbit.dense.impact_map_jacobian`, its
  eigenvalues by LAPACK;
- eq. (16) by the extrema search along the exact flow (:mod:`impactcont.orbit.extrema`).

The parameter derivatives of ``c, s`` used by continuation are exact too
(:func:`amplitude`): ``dPhi/d omega = A Phi dT/d omega`` and ``dZ/d omega`` from the
dynamic stiffness.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from impactcont.errors import ParameterError, UnresolvedMotionWarning
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.dense import impact_map_jacobian, periodic_matrix
from impactcont.orbit.flow import Flow, GeneralFlow

__all__ = ["amplitude", "amplitude_derivative", "orbit_pieces", "orbit_values",
           "orbit_values_many", "phase_matrices", "roots", "x1_maximum"]


def _refuse_elastic(osc: ImpactOscillator) -> None:
    """Refuse ``R = 1`` without damping: ``I - D Phi(T)`` of eq. (12) is singular there.

    The modal path solves that case (a family of motions, :mod:`impactcont.orbit.kernel`);
    the message names what put the oscillator on the first-order path instead: a damping
    matrix ``C = 0`` (give ``eta=0``), or a complex F (per-mass phases).
    """
    if osc.R != 1.0 or np.any(osc.C):
        return
    why, fix = [], []
    if osc.general_damping:
        why.append(f"the damping matrix C={osc.C.tolist()} (given as a matrix)")
        fix.append("give the undamped case as eta=0 instead of C")
    if osc.F.dtype.kind == "c":
        why.append(f"the complex F={osc.F.tolist()} (per-mass phases)")
        fix.append("a real F")
    raise ParameterError(
        f"R=1.0 without damping is singular on the first-order path of eq. (1) (taken for "
        f"{' and '.join(why)}): eq. (12) has no unique solution for elastic impacts without "
        f"damping. Use R < 1, add damping, or {' and '.join(fix)}: the modal path solves "
        "that case")


def orbit_pieces(osc: ImpactOscillator, N: int) -> tuple[GeneralFlow, np.ndarray, np.ndarray,
                                                             float]:
    """The flow, ``S`` (2n, 2), ``D Phi(T)`` and ``T`` of eq. (12)-(13) at the oscillator's
    parameters."""
    _refuse_elastic(osc)
    flow = Flow(osc)
    S, DPhi, T = periodic_matrix(flow, N)
    return flow, S, DPhi, T  # type: ignore[return-value]


def amplitude(osc: ImpactOscillator, N: int, which: str | None = None
              ) -> tuple[float, float, float, float]:
    """``c, s`` of eq. (14) and their exact derivative in ``which`` (``"omega"``, ``"R"``).

    With ``B = I - D Phi(T)``, ``P = (I - Phi(T)) Z_c`` and ``S = B^-1 D P``:

    - ``dS/dR = B^-1 dD (Phi S + P)``, ``dD = -e_{n+1} e_{n+1}^T`` (eq. 4);
    - ``dS/d omega = B^-1 D (Phi' S - Phi' Z_c + (I - Phi) Z_c')`` with
      ``Phi' = A Phi(T) dT/d omega``, ``dT/d omega = -T / omega``.

    Returns
    -------
    c, s, dc, ds : float
        ``dc = ds = 0`` when `which` is None.
    """
    flow, S, DPhi, T = orbit_pieces(osc, N)
    c, s = float(S[0, 0]), float(S[0, 1])
    if which is None:
        return c, s, 0.0, 0.0
    return (c, s, *amplitude_derivative(flow, S, DPhi, T, which))


def amplitude_derivative(flow: GeneralFlow, S: np.ndarray, DPhi: np.ndarray, T: float,
                         which: str) -> tuple[float, float]:
    """``dc, ds`` (eq. 14) in ``which`` (``"omega"``, ``"R"``) from :func:`orbit_pieces`
    (formulas in :func:`amplitude`)."""
    osc = flow.osc
    n = osc.n
    d = np.ones(2 * n)
    d[n] = -osc.R
    Phi = flow.transition_matrix(T)
    B = np.eye(2 * n) - DPhi
    Zc = np.column_stack([flow.Z.real, -flow.Z.imag])
    if which == "R":
        rhs = np.zeros((2 * n, 2))
        rhs[n] = -(Phi @ S + (Zc - Phi @ Zc))[n]
    elif which == "omega":
        dPhi = flow.basis.A @ Phi * (-T / osc.omega)
        dZ = flow.basis.forced_amplitude_derivative(flow.Z, osc.omega)
        dZc = np.column_stack([dZ.real, -dZ.imag])
        rhs = d[:, None] * (dPhi @ S - dPhi @ Zc + dZc - Phi @ dZc)
    elif which in ("eta", "alpha", "beta"):
        raise ParameterError(
            f"parameter={which!r}: a branch on the first-order path (complex F={osc.F.tolist()}, "
            "per-mass phases) cannot be continued in the damping eta, alpha or beta (eq. 12-14 "
            "have no exact derivative in them there); continue in omega, b, R or F0, follow a "
            f"curve with {which!r} as its second parameter (impactcont.curve), or use a real F")
    else:
        raise ParameterError(f"which must be 'omega' or 'R' (the derivative of c, s of eq. 14); "
                             f"got {which!r}")
    dS = np.linalg.solve(B, rhs)
    return float(dS[0, 0]), float(dS[0, 1])


def _pair_coefficients(flow: GeneralFlow, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``y(0), y'(0)`` of each scalar pair (:attr:`FirstOrderBasis.scalar_pairs`) from the
    complex coefficients ``c`` of ``x1``'s free part ``Re sum c e^{lam t}``; ``c`` may
    carry trailing columns (real-linear in them)."""
    _, _, k, j = flow.basis.scalar_pairs
    lam = flow.lam
    conj = (np.abs(lam[k].imag) > 0).reshape((-1,) + (1,) * (c.ndim - 1))
    lk = lam[k].reshape(conj.shape)
    lj = lam[j].reshape(conj.shape)
    # a conjugate pair: Re((c_k + conj c_j) e^{lam_k t}); a real pair: c_k e^.. + c_j e^..
    total = np.where(conj, c[k] + np.conj(c[j]), c[k] + c[j])
    slope = np.where(conj, (c[k] + np.conj(c[j])) * lk, c[k] * lk + c[j] * lj)
    return np.ascontiguousarray(total.real), np.ascontiguousarray(slope.real)


def _search_grid(flow: GeneralFlow, T: float) -> np.ndarray:
    """The kernel's grid on ``[0, T]`` for the x1 search of eq. (16), warning when capped."""
    from impactcont.orbit import kernel

    w, a, _, _ = flow.basis.scalar_pairs
    times, capped = kernel.time_grid(w, a, np.ones_like(w), flow.omega, T)
    if capped:
        warnings.warn(f"x1 search grid capped at 2000000 cells for a period of {T:.3g}: a short "
                      "excursion of mass 1 past the stop (eq. 16) may be missed",
                      UnresolvedMotionWarning, stacklevel=4)
    return times


def _search(flow: GeneralFlow, times: np.ndarray, free: np.ndarray, dy: np.ndarray,
            dv: np.ndarray, delta: float, exclude: float) -> tuple[float, float]:
    from impactcont.orbit import kernel

    w, a, _, _ = flow.basis.scalar_pairs
    work = np.empty((kernel.WORK_ROWS, 2 * times.size))
    best, best_t = kernel.x1_maximum(times, free, np.cos(flow.omega * times),
                                     np.sin(flow.omega * times), float(flow.Z[0].real),
                                     float(-flow.Z[0].imag), flow.omega, float(delta), 1.0, w,
                                     a, np.ones_like(w), dy, dv, work, float(exclude))
    return float(best), float(best_t)


def x1_maximum(flow: GeneralFlow, state: np.ndarray, delta: float, T: float,
               exclude: float = math.nan) -> tuple[float, float]:
    """Highest interior local maximum of ``x1`` on ``(0, T)`` (eq. 16): ``(value, time)``,
    ``(-inf, nan)`` when there is none. A maximum within ``1e-7 T`` of the time
    ``exclude`` is skipped (NaN: none is), e.g. the tangency of a grazing motion.

    The free part of ``x1`` is a sum over the scalar pairs of
    :attr:`FirstOrderBasis.scalar_pairs`, each ``W11 y(0) + W12 y'(0)`` with the exact
    modal transfer, and the forced part is ``Re(Z_1 e^{i theta})``: the compiled
    kernel's search (:func:`impactcont.orbit.kernel.x1_maximum`, with its grid, bounds
    and polish) runs on them unchanged, with unit weights.
    """
    from impactcont.orbit import kernel

    w, a, _, _ = flow.basis.scalar_pairs
    dy, dv = _pair_coefficients(flow, flow.V[0] * flow.modal_deviation(state, delta))
    times = _search_grid(flow, T)
    free = kernel.free_on_grid(times, w, a, np.ones_like(w), dy, dv)
    return _search(flow, times, free, dy, dv, delta, exclude)


def phase_matrices(flow: GeneralFlow, S: np.ndarray, T: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The impact-phase-linear pieces of the motion ``X(0) = S e``, ``e = [cos delta,
    sin delta]`` (eq. 13), for G of eq. (22)-(25) and the search of eq. (16):

    - ``J1`` (2n, 2): ``[h1; H1] = D E(T) [-sin delta; cos delta] = J1 e``;
    - ``Y`` (2n, 2): ``[h2; H2] = D X'(T^-) = Y e``, ``X'(T^-) = (Phi'(T) (S - P(0)) +
      P'(T)) e``, ``P(t) = [Re(Z e^{i omega t}), -Im(Z e^{i omega t})]``;
    - ``U`` (2n, 2), complex: ``V_1k (V^-1 (S - P(0)))_k``, the coefficients of ``x1``'s
      free part ``Re sum_k (U e)_k e^{lambda_k t}``.
    """
    osc = flow.osc
    n = osc.n
    d = np.ones(2 * n)
    d[n] = -osc.R
    _, E = flow.matrices(T)
    lam, V, Z = flow.lam, flow.V, flow.Z
    zt = Z * np.exp(1j * osc.omega * T)
    P0 = np.column_stack([Z.real, -Z.imag])
    dP_T = np.column_stack([(1j * osc.omega * zt).real, -(1j * osc.omega * zt).imag])
    deviation = flow.V_inv @ (S - P0)  # complex modal coordinates of the free part
    dPhi_free = (V * (lam * np.exp(lam * T))) @ deviation
    Y = d[:, None] * (dPhi_free.real + dP_T)
    J1 = d[:, None] * np.column_stack([E[:, 1], -E[:, 0]])  # E [-sin, cos] = J1 [cos, sin]
    U = V[0][:, None] * deviation
    return J1, Y, U


def orbit_values_many(flow: GeneralFlow, S: np.ndarray, DPhi: np.ndarray, T: float,
                      deltas: np.ndarray, b: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`orbit_values` for many impact phases at once, one omega (e.g. the gaps of a
    stability map): ``(h2, multipliers, gap_min, gap_min_time)`` of the motions with
    impact phases ``deltas`` at the gaps ``b`` (each phase a root of eq. 15 at its gap),
    shapes ``(m,)``, ``(m, 2n)`` (largest modulus first), ``(m,)``, ``(m,)``.

    Everything that depends on the phase is linear in ``e = [cos delta, sin delta]``
    (:func:`phase_matrices`): G of eq. (25) is assembled for all phases by broadcasting,
    the multipliers by one batched LAPACK call, and the free part of ``x1`` on the search
    grid of eq. (16) is computed for the two columns of ``e`` once. Agrees with
    :func:`orbit_values` to rounding.
    """
    from impactcont.orbit import kernel

    osc = flow.osc
    deltas = np.asarray(deltas, dtype=float)
    b = np.broadcast_to(np.asarray(b, dtype=float), deltas.shape)
    m = deltas.size
    e = np.column_stack([np.cos(deltas), np.sin(deltas)])  # (m, 2)
    J1, Y, U = phase_matrices(flow, S, T)
    dE, dX = e @ J1.T, e @ Y.T  # (m, 2n)
    h2 = dX[:, 0]
    h0_p = DPhi[0, 1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        H2 = dX[:, 1:] / h2[:, None]
        G = np.empty((m, 2 * osc.n, 2 * osc.n))
        G[:, :-1, :-1] = DPhi[1:, 1:] - H2[:, :, None] * h0_p[None, None, :]
        G[:, :-1, -1] = dE[:, 1:] - H2 * dE[:, :1]
        G[:, -1, :-1] = -osc.omega * h0_p[None, :] / h2[:, None]
        G[:, -1, -1] = 1.0 - osc.omega * dE[:, 0] / h2
    mu = np.full((m, 2 * osc.n), np.nan + 0j)
    good = np.all(np.isfinite(G), axis=(1, 2))
    if np.any(good):
        mu[good] = np.linalg.eigvals(G[good])
    mu = np.take_along_axis(mu, np.argsort(-np.abs(mu), axis=1, kind="stable"), axis=1)
    gap, gap_t = np.full(m, -math.inf), np.full(m, math.nan)
    if m:
        w, a, _, _ = flow.basis.scalar_pairs
        dy, dv = _pair_coefficients(flow, U)  # (pairs, 2): the columns of e
        times = _search_grid(flow, T)
        ones = np.ones_like(w)
        free = [kernel.free_on_grid(times, w, a, ones, np.ascontiguousarray(dy[:, col]),
                                    np.ascontiguousarray(dv[:, col])) for col in (0, 1)]
        for i, (cd, sd) in enumerate(e):
            best, gap_t[i] = _search(flow, times, cd * free[0] + sd * free[1],
                                     dy @ e[i], dv @ e[i], deltas[i], math.nan)
            gap[i] = b[i] - best
    return h2, mu, gap, gap_t


def roots(c: float, s: float, b: float) -> list[tuple[float, int]]:
    """The phases of eq. (15) with their root signs (+1 first), as the kernel orders them."""
    r2 = c * c + s * s
    if r2 == 0.0:
        if b == 0.0:
            raise ParameterError("c = s = 0 and b = 0: every phase satisfies eq. (14); the "
                                 "forcing does not reach mass 1 (check F)")
        return []
    disc = r2 - b * b
    if disc < 0.0:
        return []
    root_r = math.sqrt(disc)
    out = []
    for sg in ((1, -1) if root_r > 0.0 else (1,)):
        sin_d = (b * s + sg * c * root_r) / r2
        cos_d = (b * c - sg * s * root_r) / r2
        out.append((math.atan2(sin_d, cos_d), sg))
    return out


def orbit_values(osc: ImpactOscillator, flow: GeneralFlow, S: np.ndarray, DPhi: np.ndarray,
                 T: float, delta: float) -> tuple[np.ndarray, float, np.ndarray, np.ndarray,
                                                  float, float]:
    """The motion at phase delta from :func:`orbit_pieces`: ``(state, h2, G, multipliers,
    gap_min, gap_min_time)`` (eq. 13, 22, 25, 16); multipliers largest modulus first."""
    state = S @ np.array([math.cos(delta), math.sin(delta)])
    G, h2 = impact_map_jacobian(flow, state, delta, T, DPhi)
    state[osc.n] = -osc.R * h2  # eq. (4), as the kernel sets it
    mu = np.linalg.eigvals(G) if np.all(np.isfinite(G)) else np.full(G.shape[0], np.nan + 0j)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    best, gap_t = x1_maximum(flow, state, delta, T)
    return state, float(h2), G, mu, osc.b - best, gap_t

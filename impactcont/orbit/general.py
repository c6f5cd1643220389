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

__all__ = ["amplitude", "amplitude_derivative", "orbit_pieces", "orbit_values", "roots",
           "x1_maximum"]


def _refuse_elastic(osc: ImpactOscillator) -> None:
    if osc.R == 1.0 and not np.any(osc.C):
        raise ParameterError(
            "R=1.0 without damping (C = 0) on the first-order path (complex F): eq. (12) is "
            "singular for elastic impacts without damping; use R < 1, add damping, or a real F "
            "(whose modal path solves that case)")


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
    else:
        raise ParameterError(f"which must be 'omega' or 'R' (the derivative of c, s of eq. 14); "
                             f"got {which!r}")
    dS = np.linalg.solve(B, rhs)
    return float(dS[0, 0]), float(dS[0, 1])


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

    w, a, k, j = flow.basis.scalar_pairs
    lam = flow.lam
    c = flow.V[0] * flow.modal_deviation(state, delta)  # x1's free part: Re sum c e^{lam t}
    conj = np.abs(lam[k].imag) > 0
    # a conjugate pair: Re((c_k + conj c_j) e^{lam_k t}); a real pair: c_k e^.. + c_j e^..
    total = np.where(conj, c[k] + np.conj(c[j]), c[k] + c[j])
    slope = np.where(conj, (c[k] + np.conj(c[j])) * lam[k], c[k] * lam[k] + c[j] * lam[j])
    dy = np.ascontiguousarray(total.real)
    dv = np.ascontiguousarray(slope.real)
    ones = np.ones_like(w)
    times, capped = kernel.time_grid(w, a, ones, flow.omega, T)
    if capped:
        warnings.warn(f"x1 search grid capped at 2000000 cells for a period of {T:.3g}: a short "
                      "excursion of mass 1 past the stop (eq. 16) may be missed",
                      UnresolvedMotionWarning, stacklevel=3)
    free = kernel.free_on_grid(times, w, a, ones, dy, dv)
    work = np.empty((kernel.WORK_ROWS, 2 * times.size))
    best, best_t = kernel.x1_maximum(times, free, np.cos(flow.omega * times),
                                     np.sin(flow.omega * times), float(flow.Z[0].real),
                                     float(-flow.Z[0].imag), flow.omega, float(delta), 1.0, w,
                                     a, ones, dy, dv, work, float(exclude))
    return float(best), float(best_t)


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

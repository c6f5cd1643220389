"""The pieces of the codim-1 curve systems on the first-order path (any C, complex F).

:class:`GeneralPieces` has the interface of the modal pieces of
:mod:`impactcont.problems.codim1` (``S0``, ``T``, ``b``, ``impact_velocity``,
``jacobian``, ``split``, ``pd_condition``, ``pole_free_pd_matrix``, ``mass1``,
``other_maximum``, ``stepped``), built from the dense closed form
(:func:`impactcont.orbit.dense.periodic_matrix` on the exact flow
:class:`impactcont.orbit.flow.GeneralFlow`). With ``e = [cos delta, sin delta]``
every quantity that depends on the impact phase is *linear* in ``e``, so it is kept
as a real matrix times ``e``:

- ``X(0) = S e`` (eq. 12-13), ``c, s = S[0]`` (eq. 14);
- ``[h1; H1] = D E(T) [-sin delta; cos delta] = J1 e`` (eq. 23-25);
- ``[h2; H2] = D X'(T^-) = Y e`` with ``X'(T^-) = (Phi'(T) (S - P(0)) + P'(T)) e``,
  ``Phi'(T) = Re(V diag(lambda e^{lambda T}) V^-1)``, ``P(t) = [Re(Z e^{i omega t}),
  -Im(Z e^{i omega t})]`` (eq. 9, first order); ``h2 = x1'(T^-)`` (eq. 22);
- ``G = G_reg + a b^T / h2`` (eq. 25) with ``G_reg = [[H0, H1], [0, 1]]``,
  ``a = [-H2; -omega]``, ``b = [h0'; h1]`` and ``[h0'; H0] = D Phi(T)`` without its
  first column, as in :func:`impactcont.orbit.dense.impact_map_jacobian`;
- ``x1^(j)(t) = L_j(t) e`` with the real row ``L_j(t) = Re(sum_k lambda_k^j
  e^{lambda_k t} U_k) + [Re w_j, -Im w_j]``, ``U_k = V_1k (V^-1 (S - P(0)))_k``,
  ``w_j = (i omega)^j Z_1 e^{i omega t}`` (eq. 9, first order).

Why the Jacobian is not one complex step per column here
--------------------------------------------------------
The modal path differentiates its residual by complex steps of the parameters
through the compiled kernel. Here the free flow is ``Phi(T) = Re(V e^{Lambda T}
V^-1)``: a complex step of ``omega`` (through ``T``) is discarded by the real part,
and evaluating ``V e^{Lambda T} V^-1`` in complex arithmetic without it leaves an
imaginary part of rounding size that swamps a step of ``1e-30``. What stays exact:

- ``delta`` and the extra unknowns: everything above is real matrices applied to
  ``e`` (no complex arithmetic after it), so the complex step of the residual in
  ``delta`` is exact, as on the modal path; the grazing time ``t*`` enters through
  ``L_j(t*)``, whose complex step is its exact first-order Taylor term
  ``i h L_{j+1}(t*)``; NS gives its ``theta, v`` columns in closed form;
- ``b``: it enters eq. (14) and the grazing condition only, linearly;
- ``F0``: ``S, J1, Y`` and ``x1(t)`` are proportional to the forcing amplitude and
  ``D Phi(T)`` does not depend on it, so :meth:`GeneralPieces.stepped` scales the
  forced data by ``1 + i h / F0``: an exact complex step of every condition;
- ``omega, R``: the rows that depend on them only through ``c, s`` (eq. 14 and the
  fold condition) from the exact ``dc, ds``
  (:func:`impactcont.orbit.general.amplitude_derivative`).

The remaining entries (the ``omega`` and ``R`` derivatives of the PD, NS, GR and ZV
conditions, and ``eta, alpha, beta`` with a complex F on proportional damping) are
central differences of the residual with the step ``1e-6 max(1, |p|)``, one-sided at
the boundary of a parameter's domain (``R = 1``, ``eta = 0``). They steer Newton only:
every curve point solves the closed-form residual to the Newton tolerance.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit import general
from impactcont.orbit.dense import pole_free_pd_matrix
from impactcont.orbit.flow import GeneralFlow

__all__ = ["STEPPED_PARAMETERS", "GeneralPieces"]

STEPPED_PARAMETERS = ("b", "F0")
"""Parameters whose column :meth:`GeneralPieces.stepped` differentiates exactly."""


@dataclasses.dataclass(frozen=True, eq=False)
class GeneralPieces:
    """The closed-form pieces of one parameter pair on the first-order path.

    Real, or complex along an exact step (:meth:`stepped`); the phase ``delta`` and
    the time ``t`` may be complex (the caller's complex step).
    """

    osc: ImpactOscillator
    """The oscillator at the (real) parameter pair."""
    N: int
    flow: GeneralFlow
    T: float
    """``2 pi N / omega``."""
    DPhi: np.ndarray
    """``D Phi(T)`` (eq. 12), (2n, 2n)."""
    S: np.ndarray
    """``X(0) = S e`` (eq. 13), (2n, 2)."""
    J1: np.ndarray
    """``[h1; H1] = J1 e``, (2n, 2)."""
    Y: np.ndarray
    """``[h2; H2] = D X'(T^-) = Y e``, (2n, 2)."""
    U: np.ndarray
    """``V_1k (V^-1 (S - P(0)))_k`` (2n, 2), complex: the free part of ``x1``."""
    Z1: complex
    """``Z_1`` of the forced state (the complex amplitude of ``x1``)."""
    b: float | complex
    omega: float
    scale: float | complex = 1.0
    """``1 + i h / F0`` along the complex step of ``F0``: multiplies ``x1(t)``."""

    @classmethod
    def at(cls, osc: ImpactOscillator, N: int) -> GeneralPieces:
        """The real pieces of `osc`."""
        flow, S, DPhi, T = general.orbit_pieces(osc, N)  # eq. (12)-(13)
        J1, Y, U = general.phase_matrices(flow, S, T)
        Z = flow.Z
        return cls(osc=osc, N=N, flow=flow, T=float(T), DPhi=DPhi, S=S, J1=J1, Y=Y, U=U,
                   Z1=complex(Z[0]), b=osc.b, omega=osc.omega)

    def stepped(self, name: str | None, h: float) -> GeneralPieces:
        """These pieces in complex arithmetic with `name` moved to ``p + i h`` (exact).

        ``name`` is None (nothing moves: the caller steps the phase or an extra
        unknown), ``"b"`` or ``"F0"`` (:data:`STEPPED_PARAMETERS`; the forced data
        scale with ``F0``, ``D Phi(T)`` does not).
        """
        b = complex(self.b)
        scale = 1.0 + 0.0j
        if name == "b":
            b += 1j * h
        elif name == "F0":
            scale = complex(1.0, h / self.osc.F0)
        elif name is not None:
            raise ValueError(f"name must be None or one of {STEPPED_PARAMETERS}; got {name!r}")
        return dataclasses.replace(self, S=self.S * scale, J1=self.J1 * scale,
                                   Y=self.Y * scale, b=b, scale=scale)

    # -- eq. (12)-(15) ----------------------------------------------------------------------------
    @property
    def S0(self) -> tuple[float, float]:
        """``c, s`` of eq. (14) (the first row of S, eq. 13)."""
        return self.S[0, 0], self.S[0, 1]

    @staticmethod
    def _phase(delta: float | complex) -> np.ndarray:
        return np.array([np.cos(delta), np.sin(delta)])

    def state(self, delta: float | complex) -> np.ndarray:
        """``X(0) = S [cos delta, sin delta]`` right after the impact (eq. 13)."""
        return self.S @ self._phase(delta)

    def impact_velocity(self, delta: float | complex) -> float | complex:
        """``h2 = x1'(T^-)`` of the motion with impact phase ``delta`` (eq. 22)."""
        return self.Y[0] @ self._phase(delta)

    # -- G, eq. (22)-(25) -------------------------------------------------------------------------
    def split(self, delta: float | complex
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | complex]:
        """G of eq. (25) as ``(G_reg, a, b, h2)``, ``G = G_reg + a b^T / h2``, every piece
        finite where ``h2`` vanishes."""
        e = self._phase(delta)
        dE, dX = self.J1 @ e, self.Y @ e
        m = self.DPhi.shape[0]
        dtype = np.result_type(dE, dX, self.DPhi)
        G_reg = np.zeros((m, m), dtype=dtype)
        G_reg[:-1, :-1] = self.DPhi[1:, 1:]
        G_reg[:-1, -1] = dE[1:]
        G_reg[-1, -1] = 1.0
        a = np.empty(m, dtype=dtype)
        a[:-1] = -dX[1:]
        a[-1] = -self.omega
        b = np.empty(m, dtype=dtype)
        b[:-1] = self.DPhi[0, 1:]
        b[-1] = dE[0]
        return G_reg, a, b, dX[0]

    def jacobian(self, delta: float | complex) -> tuple[np.ndarray, float | complex]:
        """G of eq. (25) and ``h2`` for the impact phase ``delta``."""
        G_reg, a, b, h2 = self.split(delta)
        return G_reg + np.outer(a, b) / h2, h2

    def pole_free_pd_matrix(self, delta: float | complex) -> np.ndarray:
        """``E = [[G_reg + I, a], [b^T, -h2]]`` (m+1, m+1); ``det E = -h2 det(G + I)``."""
        return pole_free_pd_matrix(*self.split(delta))

    def pd_condition(self, delta: float | complex, left: np.ndarray, right: np.ndarray
                     ) -> float | complex:
        """``g``: the last component of ``[[E, left], [right^T, 0]] [q; g] = [0; 1]``
        (the pole-free period-doubling condition of :class:`PeriodDoublingCurve`)."""
        E = self.pole_free_pd_matrix(delta)
        k = E.shape[0] + 1
        A = np.zeros((k, k), dtype=E.dtype)
        A[:-1, :-1] = E
        A[:-1, -1] = left
        A[-1, :-1] = right
        rhs = np.zeros(k)
        rhs[-1] = 1.0
        try:
            return np.linalg.solve(A, rhs)[-1]
        except np.linalg.LinAlgError:
            return math.nan

    # -- x1 along the flight ------------------------------------------------------------------
    def x1_rows(self, t: float, orders: int) -> np.ndarray:
        """``L_j(t)``, ``j < orders``: ``x1^(j)(t) = L_j(t) [cos delta, sin delta]`` along
        the flight (real, shape (orders, 2); the real pieces, without :attr:`scale`)."""
        lam = self.flow.lam
        free = lam[None, :] ** np.arange(orders)[:, None] * np.exp(lam * t)  # (orders, 2n)
        w = (1j * self.omega) ** np.arange(orders) * (self.Z1 * np.exp(1j * self.omega * t))
        return (free @ self.U).real + np.column_stack([w.real, -w.imag])

    def mass1_derivatives(self, delta: float | complex, t: float | complex, orders: int = 3
                          ) -> tuple:
        """``x1(t)`` and its first ``orders - 1`` time derivatives after the impact at
        phase ``delta``. A complex ``t`` is a complex step: its imaginary part enters by
        the exact first-order term ``i Im(t) x1^(j+1)``."""
        e = self._phase(delta)
        if isinstance(t, complex) or np.iscomplexobj(t):
            t0, ht = float(np.real(t)), float(np.imag(t))
            rows = self.x1_rows(t0, orders + 1)
            rows = rows[:-1] + 1j * ht * rows[1:]
        else:
            rows = self.x1_rows(float(t), orders)
        return tuple(self.scale * (rows @ e))

    def mass1(self, delta: float | complex, t: float | complex) -> tuple:
        """``x1(t), x1'(t)`` along the flight after the impact at phase ``delta``."""
        return self.mass1_derivatives(delta, t, 2)

    def other_maximum(self, delta: float, exclude: float) -> float:
        """The highest interior maximum of ``x1`` other than the one at time ``exclude``
        (:func:`impactcont.orbit.general.x1_maximum`); ``-inf`` when there is none."""
        return general.x1_maximum(self.flow, self.state(delta), delta, self.T, exclude)[0]

    def cs_derivative(self, which: str) -> tuple[float, float]:
        """Exact ``dc, ds`` in ``which`` (``"omega"``, ``"R"``) from these pieces."""
        return general.amplitude_derivative(self.flow, self.S, self.DPhi, self.T, which)

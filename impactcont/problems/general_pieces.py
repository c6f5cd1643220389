"""The pieces of the codim-1 curve systems on the first-order path (any C, complex F).

:class:`GeneralPieces` has the interface of the modal pieces of
:mod:`impactcont.problems.closed_form_curve` (``S0``, ``T``, ``b``, ``impact_velocity``,
``jacobian``, ``split``, ``pd_condition``, ``pole_free_pd_matrix``, ``mass1``,
``other_maximum``, ``stepped``), built from eq. (12)-(14) in the impact's rank-one form
(:class:`impactcont.orbit.general.PeriodicForm`, on the exact flow
:class:`impactcont.orbit.flow.GeneralFlow`). With ``e = [cos delta, sin delta]`` and
the impact velocity ``sigma`` every quantity that depends on the impact phase is
``P e + kappa sigma q`` with real pieces ``P``, ``q`` of the frequency:

- ``X(0) = P0 e + kappa sigma y`` (eq. 12-13), ``c, s = S[0]`` (eq. 14);
- ``sigma = x1'(T^-)`` (``h2``, eq. 22) from the better of its two exact forms,
  ``x1p'(delta) / Delta`` or the impact condition ``(x1p(delta) - b) / (kappa g)``, chosen
  once per parameter pair (:func:`impact_condition_form`): far above the lowest natural
  frequency (``|c, s| >> b``) the first cancels, and so does ``S e`` for the state;
- ``[h1; H1] = D E(T) [-sin delta; cos delta] = J1 e`` (eq. 23-25);
- ``[h2; H2] = D X'(T^-)`` with ``X'(T^-) = P'(0) e + kappa sigma A (y + e_{n+1})``
  and ``h2 = sigma`` itself;
- ``G = G_reg + a b^T / h2`` (eq. 25) with ``G_reg = [[H0, H1], [0, 1]]``,
  ``a = [-H2; -omega]``, ``b = [h0'; h1]`` and ``[h0'; H0] = D Phi(T)`` without its
  first column, as in :func:`impactcont.orbit.dense.impact_map_jacobian`;
- ``x1^(j)(t) = [Re w_j, -Im w_j] e + kappa sigma Re(sum_k lambda_k^j e^{lambda_k t}
  V_1k (V^-1 y)_k)``, ``w_j = (i omega)^j Z_1 e^{i omega t}`` (eq. 9, first order).

Why the Jacobian is not one complex step per column here
--------------------------------------------------------
The modal path differentiates its residual by complex steps of the parameters
through the compiled kernel. Here the free flow is ``Phi(T) = Re(V e^{Lambda T}
V^-1)``: a complex step of ``omega`` (through ``T``) is discarded by the real part,
and evaluating ``V e^{Lambda T} V^-1`` in complex arithmetic without it leaves an
imaginary part of rounding size that swamps a step of ``1e-30``. What stays exact:

- ``delta`` and the extra unknowns: everything above is real pieces applied to
  ``e`` and ``sigma`` (no complex arithmetic after them), so the complex step of the
  residual in ``delta`` is exact, as on the modal path; the grazing time ``t*`` enters
  through ``x1^(j)(t*)``, whose complex step is its exact first-order Taylor term
  ``i h x1^(j+1)(t*)``; NS gives its ``theta, v`` columns in closed form;
- ``b``: it enters eq. (14), the grazing condition and the impact condition, linearly;
- ``F0``: the forced pieces ``P0, P'(0), E(T)`` are proportional to the forcing
  amplitude and ``D Phi(T)``, ``y``, ``g``, ``Delta`` do not depend on it, so
  :meth:`GeneralPieces.stepped` scales the forced data by ``1 + i h / F0``: an exact
  complex step of every condition;
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
from impactcont.orbit.dense import VELOCITY_POLISH, pole_free_pd_matrix
from impactcont.orbit.flow import GeneralFlow
from impactcont.problems.periodic_branch import residual_scale

__all__ = ["STEPPED_PARAMETERS", "GeneralPieces", "bordered_condition",
           "impact_condition_form"]

STEPPED_PARAMETERS = ("b", "F0")
"""Parameters whose column :meth:`GeneralPieces.stepped` differentiates exactly."""

_EPS = float(np.finfo(float).eps)


def impact_condition_form(Gam: float, B: float, g: float, Delta: float, omega: float,
                          R: float, b: float) -> bool:
    """Whether the curve systems take the impact velocity from the impact condition at
    one parameter pair (:func:`impactcont.orbit.dense.impact_velocity`: its two exact
    forms ``x1p'(delta) / Delta`` and ``(x1p(delta) - b) / (kappa g)``).

    A curve needs one form for all phases of a parameter pair (its residual is
    differentiated in the phase, and the two forms agree only on eq. 14), so the choice
    uses the phase-independent bounds of :func:`impactcont.orbit.dense.velocity_errors`
    (``|cos|, |sin| <= 1``, ``|delta| <= pi``): the first form errs by at most
    ``eps (2 + pi) omega (|Gam| + |B|) / |Delta|``, the second by ``eps (2 + pi)`` times
    the size of its terms, ``(|Gam| + |B| + |b|) / |kappa g|``, which also bounds the
    velocity. The second is taken where the first may lose more than
    :data:`~impactcont.orbit.dense.VELOCITY_POLISH` of that size: where
    ``|rho| = |kappa omega g / Delta|`` exceeds about 900 (far above the lowest natural
    frequency, ``|c, s| >> b``), and for elastic impacts without damping
    (``Delta = 0``, where the kernel uses it too). Elsewhere (the paper's system has
    ``|rho| < 80`` on ``omega`` in [0.5, 6]) the first.
    """
    terms = abs(Gam) + abs(B)
    size = (terms + abs(b)) / abs((1.0 + R) * g) if g != 0.0 else math.inf
    first = _EPS * (2.0 + math.pi) * omega * terms / abs(Delta) if Delta != 0.0 else math.inf
    return bool(first > VELOCITY_POLISH * size)


def bordered_condition(E: np.ndarray, left: np.ndarray, right: np.ndarray) -> float | complex:
    """``g``: the last component of ``[[E, left], [right^T, 0]] [q; g] = [0; 1]`` (the
    pole-free period-doubling condition of
    :class:`~impactcont.problems.closed_form_curve.PeriodDoublingCurve`; NaN when singular)."""
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
    form: general.PeriodicForm
    """Eq. (12)-(14) in the impact's rank-one form at this pair."""
    T: float
    """``2 pi N / omega``."""
    DPhi: np.ndarray
    """``D Phi(T)`` (eq. 12), (2n, 2n)."""
    S: np.ndarray
    """``X(0) = S e`` (eq. 13), (2n, 2), times :attr:`forcing`: its first row is ``c, s``."""
    J1: np.ndarray
    """``[h1; H1] = J1 e``, (2n, 2), times :attr:`forcing`."""
    Z1: complex
    """``Z_1`` of the forced state (the complex amplitude of ``x1``)."""
    b: float | complex
    omega: float
    forcing: float | complex = 1.0
    """``1 + i h / F0`` along the complex step of ``F0``: multiplies the forced data."""
    scale: float | complex = 1.0
    """:func:`~impactcont.problems.periodic_branch.residual_scale` of eq. (14) (complex
    along the complex step of ``F0``, where it is not 1)."""
    impact_form: bool = False
    """The impact velocity from the impact condition (:func:`impact_condition_form`)."""

    @classmethod
    def at(cls, osc: ImpactOscillator, N: int) -> GeneralPieces:
        """The real pieces of `osc`."""
        form = general.periodic_form(osc, N)  # eq. (12)-(14)
        n = osc.n
        d = np.ones(2 * n)
        d[n] = -osc.R
        J1 = d[:, None] * np.column_stack([form.E[:, 1], -form.E[:, 0]])  # E [-sin, cos]
        Gam, B = form.P0[0].tolist()
        return cls(osc=osc, N=N, flow=form.flow, form=form, T=float(form.T), DPhi=form.DPhi,
                   S=form.S, J1=J1, Z1=complex(form.flow.Z[0]), b=osc.b, omega=osc.omega,
                   scale=residual_scale(form.c, form.s),
                   impact_form=impact_condition_form(Gam, B, form.g, form.Delta, osc.omega,
                                                     osc.R, osc.b))

    def stepped(self, name: str | None, h: float) -> GeneralPieces:
        """These pieces in complex arithmetic with `name` moved to ``p + i h`` (exact).

        ``name`` is None (nothing moves: the caller steps the phase or an extra
        unknown), ``"b"`` or ``"F0"`` (:data:`STEPPED_PARAMETERS`; the forced data
        scale with ``F0``, ``D Phi(T)`` does not).
        """
        b = complex(self.b)
        forcing = 1.0 + 0.0j
        if name == "b":
            b += 1j * h
        elif name == "F0":
            forcing = complex(1.0, h / self.osc.F0)
        elif name is not None:
            raise ValueError(f"name must be None or one of {STEPPED_PARAMETERS}; got {name!r}")
        S = self.S * forcing
        scale = self.scale if self.scale == 1.0 else residual_scale(S[0, 0], S[0, 1])
        return dataclasses.replace(self, S=S, J1=self.J1 * forcing, b=b, forcing=forcing,
                                   scale=scale)

    # -- eq. (12)-(15) ----------------------------------------------------------------------------
    @property
    def S0(self) -> tuple[float, float]:
        """``c, s`` of eq. (14) (the first row of S, eq. 13)."""
        return self.S[0, 0], self.S[0, 1]

    @staticmethod
    def _phase(delta: float | complex) -> np.ndarray:
        return np.array([np.cos(delta), np.sin(delta)])

    def impact_velocity(self, delta: float | complex) -> float | complex:
        """``h2 = x1'(T^-)`` of the motion with impact phase ``delta`` (eq. 22), from the
        form of :attr:`impact_form`."""
        form = self.form
        e = self._phase(delta)
        if self.impact_form:  # the impact condition x1(0) = b
            return (self.forcing * (form.P0[0] @ e) - self.b) / ((1.0 + self.osc.R) * form.g)
        return self.forcing * (form.P0[self.osc.n] @ e) / form.Delta  # x1p'(delta) / Delta

    def state(self, delta: float | complex) -> np.ndarray:
        """``X(0) = P0 [cos delta, sin delta] + kappa sigma y`` right after the impact
        (eq. 13, :class:`~impactcont.orbit.general.PeriodicForm`)."""
        sigma = self.impact_velocity(delta)
        return (self.forcing * (self.form.P0 @ self._phase(delta))
                + (1.0 + self.osc.R) * sigma * self.form.y)

    # -- G, eq. (22)-(25) -------------------------------------------------------------------------
    def split(self, delta: float | complex
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | complex]:
        """G of eq. (25) as ``(G_reg, a, b, h2)``, ``G = G_reg + a b^T / h2``, every piece
        finite where ``h2`` vanishes; ``h2`` is the motion's impact velocity."""
        form, osc = self.form, self.osc
        e = self._phase(delta)
        sigma = self.impact_velocity(delta)
        d = np.ones(2 * osc.n)
        d[osc.n] = -osc.R
        dE = self.J1 @ e
        dX = d * (self.forcing * (form.rate0 @ e) + (1.0 + osc.R) * sigma * form.rate)
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
        return G_reg, a, b, sigma

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
        return bordered_condition(self.pole_free_pd_matrix(delta), left, right)

    # -- x1 along the flight ------------------------------------------------------------------
    def _x1_parts(self, t: float, orders: int) -> tuple[np.ndarray, np.ndarray]:
        """``x1^(j)(t) = forced_j [cos delta, sin delta] + kappa sigma free_j``, ``j < orders``:
        ``forced`` (orders, 2) and ``free`` (orders,), real, without :attr:`forcing`."""
        lam = self.flow.lam
        powers = lam[None, :] ** np.arange(orders)[:, None] * np.exp(lam * t)  # (orders, 2n)
        free = (powers @ (self.flow.V[0] * self.form.y_modal)).real
        w = (1j * self.omega) ** np.arange(orders) * (self.Z1 * np.exp(1j * self.omega * t))
        return np.column_stack([w.real, -w.imag]), free

    def mass1_derivatives(self, delta: float | complex, t: float | complex, orders: int = 3
                          ) -> tuple:
        """``x1(t)`` and its first ``orders - 1`` time derivatives after the impact at
        phase ``delta``. A complex ``t`` is a complex step: its imaginary part enters by
        the exact first-order term ``i Im(t) x1^(j+1)``."""
        e = self._phase(delta)
        if isinstance(t, complex) or np.iscomplexobj(t):
            t0, ht = float(np.real(t)), float(np.imag(t))
            forced, free = self._x1_parts(t0, orders + 1)
            forced = forced[:-1] + 1j * ht * forced[1:]
            free = free[:-1] + 1j * ht * free[1:]
        else:
            forced, free = self._x1_parts(float(t), orders)
        ks = (1.0 + self.osc.R) * self.impact_velocity(delta)
        return tuple(self.forcing * (forced @ e) + ks * free)

    def mass1(self, delta: float | complex, t: float | complex) -> tuple:
        """``x1(t), x1'(t)`` along the flight after the impact at phase ``delta``."""
        return self.mass1_derivatives(delta, t, 2)

    def other_maximum(self, delta: float, exclude: float) -> float:
        """The highest interior maximum of ``x1`` other than the one at time ``exclude``
        (the search of :func:`impactcont.orbit.general.x1_maximum` on the free part
        ``kappa sigma V^-1 y``, as :func:`impactcont.orbit.general.orbit_values`);
        ``-inf`` when there is none."""
        ks = (1.0 + self.osc.R) * self.impact_velocity(delta)
        return general._x1_maximum_of(self.flow, self.flow.V[0] * self.form.y_modal * ks,
                                      delta, self.T, exclude)[0]

    def cs_derivative(self, which: str) -> tuple[float, float]:
        """Exact ``dc, ds`` in ``which`` (``"omega"``, ``"R"``) from these pieces."""
        return general.amplitude_derivative(self.flow, self.form.S, self.DPhi, self.T, which)

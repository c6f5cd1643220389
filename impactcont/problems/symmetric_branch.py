"""The branch of symmetric N-p motions: the half-motion closed by the reflection.

A symmetric motion of a symmetric two-sided system (:mod:`impactcont.orbit.symmetry`)
is fixed by its first half: ``v = [delta, tau_0..tau_{h-2}, z_0..z_{h-1}]`` with
the full unknowns ``u = E v + e(omega)`` (:class:`~impactcont.orbit.symmetry.HalfUnknowns`).
The full shooting residual at such a ``u`` is equivariant (``r_{k+h} = -r_k``), so
its first ``h`` blocks,

    r_k = D_{k+1} X_k^- - X_{k+1}  (k < h - 1),     r_{h-1} = D_h X_{h-1}^- + X_0,

are the whole system: ``F(v, lam) = r_{0..h-1}(E v + e, lam)``, with the exact
``dF/dv = J_{0..h-1} E`` and ``dF/dlam`` from the full problem (plus the column of
``tau_{h-1}`` times ``de/domega`` in omega). Unlike the full system it is regular
at the symmetry-breaking pitchfork (the null vector of the full Jacobian there is
antisymmetric), so the branch is followed through it and the pitchfork located on
it like any other special point. Parameters that keep the system symmetric
(:attr:`~impactcont.model.parameters.ModelParameter.keeps_symmetry`): ``omega``, ``F0``,
the damping and every element, ``gap`` (both stops), and ``b`` and ``R`` of mirrored stops
(``Stops(mirror=True)``; otherwise they move only the upper stop, as ``b_low`` and
``R_low`` move only the lower one).
"""

from __future__ import annotations

import copy
import functools
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from impactcont.core.locate import MotionTest
from impactcont.core.stepper import CorrectorResult
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import FREQUENCY, ModelParameter
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import (
    MultiImpactOrbit,
    _geometry,
    impact_sequence,
    shot_flights,
)
from impactcont.orbit.symmetry import HalfUnknowns, _reflection, admits_symmetric_motions
from impactcont.problems.events import BRANCH_TESTS, PITCHFORK
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.vocabulary import Label

__all__ = ["SymmetricBranchProblem"]

#: Named parameters that move one stop only unless the stops are mirrored (``b``, ``R``)
#: or always (``b_low``, ``R_low``). Kept for the stability maps' check; a problem asks the
#: parameter (:attr:`~impactcont.model.parameters.ModelParameter.keeps_symmetry`).
SYMMETRY_BREAKING = ("b", "R", "b_low", "R_low")


def _flight_data(osc: ImpactOscillator) -> tuple[np.ndarray, np.ndarray]:
    """``A = [[0, I], [-M^-1 K, -M^-1 C]]`` of the flight ``X' = A X + B f`` and ``M^-1 F``
    (the forcing of ``B f = [0; M^-1 F cos(phi)]``), as the half-map's kernel takes them."""
    n = osc.n
    Minv = np.linalg.inv(np.asarray(osc.M, dtype=float))
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -Minv @ np.asarray(osc.K, dtype=float)
    A[n:, n:] = -Minv @ np.asarray(osc.C, dtype=float)
    return A, np.ascontiguousarray(Minv @ np.real(np.asarray(osc.F)), dtype=float)


def _half_map_kernel() -> Any:
    """:mod:`impactcont.kernel.half_map`, imported on first use (numba is not imported with
    :mod:`impactcont`)."""
    from impactcont.kernel import half_map

    return half_map


def _of_full(name: str, doc: str) -> property:
    """A read-only attribute of :class:`SymmetricBranchProblem`: that of its full problem."""
    return property(lambda self: getattr(self.full, name),
                    doc=f"{doc} That of the full problem (:attr:`SymmetricBranchProblem.full`).")


class SymmetricBranchProblem:
    """Symmetric N-p motions as ``F(v, lam) = 0`` for the continuation core.

    Parameters
    ----------
    osc : ImpactOscillator
        A symmetric system (``b_low == b``, ``R_low == R``).
    N, p : int
        ``N`` odd, ``p`` even.
    parameter : str
        Continued parameter, one that keeps the system symmetric (``b`` or ``R`` only with
        mirrored stops, else they move one stop only; ``gap`` moves both).
    pattern : str
        The stops of the p impacts; its second half mirrors the first.

    Attributes
    ----------
    full : MultiImpactBranchProblem
        The full shooting system of the motion (its orbits, G, checks).
    halves : HalfUnknowns
        The map between the half and the full unknowns.
    symmetric : bool
        Always True: detection adds the pitchfork test (BP) on such a branch.
    """

    symmetric = True
    separate_checks = True
    impact_dimension = True
    #: The kind of a located fold, as on any N-p branch.
    fold_kind = staticmethod(MultiImpactBranchProblem.fold_kind)
    #: The kinds of special points located on its branches: those of any N-p motion and BP.
    events: tuple[Label, ...] = (*MultiImpactBranchProblem.events, Label.BP)
    #: The tests of its kinds: those of any N-p motion and its own, BP.
    motion_tests: ClassVar[Mapping[str, MotionTest]] = MappingProxyType(
        {**BRANCH_TESTS, Label.BP: PITCHFORK})

    def __init__(self, osc: ImpactOscillator, N: int, p: int, parameter: str,
                 pattern: str) -> None:
        self.full = MultiImpactBranchProblem(osc, N, p, parameter, pattern=pattern)
        if not self.full.param.keeps_symmetry:
            raise ParameterError(f"parameter {parameter!r} moves one stop only and breaks the "
                                 "symmetry: continue symmetric motions in another parameter "
                                 "('gap' moves both stops), mirror the stops (Stops(mirror="
                                 "True): the lower stop moves with b and R), or follow the "
                                 "motion as an N-p motion (symmetric=False)")
        if not admits_symmetric_motions(osc, self.full.N, self.full.p, self.full.pattern):
            raise ParameterError(
                f"the N={N}, p={p} motions with pattern {self.full.pattern!r} of {osc!r} cannot "
                "be symmetric: that needs N odd, p even, the second half of the pattern the "
                "mirror of the first (UL, UULL, ...), and b_low == b, R_low == R")
        self.halves = HalfUnknowns(osc.n, self.full.p, self.full.N)
        self._E = self.halves.embedding
        self.size = self.halves.size
        self._S = _reflection(osc.n)[:, None]  # S of the half-map, in the section coordinates
        self._last_full: tuple[tuple[bytes, float], np.ndarray] | None = None
        #: ``-e(1)``: ``u = E v + offset / omega`` in the compiled corrector (:meth:`palc_step`)
        self._offset = -self.halves.offset_derivative(1.0)

    @functools.cached_property
    def _flight(self) -> tuple[np.ndarray, np.ndarray]:
        """A and M^-1 F of a flight (:func:`_flight_data`, for :meth:`half_map_derivative`:
        made on its first use). M, K, C, F are the same at every omega and stop position:
        moved problems share them."""
        return _flight_data(self.osc)

    # -- what the full problem says -------------------------------------------------------------
    osc = _of_full("osc", "The oscillator.")
    N = _of_full("N", "Forcing periods of the full motion.")
    p = _of_full("p", "Impacts of the full motion.")
    pattern = _of_full("pattern", "The stop of each impact of the full motion.")
    parameter = _of_full("parameter", "The continued parameter's name.")
    param = _of_full("param", "The continued parameter as an object.")

    def parameter_limits(self) -> tuple[float, float]:
        """As :meth:`MultiImpactBranchProblem.parameter_limits`."""
        return self.full.parameter_limits()

    def limit_reason(self) -> str:
        """As :meth:`MultiImpactBranchProblem.limit_reason`."""
        return self.full.limit_reason()

    def check_bounds(self, bounds: tuple[float, float]) -> None:
        """As :meth:`MultiImpactBranchProblem.check_bounds`."""
        self.full.check_bounds(bounds)

    def flow_at(self, lam: float) -> Flow:
        """The flow of the oscillator with ``parameter = lam``."""
        return self.full.flow_at(lam)

    def oscillator_at(self, lam: float) -> ImpactOscillator:
        """The oscillator with ``parameter = lam``."""
        return self.full.oscillator_at(lam)

    # -- the map between the unknowns -------------------------------------------------------------
    def full_unknowns(self, v: np.ndarray, lam: float) -> np.ndarray:
        """The full shooting unknowns of the symmetric motion `v` at ``lam``.

        Notes
        -----
        The last one is kept (a copy is returned): the residual, the Jacobian,
        ``dF/dlam`` and the test functions of one iterate ask for the same ``u``.
        """
        v = np.asarray(v, dtype=float)
        if v.shape != (self.size,):
            raise ParameterError(f"v must have shape ({self.size},) = (2 n p/2,); got {v.shape}")
        key = (v.tobytes(), float(lam))
        if self._last_full is None or self._last_full[0] != key:
            self._last_full = key, self.halves.full(v, self.oscillator_at(lam).omega)
        return self._last_full[1].copy()

    def half_unknowns(self, u: np.ndarray) -> np.ndarray:
        """The half unknowns of the full unknowns `u` of a symmetric motion."""
        return self.halves.half(u)

    # -- the Problem protocol ------------------------------------------------------------------
    def _rows(self) -> slice:
        return slice(0, self.size)

    def residual(self, v: np.ndarray, lam: float) -> np.ndarray:
        """``r_0 .. r_{h-1}`` of the full system at ``E v + e``, shape (2nh,)."""
        return self.full.residual(self.full_unknowns(v, lam), lam)[self._rows()]

    def jacobian(self, v: np.ndarray, lam: float) -> np.ndarray:
        """``dF/dv = J_{0..h-1} E``, exact, shape (2nh, 2nh)."""
        return self.full.jacobian(self.full_unknowns(v, lam), lam)[self._rows()] @ self._E

    def dparam(self, v: np.ndarray, lam: float) -> np.ndarray:
        """``dF/dlam`` at fixed ``v``, shape (2nh,)."""
        u = self.full_unknowns(v, lam)
        out = self.full.dparam(u, lam)[self._rows()]
        if self.full.param.data == FREQUENCY:  # tau_{h-1} = N pi / omega - ...
            rows = self.full.jacobian(u, lam)[self._rows()]
            out = out + rows @ self.halves.offset_derivative(float(lam))
        return out

    def moved(self, osc: ImpactOscillator) -> SymmetricBranchProblem:
        """This problem on `osc` (:meth:`MultiImpactBranchProblem.moved`; `osc` must stay
        symmetric, as the parameters of a curve of symmetric motions keep it)."""
        new = copy.copy(self)
        new.full = self.full.moved(osc)
        new._last_full = None
        return new

    def derivative(self, v: np.ndarray, lam: float, param: ModelParameter) -> np.ndarray:
        """``dF/dmu`` at fixed ``v`` for another parameter ``mu`` of the frequency or the
        stops (:meth:`MultiImpactBranchProblem.derivative`), shape (2nh,)."""
        u = self.full_unknowns(v, lam)
        out = self.full.derivative(u, lam, param)[self._rows()]
        if param.data == FREQUENCY:  # tau_{h-1} = N pi / omega - ...
            omega = self.oscillator_at(lam).omega
            rows = self.full.jacobian(u, lam)[self._rows()]
            out = out + rows @ self.halves.offset_derivative(omega)
        return out

    def linearize(self, v: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """The residual and ``[dF/dv | dF/dlam]`` at ``(v, lam)`` from one evaluation of the
        full system (:meth:`MultiImpactBranchProblem.linearize`), shapes (2nh,), (2nh, 2nh + 1).
        """
        u = self.full_unknowns(v, lam)
        residual, extended = self.full.linearize(u, lam)
        size = self.size
        rows = extended[:size]
        out = np.empty((size, size + 1))
        np.matmul(rows[:, :-1], self._E, out=out[:, :size])
        out[:, size] = rows[:, -1]
        if self.full.param.data == FREQUENCY:  # tau_{h-1} = N pi / omega - ...
            out[:, size] += rows[:, :-1] @ self.halves.offset_derivative(float(lam))
        return residual[:size], out

    def half_map(self, v: np.ndarray, lam: float) -> np.ndarray:
        """``H = S G_{h-1} .. G_0`` of the symmetric motion `v` at ``lam``
        (:func:`~impactcont.orbit.symmetry.half_map`, from one compiled call on the shot)."""
        A = self.full.jacobian_product(self.full_unknowns(v, lam), lam, self.p // 2)
        return self._S * A

    def half_map_derivative(self, v: np.ndarray, lam: float, dv: np.ndarray,
                            dc: np.ndarray, domega: np.ndarray | None = None
                            ) -> tuple[np.ndarray, np.ndarray]:
        """``H`` (:meth:`half_map`) and its derivatives along `d` directions, exactly.

        Parameters
        ----------
        v : ndarray, shape (size,)
            The half unknowns.
        lam : float
            The continued parameter (its derivative is not one of these directions).
        dv : ndarray, shape (d, size)
            Each direction's change of the half unknowns.
        dc : ndarray, shape (d, p)
            Each direction's change of the stops' positions ``c_k`` at the p impacts (a
            parameter's :meth:`~impactcont.model.parameters.ModelParameter.stop_rates`).
        domega : ndarray, shape (d,), optional
            Each direction's change of omega (the problem's parameter: the problem must be
            in omega); none by default.

        Returns
        -------
        H : ndarray, shape (2n, 2n)
        dH : ndarray, shape (d, 2n, 2n)

        Notes
        -----
        From the shot of the point alone: ``H = S G_{h-1} .. G_0`` (eq. 25) is a rational
        function of each flight's transition ``Phi_k = e^{A tau_k}``, phase column
        ``dX_k^-/dtheta_k`` and arrival rate ``X_k'^-`` (the impact matrices and normals stay),
        and these move exactly with the flight's start ``X_k`` (from ``z_k`` and ``c_k`` on
        the section), phase ``theta_k`` and time ``tau_k``:
        ``dPhi = A Phi dtau``, ``d(dX^-/dtheta) = (A dX^-/dtheta + B f') dtau - X_f dtheta``
        (the forced part ``X_f = X^- - Phi X_0`` of harmonic forcing ``Re(F e^{i phi})``,
        whose second derivative in the phase is ``-X_f``) and
        ``dX'^- = A dX^- + B f' (dtheta + omega dtau)``, ``f' = Re(i F e^{i phi})`` at the
        arrival ``phi = theta + omega tau``. In omega at fixed ``v`` the flights move
        besides through ``e(omega)`` (``tau_{h-1}``), the phases ``theta_k`` and their forced
        parts at fixed start, phase and time (:meth:`~impactcont.orbit.flow.Flow.
        omega_partial`, and its phase derivative: the same a quarter period on, the forced
        part being harmonic in the phase), and ``G_k``'s last row in omega itself.
        ``dH`` is the derivative of that rational function along them, forward mode in one
        compiled call (:func:`impactcont.kernel.half_map.jacobian_product_derivative`);
        ``H`` is :meth:`half_map`'s, operation for operation.

        A symmetric system has no constant force (the reflection would not map it to
        itself), so the forced part is harmonic.

        Raises
        ------
        ParameterError
            The problem is not in omega, or its flow is not modal; `dv` or `dc` of another
            shape.
        """
        full = self.full
        if full._base_flow is None:
            raise ParameterError(f"half_map_derivative: a problem in {self.parameter!r} on "
                                 f"{self.osc!r}; it needs the modal flow of a problem in omega "
                                 "(no damping matrix outside the paper's form): take "
                                 "differences of half_map instead")
        u = self.full_unknowns(v, lam)
        sh = full.shot(u, lam)
        flow = full.flow_at(lam)
        m = 2 * self.osc.n
        dv = np.atleast_2d(np.asarray(dv, dtype=float))
        d = dv.shape[0]
        dc = np.ascontiguousarray(np.atleast_2d(np.asarray(dc, dtype=float)))
        dw = (np.zeros(d) if domega is None
              else np.ascontiguousarray(np.asarray(domega, dtype=float).reshape(d)))
        if dv.shape != (d, self.size) or dc.shape != (d, self.p):
            raise ParameterError(f"half_map_derivative: dv must have shape (d, {self.size}) and "
                                 f"dc (d, {self.p}); got {dv.shape} and {dc.shape}")
        du = dv @ self._E.T  # (d, 2np): the full unknowns' change, with e(omega)'s
        du += dw[:, None] * self.halves.offset_derivative(float(lam))
        A, forcing_rate = self._flight
        dH = np.empty((d, m, m))
        H = _half_map_kernel().jacobian_product_derivative(
            tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
            tuple(flow.omega_arrays()), tuple(impact_sequence(_geometry(flow, full.pattern))),
            tuple(shot_flights(sh)), A, forcing_rate, du, dc, dw, self.p // 2, dH)
        return self._S * H, self._S * dH

    def palc_step(self, predicted: np.ndarray, tangent: np.ndarray, weights: np.ndarray,
                  tol: float, max_iter: int, *, hyperplane: bool = False
                  ) -> CorrectorResult | None:
        """The core's corrector and tangent of one step, compiled, on the half system
        (:meth:`MultiImpactBranchProblem.palc_step` with ``u = E v + e(omega)``)."""
        if self.full._base_flow is None:
            return None
        return self.full._palc_step(predicted, tangent, weights, tol, max_iter,
                                    self._E, self._offset, self.size, hyperplane)

    def orbit(self, v: np.ndarray, lam: float, *, checks: bool = True) -> MultiImpactOrbit:
        """The full symmetric N-p motion (states, G, multipliers, checks) at ``(v, lam)``."""
        return self.full.orbit(self.full_unknowns(v, lam), lam, checks=checks)

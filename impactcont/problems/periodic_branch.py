"""The branch of periodic N-1 motions as a curve for the continuation core.

Eq. (14) written as ``r(delta, lam) = c(lam) cos(delta) + s(lam) sin(delta) - b(lam) = 0``
is a smooth curve in ``(delta, lam)``; its two roots of eq. (15) meet at
folds (``c^2 + s^2 = b^2``), where the curve simply turns, so pseudo-arclength
continuation goes round them.
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.errors import ParameterError
from impactcont.model.modal import DAMPING_PARAMETERS, decay_rate_derivative
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import require_paper_stops
from impactcont.orbit import general
from impactcont.orbit.periodic import PeriodicOrbit, orbit_at_phase
from impactcont.vocabulary import CONTINUABLE_PARAMETERS, check_parameter

__all__ = ["CONTINUABLE_PARAMETERS", "PeriodicBranchProblem"]

_KERNEL_WHICH = {"omega": 0, "R": 1, "eta": 2, "alpha": 2, "beta": 2}


class PeriodicBranchProblem:
    """Eq. (14) as ``F(u, lam) = 0`` with ``u = [delta]`` and ``lam`` a model parameter.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator; its value of `parameter` is replaced by ``lam``.
    N : int
        One impact every N forcing periods.
    parameter : str
        One of :data:`CONTINUABLE_PARAMETERS`.

    Notes
    -----
    ``c, s`` (eq. 13) come from the compiled kernel in modal form (O(n) per
    parameter value, cached); when the parameter is the gap ``b`` they do not
    depend on it at all, and they are linear in the forcing amplitude ``F0``
    (eq. 13 is linear in F). Their parameter derivative is exact: one complex-step
    evaluation of the same kernel (no step-size error, no cancellation).
    """

    periods = (2.0 * math.pi,)
    """The unknown ``delta`` is a phase: a branch that returns to its start modulo 2 pi is
    a closed loop (read by the continuation driver)."""

    def __init__(self, osc: ImpactOscillator, N: int, parameter: str) -> None:
        check_parameter(osc, parameter)
        require_paper_stops(osc, "the N-1 branch")  # stops: mass 1, one stop only
        self.osc = osc
        self.N = N
        self.parameter = parameter
        self._general = osc.general  # general damping matrix or complex F: first-order path
        self._cache: dict[float, tuple[float, float, float]] = {}
        self._per_unit_force: tuple[float, float] | None = None  # c, s at F0 = 1
        self._osc_cache: dict[float, ImpactOscillator] = {}
        if self._general:
            return
        w, _, self._f, _, _, _, self._u0, self._ui0 = osc.modes.kernel_arrays
        self._w = w
        if parameter in DAMPING_PARAMETERS:
            self._da = decay_rate_derivative(parameter, w)
        else:
            self._da = np.zeros_like(w)

    # -- the oscillator along the branch ------------------------------------------------------
    def oscillator_at(self, lam: float) -> ImpactOscillator:
        """The oscillator with ``parameter = lam`` (sharing the modal basis)."""
        lam = float(lam)
        hit = self._osc_cache.get(lam)
        if hit is None:
            if len(self._osc_cache) > 64:
                self._osc_cache.clear()
            hit = self._osc_cache[lam] = self.osc.replace(**{self.parameter: lam})
        return hit

    def _arguments(self, lam: float) -> tuple:
        """Kernel arguments ``(a, R, omega)`` at ``lam``."""
        osc = self.osc
        a = osc.modes.kernel_arrays[1]
        R, omega = osc.R, osc.omega
        if self.parameter == "omega":
            omega = lam
        elif self.parameter == "R":
            R = lam
        elif self.parameter in DAMPING_PARAMETERS:
            current = float(getattr(osc, self.parameter) or 0.0)
            a = a + (lam - current) * self._da
        return a, R, omega

    def amplitude(self, lam: float) -> tuple[float, float, float]:
        """``c, s`` of eq. (14) and the gap ``b`` at ``lam``."""
        from impactcont.orbit import kernel

        lam = float(lam)
        hit = self._cache.get(lam)
        if hit is not None:
            return hit
        if self.parameter == "b" and self._cache:
            c, s, _ = next(iter(self._cache.values()))  # c, s do not depend on the gap
            value = (c, s, lam)
        elif self.parameter == "F0":
            self._check(lam)
            c, s = self._unit_amplitude()
            value = (c * lam, s * lam, self.osc.b)
        elif self._general:
            self._check(lam)
            c, s = general.amplitude(self.oscillator_at(lam), self.N)[:2]
            value = (c, s, lam if self.parameter == "b" else self.osc.b)
        else:
            self._check(lam)
            a, R, omega = self._arguments(lam)
            c, s = kernel.amplitude(self._w, a, self._f, self._u0, self._ui0, R, omega, self.N)
            value = (float(c), float(s), lam if self.parameter == "b" else self.osc.b)
        if len(self._cache) > 256:
            self._cache.clear()
        self._cache[lam] = value
        return value

    def _unit_amplitude(self) -> tuple[float, float]:
        """``c, s`` per unit forcing amplitude (``F0 = 1``, F of the same shape)."""
        from impactcont.orbit import kernel

        if self._per_unit_force is None and self._general:
            c, s = general.amplitude(self.osc, self.N)[:2]
            self._per_unit_force = (c / self.osc.F0, s / self.osc.F0)
        if self._per_unit_force is None:
            a, R, omega = self._arguments(self.osc.F0)
            c, s = kernel.amplitude(self._w, a, self._f, self._u0, self._ui0, R, omega, self.N)
            self._per_unit_force = (float(c) / self.osc.F0, float(s) / self.osc.F0)
        return self._per_unit_force

    def _check(self, lam: float) -> None:
        """Refuse an iterate where eq. (14) is undefined (the corrector then halves).

        ``c, s`` are analytic in R and the damping beyond their physical ranges, so a
        predictor may overshoot ``R = 1`` or ``eta = 0`` and the driver lands on the
        bound; only ``omega <= 0`` (no period), ``F0 <= 0`` and non-finite values are refused.
        """
        if not math.isfinite(lam) or (self.parameter in ("omega", "F0") and lam <= 0.0):
            raise ParameterError(f"{self.parameter}={lam!r} is outside its allowed range")

    def _amplitude_derivative(self, lam: float) -> tuple[float, float, float]:
        from impactcont.orbit import kernel

        if self.parameter == "b":
            return 0.0, 0.0, 1.0
        self._check(lam)
        if self.parameter == "F0":
            return (*self._unit_amplitude(), 0.0)
        if self._general:
            _, _, dc, ds = general.amplitude(self.oscillator_at(lam), self.N, self.parameter)
            return dc, ds, 0.0
        a, R, omega = self._arguments(float(lam))
        dc, ds = kernel.amplitude_derivative(self._w, a, self._f, self._u0, self._ui0, R, omega,
                                             self.N, _KERNEL_WHICH[self.parameter], self._da)
        return float(dc), float(ds), 0.0

    # -- the Problem protocol ------------------------------------------------------------------
    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``r = c cos(delta) + s sin(delta) - b`` (eq. 14), shape (1,)."""
        c, s, b = self.amplitude(lam)
        d = float(u[0])
        return np.array([c * math.cos(d) + s * math.sin(d) - b])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dr/d delta``, shape (1, 1)."""
        c, s, _ = self.amplitude(lam)
        d = float(u[0])
        return np.array([[-c * math.sin(d) + s * math.cos(d)]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dr/d lam``, shape (1,)."""
        dc, ds, db = self._amplitude_derivative(lam)
        d = float(u[0])
        return np.array([dc * math.cos(d) + ds * math.sin(d) - db])

    # -- what the branch carries ----------------------------------------------------------------
    def orbit(self, delta: float, lam: float) -> PeriodicOrbit:
        """The full periodic motion (state, G, multipliers, checks) at a branch point."""
        return orbit_at_phase(self.oscillator_at(lam), self.N, delta)

    def fold_residual(self, delta: float, lam: float) -> np.ndarray:
        """``[r, dr/d delta]``: both vanish at a fold (saddle-node) of the branch."""
        c, s, b = self.amplitude(lam)
        return np.array([c * math.cos(delta) + s * math.sin(delta) - b,
                         -c * math.sin(delta) + s * math.cos(delta)])

    def fold_jacobian(self, delta: float, lam: float) -> np.ndarray:
        """Jacobian of :meth:`fold_residual` in ``(delta, lam)``."""
        c, s, _ = self.amplitude(lam)
        dc, ds, db = self._amplitude_derivative(lam)
        cd, sd = math.cos(delta), math.sin(delta)
        return np.array([[-c * sd + s * cd, dc * cd + ds * sd - db],
                         [-c * cd - s * sd, -dc * sd + ds * cd]])

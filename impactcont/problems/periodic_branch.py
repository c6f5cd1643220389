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
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.flow import Flow
from impactcont.orbit.periodic import PeriodicOrbit, orbit_at_phase, periodic_matrix

__all__ = ["CONTINUABLE_PARAMETERS", "PeriodicBranchProblem"]

CONTINUABLE_PARAMETERS = ("omega", "b", "R", "eta", "alpha", "beta")
"""Model parameters a branch can be continued in."""

_FD_STEP = 1e-6
_DERIVATIVE_REUSE = 1e-5


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
    ``c, s`` (eq. 13) are computed once per parameter value and cached; when
    the parameter is the gap ``b`` they do not depend on it at all. The
    parameter derivative of ``c, s`` uses central differences (relative step
    1e-6), reused while the parameter moves by less than 1e-5 (relative), as
    within one corrector; it only steers the predictor and Newton, never the
    accuracy of a point, which is set by the residual.
    """

    def __init__(self, osc: ImpactOscillator, N: int, parameter: str) -> None:
        if parameter not in CONTINUABLE_PARAMETERS:
            raise ParameterError(f"parameter must be one of {CONTINUABLE_PARAMETERS}; "
                                 f"got {parameter!r}")
        if parameter in ("alpha", "beta") and osc.eta is not None:
            raise ParameterError(f"parameter={parameter!r} needs Rayleigh damping; the "
                                 f"oscillator uses eta={osc.eta!r}")
        if parameter == "eta" and osc.eta is None:
            raise ParameterError("parameter='eta' needs the paper's damping C = 2 eta K; the "
                                 "oscillator uses Rayleigh damping (alpha, beta)")
        _ = osc.modes  # computed once here, then shared by every replace() along the branch
        self.osc = osc
        self.N = N
        self.parameter = parameter
        self._cache: dict[float, tuple[ImpactOscillator, Flow, np.ndarray, np.ndarray]] = {}
        self._derivative_cache: tuple[float, tuple[float, float, float]] | None = None

    # -- the oscillator along the branch ------------------------------------------------------
    def oscillator_at(self, lam: float) -> ImpactOscillator:
        """The oscillator with ``parameter = lam``."""
        return self._pieces(lam)[0]

    def _pieces(self, lam: float) -> tuple[ImpactOscillator, Flow, np.ndarray, np.ndarray]:
        lam = float(lam)
        hit = self._cache.get(lam)
        if hit is not None:
            return hit
        osc = self.osc.replace(**{self.parameter: lam})
        flow = Flow(osc)
        if self.parameter == "b" and self._cache:
            _, _, S, DPhi = next(iter(self._cache.values()))  # c, s do not depend on the gap
        else:
            S, DPhi, _ = periodic_matrix(flow, self.N)
        if len(self._cache) > 64:
            self._cache.clear()
        self._cache[lam] = (osc, flow, S, DPhi)
        return self._cache[lam]

    def amplitude(self, lam: float) -> tuple[float, float, float]:
        """``c, s`` of eq. (14) and the gap ``b`` at ``lam``."""
        osc, _, S, _ = self._pieces(lam)
        return float(S[0, 0]), float(S[0, 1]), osc.b

    def _amplitude_derivative(self, lam: float) -> tuple[float, float, float]:
        if self.parameter == "b":
            return 0.0, 0.0, 1.0
        last = self._derivative_cache
        if last is not None and abs(lam - last[0]) <= _DERIVATIVE_REUSE * max(1.0, abs(lam)):
            return last[1]  # a chord step: Newton's iterates of one corrector stay this close
        value = self._difference_quotient(lam)
        self._derivative_cache = (lam, value)
        return value

    def _difference_quotient(self, lam: float) -> tuple[float, float, float]:
        h = _FD_STEP * max(1.0, abs(lam))
        if self.parameter in ("R", "eta", "alpha", "beta"):
            lo = max(lam - h, 0.0)
            hi = min(lam + h, 1.0) if self.parameter == "R" else lam + h
        else:
            lo, hi = lam - h, lam + h
        c1, s1, _ = self.amplitude(hi)
        c0, s0, _ = self.amplitude(lo)
        return (c1 - c0) / (hi - lo), (s1 - s0) / (hi - lo), 0.0

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
        osc, flow, S, DPhi = self._pieces(lam)
        return orbit_at_phase(osc, self.N, delta, flow=flow, S=S, DPhi=DPhi)

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

"""The branch of periodic N-p motions as a curve for the continuation core.

``F(u, lam) = 0`` is the shooting system of :mod:`impactcont.orbit.multi_impact`
(p flights with the exact flow of eq. 9, p impacts with the law of eq. 4) in
``u = [delta, tau_0..tau_{p-2}, z_0..z_{p-1}]`` (2np unknowns) and one model
parameter ``lam`` (a :class:`~impactcont.model.parameters.ModelParameter`). ``dF/du`` is
exact; ``dF/dlam`` is exact for the forcing frequency, the stops' positions and
restitutions (``omega``, ``b``, ``R``, ``b_low``, ``R_low``, ``gap``) and the forcing
amplitude (``F0``, ``F[j]``: the residual is affine in F); the damping and the elements
take the parameter's one finite-difference fallback
(:meth:`~impactcont.model.parameters.ModelParameter.difference`), where it only steers the
predictor and Newton.

With two stops (``osc.stops``) the impact sequence ``pattern`` says which stop
each impact hits; a parameter says how fast each stop moves with it
(:attr:`~impactcont.model.parameters.ModelParameter.upper`, ``lower``): ``b`` and ``R`` move
the upper stop only, unless the stops are mirrored (``Stops(mirror=True)``: the lower stop
at ``-b`` with ``R`` moves with them), ``b_low`` and ``R_low`` the lower one, ``gap`` both.
The upper stop must stay above the lower one: the problem is defined only where the
clearance ``b + b_low`` between the stops is open
(:meth:`MultiImpactBranchProblem.parameter_limits`).
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import FREQUENCY, GAP, RESTITUTION, model_parameter
from impactcont.model.stops import check_pattern
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import (
    MultiImpactOrbit,
    Shooting,
    check_impacts,
    impact_geometry,
    omega_partials,
    orbit_from_unknowns,
    shooting,
)
from impactcont.orbit.periodic import _check_N

__all__ = ["MultiImpactBranchProblem"]

_CACHE_SIZE = 64


class MultiImpactBranchProblem:
    """The N-p shooting system as ``F(u, lam) = 0`` for the continuation core.

    `osc`, `N` and `parameter` are those of
    :class:`~impactcont.problems.PeriodicBranchProblem` (`parameter` is replaced by
    ``lam``); the motion has `p` impacts in its N forcing periods, impact k on the
    stop ``pattern[k]`` (``"U"``/``"L"``, all ``"U"`` by default).

    Notes
    -----
    The shooting system at the last few ``(u, lam)`` is cached, so that the
    residual, Jacobian and orbit of one point are computed from one shot.
    """

    #: The special points located on its branches (a symmetric motion's problem adds BP).
    events: tuple[str, ...] = ("SN", "PD", "NS", "GR", "ZV")

    def __init__(self, osc: ImpactOscillator, N: int, p: int, parameter: str,
                 pattern: str | None = None) -> None:
        if not isinstance(osc, ImpactOscillator):
            raise TypeError(f"osc must be an ImpactOscillator; got {type(osc).__name__}")
        self.param = model_parameter(osc, parameter)
        self.osc = osc
        self.N = _check_N(N)
        self.p = check_impacts(p)
        self.pattern = check_pattern(pattern, self.p, osc.stops)
        self.parameter = parameter
        self.size = 2 * osc.n * self.p
        self._flows: dict[float, Flow] = {}
        self._shots: dict[tuple[bytes, float], Shooting] = {}

    # -- where the parameter may go -----------------------------------------------------------
    def parameter_limits(self) -> tuple[float, float]:
        """Open interval of the parameter in which the stops exist as given.

        A parameter that moves a stop of a two-sided system must keep the upper stop
        ``x_j = b`` above the lower one ``x_j = -b_low`` (``b > -b_low``; ``b > 0`` for
        mirrored stops, ``gap > 0``, ``b_low > -b``:
        :meth:`~impactcont.model.parameters.ModelParameter.clearance_limit`). Every other
        case is unlimited here (a parameter's own range, e.g. ``R`` in [0, 1], is checked
        by the oscillator).

        Returns
        -------
        (float, float)
            ``(lower, upper)``, either possibly infinite.
        """
        return self.param.clearance_limit(self.osc), math.inf

    def limit_reason(self) -> str:
        """Why the parameter cannot reach :meth:`parameter_limits` ("" when unlimited)."""
        lower, _ = self.parameter_limits()
        if not math.isfinite(lower):
            return ""
        stops = self.osc.stops
        return (f"at {self.parameter} = {lower!r} the upper stop x_{stops.mass} = b meets the "
                f"lower stop x_{stops.mass} = -b_low (b={self.osc.b!r}, stops={stops!r}): the "
                "clearance b + b_low between them closes")

    def check_bounds(self, bounds: tuple[float, float]) -> None:
        """Refuse bounds that reach beyond :meth:`parameter_limits`.

        Raises
        ------
        ParameterError
            Naming the parameter, the bounds, the limit and the stops.
        """
        lower, upper = self.parameter_limits()
        lo, hi = (float(v) for v in bounds)
        if lo <= lower or hi >= upper:
            raise ParameterError(
                f"bounds ({lo!r}, {hi!r}) of parameter {self.parameter!r} reach "
                f"{self.parameter} = {lower!r}: {self.limit_reason()}; give bounds with "
                f"{self.parameter} > {lower!r}")

    # -- the oscillator along the branch ------------------------------------------------------
    def flow_at(self, lam: float) -> Flow:
        """The flow of the oscillator with ``parameter = lam``."""
        lam = float(lam)
        flow = self._flows.get(lam)
        if flow is None:
            if len(self._flows) > _CACHE_SIZE:
                self._flows.clear()
            flow = self._flows[lam] = Flow(self.param.at(self.osc, lam))
        return flow

    def oscillator_at(self, lam: float) -> ImpactOscillator:
        """The oscillator with ``parameter = lam``."""
        return self.flow_at(lam).osc

    def _shoot(self, u: np.ndarray, lam: float) -> Shooting:
        u = np.asarray(u, dtype=float)
        if u.shape != (self.size,):
            raise ParameterError(f"u must have shape ({self.size},) = (2 n p,); got {u.shape}")
        key = (u.tobytes(), float(lam))
        sh = self._shots.get(key)
        if sh is None:
            if len(self._shots) > _CACHE_SIZE:
                self._shots.clear()
            sh = self._shots[key] = shooting(self.flow_at(lam), self.N, self.p, u,
                                             pattern=self.pattern)
        return sh

    # -- the Problem protocol ------------------------------------------------------------------
    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``[r_0, .., r_{p-1}]``, ``r_k = D X_k^- - X_{k+1}``, shape (2np,)."""
        return self._shoot(u, lam).residual.copy()

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/du`` from the exact flow, shape (2np, 2np)."""
        return self._shoot(u, lam).jacobian.copy()

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/dlam``, shape (2np,)."""
        data = self.param.data
        if data not in (FREQUENCY, GAP, RESTITUTION):
            # the fallback; exact for the forcing amplitude (the residual is affine in F)
            return self._difference_quotient(u, lam)
        sh = self._shoot(u, lam)
        osc = self.oscillator_at(lam)
        n, p, m = osc.n, self.p, 2 * osc.n
        j, _, diagonals = impact_geometry(osc, self.pattern)
        # d(position c_k)/dlam or d(restitution R_k)/dlam of the stop of each impact
        rates = self.param.stop_rates(self.pattern)
        out = np.zeros(p * m)
        if data == GAP:
            for k in range(p):  # x_j = c_k at every start and arrival on a moving stop
                nxt = (k + 1) % p
                out[k * m:(k + 1) * m] = rates[k] * diagonals[nxt] * sh.transitions[k][:, j]
                out[k * m + j] -= rates[nxt]
            return out
        if data == RESTITUTION:  # x_j'^+ = -R_k x_j'^-: flight k ends at impact k+1
            out[n + j::m] = -np.roll(rates, -1) * sh.arrivals[:, n + j]
            return out
        if data == FREQUENCY:
            period = 2.0 * math.pi * self.N / osc.omega
            explicit = omega_partials(self.flow_at(lam), sh)
            # theta_k = delta + omega * (time elapsed since impact 0)
            elapsed = np.concatenate([[0.0], np.cumsum(sh.flight_times[:-1])])
            out[:] = (np.roll(diagonals, -1, axis=0)
                      * (explicit + elapsed[:, None] * sh.phase_columns)).ravel()
            # tau_{p-1} = 2 pi N / omega - sum(others)
            out[(p - 1) * m:] += diagonals[0] * sh.arrival_rates[p - 1] * (-period / osc.omega)
        return out

    def _difference_quotient(self, u: np.ndarray, lam: float) -> np.ndarray:
        """The parameter's one finite-difference fallback applied to the residual."""
        return self.param.difference(lambda v: self.residual(u, v), float(lam),
                                     self.oscillator_at(lam))

    # -- what the branch carries ----------------------------------------------------------------
    def orbit(self, u: np.ndarray, lam: float, *, checks: bool = True) -> MultiImpactOrbit:
        """The full N-p motion (states, G, multipliers, checks) at a branch point.

        ``checks=False`` skips the interior-contact search (see
        :func:`~impactcont.orbit.multi_impact.orbit_from_unknowns`).
        """
        return orbit_from_unknowns(self.flow_at(lam), self.N, self.p, np.asarray(u, float),
                                   self._shoot(u, lam), checks=checks, pattern=self.pattern)

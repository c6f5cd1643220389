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
each impact hits. Both act on one stop coordinate ``s = n . x`` (``x_j``, or ``x_j - x_k``
for a clearance between masses) with the impact matrices ``D_k`` (eq. 4; the two-body law
between masses), :func:`~impactcont.orbit.stop_geometry.stop_geometry`, so the derivatives
hold for free masses, clearances between masses and a constant force ``F_static`` alike.
A parameter says how fast each stop moves with it
(:attr:`~impactcont.model.parameters.ModelParameter.upper`, ``lower``): ``b`` and ``R`` move
the upper stop only, unless the stops are mirrored (``Stops(mirror=True)``: the lower stop
at ``-b`` with ``R`` moves with them), ``b_low`` and ``R_low`` the lower one, ``gap`` both.
The upper stop must stay above the lower one: the problem is defined only where the
clearance ``b + b_low`` between the stops is open
(:meth:`MultiImpactBranchProblem.parameter_limits`).

A pattern with lowercase letters (a plastic impact followed by a sticking phase until the
release, :func:`~impactcont.model.stops.sticking_pattern`) is the system of
:func:`~impactcont.orbit.sticky.sticky_shooting` instead: ``2 n p + q`` unknowns (the
q stick times after the flight times), the release rows ``p(X_r, theta_r) = 0`` after the
impact rows, ``dF/du`` exact (the held flow's and the flights'), ``dF/domega`` exact
(:func:`~impactcont.orbit.sticky.sticky_omega_column`: the flights' and the held
systems' forcing, the phases and the period) and, for the other parameters, the
parameter's central difference (:meth:`~impactcont.model.parameters.ModelParameter.
difference`, about 1e-11 relative, which steers the predictor and Newton only: the points
solve ``F = 0`` to the Newton tolerance). In omega the corrector step is compiled
(:func:`~impactcont.orbit.sticky.sticky_palc_step`). Its motions report the
stick times, release states and pressing minima; its branches end where a stick time
reaches 0 (the landing becomes a release: the end of a ride), where the pressing force
touches 0 inside a stick (release grazing) and where it is 0 at the landing (the onset of
sticking), each a sign change of a test of the motion (:data:`STICKING_TESTS`): the special
points ``SE``, ``RG`` and ``SO`` (:class:`~impactcont.vocabulary.Label`), which such a
problem declares besides those of every branch, so they are located by default.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np

from impactcont.core.locate import MotionTest
from impactcont.core.stepper import SINGULAR_CONDITION, CorrectorResult
from impactcont.errors import ParameterError
from impactcont.kernel.arrays import Forcing, ForcingDerivatives, HeldSegments
from impactcont.model.modal import _RESONANCE_REL_ERROR_WARN, forced_coefficients
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import (
    FREQUENCY,
    GAP,
    RESTITUTION,
    ModelParameter,
    model_parameter,
)
from impactcont.model.stops import check_pattern, sticking_pattern
from impactcont.orbit.flow import Flow, GeneralFlow, flow_of
from impactcont.orbit.held_flow import held_flow, held_flow_at
from impactcont.orbit.multi_impact import (
    MultiImpactOrbit,
    Shooting,
    _as_shooting,
    _geometry,
    _kernel,
    _writable,
    check_impacts,
    impact_sequence,
    orbit_from_unknowns,
    shooting,
    shot_flights,
)
from impactcont.orbit.periodic import _check_N
from impactcont.orbit.sticky import (
    StickyShooting,
    chatter_restitution,
    held_segments,
    sticky_jacobians,
    sticky_omega_column,
    sticky_orbit_from_unknowns,
    sticky_palc_step,
    sticky_shooting,
)
from impactcont.orbit.stop_geometry import StopGeometry, moved_stop_geometry
from impactcont.orbit.symmetry import half_map, symmetry_defect
from impactcont.problems.events import BRANCH_TESTS
from impactcont.vocabulary import Label

__all__ = ["STICKING_EVENTS", "STICKING_TESTS", "MultiImpactBranchProblem",
           "release_grazing_test", "stick_end_test", "sticking_onset_test"]

_CACHE_SIZE = 64
_EPS = float(np.finfo(float).eps)
#: rounding of the sticking tests, in eps times the size of what they are summed from
_NOISE_ULPS = 64.0
_REFUSED = 2
#: :func:`impactcont.kernel.shooting.palc_correct`'s statuses in the core's words
_STATUSES = ("converged", "not converged", "refused", "non-finite residual",
             "non-finite system", "singular", "non-finite update")


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

    #: The kinds of special points located on its branches (a symmetric motion's problem
    #: adds BP): the folds, and those with a test of the motion.
    events: tuple[Label, ...] = (Label.SN, *BRANCH_TESTS)
    #: The test of each kind but the fold, as functions of the motion.
    motion_tests: ClassVar[Mapping[str, MotionTest]] = BRANCH_TESTS
    #: The interior-contact search of every flight is costly: only the tests that need it
    #: (GR) ask the motion with its checks (:mod:`impactcont.problems.motion`).
    separate_checks = True
    #: Its datasets carry the ``impact`` dimension (:mod:`impactcont.dataset.multi`).
    impact_dimension = True

    def __init__(self, osc: ImpactOscillator, N: int, p: int, parameter: str,
                 pattern: str | None = None) -> None:
        if not isinstance(osc, ImpactOscillator):
            raise TypeError(f"osc must be an ImpactOscillator; got {type(osc).__name__}")
        self.param = model_parameter(osc, parameter)
        self.osc = osc
        self.N = _check_N(N)
        self.p = check_impacts(p)
        self.pattern = check_pattern(pattern, self.p, osc.stops, sticking=True)
        self.parameter = parameter
        #: The stop of each impact (the pattern in capitals) and whether a sticking phase
        #: follows it (:func:`~impactcont.model.stops.sticking_pattern`).
        self.impacts, self.sticks = sticking_pattern(osc, self.pattern)
        self.sticky = bool(np.any(self.sticks))
        if self.sticky:
            _check_sticking_parameter(self.param, osc, self.pattern, self.impacts,
                                      self.sticks)
            #: the kinds of points that end a branch of motions with sticking phases,
            #: located by default as the branch's special points
            self.events = (*self.events, *STICKING_TESTS)
            self.motion_tests = MappingProxyType({**BRANCH_TESTS, **STICKING_TESTS})
        self.size = 2 * osc.n * self.p + int(np.count_nonzero(self.sticks))
        self._flows: dict[float, Flow] = {}
        # omega leaves the modal basis, the stops and the constant force as they are: the
        # flow at another omega is the start's with new forced amplitudes (eq. 7)
        self._base_flow = (flow_of(osc) if self.param.data == FREQUENCY
                           and type(flow_of(osc)) is Flow and np.isrealobj(flow_of(osc).f)
                           else None)
        if self._base_flow is not None:  # made here so that every flow shares it
            _geometry(self._base_flow, self.impacts)
        self._shots: dict[tuple[bytes, float], Shooting | StickyShooting] = {}
        self._extended: dict[tuple[bytes, float], np.ndarray] = {}  # [J | dF/domega]

    # -- where the parameter may go -----------------------------------------------------------
    def parameter_limits(self) -> tuple[float, float]:
        """Open interval of the parameter in which the stops exist as given.

        A parameter that moves a stop of a two-sided system must keep the upper stop
        ``s = b`` above the lower one ``s = -b_low`` (stop coordinate ``s = n . x``: ``x_j``,
        or ``x_j - x_k`` for a clearance between masses; ``b > -b_low``; ``b > 0`` for
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
        s = stops.coordinate
        return (f"at {self.parameter} = {lower!r} the upper stop {s} = b meets the "
                f"lower stop {s} = -b_low (b={self.osc.b!r}, stops={stops!r}): the "
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

    def moved(self, osc: ImpactOscillator) -> MultiImpactBranchProblem:
        """This problem on `osc`, which differs from :attr:`osc` only in omega and the stops'
        positions and restitutions (a curve's other parameter: the modal basis, the forcing
        and the continued parameter are the same).

        What the constructor gives, without checking the parameter, the pattern and the
        modes again: the flow at `osc` shares this problem's modal basis.
        """
        new = copy.copy(self)
        new.osc = osc
        new._flows, new._shots, new._extended = {}, {}, {}
        if self._base_flow is not None:
            base = self._base_flow
            new._base_flow = _at_frequency(base, osc, same_stops=False)
            # the stops moved, their normals and impact matrices kept (unless R changed)
            cache = new._base_flow.__dict__.setdefault("_stop_geometry", {})
            for pattern in {self.impacts, self.pattern}:
                cache[pattern] = moved_stop_geometry(_geometry(base, pattern), base.osc, osc,
                                                     pattern)
        return new

    # -- the oscillator along the branch ------------------------------------------------------
    def flow_at(self, lam: float) -> Flow:
        """The flow of the oscillator with ``parameter = lam``."""
        lam = float(lam)
        flow = self._flows.get(lam)
        if flow is None:
            if len(self._flows) > _CACHE_SIZE:
                self._flows.clear()
            osc = self.param.at(self.osc, lam)
            flow = self._flows[lam] = (Flow(osc) if self._base_flow is None
                                       else _at_frequency(self._base_flow, osc))
            if self.sticky and self._base_flow is not None:
                self._held_at_frequency(osc)
        return flow

    def _held_at_frequency(self, osc: ImpactOscillator) -> None:
        """The held systems' flows of the sticking stops at `osc` (the start's at another
        omega) from the start's: their modes kept, the forced amplitudes new
        (:func:`~impactcont.orbit.held_flow.held_flow_at`)."""
        for name in sorted({self.impacts[k] for k in np.flatnonzero(self.sticks)}):
            base = held_flow(self.osc, name)
            reduced = base.reduced
            if reduced is not None:
                reduced = _flow_at_frequency(reduced, reduced.osc.replace(omega=osc.omega))
            held_flow_at(base, osc, name, reduced)

    def oscillator_at(self, lam: float) -> ImpactOscillator:
        """The oscillator with ``parameter = lam``."""
        return self.flow_at(lam).osc

    def shot(self, u: np.ndarray, lam: float) -> Shooting | StickyShooting:
        """The shooting system at ``(u, lam)``: its flights (starts, phases, flight times,
        arrivals, transitions, phase columns, arrival rates), residual and ``dF/du``.

        What the residual, the Jacobian, the tests and the orbit of a point are computed
        from (:func:`~impactcont.orbit.multi_impact.shooting`; with sticking phases
        :func:`~impactcont.orbit.sticky.sticky_shooting`, with their stick times); kept for
        the last few points and shared by them: read it, do not modify it.

        Raises
        ------
        ParameterError
            `u` does not have :attr:`size` entries.
        """
        return self._shoot(u, lam)

    def _held_shifts(self, lam: float) -> np.ndarray:
        """Where the contact search of each flight from a release starts at ``lam``
        (:func:`~impactcont.orbit.sticky.held_segments`' shifts)."""
        return HeldSegments(*held_segments(self.flow_at(lam), self.pattern)).shifts

    def _keep_shot(self, u: np.ndarray, lam: float, sh: Shooting | StickyShooting) -> None:
        """Keep `sh`, the shot at ``(u, lam)`` computed elsewhere (a compiled corrector's at
        its converged point), for :meth:`shot`."""
        if len(self._shots) > _CACHE_SIZE:
            self._shots.clear()
            self._extended.clear()
        self._shots[(np.asarray(u, dtype=float).tobytes(), float(lam))] = sh

    def _shoot(self, u: np.ndarray, lam: float) -> Shooting | StickyShooting:
        u = np.asarray(u, dtype=float)
        if u.shape != (self.size,):
            q = self.size - 2 * self.osc.n * self.p
            raise ParameterError(f"u must have shape ({self.size},) = (2 n p"
                                 + (f" + q,) with q = {q} sticking phases" if q else ",)")
                                 + f"; got {u.shape}")
        key = (u.tobytes(), float(lam))
        sh = self._shots.get(key)
        if sh is None:
            if len(self._shots) > _CACHE_SIZE:
                self._shots.clear()
                self._extended.clear()
            if self.sticky:  # the held flows and the release rows (no compiled step)
                sh = sticky_shooting(self.flow_at(lam), self.N, self.pattern, u)
            elif self._base_flow is None:
                sh = shooting(self.flow_at(lam), self.N, self.p, u, pattern=self.pattern)
            else:  # omega: the residual, the Jacobian and dF/domega in one compiled call
                flow = self.flow_at(lam)
                geo = _geometry(flow, self.pattern)
                linear = _kernel().branch_linearization(
                    tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
                    tuple(flow.omega_arrays()), tuple(impact_sequence(geo)),
                    2.0 * math.pi * self.N / flow.omega, _writable(u))
                sh = _as_shooting(linear.shot, True)
                self._extended[key] = linear.extended
            self._shots[key] = sh
        return sh

    def linearize(self, u: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """The residual and ``[dF/du | dF/dlam]`` at ``(u, lam)``, shapes (2np,), (2np, 2np + 1).

        What a corrector step of the continuation core needs at one point (the core's
        optional one-call evaluation, :class:`~impactcont.core.problem.Problem`): in omega
        one compiled call (:func:`impactcont.kernel.shooting.branch_linearization`), else
        :meth:`residual`, :meth:`jacobian` and :meth:`dparam`.
        """
        sh = self._shoot(u, lam)
        extended = self._extended.get((np.asarray(u, dtype=float).tobytes(), float(lam)))
        if extended is None:
            extended = np.column_stack([sh.jacobian, self.dparam(u, lam)])
        else:
            extended = extended.copy()
        return sh.residual.copy(), extended

    # -- the Problem protocol ------------------------------------------------------------------
    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``[r_0, .., r_{p-1}]``, ``r_k = D X_k^- - X_{k+1}``, shape (2np,)."""
        return self._shoot(u, lam).residual.copy()

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/du`` from the exact flow, shape (2np, 2np)."""
        return self._shoot(u, lam).jacobian.copy()

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/dlam``, shape (2np,).

        Exact for the frequency and the stops (:meth:`_frequency_derivative`,
        :meth:`_gap_derivative`, :meth:`_restitution_derivative`, on the stop coordinate
        ``n . x`` and the full impact matrices ``D_k`` of :func:`stop_geometry`); the
        parameter's finite-difference fallback otherwise (exact for the forcing amplitude).
        """
        data = self.param.data
        if self.sticky and data == FREQUENCY:  # exact: the flights' and held systems' forcing
            return sticky_omega_column(self.flow_at(lam), self.N, self.pattern, u,
                                       self._shoot(u, lam))
        if self.sticky or data not in (FREQUENCY, GAP, RESTITUTION):
            # the fallback; exact for the forcing amplitude (the residual is affine in F;
            # with sticking phases the release rows' pressing force too)
            return self._difference_quotient(u, lam)
        if self._base_flow is not None:  # dF/domega comes with the shooting system
            self._shoot(u, lam)
            return self._extended[(np.asarray(u, dtype=float).tobytes(), float(lam))][:, -1].copy()
        return self.derivative(u, lam, self.param)

    def derivative(self, u: np.ndarray, lam: float, param: ModelParameter) -> np.ndarray:
        """``dF/dmu`` at ``(u, lam)`` for another parameter ``mu`` of the frequency or the
        stops (`param`, of this oscillator), exact, shape (2np,): a curve's derivative in
        its second parameter from the shot of this problem (:meth:`dparam` in `param`).

        Raises
        ------
        ParameterError
            `param` changes other flight data (its derivative is a finite difference of
            the problem continued in it).
        """
        data = param.data
        if self.sticky:
            raise ParameterError(f"derivative: the pattern {self.pattern!r} has sticking "
                                 "phases, whose curves in two parameters are not solved yet; "
                                 "continue the motion in one parameter (continuation)")
        if data not in (FREQUENCY, GAP, RESTITUTION):
            raise ParameterError(f"derivative: parameter {param.name!r} changes the "
                                 f"{data}; only the frequency and the stops have it here")
        sh = self._shoot(u, lam)
        flow = self.flow_at(lam)
        geo = _geometry(flow, self.pattern)
        if data == GAP:
            return self._gap_derivative(sh, geo, param)
        if data == RESTITUTION:
            return self._restitution_derivative(sh, flow.osc, param)
        return self._frequency_derivative(sh, geo, lam)

    def _gap_derivative(self, sh: Shooting, geo: StopGeometry, param: ModelParameter
                        ) -> np.ndarray:
        """``dF/dlam`` of a parameter moving the stops (``c_k`` of eq. 3).

        On the section ``n_k . x = c_k`` the eliminated position is
        ``x_j = (c_k - sum_{i != j} n_i x_i) / n_j``, so ``dX_k/dc_k = e_j / n_j`` at the
        start of flight k (carried to its arrival by ``Phi_k``) and at the next start:
        ``d r_k = D_{k+1} Phi_k e_j dc_k / n_{k,j} - e_j dc_{k+1} / n_{k+1,j}``.
        """
        p, m = self.p, 2 * self.osc.n
        rates = param.stop_rates(self.pattern)  # d c_k / d lam
        out = np.zeros(p * m)
        for k in range(p):
            nxt = (k + 1) % p
            j, jn = geo.pivots[k], geo.pivots[nxt]  # each impact's own stop's mass
            out[k * m:(k + 1) * m] = (rates[k] * geo.matrices[nxt] @ sh.transitions[k][:, j]
                                      / geo.normals[k, j])
            out[k * m + jn] -= rates[nxt] / geo.normals[nxt, jn]
        return out

    def _restitution_derivative(self, sh: Shooting, osc: ImpactOscillator,
                                param: ModelParameter) -> np.ndarray:
        """``dF/dlam`` of a parameter changing the restitutions (``R_k`` of eq. 4).

        The impact law ``D = I - (1 + R) M^-1 n n^T / (n^T M^-1 n)`` on the velocities
        (eq. 4 on one mass: ``-R`` on ``x_j'``; both stops act on one coordinate ``n . x``)
        is affine in R, so
        ``dD/dR = D(R=1) - D(R=0)`` exactly, and ``d r_k = dR_{k+1} (dD/dR) X_k^-``.
        """
        n, m = osc.n, 2 * osc.n
        slopes = np.zeros((self.p, m, m))  # dD_{k+1}/dR of the stop ending flight k
        for k, s in enumerate(self.pattern[1:] + self.pattern[0]):
            slopes[k, n:, n:] = osc.stops.restitution_slope(s, osc.M)
        rates = np.roll(param.stop_rates(self.pattern), -1)  # dR_{k+1} / dlam
        return (rates[:, None] * np.einsum("kij,kj->ki", slopes, sh.arrivals)).ravel()

    def _frequency_derivative(self, sh: Shooting, geo: StopGeometry, lam: float) -> np.ndarray:
        """``dF/domega``: the forced part of eq. (9) at fixed flight times, the phases
        ``theta_k = delta + omega (tau_0 + .. + tau_{k-1})`` and the last flight time
        ``tau_{p-1} = 2 pi N / omega - (tau_0 + .. + tau_{p-2})``, each through ``D_{k+1}``.
        """
        flow = self.flow_at(lam)
        return _kernel().frequency_column(
            tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
            tuple(flow.omega_arrays()), tuple(impact_sequence(geo)),
            2.0 * math.pi * self.N / flow.omega, tuple(shot_flights(sh)))

    def _difference_quotient(self, u: np.ndarray, lam: float) -> np.ndarray:
        """The parameter's one finite-difference fallback applied to the residual."""
        return self.param.difference(lambda v: self.residual(u, v), float(lam),
                                     self.oscillator_at(lam))

    def jacobian_product(self, u: np.ndarray, lam: float, count: int) -> np.ndarray:
        """``G_{count-1} .. G_0`` (eq. 25) of the motion with unknowns `u` at ``lam``, (2n, 2n).

        ``count = p`` gives G (the PD test), ``p / 2`` the product in the half-map of a
        symmetric motion (the BP test): one compiled call on the shot, without the rest
        of :meth:`orbit` (multipliers, contact checks).
        """
        sh = self._shoot(u, lam)
        flow = self.flow_at(lam)
        if self.sticky:
            jacobians, _ = sticky_jacobians(flow, self.pattern, sh)
            G = np.eye(2 * self.osc.n)
            for k in range(int(count)):
                G = jacobians[k] @ G
            return G
        geo = _geometry(flow, self.pattern)
        return _kernel().jacobian_product(tuple(impact_sequence(geo)), float(flow.omega),
                                          tuple(shot_flights(sh)), int(count))

    def palc_step(self, predicted: np.ndarray, tangent: np.ndarray, weights: np.ndarray,
                  tol: float, max_iter: int, *, hyperplane: bool = False
                  ) -> CorrectorResult | None:
        """The continuation core's corrector and tangent of one step, compiled (omega only).

        :func:`impactcont.kernel.shooting.palc_correct` (with sticking phases
        :func:`impactcont.kernel.sticky.sticky_palc_correct`): the core's optional one-call
        step (:class:`~impactcont.core.problem.Problem`); with `hyperplane`, the Newton of
        :func:`~impactcont.core.corrector.solve_on_hyperplane` instead. None when the
        parameter is not omega or the flow is not modal (the core then corrects with
        :meth:`linearize`).
        """
        if self._base_flow is None:
            return None
        if self.sticky:  # kernel.sticky.sticky_palc_correct
            out, sh = sticky_palc_step(self._base_flow, self.N, self.pattern, predicted,
                                       tangent, weights, tol, max_iter, SINGULAR_CONDITION,
                                       hyperplane=hyperplane, with_shot=True)
            if sh is not None and np.array_equal(
                    sh.search_shifts, self._held_shifts(out.omega)):
                # the converged point's shot, its motion made from it (where the contact
                # searches from the releases start as at the point's omega: the corrector
                # keeps the start's shifts)
                self._keep_shot(out.state[:-1], out.omega, sh)
            return self._corrector_result(out)
        return self._palc_step(predicted, tangent, weights, tol, max_iter,
                               np.eye(self.size), np.zeros(self.size), self.size, hyperplane)

    def _palc_step(self, predicted: np.ndarray, tangent: np.ndarray, weights: np.ndarray,
                   tol: float, max_iter: int, E: np.ndarray, c: np.ndarray, rows: int,
                   hyperplane: bool = False) -> CorrectorResult:
        """:meth:`palc_step` on the unknowns ``v`` with ``u = E v + c / omega`` and the
        first `rows` equations (a symmetric motion's half system)."""
        base = self._base_flow
        errors = self.osc.modes.eigenvalue_errors
        geo = _geometry(base, self.pattern)
        out = _kernel().palc_correct(
            tuple(base.shooting_arrays()), _errors(errors, base.n), tuple(impact_sequence(geo)),
            float(self.N), (E, c, int(rows)),
            (_writable(predicted), _writable(tangent), _writable(weights)),
            (float(tol), int(max_iter), SINGULAR_CONDITION, bool(hyperplane)))
        if errors is not None and out.worst > _RESONANCE_REL_ERROR_WARN:
            # an iterate near a lightly damped mode: forced_coefficients warns in its words
            forced_coefficients(base.w, base.a, base.f, out.worst_omega, eigenvalue_errors=errors)
        return self._corrector_result(out)

    def _corrector_result(self, out: Any) -> CorrectorResult:
        """The core's :class:`~impactcont.core.stepper.CorrectorResult` of a compiled step
        (a :class:`~impactcont.kernel.arrays.PalcResult`), with the oscillator's own words
        where it refused the omega reached."""
        message = ""
        if out.status == _REFUSED:
            try:  # the oscillator's own refusal (omega <= 0, an undamped resonance)
                self.flow_at(out.omega)
                message = f"omega = {out.omega!r} refused"
            except ParameterError as error:
                message = str(error)
        return CorrectorResult(state=out.state, iterations=int(out.iterations),
                               status=_STATUSES[int(out.status)], lam=float(out.omega),
                               residual_norm=float(out.residual_norm), tangent=out.tangent,
                               ill_conditioned=out.flagged if out.flagged.size else None,
                               message=message, last_step=float(out.last_update))

    # -- what the branch carries ----------------------------------------------------------------
    @staticmethod
    def fold_kind(orbit: MultiImpactOrbit, left: MultiImpactOrbit, right: MultiImpactOrbit
                  ) -> Label:
        """The kind of a located fold (:func:`fold_kind`: BP where the branch meets the
        branch of symmetric motions)."""
        return fold_kind(orbit, left, right)

    def orbit(self, u: np.ndarray, lam: float, *, checks: bool = True) -> MultiImpactOrbit:
        """The full N-p motion (states, G, multipliers, checks) at a branch point.

        ``checks=False`` skips the interior-contact search (see
        :func:`~impactcont.orbit.multi_impact.orbit_from_unknowns`; with sticking phases
        :func:`~impactcont.orbit.sticky.sticky_orbit_from_unknowns`).
        """
        if self.sticky:
            return sticky_orbit_from_unknowns(self.flow_at(lam), self.N, self.pattern,
                                              np.asarray(u, float), self._shoot(u, lam),
                                              checks=checks)
        return orbit_from_unknowns(self.flow_at(lam), self.N, self.p, np.asarray(u, float),
                                   self._shoot(u, lam), checks=checks, pattern=self.pattern)


#: A fold is a pitchfork when the motion is symmetric to this and its half-map has a
#: multiplier within it of -1 (:func:`fold_kind`).
_MEETS_TOL = 1e-2


def fold_kind(orbit: MultiImpactOrbit, left: MultiImpactOrbit, right: MultiImpactOrbit
              ) -> Label:
    """The kind of a fold of an N-p branch: BP where it meets a branch of symmetric motions.

    An asymmetric branch (followed as a general N-p motion) meets the symmetric one at a
    pitchfork, where its parameter turns (``lam - lam_BP`` grows like the square of the
    asymmetry): that fold is the BP it is when the motion there, or at one of the two
    accepted points around it, is nearly symmetric (asymmetry at most 1e-2,
    :func:`~impactcont.orbit.symmetry.symmetry_defect`: it grows like the square root of
    the distance to the BP, and the fold next to a BP is often only bracketed: the full
    system is singular there) with a multiplier of the half-map ``H`` within 1e-2 of -1.
    Otherwise SN.
    """
    for motion in (orbit, left, right):
        if symmetry_defect(motion) <= _MEETS_TOL:
            H = half_map(motion)
            if np.all(np.isfinite(H)) and np.min(np.abs(np.linalg.eigvals(H) + 1.0)) \
                    <= _MEETS_TOL:
                return Label.BP
    return Label.SN


def _at_frequency(base: Flow, osc: ImpactOscillator, *, same_stops: bool = True) -> Flow:
    """The modal flow of `osc`, which differs from ``base.osc`` in omega only (and, with
    ``same_stops=False``, in the stops' positions and restitutions).

    Shares the modal basis, the constant force's arrays and (with `same_stops`) the stop
    geometry of `base` (none depends on omega; eq. 9) and takes the new steady amplitudes
    ``gamma_i, beta_i`` of eq. (7) (:func:`~impactcont.model.modal.forced_coefficients`,
    with its resonance refusal and warning): what ``Flow(osc)`` computes, without the
    modal basis, the static response and the stop geometry again.
    """
    flow = object.__new__(Flow)
    flow.__dict__.update(base.__dict__)
    flow.__dict__.pop("_held_segments", None)  # the held systems' forcing moves with omega
    if not same_stops:
        flow.__dict__.pop("_stop_geometry", None)
    omega = osc.omega
    flow.osc, flow.omega = osc, omega
    arrays = base.shooting_arrays()
    errors = osc.modes.eigenvalue_errors
    amplitudes = _kernel().forced_amplitudes(arrays.w, arrays.a, arrays.f,
                                             _errors(errors, base.n), omega)
    gam, bet = amplitudes.gamma, amplitudes.beta
    if amplitudes.resonant or not amplitudes.worst <= _RESONANCE_REL_ERROR_WARN:
        # refused or warned about: forced_coefficients says so in its own words
        gam, bet = (np.array(c, dtype=float) for c in forced_coefficients(
            base.w, base.a, base.f, omega, eigenvalue_errors=errors))
    flow.gamma, flow.beta = gam, bet
    flow._forcing = Forcing(omega=float(omega), gamma=gam, beta=bet, Z=base.forcing_arrays().Z)
    flow._omega_arrays = ForcingDerivatives(dgamma=amplitudes.dgamma, dbeta=amplitudes.dbeta,
                                            dZ=base.omega_arrays().dZ)
    return flow


def _check_sticking_parameter(param: ModelParameter, osc: ImpactOscillator, pattern: str,
                              impacts: str, sticks: np.ndarray) -> None:
    """Refuse a parameter that changes the restitution of a stop the motion sticks on:
    shooting solves sticking phases entered by a plastic impact (``R = 0``) only, so the
    held system exists at the start value alone.

    Raises
    ------
    ParameterError
        Naming the parameter, the stops and what may be continued instead.
    """
    if param.data != RESTITUTION:
        return
    rates = param.stop_rates(impacts)
    held = sorted({impacts[k] for k in np.flatnonzero(sticks) if rates[k] != 0.0})
    if held:
        raise ParameterError(
            f"parameter {param.name!r} changes the restitution of stop(s) {held} (now "
            f"{[float(osc.stops.stop(s, osc.M, osc.b, osc.R).restitution) for s in held]!r})"
            ", on which the motion sticks "
            f"(pattern {pattern!r}): "
            "its restitution decides how a sticking phase is entered (by the plastic impact "
            "at 0, through complete chatter above 0) and is not continued; continue in the "
            "restitution of a stop without sticking phases, or in another parameter")


def _flow_at_frequency(base: Flow, osc: ImpactOscillator) -> Flow:
    """The flow of `osc`, ``base.osc`` at another omega, of either kind: the modal flow by
    :func:`_at_frequency`, the first-order one with its basis, constant force and kernel
    arrays kept and the steady amplitude ``Z`` new (eq. 9), else built anew."""
    if type(base) is Flow and np.isrealobj(base.f):
        return _at_frequency(base, osc)
    if type(base) is not GeneralFlow:
        return flow_of(osc)
    flow = object.__new__(GeneralFlow)
    flow.__dict__.update(base.__dict__)
    flow.osc, flow.omega = osc, osc.omega
    flow.Z = base.basis.forced_amplitude(osc.F, osc.omega)
    flow._last = flow._forcing = flow._omega_arrays = None
    return flow


def _errors(errors: np.ndarray | None, n: int) -> np.ndarray:
    """The eigenvalue errors as the kernel's float array (zeros when unknown)."""
    if errors is None:
        return np.zeros(n)
    return _writable(np.asarray(errors, dtype=float))


# -- the points that end a branch of motions with sticking phases -----------------------------
def _sticks_of(orbit: Any) -> np.ndarray:
    """The impacts of `orbit` followed by a sticking phase (their release states are set)."""
    return np.flatnonzero(np.all(np.isfinite(np.asarray(orbit.release_states)), axis=1))


def _smallest(values: np.ndarray, orbit: Any) -> float:
    """The smallest of `values` over the sticking phases of `orbit` (NaN when it has none
    or one of them is NaN: a stick of duration <= 0 has no pressing minimum)."""
    held = _sticks_of(orbit)
    return float(np.min(np.asarray(values, dtype=float)[held])) if held.size else math.nan


def _held(orbit: Any) -> np.ndarray:
    """Which impacts of `orbit` start a held phase: its pressing minimum is known and, on a
    stop with restitution above 0, the chatter the landing starts accumulates (a chatter
    whose impacts do not accumulate, left out of ``orbit.chatters``, enters no stick: the
    motion is not physical for it, and its pressing force is the landing's, not one of a
    held phase)."""
    held = ~np.isnan(np.asarray(orbit.pressing_min, dtype=float))
    accumulated = {chatter.impact for chatter in orbit.chatters}
    impacts, _ = sticking_pattern(orbit.oscillator, orbit.pattern)
    for k in np.flatnonzero(held):
        if chatter_restitution(orbit.oscillator, impacts[k]) > 0.0 \
                and int(k) not in accumulated:
            held[k] = False
    return held


def stick_end_test(orbit: Any) -> float:
    """The end of a ride: the shortest stick time ``min_k s_k`` of the motion.

    Zero where a sticking phase shrinks to nothing: the plastic impact lands where the
    stop stops pressing its coordinate (the landing is itself a release); past it the
    shooting continues with a negative stick time, a motion flagged not physical. NaN
    for a motion without sticking phases.
    """
    return _smallest(orbit.stick_times, orbit)


def release_grazing_test(orbit: Any) -> float:
    """Release grazing: the smallest pressing force inside the sticking phases,
    ``min_k pressing_min_k`` (their starts included, the releases excluded).

    Zero where the pressing force touches zero inside a stick (the release would come
    earlier: another motion). A held phase of duration <= 0 counts minus the size of its
    landing's pressing force (the limit of its minimum as the stick shrinks to its start,
    taken negative: no held phase is not a physical one), so the test is finite along the
    whole branch and changes sign where the held phase vanishes: at the end of a ride
    (the landing there is a release) and at the onset of complete chatter (the
    accumulation point reaches the release), whatever the landing's pressing force does
    past it.
    """
    low = np.asarray(orbit.pressing_min, dtype=float)
    return _smallest(np.where(_held(orbit), low, -np.abs(orbit.landing_pressing)), orbit)


def sticking_onset_test(orbit: Any) -> float:
    """The onset of sticking: the smallest pressing force right after the plastic impacts
    that start the sticking phases, ``min_k p(X_k, theta_k)``.

    Zero where an impact lands with the acceleration tangent to its stop: on one side the
    stop holds the coordinate, on the other the mass leaves at once. On a stick entered
    through complete chatter the pressing force is the one at the accumulation point, and
    its zero is the onset of complete chatter: the accumulation point reaches the
    release. A held phase of duration <= 0 counts minus the size of its landing's
    pressing force: past the onset the chatter map may accumulate in a later forcing
    period with a positive pressing force again, which is no stick of this motion (the
    test would step over the onset without a sign change); a chatter whose impacts do not
    accumulate enters no held phase either (:func:`_held`).
    """
    landing = np.asarray(orbit.landing_pressing, dtype=float)
    return _smallest(np.where(_held(orbit), landing, -np.abs(landing)), orbit)


def _time_noise(orbit: Any) -> float:
    """Rounding of a stick time: eps times the period (the last flight time closes it)."""
    return _NOISE_ULPS * _EPS * 2.0 * math.pi * orbit.N / orbit.oscillator.omega


def _force_noise(orbit: Any) -> float:
    """Rounding of a pressing force: eps times the forces it is summed from (the forcing,
    the constant force and the spring and damper forces at the impacts' states)."""
    osc = orbit.oscillator
    states = np.asarray(orbit.states, dtype=float)
    n = osc.n
    size = max(float(np.max(np.abs(np.asarray(osc.F)), initial=0.0)),
               float(np.max(np.abs(np.asarray(osc.F_static)), initial=0.0)),
               float(np.max(np.abs(states[:, :n] @ np.asarray(osc.K).T), initial=0.0)),
               float(np.max(np.abs(states[:, n:] @ np.asarray(osc.C).T), initial=0.0)))
    return _NOISE_ULPS * _EPS * size


#: The tests of the points that end a branch of motions with sticking phases, as
#: :class:`~impactcont.core.locate.MotionTest` by their kind
#: (:class:`~impactcont.vocabulary.Label`): ``SE`` the end of a sticking phase (a stick
#: time through 0), ``RG`` release grazing (the pressing force touching 0 inside a stick),
#: ``SO`` the onset of sticking (the pressing force at a landing through 0). A sticky
#: problem declares them (its ``events`` and ``motion_tests``), so they are detected and
#: located on its branches by default, as their other special points; none is critical
#: beyond its zero (no multiplier check).
STICKING_TESTS: Mapping[Label, MotionTest] = MappingProxyType({
    Label.SE: MotionTest(stick_end_test, _time_noise),
    Label.RG: MotionTest(release_grazing_test, _force_noise),
    Label.SO: MotionTest(sticking_onset_test, _force_noise),
})

#: The same tests as user functions: ``{"stick_end": .., "release_grazing": ..,
#: "sticking_onset": ..}``. Deprecated as ``events=`` of :func:`impactcont.continuation`:
#: a sticky branch locates these points as its special points ``SE``, ``RG`` and ``SO``;
#: passed as events where those kinds are detected, they are kept as monitors only, with
#: a ``DeprecationWarning``
#: (:func:`~impactcont.detection.special_points.without_detected_events`), so that no
#: point is reported twice. As ``monitors=`` they give the tests' values at every point.
STICKING_EVENTS: Mapping[str, Callable[[Any], float]] = MappingProxyType({
    "stick_end": stick_end_test, "release_grazing": release_grazing_test,
    "sticking_onset": sticking_onset_test})

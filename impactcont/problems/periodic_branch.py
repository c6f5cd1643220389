"""The branch of periodic N-1 motions as a curve for the continuation core.

Eq. (14) written as ``r(delta, lam) = c(lam) cos(delta) + s(lam) sin(delta) - b(lam) = 0``
is a smooth curve in ``(delta, lam)``; its two roots of eq. (15) meet at
folds (``c^2 + s^2 = b^2``), where the curve simply turns, so pseudo-arclength
continuation goes round them.

Far above the lowest natural frequency ``|c, s|`` grows far above ``b`` (``1e9`` against
``0.3`` at ``omega / omega_1 = 670`` on issue 19's system): ``r`` is then a difference of
terms of that size, known only to about ``eps sqrt(c^2 + s^2)``, so it is divided by
:func:`residual_scale`, and the motion at a point is evaluated at the root of eq. (14)
nearest its phase (:func:`root_phase`), where the impact velocity's exact form does not
depend on the corrector's tolerance.
"""

from __future__ import annotations

import cmath
import logging
import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from scipy.optimize import minimize_scalar

from impactcont.core.locate import Event, MotionTest, locate_events
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import FORCING, GAP, RESTITUTION, model_parameter
from impactcont.model.stops import require_paper_stops
from impactcont.orbit import general
from impactcont.orbit.periodic import (
    PeriodicOrbit,
    modal_arrays,
    orbit_at_phase,
    periodic_orbits,
)
from impactcont.problems.events import BRANCH_TESTS
from impactcont.vocabulary import CONTINUABLE_PARAMETERS, Label

__all__ = ["CONTINUABLE_PARAMETERS", "PeriodicBranchProblem", "residual_scale", "root_phase",
           "scaled_derivative"]

log = logging.getLogger(__name__)

#: Parameter values scanned for the existence of motions (eq. 15) along a branch's bounds.
EXISTENCE_SCAN = 400
_FOLD_XTOL = 1e-13  # the chord coordinate of the fold's fallback location (the detector's)
_ROOT_STEP = 1e-6  # rad: the largest correction root_phase makes (far above any tolerance)
_UNSCALED = 64.0  # |c, s| up to which eq. (14) is not scaled (residual_scale)


def residual_scale(c: float | complex, s: float | complex) -> float | complex:
    """The scale of eq. (14) at one parameter value: ``max(1, sqrt(c^2 + s^2) / 64)``.

    ``r = c cos(delta) + s sin(delta) - b`` sums terms up to ``sqrt(c^2 + s^2)`` (at a
    root ``|b| <= sqrt(c^2 + s^2)`` too), so it is known only to a few
    ``eps sqrt(c^2 + s^2)``: far above the lowest natural frequency that exceeds any
    absolute Newton tolerance, and no point could be corrected (issue 19's system at
    omega = 300, ``|c, s| = 1.2e9``, stopped at a residual of 5.6e-8; an undamped chain
    near its resonance at 1e-12). Divided by this scale the residual's rounding stays
    below ``64 sqrt(2) 2 eps = 4e-14``, under the tightest tolerance of the drivers
    (1e-13, the event location), and eq. (14) is unchanged where ``|c, s| <= 64`` (the
    paper's system: below 7). The solutions and the tangent do not change. Complex
    ``c, s`` (a complex step) give the analytic ``sqrt(c^2 + s^2) / 64`` on the side of
    its real part: the step differentiates the scaled residual exactly;
    :func:`scaled_derivative` does it for a derivative.
    """
    if isinstance(c, float) and isinstance(s, float):  # (numpy's float64 too)
        return max(1.0, math.hypot(c, s) / _UNSCALED)
    if math.hypot(c.real, s.real) <= _UNSCALED:
        return 1.0
    return cmath.sqrt(complex(c * c + s * s)) / _UNSCALED


def scaled_derivative(f: float, df: float, c: float, s: float, dc: float, ds: float
                      ) -> float:
    """``d(f / scale)`` from ``f``, its derivative ``df`` and those of ``c, s``, with
    ``scale`` = :func:`residual_scale` ``(c, s)``."""
    rho = math.hypot(c, s)
    if rho <= _UNSCALED:
        return df
    return (df - f * (c * dc + s * ds) / (rho * rho)) * (_UNSCALED / rho)


def root_phase(c: float, s: float, b: float, delta: float) -> float:
    """The root of eq. (14) nearest `delta`: one Newton step ``delta - r / (dr/d delta)``.

    A continuation point solves eq. (14) to the corrector's tolerance (1e-12 relative,
    or looser on a bound or a located point), not to rounding. Far above the lowest
    natural frequency the kernel's impact velocity ``x1p'(delta) / Delta`` moves with the
    phase like ``sqrt(c^2 + s^2) / (kappa g)`` (0.1 % for a phase 7e-13 off on issue 19's
    system) and :func:`impactcont.orbit.periodic.orbit_at_phase` takes the exact form
    that does not (:func:`impactcont.orbit.dense.impact_velocity`) only at a root: one
    step from within the tolerance reaches the root to rounding. No step is taken where
    it would exceed 1e-6 rad (next to a fold, where ``dr/d delta`` vanishes and the phase
    is known only to about ``sqrt(eps)`` anyway).
    """
    cd, sd = math.cos(delta), math.sin(delta)
    slope = -c * sd + s * cd
    step = (c * cd + s * sd - b) / slope if slope != 0.0 else math.inf
    return delta - step if abs(step) <= _ROOT_STEP else delta


class _LeftTheStepError(ArithmeticError):
    """Newton on the fold system left the box around the step."""


class PeriodicBranchProblem:
    """Eq. (14) as ``F(u, lam) = 0`` with ``u = [delta]`` and ``lam`` a model parameter.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator; its value of `parameter` is replaced by ``lam``.
    N : int
        One impact every N forcing periods.
    parameter : str
        One of :data:`CONTINUABLE_PARAMETERS` or an element name (``m2``, ``k1``, ``c1``,
        ``M[1,2]``, ``K[1,2]``, ``C[1,2]``, ``F[2]``), as a
        :class:`~impactcont.model.parameters.ModelParameter` (:attr:`param`).

    Notes
    -----
    ``c, s`` (eq. 13) come from the compiled kernel in modal form (O(n) per
    parameter value, cached); when the parameter moves the stop (``b``) they do not
    depend on it at all, and they are affine in the forcing amplitude (``F0``, ``F[j]``:
    eq. 13 is linear in F). Their derivative is exact in omega and R (the chain rule in
    real arithmetic, :func:`~impactcont.kernel.closed_form.setup_slope`: no complex
    variant of the flights is compiled for the first branch), in the proportional damping
    (one complex-step evaluation of the same kernel: no step-size error, no
    cancellation), in the stop and the forcing; in the elements (masses, springs, dampers,
    matrix entries: a new modal basis at each value) and on the first-order path in the
    damping it is the parameter's finite-difference fallback
    (:meth:`~impactcont.model.parameters.ModelParameter.difference`). Eq. (14) is divided
    by :func:`residual_scale`, and differentiated with it.
    """

    #: The kinds of special points located on its branches (SN by the closed-form fold
    #: system of eq. 14-15, the others by their tests).
    events: tuple[Label, ...] = (Label.SN, *BRANCH_TESTS)
    #: The test of each kind but the fold, as functions of the motion.
    motion_tests: ClassVar[Mapping[str, MotionTest]] = BRANCH_TESTS

    #: Impacts per motion, and their stops (the paper's one stop).
    p = 1
    pattern = "U"
    #: The closed form checks contact at no extra cost: one motion per trial point.
    separate_checks = False
    #: Its datasets keep the paper's N-1 schema (no ``impact`` dimension; read as p = 1).
    impact_dimension = False
    #: The motion at a point is evaluated once the branch is traced: nothing of the
    #: corrector's is reused (a shooting problem's cached shot is), and no compiled motion
    #: evaluation runs while the core may take a Ctrl-C.
    motion_in_step = False

    periods = (2.0 * math.pi,)
    """The unknown ``delta`` is a phase: a branch that returns to its start modulo 2 pi is
    a closed loop (read by the continuation driver)."""

    def __init__(self, osc: ImpactOscillator, N: int, parameter: str) -> None:
        self.param = model_parameter(osc, parameter)
        require_paper_stops(osc, "the N-1 branch")  # stops: mass 1, one stop only
        self.osc = osc
        self.N = N
        self.parameter = parameter
        self._general = osc.general  # general damping matrix or complex F: first-order path
        self._cache: dict[float, tuple[float, float, float, float]] = {}
        self._forcing_slope: tuple[float, float] | None = None  # d(c, s)/d lam, affine in F
        self._osc_cache: dict[float, ImpactOscillator] = {}
        # the compiled kernel's exact derivative serves omega, R and the decay rates on the
        # proportional path; the elements change the modes (a new basis per value)
        self._kernel = None if self._general else self.param.kernel
        if self._general:
            return
        arrays = modal_arrays(osc)
        self._w, self._a, self._f = arrays.w, arrays.a, arrays.f
        self._u0, self._ui0 = arrays.u0, arrays.ui0
        self._da = self.param.decay_rates_derivative(arrays.w)

    # -- the oscillator along the branch ------------------------------------------------------
    def oscillator_at(self, lam: float) -> ImpactOscillator:
        """The oscillator with ``parameter = lam`` (sharing the modal basis)."""
        lam = float(lam)
        hit = self._osc_cache.get(lam)
        if hit is None:
            if len(self._osc_cache) > 64:
                self._osc_cache.clear()
            hit = self._osc_cache[lam] = self.param.at(self.osc, lam)
        return hit

    def _arguments(self, lam: float) -> tuple:
        """Kernel arguments ``(a, R, omega)`` at ``lam``."""
        osc = self.osc
        a = self._a
        R, omega = osc.R, osc.omega
        if self._kernel == 0:
            omega = lam
        elif self._kernel == 1:
            R = lam
        elif self._kernel == 2:  # the decay rates are linear in eta, alpha, beta (eq. 6)
            a = a + (lam - self.param.value(osc)) * self._da
        return a, R, omega

    def amplitude(self, lam: float) -> tuple[float, float, float]:
        """``c, s`` of eq. (14) and the gap ``b`` at ``lam``."""
        lam = float(lam)
        return (self._cache.get(lam) or self._setup(lam))[:3]

    def _setup(self, lam: float) -> tuple[float, float, float, float]:
        """``c, s, b`` and :func:`residual_scale` (real) at ``lam`` (a float), cached (the
        callers read the cache first)."""
        from impactcont.kernel import closed_form as kernel

        data = self.param.data
        b = self.oscillator_at(lam).b if data == GAP else self.osc.b
        if data == GAP and self._cache:
            c, s = next(iter(self._cache.values()))[:2]  # c, s do not depend on the gap
        elif data == GAP:
            c, s = self._amplitude_at(self.param.value(self.osc))
        elif data == FORCING:  # affine in F: c(lam) = c(lam0) + (lam - lam0) dc/dlam
            self._check(lam)
            lam0 = self.param.value(self.osc)
            (c0, s0), (dc, ds) = self._amplitude_at(lam0), self._forcing_derivative()
            c, s = c0 + (lam - lam0) * dc, s0 + (lam - lam0) * ds
        elif self._kernel is not None:
            self._check(lam)
            a, R, omega = self._arguments(lam)
            c, s = kernel.amplitude(self._w, a, self._f, self._u0, self._ui0, R, omega, self.N)
            c, s = float(c), float(s)
        else:
            self._check(lam)
            c, s = self._amplitude_at(lam)
        if len(self._cache) > 256:
            self._cache.clear()
        hit = self._cache[lam] = (c, s, b, max(1.0, math.hypot(c, s) / _UNSCALED))
        return hit

    def _amplitude_at(self, lam: float) -> tuple[float, float]:
        """``c, s`` of eq. (14) of the oscillator at ``lam``, built anew (its own modal or
        first-order basis, the kernel's parameters as they are)."""
        from impactcont.kernel import closed_form as kernel

        osc = self.oscillator_at(lam)
        if osc.general:
            c, s = general.amplitude(osc, self.N)[:2]
            return float(c), float(s)
        arrays = modal_arrays(osc)
        c, s = kernel.amplitude(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0, osc.R,
                                osc.omega, self.N)
        return float(c), float(s)

    def _forcing_derivative(self) -> tuple[float, float]:
        """``d(c, s)/d lam`` in the forcing amplitude: constant (eq. 13 is linear in F), so
        the parameter's difference with its large step is exact to rounding."""
        if self._forcing_slope is None:
            lam0 = self.param.value(self.osc)
            dc, ds = self.param.difference(self._amplitude_at, lam0, self.osc)
            self._forcing_slope = (float(dc), float(ds))
        return self._forcing_slope

    def _check(self, lam: float) -> None:
        """Refuse an iterate where eq. (14) is undefined (the corrector then halves).

        ``c, s`` are analytic in R and the damping beyond their physical ranges (the
        kernel's parameters 1 and 2), so a predictor may overshoot ``R = 1`` or ``eta = 0``
        and the driver lands on the bound; outside its range every other parameter is
        refused (``omega <= 0``: no period; ``F0 <= 0``; a mass at 0), as are non-finite
        values.
        """
        analytic = self._kernel in (1, 2)
        if not math.isfinite(lam) or not (analytic or self.param.info.contains(lam)):
            raise ParameterError(f"{self.parameter}={lam!r} is outside its allowed range "
                                 f"({self.param.info.allowed})")

    def _amplitude_derivative(self, lam: float) -> tuple[float, float, float]:
        from impactcont.kernel import closed_form as kernel

        data = self.param.data
        if data == GAP:
            return 0.0, 0.0, self.param.upper
        self._check(lam)
        if data == FORCING:
            return (*self._forcing_derivative(), 0.0)
        if self._general and self.param.kernel in (0, 1):  # omega, R: exact there too
            _, _, dc, ds = general.amplitude(self.oscillator_at(lam), self.N, self.parameter)
            return dc, ds, 0.0
        if self._kernel is None:  # the elements; the damping on the first-order path
            dc, ds = self.param.difference(self._amplitude_at, float(lam),
                                           self.oscillator_at(lam))
            return float(dc), float(ds), 0.0
        a, R, omega = self._arguments(float(lam))
        if self._kernel == 2:  # the damping: the complex step (its variants compiled here only)
            dc, ds = kernel.amplitude_derivative(self._w, a, self._f, self._u0, self._ui0, R,
                                                 omega, self.N, self._kernel, self._da)
        else:
            _, slope = kernel.setup_slope(self._w, a, self._f, self._u0, self._ui0, R, omega,
                                          self.N, self._kernel)
            dc, ds = slope[5], slope[6]
        return float(dc), float(ds), 0.0

    # -- the Problem protocol ------------------------------------------------------------------
    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``r = c cos(delta) + s sin(delta) - b`` (eq. 14) over :func:`residual_scale`,
        shape (1,)."""
        lam = float(lam)
        c, s, b, scale = self._cache.get(lam) or self._setup(lam)
        d = float(u[0])
        return np.array([(c * math.cos(d) + s * math.sin(d) - b) / scale])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dr/d delta`` over :func:`residual_scale`, shape (1, 1)."""
        lam = float(lam)
        c, s, _, scale = self._cache.get(lam) or self._setup(lam)
        d = float(u[0])
        return np.array([[(-c * math.sin(d) + s * math.cos(d)) / scale]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``d/d lam`` of :meth:`residual` (:func:`scaled_derivative`), shape (1,)."""
        dc, ds, db = self._amplitude_derivative(lam)
        cd, sd = math.cos(float(u[0])), math.sin(float(u[0]))
        lam = float(lam)
        c, s, b, scale = self._cache.get(lam) or self._setup(lam)
        if scale == 1.0:
            return np.array([dc * cd + ds * sd - db])
        return np.array([scaled_derivative(c * cd + s * sd - b, dc * cd + ds * sd - db, c, s,
                                           dc, ds)])

    # -- where the parameter may go (the branch problem's interface) ---------------------------
    def parameter_limits(self) -> tuple[float, float]:
        """Open interval of the parameter where the stop exists: unlimited (the paper's one
        stop; a parameter's own range is checked by the oscillator)."""
        return -math.inf, math.inf

    def limit_reason(self) -> str:
        """Why the parameter cannot reach :meth:`parameter_limits`: "" (unlimited)."""
        return ""

    def check_bounds(self, bounds: tuple[float, float]) -> None:
        """Refuse a range that reaches elastic impacts without damping (R = 1, C = 0).

        There eq. (12) is singular and eq. (14) is replaced by ``x1p'(delta) = 0``
        (``docs/kernel.md``): the branch equation changes, so a branch cannot be followed
        into that case; :func:`impactcont.periodic_orbits` solves it point by point. The
        parameter's own range is checked by the driver
        (:meth:`~impactcont.model.parameters.ModelParameter.check_bounds`).

        Raises
        ------
        ParameterError
            Naming the parameter, the bounds and what to do instead.
        """
        lo, hi = (float(v) for v in bounds)
        osc, parameter = self.osc, self.parameter
        if osc.general_damping:  # only whether the damping vanishes matters here
            alpha, beta = (1.0 if np.any(osc.C) else 0.0), 0.0
        else:
            alpha, beta = osc.rayleigh
        undamped = {"eta": lo == 0.0, "alpha": lo == 0.0 and beta == 0.0,
                    "beta": lo == 0.0 and alpha == 0.0}.get(parameter,
                                                            alpha == 0.0 and beta == 0.0)
        # a parameter that is the stop's restitution (eq. 4) reaches R = 1 at hi >= 1
        elastic = (hi >= 1.0 if self.param.data == RESTITUTION and self.param.upper
                   else osc.R == 1.0)
        if undamped and elastic:
            raise ParameterError(
                f"continuation in {parameter} over [{lo!r}, {hi!r}] reaches elastic impacts "
                "without damping (R = 1, no damping), where eq. (12) is singular and the "
                "motions obey another equation; use periodic_orbits at each value there, add "
                "damping or keep R below 1")

    # -- the seeds of its branches: the roots of eq. (15) ---------------------------------------
    def start_value(self, bounds: tuple[float, float], start: float | None) -> float:
        """The parameter value a branch starts from: `start`, else the oscillator's value
        inside `bounds`, else the first of :data:`EXISTENCE_SCAN` values of `bounds` where
        eq. (15) has a root (``c^2 + s^2 >= b^2``).

        Raises
        ------
        ParameterError
            `start` outside `bounds`.
        NoPeriodicMotionError
            No motion anywhere in `bounds`.
        """
        lo, hi = bounds
        if start is not None:
            if not lo <= start <= hi:
                raise ParameterError(f"start must lie within bounds {bounds}; got {start!r}")
            return float(start)
        current = self.param.value(self.osc)
        candidates = [current] if lo <= current <= hi else []
        candidates += list(np.linspace(lo, hi, EXISTENCE_SCAN))
        for lam in candidates:
            c, s, b = self.amplitude(float(lam))
            if c * c + s * s >= b * b:
                return float(lam)
        raise NoPeriodicMotionError(
            f"no N={self.N} motion anywhere in {self.parameter} in {bounds} "
            f"(c^2 + s^2 < b^2 at all {EXISTENCE_SCAN} values scanned)")

    def start_root(self, lam: float, root: int | None) -> np.ndarray:
        """The unknowns ``[delta]`` of the motion at `lam` a branch starts on: the root
        ``+1``/``-1`` of eq. (15), default the physical (then stable) one.

        Raises
        ------
        ParameterError
            `root` not +1, -1 or None.
        NoPeriodicMotionError
            No motion at `lam`.
        """
        orbits = periodic_orbits(self.oscillator_at(lam), self.N)
        if not orbits:
            raise NoPeriodicMotionError(f"no N={self.N} motion at {self.parameter}={lam!r}")
        if root is not None:
            if root not in (1, -1):
                raise ParameterError(f"root must be +1, -1 or None; got {root!r}")
            chosen = [o for o in orbits if o.root == root] or orbits
        else:
            chosen = sorted(orbits, key=lambda o: (not o.physical, not o.stable))
        return np.array([chosen[0].delta])

    def component_seeds(self, bounds: tuple[float, float]) -> list[tuple[float, np.ndarray]]:
        """Both roots of eq. (15) at the best-separated scan value of every existence
        interval, as ``(lam, [delta])``.

        Motions exist where ``c^2 + s^2 >= b^2`` (eq. 15); each maximal interval of scan
        values where they do holds one or two connected components of the solution set
        (the roots join at the folds that end the interval, or run to the bounds apart).
        Between scan values the discriminant is maximised wherever it has a local maximum
        below 0, so an interval narrower than the scan step is found too.
        """
        def discriminant(lam: float) -> float:
            c, s, b = self.amplitude(lam)
            return c * c + s * s - b * b

        lams = list(np.linspace(bounds[0], bounds[1], EXISTENCE_SCAN))
        disc = [discriminant(float(lam)) for lam in lams]
        # a component narrower than the scan step shows as a local maximum of the
        # discriminant below 0 between scan values: maximise it there and keep it if >= 0
        for k in range(len(lams) - 2, 0, -1):
            if disc[k] < 0 and disc[k] >= disc[k - 1] and disc[k] >= disc[k + 1]:
                best = minimize_scalar(lambda x: -discriminant(x),
                                       bounds=(lams[k - 1], lams[k + 1]), method="bounded",
                                       options={"xatol": 1e-12})
                if -best.fun >= 0:
                    log.info("narrow component found at %s=%.12g", self.parameter, best.x)
                    lams.insert(k + 1, float(best.x))
                    disc.insert(k + 1, -float(best.fun))
        seeds = []
        exists = np.asarray(disc) >= 0
        edges = np.flatnonzero(np.diff(np.r_[0, exists.astype(int), 0]))
        for first, last in zip(edges[::2], edges[1::2], strict=True):
            k = first + int(np.argmax(disc[first:last]))
            c, s, b = self.amplitude(float(lams[k]))
            r2, root = c * c + s * s, math.sqrt(max(disc[k], 0.0))
            for sign in (1.0, -1.0):
                seeds.append((float(lams[k]), np.array([math.atan2(
                    (b * s + sign * c * root) / r2, (b * c - sign * s * root) / r2)])))
        return seeds

    # -- what the branch carries ----------------------------------------------------------------
    def orbit(self, u: np.ndarray | float, lam: float, *, checks: bool = True
              ) -> PeriodicOrbit:
        """The full periodic motion (state, G, multipliers, checks) at a branch point: that
        of the root of eq. (14) nearest its phase (:func:`root_phase`).

        `u` is the unknowns ``[delta]`` (or the phase ``delta``); the closed form's contact
        check costs nothing extra, so `checks` is accepted and always made
        (:attr:`separate_checks`).
        """
        delta = float(u) if np.ndim(u) == 0 else float(u[0])
        lam = float(lam)
        c, s, b, _ = self._cache.get(lam) or self._setup(lam)
        return orbit_at_phase(self.oscillator_at(lam), self.N, root_phase(c, s, b, delta))

    def locate_fold(self, left: Any, right: Any) -> tuple[np.ndarray, float, float, str, bool]:
        """The fold between two accepted points (samples with ``u``, ``lam``, ``dlam``):
        Newton on ``r = dr/d delta = 0`` (eq. 14-15), the closed form's exact fold.

        Newton starts at the middle of the step and is held to a box around it (the
        step's phases and parameters widened by the step's own size on each side): at
        a fold both bracketing points lie on one side of it in the parameter, close to
        it on a step the continuation accepted. When Newton leaves the box, would leave
        the parameter's domain (e.g. ``omega <= 0``) or does not converge, the fold is
        located as a sign change of the tangent's parameter component on the branch
        between the two points (:func:`~impactcont.core.locate_events`), which never
        leaves the step; a failure there keeps the point as bracketed.

        Returns
        -------
        u, lam, precision, status, failed
        """
        try:
            delta, lam, precision, status = self._fold_newton(left, right)
            return np.array([delta]), lam, precision, status, False
        except (ParameterError, np.linalg.LinAlgError, _LeftTheStepError) as exc:
            log.debug("fold Newton between %s=%.12g and %.12g gave up (%s); locating the sign "
                      "change of d%s/ds on the branch", self.parameter, left.lam, right.lam,
                      exc, self.parameter)
        (ep,) = locate_events(self, [[left.delta], [right.delta]], [left.lam, right.lam],
                              [[0.0, left.dlam], [0.0, right.dlam]], [Event(Label.SN, None)],
                              s_tol=_FOLD_XTOL)
        return np.asarray(ep.u, dtype=float), ep.lam, ep.precision, ep.status, ep.failed

    def _fold_newton(self, left: Any, right: Any) -> tuple[float, float, float, str]:
        lo = np.array([min(left.delta, right.delta), min(left.lam, right.lam)])
        hi = np.array([max(left.delta, right.delta), max(left.lam, right.lam)])
        width = hi - lo
        box_lo, box_hi = lo - width, hi + width
        x = 0.5 * (lo + hi)
        step = np.full(2, np.inf)
        for _ in range(50):
            F = self.fold_residual(x[0], x[1])
            step = np.linalg.solve(self.fold_jacobian(x[0], x[1]), F)
            x = x - step
            if not (np.all(np.isfinite(x)) and np.all(box_lo <= x) and np.all(x <= box_hi)):
                raise _LeftTheStepError(f"Newton reached (delta, {self.parameter}) = "
                                        f"({x[0]:.6g}, {x[1]:.6g})")
            if abs(step[1]) < 1e-15 * max(1.0, abs(x[1])) and abs(step[0]) < 1e-14:
                break
        else:
            raise _LeftTheStepError("Newton did not converge in 50 steps")
        # at a fold lam is extremal, so both bracketing points lie on one side of it in lam;
        # delta runs monotonically through the fold and must be bracketed
        slack = 1e-9 * max(width[0], 1e-12)
        inside = lo[0] - slack <= x[0] <= hi[0] + slack
        # Newton on r = r_delta = 0 converges quadratically; the last step bounds the error,
        # the finite-difference parameter derivative only slows it down
        precision = max(abs(step[1]) * 10, 4 * np.finfo(float).eps * abs(x[1]))
        return float(x[0]), float(x[1]), precision, "located" if inside else "bracketed"

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

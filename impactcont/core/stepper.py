"""Pseudo-arclength continuation (PALC) stepper with an adaptive step.

The stepper follows the solution curve of ``F(u, lam) = 0`` in the extended
space ``x = (u, lam)``. Lengths and angles are measured in the scaled norm

    ``||(du, dlam)||^2 = ||du||^2 / m + theta * dlam^2``,

with ``m`` the number of unknowns and ``theta`` the weight of the parameter.
One step is a tangent predictor ``x_pred = x + ds * t`` followed by Newton on
the bordered system ``[F(x); <t, x - x_pred>] = 0``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from impactcont.core.options import ContinuationOptions
from impactcont.core.point import ContinuationPoint
from impactcont.core.problem import (
    FloatArray,
    Problem,
    check_problem_outputs,
    evaluate_monitors,
)
from impactcont.errors import ParameterError

__all__ = [
    "BoundReachedError",
    "ContinuationStepError",
    "CorrectorResult",
    "NewtonConvergenceError",
    "PalcStepper",
    "StepSizeBelowMinimumError",
]

logger = logging.getLogger(__name__)

STEP_GROWTH_FACTOR = 1.5
"""Factor applied to the step after an easy step."""
STEP_SLOW_NEWTON_FACTOR = 0.75
"""Factor applied to the step when Newton needed more than the target iterations."""
STEP_REJECTION_FACTOR = 0.5
"""Factor applied to the step after a rejected step."""
FOLD_DLAM_TOLERANCE = 1e-12
"""Relative size below which the ``dlam`` of the initial tangent counts as zero."""
SINGULAR_CONDITION = 1.0 / np.finfo(float).eps
"""Condition number above which a matrix is singular to working precision."""


@dataclass(frozen=True, eq=False)
class CorrectorResult:
    """One step's corrector and tangent computed by the problem itself (``palc_step``).

    A problem may provide ``palc_step(predicted, tangent, weights, tol, max_iter) ->
    CorrectorResult | None``: Newton on ``[F(x); <W t, x - x_pred>] = 0`` from ``x_pred``
    with the tests of :meth:`PalcStepper._correct_on_hyperplane`, then the (not
    normalised) tangent of :meth:`PalcStepper._tangent_at` at the point (None: the core
    corrects as usual).

    Attributes
    ----------
    state : ndarray, shape (m + 1,)
        The last iterate ``(u, lam)``.
    iterations : int
        Newton updates taken.
    status : str
        ``"converged"``, ``"not converged"``, ``"refused"`` (the problem refuses ``lam``:
        `message` says why), ``"non-finite residual"``, ``"non-finite system"``,
        ``"singular"`` or ``"non-finite update"``.
    lam : float
        The last ``lam`` evaluated.
    residual_norm : float
        Max-norm of the last residual.
    tangent : ndarray, shape (m + 1,)
        The raw tangent (converged only).
    ill_conditioned : ndarray or None
        A bordered matrix whose condition number may exceed :data:`SINGULAR_CONDITION`
        (the stepper checks it and warns as for its own solves).
    message : str
        Why ``lam`` was refused.
    last_step : float
        Max-norm of the last update.

    Notes
    -----
    ``palc_step(..., hyperplane=True)`` is asked by
    :func:`~impactcont.core.corrector.solve_on_hyperplane` for its own Newton (``weights``
    ones, ``tangent`` the normal, converged when an update is at most ``tol``; the point
    after it and no tangent); any status but ``"converged"`` and ``"not converged"``
    makes it run its own loop.
    """

    state: FloatArray
    iterations: int
    status: str
    lam: float
    residual_norm: float
    tangent: FloatArray
    ill_conditioned: FloatArray | None = None
    message: str = ""
    last_step: float = math.nan


class ContinuationStepError(RuntimeError):
    """Base class of the failures of the stepper."""


class NewtonConvergenceError(ContinuationStepError):
    """Newton's method did not converge."""


class StepSizeBelowMinimumError(ContinuationStepError):
    """No step of at least ``ds_min`` could be accepted."""


class BoundReachedError(ContinuationStepError):
    """The last point lies on a bound of ``lam`` and every step leaves the bounds.

    Raised by :meth:`PalcStepper.step` when a step from a point exactly on a
    bound is refused past it (the problem is not defined there): the branch
    has reached the bound, as when a step past it is accepted.

    Attributes
    ----------
    bound : float
        The bound of ``lam`` the last point lies on.
    """

    def __init__(self, bound: float, message: str) -> None:
        super().__init__(message)
        self.bound = bound


class PalcStepper:
    """Pseudo-arclength stepper along the solution curve of a :class:`Problem`.

    Parameters
    ----------
    problem : Problem
        The system ``F(u, lam) = 0``.
    options : ContinuationOptions
        Step sizes, Newton tolerances and the adaptive rule.
    direction : int, optional
        Sign of ``dlam`` of the initial tangent, ``+1`` or ``-1``; defaults to
        ``options.direction``.

    Notes
    -----
    Call :meth:`init` once, then :meth:`step` repeatedly. :attr:`current`
    holds the last accepted point.
    """

    def __init__(
        self, problem: Problem, options: ContinuationOptions, direction: int | None = None
    ) -> None:
        self.problem = problem
        self.options = options
        self.direction = options.direction if direction is None else direction
        if self.direction not in (1, -1):
            raise ValueError(f"direction = {direction!r} is invalid; it must be +1 or -1")
        self.ds = options.ds
        self._evaluated_lam = math.nan  # lam of the last evaluation of the problem
        self._weights: FloatArray | None = None
        self._current: ContinuationPoint | None = None

    # ------------------------------------------------------------------ state

    @property
    def current(self) -> ContinuationPoint:
        """The last accepted point."""
        if self._current is None:
            raise RuntimeError("PalcStepper.init(u0, lam0) must be called before stepping")
        return self._current

    def scaled_dot(self, a: FloatArray, b: FloatArray) -> float:
        """Scaled inner product of two extended vectors ``(u, lam)``.

        Overflow gives ``inf`` silently; the Newton loops reject non-finite values.
        """
        # Python floats: no numpy call overhead on these short vectors, and overflow
        # gives inf without a warning
        return math.fsum(w * x * y for w, x, y in zip(self._metric_weights().tolist(),
                                                       np.ravel(a).tolist(),
                                                       np.ravel(b).tolist(), strict=True))

    def scaled_norm(self, a: FloatArray) -> float:
        """Scaled norm of an extended vector ``(u, lam)``."""
        return math.sqrt(self.scaled_dot(a, a))

    def _metric_weights(self) -> FloatArray:
        if self._weights is None:
            raise RuntimeError("PalcStepper.init(u0, lam0) must be called first")
        return self._weights

    # ------------------------------------------------------------------- init

    def init(self, u0: FloatArray, lam0: float) -> ContinuationPoint:
        """Correct the start point at fixed parameter and compute its tangent.

        Parameters
        ----------
        u0 : ndarray, shape (m,)
            Guess of the unknowns at the start.
        lam0 : float
            Parameter value of the start point, kept fixed.

        Returns
        -------
        ContinuationPoint
            The corrected start point (index 0, ``ds = 0``).

        Raises
        ------
        NewtonConvergenceError
            If Newton does not converge at ``lam0``.
        ProblemOutputError
            If the problem's methods return arrays of the wrong shape.
        """
        u0 = np.array(u0, dtype=float)
        lam0 = float(lam0)
        m = u0.shape[0]
        self._weights = np.append(np.full(m, 1.0 / m), self.options.theta)
        check_problem_outputs(self.problem, u0, lam0)
        u, iterations = self.correct_at_fixed_parameter(u0, lam0)
        tangent = self._initial_tangent(u, lam0)
        self._current = self._make_point(u, lam0, tangent, 0.0, iterations, index=0)
        logger.debug("start point corrected at lam = %.10g in %d iterations", lam0, iterations)
        return self._current

    def init_reversed(self, start: ContinuationPoint) -> ContinuationPoint:
        """Start from the corrected start of the run in the other direction.

        What :meth:`init` computes from the same guess, without computing it again: the
        point of `start` with its tangent reversed (:meth:`init` orients the same null
        vector by the run direction, so the two tangents are exact opposites, at a fold
        too), index 0 and this stepper's direction.

        Parameters
        ----------
        start : ContinuationPoint
            The point :meth:`init` returned to the stepper of the other direction.

        Returns
        -------
        ContinuationPoint
            The start point of this run (also :attr:`current`).
        """
        if start.direction != -self.direction:
            raise ValueError(f"init_reversed: the start of a run in direction "
                             f"{start.direction:+d}; this one runs in {self.direction:+d}")
        self._weights = np.append(np.full(start.u.shape[0], 1.0 / start.u.shape[0]),
                                  self.options.theta)
        self._current = ContinuationPoint(
            u=start.u.copy(), lam=start.lam, tangent=-start.tangent, ds=0.0,
            newton_iterations=start.newton_iterations, index=0, direction=self.direction,
            monitors=dict(start.monitors))
        return self._current

    def _initial_tangent(self, u: FloatArray, lam: float) -> FloatArray:
        """Null vector of ``[J | dF/dlam]`` oriented by the run direction."""
        extended = np.column_stack([self._jacobian(u, lam), self._dparam(u, lam)])
        if not np.all(np.isfinite(extended)):
            raise NewtonConvergenceError(f"non-finite extended Jacobian at lam = {lam:.10g}")
        _, singular_values, vh = np.linalg.svd(extended)
        tangent = vh[-1]
        if singular_values.size and singular_values[-1] <= (
            singular_values[0] * tangent.size * np.finfo(float).eps
        ):
            logger.warning(
                "extended Jacobian [J | dF/dlam] has rank below m at lam = %.10g "
                "(singular values %s): the start may be a branch point",
                lam,
                singular_values,
            )
        return self._oriented(tangent, lam) / self.scaled_norm(tangent)

    def _oriented(self, tangent: FloatArray, lam: float) -> FloatArray:
        """Flip `tangent` so that its ``dlam`` has the sign of the run direction.

        At a fold (``dlam`` zero to working precision) the largest ``u``
        component gets the sign of the direction instead, so that the two
        directions still leave the start on opposite sides.
        """
        if abs(tangent[-1]) > FOLD_DLAM_TOLERANCE * np.max(np.abs(tangent)):
            return tangent if np.sign(tangent[-1]) == self.direction else -tangent
        largest = int(np.argmax(np.abs(tangent[:-1])))
        logger.warning(
            "initial tangent has dlam = 0 at lam = %.10g (start at a fold); "
            "orienting it by the sign of its largest component u[%d] instead",
            lam,
            largest,
        )
        return tangent if np.sign(tangent[largest]) == self.direction else -tangent

    # ------------------------------------------------------------------- step

    def step(self) -> ContinuationPoint:
        """Take one adaptive pseudo-arclength step from :attr:`current`.

        A step whose corrector fails because it went past a bound of ``lam``
        (``options.bounds``: the predicted ``lam`` or the ``lam`` of the
        failing evaluation lies beyond it, typically a problem that refuses
        such values, e.g. a restitution above 1) lands on the bound instead
        (:meth:`_land_on_bound`): the point returned then has ``lam`` exactly
        on the bound. Every other rejected step halves ``ds``.

        Returns
        -------
        ContinuationPoint
            The new accepted point, also stored in :attr:`current`.

        Raises
        ------
        StepSizeBelowMinimumError
            If the step had to shrink below ``options.ds_min``.
        BoundReachedError
            If :attr:`current` lies on a bound and the steps past it are refused.
        """
        previous = self.current
        landing_tried = False
        while True:
            self._evaluated_lam = math.nan
            try:
                point, angle = self._try_step(previous, self.ds)
            except NewtonConvergenceError as error:
                reason = f"Newton failed ({error})"
                bound = None if landing_tried else self._bound_passed(previous, self.ds)
                if bound is not None:
                    landing_tried = True
                    landed, why_not = self._land_on_bound(previous, bound)
                    if landed is not None:
                        return landed
                    reason += f"; {why_not}"
            else:
                correction = self._correction(previous, point, self.ds)
                if angle <= self.options.max_angle and correction is None:
                    self.ds = self._adapted_step(self.ds, point.newton_iterations, angle)
                    self._current = point
                    return point
                reason = (f"tangent turned by {angle:.3g} rad > max_angle"
                          if correction is None else correction)
            self._shrink_after_rejection(previous, reason)

    def _correction(self, previous: ContinuationPoint, point: ContinuationPoint, ds: float
                    ) -> str | None:
        """Why `point` is too far from its predictor ``previous + ds * tangent``; None if not.

        An arc of length ``ds`` whose tangent turns by ``theta`` ends ``ds tan(theta / 2)``
        from the predictor; with ``theta <= max_angle`` a corrected point (scaled norm)
        farther than ``ds * max_angle`` (twice that, with room for Newton's error) was
        not reached along the branch: the corrector jumped to another part of it, or
        over a bend, and with it over the special points in between.
        """
        predicted = previous.state + ds * previous.tangent
        correction = self.scaled_norm(point.state - predicted)
        limit = ds * self.options.max_angle
        if correction <= limit:
            return None
        return (f"the corrector moved the point {correction:.3g} from its predictor, more "
                f"than ds * max_angle = {limit:.3g} (a jump along the branch)")

    def _bound_passed(self, previous: ContinuationPoint, ds: float) -> float | None:
        """The bound of ``lam`` that a failed step of size `ds` went past, ``None`` if none.

        The step went past a bound when its predicted ``lam`` or the last
        ``lam`` the problem was evaluated at (where the corrector failed) lies
        strictly beyond it.
        """
        if self.options.bounds is None:
            return None
        lam_min, lam_max = self.options.bounds
        predicted = previous.lam + ds * float(previous.tangent[-1])
        tried = (predicted, self._evaluated_lam)  # nan compares False: not past
        if any(lam > lam_max for lam in tried):
            return lam_max
        if any(lam < lam_min for lam in tried):
            return lam_min
        return None

    def _land_on_bound(self, previous: ContinuationPoint, bound: float
                       ) -> tuple[ContinuationPoint | None, str]:
        """Land on ``lam = bound`` from `previous` after a step past it failed.

        The predictor is shortened so that its ``lam`` is exactly `bound`, and
        Newton then corrects ``u`` at that fixed ``lam``
        (:meth:`land_on_parameter`), so the problem is never evaluated past
        the bound. The landed point is accepted by the test of a step: the
        tangent turns by at most ``max_angle``; the shortened step is at most
        ``ds_max``; and the corrector moved it at most ``ds * max_angle`` (scaled)
        from its predictor, as far as an arc of length ``ds`` turning by
        ``max_angle`` strays from its tangent (a landing corrected farther jumped
        over a bend of the branch).

        Returns
        -------
        point : ContinuationPoint or None
            The point on the bound (also :attr:`current`), or ``None`` when it
            was not found (the caller shrinks the step as after any failure).
        why_not : str
            Why there is no point (empty when there is one).

        Raises
        ------
        BoundReachedError
            If `previous` itself lies on `bound` with its tangent pointing past it.
        """
        dlam = float(previous.tangent[-1])
        if previous.lam == bound and (dlam > 0.0 if bound == self.options.bounds[1]
                                      else dlam < 0.0):
            raise BoundReachedError(bound, f"lam = {bound:.10g} reached; the steps past it "
                                           f"were refused")
        ds = (bound - previous.lam) / dlam if dlam != 0.0 else math.inf
        if not 0.0 < ds <= self.options.ds_max:
            return None, (f"the tangent does not reach the bound lam = {bound:.10g} within "
                          f"ds_max = {self.options.ds_max:.3g}")
        guess = previous.state + ds * previous.tangent
        target = ContinuationPoint(u=guess[:-1], lam=bound, tangent=previous.tangent, ds=ds,
                                   newton_iterations=0, index=previous.index + 1,
                                   direction=self.direction)
        try:
            point = self.land_on_parameter(previous, target, bound)
        except NewtonConvergenceError as error:
            self._current = previous
            return None, f"landing on the bound lam = {bound:.10g} failed ({error})"
        angle = float(np.arccos(_clip(self.scaled_dot(previous.tangent, point.tangent),
                                      -1.0, 1.0)))
        if angle > self.options.max_angle:
            self._current = previous
            return None, (f"the point on the bound lam = {bound:.10g} turns the tangent by "
                          f"{angle:.3g} rad > max_angle")
        too_far = self._correction(previous, point, ds)
        if too_far is not None:
            self._current = previous
            return None, f"the point on the bound lam = {bound:.10g}: {too_far}"
        logger.debug("step past the bound lam = %.10g refused; landed on it from lam = %.10g",
                     bound, previous.lam)
        return point, ""

    def _shrink_after_rejection(self, previous: ContinuationPoint, reason: str) -> None:
        rejected_ds = self.ds
        self.ds = rejected_ds * STEP_REJECTION_FACTOR
        logger.debug(
            "step ds = %.3g from lam = %.10g rejected: %s", rejected_ds, previous.lam, reason
        )
        if self.ds < self.options.ds_min:
            raise StepSizeBelowMinimumError(
                f"step {self.ds:.3g} fell below ds_min = {self.options.ds_min:.3g} "
                f"at lam = {previous.lam:.10g}: {reason}"
            )

    def _try_step(self, previous: ContinuationPoint, ds: float) -> tuple[ContinuationPoint, float]:
        """Predict, correct and compute the new tangent; return the point and turn angle."""
        predicted = previous.state + ds * previous.tangent
        compiled = self._problem_step(predicted, previous.tangent)
        if compiled is None:
            state, iterations = self._correct_on_hyperplane(predicted, previous.tangent)
            u, lam = state[:-1], float(state[-1])
            tangent = self._tangent_at(u, lam, previous.tangent)
        else:
            state, iterations, tangent = compiled
            u, lam = state[:-1], float(state[-1])
        cosine = _clip(self.scaled_dot(previous.tangent, tangent), -1.0, 1.0)
        point = self._make_point(u, lam, tangent, ds, iterations, index=previous.index + 1)
        return point, float(np.arccos(cosine))

    def _problem_step(self, predicted: FloatArray, tangent: FloatArray
                      ) -> tuple[FloatArray, int, FloatArray] | None:
        """The problem's own corrector and tangent (``palc_step``, :class:`CorrectorResult`)
        with the stepper's errors and warnings; None when it has none."""
        step = getattr(self.problem, "palc_step", None)
        if step is None or predicted.size == 2:
            return None
        result = step(predicted.copy(), tangent.copy(), self._metric_weights(),
                      self.options.newton_tol, self.options.newton_max_iter)
        if result is None:
            return None
        lam = result.lam
        self._evaluated_lam = lam
        if result.ill_conditioned is not None:
            condition = _condition_number(result.ill_conditioned)
            if condition > SINGULAR_CONDITION:
                logger.warning("matrix singular to working precision at lam = %.10g "
                               "(condition number %.3e)", lam, condition)
        if result.status != "converged":  # the message only when it is raised
            raise NewtonConvergenceError(self._failure(result.status, result))
        tangent = np.asarray(result.tangent, dtype=float)
        if not np.isfinite(tangent).all():
            raise NewtonConvergenceError(self._failure("non-finite update", result))
        state = np.array(result.state, dtype=float)
        return state, result.iterations, tangent / self.scaled_norm(tangent)

    def _failure(self, status: str, result: CorrectorResult) -> str:
        """Why the problem's corrector (:meth:`_problem_step`) failed (`status`), in the
        stepper's words."""
        lam = result.lam
        failure = {
            "not converged": f"corrector did not converge in {self.options.newton_max_iter} "
                             f"iterations (residual {result.residual_norm:.3g})",
            "refused": f"the problem refused lam = {lam:.10g}: {result.message}",
            "non-finite residual": f"non-finite residual at lam = {lam:.10g}",
            "non-finite system": f"non-finite linear system at lam = {lam:.10g}",
            "singular": f"singular matrix at lam = {lam:.10g}",
            "non-finite update": f"non-finite Newton update at lam = {lam:.10g}",
        }
        return failure.get(status, status)

    def _adapted_step(self, ds: float, iterations: int, angle: float) -> float:
        """Step size for the next step after an accepted one."""
        if iterations <= self.options.target_newton_iter and angle <= self.options.max_angle / 2:
            ds *= STEP_GROWTH_FACTOR
        elif iterations > self.options.target_newton_iter:
            ds *= STEP_SLOW_NEWTON_FACTOR
        return float(_clip(ds, self.options.ds_min, self.options.ds_max))

    def _tangent_at(self, u: FloatArray, lam: float, reference: FloatArray) -> FloatArray:
        """Unit tangent at ``(u, lam)`` with positive scaled dot product with `reference`."""
        if u.size == 1:  # one unknown: the 2 x 2 bordered system in Python floats
            return self._tangent_one_unknown(u, lam, reference)
        bordered = self._bordered_matrix(u, lam, reference)
        right_hand_side = np.zeros(bordered.shape[0])
        right_hand_side[-1] = 1.0
        tangent = self._solve(bordered, right_hand_side, lam)
        return tangent / self.scaled_norm(tangent)

    def _tangent_one_unknown(self, u: FloatArray, lam: float, reference: FloatArray
                             ) -> FloatArray:
        """:meth:`_tangent_at` for one unknown: the same Cramer solve and normalisation."""
        (w_u, w_lam), (r_u, r_lam) = self._metric_weights().tolist(), reference.tolist()
        a = float(self._jacobian(u, lam)[0, 0])
        b = float(self._dparam(u, lam)[0])
        tangent = np.array(_solve_2x2(a, b, w_u * r_u, w_lam * r_lam, 0.0, 1.0, lam))
        return tangent / self.scaled_norm(tangent)

    # ----------------------------------------------------------- bound landing

    def land_on_parameter(
        self, previous: ContinuationPoint, current: ContinuationPoint, lam_target: float
    ) -> ContinuationPoint:
        """Solve for the point at ``lam = lam_target`` between two accepted points.

        The guess is the linear interpolation of `previous` and `current` at
        `lam_target`, which must lie between their parameter values. The
        result replaces `current` as :attr:`current`.

        Parameters
        ----------
        previous, current : ContinuationPoint
            Consecutive accepted points whose parameters bracket `lam_target`.
        lam_target : float
            Parameter value of the new point.

        Returns
        -------
        ContinuationPoint
            The point on the branch at ``lam_target``, with the index of `current`.

        Raises
        ------
        NewtonConvergenceError
            If Newton at fixed ``lam_target`` does not converge.
        """
        fraction = (lam_target - previous.lam) / (current.lam - previous.lam)
        u_guess = previous.u + fraction * (current.u - previous.u)
        u, iterations = self.correct_at_fixed_parameter(u_guess, lam_target)
        tangent = self._tangent_at(u, lam_target, previous.tangent)
        ds = self.scaled_norm(np.append(u, lam_target) - previous.state)
        point = self._make_point(u, lam_target, tangent, ds, iterations, index=current.index)
        self._current = point
        return point

    # ----------------------------------------------------------------- Newton

    def correct_at_fixed_parameter(self, u_guess: FloatArray, lam: float) -> tuple[FloatArray, int]:
        """Newton's method on ``F(u, lam) = 0`` in ``u`` at fixed `lam`.

        Returns
        -------
        u : ndarray, shape (m,)
            The converged unknowns.
        iterations : int
            Number of Newton updates.

        Raises
        ------
        NewtonConvergenceError
            If the iteration does not converge in ``options.newton_max_iter``
            updates or produces non-finite values.
        """
        u = np.array(u_guess, dtype=float)
        last_update_norm = math.inf
        for iteration in range(self.options.newton_max_iter + 1):
            residual = self._residual(u, lam)
            if self._converged(residual, last_update_norm, iteration):
                return u, iteration
            if iteration == self.options.newton_max_iter:
                break
            update = self._solve(self._jacobian(u, lam), -residual, lam)
            last_update_norm = float(np.max(np.abs(update)))
            u = u + update
        raise NewtonConvergenceError(
            f"no convergence at fixed lam = {lam:.10g} in {self.options.newton_max_iter} "
            f"iterations (residual {np.max(np.abs(residual)):.3g})"
        )

    def _correct_on_hyperplane(
        self, predicted: FloatArray, tangent: FloatArray
    ) -> tuple[FloatArray, int]:
        """Newton on ``[F(x); <tangent, x - predicted>] = 0`` starting at `predicted`."""
        if predicted.size == 2:
            return self._correct_one_unknown(predicted, tangent)
        state = predicted.copy()
        last_update_norm = math.inf
        for iteration in range(self.options.newton_max_iter + 1):
            u, lam = state[:-1], float(state[-1])
            residual, extended = self._linearized(u, lam)
            if self._converged(residual, last_update_norm, iteration):
                return state, iteration
            if iteration == self.options.newton_max_iter:
                break
            bordered_residual = np.concatenate(
                [residual, [self.scaled_dot(tangent, state - predicted)]])
            update = self._solve(self._bordered_matrix(u, lam, tangent, extended),
                                 -bordered_residual, lam)
            last_update_norm = float(np.max(np.abs(update)))
            state = state + update
        raise NewtonConvergenceError(
            f"corrector did not converge in {self.options.newton_max_iter} iterations "
            f"(residual {np.max(np.abs(residual)):.3g})"
        )

    def _correct_one_unknown(self, predicted: FloatArray, tangent: FloatArray
                             ) -> tuple[FloatArray, int]:
        """:meth:`_correct_on_hyperplane` for one unknown, in Python floats.

        The same arithmetic as the general loop (the 2 x 2 bordered system by Cramer's
        rule, the same tests), without building small numpy arrays: a branch of the
        N-1 motions spends most of its time here.
        """
        (w_u, w_lam), (t_u, t_lam) = self._metric_weights().tolist(), tangent.tolist()
        p_u, p_lam = predicted.tolist()
        c, d = w_u * t_u, w_lam * t_lam  # the border: the scaled tangent
        x, lam = p_u, p_lam
        last_update_norm = math.inf
        residual = math.nan
        for iteration in range(self.options.newton_max_iter + 1):
            u = np.array([x])
            residual = float(self._residual(u, lam)[0])
            if abs(residual) <= self.options.newton_tol and (
                    iteration == 0 or last_update_norm <= self.options.newton_tol):
                return np.array([x, lam]), iteration
            if iteration == self.options.newton_max_iter:
                break
            a = float(self._jacobian(u, lam)[0, 0])
            b = float(self._dparam(u, lam)[0])
            f = -math.fsum((c * (x - p_u), d * (lam - p_lam)))
            dx, dlam = _solve_2x2(a, b, c, d, -residual, f, lam)
            last_update_norm = max(abs(dx), abs(dlam))
            x, lam = x + dx, lam + dlam
        raise NewtonConvergenceError(
            f"corrector did not converge in {self.options.newton_max_iter} iterations "
            f"(residual {abs(residual):.3g})"
        )

    def _converged(self, residual: FloatArray, last_update_norm: float, iteration: int) -> bool:
        """Residual within tolerance and, after at least one update, the last update too.

        A guess that already satisfies the residual is accepted without any
        update, so that an exact start at a fold (singular ``J``) is accepted.
        """
        tolerance = self.options.newton_tol
        if float(np.max(np.abs(residual))) > tolerance:
            return False
        return iteration == 0 or last_update_norm <= tolerance

    def _bordered_matrix(self, u: FloatArray, lam: float, tangent: FloatArray,
                         extended: FloatArray | None = None) -> FloatArray:
        """``[[J, dF/dlam], [W tangent]]`` with ``W`` the scaled-norm weights.

        `extended` is ``[J | dF/dlam]`` when already evaluated (:meth:`_linearized`).
        """
        if extended is None and getattr(self.problem, "linearize", None) is not None:
            extended = self._linearized(u, lam)[1]
        if extended is None:
            extended = np.column_stack([self._jacobian(u, lam), self._dparam(u, lam)])
        bordered = np.empty((extended.shape[0] + 1, extended.shape[1]))
        bordered[:-1] = extended
        np.multiply(self._metric_weights(), tangent, out=bordered[-1])
        return bordered

    def _linearized(self, u: FloatArray, lam: float) -> tuple[FloatArray, FloatArray | None]:
        """The residual and, from a problem with ``linearize``, ``[J | dF/dlam]`` (else None).

        A problem that evaluates ``F``, ``J`` and ``dF/dlam`` together (one shot of the
        N-p shooting system) provides the optional ``linearize(u, lam) -> (F, [J | dF/dlam])``
        (:class:`~impactcont.core.problem.Problem`); the corrector asks it once per
        iterate, with the refusals and checks of :meth:`_residual`.
        """
        linearize = getattr(self.problem, "linearize", None)
        if linearize is None:
            return self._residual(u, lam), None
        self._evaluated_lam = lam
        try:
            residual, extended = linearize(u.copy(), lam)
        except ParameterError as error:
            raise NewtonConvergenceError(f"the problem refused lam = {lam:.10g}: {error}") \
                from error
        residual = np.asarray(residual, dtype=float)
        if not np.isfinite(residual).all():
            raise NewtonConvergenceError(f"non-finite residual at lam = {lam:.10g}")
        return residual, np.asarray(extended, dtype=float)

    def _solve(self, matrix: FloatArray, right_hand_side: FloatArray, lam: float) -> FloatArray:
        """Solve a linear system, warning when it is singular to working precision."""
        if not (np.isfinite(matrix).all() and np.isfinite(right_hand_side).all()):
            raise NewtonConvergenceError(f"non-finite linear system at lam = {lam:.10g}")
        condition = _condition_number(matrix)
        if condition > SINGULAR_CONDITION:
            logger.warning(
                "matrix singular to working precision at lam = %.10g (condition number %.3e)",
                lam,
                condition,
            )
        if matrix.shape == (2, 2) and math.isfinite(condition):
            (a, b), (c, d) = matrix.tolist()
            solution = np.array(_cramer(a, b, c, d, *right_hand_side.tolist()))
        else:
            try:
                solution = np.linalg.solve(matrix, right_hand_side)
            except np.linalg.LinAlgError as error:
                raise NewtonConvergenceError(f"singular matrix at lam = {lam:.10g}") from error
        if not np.isfinite(solution).all():
            raise NewtonConvergenceError(f"non-finite Newton update at lam = {lam:.10g}")
        return solution

    # ------------------------------------------------------ problem evaluation

    def _evaluate(self, what: str, u: FloatArray, lam: float) -> FloatArray:
        self._evaluated_lam = lam
        try:
            return np.asarray(getattr(self.problem, what)(u.copy(), lam), dtype=float)
        except ParameterError as error:
            # an iterate left the problem's domain (e.g. a parameter that must stay > 0):
            # a failed corrector, retried with a smaller step, not a crash
            raise NewtonConvergenceError(f"the problem refused lam = {lam:.10g}: {error}") \
                from error

    def _residual(self, u: FloatArray, lam: float) -> FloatArray:
        residual = self._evaluate("residual", u, lam)
        if not np.isfinite(residual).all():
            raise NewtonConvergenceError(f"non-finite residual at lam = {lam:.10g}")
        return residual

    def _jacobian(self, u: FloatArray, lam: float) -> FloatArray:
        return self._evaluate("jacobian", u, lam)

    def _dparam(self, u: FloatArray, lam: float) -> FloatArray:
        return self._evaluate("dparam", u, lam)

    def _make_point(
        self,
        u: FloatArray,
        lam: float,
        tangent: FloatArray,
        ds: float,
        iterations: int,
        index: int,
    ) -> ContinuationPoint:
        return ContinuationPoint(
            u=np.array(u, dtype=float),
            lam=float(lam),
            tangent=np.array(tangent, dtype=float),
            ds=float(ds),
            newton_iterations=int(iterations),
            index=index,
            direction=self.direction,
            monitors=evaluate_monitors(self.problem, u, lam),
        )


def _clip(x: float, lo: float, hi: float) -> float:
    """``np.clip(x, lo, hi)`` of one float, in Python (the same value; numpy's call costs
    microseconds, two per step)."""
    return min(max(x, lo), hi)


def _solve_2x2(a: float, b: float, c: float, d: float, e: float, f: float, lam: float
               ) -> tuple[float, float]:
    """``[[a, b], [c, d]] y = [e, f]`` in Python floats, with the checks of
    :meth:`PalcStepper._solve` (non-finite system, singular or near-singular matrix,
    non-finite solution)."""
    if not all(map(math.isfinite, (a, b, c, d, e, f))):
        raise NewtonConvergenceError(f"non-finite linear system at lam = {lam:.10g}")
    condition = _condition_number(np.array([[a, b], [c, d]]))
    if condition > SINGULAR_CONDITION:
        logger.warning("matrix singular to working precision at lam = %.10g "
                       "(condition number %.3e)", lam, condition)
    if not math.isfinite(condition):
        raise NewtonConvergenceError(f"singular matrix at lam = {lam:.10g}")
    y = _cramer(a, b, c, d, e, f)
    if not (math.isfinite(y[0]) and math.isfinite(y[1])):
        raise NewtonConvergenceError(f"non-finite Newton update at lam = {lam:.10g}")
    return y


def _cramer(a: float, b: float, c: float, d: float, e: float, f: float) -> tuple[float, float]:
    """Cramer's rule for one unknown and the parameter (numpy's solve costs more in call
    overhead than the arithmetic), accurate for any condition number that does not
    already warn."""
    det = a * d - b * c
    return (e * d - b * f) / det, (a * f - e * c) / det


def _condition_number(matrix: FloatArray) -> float:
    """2-norm condition number, ``inf`` for an exactly singular matrix."""
    if matrix.shape == (2, 2):  # the bordered system of a one-unknown problem: closed form
        (a, b), (c, d) = matrix.tolist()
        det = abs(a * d - b * c)
        frob2 = a * a + b * b + c * c + d * d
        if det == 0.0:
            return math.inf
        # sigma_max / sigma_min from sigma_max^2 + sigma_min^2 = |A|_F^2, product = |det|
        root = math.sqrt(max(frob2 * frob2 - 4.0 * det * det, 0.0))
        return (frob2 + root) / (2.0 * det)
    singular_values = np.linalg.svd(matrix, compute_uv=False)
    if singular_values[-1] == 0.0:
        return math.inf
    return float(singular_values[0] / singular_values[-1])

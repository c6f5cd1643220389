"""Newton's method on a branch cut by a hyperplane: the corrector every locator uses.

A point of the branch ``F(u, lam) = 0`` is pinned by one more equation
``<normal, x - target> = 0`` (``x = (u, lam)``): a hyperplane through `target`
across the branch. Locators (special points, codim-2 points) and branch
switching solve this bordered system; the continuation stepper solves the same
system with its tangent as the normal (:class:`~impactcont.core.PalcStepper`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from impactcont.core.problem import FloatArray, Problem

__all__ = ["HyperplanePoint", "solve_on_hyperplane"]

log = logging.getLogger(__name__)

#: how often a Newton step that leaves the problem's domain is halved before giving up
_MAX_HALVINGS = 40


@dataclass(frozen=True, eq=False)
class HyperplanePoint:
    """The result of :func:`solve_on_hyperplane`.

    Attributes
    ----------
    x : ndarray, shape (m + 1,)
        The last iterate ``(u, lam)``.
    converged : bool
        Whether the convergence test passed (else `x` is the last iterate).
    last_step : float
        Max-norm of the last Newton step (a bound on the error when converged).
    iterations : int
        Newton steps taken.
    """

    x: FloatArray
    converged: bool
    last_step: float
    iterations: int

    @property
    def u(self) -> FloatArray:
        """The unknowns of the point."""
        return self.x[:-1]

    @property
    def lam(self) -> float:
        """The parameter of the point."""
        return float(self.x[-1])


def _solve(matrix: FloatArray, rhs: FloatArray) -> FloatArray:
    """``matrix^-1 rhs``; Cramer's rule for 2 x 2 (numpy's call overhead dominates there)."""
    if matrix.shape == (2, 2):
        (a, b), (c, d) = matrix.tolist()
        e, f = rhs.tolist()
        det = a * d - b * c
        return np.array([(e * d - b * f) / det, (a * f - e * c) / det])
    return np.linalg.solve(matrix, rhs)


def solve_on_hyperplane(problem: Problem, target: FloatArray, normal: FloatArray, *,
                        tol: float, max_iter: int = 30, residual_tol: float | None = None
                        ) -> HyperplanePoint:
    """Newton on ``[F(u, lam); <normal, x - target>] = 0`` from ``x = target``.

    Parameters
    ----------
    problem : Problem
        Provides ``residual``, ``jacobian`` and ``dparam``.
    target : ndarray, shape (m + 1,)
        A point of the hyperplane (the start guess).
    normal : ndarray, shape (m + 1,)
        Normal of the hyperplane (across the branch: a chord, a tangent or a
        coordinate direction).
    tol : float
        Converged when the max-norm of a Newton step is at most
        ``tol * max(1, |target|_inf)``.
    max_iter : int
        Newton steps allowed.
    residual_tol : float, optional
        Also require ``|F|_inf <= residual_tol * max(1, |target|_inf)`` after
        the step (long motions make the linear solve less accurate than the
        residual).

    Returns
    -------
    HyperplanePoint
        The point, whether it converged, and its last step.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the bordered matrix is singular (the hyperplane is tangent to the branch).
    ValueError
        When the problem refuses `target` itself (outside its domain).

    Notes
    -----
    A Newton step to a point outside the problem's domain (the problem raises
    ``ValueError`` there, e.g. ``omega <= 0``) is halved, up to
    ``_MAX_HALVINGS`` times: Newton never leaves the domain.
    """
    x = np.array(target, dtype=float)
    normal = np.asarray(normal, dtype=float)
    linearize = getattr(problem, "linearize", None)
    scale = max(1.0, float(np.max(np.abs(x))))
    step_of = getattr(problem, "palc_step", None)
    if step_of is not None and residual_tol is None:
        # the problem's compiled Newton on the same system (CorrectorResult); a refusal or a
        # non-finite value runs the loop below, which halves the step or fails as always
        found = step_of(x.copy(), normal.copy(), np.ones(x.size), tol * scale, max_iter,
                        hyperplane=True)
        if found is not None and found.status in ("converged", "not converged"):
            return HyperplanePoint(np.array(found.state, dtype=float),
                                   found.status == "converged", float(found.last_step),
                                   int(found.iterations))
    last = np.inf
    step: FloatArray | None = None
    halvings = 0
    iteration = 0
    while iteration < max_iter:
        u, lam = x[:-1], float(x[-1])
        try:
            if linearize is not None:  # the problem's one-call evaluation (Problem)
                residual, extended = linearize(u, lam)
                matrix = np.vstack([extended, normal])
            else:
                residual = problem.residual(u, lam)
                matrix = np.vstack([np.column_stack([problem.jacobian(u, lam),
                                                     problem.dparam(u, lam)]), normal])
        except ValueError:
            if step is None or halvings >= _MAX_HALVINGS:
                raise
            halvings += 1  # the last step left the domain: take half of it
            step = 0.5 * step
            x = x - step
            continue
        iteration += 1
        rhs = -np.append(residual, normal @ (x - target))
        step = _solve(matrix, rhs)
        x = x + step
        last = float(np.max(np.abs(step)))
        if last <= tol * scale and (residual_tol is None or _small_residual(
                problem, x, residual_tol * scale)):
            return HyperplanePoint(x, True, last, iteration)
    return HyperplanePoint(x, False, last, max_iter)


def _small_residual(problem: Problem, x: FloatArray, bound: float) -> bool:
    try:
        return float(np.max(np.abs(problem.residual(x[:-1], float(x[-1]))))) <= bound
    except ValueError:  # outside the domain: not converged, the next step halves
        return False

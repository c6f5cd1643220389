"""The interface a continuation problem ``F(u, lam) = 0`` has to provide.

The continuation core knows nothing about the physics behind ``F``: it only
calls the methods of :class:`Problem`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "FloatArray",
    "Problem",
    "ProblemOutputError",
    "check_problem_outputs",
    "evaluate_monitors",
]

FloatArray = NDArray[np.float64]
"""A numpy array of float64 values."""


class ProblemOutputError(ValueError):
    """A :class:`Problem` method returned an array of the wrong shape."""


@runtime_checkable
class Problem(Protocol):
    """A system of ``m`` equations ``F(u, lam) = 0`` in ``m`` unknowns and one parameter.

    ``u`` is a 1-D float array of the ``m`` unknowns and ``lam`` the float
    continuation parameter.

    An implementation may also provide ``monitors(u, lam) -> dict[str, float]``,
    scalar quantities recorded at every accepted point; the continuation core
    looks it up with ``getattr`` and records nothing when it is absent. A problem
    that evaluates ``F``, ``dF/du`` and ``dF/dlam`` together may provide
    ``linearize(u, lam) -> (F, [dF/du | dF/dlam])`` (shapes ``(m,)`` and
    ``(m, m + 1)``): the corrector then asks it once per Newton iterate instead of
    the three methods.
    """

    def residual(self, u: FloatArray, lam: float) -> FloatArray:
        """Return the residual ``F(u, lam)``, shape ``(m,)``."""
        ...

    def jacobian(self, u: FloatArray, lam: float) -> FloatArray:
        """Return ``dF/du`` at ``(u, lam)``, shape ``(m, m)``."""
        ...

    def dparam(self, u: FloatArray, lam: float) -> FloatArray:
        """Return ``dF/dlam`` at ``(u, lam)``, shape ``(m,)``."""
        ...


def check_problem_outputs(problem: Problem, u: FloatArray, lam: float) -> None:
    """Check that the methods of `problem` return arrays of the right shapes.

    Parameters
    ----------
    problem : Problem
        The problem to check.
    u : ndarray, shape (m,)
        Unknowns at which the methods are evaluated.
    lam : float
        Parameter value at which the methods are evaluated.

    Raises
    ------
    ProblemOutputError
        If ``residual`` or ``dparam`` does not return shape ``(m,)``,
        ``jacobian`` does not return shape ``(m, m)`` or the optional ``linearize``
        not shapes ``(m,)`` and ``(m, m + 1)``.
    """
    m = u.shape[0]
    expected = {"residual": (m,), "jacobian": (m, m), "dparam": (m,)}
    for method_name, shape in expected.items():
        value = np.asarray(getattr(problem, method_name)(u.copy(), lam))
        if value.shape != shape:
            raise ProblemOutputError(
                f"problem.{method_name}(u, lam) returned shape {value.shape} for "
                f"m = {m} unknowns; expected shape {shape}"
            )
    linearize = getattr(problem, "linearize", None)
    if linearize is not None:
        residual, extended = (np.asarray(v) for v in linearize(u.copy(), lam))
        if residual.shape != (m,) or extended.shape != (m, m + 1):
            raise ProblemOutputError(
                f"problem.linearize(u, lam) returned shapes {residual.shape} and "
                f"{extended.shape} for m = {m} unknowns; expected ({m},) and ({m}, {m + 1})"
            )


def evaluate_monitors(problem: Problem, u: FloatArray, lam: float) -> dict[str, float]:
    """Evaluate the optional ``monitors`` method of `problem`.

    Parameters
    ----------
    problem : Problem
        The problem; ``problem.monitors`` is optional.
    u : ndarray, shape (m,)
        Unknowns of the point.
    lam : float
        Parameter value of the point.

    Returns
    -------
    dict of str to float
        The monitor values, empty when the problem has no ``monitors`` method.
    """
    monitors = getattr(problem, "monitors", None)
    if monitors is None:
        return {}
    return {str(name): float(value) for name, value in monitors(u.copy(), lam).items()}

"""The stopping and backtracking rules of the kernel's Newton loops.

The rules of :func:`impactcont.orbit.multi_impact.newton` (which documents them), in one
place for every compiled loop that applies them (the map sweep's
:func:`impactcont.kernel.sweep._newton`): converged when ``max|r| <= tol * scale`` and
the last step's max-norm too (or at the last iteration), or when within tol a step does not
lower the residual (its rounding floor); each step halved until the residual falls (down
to a thousandth). ``scale`` is :func:`impactcont.kernel.shooting.unknowns_scale` of the
iterate. Scalars only: a call costs no reference counting.
"""

from __future__ import annotations

import numpy as np

from impactcont.kernel.jit import inner as _inner

__all__: list[str] = []

#: What a trial point of the backtracking makes of the step (:func:`_trial_outcome`).
HALVE = 0
TAKE = 1
FLOOR = 2


@_inner
def _converged(norm, step_norm, bound, it, max_iter):
    """``(small, converged)`` at an iterate of residual max-norm `norm` reached by a step of
    max-norm `step_norm` (``inf`` before the first), ``bound = tol * scale``: `small` the
    residual is within the tolerance, `converged` so is the step, or this is the last
    iteration `max_iter`."""
    small = norm <= bound
    return small, small and (step_norm <= bound or it == max_iter)


@_inner
def _trial_outcome(tnorm, norm, small, bound, lam_step):
    """What the trial point of residual max-norm `tnorm` (at step fraction `lam_step`) makes
    of the step from an iterate of residual max-norm `norm` (`small`: within the tolerance
    ``bound = tol * scale``): :data:`FLOOR` when the iterate is within tol and the trial
    does not lower its residual (the iterate is at its rounding floor: converged),
    :data:`TAKE` when the trial lowers the residual, meets the tolerance or the step is
    down to a thousandth, else :data:`HALVE` (halve the step and try again)."""
    finite = np.isfinite(tnorm)
    if small and not (finite and tnorm < norm):
        return FLOOR
    if finite and (tnorm < norm or tnorm <= bound or lam_step < 1e-3):
        return TAKE
    return HALVE

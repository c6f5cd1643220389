"""Generic pseudo-arclength continuation (PALC) of ``F(u, lam) = 0``.

The core knows nothing about oscillators: a problem provides the residual and
its derivatives (:class:`Problem`), :func:`continue_branch` computes a branch
and :func:`iter_points` streams the accepted points of one direction.
"""

from impactcont.continuation.corrector import HyperplanePoint, solve_on_hyperplane
from impactcont.continuation.driver import (
    BranchRun,
    ContinuationResult,
    ContinuationStatus,
    continue_branch,
    follow,
    iter_points,
)
from impactcont.continuation.events import Stop, StopRule
from impactcont.continuation.options import ContinuationOptionError, ContinuationOptions
from impactcont.continuation.point import ContinuationPoint
from impactcont.continuation.problem import Problem, ProblemOutputError
from impactcont.continuation.stepper import (
    ContinuationStepError,
    NewtonConvergenceError,
    PalcStepper,
    StepSizeBelowMinimumError,
)

__all__ = [
    "BranchRun",
    "ContinuationOptionError",
    "ContinuationOptions",
    "ContinuationPoint",
    "ContinuationResult",
    "ContinuationStatus",
    "ContinuationStepError",
    "HyperplanePoint",
    "NewtonConvergenceError",
    "PalcStepper",
    "Problem",
    "ProblemOutputError",
    "StepSizeBelowMinimumError",
    "Stop",
    "StopRule",
    "continue_branch",
    "follow",
    "iter_points",
    "solve_on_hyperplane",
]

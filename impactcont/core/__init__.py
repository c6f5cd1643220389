"""Generic pseudo-arclength continuation (PALC) of ``F(u, lam) = 0``.

The core knows nothing about oscillators: a problem provides the residual and
its derivatives (:class:`Problem`), :func:`continue_branch` computes a branch
and :func:`iter_points` streams the accepted points of one direction.
"""

from impactcont.core.corrector import HyperplanePoint, solve_on_hyperplane
from impactcont.core.driver import (
    BranchRun,
    ContinuationResult,
    ContinuationStatus,
    continue_branch,
    follow,
    iter_points,
)
from impactcont.core.events import Stop, StopRule
from impactcont.core.locate import (
    Event,
    EventPoint,
    MotionTest,
    dip_bottom,
    locate_events,
    parts_beside_poles,
    zero_precision,
)
from impactcont.core.options import ContinuationOptionError, ContinuationOptions
from impactcont.core.point import ContinuationPoint
from impactcont.core.problem import Problem, ProblemOutputError
from impactcont.core.stepper import (
    BoundReachedError,
    ContinuationStepError,
    NewtonConvergenceError,
    PalcStepper,
    StepSizeBelowMinimumError,
)

__all__ = [
    "BoundReachedError",
    "BranchRun",
    "ContinuationOptionError",
    "ContinuationOptions",
    "ContinuationPoint",
    "ContinuationResult",
    "ContinuationStatus",
    "ContinuationStepError",
    "Event",
    "EventPoint",
    "HyperplanePoint",
    "MotionTest",
    "NewtonConvergenceError",
    "PalcStepper",
    "Problem",
    "ProblemOutputError",
    "StepSizeBelowMinimumError",
    "Stop",
    "StopRule",
    "continue_branch",
    "dip_bottom",
    "follow",
    "iter_points",
    "locate_events",
    "parts_beside_poles",
    "solve_on_hyperplane",
    "zero_precision",
]

"""Why a continuation stops: typed statuses and the stop rules a driver adds.

The core stops on its own at the bounds, after ``max_points``, on a closed loop
and when the step falls below ``ds_min`` (:class:`ContinuationStatus`). A driver
adds its own reasons (a curve ends at a codim-2 point, a branch returns to the
motion it was born from) as a *stop rule*: a callable that sees every accepted
point of one direction and returns a :class:`Stop` to end that direction.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from impactcont.core.point import ContinuationPoint

__all__ = ["ContinuationStatus", "Stop", "StopRule", "StopRuleFactory"]


class ContinuationStatus(enum.Enum):
    """Why a continuation run stopped; the values are readable messages."""

    BOUNDS_REACHED = "parameter bound reached"
    MAX_POINTS_REACHED = "maximum number of points reached"
    STEP_BELOW_MINIMUM = "step size fell below ds_min"
    CLOSED_LOOP = "closed loop detected"
    NEWTON_FAILED_AT_START = "Newton failed at the start point"
    REACHED_PARENT = "reached the motion the branch was born from"
    STOPPED_AFTER_EVENT = "stopped after an event"
    CURVE_END = "the curve ends"


@dataclass(frozen=True, eq=False)
class Stop:
    """A stop rule's verdict: end this direction.

    Attributes
    ----------
    status : ContinuationStatus
        Why.
    detail : str
        Where and what, appended to the status's message.
    keep : bool
        Whether the point that triggered the stop is kept as the last point.
    point : ContinuationPoint, optional
        A point that replaces it as the last one (e.g. the curve end located
        between the last two points, or the point on a bound of an unknown).
    """

    status: ContinuationStatus
    detail: str
    keep: bool = True
    point: ContinuationPoint | None = None


class StopRule(Protocol):
    """Sees each accepted point of one direction (the start with ``previous=None``)."""

    def __call__(self, previous: ContinuationPoint | None, current: ContinuationPoint
                 ) -> Stop | None:
        """Return a :class:`Stop` to end the direction at `current`, else ``None``."""
        ...


StopRuleFactory = Callable[[int], StopRule]
"""Called with the direction (``+1`` or ``-1``) at the start of each; returns its rule."""

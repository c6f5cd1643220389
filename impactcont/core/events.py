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

__all__ = ["ContinuationStatus", "Stop", "StopRule", "StopRuleFactory", "parameter_name"]


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
    INTERRUPTED = "interrupted by the user (KeyboardInterrupt)"


def parameter_name(problem: object) -> str:
    """The name of the continued parameter in the stop reasons of ``problem``'s runs.

    A problem may name its ``lam`` with a text attribute ``parameter`` (``"omega"``, ``"b"``,
    ``"k2"``: the branch problems do), or ``parameters = (p1, p2)`` with ``lam = p2`` (the
    codim-1 curve problems); the reasons then say ``parameter bound reached: omega = 6``
    rather than the core's own ``lam = 6``, which stays for a problem of neither.
    """
    name = getattr(problem, "parameter", None)
    if isinstance(name, str) and name:
        return name
    names = getattr(problem, "parameters", None)
    if isinstance(names, tuple) and len(names) == 2 and isinstance(names[1], str) \
            and names[1]:
        return names[1]
    return "lam"


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

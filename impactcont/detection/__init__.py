"""Detection and location of special points on branches.

Every detector returns the one record :class:`SpecialPoint` (:mod:`impactcont.detection.points`).
"""

from impactcont.detection.points import SpecialPoint
from impactcont.detection.special_points import (
    BranchSample,
    detect_special_points,
    event_function,
)
from impactcont.vocabulary import LABELS

__all__ = ["LABELS", "BranchSample", "SpecialPoint", "detect_special_points", "event_function"]

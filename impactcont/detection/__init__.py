"""Detection and location of special points on branches."""

from impactcont.detection.special_points import (
    BranchSample,
    SpecialPoint,
    detect_special_points,
    event_function,
)
from impactcont.vocabulary import LABELS

__all__ = ["LABELS", "BranchSample", "SpecialPoint", "detect_special_points", "event_function"]

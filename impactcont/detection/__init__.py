"""Detection and location of special points on branches."""

from impactcont.detection.special_points import (
    LABELS,
    BranchSample,
    SpecialPoint,
    detect_special_points,
    event_function,
)

__all__ = ["LABELS", "BranchSample", "SpecialPoint", "detect_special_points", "event_function"]

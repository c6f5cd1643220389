"""The earlier place of the curves of N-p motions: now :mod:`impactcont.analysis.curves`."""

from impactcont.analysis.curves import (
    check_crossing_line,
    multi_impact_curve,
    multi_impact_curve_crossings,
)

__all__ = ["check_crossing_line", "multi_impact_curve", "multi_impact_curve_crossings"]

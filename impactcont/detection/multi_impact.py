"""Former home of the N-p detector: now the one detector of every motion.

Re-exports for those who import from here (the lead removes this shim):
:class:`~impactcont.detection.special_points.BranchSample` (``MultiImpactSample``),
:func:`~impactcont.detection.special_points.detect_special_points`
(``detect_multi_impact_points``) and
:func:`~impactcont.detection.special_points.locate_sample_events`
(``locate_multi_impact_events``).
"""

from impactcont.core.locate import tangent_at
from impactcont.detection.points import SpecialPoint as MultiImpactSpecialPoint
from impactcont.detection.special_points import BranchSample as MultiImpactSample
from impactcont.detection.special_points import detect_special_points as detect_multi_impact_points
from impactcont.detection.special_points import (
    locate_sample_events as locate_multi_impact_events,
)

__all__ = ["MultiImpactSample", "MultiImpactSpecialPoint", "detect_multi_impact_points",
           "locate_multi_impact_events", "tangent_at"]

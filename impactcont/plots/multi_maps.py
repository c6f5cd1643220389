"""The stability map of one N-p motion family: now in :mod:`impactcont.plots.maps`.

Kept so that ``from impactcont.plots.multi_maps import multi_impact_map_diagram`` (the
docs, the studies) keeps working; :func:`impactcont.plots.maps.two_parameter_diagram`
draws these maps too.
"""

from __future__ import annotations

from impactcont.plots.maps import (
    MULTI_MAP_BOUNDARIES,
    MULTI_MAP_REGIONS,
    multi_impact_map_diagram,
    multi_map_regions,
    multi_map_title,
)

__all__ = ["MULTI_MAP_BOUNDARIES", "MULTI_MAP_REGIONS", "multi_impact_map_diagram",
           "multi_map_regions", "multi_map_title"]

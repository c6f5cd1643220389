"""Former home of the schema of a map of one motion family: :mod:`impactcont.dataset.maps`.

Kept so that ``from impactcont.dataset.multi_maps import multi_impact_map_dataset`` (and
the other names below) goes on working; every map's schema is in
:mod:`impactcont.dataset.maps`.
"""

from impactcont.dataset.maps import (
    MULTI_MAP_KIND,
    MULTI_MAP_VARIABLES,
    multi_impact_map_dataset,
    validate_multi_impact_map_dataset,
)

__all__ = [
    "MULTI_MAP_KIND",
    "MULTI_MAP_VARIABLES",
    "multi_impact_map_dataset",
    "validate_multi_impact_map_dataset",
]

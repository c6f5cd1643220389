"""Former home of the map of one motion family: :mod:`impactcont.analysis.maps`.

Kept so that ``from impactcont.analysis.multi_maps import multi_impact_map`` (and
``multi_impact_map_orbit``) goes on working: every map has one entry,
:func:`impactcont.stability_map` (:mod:`impactcont.analysis.maps`, where
:func:`~impactcont.analysis.maps.multi_impact_map` is its alias for a motion), and the
family's sweep is :mod:`impactcont.analysis.family_maps`.
"""

from impactcont.analysis.maps import multi_impact_map, multi_impact_map_orbit

__all__ = ["multi_impact_map", "multi_impact_map_orbit"]

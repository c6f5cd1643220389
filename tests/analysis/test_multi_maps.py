"""The former home of the family map (:mod:`impactcont.analysis.multi_maps`) gives the names of
:mod:`impactcont.analysis.maps`, which ``impactcont`` exports too: code written against
either keeps working."""

from __future__ import annotations

import impactcont as ic
from impactcont.analysis import maps, multi_maps


def test_the_former_names_are_those_of_the_one_map_entry() -> None:
    assert multi_maps.__all__ == ["multi_impact_map", "multi_impact_map_orbit"]
    for name in multi_maps.__all__:
        assert getattr(multi_maps, name) is getattr(maps, name) is getattr(ic, name), name

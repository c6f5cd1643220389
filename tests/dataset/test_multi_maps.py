"""The former home of the family map's schema (:mod:`impactcont.dataset.multi_maps`) gives the
names of :mod:`impactcont.dataset.maps`, and so do the map names of
:mod:`impactcont.dataset.curves`: code written against either keeps working."""

from __future__ import annotations

from impactcont.dataset import curves, maps, multi_maps


def test_the_former_names_are_those_of_the_one_map_schema() -> None:
    for name in multi_maps.__all__:
        assert getattr(multi_maps, name) is getattr(maps, name), name
    for name in ("MAP_VARIABLES", "map_dataset", "map_parameters", "map_variables",
                 "validate_map_dataset"):
        assert getattr(curves, name) is getattr(maps, name), name

"""The old place of the N-p family map's plots (:mod:`impactcont.plots.multi_maps`): the
same objects as :mod:`impactcont.plots.maps`, where they are tested."""

from __future__ import annotations

import impactcont.plots.maps as maps
import impactcont.plots.multi_maps as multi_maps


def test_the_old_import_path_gives_the_same_objects() -> None:
    assert multi_maps.__all__
    for name in multi_maps.__all__:
        assert getattr(multi_maps, name) is getattr(maps, name), name

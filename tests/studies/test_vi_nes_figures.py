"""The VI-NES study's figures at one and two journal columns, from short real computations.

``source_compare.png``: drawn by ``source_compare.figure`` from the source's limit computed
by the study (``limit_row``: the published formula against the exact closed form, two
``r0``, one halving of ``s``); the figure's left panel computes its exact motions itself
(here at three omegas, the source's curves at 31).
"""

from __future__ import annotations

import importlib.util
import sys

import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import ROOT, WIDTHS

OMEGAS = (0.8, 1.0, 1.3)  # the study's grid has 21, its curves 201 points


def _source_compare():
    name = "vi_nes_sources_compare"  # the name test_study_sources imports it by
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, ROOT / "studies" / "vi_nes" / "source_compare.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


@pytest.fixture(scope="module")
def sources():
    """``(module, out)``: ``out`` as ``output/source_compare.json`` holds the limit."""
    module = _source_compare()
    limit = [module.limit_row(r0, s) for r0 in (0.9, 1.1) for s in (1.0, 0.5)]
    return module, {"limit": limit}


@pytest.mark.parametrize("width", WIDTHS)
def test_source_compare_figure_is_clean(sources, width):
    module, out = sources
    fig = module.figure(out, width=width, omegas=OMEGAS, points=31)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)

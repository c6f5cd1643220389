"""The VI-NES study's figures at one and two journal columns, from short real computations.

``source_compare.png``: drawn by ``source_compare.figure`` from the source's limit computed
by the study (``limit_row``: the published formula against the exact closed form, two
``r0``, one halving of ``s``); the figure's left panel computes its exact motions itself
(here at three omegas, the source's curves at 31).

``vi_nes_plane.png``: drawn by ``run.plane_figure`` from what ``run.beyond`` computes, in
short: the branch in omega at b = 5, its BP curves in (omega, b) and a 9 x 7 map.
"""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest

import impactcont as ic
from tests._layout_checks import check_layout
from tests.studies._figure_study import ROOT, WIDTHS, study_module

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


# -- vi_nes_plane.png -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def study():
    return study_module("vi_nes")


@pytest.fixture(scope="module")
def plane_groups():
    """``branches.nc`` of a short run: the branch in omega at b = 5, its BP curves in
    (omega, b) (few points) and the map of the UL motion on a 9 x 7 grid."""
    study = study_module("vi_nes", figures=False)
    p = study.params("symmetric", 1.2)
    m = next(m for m in study.ul_motions(p) if m.physical and m.stable)
    seed = ic.multi_impact_orbit(study.system(p, mirror=True), 1, 2, study.guess(m))
    br = ic.multi_impact_continuation(seed, "omega", study.PLANE["omega"], ds_max=0.01,
                                      max_points=3000)  # the study's: its BP, GR, GR, BP
    groups = {"branch_omega": br}
    labels = br["special_label"].values.tolist()
    assert labels.count("BP") >= 1, labels
    for which in range(labels.count("BP")):
        groups[f"curve_BP{which}"] = ic.multi_impact_curve(
            br, "BP", which, parameter="b", bounds=study.PLANE, ds_max=0.2, max_points=60)
    grid = {k: np.linspace(*study.PLANE[k], n) for k, n in (("omega", 9), ("b", 7))}
    groups["map"] = ic.multi_impact_map(seed, ("omega", "b"), grid)
    return groups


@pytest.mark.parametrize("width", WIDTHS)
def test_plane_figure_is_clean(study, plane_groups, width):
    fig = study.plane_figure(plane_groups, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)

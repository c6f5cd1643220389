"""The impact damper's plane figure (``impact_damper_plane.png``) at one and two journal
columns, from a short real run of what ``run.beyond`` and ``run.closed_form_plane``
compute: the closed form's plane and the package's two maps on a 21 x 9 grid (the study's
is 151 x 59), the branch in omega at b = 1 and its curves in (omega, b) with few points.
"""

from __future__ import annotations

import pytest

import impactcont as ic
from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module


@pytest.fixture(scope="module")
def study():
    return study_module("impact_damper")


@pytest.fixture(scope="module")
def plane():
    """``(cf, groups, info)`` as ``closed_form_plane.npz``, ``branches.nc`` and
    ``impact_damper.json`` hold them."""
    study = study_module("impact_damper", figures=False)
    study.PLANE_GRID = (21, 9)  # this module's own copy: the study's constant is untouched
    cf = study.closed_form_plane()
    seed = ic.multi_impact_orbit(study.system(1.5, 1.0), 1, 2,
                                 study.guess(study.stable_root(1.5, 2.0)))
    br = ic.multi_impact_continuation(seed, "omega", study.PLANE["omega"], ds_max=0.05,
                                      max_points=300)
    groups = {"branch_omega_b1": br}
    labels = br["special_label"].values.tolist()
    for kind in ("NS", "BP", "SN", "GR"):
        for which in range(labels.count(kind)):
            groups[f"curve_{kind}{which}"] = ic.multi_impact_curve(
                br, kind, which, parameter="b", bounds=study.PLANE, ds_max=0.1, max_points=60)
    assert any(name.startswith("curve_") for name in groups), labels
    grid = {"omega": cf["omega"], "b": cf["b"]}
    groups["map"] = ic.multi_impact_map(seed, ("omega", "b"), grid,
                                        max_change=study.MAP_MAX_CHANGE)
    groups["map_default"] = ic.multi_impact_map(seed, ("omega", "b"), grid)
    info = {"map_vs_closed_form": study.map_vs_closed_form(groups["map"], cf,
                                                          groups["map_default"])}
    return cf, groups, info


@pytest.mark.parametrize("width", WIDTHS)
def test_plane_figure_is_clean(study, plane, width):
    fig = study.plane_figure(*plane, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)

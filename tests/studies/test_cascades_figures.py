"""The cascades study's figures (``paper2dof.png``) at one and two journal columns.

Drawn by the study's own figure function from the study's own quick computation of the
paper's 2-DOF system (its N-1 branches, two period doublings of the cascade, the branch
born at a grazing) and a short simulated sweep up and down in omega (four omegas each,
quick transients), the full range over the zoom on the cascade.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module

NAME = "paper2dof"


@pytest.fixture(scope="module")
def data():
    """``(branches, up, down, zoom_up)`` as the study draws them."""
    study = study_module("cascades", figures=False)
    branches = study.compute_branches(NAME, quick=True)["branches"]
    omegas = np.linspace(*study.SYSTEMS[NAME]["range"], 4)
    up = study.sweep(NAME, omegas, True, None)
    down = study.sweep(NAME, omegas[::-1], True, up["end"])
    zoom = study.sweep(NAME, np.linspace(*study.SYSTEMS[NAME]["zoom"], 3), True, None)
    return branches, up["records"], down["records"], zoom["records"]


@pytest.mark.parametrize("width", WIDTHS)
def test_cascades_figure_is_clean(data, width):
    fig = study_module("cascades").figure(NAME, *data, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert fig.get_size_inches()[1] <= 9.5
    check_layout(fig, journal=True)

"""The sticking-motions study's figures at one and two journal columns.

Drawn by the study's own figure functions (``studies/sticking_motions/run.py``): one period
of the impact damper whose plastic ball rides each wall (the simulator on the closed form's
motion, :func:`impactcont.plots.series.time_history`, the closed form's landings and
releases marked), and the motion followed in omega by the closed form and the shooting path
(three frequencies here).
"""

from __future__ import annotations

import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module


@pytest.fixture(scope="module")
def study():
    return study_module("sticking_motions")


@pytest.fixture(scope="module")
def points():
    return study_module("sticking_motions", figures=False).omega_sweep((1.0, 1.05, 1.1))


@pytest.mark.parametrize("width", WIDTHS)
def test_riding_period_figure_is_clean(study, width):
    fig = study.riding_figure(0.2, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, system=["m = 0.2", "b = 0.3"], journal=True)


@pytest.mark.parametrize("width", WIDTHS)
def test_sweep_figure_is_clean(study, points, width):
    assert [p["omega"] for p in points] == [1.0, 1.05, 1.1]
    assert max(p["phase"] for p in points) < 1e-10
    fig = study.sweep_figure(points, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, system=["m = 0.2", "b = 0.3"], journal=True)

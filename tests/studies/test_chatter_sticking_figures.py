"""The chatter and sticking study's time-history figures at one and two journal columns.

Drawn by the study's own figure functions (run.ride_figure, run.preload_figure, through
impactcont.plots.series.time_history) from short real simulations: the riding impact damper
for 1.6 forcing periods (a ride on each wall, two accumulation points) and the preloaded
oscillator for 2 periods.
"""

from __future__ import annotations

import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module


@pytest.fixture(scope="module")
def study():
    return study_module("chatter_sticking")


@pytest.fixture(scope="module")
def ride():
    return study_module("chatter_sticking", figures=False).riding(0.3, 1.6,
                                                                  chatter_tolerance=1e-3)


@pytest.fixture(scope="module")
def preload():
    return study_module("chatter_sticking", figures=False).preloaded_run(0.7, 2.0)


@pytest.mark.parametrize("width", WIDTHS)
def test_ride_figure_is_clean(study, ride, width):
    osc, res = ride
    assert len(res.chatter) >= 2 and {p.stops for p in res.sticking} == {"U", "L"}
    fig = study.ride_figure(osc, res, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, system=["m = 0.2", "b = 0.3"], journal=True)


@pytest.mark.parametrize("width", WIDTHS)
def test_preload_figure_is_clean(study, preload, width):
    osc, res = preload
    assert res.chatter and res.sticking
    fig = study.preload_figure(res, osc, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)

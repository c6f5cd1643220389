"""The performance study's cost figure (``cost_vs_n.png``) at one and two journal columns.

Drawn by the study's own figure function from a short real run of its section 6 (chains of
n = 2 and 3 degrees of freedom, one timing round): the layout is checked, not the timings.
"""

from __future__ import annotations

import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module


@pytest.fixture(scope="module")
def study():
    return study_module("performance")


@pytest.fixture(scope="module")
def rows():
    """Rows of ``cost_vs_n`` as ``results.json`` holds them, timed in a few milliseconds."""
    study = study_module("performance", figures=False)
    study.BUDGET = 1e-4  # one call per round: the figure's layout does not need the numbers
    return study.cost_vs_n((2, 3), 1)


@pytest.mark.parametrize("width", WIDTHS)
def test_cost_figure_is_clean(study, rows, width):
    fig = study.cost_figure(rows, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)


def test_the_published_cost_table_redraws_the_committed_figure(study):
    """``--figure-from-readme`` reads every row of the README's cost table (n = 2 ... 200, in
    seconds as ``cost_vs_n`` gives them) and the figure drawn from them is clean."""
    rows = study.rows_from_readme()
    assert [r["n"] for r in rows][:2] == [2, 5] and rows[-1]["n"] == 200
    assert rows[0]["orbits"] == pytest.approx(0.0195e-3)
    assert all(set(study.COST_COLUMNS) <= set(r) for r in rows)
    check_layout(study.cost_figure(rows, 7.0), journal=True)

"""The rattle study's figure (``rattle.png``) at one and two journal columns.

Drawn by the study's own figure function from the study's own computations, coarser than
a full run (steps up to 0.1 in Gamma, a cascade of three doublings, the two-flank branch
in steps up to 0.5): the period-1 and period-2 branches of the bouncing ball against
the closed form, the period-doubling cascade of N = 1 and the motion between two flanks
with its special points labelled.
"""

from __future__ import annotations

import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module


@pytest.fixture(scope="module")
def data():
    """``(groups, pd_values)`` as ``branches.nc`` and ``rattle.json`` hold them."""
    study = study_module("rattle", figures=False)
    groups = {f"N{N}_gamma": study.branch_in_gamma(N, ds_max=0.1)[0] for N in study.TABLE}
    cas, info = study.cascade(groups["N1_gamma"], max_doublings=3)
    groups.update({f"cascade_{k}": b for k, b in enumerate(cas.branches[1:], start=1)})
    two, _ = study.two_flank(ds_max=0.5)
    assert two is not None  # the motion with one impact on each flank is found
    groups["two_flank"] = two
    return groups, info["pd_values"]


@pytest.mark.parametrize("width", WIDTHS)
def test_rattle_figure_is_clean(data, width):
    fig = study_module("rattle").figure(*data, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert fig.get_size_inches()[1] <= 9.5
    check_layout(fig, journal=True)

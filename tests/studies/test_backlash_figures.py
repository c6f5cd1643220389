"""The backlash study's diagrams (``backlash.png``) at one and two journal columns.

Drawn by the study's own figure function from a short real computation: the b = 0.8
backlash settled by the study's sweep at two omegas, its symmetric 1-2 branch and the
asymmetric pairs switched onto at its three pitchforks (three pairs: the figure must name
each kind of motion once). The plane figure needs the stability maps of a full run and is
not drawn here.
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from tests._layout_checks import check_layout, legend_entries_alike, render
from tests.studies._figure_study import WIDTHS, study_module

B = 0.8


@pytest.fixture(scope="module")
def study():
    return study_module("backlash")


@pytest.fixture(scope="module")
def data():
    """``(groups, sweeps)`` as ``branches.nc`` and ``sweeps.nc`` hold them, for b = 0.8."""
    study = study_module("backlash", figures=False)
    sw = study.sweep(B, np.array([0.8, 1.6]), transient=60.0, record=10.0)
    row = sw["rows"][0]
    assert row["one_two"], "the sweep settles on the symmetric 1-2 motion at omega = 0.8"
    orbit = ic.multi_impact_orbit(study.system(B, row["omega"]), 1, 2, row["result"])
    sym = ic.multi_impact_continuation(orbit, "omega", (0.7, 1.3), both_directions=True,
                                       max_points=80, ds_max=0.05)
    key = f"b{B}"
    groups = {f"{key}_0_symmetric": sym}
    forks = study.pitchforks(sym)
    assert len(forks) >= 2, forks  # two asymmetric pairs at least: kinds repeat
    for which in range(len(forks)):
        pair = ic.pitchfork_switch(sym, which, max_points=40, ds_max=0.05)
        for sub, side in zip(pair, ("asymmetric", "mirror"), strict=True):
            groups[f"{key}_{len(groups)}_{side}"] = sub
    return groups, {key: study.sweep_dataset(sw)}


@pytest.mark.parametrize("width", WIDTHS)
def test_backlash_diagrams_are_clean(study, data, width):
    groups, sweeps = data
    fig = study.diagrams_figure(groups, sweeps, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)


def test_each_kind_of_motion_has_one_legend_entry(study, data):
    """Three asymmetric pairs: one entry says what a red curve is (was: ``asymmetric``,
    ``asymmetric 2``, ``asymmetric 3`` and three ``mirror image`` entries in two colours)."""
    fig = study.diagrams_figure(*data, 7.0)
    assert legend_entries_alike(fig) == []
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    branch_entries = [t for t in texts if t.endswith("(1-2)")]
    assert len(branch_entries) == 2, texts  # symmetric; asymmetric pair
    assert not any(t.split(" (")[0][-1].isdigit() for t in branch_entries), texts
    assert "simulated sweep, every impact" in " ".join(t.get_text() for t in render(fig).texts)

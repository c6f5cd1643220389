"""The paper example's figures 3 and 4 (``figure3.png``, ``figure4.png``) at one and two
journal columns.

Drawn by the study's own figure function from the study's own quick computation: the
closed-form motions at each of the paper's parameter points and the steady state the
simulator reaches from rest after a 100-period transient (``--quick``'s).
"""

from __future__ import annotations

import numpy as np
import pytest

from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module

SYSTEM = r"$R = 0.6$, $\eta = 0.1$"


@pytest.fixture(scope="module")
def rows():
    """The rows of figures 3 and 4, as ``main`` draws them."""
    study = study_module("paper_example", figures=False)
    points = [(w, 0.0, N) for w, N in study.FIGURE3] + [(1.0, b, 1) for b in study.FIGURE4]
    steadies = {}
    for omega, b, N in points:
        osc = study.paper_oscillator(b=b, omega=omega)
        _, steadies[(omega, b)] = study.attractor_survey(osc, N, np.random.default_rng(0), 0,
                                                         100)
    return {"figure3": (study._figure3_rows(steadies),
                        f"Cao and Shu's figure 3: periodic motions at $b = 0$, {SYSTEM}"),
            "figure4": (study._figure4_rows(steadies),
                        rf"Cao and Shu's figure 4: periodic motions at $\omega = 1$, {SYSTEM}")}


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("name", ["figure3", "figure4"])
def test_paper_example_figure_is_clean(rows, name, width):
    fig = study_module("paper_example").motion_figure(*rows[name], width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert fig.get_size_inches()[1] <= 9.5
    check_layout(fig, journal=True)

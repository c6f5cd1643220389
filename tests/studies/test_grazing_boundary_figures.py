"""The grazing-boundary study's figure (``grazing_boundary.png``) at one and two journal columns.

Drawn by the study's own figure function (``plots.maps.two_parameter_figure``) from the
study's own quick computation: the N = 1 stability map on a 56 x 31 grid of (omega, b) and
the SN, PD, NS, GR and ZV curves continued from its edges, with their codim-2 points. The
N = 1 panel crowds at omega about 1.2: the curve labels ``SN`` and ``PD`` were placed
independently of each other (side by side, read as one), the merged label of the codim-2
points there ran over the ``R1`` and ``SN`` labels, and a codim-2 star on the map's edge
was cut in half by the frame.
"""

from __future__ import annotations

import numpy as np
import pytest

from impactcont.analysis.maps import stability_map
from impactcont.plots.maps import two_parameter_figure
from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module


@pytest.fixture(scope="module")
def data():
    """``(map, curves)`` of the study's quick configuration."""
    study = study_module("grazing_boundary", figures=False)
    cfg = study.QUICK
    osc = study.paper_oscillator()
    m = stability_map(osc, cfg["N"], np.linspace(*study.OMEGA_RANGE, cfg["n_omega"]),
                      np.linspace(*study.B_RANGE, cfg["n_b"]))
    curves, _ = study.compute_curves(osc, m, cfg)
    return m, curves


@pytest.mark.parametrize("width", WIDTHS)
def test_grazing_boundary_figure_is_clean(data, width):
    fig = two_parameter_figure(*data, width=width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig)

"""The studies' figures at a journal's single (3.5 in) and double (7 in) column.

Each figure is drawn by the study's own figure function (the one ``run.py`` and its
``--figures-only`` call) from data shaped like the study's (small synthetic rows, or
branches computed in a second), and passes the layout checks of the package's own
figures (:mod:`tests._layout_checks`): no text outside the figure or over another, no
marker cut by a frame, every style in a legend, no legend over data, axis labels in
symbols, no width beyond a double column. :mod:`impactcont.plots.series`, which they
draw with, is checked on its own in ``tests/plots/test_series.py``.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from impactcont.plots.series import (
    MAX_WIDTH,
    ZERO_LABEL,
)
from tests._layout_checks import check_layout, render
from tests.studies._figure_study import WIDTHS
from tests.studies._figure_study import study_module as _study


# -- the studies' figures ----------------------------------------------------------------------
def _vi_nes_rows() -> list[dict]:
    """Rows shaped like ``studies/vi_nes/output/rows.json``: every root, some physical."""
    rows = []
    rng = np.random.default_rng(3)
    for variant in ("symmetric", "restitution", "vertical"):
        for k, r in enumerate(np.linspace(0.7, 1.3, 13)):
            for root in range(2):
                physical = (k + root) % 3 != 0
                stable = physical and root == 0 and r > 0.9
                rows.append({"variant": variant, "omega": float(r), "physical_cf": physical,
                             "stable_cf": stable, "stable_pkg": stable,
                             "amplitude_cf": float(5 + 10 * root + 8 * abs(r - 1)),
                             "phase": float(10 ** rng.uniform(-16, -13)),
                             "state": float(10 ** rng.uniform(-16, -14)),
                             "flight_times": float(10 ** rng.uniform(-16, -14))})
                if k % 4 == 0:  # the package's motion is the closed form's to the last bit
                    rows[-1].update(phase=0.0, state=0.0, flight_times=0.0)
    return rows


@pytest.mark.parametrize("width", WIDTHS)
def test_vi_nes_agreement_figure_is_clean(width):
    fig = _study("vi_nes").agreement_figure(_vi_nes_rows(), width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert width <= MAX_WIDTH
    check_layout(fig, journal=True)
    text = " ".join(t.get_text() for t in render(fig).texts)
    assert r"$\mu = 0.05$" in text and ZERO_LABEL in text
    assert "{'" not in text  # no Python dict in a title
    assert not re.search(r"(?<!\\)\b(mu|zeta|omega) =", text)  # symbols in mathtext


def _damper_rows(module) -> list[dict]:
    rows = []
    for d in module.CLEARANCES:
        for k, r in enumerate(np.linspace(0.6, 3.0, 9)):
            rows.append({"d": d, "omega": float(r), "physical_pkg": k % 3 != 0,
                         "amplitude_cf": 1.0 + 0.3 * math.sin(3 * r),
                         "amplitude": 0.0 if k % 2 else 1e-9, "phase": 1e-15 * k,
                         "state": 2e-15, "multipliers": 0.0 if k == 4 else 3e-14})
    return rows


@pytest.mark.parametrize("width", WIDTHS)
def test_impact_damper_agreement_figure_is_clean(width):
    module = _study("impact_damper")
    fig = module.agreement_figure(_damper_rows(module), width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)
    text = " ".join(t.get_text() for t in render(fig).texts)
    assert r"$\mu = 0.2$" in text and "1e-17" not in text


def _work_precision_rows(seed: int) -> list[dict]:
    """Rows shaped like ``results.json`` of accuracy_vs_runtime: error against run time."""
    rng = np.random.default_rng(seed)
    rows = [{"family": "closed form", "method": "impactcont", "time": 2e-4, "orbit_error": 0.0,
             "multiplier_error": 3e-16, "error": 0.0}]
    for method in ("RK45", "DOP853"):
        for k, tol in enumerate((1e-4, 1e-8, 1e-12)):
            err = tol * 10 ** rng.uniform(-1, 1)
            rows.append({"family": "shooting", "method": method, "time": 0.01 * (k + 1),
                         "orbit_error": err, "multiplier_error": 10 * err, "error": err})
    rows.append({"family": "brute force", "method": "impactcont.simulate", "time": 0.5,
                 "orbit_error": 1e-9, "multiplier_error": float("nan"), "error": 1e-7})
    return rows


@pytest.mark.parametrize("width", WIDTHS)
def test_work_precision_figures_are_clean(width):
    module = _study("accuracy_vs_runtime")
    results = {"orbits": [{"n": n, "rows": _work_precision_rows(n)} for n in (2, 10, 50)],
               "locations": [{"n": n, "points": {lab: {"rows": _work_precision_rows(n + k)}
                                                 for k, lab in enumerate(("PD", "GR"))}}
                             for n in (2, 10)]}
    figures = [module.location_figure(results, width)]
    if width >= 5.0:  # six panels: a double-column figure (in one column they are too low)
        figures.append(module.orbit_figure(results, width))
    for fig in figures:
        assert fig.get_size_inches()[0] == pytest.approx(width)
        assert fig.get_size_inches()[1] <= 9.5
        check_layout(fig, journal=True)
        text = " ".join(t.get_text() for t in render(fig).texts)
        assert ZERO_LABEL in text  # the closed form's exact orbit, not a point at 1e-17

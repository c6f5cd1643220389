"""The backlash study's plane figure (``backlash_plane.png``) at one and two journal columns.

Drawn by the study's own ``plane_figure`` from a short real run of what ``run.plane``
computes: the symmetric 1-2 branch of the mirrored backlash at b = 0.5, its BP and GR
curves in (omega, b) and the asymmetric pair's GR curves (few points), the symmetric and
asymmetric stability maps on a 21 x 9 grid (the study's is 401 x 161), the pitchforks
located in omega and the simulator either side of the first one (100 periods, not 800).
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_rgb
from matplotlib.patches import Patch

import impactcont as ic
from impactcont.analysis.curves import multi_impact_curve
from impactcont.analysis.switching import pitchfork_branch
from tests._layout_checks import check_layout
from tests.studies._figure_study import WIDTHS, study_module

B = 0.5


@pytest.fixture(scope="module")
def study():
    return study_module("backlash")


@pytest.fixture(scope="module")
def plane():
    """``(groups, summary)`` as ``branches.nc`` and ``backlash.json`` hold the plane."""
    study = study_module("backlash", figures=False)
    osc = study.mirrored(B, 1.6)
    seed = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    sym = ic.multi_impact_continuation(seed, "omega", study.OMEGA, both_directions=True,
                                       ds_max=0.05, max_points=200)
    short = {"bounds": study.PLANE, "ds_max": 0.05, "max_points": 60}
    groups = {"plane_BP": multi_impact_curve(sym, "BP", 0, parameter="b", **short)}
    if "GR" in sym["special_label"].values.tolist():
        groups["plane_GR_symmetric"] = multi_impact_curve(sym, "GR", 0, parameter="b",
                                                          **short)
    asym = pitchfork_branch(sym, 0, 1, max_points=150, ds_max=0.05)
    grazes = asym["special_label"].values.tolist().count("GR")
    for which in range(min(grazes, 2)):
        try:
            groups[f"plane_GR_asymmetric_{which}"] = multi_impact_curve(
                asym, "GR", which, parameter="b", **short)
        except (ic.NoPeriodicMotionError, ic.ParameterError):
            continue  # as the study: no curve from this graze
    grid = {k: np.linspace(*study.PLANE[k], n) for k, n in (("omega", 21), ("b", 9))}
    groups["plane_map_symmetric"] = ic.multi_impact_map(seed, ("omega", "b"), grid)
    ok = np.flatnonzero(asym["stable"].values & asym["physical"].values)
    assert ok.size, "the asymmetric pair is stable and physical somewhere at b = 0.5"
    i = int(ok[ok.size // 2])
    motion = ic.multi_impact_orbit(study.mirrored(B, float(asym["omega"].values[i])), 1, 2, {
        "delta": float(asym["delta_k"].values[i, 0]),
        "flight_times": asym["flight_time_k"].values[i], "states": asym["state_k"].values[i],
        "pattern": asym.attrs["pattern"]})
    groups["plane_map_asymmetric_b0.5_1_asymmetric"] = ic.multi_impact_map(
        motion, ("omega", "b"), grid)
    forks = [w for w, _ in study.pitchforks(sym)]
    witness = study.fork_witness(B, None, sym, 0, system_of=study.mirrored, offset=0.01,
                                 periods=100.0)
    summary = {"clearances": {str(B): {"pitchforks": forks}},
               "plane": {"simulated": [{**witness, "b": B}]}}
    return groups, summary


@pytest.mark.parametrize("width", WIDTHS)
def test_plane_figure_is_clean(study, plane, width):
    fig = study.plane_figure(*plane, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig, journal=True)


def test_each_region_in_the_legend_is_drawn(study, plane):
    """A shaded region's legend entry only for a region with cells (here the asymmetric
    pair's 21 x 9 map has none: its entry was listed over nothing)."""
    fig = study.plane_figure(*plane, 7.0)
    fig.draw_without_rendering()
    legend = fig.legends[0] if fig.legends else fig.axes[0].get_legend()
    shaded = [h for h in legend.legend_handles if isinstance(h, Patch)]
    assert shaded, "the symmetric region is drawn and in the legend"
    for h in shaded:
        drawn = [c for ax in fig.axes for c in ax.collections
                 if len(c.get_facecolor()) and np.allclose(c.get_facecolor()[0][:3],
                                                           to_rgb(h.get_facecolor()))
                 and any(len(p.vertices) for p in c.get_paths())]
        assert drawn, f"legend entry {h.get_label()!r}: no region of its colour drawn"

"""The bifurcation-diagram study's figures (``bifurcation_b0.png``, ``bifurcation_b0p5.png``)
at one and two journal columns.

Drawn by the study's own figure function from a short real computation by the study's own
functions: every N = 1..4 branch of both gaps (its existence scans and continuations, a
few seconds), the special points on physical parts (what the study checks and marks) and a
4-value simulated sweep up and down in omega (quick transients). At b = 0.5 the NS, ZV,
SN and GR points at omega 1.21-1.26 crowd into a few points of the diagram (they are named
in the zoom panel under it; the ZV points of N = 1 and N = 3 are one point, drawn as one
combined marker).

A full run sweeps 120 omega values and records every impact of 30 periods: between the
N-1 windows, where the grazings and period doublings lie, the simulated points fill the
diagram. :func:`dense_sweeps` lays such a cloud over the real branches (the stable N-1
motion where there is one, a spread of velocities where there is none), so that the
figures are checked as a full run draws them: labels over that cloud covered about a
hundred simulated points at b = 0, 7 in.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from tests._layout_checks import check_layout, markers_hiding_markers
from tests.studies._figure_study import WIDTHS, study_module

GAPS = (0.0, 0.5)


@pytest.fixture(scope="module")
def data():
    """``(branches, checked keys, sweeps)`` as the study draws them."""
    study = study_module("bifurcation_diagram", figures=False)
    branches, _ = study.compute_branches(GAPS, 1, study.EXISTENCE_SCAN)
    keys = {(r["branch"], r["omega"]) for r in study.special_records(branches)
            if r["part"] != "non-physical"}
    sweeps, _ = study.brute_force_sweeps(GAPS, 4, study.TRANSIENT_QUICK, study.RECORD_QUICK, 1)
    return branches, keys, sweeps


def dense_sweeps(branches, n_omega: int = 120, samples: int = 30) -> xr.Dataset:
    """Sweeps up and down as a full run records them, made from the branches: at each of
    ``n_omega`` omega values the velocity of a stable physical N-1 motion (the one of
    least N; ``samples // N`` impacts), else ``samples`` impacts spread between 0 and the
    largest physical velocity at that omega (irregular motion), the two sweeps 1 % apart."""
    study = study_module("bifurcation_diagram", figures=False)
    omegas = np.linspace(*study.OMEGA_RANGE, n_omega)
    rng = np.random.default_rng(3)
    vel = np.full((len(GAPS), 2, n_omega, samples), np.nan)
    for g, b in enumerate(GAPS):
        tag = study.gap_tag(b)
        for k, w in enumerate(omegas):
            stable, reach = [], 0.0
            for name, ds in branches.items():
                if not name.startswith(tag + "_"):
                    continue
                om = ds["omega"].values
                near = np.flatnonzero(np.abs(om - w) < 0.02)
                for i in near:
                    v = float(ds["impact_velocity"].values[i])
                    if bool(ds["physical"].values[i]):
                        reach = max(reach, v)
                        if bool(ds["stable"].values[i]):
                            stable.append((int(ds.attrs["N"]), v))
            if stable:
                N, v = min(stable)
                vel[g, :, k, :samples // N] = v
            elif reach > 0:
                vel[g, :, k, :] = rng.uniform(0.0, reach, samples)
        vel[g, 1] *= 1.01
    return xr.Dataset({"impact_velocity": (("gap", "sweep", "omega", "sample"), vel)},
                      coords={"gap": list(GAPS), "sweep": ["up", "down"], "omega": omegas})


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("b", GAPS)
def test_bifurcation_diagram_figure_is_clean(data, b, width):
    fig = study_module("bifurcation_diagram").gap_figure(b, *data, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert fig.get_size_inches()[1] <= 9.5
    check_layout(fig)


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("b", GAPS)
def test_bifurcation_diagram_figure_is_clean_over_a_full_run_of_sweeps(data, b, width):
    branches, keys, _ = data
    fig = study_module("bifurcation_diagram").gap_figure(b, branches, keys,
                                                         dense_sweeps(branches), width)
    check_layout(fig)


def test_special_points_at_one_place_are_one_combined_marker(data):
    """At b = 0.5 the ZV points of N = 1 and N = 3 are one point (omega = 1.213462, v = 0):
    each is drawn, the later one inside the earlier, not under it at the same size."""
    study = study_module("bifurcation_diagram")
    fig = study.gap_figure(0.5, *data, 7.0)
    assert markers_hiding_markers(fig) == []
    for ax in fig.axes[:2]:
        at = [(str(line.get_marker()), line.get_markersize())
              for line in ax.get_lines() if line.get_linestyle() in ("None", "none")
              for x, y in line.get_xydata() if abs(x - 1.213462) < 1e-5 and abs(y) < 1e-3]
        assert sorted(m for m, _ in at) == ["v", "v"]
        assert len({size for _, size in at}) == 2  # one inside the other

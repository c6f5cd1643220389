"""Maps of one N-p family drawn (:mod:`impactcont.plots.multi_maps`): the region of every
grid point follows its flags, the shading is those regions, the boundaries separate found
from not found, the seed is marked where it was, the title names the motion, the system and
the stops, the axes the two parameters."""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import QuadMesh
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.analysis.multi_maps import multi_impact_map
from impactcont.dataset.multi_maps import multi_impact_map_dataset
from impactcont.model.stops import Stops
from impactcont.plots.multi_maps import (
    MULTI_MAP_BOUNDARIES,
    MULTI_MAP_REGIONS,
    multi_impact_map_diagram,
    multi_map_regions,
    multi_map_title,
)

matplotlib.use("Agg")

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.6, omega=1.0, eta=0.1)
OMEGA, B = np.linspace(0.6, 1.6, 6), np.linspace(0.0, 1.2, 5)


@pytest.fixture(scope="module")
def family() -> xr.Dataset:
    """The 1-1 family of the paper's system from its physical closed-form motion."""
    physical = next(o for o in ic.periodic_orbits(PAPER, 1) if o.physical)
    return multi_impact_map(physical, ("omega", "b"), grid={"omega": OMEGA, "b": B})


def _axes():
    fig = Figure(figsize=(5.0, 5.6), layout="constrained")
    FigureCanvasAgg(fig)
    return fig.add_subplot()


def test_the_region_of_a_grid_point_follows_its_flags(family) -> None:
    code = multi_map_regions(family).values
    found, physical, stable, checked = (family[k].values.astype(bool) for k in (
        "found", "physical", "stable", "contact_checked"))
    np.testing.assert_array_equal(code == 3, physical & stable)
    np.testing.assert_array_equal(code == 2, physical & ~stable)
    np.testing.assert_array_equal(code == 0, ~found)
    np.testing.assert_array_equal(code == 4, found & ~checked & ~physical)
    assert {0, 1}.issubset(set(np.unique(code)))  # the family ends inside the grid
    unchecked = family.assign(contact_checked=family["contact_checked"] & False,
                              physical=family["physical"] & False)
    assert set(np.unique(multi_map_regions(unchecked).values)) == {0, 4}


def test_the_panel_shades_the_regions_marks_the_seed_and_names_its_axes(family) -> None:
    ax = multi_impact_map_diagram(family, ax=_axes())
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(B.size, OMEGA.size),
                                  multi_map_regions(family).values.T)
    seed = json.loads(family.attrs["seed"])
    (star,) = [line for line in ax.get_lines() if line.get_marker() == "*"]
    np.testing.assert_array_equal(star.get_xydata(), [[seed["omega"], seed["b"]]])
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    present = np.unique(multi_map_regions(family).values)
    assert texts[:len(present)] == [MULTI_MAP_REGIONS[k][0] for k in sorted(present)]
    assert "boundary of the found region" in texts and texts[-1] == "seed"
    black = [line for line in ax.get_lines()
             if line.get_color() == MULTI_MAP_BOUNDARIES["found"][0]]
    assert black  # the found region's boundary lies between found and not-found points
    for line in black:
        xy = line.get_xydata()
        assert np.all((xy[:, 0] >= OMEGA[0]) & (xy[:, 0] <= OMEGA[-1]))
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel().startswith("gap $b$")
    assert ax.get_title() == multi_map_title(family)


def test_without_boundaries_legend_and_title(family) -> None:
    ax = multi_impact_map_diagram(family, ax=_axes(), boundaries=False, legend=False, title="")
    assert ax.get_legend() is None and ax.get_title() == ""
    assert [line.get_marker() for line in ax.get_lines()] == ["*"]


def test_the_title_names_the_motion_the_fixed_parameters_and_the_stops(family) -> None:
    assert multi_map_title(family) == r"Period-1 motions with 1 impact, $R = 0.6$, $\eta = 0.1$"
    mirrored = PAPER.replace(b=0.5, stops=Stops(mirror=True))
    shape, p = (2, 3), 2
    values = {"found": np.ones(shape, bool), "newton_iterations": np.full(shape, 3),
              "stable": np.ones(shape, bool), "physical": np.ones(shape, bool),
              "contact_checked": np.ones(shape, bool), "spectral_radius": np.full(shape, 0.5),
              "critical_multiplier": np.full(shape, 0.5 + 0j), "delta": np.zeros(shape),
              "gap_min": np.ones(shape), "impact_velocity_k": np.ones((*shape, p)),
              "flight_time_k": np.full((*shape, p), np.pi), "state_k": np.zeros((*shape, p, 4))}
    ds = multi_impact_map_dataset(oscillator=mirrored, N=1, pattern="UL",
                                  parameters=("omega", "R"),
                                  grid={"omega": [1.0, 1.2], "R": [0.5, 0.6, 0.7]},
                                  values=values, symmetric=True, seed={"omega": 1.0},
                                  options={})
    # R is on an axis; the mirrored lower stop moves with b (no b_low of its own)
    assert multi_map_title(ds) == (r"Period-1 symmetric motions with 2 impacts, impacts UL "
                                   r"(L: lower stop), $b = 0.5$, $\eta = 0.1$, "
                                   r"mirror stops $x_1 = \pm b$")
    ax = multi_impact_map_diagram(ds, ax=_axes())
    assert not [line for line in ax.get_lines() if line.get_marker() == "*"]  # seed: omega only
    assert ax.get_ylabel().startswith("coefficient of restitution $R$")

"""Two-parameter diagrams (:mod:`impactcont.plots.maps`): the region of every grid point
follows the map's counts, the shading is those regions, each curve is drawn through its own
(omega, b) points in its kind's colour, the legend names what is shown and the axes the two
parameters; one panel per N; bad arguments refused by name.

Maps of one N-p family: the region of every grid point follows its flags, the shading is
those regions, the boundaries separate found from not found, the seed is marked where it
was, the title names the motion, the system and the stops, the axes the two parameters;
:func:`two_parameter_diagram` draws them as :func:`multi_impact_map_diagram` does."""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import QuadMesh
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.dataset.maps import multi_impact_map_dataset
from impactcont.model.stops import Stops
from impactcont.plots.maps import (
    CURVE_STYLES,
    MULTI_MAP_BOUNDARIES,
    MULTI_MAP_REGIONS,
    REGIONS,
    multi_impact_map_diagram,
    multi_map_regions,
    multi_map_title,
    region_codes,
    two_parameter_diagram,
    two_parameter_figure,
)

matplotlib.use("Agg")

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.0, omega=1.75, eta=0.1)
OMEGA, B = np.linspace(1.6, 1.9, 7), np.linspace(-0.1, 0.1, 5)


@pytest.fixture(scope="module")
def grid() -> xr.Dataset:
    return ic.stability_map(PAPER, [1, 2], OMEGA, B)


@pytest.fixture(scope="module")
def pd_curve() -> xr.Dataset:
    branch = ic.continuation(PAPER, N=1, bounds=(1.6, 1.9), detect=("PD",))
    return ic.curve(None, kind="PD", start=branch, special=0,
                    bounds={"omega": [1.6, 1.9], "b": [-0.1, 0.1]}, max_points=30)


def _axes():
    fig = Figure(figsize=(5.0, 5.4), layout="constrained")
    FigureCanvasAgg(fig)
    return fig.add_subplot()


def test_the_region_of_a_grid_point_follows_its_counts(grid) -> None:
    for N in (1, 2):
        code = region_codes(grid, N)
        m = grid.sel(N=N)
        expected = np.where(m["n_stable"] > 0, 3, np.where(m["n_physical"] > 0, 2,
                                                           np.where(m["exists"], 1, 0)))
        np.testing.assert_array_equal(code.values, expected)
        assert code.dims == ("omega", "b") and code.name == "region"
    assert set(np.unique(region_codes(grid, 1).values)) >= {3}
    with pytest.raises(ValueError, match=r"N must be one of the map's \[1, 2\]; got 3"):
        region_codes(grid, 3)


def test_the_panel_shades_the_regions_and_draws_the_curve_through_its_points(grid,
                                                                              pd_curve) -> None:
    ax = two_parameter_diagram(grid, pd_curve, N=1, ax=_axes())
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(B.size, OMEGA.size),
                                  region_codes(grid, 1).values.T)
    red = to_rgba(CURVE_STYLES["PD"]["color"])
    lines = [line for line in ax.get_lines() if to_rgba(line.get_color()) == red
             and line.get_marker() in ("None", "")]
    drawn = {(float(x), float(y)) for line in lines for x, y in line.get_xydata()}
    assert drawn == {(float(x), float(y)) for x, y in zip(pd_curve["omega"].values,
                                                          pd_curve["b"].values, strict=True)}
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    present = np.unique(region_codes(grid, 1).values)
    assert [t for t in texts if t in {r[0] for r in REGIONS.values()}] == [
        REGIONS[k][0] for k in sorted(present)]
    assert "PD period doubling" in texts
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel().startswith("gap $b$")
    assert ax.get_title().startswith("Period-1 motions with 1 impact, ")
    assert ax.get_xlim() == (1.6, 1.9) and ax.get_ylim() == (-0.1, 0.1)


def test_a_curve_of_another_N_is_left_out(grid, pd_curve) -> None:
    ax = two_parameter_diagram(grid, {"pd": pd_curve}, N=2, ax=_axes())
    red = to_rgba(CURVE_STYLES["PD"]["color"])
    assert not [line for line in ax.get_lines() if to_rgba(line.get_color()) == red]
    assert ax.get_title().startswith("Period-2 motions with 1 impact")


def test_curves_alone_are_drawn_without_a_map(pd_curve) -> None:
    ax = two_parameter_diagram(curves=[pd_curve], ax=_axes(), legend=False, title="")
    assert ax.get_legend() is None and ax.get_title() == ""
    assert not [c for c in ax.collections if isinstance(c, QuadMesh)]
    assert len(ax.get_lines()) >= 1


def test_a_bad_diagram_is_named(grid, pd_curve) -> None:
    with pytest.raises(ValueError, match=r"give map_ds or curves \(or both\); got neither"):
        two_parameter_diagram(ax=_axes())
    with pytest.raises(TypeError, match=r"curves must be a curve Dataset, .*; got int"):
        two_parameter_diagram(grid, 3, ax=_axes())
    other = pd_curve.assign_attrs(parameters="omega,R").assign(
        R=pd_curve["b"] * 0 + 0.6, codim2_R=pd_curve["codim2_b"])
    with pytest.raises(ValueError, match=r"two_parameter_diagram draws curves in \(omega, b\); "
                                         r"got a curve in \(omega, R\)"):
        two_parameter_diagram(grid, other, ax=_axes())


def test_the_figure_has_one_panel_per_N_and_one_legend(grid, pd_curve) -> None:
    fig = two_parameter_figure(grid, pd_curve, width=7.0)
    try:
        axes = fig.get_axes()
        assert [ax.get_title() for ax in axes] == ["$N = 1$", "$N = 2$"]
        assert len(fig.legends) == 1
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)
    with pytest.raises(ValueError,
                       match=r"ncols must be an integer >= 1 \(panels per row\); got 0"):
        two_parameter_figure(grid, ncols=0)
    for wide in (30, 7.5):  # wider than a journal's page
        with pytest.raises(ValueError, match=r"width must be a number of inches in \[2, 7\.2\] "
                                             rf"\(3\.5: a journal's column, 7: its page\); "
                                             rf"got {wide}"):
            two_parameter_figure(grid, width=wide)


def test_codim2_marks_of_several_panels_are_one_legend_entry():
    """Each panel of a multi-N figure names its own codim-2 points; the figure's legend
    has one star per style naming those of every panel (it listed the star once per
    panel, each with other text)."""
    from matplotlib.lines import Line2D

    from impactcont.plots.maps import CODIM2_STYLES, _codim2_label, _merge

    style = next(iter(CODIM2_STYLES))
    handles = []
    for seen in (["PD+SN"], ["PD+NS", "PD+SN"], ["PD+GR"]):
        h = Line2D([], [], label=_codim2_label(style, seen, True))
        h.codim2_seen = (style, True, seen)
        handles.append(h)
    merged = _merge([Line2D([], [], label="PD"), *handles])
    stars = [h for h in merged if getattr(h, "codim2_seen", None)]
    assert len(stars) == 1
    assert stars[0].get_label() == _codim2_label(style, ["PD+SN", "PD+NS", "PD+GR"], True)
    assert len(merged) == 2


def test_a_map_over_other_parameters_is_drawn_in_its_own_plane() -> None:
    osc = PAPER.replace(omega=1.2, b=0.3)
    k2, R = np.linspace(0.6, 2.0, 5), np.linspace(0.3, 0.9, 4)
    ds = ic.stability_map(osc, [1], parameters=("k2", "R"), grid={"k2": k2, "R": R})
    ax = two_parameter_diagram(ds, ax=_axes())
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(R.size, k2.size),
                                  region_codes(ds, 1).values.T)
    # the axes are named from the parameter table, the title leaves them out of the system
    assert ax.get_xlabel() == "spring k2"
    assert ax.get_ylabel() == r"coefficient of restitution $R$"
    assert ax.get_xlim() == (0.6, 2.0) and ax.get_ylim() == (0.3, 0.9)
    assert "R =" not in ax.get_title() and r"\omega = 1.2" in ax.get_title()
    fig = two_parameter_figure(ds, width=3.5)
    try:
        assert r"in (k2, $R$)" in fig._suptitle.get_text()
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


# -- the map of one N-p motion family -------------------------------------------------------
FAMILY_PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                                   R=0.6, b=0.6, omega=1.0, eta=0.1)
FAMILY_OMEGA, FAMILY_B = np.linspace(0.6, 1.6, 6), np.linspace(0.0, 1.2, 5)


@pytest.fixture(scope="module")
def family() -> xr.Dataset:
    """The 1-1 family of the paper's system from its physical closed-form motion."""
    physical = next(o for o in ic.periodic_orbits(FAMILY_PAPER, 1) if o.physical)
    return ic.multi_impact_map(physical, ("omega", "b"),
                               grid={"omega": FAMILY_OMEGA, "b": FAMILY_B})


def _family_axes():
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
    ax = multi_impact_map_diagram(family, ax=_family_axes())
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    np.testing.assert_array_equal(
        np.asarray(mesh.get_array()).reshape(FAMILY_B.size, FAMILY_OMEGA.size),
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
        assert np.all((xy[:, 0] >= FAMILY_OMEGA[0]) & (xy[:, 0] <= FAMILY_OMEGA[-1]))
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel().startswith("gap $b$")
    assert ax.get_title() == multi_map_title(family)


def test_without_boundaries_legend_and_title(family) -> None:
    ax = multi_impact_map_diagram(family, ax=_family_axes(), boundaries=False, legend=False,
                                  title="")
    assert ax.get_legend() is None and ax.get_title() == ""
    assert [line.get_marker() for line in ax.get_lines()] == ["*"]


def test_the_title_names_the_motion_the_fixed_parameters_and_the_stops(family) -> None:
    assert multi_map_title(family) == r"Period-1 motions with 1 impact, $R = 0.6$, $\eta = 0.1$"
    mirrored = FAMILY_PAPER.replace(b=0.5, stops=Stops(mirror=True))
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
    ax = multi_impact_map_diagram(ds, ax=_family_axes())
    assert not [line for line in ax.get_lines() if line.get_marker() == "*"]  # seed: omega only
    assert ax.get_ylabel().startswith("coefficient of restitution $R$")


def test_two_parameter_diagram_draws_the_map_of_a_family_as_its_own_diagram(family) -> None:
    ax = two_parameter_diagram(family, ax=_family_axes())
    (mesh,) = [c for c in ax.collections if isinstance(c, QuadMesh)]
    np.testing.assert_array_equal(
        np.asarray(mesh.get_array()).reshape(FAMILY_B.size, FAMILY_OMEGA.size),
        multi_map_regions(family).values.T)
    assert ax.get_title() == multi_map_title(family)
    assert ax.get_legend() is not None
    with pytest.raises(ValueError, match="got curves with the map of an N-p motion family"):
        two_parameter_diagram(family, [], ax=_family_axes())
    fig = two_parameter_figure(family, width=3.5)
    try:
        (ax,) = fig.get_axes()
        assert ax.get_title().replace("\n", " ") == multi_map_title(family)  # wrapped to fit
        assert fig.get_size_inches()[0] == 3.5
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


def test_a_sticky_map_shades_each_sticking_reason_as_its_own_region() -> None:
    """A map with the variable ``reason`` (a motion with sticking phases): a found point that
    is not physical is shaded by its first sticking reason (stick ended 5, release grazing
    6, sticking onset 7; SE before SO before RG), a plain reason as before (1); each shade
    present is named in the legend."""
    from impactcont.dataset.maps import MAP_REASONS

    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.0, b=0.0,
                              omega=0.8, eta=0.05)
    shape, p = (2, 3), 1
    reason = np.array([[0, MAP_REASONS["stick_ended"] | MAP_REASONS["release_grazing"],
                        MAP_REASONS["release_grazing"]],
                       [MAP_REASONS["sticking_onset"] | MAP_REASONS["release_grazing"],
                        MAP_REASONS["impact_velocity"], 0]], dtype=np.int32)
    physical = reason == 0
    found = np.ones(shape, bool)
    found[1, 2] = False
    values = {"found": found, "newton_iterations": np.full(shape, 3),
              "stable": found, "physical": physical & found,
              "contact_checked": found, "spectral_radius": np.zeros(shape),
              "critical_multiplier": np.zeros(shape, complex), "delta": np.zeros(shape),
              "gap_min": np.ones(shape), "impact_velocity_k": np.ones((*shape, p)),
              "flight_time_k": np.ones((*shape, p)), "state_k": np.zeros((*shape, p, 2)),
              **{k: np.ones((*shape, p)) for k in ("stick_time_k", "release_phase_k",
                                                   "pressing_min_k", "landing_pressing_k")},
              "stick_time_min": np.ones(shape), "pressing_min": np.ones(shape),
              "reason": reason}
    ds = multi_impact_map_dataset(oscillator=osc, N=1, pattern="u", parameters=("omega", "F0"),
                                  grid={"omega": [0.7, 0.8], "F0": [2.0, 3.0, 4.0]},
                                  values=values, symmetric=False, seed={"omega": 0.8, "F0": 3.0},
                                  options={})
    np.testing.assert_array_equal(multi_map_regions(ds).values, [[3, 5, 6], [7, 1, 0]])
    ax = multi_impact_map_diagram(ds, ax=_family_axes())
    texts = [t.get_text() for t in (ax.get_legend() or ax.figure.legends[0]).get_texts()]
    for code in (5, 6, 7, 1):
        assert MULTI_MAP_REGIONS[code][0] in texts

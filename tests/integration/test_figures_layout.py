"""Layout of every figure kind at a journal's single-column (3.5 in) and double (7 in) width.

Each figure is drawn with the Agg renderer and checked from the artists it drew by
the checks of ``tests/_layout_checks.py`` (no text outside the figure, no two texts
overlapping, no text on a special-point marker, no marker cut by the frame of its
axes, no leader line across a curve, every style that carries meaning in a legend
and only those, titles without internal names, at most 7.2 in wide).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.analysis.multi_branch import multi_impact_continuation
from impactcont.analysis.multi_maps import multi_impact_map
from impactcont.model.stops import Stops
from impactcont.orbit.multi_impact import multi_impact_orbit
from impactcont.plots import SPECIAL_MARKERS, bifurcation_diagram, multipliers_plot
from impactcont.plots.impacts import impact_diagram
from impactcont.plots.maps import two_parameter_diagram, two_parameter_figure
from impactcont.plots.multi_maps import multi_impact_map_diagram
from impactcont.scene import figures
from impactcont.scene.run import run_scene
from tests._layout_checks import check_layout, color, marker_artists, marker_key, render

matplotlib.use("Agg")

WIDTHS = (3.5, 7.0)

SCENE = '''title = "figures"
[oscillator]
K = [[1.0, -1.0], [-1.0, 2.0]]
F = [1.0, 0.0]
R = 0.6
eta = 0.1
b = 0.6
omega = 1.0

[[orbits]]
name = "fig3_N1"
b = 0.0
omega = 1.2

[[orbits]]
name = "fig3_N3"
N = 3
b = 0.0
omega = 2.6

[[robust]]
name = "gap_box"
vary = { b = [0.2, 1.0] }
samples = 5

[[simulations]]
name = "sim"
periods = 6
trajectory = true

[[branches]]
name = "b0p5_N1"
b = 0.5
bounds = [0.5, 6.0]
start = 1.0
root = -1

[[branches]]
name = "b0p5_N2"
N = 2
b = 0.5
bounds = [0.5, 6.0]
start = 1.8
root = -1

[[branches]]
name = "b0p5_N3"
N = 3
b = 0.5
bounds = [0.5, 6.0]
start = 2.6
root = -1

[[curves]]
name = "pd"
kind = "PD"
start = "b0p5_N2"
bounds = { omega = [0.5, 3.0], b = [0.0, 1.0] }
max_points = 60

[[maps]]
name = "map"
N = [1, 2]
omega_range = [0.5, 3.0]
omega_points = 30
b_range = [0.0, 1.0]
b_points = 20
'''


@pytest.fixture(scope="module")
def data(tmp_path_factory) -> dict:
    """The main job's data at b = 0.5 (24 special points, nine in omega [1.19, 1.26])."""
    d = tmp_path_factory.mktemp("figures")
    (d / "scene.toml").write_text(SCENE)
    return run_scene(d / "scene.toml", output=d / "out").datasets


@pytest.fixture(scope="module")
def two_sided():
    """A symmetric 1-2 motion between two stops (b_low = b = 0.8), continued in omega."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              R=0.6, b=0.8, omega=0.8, eta=0.1, stops=Stops(b_low=0.8))
    res = ic.simulate(osc, np.zeros(4), 0.0, 200.0)
    return multi_impact_continuation(multi_impact_orbit(osc, 1, 2, res), "omega", (0.7, 0.9),
                                     max_points=40)


@pytest.fixture(scope="module")
def cascade() -> dict:
    """The 1-1 branch at b = 0 and the 2-2 branch born at its period doubling (omega 1.70)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.0, omega=1.5, eta=0.1)
    n1 = ic.continuation(osc, N=1, parameter="omega", bounds=(1.4, 2.0), components="start")
    return {"N1": n1, "N2": ic.period_doubling_switch(n1, bounds=(1.6, 1.9))}


@pytest.fixture(scope="module")
def np_map():
    """The symmetric 1-2 motion between mirrored stops mapped over (omega, b)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              eta=0.1, b=0.5, omega=1.6, stops=Stops(mirror=True))
    start = multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    grid = {"omega": np.linspace(0.8, 1.8, 21), "b": np.linspace(0.3, 0.8, 6)}
    return multi_impact_map(start, ("omega", "b"), grid=grid)


class _Options:
    def __init__(self, **kw) -> None:
        self.__dict__.update({"title": None, "y": None, "yscale": None, **kw})


def _render(fig: Figure):
    d = render(fig)
    return d.texts, d.renderer


def _assert_clean(fig: Figure) -> None:
    check_layout(fig)


def _assert_journal(fig: Figure) -> None:
    check_layout(fig, journal=True)


def _figure(width: float, height: float | None = None) -> Figure:
    return Figure(figsize=(width, height or 0.75 * width), layout="constrained")


def _all_text(fig: Figure) -> str:
    texts, _ = _render(fig)
    return " | ".join(t.get_text() for t in texts)


# -- the figures --------------------------------------------------------------------------------
@pytest.mark.parametrize("width", WIDTHS)
def test_bifurcation_diagram_with_a_dense_cluster_is_clean(data, width):
    fig = figures.draw_bifurcation(data["branches"], _Options(width=width))
    assert fig.get_size_inches()[0] == pytest.approx(width)
    _assert_clean(fig)


@pytest.mark.parametrize("width", WIDTHS)
def test_bifurcation_diagram_on_given_axes_is_clean(data, width):
    fig = _figure(width, 0.75 * width + 1.0)
    bifurcation_diagram(data["branches"], ax=fig.add_subplot())
    _assert_clean(fig)


def test_bifurcation_diagram_default_figure_is_clean(data):
    import matplotlib.pyplot as plt

    ax = bifurcation_diagram(data["branches"])
    try:
        _assert_clean(ax.figure)
    finally:
        plt.close(ax.figure)


def test_bifurcation_diagram_leaves_the_axes_most_of_the_width(data):
    fig = _figure(3.5, 3.6)
    ax = bifurcation_diagram(data["branches"], ax=fig.add_subplot())
    _render(fig)
    assert ax.bbox.width >= 0.7 * fig.bbox.width


def test_dense_cluster_gets_a_zoom(data):
    """The nine special points in omega [1.19, 1.26] at b = 0.5 are drawn apart in an inset."""
    fig = _figure(3.5, 3.6)
    ax = bifurcation_diagram(data["branches"], ax=fig.add_subplot())
    insets = [c for c in ax.child_axes if c.get_visible()]
    assert len(insets) == 1
    x0, x1 = insets[0].get_xlim()
    assert x0 <= 1.2117 and x1 >= 1.2583 and x1 - x0 < 0.2
    _assert_clean(fig)


def test_special_markers_take_their_branch_colour(data):
    fig = _figure(7.0)
    ax = bifurcation_diagram(data["branches"], ax=fig.add_subplot())
    _render(fig)
    branch_colours = {color(line.getcolor()) for line in ax.get_lines()
                      if line.get_linestyle() == "-"}
    special_keys = {marker_key(m) for m in SPECIAL_MARKERS.values()}
    edges = {c for _, key, c, _ in marker_artists(ax) if key in special_keys}
    assert edges and edges <= branch_colours | {color("0.6")}
    assert len(edges & branch_colours) == 3


def test_pitchfork_keeps_its_marker_and_legend(data):
    ds = data["branches"]["b0p5_N2"].copy(deep=True)
    ds["special_label"].values[0] = "BP"
    fig = _figure(7.0)
    ax = bifurcation_diagram(ds, ax=fig.add_subplot())
    _render(fig)
    assert marker_key("P") in {key for _, key, _, _ in marker_artists(ax)}
    assert "BP symmetry-breaking pitchfork" in _all_text(fig)
    _assert_clean(fig)


@pytest.mark.parametrize("width", WIDTHS)
def test_multipliers_are_clean(data, width):
    fig = figures.draw_multipliers({"b0p5_N1": data["branches"]["b0p5_N1"]},
                                   _Options(width=width))
    _assert_clean(fig)


def test_multipliers_spike_goes_to_a_log_axis(data):
    """|mu| = 27 near omega = 1.7 would flatten every other modulus on a linear axis."""
    fig = Figure()
    ax_abs, _ = multipliers_plot(data["branches"]["b0p5_N1"], ax=tuple(fig.subplots(1, 2)))
    assert ax_abs.get_yscale() == "log"


@pytest.mark.parametrize("width", WIDTHS)
def test_orbits_are_clean(data, width):
    fig = figures.draw_orbits(data["orbits"], _Options(width=width))
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert fig.get_size_inches()[1] <= 1.5 * width + 1.0
    _assert_clean(fig)


def test_orbits_draw_physical_motions_in_mathtext(data):
    """Physical roots drawn; an entry without one says so; labels are symbols, not ASCII."""
    fig = figures.draw_orbits(data["orbits"], _Options(width=7.0))
    text = _all_text(fig)
    assert "x1" not in text and "omega=" not in text
    assert r"$x_1$" in text and r"$\omega = 1.2$" in text
    assert "no physical" in text  # N = 3 at omega = 2.6
    assert sum(ax.get_visible() and ax.axison for ax in fig.axes) == 4


@pytest.mark.parametrize("width", WIDTHS)
def test_robust_is_clean_with_named_axes(data, width):
    fig = figures.draw_robust(data["robust"], _Options(width=width))
    _assert_clean(fig)
    ax = fig.axes[0]
    assert ax.get_xlabel() and ax.get_ylabel()
    ticks = [t.get_text() for t in ax.get_xticklabels()]
    assert ticks and all(t.startswith("$") for t in ticks)


@pytest.mark.parametrize("width", WIDTHS)
def test_simulation_is_clean(data, width):
    _assert_clean(figures.draw_simulations(data["simulations"], _Options(width=width)))


@pytest.mark.parametrize("width", WIDTHS)
def test_curves_are_clean(data, width):
    _assert_clean(figures.draw_curves(data["curves"], _Options(width=width)))


@pytest.mark.parametrize("width", WIDTHS)
def test_map_is_clean(data, width):
    _assert_clean(figures.draw_map(data["maps"], _Options(width=width)))


@pytest.mark.parametrize("width", WIDTHS)
def test_two_sided_branch_names_pattern_stops_and_speed(two_sided, width):
    fig = figures.draw_bifurcation({"sym": two_sided}, _Options(width=width))
    _assert_clean(fig)
    text = _all_text(fig)
    assert "1-2" in text and "LU" in text and "b_{low}" in text
    assert "1-1" not in text
    ax = fig.axes[0]
    assert "speed" in ax.get_ylabel() and "towards" in ax.get_ylabel()


def test_titles_name_system_and_motion(data):
    fig = figures.draw_bifurcation(data["branches"], _Options(width=7.0))
    text = _all_text(fig)
    assert "b = 0.5" in text and "R = 0.6" in text


def test_scene_figures_are_written_at_their_width(data, tmp_path):
    fig = figures.draw_robust(data["robust"], _Options(width=3.5))
    path = figures.save_figure(fig, tmp_path / "r.png", 100)
    assert Path(path).stat().st_size > 0


def test_scene_plot_width_and_automatic_yscale(data, tmp_path):
    """``[[plots]] width`` sizes the figure; a multipliers plot's moduli scale is ``auto``."""
    from impactcont.scene.keys import SceneError
    from impactcont.scene.schema import load_scene

    head = SCENE.split("[[orbits]]")[0] + '[[branches]]\nname = "b0p5_N1"\nb = 0.5\n' \
        'bounds = [0.5, 6.0]\n[[plots]]\nname = "mult"\nkind = "multipliers"\n'
    (tmp_path / "a.toml").write_text(head + "width = 3.5\n")
    spec = load_scene(tmp_path / "a.toml").plots[0]
    assert spec.width == 3.5 and spec.yscale == "auto"
    fig = figures.draw_multipliers({"b0p5_N1": data["branches"]["b0p5_N1"]}, spec)
    assert fig.get_size_inches()[0] == pytest.approx(3.5)
    assert fig.axes[0].get_yscale() == "log"  # |mu| = 27 near omega = 1.7
    _assert_clean(fig)
    (tmp_path / "b.toml").write_text(head)
    assert load_scene(tmp_path / "b.toml").plots[0].width == 7.0
    (tmp_path / "c.toml").write_text(head + "width = 1.0\n")
    with pytest.raises(SceneError, match=r"plots\[0\]\.width.*\[2, 20\]"):
        load_scene(tmp_path / "c.toml")


# -- impact diagrams, two-parameter diagrams and N-p maps ----------------------------------------
@pytest.mark.parametrize("width", WIDTHS)
def test_impact_diagram_is_clean_and_named(cascade, width):
    fig = _figure(width, 0.75 * width + 1.0)
    ax = impact_diagram(cascade, ax=fig.add_subplot(), label_special=True)
    _assert_journal(fig)
    title = ax.get_title()
    assert "motions" in title and "b = 0" in title and "R = 0.6" in title


@pytest.mark.parametrize("width", WIDTHS)
def test_impact_diagram_with_a_dense_cluster_is_clean(data, width):
    """The nine special points in omega [1.19, 1.26] at b = 0.5, labelled, one impact each."""
    fig = _figure(width, 0.75 * width + 1.0)
    impact_diagram(data["branches"], ax=fig.add_subplot(), label_special=True)
    _assert_journal(fig)


def test_impact_diagram_default_figure_is_clean(cascade):
    import matplotlib.pyplot as plt

    ax = impact_diagram(cascade, label_special=True)
    try:
        _assert_journal(ax.figure)
    finally:
        plt.close(ax.figure)


def test_impact_diagram_markers_take_their_branch_colour(cascade):
    fig = _figure(7.0)
    ax = impact_diagram(cascade, ax=fig.add_subplot())
    _render(fig)
    branch_colours = {color(line.getcolor()) for line in ax.get_lines()
                      if line.get_linestyle() == "-"}
    special_keys = {marker_key(m) for m in SPECIAL_MARKERS.values()}
    edges = {c for _, key, c, _ in marker_artists(ax) if key in special_keys}
    assert edges and edges <= branch_colours | {color("0.6")}
    assert len(edges & branch_colours) == 2  # the PD of N1, the PD and ZV of the 2-2 branch


@pytest.mark.parametrize("width", WIDTHS)
def test_impact_diagram_of_two_sided_motion_names_pattern_stops_and_speed(two_sided, width):
    fig = _figure(width, 0.75 * width + 1.0)
    ax = impact_diagram({"sym": two_sided}, ax=fig.add_subplot())
    _assert_journal(fig)
    assert "1-2" in ax.get_title() and "LU" in ax.get_title() and "b_{low}" in ax.get_title()
    assert "speed" in ax.get_ylabel() and "towards" in ax.get_ylabel()


@pytest.mark.parametrize("width", WIDTHS)
def test_two_parameter_diagram_is_clean_and_named(data, width):
    fig = _figure(width, 0.75 * width + 1.2)
    ax = two_parameter_diagram(data["maps"]["map"], data["curves"], N=2, ax=fig.add_subplot())
    _assert_journal(fig)
    title = ax.get_title()
    assert "2-1" in title and "R = 0.6" in title and "b = " not in title


@pytest.mark.parametrize("width", WIDTHS)
def test_two_parameter_figure_is_clean_at_its_width(data, width):
    fig = two_parameter_figure(data["maps"]["map"], data["curves"], width=width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    _assert_journal(fig)
    text = _all_text(fig)
    assert "$N = 1$" in text and "$N = 2$" in text and "R = 0.6" in text


@pytest.mark.parametrize("width", WIDTHS)
def test_multi_impact_map_diagram_is_clean_and_named(np_map, width):
    fig = _figure(width, 0.75 * width + 1.5)
    ax = multi_impact_map_diagram(np_map, ax=fig.add_subplot())
    _assert_journal(fig)
    title = ax.get_title()
    assert "1-2" in title and "LU" in title and "R = 0.6" in title and "mirror" in title


def test_multi_impact_map_default_figure_is_clean(np_map):
    import matplotlib.pyplot as plt

    ax = multi_impact_map_diagram(np_map)
    try:
        _assert_journal(ax.figure)
    finally:
        plt.close(ax.figure)

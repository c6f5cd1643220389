"""Layout of every figure kind at a journal's single-column (3.5 in) and double (7 in) width.

Each figure is drawn with the Agg renderer and checked from the artists it drew by
the checks of ``tests/_layout_checks.py`` (no text outside the figure, no two texts
overlapping, no text on a special-point marker, no marker cut by the frame of its
axes, no leader line across a curve, every style that carries meaning in a legend
and only those, titles without internal names, at most 7.2 in wide).
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.maps import multi_impact_map
from impactcont.model.stops import Stops
from impactcont.orbit.multi_impact import multi_impact_orbit
from impactcont.plots import SPECIAL_MARKERS, bifurcation_diagram, multipliers_plot
from impactcont.plots.impacts import impact_diagram
from impactcont.plots.maps import (
    multi_impact_map_diagram,
    two_parameter_diagram,
    two_parameter_figure,
)
from impactcont.scene import figures
from impactcont.scene.run import run_scene
from tests._layout_checks import (
    check_layout,
    check_titles,
    color,
    marker_artists,
    marker_key,
    render,
)

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
    branch_colours = {color(line.get_color()) for line in ax.get_lines()
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
    assert "Period-1 motions with 2 impacts" in text and "LU" in text and "b_{low}" in text
    assert "with 1 impact" not in text
    ax = fig.axes[0]
    assert "speed" in ax.get_ylabel() and "towards" in ax.get_ylabel()


def test_titles_name_system_and_motion(data):
    """In words a reader understands: ``Period-$N$ motions with 1 impact``, never ``N-1``
    (read as N minus 1) nor an entry's name."""
    fig = figures.draw_bifurcation(data["branches"], _Options(width=7.0))
    check_titles(fig, system=["$b = 0.5$", "$R = 0.6$"],
                 motion=["Period-$N$ motions with 1 impact"])
    assert "N-1" not in _all_text(fig)
    fig = figures.draw_orbits(data["orbits"], _Options(width=7.0))
    check_titles(fig, motion=["Period-1 motion with 1 impact", "Period-3 motion with 1 impact",
                              "root of eq. (15)"])
    assert "fig3_N1" not in _all_text(fig) and "root -1" not in _all_text(fig)
    fig = figures.draw_multipliers({"b0p5_N1": data["branches"]["b0p5_N1"]},
                                   _Options(width=7.0))
    check_titles(fig, motion=["period-1 motions with 1 impact"])


def test_special_points_of_non_physical_motions_have_one_style(data):
    """The legend's grey circle is the only grey mark: no grey squares or triangles."""
    from impactcont.plots.branches import NONPHYSICAL_GREY, NONPHYSICAL_MARKER

    fig = figures.draw_bifurcation(data["branches"], _Options(width=7.0))
    render(fig)
    grey = [key for ax in fig.axes for _, key, c, _ in marker_artists(ax)
            if c == color(NONPHYSICAL_GREY)]
    assert grey and set(grey) == {marker_key(NONPHYSICAL_MARKER)}
    check_layout(fig)


@pytest.mark.parametrize(("width", "least"), [(3.5, 7.0), (7.0, 8.0)])
def test_robust_numbers_are_legible(data, width, least):
    """The Gamma values in the cells: >= 7 pt on a column, >= 8 pt on a page."""
    fig = figures.draw_robust(data["robust"], _Options(width=width))
    cells = [t for t in fig.axes[0].texts if re.fullmatch(r"\d\.\d\d", t.get_text())]
    assert cells and min(t.get_fontsize() for t in cells) >= least


@pytest.mark.parametrize("width", [1.0, 7.5, 20.0, float("nan")])
def test_figures_refuse_a_width_wider_than_a_page(data, width):
    from impactcont.errors import ParameterError

    with pytest.raises(ParameterError, match=r"width must be a number of inches in \[2, 7\.2\]"):
        figures.draw_robust(data["robust"], _Options(width=width))


def test_cli_plot_width_and_choices(data, tmp_path, capsys):
    """``impactcont plot --width`` sizes the figure, refuses what a page cannot take by
    name, value and range; ``--help`` lists the plot kinds and variables of the registries."""
    from matplotlib.image import imread

    from impactcont.cli import main
    from impactcont.dataset.io import save
    from impactcont.plots.branches import Y_VARIABLES
    from impactcont.scene.plugins import plot_kinds

    nc = save({"b0p5_N1": data["branches"]["b0p5_N1"]}, tmp_path / "b.nc")
    png = tmp_path / "b.png"
    assert main(["plot", str(nc), "-o", str(png), "--dpi", "40", "--width", "3.5",
                 "--y", "delta"]) == 0
    assert imread(png).shape[1] == 140  # 3.5 in at 40 dpi
    for bad, says in (("9", " in [2, 7.2] (3.5: a journal's column, 7: its page); got 9.0"),
                      ("0", " in [2, 7.2] (3.5: a journal's column, 7: its page); got 0.0"),
                      ("nan", " in [2, 7.2] (3.5: a journal's column, 7: its page); got nan"),
                      ("wide", "; got 'wide'")):
        assert main(["plot", str(nc), "--width", bad]) == 2
        assert f"argument --width: --width must be a number of inches{says}" \
            in capsys.readouterr().err
    assert main(["plot", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert all(k in out for k in plot_kinds()) and ", ".join(Y_VARIABLES) in out
    assert "2 to 7.2" in out and f"{figures.WIDTH_RANGE[1]:g}" == "7.2"
    assert main(["plot", str(nc), "--y", "nonsense"]) == 2
    assert "invalid choice: 'nonsense'" in capsys.readouterr().err


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
    with pytest.raises(SceneError, match=r"plots\[0\]\.width.*\[2, 7\.2\]"):
        load_scene(tmp_path / "c.toml")
    (tmp_path / "d.toml").write_text(head + "width = 8.0\n")  # wider than a journal's page
    with pytest.raises(SceneError, match=r"plots\[0\]\.width.*\[2, 7\.2\]"):
        load_scene(tmp_path / "d.toml")


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
    branch_colours = {color(line.get_color()) for line in ax.get_lines()
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
    check_titles(fig, system=["b_{low}"], motion=["Period-1 motions with 2 impacts", "LU"])
    assert "speed" in ax.get_ylabel() and "towards" in ax.get_ylabel()


@pytest.mark.parametrize("width", WIDTHS)
def test_two_parameter_diagram_is_clean_and_named(data, width):
    fig = _figure(width, 0.75 * width + 1.2)
    ax = two_parameter_diagram(data["maps"]["map"], data["curves"], N=2, ax=fig.add_subplot())
    _assert_journal(fig)
    title = ax.get_title()
    assert "Period-2 motions with 1 impact" in title and "R = 0.6" in title and "b = " not in title


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
    title = " ".join(title.split())  # as read, whatever the line breaks
    assert "with 2 impacts" in title and "LU" in title and "R = 0.6" in title and "mirror" in title


def test_multi_impact_map_default_figure_is_clean(np_map):
    import matplotlib.pyplot as plt

    ax = multi_impact_map_diagram(np_map)
    try:
        _assert_journal(ax.figure)
    finally:
        plt.close(ax.figure)


# -- clusters of special points (issue 31: cascades, grazing_boundary, vi_nes_plane) ------------
def _cascade_branches() -> dict:
    """Ten branches with a period doubling each at one frequency, markers stacked 3-7 pt apart
    (the cascades study: PD squares piled at omega = 1.817)."""
    from impactcont.dataset import branch_dataset
    from tests._made_up_branch import _columns, _special

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0,
                              omega=1.0, eta=0.1)
    out = {}
    for k in range(10):
        cols = _columns()
        cols["impact_velocity"] = cols["impact_velocity"] + 0.004 * k
        out[f"n{k}"] = branch_dataset(parameter="omega", N=2 ** k, oscillator=osc, options={},
                                      columns=cols, special_points=[_special("PD", 30, cols)])
    return out


@pytest.mark.parametrize("width", WIDTHS)
def test_a_stack_of_period_doublings_gets_one_label(width):
    fig = _figure(width, 0.75 * width + 1.6)
    ax = bifurcation_diagram(_cascade_branches(), ax=fig.add_subplot())
    check_layout(fig)
    texts = [t.get_text() for a in (ax, *ax.child_axes) for t in a.texts]
    assert texts.count("PD \N{MULTIPLICATION SIGN}10") == 1, texts
    assert not [t for t in texts if t == "PD"]


def _codim2_cluster(curve):
    """The PD curve with five codim-2 points within 1e-3 of each other on it (the N = 1
    panel of the grazing_boundary study: PD+PD (now R2), PD+NS, SN+SN, SN+ZV, PD+ZV near
    omega = 1.2)."""
    k = int(curve["codim2_point"].values[0])
    c = curve.isel(codim2=[0] * 5)
    labels = np.array(["R2", "PD+NS", "PD+SN", "PD+ZV", "PD+GR"])
    c["codim2_label"] = ("codim2", labels.astype(curve["codim2_label"].dtype))
    c["codim2_point"] = ("codim2", np.full(5, k))
    c["codim2_omega"] = ("codim2", float(curve["omega"][k]) + 1e-3 * np.arange(5))
    c["codim2_b"] = ("codim2", float(curve["b"][k]) + 5e-4 * np.arange(5))
    c["physical"][:] = True
    return c


@pytest.mark.parametrize("width", WIDTHS)
def test_coincident_codim2_points_get_one_label_with_standard_names(data, width):
    fig = _figure(width, 0.75 * width + 1.6)
    curves = {"pd": _codim2_cluster(data["curves"]["pd"])}
    ax = two_parameter_diagram(data["maps"]["map"], curves, N=2, ax=fig.add_subplot())
    check_layout(fig, journal=True)
    texts = [t.get_text() for t in ax.texts]
    names = [t.replace("\n", " ") for t in texts if "PDNS" in t]  # in lines of two names
    assert names == ["R2, PDNS, LPPD, PD+ZV, PD+GR"], texts
    legend = " ".join(t.get_text() for t in ax.figure.legends[0].get_texts()) \
        if ax.figure.legends else " ".join(t.get_text() for t in ax.get_legend().get_texts())
    assert "LPPD fold-flip" in legend and "R2 1:2 resonance" in legend
    assert "no standard name" in legend


@pytest.mark.parametrize("width", WIDTHS)
def test_two_grazings_side_by_side_get_one_label(width):
    """vi_nes_plane: two GR markers nearly touching got two labels, read ``GR GR``."""
    from matplotlib.lines import Line2D

    from impactcont.plots.branches import label_specials

    fig = _figure(width)
    ax = fig.add_subplot()
    x = np.linspace(0.0, 1.0, 50)
    ax.plot(x, x ** 2, color="C0", linewidth=1.6)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    fig.draw_without_rendering()
    # 9.5 points apart on the page: two 6-point markers side by side, not one place
    dx = float((ax.transData.inverted().transform([[9.5 * fig.dpi / 72, 0]])
                - ax.transData.inverted().transform([[0, 0]]))[0, 0])
    pts = [(0.5, 0.4), (0.5 + dx, 0.4)]
    for px, py in pts:
        ax.plot([px], [py], linestyle="none", marker=SPECIAL_MARKERS["GR"], markersize=6,
                markerfacecolor="white", markeredgecolor="C0")
    ax.legend(handles=[Line2D([], [], color="C0", linewidth=1.6, label="branch"),
                       Line2D([], [], linestyle="none", marker=SPECIAL_MARKERS["GR"],
                              markeredgecolor="black", markerfacecolor="white",
                              label="GR grazing")], loc="upper left")
    label_specials(ax, [(px, py, "GR") for px, py in pts])
    check_layout(fig)
    assert [t.get_text() for t in ax.texts] == ["GR \N{MULTIPLICATION SIGN}2"]


@pytest.mark.parametrize("folder", ["studies/main_job/figures", "docs/figures"])
def test_committed_figures_fit_a_page(folder):
    """The figures the package's docs and main job show are at most 7.2 in wide."""
    from PIL import Image

    root = Path(__file__).resolve().parents[2]
    pngs = sorted((root / folder).glob("*.png"))
    assert pngs
    for png in pngs:
        with Image.open(png) as im:
            width = im.size[0] / im.info["dpi"][0]
        assert width <= 7.2 + 0.01, f"{png.name} is {width:.2f} in wide"


@pytest.mark.parametrize("width", WIDTHS)
def test_scene_curves_name_codim2_points_as_the_field_does(data, width):
    """A scene's curves figure: LPPD, PDNS, R2 for the smooth points, ``PD+GR`` (with the
    legend saying it has no standard name) for a non-smooth one; no entry names."""
    fig = figures.draw_curves({"pd": _codim2_cluster(data["curves"]["pd"])},
                              _Options(width=width))
    check_layout(fig)
    text = _all_text(fig)
    assert "R2, PDNS, LPPD, PD+ZV, PD+GR" in text and "PD+SN" not in text
    assert "LPPD fold-flip" in text and "no standard name" in text
    assert "PD curve, period-2 motions" in text and "pd (" not in text


@pytest.fixture(scope="module")
def held_simulation(tmp_path_factory):
    """The chatter-and-sticking study's scene: the preloaded oscillator held on its stop,
    released and chattering back (4 periods, about 2 s)."""
    scene = Path(__file__).resolve().parents[2] / "studies" / "chatter_sticking" / "scene.toml"
    out = tmp_path_factory.mktemp("held")
    return run_scene(scene, output=out).datasets["simulations"]


@pytest.mark.parametrize("width", WIDTHS)
def test_a_simulation_with_sticking_is_drawn_as_its_time_history(held_simulation, width):
    """Held intervals shaded on the motion and on the contact force under it; the phase
    portrait (which drew a held interval as one point) is not drawn for it."""
    fig = figures.draw_simulations(held_simulation, _Options(width=width))
    _assert_clean(fig)
    motion, force = fig.axes[:2]
    assert force.get_ylabel() == "$p$"
    assert len(motion.patches) == next(iter(held_simulation.values())).sizes["sticking"] > 0
    labels = {t.get_text() for leg in fig.legends for t in leg.get_texts()}
    assert {"held (sticking)", "simulated trajectory", "accumulation point"} <= labels


@pytest.fixture(scope="module")
def riding_simulation(tmp_path_factory):
    """The sticking-motions study's scene: the plastic ball of an impact damper riding each
    wall of its clearance ``|x2 - x1| <= 0.3`` (a stop between two masses, two walls)."""
    scene = Path(__file__).resolve().parents[2] / "studies" / "sticking_motions" / "scene.toml"
    out = tmp_path_factory.mktemp("riding")
    return run_scene(scene, output=out).datasets["simulations"]


def test_a_simulation_draws_its_stop_coordinate_and_both_walls(riding_simulation):
    """For a clearance between masses the motion drawn is the stop coordinate ``x2 - x1``
    with both walls, not ``x2`` against ``x2 = b`` (it drew the ball's own coordinate)."""
    fig = figures.draw_simulations(riding_simulation, _Options(width=7.0))
    _assert_clean(fig)
    motion = fig.axes[0]
    assert motion.get_ylabel() == "$x_2 - x_1$"
    ds = next(iter(riding_simulation.values()))
    X = np.asarray(ds["X"].values)
    line = motion.get_lines()[0]
    np.testing.assert_array_equal(line.get_ydata(), X[:, 1] - X[:, 0])
    walls = sorted(float(h.get_ydata()[0]) for h in motion.get_lines()[1:]
                   if h.get_linestyle() == ":")
    assert walls == [-0.3, 0.3]
    labels = {t.get_text() for leg in fig.legends for t in leg.get_texts()}
    assert "stops" in labels

"""impactcont.plots.series at a journal's single (3.5 in) and double (7 in) column.

Lines over hollow markers, exact zeros in a row of their own on a log axis (never at an
invented floor), n panels at a journal's width, one legend under the panels, clear errors;
every figure passes the layout checks of the package's figures (:mod:`tests._layout_checks`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from impactcont.plots.series import (
    ZERO_LABEL,
    Series,
    figure_legend,
    one_per_style,
    panel_figure,
    series_plot,
)
from tests._layout_checks import check_layout, render

ROOT = Path(__file__).resolve().parents[2]
WIDTHS = (3.5, 7.0)


# -- impactcont.plots.series -------------------------------------------------------------------
def _differences(x: np.ndarray, seed: int) -> np.ndarray:
    """Differences of a witness comparison: rounding-sized, every fifth one exactly 0."""
    rng = np.random.default_rng(seed)
    d = 10.0 ** rng.uniform(-16, -13, x.size)
    d[::5] = 0.0
    return d


def _four_panels(width: float) -> Figure:
    fig, axes = panel_figure(4, width)
    x = np.linspace(0.7, 1.3, 25)
    for i, ax in enumerate(axes[:3]):
        dense = np.linspace(0.7, 1.3, 200)
        series_plot(ax, [
            Series(dense, 1.0 / np.abs(1 - dense ** 2 + 0.04j * dense), "closed form",
                   color="k"),
            Series(x, 1.0 / np.abs(1 - x ** 2 + 0.04j * x), "package", color="C0",
                   linestyle="none", marker="o")],
            xlabel=r"$\omega/\omega_n$", ylabel=r"amplitude $\max|x_1|$",
            title=f"machine {i + 1}")
    series_plot(axes[3], [Series(x, _differences(x, k), f"difference {k}", color=f"C{k + 1}",
                                 linestyle="none", marker="os^"[k]) for k in range(3)],
                xlabel=r"$\omega/\omega_n$", ylabel=r"$|\Delta|$", yscale="log",
                title="package against closed form")
    figure_legend(fig)
    return fig


@pytest.mark.parametrize("width", WIDTHS)
def test_four_panels_of_series_are_clean(width):
    fig = _four_panels(width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    assert fig.get_size_inches()[1] <= 9.5  # a page
    check_layout(fig, journal=True)


def test_four_panels_make_a_grid_at_a_double_column():
    fig, axes = panel_figure(4, 7.0)
    render(fig)
    x0 = sorted({round(ax.get_position().x0, 3) for ax in axes})
    y0 = sorted({round(ax.get_position().y0, 3) for ax in axes})
    assert len(x0) == 2 and len(y0) == 2
    fig, axes = panel_figure(3, 7.0)  # the odd panel out spans the last row
    render(fig)
    assert axes[2].get_position().width > 1.8 * axes[0].get_position().width


def test_exact_zeros_get_their_own_row_not_a_floor():
    fig, (ax,) = panel_figure(1, 3.5)
    x = np.linspace(0.0, 1.0, 10)
    y = np.array([0.0, 1e-15, 2e-14, 0.0, 3e-16, 1e-13, 0.0, 5e-15, 7e-16, 1e-14])
    series_plot(ax, [Series(x, y, "difference", linestyle="none", marker="o")],
                xlabel="$x$", ylabel=r"$|\Delta|$", yscale="log")
    figure_legend(fig)
    render(fig)
    drawn = np.concatenate([line.get_ydata() for line in ax.get_lines()])
    drawn = drawn[np.isfinite(drawn)]
    assert drawn.size == 7 and np.all(drawn >= 3e-16)  # no zero lifted to a fake value
    rows = [c for c in ax.child_axes if c.get_visible()]
    assert len(rows) == 1
    (row,) = rows
    assert [t.get_text() for t in row.get_yticklabels()] == [ZERO_LABEL]
    zx = np.concatenate([line.get_xdata() for line in row.get_lines()])
    assert np.allclose(np.sort(zx), x[[0, 3, 6]])
    assert ax.get_ylim()[0] < 3e-16  # the row lies under every drawn value
    check_layout(fig, journal=True)


def test_no_zero_row_without_exact_zeros():
    _fig, (ax,) = panel_figure(1, 3.5)
    series_plot(ax, [Series([1, 2], [1e-3, 1e-5], "error", marker="o")], xlabel="$t$",
                ylabel=r"$\epsilon$", xscale="log", yscale="log")
    assert not ax.child_axes


def test_lines_are_drawn_over_markers():
    _fig, (ax,) = panel_figure(1, 3.5)
    series_plot(ax, [Series([0, 1], [0, 1], "line"),
                     Series([0, 1], [0, 1], "points", linestyle="none", marker="o")],
                xlabel="$x$", ylabel="$y$")
    line, points = ax.get_lines()
    assert line.get_zorder() > points.get_zorder()
    assert points.get_markerfacecolor() == "white"  # hollow: the line shows through


@pytest.mark.parametrize(("call", "match"), [
    (lambda: panel_figure(4, 20.8), r"width must be .*\[2\.0, 7\.2\].*20\.8"),
    (lambda: panel_figure(0, 7.0), r"n must be .*got 0"),
    (lambda: panel_figure(2, 7.0, ncols=3), r"ncols must be .*got 3"),
    (lambda: Series([1, 2], [1], "a"), r"'a': x and y must have equal lengths"),
    (lambda: Series([1], [1], "a", linestyle="none"), r"draws nothing"),
    (lambda: series_plot(panel_figure(1, 3.5)[1][0], [Series([1], [-1e-3], "d")],
                         xlabel="$x$", ylabel="$y$", yscale="log"), r"'d': y must be >= 0"),
    (lambda: series_plot(panel_figure(1, 3.5)[1][0], [Series([1], [1], "d")],
                         xlabel="$x$", ylabel="$y$", yscale="symlog"), r"yscale must be"),
    (lambda: series_plot(panel_figure(1, 3.5)[1][0],
                         [Series([1], [1], "d"), Series([1], [1], "d", color="r")],
                         xlabel="$x$", ylabel="$y$"), r"'d' are given two styles"),
])
def test_bad_input_is_refused_with_its_name(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_one_legend_entry_per_style():
    """Entries drawn alike (``asymmetric``, ``asymmetric 2``: one red line each) keep the
    first; a marker, another colour or another line style is another entry."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    red = [Line2D([], [], color="C3", linewidth=1.6, label=f"asymmetric {k}") for k in (1, 2)]
    others = [Line2D([], [], color="C0", linewidth=1.6, label="symmetric"),
              Line2D([], [], color="C3", linewidth=1.6, linestyle="--", label="unstable"),
              Line2D([], [], color="C3", linestyle="none", marker="o", label="SN"),
              Patch(facecolor="C3", alpha=0.3, label="region"),
              Patch(facecolor="C3", alpha=0.3, label="same region")]
    kept = one_per_style([*red, *others])
    assert [h.get_label() for h in kept] == ["asymmetric 1", "symmetric", "unstable", "SN",
                                             "region"]


def test_markers_whole_widens_the_limits_until_no_marker_is_cut():
    """A special point at the edge of a zoom is drawn whole, not cut by the frame."""
    from impactcont.plots.series import markers_whole
    from tests._layout_checks import markers_cut_by_frame

    fig = Figure(figsize=(3.5, 2.5), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0.0, 1.0, 0.5], [0.5, 0.5, 1.0], linestyle="none", marker="s", markersize=6)
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.0, 1.0)
    assert markers_cut_by_frame(fig)  # three squares on the frame
    markers_whole(ax)
    assert markers_cut_by_frame(fig) == []
    x0, x1 = ax.get_xlim()
    assert -0.1 < x0 < 0.0 and 1.0 < x1 < 1.1  # by about a marker, not more


def test_inside_frame_leaves_out_the_points_the_frame_would_cut():
    from impactcont.plots.series import inside_frame

    fig = Figure(figsize=(3.5, 2.5), layout="constrained")
    ax = fig.add_subplot()
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.0, 1.0)
    x = np.array([0.0, 0.5, 1.0, 0.5, 2.0])
    y = np.array([0.5, 0.5, 0.5, 1.0, 0.5])
    assert inside_frame(ax, x, y, 4.0).tolist() == [False, True, False, False, False]


# -- time_history -------------------------------------------------------------------------------
def _simulated_events():
    """A motion with two sticking phases on two stops, force samples and one accumulation
    point, laid out as SimulationResult.sticking_arrays() gives them."""
    t = np.linspace(0.0, 4.0, 401)
    return t, np.sin(np.pi * t / 2), {
        "sticking_start": np.array([0.5, 2.5]), "sticking_end": np.array([1.2, 3.1]),
        "force_time": np.array([0.5, 0.85, 1.2, 2.5, 2.8, 3.1]),
        "force": np.array([0.2, 0.1, 0.0, 0.3, 0.15, 0.0]),
        "force_phase": np.array([0, 0, 0, 1, 1, 1]),
        "force_stop": np.array(["U", "U", "U", "L", "L", "L"]),
        "chatter_time": np.array([2.5])}


@pytest.mark.parametrize("width", WIDTHS)
def test_time_history_shades_the_held_intervals_and_draws_the_forces(width):
    """The held intervals shaded on both panels, one force curve per stop (a gap between its
    phases), the accumulation point on the motion's curve, every style in the legend."""
    from matplotlib.patches import Rectangle

    from impactcont.plots.series import HELD_COLOR, time_history

    t, y, events = _simulated_events()
    fig, (top, bottom) = panel_figure(2, width, ncols=1, aspect=0.35)
    handles = time_history(top, bottom, [Series(0.5 * t, y, "$s$", linestyle="-")], events,
                           time_scale=0.5, xlabel="$t\\,\\omega / 2\\pi$", ylabel="$s$")
    figure_legend(fig, handles)
    check_layout(fig, journal=True)
    for ax in (top, bottom):
        spans = [p for p in ax.patches if isinstance(p, Rectangle)]
        assert sorted((p.get_x(), p.get_x() + p.get_width()) for p in spans) == [
            pytest.approx((0.25, 0.6)), pytest.approx((1.25, 1.55))]
        assert all(np.allclose(p.get_facecolor()[:3], [float(HELD_COLOR)] * 3) for p in spans)
    forces = {line.get_label(): line for line in bottom.get_lines()}
    assert sorted(forces) == ["force on stop L", "force on stop U"]
    u = forces["force on stop U"].get_xydata()
    assert np.allclose(u[:3], [[0.25, 0.2], [0.425, 0.1], [0.6, 0.0]]) and np.isnan(u[3]).all()
    mark = [line for line in top.get_lines() if line.get_label() == "accumulation point"]
    assert np.allclose(mark[0].get_xydata(), [[1.25, np.sin(np.pi * 2.5 / 2)]], atol=1e-3)
    assert [h.get_label() for h in handles] == ["$s$", "held (sticking)", "force on stop U",
                                                "force on stop L", "accumulation point"]


def test_time_history_names_what_its_events_lack():
    from impactcont.plots.series import time_history

    t, y, events = _simulated_events()
    del events["force_stop"]
    _fig, (top, bottom) = panel_figure(2, 3.5, ncols=1)
    with pytest.raises(ValueError, match=r"events lacks \['force_stop'\]"):
        time_history(top, bottom, [Series(t, y, "$s$", linestyle="-")], events)


def test_time_history_takes_a_scene_datasets_contact_force():
    """A scene's simulations.nc stores the force as ``contact_force``: drawn the same."""
    from impactcont.plots.series import time_history

    t, y, events = _simulated_events()
    events["contact_force"] = events.pop("force")
    fig, (top, bottom) = panel_figure(2, 3.5, ncols=1)
    time_history(top, bottom, [Series(0.5 * t, y, "$s$", linestyle="-")], events,
                 time_scale=0.5)
    u = next(line for line in bottom.get_lines() if line.get_label() == "force on stop U")
    assert np.allclose(u.get_xydata()[:3], [[0.25, 0.2], [0.425, 0.1], [0.6, 0.0]])
    assert fig.axes == [top, bottom]

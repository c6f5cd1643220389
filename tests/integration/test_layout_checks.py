"""The layout checks of ``tests/_layout_checks.py`` on small figures made to have (or not
have) the problem each check looks for."""

from __future__ import annotations

import pytest
from matplotlib.figure import Figure

from tests._layout_checks import layout_problems, markers_hiding_markers


def _axes() -> tuple[Figure, object]:
    fig = Figure(figsize=(3.5, 2.5))
    ax = fig.add_subplot()
    ax.set_xlim(0.0, 2.0)
    ax.set_ylim(0.0, 2.0)
    return fig, ax


def test_a_filled_marker_over_a_smaller_one_of_another_kind_hides_it():
    fig, ax = _axes()
    ax.plot([1.0], [1.0], linestyle="none", marker="^", markersize=6, color="tab:green",
            markerfacecolor="white")  # GR
    ax.plot([1.0], [1.0], linestyle="none", marker="s", markersize=6, color="tab:green",
            markerfacecolor="white")  # PD over it: the triangle lies inside the square
    problems = markers_hiding_markers(fig)
    assert problems == ["a marker at (1, 1) is hidden under a marker of another kind"]
    assert problems[0] in layout_problems(fig)


def test_a_simulated_point_under_a_special_marker_is_hidden():
    fig, ax = _axes()
    ax.scatter([1.0, 1.5], [1.0, 1.5], marker="o", s=12, facecolors="none", edgecolors="0.45")
    ax.plot([1.0], [1.0], linestyle="none", marker="s", markersize=6, color="tab:red",
            markerfacecolor="white")
    assert len(markers_hiding_markers(fig)) == 1


@pytest.mark.parametrize("case", ["triangle over square", "open square", "apart",
                                  "same kind twice", "one artist", "coinciding, smaller on top",
                                  "cross under a circle's edge", "out of view"])
def test_markers_left_in_view_are_not_hidden(case):
    fig, ax = _axes()
    first = {"linestyle": "none", "marker": "^", "markersize": 6, "color": "tab:green",
             "markerfacecolor": "white"}
    second = {"linestyle": "none", "marker": "s", "markersize": 6, "color": "tab:green",
              "markerfacecolor": "white"}
    x2 = [1.0]
    if case == "triangle over square":  # the square's corners stay in view
        first, second = second, first
    elif case == "open square":
        second["markerfacecolor"] = "none"
    elif case == "apart":  # 0.05 of 2 over ~2.5 in: about 6 points away
        x2 = [1.05]
    elif case == "same kind twice":  # drawn twice, alike: nothing of another kind is hidden
        second = dict(first)
    elif case == "one artist":
        first = None
        second["marker"], x2 = "s", [1.0, 1.0]
    elif case == "coinciding, smaller on top":  # a combined marker: both in view
        second["markersize"] = 3
    elif case == "cross under a circle's edge":
        first = {"linestyle": "none", "marker": "x", "markersize": 6, "color": "0.1"}
        second = {"linestyle": "none", "marker": "o", "markersize": 6, "color": "tab:blue",
                  "markerfacecolor": "white"}
        x2 = [1.012]  # about a point off: an arm of the cross reaches out of the circle
    elif case == "out of view":  # both beyond the limits: nothing to see
        ax.set_xlim(0.0, 0.5)
    if first is not None:
        ax.plot([1.0], [1.0], **first)
    ax.plot(x2, [1.0] * len(x2), **second)
    assert markers_hiding_markers(fig) == []

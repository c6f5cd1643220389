"""Labels of marked points (:mod:`impactcont.plots.labels`): points drawn within a marker of
each other are one place, labels never overlap each other and name the point they annotate,
markers are obstacles of the size they are drawn."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text

from impactcont.plots.labels import coincident_groups, marker_boxes, place_labels

matplotlib.use("Agg")


def _axes(dpi: float = 100.0):
    fig = Figure(figsize=(4.0, 4.0), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xlim(0.0, 10.0)
    ax.set_ylim(0.0, 10.0)
    fig.draw_without_rendering()
    return ax


def _points_per_unit(ax) -> float:
    """Points of the page per data unit along x."""
    x0 = ax.transData.transform([(0.0, 0.0), (1.0, 0.0)])
    return float(np.diff(x0[:, 0])[0]) * 72.0 / ax.figure.dpi


def test_points_within_a_marker_are_one_place() -> None:
    ax = _axes()
    tiny = 1.0 / _points_per_unit(ax)  # one point of the page, in data units
    groups = coincident_groups(ax, [(1.0, 1.0), (5.0, 5.0), (1.0 + 3 * tiny, 1.0)])
    assert sorted(map(sorted, groups)) == [[0, 2], [1]]
    assert coincident_groups(ax, []) == []


def test_a_chain_of_near_points_is_one_group_only_when_chained() -> None:
    ax = _axes()
    step = 6.0 / _points_per_unit(ax)  # 6 points apart: within the default 8-point distance
    row = [(1.0 + i * step, 5.0) for i in range(4)]  # the ends are 18 points apart
    assert coincident_groups(ax, row) == [[0, 1, 2, 3]]
    places = coincident_groups(ax, row, chain=False)
    assert places == [[0, 1], [2, 3]]


def test_the_groups_follow_the_page_not_the_data() -> None:
    """The same data points are one place when zoomed out and two when zoomed in."""
    xy = [(5.0, 5.0), (5.05, 5.0)]
    ax = _axes()
    ax.set_xlim(0.0, 100.0)
    assert coincident_groups(ax, xy) == [[0, 1]]
    ax.set_xlim(4.9, 5.2)
    assert coincident_groups(ax, xy) == [[0], [1]]


def test_labels_of_crowded_points_do_not_overlap_and_name_their_point() -> None:
    ax = _axes()
    ax.plot([0, 10], [5, 5])  # a curve the labels avoid
    xy = [(5.0, 5.0), (5.02, 5.0), (5.04, 5.01), (5.0, 5.03), (7.0, 2.0)]
    texts = ["SN", "PD", "NS", "GR", "ZV"]
    labels = place_labels(ax, xy, texts)
    assert sorted(label.get_text() for label in labels) == sorted(texts)
    for label in labels:
        assert tuple(label.xy) == xy[texts.index(label.get_text())]
    ax.figure.draw_without_rendering()
    # the text's own box (an Annotation's extent includes its leader line)
    boxes = [Text.get_window_extent(label) for label in labels]
    for i in range(len(boxes)):
        for j in range(i):
            assert not boxes[i].overlaps(boxes[j]), (labels[i].get_text(), labels[j].get_text())
    frame = ax.get_window_extent()
    for box in boxes:
        assert frame.contains(box.x0, box.y0) and frame.contains(box.x1, box.y1)


def test_labels_keep_clear_of_what_they_are_told_to_avoid() -> None:
    ax = _axes()
    ax.plot([5.0], [5.0], marker="o", markersize=8, linestyle="none")
    ax.plot([5.2], [5.0], marker="s", markersize=8, linestyle="none")
    ax.figure.draw_without_rendering()
    avoid = marker_boxes(ax)
    (label,) = place_labels(ax, [(5.0, 5.0)], ["a long label"], avoid=avoid)
    ax.figure.draw_without_rendering()
    box = Text.get_window_extent(label)
    assert not any(box.overlaps(b) for b in avoid)


def test_place_labels_refuses_texts_of_another_length() -> None:
    ax = _axes()
    with pytest.raises(ValueError, match=r"xy and texts must have the same length; got 2 and 1"):
        place_labels(ax, [(1, 1), (2, 2)], ["a"])
    assert place_labels(ax, [], []) == []


def test_marker_boxes_are_the_markers_as_drawn() -> None:
    ax = _axes(dpi=144.0)
    ax.plot([1.0, 2.0, 3.0], [1.0, 2.0, np.nan], marker="o", markersize=8, linestyle="none")
    ax.plot([0.0, 10.0], [0.0, 10.0])  # a line without markers: no obstacle
    boxes = marker_boxes(ax)
    assert len(boxes) == 2  # the NaN point is not drawn
    centres = ax.transData.transform([(1.0, 1.0), (2.0, 2.0)])
    for box, (cx, cy) in zip(boxes, centres, strict=True):
        assert box.width == pytest.approx(8 * 144.0 / 72.0)  # 8 points at 144 dpi
        assert (box.x0 + box.x1) / 2 == pytest.approx(cx)
        assert (box.y0 + box.y1) / 2 == pytest.approx(cy)


def test_a_stack_is_named_once_with_its_count() -> None:
    """Ten points 5 pt apart in a column (a cascade's period doublings) and a point of
    another kind touching the stack: one label, ``PD ×10, GR``, at the stack's middle;
    a point far away keeps its own."""
    from impactcont.plots.labels import merged_labels

    ax = _axes()
    pt = 1.0 / _points_per_unit(ax)  # one point of the page, in data units (square axes)
    xy = [(5.0, 2.0 + 5 * k * pt) for k in range(10)] + [(5.0 + 5 * pt, 2.0), (9.0, 9.0)]
    texts = ["PD"] * 10 + ["GR", "PD"]
    where, out = merged_labels(ax, xy, texts)
    assert out == ["PD \N{MULTIPLICATION SIGN}10, GR", "PD"]
    assert where[0] in (xy[4], xy[5]) and where[1] == xy[11]
    # counts add up when merged labels merge again
    again = merged_labels(ax, [xy[0], xy[1]], ["PD \N{MULTIPLICATION SIGN}3", "PD, GR"])
    assert again[1] == ["PD \N{MULTIPLICATION SIGN}4, GR"]
    # one place (chain=False): the label points at the first point of the place
    where, out = merged_labels(ax, xy[:3], ["SN", "GR", "SN"], distance=8.0, chain=False)
    assert out == ["SN, GR", "SN"] and where[0] == xy[0]  # the third is 10 pt from the first
    with pytest.raises(ValueError, match="xy and texts must have the same length; got 2 and 1"):
        merged_labels(ax, xy[:2], ["PD"])


def test_leaders_do_not_cross() -> None:
    """Six points scattered within a few markers, long labels: each label moves away on a
    leader, and no two leaders cross (a crossing costs as much as crossing a curve)."""
    from tests._layout_checks import leaders_crossing_each_other

    ax = _axes()
    pt = 1.0 / _points_per_unit(ax)
    xy = [tuple(v) for v in 5.0 + np.random.default_rng(1).normal(0.0, 6 * pt, size=(6, 2))]
    ax.plot(*np.array(xy).T, linestyle="none", marker="o", markersize=6)
    labels = place_labels(ax, xy, [f"LABEL{k}" for k in range(6)], fontsize="x-small",
                          avoid=marker_boxes(ax))
    assert sum(t.arrow_patch is not None for t in labels) >= 2
    assert not leaders_crossing_each_other(ax.figure)

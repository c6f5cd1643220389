"""Text labels that avoid each other, the markers they name and, where they can, the curves.

Special points crowd together (NS, ZV and SN within 0.003 in omega on the
paper's b = 0.5 branch): a label written at a fixed offset from each marker
covers its neighbours. :func:`place_labels` puts each label at the nearest
free place around its point, on rings of growing radius, with a thin leader
line when it had to move away; a leader crosses no curve, no other leader and
no other label where a place allows it, and no label stands beside another
on one line closer than two ems (``SN GR`` would read as one name).
:func:`merged_labels` gives a stack of points one label (``PD ×10``). Positions
are computed in points on the laid-out figure, so the result holds for the size
the figure is saved at.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PathCollection
from matplotlib.font_manager import FontProperties
from matplotlib.text import Annotation, Text

__all__ = ["coincident_groups", "marker_boxes", "merged_labels", "place_labels"]

_RINGS = (4.0, 12.0, 22.0, 34.0, 48.0, 64.0)  # distance of a label from its point, in points
_MARKER = 4.0  # half-size of a marker, in points
#: Least gap between two labels on one line, in ems of their font: closer, they read as one.
_SIDE_GAP = 2.0


def _candidates(w: float, h: float) -> list[tuple[float, float, int]]:
    """Lower-left corners ``(dx, dy)`` of a ``w x h`` box around a point, nearest first."""
    out = []
    for ring, r in enumerate(_RINGS):
        for dx, dy in ((r, r / 2), (r, -r / 2 - h), (-r - w, r / 2), (-r - w, -r / 2 - h),
                       (-w / 2, r), (-w / 2, -r - h), (r, -h / 2), (-r - w, -h / 2)):
            out.append((dx, dy, ring))
    return out


def _overlap(box: np.ndarray, boxes: np.ndarray) -> float:
    """Total overlap area of ``box`` (x0, y0, x1, y1) with the rows of ``boxes``."""
    if boxes.size == 0:
        return 0.0
    w = np.minimum(box[2], boxes[:, 2]) - np.maximum(box[0], boxes[:, 0])
    h = np.minimum(box[3], boxes[:, 3]) - np.maximum(box[1], boxes[:, 1])
    return float(np.sum(np.clip(w, 0, None) * np.clip(h, 0, None)))


def _side_room(labels: Sequence[np.ndarray], size: float) -> np.ndarray:
    """The boxes of ``labels`` (points) widened by :data:`_SIDE_GAP` ems on each side.

    Two labels on one line closer than that read as one (``SN GR`` for a saddle-node
    and a grazing a few points apart): another label may stand above or below a
    label, not beside it.
    """
    if not len(labels):
        return np.empty((0, 4))
    boxes = np.array(labels, dtype=float).reshape(-1, 4)
    return boxes + np.array([-1.0, 0.0, 1.0, 0.0]) * _SIDE_GAP * size


def _curve_points(ax: Axes, to_points: Any) -> np.ndarray:
    """Vertices of the lines drawn on ``ax``, in points (soft obstacles)."""
    parts = [line.get_xydata() for line in ax.get_lines() if line.get_visible()]
    xy = np.vstack([p for p in parts if len(p)]) if parts else np.empty((0, 2))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    return to_points(xy) if len(xy) else xy


def _leader_crossings(p: np.ndarray, box: np.ndarray, segments: np.ndarray) -> int:
    """How many curve segments the leader from point ``p`` to ``box`` crosses (points)."""
    if segments.size == 0:
        return 0
    a = np.clip(p, box[:2], box[2:])
    d = a - p
    length = float(np.hypot(*d))
    if length <= _MARKER:
        return 0
    b = p + d * (_MARKER / length)
    q0, q1 = segments[:, 0], segments[:, 1]

    def orient(u: np.ndarray, v: np.ndarray, w: np.ndarray) -> np.ndarray:
        return np.sign((v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1])
                       - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0]))

    cross = ((orient(a, b, q0) * orient(a, b, q1) < 0) & (orient(q0, q1, a) * orient(q0, q1, b)
                                                          < 0))
    return int(np.count_nonzero(cross))


def _crossings(a: np.ndarray, b: np.ndarray, segments: Sequence[np.ndarray]) -> int:
    """How many of ``segments`` ((2, 2) each) the segment ``a``-``b`` crosses (points)."""
    if not len(segments):
        return 0
    q = np.asarray(segments, dtype=float)
    q0, q1 = q[:, 0], q[:, 1]

    def orient(u: np.ndarray, v: np.ndarray, w: np.ndarray) -> np.ndarray:
        return np.sign((v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1])
                       - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0]))

    return int(np.count_nonzero((orient(a, b, q0) * orient(a, b, q1) < 0)
                                & (orient(q0, q1, a) * orient(q0, q1, b) < 0)))


def _leader_crossings_box(box: np.ndarray, leaders: Sequence[np.ndarray]) -> int:
    """How many of the ``leaders`` (segments, points) pass through ``box``."""
    count = 0
    for a, b in leaders:
        t = np.linspace(0.0, 1.0, 24)[:, None]
        line = a + t * (b - a)
        count += int(np.any((line[:, 0] > box[0]) & (line[:, 0] < box[2])
                            & (line[:, 1] > box[1]) & (line[:, 1] < box[3])))
    return count


def _curve_segments(ax: Axes, to_points: Any) -> np.ndarray:
    """``(m, 2, 2)`` segments of the lines drawn on ``ax`` with a line style, in points."""
    out = []
    for line in ax.get_lines():
        if not line.get_visible() or line.get_linestyle() in ("None", "none", " ", ""):
            continue
        xy = np.asarray(line.get_xydata(), dtype=float)
        if len(xy) < 2:
            continue
        xy = to_points(xy)
        ok = np.all(np.isfinite(xy), axis=1)
        seg = ok[:-1] & ok[1:]
        out.append(np.stack([xy[:-1][seg], xy[1:][seg]], axis=1))
    return np.concatenate(out) if out else np.empty((0, 2, 2))


def coincident_groups(ax: Axes, xy: Sequence[tuple[float, float]], *,
                      distance: float = 2.0 * _MARKER, chain: bool = True) -> list[list[int]]:
    """Indices of the points of ``xy`` drawn within ``distance`` points of each other.

    Points closer than a marker are one place on the page whatever the zoom
    (e.g. a grazing and a fold at the same frequency): they get one label.
    Call it on a laid-out figure (see :func:`place_labels`).

    ``chain=True`` links points in chains (a row of markers each near the next is one
    group: a crowd); ``chain=False`` groups only the points within ``distance`` of
    the group's first point (one place, one label).
    """
    if not len(xy):
        return []
    pts = ax.transData.transform(np.asarray(xy, dtype=float)) * 72.0 / ax.figure.dpi
    if not chain:
        places: list[list[int]] = []
        for i in np.argsort(pts[:, 0], kind="stable"):
            for g in places:
                if np.hypot(*(pts[i] - pts[g[0]])) <= distance:
                    g.append(int(i))
                    break
            else:
                places.append([int(i)])
        return places
    group = list(range(len(pts)))

    def root(i: int) -> int:
        while group[i] != i:
            i = group[i]
        return i

    for i in range(len(pts)):
        for j in range(i):
            if np.hypot(*(pts[i] - pts[j])) <= distance:
                group[root(i)] = root(j)
    out: dict[int, list[int]] = {}
    for i in range(len(pts)):
        out.setdefault(root(i), []).append(i)
    return list(out.values())


def merged_labels(ax: Axes, xy: Sequence[tuple[float, float]], texts: Sequence[str], *,
                  distance: float = 3.0 * _MARKER, chain: bool = True
                  ) -> tuple[list[tuple[float, float]], list[str]]:
    """One label per cluster of points drawn near each other: ``PD ×10``, ``SN, GR``.

    Points chained within ``distance`` points on the page (markers touching, e.g.
    ten period doublings stacked at one frequency, or a fold and a grazing at one
    place) are one cluster: its label names each text once, with how many points
    carry it (``PD ×10, GR``), and points at the cluster's middle point. With
    ``chain=False`` a cluster is the points within ``distance`` of its first one
    (one place; see :func:`coincident_groups`), and the label points at that one.
    Call it on a laid-out figure; pass the result to :func:`place_labels`.

    Returns
    -------
    (list of (float, float), list of str)
        The point each label names and its text.
    """
    if len(xy) != len(texts):
        raise ValueError(f"xy and texts must have the same length; got {len(xy)} and "
                         f"{len(texts)}")
    if not len(xy):
        return [], []
    groups = coincident_groups(ax, xy, distance=distance, chain=chain)
    pts = ax.transData.transform(np.asarray(xy, dtype=float))
    where, out = [], []
    for g in sorted(groups, key=lambda g: min(pts[i, 0] for i in g)):
        counts: dict[str, int] = {}
        for i in g:
            for part in str(texts[i]).split(", "):
                name, _, n = part.partition(" \N{MULTIPLICATION SIGN}")
                counts[name] = counts.get(name, 0) + (int(n) if n.isdigit() else 1)
        centre = pts[g].mean(axis=0)  # a chain: its middle point; one place: its first
        middle = g[int(np.argmin(np.hypot(*(pts[g] - centre).T)))] if chain else g[0]
        where.append(tuple(np.asarray(xy[middle], dtype=float)))
        out.append(", ".join(f"{t} \N{MULTIPLICATION SIGN}{n}" if n > 1 else t
                             for t, n in counts.items()))
    return where, out


def place_labels(ax: Axes, xy: Sequence[tuple[float, float]], texts: Sequence[str], *,
                 fontsize: Any = "small", avoid: Sequence[Any] = (),
                 styles: Sequence[dict[str, Any]] | None = None,
                 **text_kw: Any) -> list[Annotation]:
    """Annotate the data points ``xy`` with ``texts`` so that no two labels overlap.

    Call it last, once everything else is drawn on the figure: it lays the
    figure out (:meth:`matplotlib.figure.Figure.draw_without_rendering`) to
    know where the points are.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    xy : sequence of (float, float)
        The points, in data coordinates.
    texts : sequence of str
        One label per point.
    fontsize : str or float, optional
    avoid : sequence of matplotlib.transforms.Bbox, optional
        Further regions, in display coordinates, that no label may cover
        (e.g. an inset).
    styles : sequence of dict, optional
        One dict of text keywords per label (e.g. its colour and weight), over
        ``text_kw``: labels of several kinds placed together, clear of each other.
    **text_kw
        Passed on to :meth:`matplotlib.axes.Axes.annotate`.

    Returns
    -------
    list of matplotlib.text.Annotation
    """
    if len(xy) != len(texts):
        raise ValueError(f"xy and texts must have the same length; got {len(xy)} and "
                         f"{len(texts)}")
    if styles is not None and len(styles) != len(texts):
        raise ValueError(f"styles must have one dict per label ({len(texts)}); got "
                         f"{len(styles)}")
    if not len(xy):
        return []
    kws = [{**text_kw, **(styles[k] if styles is not None else {})} for k in range(len(texts))]
    fig = ax.figure
    fig.draw_without_rendering()
    scale = 72.0 / fig.dpi

    def to_points(data: np.ndarray) -> np.ndarray:
        return ax.transData.transform(data) * scale

    pts = to_points(np.asarray(xy, dtype=float))
    frame = np.asarray(ax.get_window_extent().extents) * scale
    size = FontProperties(size=fontsize).get_size_in_points()
    curves = _curve_points(ax, to_points)
    segments = _curve_segments(ax, to_points)
    markers = np.hstack([pts - _MARKER, pts + _MARKER])
    # texts already there (an earlier call on these axes) are obstacles too
    earlier = [t for t in ax.texts if t.get_visible() and t.get_text()]
    named: list[np.ndarray] = [np.asarray(Text.get_window_extent(t).extents) * scale
                               for t in earlier]  # the texts
    reach: list[np.ndarray] = [np.asarray(t.get_window_extent().extents) * scale
                               for t in earlier]  # with their leaders (an Annotation's extent)
    placed: list[np.ndarray] = [np.asarray(b.extents) * scale for b in avoid]
    legend = ax.get_legend()
    if legend is not None and legend.get_visible():
        placed.append(np.asarray(legend.get_window_extent().extents) * scale)
    leaders: list[np.ndarray] = []  # (2, 2): the leader lines drawn, in points
    out = []
    # the longest labels first (a merged label of a cluster needs the most room), then
    # from left to right
    order = np.lexsort((pts[:, 0], [-len(str(t)) for t in texts]))
    for i, k in enumerate(order):
        px, py = pts[k]
        # the points of the labels still to place: a label (with its leader) over one of
        # them leaves that label no room but over it
        pending = pts[order[i + 1:]]
        probe = Text(0.0, 0.0, texts[k], fontsize=fontsize,
                     fontweight=kws[k].get("fontweight", "normal"))
        probe.set_figure(fig)
        drawn = probe.get_window_extent()  # the text as drawn (weight, mathtext)
        w, h = drawn.width * scale + 2.0, max(drawn.height * scale, 1.2 * size)
        best: tuple[float, float, float, int] | None = None
        for dx, dy, ring in _candidates(w, h):
            box = np.array([px + dx, py + dy, px + dx + w, py + dy + h])
            labels = np.array(named).reshape(-1, 4)
            # the label with its leader (the box up to the point) never over another's
            extent = (np.array([min(box[0], px), min(box[1], py), max(box[2], px),
                                max(box[3], py)]) if ring > 0 else box)
            hard = (_overlap(box, np.array(placed).reshape(-1, 4)) + _overlap(box, markers)
                    + _overlap(extent, np.array(reach).reshape(-1, 4)))
            covered = np.count_nonzero((pending[:, 0] > extent[0]) & (pending[:, 0] < extent[2])
                                       & (pending[:, 1] > extent[1])
                                       & (pending[:, 1] < extent[3]))
            beside = _overlap(box, _side_room(labels, size)) - _overlap(box, labels)
            outside = (max(frame[0] - box[0], 0) + max(box[2] - frame[2], 0)
                       + max(frame[1] - box[1], 0) + max(box[3] - frame[3], 0))
            crossed = np.count_nonzero((curves[:, 0] > box[0]) & (curves[:, 0] < box[2])
                                       & (curves[:, 1] > box[1]) & (curves[:, 1] < box[3]))
            leader = _leader_crossings(pts[k], box, segments) if ring > 0 else 0
            tangle = (_crossings(np.clip(pts[k], box[:2], box[2:]), pts[k], leaders)
                      + _leader_crossings_box(box, leaders)) if ring > 0 else 0
            # any overlap with a label or marker, any label beside another, outweighs the
            # curves under the box: a big label (three lines) covers many curve vertices
            score = (100.0 * hard + 5000.0 * (hard > 1.0) + 10.0 * beside
                     + 5000.0 * (beside > 1.0) + 50.0 * h * outside + 20.0 * crossed
                     + 30.0 * ring + 400.0 * (leader + tangle) + 5000.0 * covered)
            if best is None or score < best[0]:
                best = (score, dx, dy, ring)
        _, dx, dy, ring = best  # type: ignore[misc]
        box = np.array([px + dx, py + dy, px + dx + w, py + dy + h])
        named.append(box)
        reach.append(np.array([min(box[0], px), min(box[1], py), max(box[2], px),
                               max(box[3], py)]) if ring > 0 else box)
        if ring > 0:
            leaders.append(np.array([np.clip(pts[k], box[:2], box[2:]), pts[k]]))
        arrow = ({"arrowstyle": "-", "color": "0.45", "linewidth": 0.6, "shrinkA": 0,
                  "shrinkB": _MARKER} if ring > 0 else None)
        label = ax.annotate(texts[k], xy[k], xytext=(dx, dy), textcoords="offset points",
                            ha="left", va="bottom", fontsize=fontsize, arrowprops=arrow,
                            **kws[k])
        label.set_in_layout(False)  # placed inside the frame; never let it move the axes
        out.append(label)
    return out


def marker_boxes(ax: Axes) -> list[Any]:
    """Display-coordinate boxes of the markers drawn by the lines and scatter plots of ``ax``
    (obstacles).

    Pass them as ``avoid`` to :func:`place_labels` so that a label does not
    cover a mark it does not name. Call it on a laid-out figure.
    """
    from matplotlib.transforms import Bbox

    out = []
    for line in ax.get_lines():
        if not line.get_visible() or line.get_marker() in (None, "", "None", " ", "none"):
            continue
        r = line.get_markersize() / 2 * ax.figure.dpi / 72.0
        xy = ax.transData.transform(np.asarray(line.get_xydata(), dtype=float))
        out += [Bbox.from_extents(px - r, py - r, px + r, py + r)
                for px, py in xy[np.all(np.isfinite(xy), axis=1)]]
    for coll in ax.collections:  # scatter plots (e.g. simulated points) too
        if not isinstance(coll, PathCollection) or not coll.get_visible() \
                or not len(coll.get_offsets()) or not len(coll.get_sizes()):
            continue
        r = np.sqrt(np.max(coll.get_sizes())) / 2 * ax.figure.dpi / 72.0
        xy = coll.get_offset_transform().transform(np.asarray(coll.get_offsets(), dtype=float))
        out += [Bbox.from_extents(px - r, py - r, px + r, py + r)
                for px, py in xy[np.all(np.isfinite(xy), axis=1)]]
    return out

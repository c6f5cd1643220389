"""Layout checks of a figure, from the artists it drew (shared by the figure tests).

A figure is drawn once with the Agg renderer and checked for what a referee
objects to: text outside the figure, two texts overlapping, text on a
special-point marker, two point labels side by side (read as one), a marker cut
by the frame of its axes, a marker hidden under a marker of another kind, a
leader line across a curve, a line or marker style that carries meaning (line
style, colour, marker shape) and has no legend entry, two legend entries drawn
alike, a legend entry for nothing drawn in view, a title with an internal name
(``fig3_N1``, ``root -1``) or without the system and the motion it shows, a
figure wider than a journal page (:data:`MAX_WIDTH`).

Each check returns a list of sentences, one per problem (empty: the figure is
clean); :func:`layout_problems` runs them all and :func:`check_layout` asserts
there is none. Use::

    from tests._layout_checks import check_layout

    check_layout(fig)                                     # the layout only
    check_layout(fig, system=["R = 0.6"], motion=["1-1"])  # and what the titles say
    check_layout(fig, journal=True)                       # and journal conventions
"""

from __future__ import annotations

import contextlib
import itertools
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np
from matplotlib import colors as mcolors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.markers import MarkerStyle
from matplotlib.text import Annotation, Text

from impactcont.plots import SPECIAL_MARKERS

__all__ = ["MAX_WIDTH", "Drawn", "axes_of", "check_layout", "check_titles", "color",
           "journal_problems", "labels_side_by_side", "layout_problems", "leaders_across_curves",
           "leaders_crossing_each_other", "legend_entries_alike", "legend_entries_not_drawn",
           "line_style", "marker_artists", "marker_key", "markers_cut_by_frame",
           "markers_hiding_markers",
           "overlapping_texts", "render", "styles_without_legend", "texts_on_markers",
           "texts_outside_figure", "title_problems", "too_wide"]

#: Widest figure a journal page takes, in inches (a double column is 7 to 7.2 in).
MAX_WIDTH = 7.2

_NO_LINE = ("None", "none", " ", "")
_NO_MARKER = (None, "", "None", " ", "none")
_DARK = {"#000000", "#333333"}  # legend colours that stand for a style in any colour


@dataclass
class Drawn:
    """What one draw of a figure put on the page (display coordinates, pixels)."""

    fig: Figure
    texts: list[Text]
    boxes: np.ndarray
    renderer: object


# -- what was drawn ---------------------------------------------------------------------------
@contextlib.contextmanager
def _recording() -> Iterator[list[Text]]:
    """Record every Text that draws itself (tick labels of ticks in view only, etc.)."""
    drawn: list[Text] = []
    original = Text.draw

    def draw(self, renderer):
        if self.get_visible() and self.get_text().strip():
            drawn.append(self)
        return original(self, renderer)

    Text.draw = draw
    try:
        yield drawn
    finally:
        Text.draw = original


def render(fig: Figure) -> Drawn:
    """Draw ``fig`` with Agg and record the texts drawn and their boxes."""
    if isinstance(fig, Drawn):
        return fig
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    with _recording() as texts:
        canvas.draw()
    renderer = canvas.get_renderer()
    boxes = np.array([t.get_window_extent(renderer).extents for t in texts]).reshape(-1, 4)
    return Drawn(fig, texts, boxes, renderer)


def marker_key(marker) -> tuple:
    """The shape of a marker (its path's vertices), to compare markers."""
    m = MarkerStyle(marker)
    return tuple(np.round(m.get_path().transformed(m.get_transform()).vertices, 3).ravel())


def color(c) -> str:
    """``#rrggbb`` of a colour (alpha dropped)."""
    return to_hex(c, keep_alpha=False)


def axes_of(fig: Figure) -> list:
    """Every visible Axes, insets included."""
    out = []
    for ax in fig.axes:
        out += [ax, *[c for c in ax.child_axes if c.get_visible()]]
    return [ax for ax in dict.fromkeys(out) if ax.get_visible() and ax.axison]


def marker_artists(ax, *, clipped: bool = False) -> list[tuple[np.ndarray, tuple, str, float]]:
    """``(display xy, marker key, edge colour, radius px)`` of every marker drawn on ``ax``
    (``clipped``: only of the artists the frame clips)."""
    out = []
    dpi = ax.figure.dpi
    for line in ax.get_lines():
        if not line.get_visible() or line.get_marker() in _NO_MARKER \
                or (clipped and not line.get_clip_on()):
            continue
        xy = ax.transData.transform(np.asarray(line.get_xydata(), dtype=float))
        r = line.get_markersize() / 2 * dpi / 72
        for p in xy[np.all(np.isfinite(xy), axis=1)]:
            out.append((p, marker_key(line.get_marker()), color(line.get_markeredgecolor()), r))
    for coll in ax.collections:
        if not isinstance(coll, PathCollection) or not coll.get_visible() \
                or coll.get_array() is not None or not len(coll.get_offsets()) \
                or (clipped and not coll.get_clip_on()):
            continue
        key = tuple(np.round(coll.get_paths()[0].vertices, 3).ravel())
        xy = coll.get_offset_transform().transform(np.asarray(coll.get_offsets()))
        r = np.sqrt(coll.get_sizes()[0]) / 2 * dpi / 72
        edges = coll.get_edgecolors()
        for i, p in enumerate(xy):
            out.append((p, key, color(edges[i % len(edges)]) if len(edges) else "none", r))
    return out


def _legends(fig: Figure) -> list:
    return [*fig.legends, *[ax.get_legend() for ax in axes_of(fig) if ax.get_legend()]]


def line_style(line: Line2D) -> tuple:
    """``(dashes, width, alpha)`` of a line, to compare line styles."""
    _, dashes = line._unscaled_dash_pattern
    return (tuple(np.round(dashes, 2)) if dashes else None, round(line.get_linewidth(), 2),
            round(line.get_alpha() if line.get_alpha() is not None else 1.0, 2))


def _legend_styles(fig: Figure) -> tuple[set, set, set]:
    """Line styles ``(dashes, width, alpha)``, marker keys and colours of every legend."""
    styles, markers, colours = set(), set(), set()
    for legend in _legends(fig):
        for h in legend.legend_handles:
            if isinstance(h, Line2D):
                if h.get_linestyle() not in _NO_LINE:
                    styles.add(line_style(h))
                    colours.add(color(h.get_color()))
                if h.get_marker() not in _NO_MARKER:
                    markers.add(marker_key(h.get_marker()))
                    colours.add(color(h.get_markeredgecolor()))
            elif isinstance(h, PathCollection):
                markers.add(tuple(np.round(h.get_paths()[0].vertices, 3).ravel()))
                colours.update(color(c) for c in h.get_edgecolors())
            elif hasattr(h, "get_facecolor"):
                colours.add(color(h.get_facecolor()))
    return styles, markers, colours


def _segments_cross(p0, p1, q0, q1) -> np.ndarray:
    """Whether segment p0-p1 crosses each segment q0[i]-q1[i] (display coordinates)."""
    def orient(a, b, c):
        return np.sign((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
                       - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))
    return ((orient(p0, p1, q0) * orient(p0, p1, q1) < 0)
            & (orient(q0, q1, p0) * orient(q0, q1, p1) < 0))


def _in_view(ax, xy: np.ndarray, pad: float = 0.0) -> np.ndarray:
    """Which display points ``xy`` lie inside the frame of ``ax`` (``pad`` px inside)."""
    box = ax.bbox.extents
    return ((xy[:, 0] >= box[0] + pad) & (xy[:, 0] <= box[2] - pad)
            & (xy[:, 1] >= box[1] + pad) & (xy[:, 1] <= box[3] - pad))


# -- the checks -------------------------------------------------------------------------------
def too_wide(fig: Figure, max_width: float = MAX_WIDTH) -> list[str]:
    """The figure is wider than ``max_width`` inches (a journal's page)."""
    width = float(fig.get_size_inches()[0])
    return ([f"the figure is {width:.2f} in wide, more than {max_width} in"]
            if width > max_width + 1e-9 else [])


def texts_outside_figure(fig: Figure | Drawn) -> list[str]:
    """A text drawn (partly) outside the figure."""
    d = render(fig)
    frame = d.fig.bbox.extents
    return [f"text {t.get_text()!r} outside the figure"
            for t, (x0, y0, x1, y1) in zip(d.texts, d.boxes, strict=True)
            if x0 < frame[0] - 1 or y0 < frame[1] - 1 or x1 > frame[2] + 1 or y1 > frame[3] + 1]


def overlapping_texts(fig: Figure | Drawn) -> list[str]:
    """Two texts whose boxes overlap by more than a pixel each way."""
    d = render(fig)
    out = []
    for (i, a), (j, b) in itertools.combinations(enumerate(d.boxes), 2):
        w = min(a[2], b[2]) - max(a[0], b[0])
        h = min(a[3], b[3]) - max(a[1], b[1])
        if w > 1 and h > 1:
            out.append(f"texts {d.texts[i].get_text()!r} and {d.texts[j].get_text()!r} "
                       f"overlap")
    return out


def labels_side_by_side(fig: Figure | Drawn) -> list[str]:
    """Two point labels of one axes on one line, less than two ems apart: they read as one.

    Labels of special points placed next to each other (``SN GR``, a few points
    apart) read as the name of one point; they share a label (``SN, GR``) or stand
    apart. Two :class:`~matplotlib.text.Annotation` labels of the same axes are side by
    side when their boxes overlap vertically by half the lower one and the gap between
    them is less than the font size of the smaller one.
    """
    d = render(fig)
    labels = [(t, Text.get_window_extent(t, d.renderer).extents)  # the text, not its leader
              for t in d.texts if isinstance(t, Annotation) and t.axes is not None]
    out = []
    for (ta, a), (tb, b) in itertools.combinations(labels, 2):
        if ta.axes is not tb.axes:
            continue
        rise = min(a[3], b[3]) - max(a[1], b[1])
        gap = max(a[0], b[0]) - min(a[2], b[2])
        em = min(ta.get_fontsize(), tb.get_fontsize()) * d.fig.dpi / 72.0
        if rise > 0.5 * min(a[3] - a[1], b[3] - b[1]) and -1.0 <= gap < 2.0 * em:
            out.append(f"labels {ta.get_text()!r} and {tb.get_text()!r} side by side "
                       f"({gap * 72.0 / d.fig.dpi:.1f} pt apart) read as one")
    return out


def texts_on_markers(fig: Figure | Drawn) -> list[str]:
    """A text over the centre of a special-point marker it does not name."""
    d = render(fig)
    special_keys = {marker_key(m) for m in SPECIAL_MARKERS.values()}
    out = []
    for ax in axes_of(d.fig):
        specials = [p for p, key, _, _ in marker_artists(ax) if key in special_keys]
        for t, tb in zip(d.texts, d.boxes, strict=True):
            if t.axes is not ax:
                continue
            for p in specials:
                own = isinstance(t, Annotation) and np.allclose(
                    ax.transData.transform(t.xy), p, atol=1.0)
                if not own and tb[0] < p[0] < tb[2] and tb[1] < p[1] < tb[3]:
                    out.append(f"text {t.get_text()!r} covers a marker")
    return out


def markers_cut_by_frame(fig: Figure | Drawn) -> list[str]:
    """A marker neither wholly inside nor wholly outside the frame of its axes.

    A marker drawn unclipped (``clip_on=False``, a point on the edge of a map drawn over
    the frame) is whole wherever it is.
    """
    d = render(fig)
    out = []
    for ax in axes_of(d.fig):
        box = ax.bbox.extents
        for p, _key, _colour, r in marker_artists(ax, clipped=True):
            inside = box[0] + r <= p[0] <= box[2] - r and box[1] + r <= p[1] <= box[3] - r
            outside = (p[0] < box[0] - r or p[0] > box[2] + r or p[1] < box[1] - r
                       or p[1] > box[3] + r)
            if not inside and not outside:
                out.append(f"a marker at {p.round(1)} is cut by the frame")
    return out


def _marker_paths(ax) -> list[tuple[int, object, np.ndarray, object, tuple, float, bool]]:
    """Every marker drawn on ``ax`` in drawing order: ``(order, artist, display centre,
    outline path in display coordinates, style, diameter px, filled)``.

    The style is the marker's shape, size, edge and face colour; ``filled``: its face
    is painted (it hides what lies under it).
    """
    from matplotlib.transforms import Affine2D

    dpi = ax.figure.dpi
    artists = sorted(((a.get_zorder(), i, a) for i, a in enumerate(ax.get_children())
                      if a.get_visible() and (isinstance(a, PathCollection) or (
                          isinstance(a, Line2D) and a.get_marker() not in _NO_MARKER))),
                     key=lambda t: (t[0], t[1]))
    out = []
    for order, (_, _, a) in enumerate(artists):
        if isinstance(a, Line2D):
            m = MarkerStyle(a.get_marker(), a.get_fillstyle())
            size = a.get_markersize() * dpi / 72.0
            path = m.get_path().transformed(m.get_transform() + Affine2D().scale(size))
            face = a.get_markerfacecolor()
            filled = (m.is_filled() and m.get_fillstyle() == "full"
                      and not (isinstance(face, str) and face.lower() == "none")
                      and mcolors.to_rgba(face, a.get_alpha())[3] > 0.5)
            style = (marker_key(a.get_marker()), round(size, 1), color(a.get_markeredgecolor()),
                     color(face) if filled else "none")
            xy = ax.transData.transform(np.asarray(a.get_xydata(), dtype=float))
            for p in xy[np.all(np.isfinite(xy), axis=1)]:
                out.append((order, a, p, path.transformed(Affine2D().translate(*p)), style,
                            size, filled))
            continue
        offsets = np.asarray(a.get_offsets(), dtype=float)
        if not len(offsets) or not len(a.get_paths()):
            continue
        xy = a.get_offset_transform().transform(offsets)
        transforms = a.get_transforms()
        faces, edges = a.get_facecolors(), a.get_edgecolors()
        for i, p in enumerate(xy):
            if not np.all(np.isfinite(p)):
                continue
            base = a.get_paths()[i % len(a.get_paths())]
            t = Affine2D(transforms[i % len(transforms)]) if len(transforms) else Affine2D()
            path = base.transformed(t)
            size = float(np.ptp(path.vertices, axis=0).max()) if len(path.vertices) else 0.0
            face = faces[i % len(faces)] if len(faces) else None
            filled = face is not None and face[3] > 0.5
            style = (tuple(np.round(base.vertices, 3).ravel()), round(size, 1),
                     color(edges[i % len(edges)]) if len(edges) else "none",
                     color(face) if filled else "none")
            out.append((order, a, p, path.transformed(Affine2D().translate(*p)), style, size,
                        filled))
    return out


def markers_hiding_markers(fig: Figure | Drawn, closeness: float = 1.0 / 3.0) -> list[str]:
    """A marker drawn over a marker of another kind that lies wholly under it.

    The reader cannot see the covered one (a PD marker over a GR marker of the same
    point, a special point over a simulated point). Two markers of different style
    (shape, size, edge or face colour) of different artists count when their centres
    are closer than ``closeness`` times the smaller marker's size, the later-drawn one
    has a painted face, and the earlier one's outline lies wholly inside it. Points that
    coincide are drawn as one combined marker (or of sizes that leave both in view).
    """
    from scipy.spatial import cKDTree

    d = render(fig)
    out = []
    for ax in axes_of(d.fig):
        box = ax.bbox.extents
        marks = [m for m in _marker_paths(ax)  # in view (a log axis puts zeros far off)
                 if box[0] <= m[2][0] <= box[2] and box[1] <= m[2][1] <= box[3]]
        if len(marks) < 2:
            continue
        centres = np.array([m[2] for m in marks])
        reach = closeness * max(m[5] for m in marks)
        for i, j in sorted(cKDTree(centres).query_pairs(reach)):
            under, over = (marks[i], marks[j]) if marks[i][0] < marks[j][0] else (
                marks[j], marks[i])
            if under[0] == over[0] or under[4] == over[4] or not over[6]:
                continue
            if np.hypot(*(under[2] - over[2])) >= closeness * min(under[5], over[5]):
                continue
            # shrunk a little about its centre: an outline on the other's is under it
            inner = (under[3].vertices - under[2]) * 0.97 + under[2]
            if np.all(over[3].contains_points(inner)):
                x, y = ax.transData.inverted().transform(under[2])
                out.append(f"a marker at ({x:.4g}, {y:.4g}) is hidden under a marker of "
                           f"another kind")
    return out


def _coloured_marker_entries(fig: Figure) -> dict[str, set]:
    """Edge colour -> marker shapes of the legend's marker entries not drawn in black."""
    out: dict[str, set] = {}
    for legend in _legends(fig):
        for h in legend.legend_handles:
            if isinstance(h, Line2D) and h.get_marker() not in _NO_MARKER:
                c = color(h.get_markeredgecolor())
                if c != "#000000":
                    out.setdefault(c, set()).add(marker_key(h.get_marker()))
    return out


def styles_without_legend(fig: Figure | Drawn) -> list[str]:
    """A marker in view or a line whose style or colour no legend shows.

    A marker needs a legend entry of its shape and one of its colour; a marker of
    a colour that has marker entries of its own (e.g. grey: on a non-physical
    motion) needs an entry of that colour and its shape.
    """
    d = render(fig)
    styles, legend_markers, legend_colours = _legend_styles(d.fig)
    coloured = _coloured_marker_entries(d.fig)
    out = []
    for ax in axes_of(d.fig):
        box = ax.bbox.extents
        for p, key, colour, r in marker_artists(ax):
            outside = (p[0] < box[0] - r or p[0] > box[2] + r or p[1] < box[1] - r
                       or p[1] > box[3] + r)
            if not outside and (key not in legend_markers or colour not in legend_colours):
                out.append(f"a marker of colour {colour} at {p.round(1)} has no legend entry")
            elif not outside and colour in coloured and key not in coloured[colour]:
                out.append(f"a marker of colour {colour} at {p.round(1)} has another shape "
                           f"than the legend entries of that colour")
        for line in ax.get_lines():
            if not line.get_visible() or line.get_linestyle() in _NO_LINE \
                    or not len(line.get_xydata()):
                continue
            if line_style(line) not in styles or color(line.get_color()) not in legend_colours:
                out.append(f"a {line.get_linestyle()} line of colour "
                           f"{color(line.get_color())} has no legend entry")
    return out


def legend_entries_not_drawn(fig: Figure | Drawn) -> list[str]:
    """A legend entry (line or marker) that nothing in view on any axes looks like.

    A legend lists what the reader can see. A line entry in a dark neutral colour
    (black to ``0.2``) stands for its line style in any colour and needs a line
    of that style (dashes, width, alpha) with a vertex in view; a line entry in
    another colour stands for that colour and needs a line of it in view. A
    marker entry with a black edge stands for its shape in any colour (special
    points are drawn in their branch's colour); another marker entry needs a
    marker of its shape and edge colour in view. Patches (shaded regions) are not
    checked.
    """
    d = render(fig)
    styles, colours, markers = set(), set(), {}
    for ax in axes_of(d.fig):
        for line in ax.get_lines():
            if not line.get_visible() or line.get_linestyle() in _NO_LINE:
                continue
            xy = ax.transData.transform(np.asarray(line.get_xydata(), dtype=float))
            if np.any(_in_view(ax, xy[np.all(np.isfinite(xy), axis=1)])):
                styles.add(line_style(line))
                colours.add(color(line.get_color()))
        for p, key, colour, _r in marker_artists(ax):
            if _in_view(ax, p[None, :])[0]:
                markers.setdefault(key, set()).add(colour)
    out = []
    for legend in _legends(d.fig):
        for h, text in zip(legend.legend_handles, legend.get_texts(), strict=False):
            if not isinstance(h, Line2D):
                continue
            name = text.get_text()
            if h.get_linestyle() not in _NO_LINE and h.get_marker() in _NO_MARKER:
                c = color(h.get_color())
                seen = line_style(h) in styles if c in _DARK else c in colours
                if not seen:
                    out.append(f"legend entry {name!r}: no such line in view")
            if h.get_marker() not in _NO_MARKER and h.get_linestyle() in _NO_LINE:
                seen = markers.get(marker_key(h.get_marker()), set())
                c = color(h.get_markeredgecolor())
                if not seen or (c != "#000000" and c not in seen):
                    out.append(f"legend entry {name!r}: no such marker in view")
    return out


def _handle_style(h) -> tuple:
    """What a legend handle looks like: line style, colours, marker (its label aside)."""
    if isinstance(h, Line2D):
        line = line_style(h) if h.get_linestyle() not in _NO_LINE else None
        marker = marker_key(h.get_marker()) if h.get_marker() not in _NO_MARKER else None
        return ("line", line, color(h.get_color()) if line else None, marker,
                color(h.get_markeredgecolor()) if marker else None,
                color(h.get_markerfacecolor()) if marker else None,
                round(h.get_markersize(), 1) if marker else None)
    if isinstance(h, PathCollection):
        return ("markers", tuple(np.round(h.get_paths()[0].vertices, 3).ravel()),
                tuple(color(c) for c in h.get_edgecolors()),
                tuple(color(c) for c in h.get_facecolors()))
    if hasattr(h, "get_facecolor"):
        return ("patch", color(h.get_facecolor()), round(float(h.get_alpha() or 1.0), 2),
                color(h.get_edgecolor()) if hasattr(h, "get_edgecolor") else None)
    return ("other", id(h))


def legend_entries_alike(fig: Figure | Drawn) -> list[str]:
    """Two entries of one legend with handles drawn alike: the reader cannot tell which
    of the two a mark of that style is (``asymmetric`` and ``asymmetric 2`` in one red)."""
    d = render(fig)
    out = []
    for legend in _legends(d.fig):
        seen: dict[tuple, str] = {}
        for h, text in zip(legend.legend_handles, legend.get_texts(), strict=False):
            key = _handle_style(h)
            if key in seen:
                out.append(f"legend entries {seen[key]!r} and {text.get_text()!r} look alike")
            else:
                seen[key] = text.get_text()
    return out


def leaders_across_curves(fig: Figure | Drawn) -> list[str]:
    """The leader line of a label crossing a drawn curve (its last 6 px excepted)."""
    d = render(fig)
    out = []
    for ax in axes_of(d.fig):
        curves = [ax.transData.transform(np.asarray(line.get_xydata(), dtype=float))
                  for line in ax.get_lines() if line.get_visible()
                  and line.get_linestyle() not in _NO_LINE]
        for t in d.texts:
            if t.axes is not ax or not isinstance(t, Annotation) or t.arrow_patch is None:
                continue
            tb = t.get_window_extent(d.renderer).extents
            p = ax.transData.transform(t.xy)
            start = np.clip(p, tb[:2], tb[2:])
            end = start + (p - start) * max(0.0, 1 - 6.0 / max(np.hypot(*(p - start)), 1e-9))
            for xy in curves:
                ok = np.all(np.isfinite(xy), axis=1)
                seg = ok[:-1] & ok[1:]
                if np.any(_segments_cross(start, end, xy[:-1][seg], xy[1:][seg])):
                    out.append(f"the leader line of {t.get_text()!r} crosses a curve")
                    break
    return out


def leaders_crossing_each_other(fig: Figure | Drawn) -> list[str]:
    """Two leader lines of one axes crossing each other."""
    d = render(fig)
    out = []
    for ax in axes_of(d.fig):
        leaders = []
        for t in d.texts:
            if t.axes is ax and isinstance(t, Annotation) and t.arrow_patch is not None:
                tb = t.get_window_extent(d.renderer).extents
                p = ax.transData.transform(t.xy)
                leaders.append((t.get_text(), np.clip(p, tb[:2], tb[2:]), p))
        for (na, a0, a1), (nb, b0, b1) in itertools.combinations(leaders, 2):
            if _segments_cross(a0, a1, b0[None, :], b1[None, :])[0]:
                out.append(f"the leader lines of {na!r} and {nb!r} cross")
    return out


def _titles(fig: Figure) -> list[str]:
    """The suptitles of the figure and its subfigures and the titles of its axes."""
    out, figs = [], [fig]
    while figs:
        f = figs.pop()
        out += [f._suptitle.get_text()] if f._suptitle is not None else []
        figs += list(getattr(f, "subfigs", []))
    for ax in axes_of(fig):
        out += [ax.title.get_text(), ax._left_title.get_text(), ax._right_title.get_text()]
    return [t for t in out if t.strip()]


def title_problems(fig: Figure, *, system: Iterable[str] = (),
                   motion: Iterable[str] = ()) -> list[str]:
    """Titles that use internal names, or do not name the system and the motion.

    An internal name is an identifier with an underscore outside mathtext
    (``fig3_N1``, ``b0p5_N2``) or a raw root index (``root -1``). ``system`` and
    ``motion`` are texts the titles (suptitle and axes titles together) must
    contain, e.g. ``["R = 0.6"]`` and ``["1-1"]``.
    """
    titles = _titles(fig)
    out = []
    for title in titles:
        plain = re.sub(r"(?<!\\)\$.*?(?<!\\)\$", "", title)
        if re.search(r"\w_\w", plain) or re.search(r"\broot\s*-?\d", plain):
            out.append(f"title {title!r} uses an internal name")
    joined = " | ".join(titles)
    for word in [*system, *motion]:
        if word not in joined:
            out.append(f"no title names {word!r} (titles: {joined!r})")
    return out


def journal_problems(fig: Figure | Drawn) -> list[str]:
    """Axis labels in symbols, not identifiers; no legend over the data of an axes."""
    d = render(fig)
    problems = []
    axes = [ax for ax in d.fig.axes if ax.get_visible() and ax.axison]
    for ax in axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            plain = re.sub(r"\$[^$]*\$", "", label)
            if "$" not in label or "_" in plain or re.search(
                    r"\b(omega|eta|alpha|beta|delta|b|R)\b", plain):
                problems.append(f"axis label {label!r} is not in symbols (mathtext)")
    for legend, ax in itertools.product(_legends(d.fig), axes_of(d.fig)):
        a, b = legend.get_window_extent().extents, ax.bbox.extents
        w = min(a[2], b[2]) - max(a[0], b[0])
        h = min(a[3], b[3]) - max(a[1], b[1])
        if w > 1 and h > 1:
            problems.append(f"a legend covers {w * h:.0f} px^2 of the data area of an axes")
    return problems


def layout_problems(fig: Figure, *, max_width: float = MAX_WIDTH) -> list[str]:
    """Everything a referee would object to in the layout of ``fig``, as sentences.

    Runs :func:`too_wide`, :func:`texts_outside_figure`, :func:`overlapping_texts`,
    :func:`labels_side_by_side`,
    :func:`texts_on_markers`, :func:`markers_cut_by_frame`,
    :func:`markers_hiding_markers`, :func:`styles_without_legend`, :func:`legend_entries_not_drawn`,
    :func:`legend_entries_alike`,
    :func:`leaders_across_curves`, :func:`leaders_crossing_each_other` and
    :func:`title_problems` (internal names only) on one drawing of the figure.
    """
    d = render(fig)
    out = too_wide(d.fig, max_width)
    for check in (texts_outside_figure, overlapping_texts, labels_side_by_side, texts_on_markers,
                  markers_cut_by_frame, markers_hiding_markers, styles_without_legend,
                  legend_entries_not_drawn,
                  legend_entries_alike,
                  leaders_across_curves, leaders_crossing_each_other):
        out += check(d)
    return out + title_problems(d.fig)


def check_titles(fig: Figure, *, system: Iterable[str] = (), motion: Iterable[str] = ()) -> None:
    """Assert :func:`title_problems` finds nothing."""
    problems = title_problems(fig, system=system, motion=motion)
    assert not problems, "\n".join(dict.fromkeys(problems))


def check_layout(fig: Figure, *, system: Iterable[str] = (), motion: Iterable[str] = (),
                 journal: bool = False, max_width: float = MAX_WIDTH) -> None:
    """Assert the figure has none of the problems of :func:`layout_problems`.

    With ``system``/``motion``, the titles must also contain those texts; with
    ``journal``, the checks of :func:`journal_problems` run too.
    """
    problems = layout_problems(fig, max_width=max_width)
    if system or motion:
        problems += title_problems(fig, system=system, motion=motion)
    if journal:
        problems += journal_problems(fig)
    assert not problems, "\n".join(dict.fromkeys(problems))

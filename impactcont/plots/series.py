"""Series against a parameter, and figures of several panels at a journal's width.

The studies compare the package with a witness (a closed form, a simulator, a
reference computed in 50 digits): values, or their differences, against a
parameter. :func:`series_plot` draws such series on one Axes with the
conventions every figure of impactcont keeps:

- a line (a closed form, a reference) is drawn over the markers (a witness, the
  package's points), and the markers are hollow by default, so neither hides
  the other;
- on a logarithmic axis an exact zero (a difference that is 0 in floating
  point) is drawn in its own row under the axes, labelled ``exact 0``, never at
  an invented floor value;
- every line style, marker and colour drawn is named in the legend.

:func:`time_history` draws a simulated motion with its sticking phases: the held
intervals shaded, the contact force of each held stop on a panel of its own, the
accumulation points of complete chatter marked.

:func:`panel_figure` lays out several panels at a given width (one column
below 5 in, two columns above: a 2 x 2 grid for four panels), and
:func:`figure_legend` puts one legend for all of them under the panels,
off every data area.

Like the other plots of :mod:`impactcont.plots` the functions take arrays, draw
on a :class:`matplotlib.figure.Figure` (no pyplot) and never show it.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.ticker import LogFormatterSciNotation, NullFormatter, NullLocator

from impactcont.plots.branches import fit_text, legend_fontsize

__all__ = ["HELD_COLOR", "MAX_WIDTH", "MIN_WIDTH", "ZERO_LABEL", "Series", "figure_legend",
           "fit_labels", "inside_frame", "markers_whole", "one_per_style", "panel_figure",
           "series_plot", "take_legend", "time_history"]

logger = logging.getLogger(__name__)

#: Widest figure, in inches: a journal's double column (Elsevier 190 mm, AIP 7 in).
MAX_WIDTH = 7.2
#: Narrowest figure, in inches (below a single column of 3.5 in text no longer fits).
MIN_WIDTH = 2.0
#: Label of the row of exact zeros under a logarithmic axis.
ZERO_LABEL = "exact 0"
_NONE = ("", "none", "None", " ")
_ZERO_ROW = 0.13  # height of the row of exact zeros, as a fraction of the axes
_ZERO_LINE = 1.15  # spacing of the series' lines of markers in that row, in marker sizes
_LINE_ZORDER, _MARKER_ZORDER = 3.0, 2.0
#: Shade of the intervals a stop holds (sticking phases) in :func:`time_history`.
HELD_COLOR = "0.86"
_FORCE_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#e377c2")


@dataclass(frozen=True)
class Series:
    """One series of :func:`series_plot`: ``y`` against ``x``, its legend label and style.

    Parameters
    ----------
    x, y : array_like
        Values of equal length; NaN values are not drawn (a gap in a line).
    label : str
        The legend entry (mathtext for symbols). Series sharing a label share
        one legend entry and must share their style.
    color : str
        A matplotlib colour.
    linestyle : str
        ``"-"``, ``"--"``, ``":"``, ``"-."`` or ``"none"`` (markers only).
    marker : str or None
        A matplotlib marker, or None for a line only.
    filled : bool
        Filled markers; hollow by default, so a line through them stays visible.
    markersize, linewidth : float
        In points.
    """

    x: Any
    y: Any
    label: str
    color: str = "k"
    linestyle: str = "-"
    marker: str | None = None
    filled: bool = False
    markersize: float = 4.0
    linewidth: float = 1.2
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        x = np.asarray(self.x, dtype=float).ravel()
        y = np.asarray(self.y, dtype=float).ravel()
        if x.shape != y.shape:
            raise ValueError(f"Series {self.label!r}: x and y must have equal lengths; got "
                             f"{x.size} and {y.size}")
        if not isinstance(self.label, str) or not self.label.strip():
            raise ValueError(f"Series label must be a non-empty string; got {self.label!r}")
        if self.linestyle in _NONE and self.marker in (None, *_NONE):
            raise ValueError(f"Series {self.label!r} draws nothing: linestyle "
                             f"{self.linestyle!r} and marker {self.marker!r}")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)

    @property
    def is_line(self) -> bool:
        """Whether the series is drawn as a line (with or without markers)."""
        return self.linestyle not in _NONE

    def style(self) -> dict[str, Any]:
        """Keyword arguments of :meth:`matplotlib.axes.Axes.plot` for this series."""
        marker = self.marker if self.marker not in (None, *_NONE) else "none"
        return {"color": self.color, "linestyle": "none" if not self.is_line else
                self.linestyle, "linewidth": self.linewidth, "marker": marker,
                "markersize": self.markersize, "markeredgecolor": self.color,
                "markerfacecolor": self.color if self.filled else "white",
                "markeredgewidth": 1.0, **self.extra}

    def handle(self) -> Line2D:
        """Its legend entry."""
        return Line2D([], [], label=self.label, **self.style())


def _check_width(width: float) -> float:
    if not isinstance(width, (int, float)) or isinstance(width, bool) \
            or not MIN_WIDTH <= float(width) <= MAX_WIDTH:
        raise ValueError(f"width must be a number of inches in [{MIN_WIDTH}, {MAX_WIDTH}] "
                         f"(a journal's single to double column); got {width!r}")
    return float(width)


def panel_figure(n: int, width: float, *, ncols: int | None = None,
                 aspect: float | None = None, extra_height: float = 0.9
                 ) -> tuple[Figure, list[Axes]]:
    """A figure of ``n`` panels ``width`` inches wide, in a constrained layout.

    Parameters
    ----------
    n : int
        Number of panels, 1 to 8.
    width : float
        Figure width in inches, in [:data:`MIN_WIDTH`, :data:`MAX_WIDTH`]: 3.5 for a
        journal's single column, 7 for its double column.
    ncols : int, optional
        Columns of panels; by default 1 below 5 in and 2 (``min(n, 2)``) above,
        so four panels make a 2 x 2 grid.
    aspect : float, optional
        Height of each panel over its width; by default 0.72, or 0.55 for three
        or more panels in one column (a figure no taller than a page).
    extra_height : float
        Inches added to the height for a figure legend, titles and labels.

    Returns
    -------
    (matplotlib.figure.Figure, list of matplotlib.axes.Axes)
        The figure (Agg-compatible, no pyplot) and its ``n`` axes, row by row;
        a last panel alone in its row spans the row (three panels at 7 in: two
        side by side over one as wide as the figure).

    Raises
    ------
    ValueError
        ``n``, ``width``, ``ncols`` or ``aspect`` out of range.
    """
    width = _check_width(width)
    if not isinstance(n, (int, np.integer)) or not 1 <= n <= 8:
        raise ValueError(f"n must be an integer number of panels in [1, 8]; got {n!r}")
    if ncols is None:
        ncols = 1 if width < 5.0 else min(int(n), 2)
    if not isinstance(ncols, (int, np.integer)) or not 1 <= ncols <= min(int(n), 3):
        raise ValueError(f"ncols must be an integer in [1, {min(int(n), 3)}]; got {ncols!r}")
    if aspect is None:
        aspect = 0.55 if ncols == 1 and n >= 3 else 0.72
    if not 0.2 <= aspect <= 2.0:
        raise ValueError(f"aspect must be in [0.2, 2]; got {aspect!r}")
    nrows = math.ceil(n / ncols)
    height = nrows * aspect * width / ncols + extra_height
    fig = Figure(figsize=(width, height), layout="constrained")
    grid = fig.add_gridspec(nrows, ncols)
    axes = [fig.add_subplot(grid[i // ncols, i % ncols]) for i in range(int(n) - 1)]
    last = int(n) - 1  # an odd panel out spans the last row
    axes.append(fig.add_subplot(grid[last // ncols, last % ncols:]))
    return fig, axes


class _AboveFloor(LogFormatterSciNotation):
    """Log tick labels from ``floor`` up; none below it (beside the row of exact zeros)."""

    def __init__(self, floor: float) -> None:
        super().__init__()
        self.floor = floor

    def __call__(self, x: float, pos: int | None = None) -> str:
        return super().__call__(x, pos) if x >= self.floor * (1 - 1e-9) else ""


def _zero_row_height(ax: Axes, zeros: Sequence[tuple[Series, np.ndarray]]) -> float:
    """The row's height, a fraction of the axes: :data:`_ZERO_ROW`, or more on a short
    axes, so that its markers and its label fit (at most 0.3)."""
    ax.figure.draw_without_rendering()
    height = ax.bbox.height * 72.0 / ax.figure.dpi  # points
    # a line of markers per series (their zeros may share an x) and margins, points
    need = _ZERO_LINE * len(zeros) * max(s.markersize for s, _ in zeros) + 10.0
    return float(min(0.3, max(_ZERO_ROW, 1.3 * need / max(height, 1.0))))


def _zero_row(ax: Axes, zeros: Sequence[tuple[Series, np.ndarray]], height: float) -> Axes:
    """The row of exact zeros under the data of ``ax`` (a child axes sharing its x)."""
    row = ax.inset_axes((0.0, 0.0, 1.0, height), sharex=ax)
    row.set_facecolor("white")
    row.set_zorder(ax.get_zorder() + 1)
    # each series on a line of its own inside the row, so that exact zeros of several
    # series at one x are all seen (one marker drawn over another would hide it)
    ax.figure.draw_without_rendering()
    points = max(ax.bbox.height * height * 72.0 / ax.figure.dpi, 1.0)  # the row's height
    step = 2.0 * _ZERO_LINE * max(s.markersize for s, _ in zeros) / points  # data units
    for k, (series, x) in enumerate(zeros):
        row.plot(x, np.full(x.size, (k - (len(zeros) - 1) / 2.0) * step),
                 zorder=_MARKER_ZORDER, **{**series.style(), "linestyle": "none"})
    row.set_ylim(-1.0, 1.0)
    row.set_yticks([0.0], [ZERO_LABEL], fontsize="x-small")
    row.yaxis.set_minor_locator(NullLocator())
    row.tick_params(axis="x", which="both", bottom=False, labelbottom=False)
    row.tick_params(axis="y", length=0, pad=2)
    return row


def series_plot(ax: Axes, series: Iterable[Series], *, xlabel: str, ylabel: str,
                xscale: str = "linear", yscale: str = "linear", title: str | None = None,
                legend: bool = False) -> Axes:
    """Draw ``series`` on ``ax``: lines over hollow markers, exact zeros apart on a log axis.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    series : iterable of Series
        Drawn in order; lines (closed forms, references) on top of markers.
    xlabel, ylabel : str
        Axis labels, with the quantity's symbol in mathtext (``r"$\\omega$"``).
    xscale, yscale : {"linear", "log"}
        On a ``"log"`` y axis an exact zero is drawn in a row of its own under the
        data, labelled :data:`ZERO_LABEL`; a negative value is an error.
    title : str, optional
        Axes title.
    legend : bool
        Draw the legend inside the axes at its best place (a single panel with
        room); by default none: use :func:`figure_legend` for the figure.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``; its row of exact zeros, if one was drawn, is its child axes.

    Raises
    ------
    ValueError
        A scale other than linear or log, a non-positive x on a log x axis, a
        negative y on a log y axis, or one label given two styles.
    """
    series = list(series)
    for name, scale in (("xscale", xscale), ("yscale", yscale)):
        if scale not in ("linear", "log"):
            raise ValueError(f"{name} must be 'linear' or 'log'; got {scale!r}")
    styles: dict[str, dict[str, Any]] = {}
    for s in series:
        if styles.setdefault(s.label, s.style()) != s.style():
            raise ValueError(f"series labelled {s.label!r} are given two styles; one label, "
                             f"one style")
        if xscale == "log" and np.any(s.x[np.isfinite(s.x)] <= 0):
            raise ValueError(f"series {s.label!r}: x must be > 0 on a log x axis; got "
                             f"{float(np.nanmin(s.x))!r}")
        if yscale == "log" and np.any(s.y[np.isfinite(s.y)] < 0):
            raise ValueError(f"series {s.label!r}: y must be >= 0 on a log y axis; got "
                             f"{float(np.nanmin(s.y))!r}")
    ax.set_xscale(xscale)
    ax.set_yscale(yscale)
    zeros: list[tuple[Series, np.ndarray]] = []
    positive: list[np.ndarray] = []
    for s in series:
        y = s.y
        if yscale == "log":
            zero = y == 0.0
            if zero.any():
                zeros.append((s, s.x[zero]))
            y = np.where(zero, np.nan, y)
            positive.append(y[np.isfinite(y)])
        ax.plot(s.x, y, zorder=_LINE_ZORDER if s.is_line else _MARKER_ZORDER, label=s.label,
                **s.style())
    if zeros:
        values = np.concatenate(positive) if positive else np.empty(0)
        lo, hi = (float(values.min()), float(values.max())) if values.size else (1e-16, 1.0)
        lo_exp = math.floor(math.log10(lo))
        hi_exp = max(math.ceil(math.log10(hi) + 0.15), lo_exp + 1)  # no marker on the top
        # the row takes the bottom of the axes, a margin above it: no data there
        height = _zero_row_height(ax, zeros)
        span = (hi_exp - lo_exp) / (1.0 - height - 0.08)
        ax.set_ylim(10.0 ** (hi_exp - span), 10.0 ** hi_exp)
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.yaxis.set_major_formatter(_AboveFloor(10.0 ** lo_exp))  # none beside the row
        _zero_row(ax, zeros, height)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize="medium")
    if legend:
        ax.legend(handles=[s.handle() for s in _unique(series)],
                  fontsize=legend_fontsize(ax.figure), loc="best")
    logger.debug("series plot: %d series, %d with exact zeros", len(series), len(zeros))
    return ax


def _unique(series: Iterable[Series]) -> list[Series]:
    return list({s.label: s for s in reversed(list(series))}.values())[::-1]


def take_legend(ax: Axes) -> list[Any]:
    """The handles of the legend a package plot drew on ``ax``, each labelled with its text,
    and the legend removed (for one legend of several panels, :func:`figure_legend`)."""
    legend = ax.get_legend()
    handles = list(legend.legend_handles)
    for h, text in zip(handles, legend.get_texts(), strict=True):
        h.set_label(text.get_text())
    legend.remove()
    return handles


def inside_frame(ax: Axes, x: Any, y: Any, size: float) -> np.ndarray:
    """Which points ``(x, y)`` a marker of ``size`` points shows whole inside the frame of
    ``ax``, on its laid-out figure: draw only those, never one the frame cuts in half."""
    ax.figure.draw_without_rendering()
    r = size / 2 * ax.figure.dpi / 72.0
    xy = ax.transData.transform(np.column_stack([np.ravel(x), np.ravel(y)]))
    box = ax.bbox.extents
    inside = ((xy[:, 0] >= box[0] + r) & (xy[:, 0] <= box[2] - r)
              & (xy[:, 1] >= box[1] + r) & (xy[:, 1] <= box[3] - r))
    return inside.reshape(np.shape(x))


def markers_whole(ax: Axes) -> None:
    """Widen the limits of ``ax`` until no marker of its lines is cut by the frame.

    A special point at the edge of a zoom is drawn whole (the limits grow by at most a
    marker's size on each side). Call it on a laid-out figure, last.
    """
    for _ in range(4):
        ax.figure.draw_without_rendering()
        box = ax.bbox.extents
        grow = np.zeros(4)  # pixels to add left, bottom, right, top
        for line in ax.get_lines():
            if not line.get_visible() or line.get_marker() in (None, "", "None", " ", "none"):
                continue
            r = line.get_markersize() / 2 * ax.figure.dpi / 72.0 + 1.0
            xy = ax.transData.transform(np.asarray(line.get_xydata(), dtype=float))
            for px, py in xy[np.all(np.isfinite(xy), axis=1)]:
                if box[0] - r < px < box[2] + r and box[1] - r < py < box[3] + r:
                    grow = np.maximum(grow, [box[0] + r - px, box[1] + r - py,
                                             px + r - box[2], py + r - box[3]])
        if not np.any(grow > 0):
            return
        (x0, y0), (x1, y1) = ax.transData.inverted().transform(
            [(box[0] - grow[0], box[1] - grow[1]), (box[2] + grow[2], box[3] + grow[3])])
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)


def _style_key(handle: Any) -> tuple:
    """What a legend handle looks like (line, colours, marker), its label aside."""
    from matplotlib.colors import to_hex

    if isinstance(handle, Line2D):
        line = handle.get_linestyle() not in ("None", "none", " ", "")
        marker = handle.get_marker() not in (None, "", "None", " ", "none")
        return ("line", handle.get_linestyle() if line else None,
                round(handle.get_linewidth(), 2) if line else None,
                to_hex(handle.get_color()) if line else None,
                str(handle.get_marker()) if marker else None,
                to_hex(handle.get_markeredgecolor()) if marker else None,
                to_hex(handle.get_markerfacecolor()) if marker else None,
                round(handle.get_markersize(), 1) if marker else None, handle.get_alpha())
    if hasattr(handle, "get_facecolor"):
        return ("patch", to_hex(handle.get_facecolor(), keep_alpha=True), handle.get_alpha())
    return ("other", id(handle))


def one_per_style(handles: Sequence[Any]) -> list[Any]:
    """The first of the legend ``handles`` of each look (line, colours, marker).

    Two entries drawn alike (``asymmetric`` and ``asymmetric 2``, one red line each)
    cannot be told apart on the plot: the first names the style.
    """
    out: dict[tuple, Any] = {}
    for h in handles:
        out.setdefault(_style_key(h), h)
    return list(out.values())


def figure_legend(fig: Figure, handles: Sequence[Any] | None = None) -> Legend:
    """One legend for all panels of ``fig``, under them and off every data area.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure with the constrained layout (it makes room for the legend).
    handles : sequence of artists, optional
        The entries; by default every labelled artist of the figure's axes, one
        per label.

    Returns
    -------
    matplotlib.legend.Legend
    """
    if handles is None:
        found: dict[str, Any] = {}
        for ax in fig.axes:
            for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
                found.setdefault(label, h)
        handles = list(found.values())
    handles = list(handles)
    if not handles:
        raise ValueError("figure_legend: no labelled artist to put in the legend")
    fontsize = legend_fontsize(fig)
    legend = None
    room = fig.bbox.width - 8.0
    for ncols in range(min(len(handles), 4), 0, -1):
        if legend is not None:
            legend.remove()
        legend = fig.legend(handles=handles, loc="outside lower center", ncols=ncols,
                            fontsize=fontsize, frameon=False, handlelength=2.0,
                            columnspacing=1.0, handletextpad=0.5)
        fig.draw_without_rendering()
        if legend.get_window_extent().width <= room:
            break
    return legend


def fit_labels(fig: Figure) -> None:
    """Break the titles and vertical axis labels of ``fig`` that do not fit into lines.

    The suptitle is broken at ``", "`` to the figure's width, each axes title to its
    axes' width (:func:`impactcont.plots.branches.fit_text`), and a vertical axis
    label taller than its axes at the space nearest its middle. Call it last, on a
    figure with the constrained layout, before saving.
    """
    fig.draw_without_rendering()
    if fig._suptitle is not None:
        fit_text(fig._suptitle, fig.bbox.width - 8.0)
    for ax in fig.axes:
        if ax.get_title():
            fit_text(ax.title, ax.bbox.width)
        label = ax.yaxis.label
        text = label.get_text()
        if text and "\n" not in text and label.get_window_extent().height > ax.bbox.height:
            spaces = [i for i, c in enumerate(text) if c == " " and text[:i].count("$") % 2 == 0]
            if spaces:
                cut = min(spaces, key=lambda i: abs(i - len(text) / 2))
                label.set_text(text[:cut] + "\n" + text[cut + 1:])
    fig.draw_without_rendering()


def time_history(ax_motion: Axes, ax_force: Axes, series: Iterable[Series],
                 events: dict[str, Any], *, time_scale: float = 1.0,
                 xlabel: str = "$t$", ylabel: str = "$s$",
                 force_label: str = "pressing force $p$",
                 force_entry: str = "force on stop {stop}") -> list[Any]:
    """A simulated motion with its sticking phases and complete chatter.

    Parameters
    ----------
    ax_motion : matplotlib.axes.Axes
        The motion's panel: `series` (stop coordinates, positions) against time, the
        intervals in which a stop holds shaded (:data:`HELD_COLOR`), and the accumulation
        points of complete chatter marked on the first series (black down triangles).
    ax_force : matplotlib.axes.Axes
        The contact force's panel, under the motion and sharing its time axis: the
        pressing force of each held stop (``>= 0``; a line per stop, in a colour of its
        own), zero outside the held intervals (not drawn there), the same shading.
    series : iterable of Series
        The motion's curves (times already scaled as the events will be).
    events : dict
        The flat arrays of :meth:`impactcont.simulate.simulator.SimulationResult.
        sticking_arrays` (or the same variables of a scene's ``simulations.nc``):
        ``sticking_start``, ``sticking_end``, ``force_time``, ``force`` (a dataset's
        ``contact_force``), ``force_phase``, ``force_stop`` and ``chatter_time``; any mapping
        of arrays (an :class:`xarray.Dataset` too).
    time_scale : float
        Factor applied to every time of `events` (``omega / (2 pi)``: forcing periods).
    xlabel, ylabel, force_label : str
        Axis labels (mathtext for symbols).
    force_entry : str
        The legend entry of a stop's force, ``{stop}`` replaced by the stop's name.

    Returns
    -------
    list
        The legend entries (the series, the shading, each stop's force, the
        accumulation points when there are any), for :func:`figure_legend`.

    Raises
    ------
    ValueError
        An array of `events` missing, or sticking starts and ends of different lengths.
    """
    if "force" not in events and "contact_force" in events:  # a scene's simulations.nc
        events = {k: events[k] for k in ("sticking_start", "sticking_end", "force_time",
                                         "force_phase", "force_stop", "chatter_time")
                  if k in events} | {"force": events["contact_force"]}
    need = ("sticking_start", "sticking_end", "force_time", "force", "force_phase",
            "force_stop", "chatter_time")
    missing = [k for k in need if k not in events]
    if missing:
        raise ValueError(f"events lacks {missing}: pass SimulationResult.sticking_arrays() "
                         f"(or a scene's simulations.nc variables); got keys "
                         f"{sorted(map(str, events))}")
    series = list(series)
    starts = np.asarray(events["sticking_start"], dtype=float) * time_scale
    ends = np.asarray(events["sticking_end"], dtype=float) * time_scale
    if starts.shape != ends.shape:
        raise ValueError(f"sticking_start and sticking_end must have one entry per phase; got "
                         f"{starts.size} and {ends.size}")
    series_plot(ax_motion, series, xlabel=xlabel, ylabel=ylabel)
    ax_motion.xaxis.label.set_visible(False)  # the force panel under it shows the time axis
    ax_motion.tick_params(labelbottom=False)
    handles: list[Any] = [s.handle() for s in _unique(series)]
    if starts.size:
        for ax in (ax_motion, ax_force):
            for a, b in zip(starts, ends, strict=True):
                ax.axvspan(a, b, color=HELD_COLOR, lw=0, zorder=0.5)
        from matplotlib.patches import Patch

        handles.append(Patch(color=HELD_COLOR, label="held (sticking)"))
    t_f = np.asarray(events["force_time"], dtype=float) * time_scale
    force = np.asarray(events["force"], dtype=float)
    phase = np.asarray(events["force_phase"])
    stop = np.asarray(events["force_stop"]).astype(str)
    for k, name in enumerate(dict.fromkeys(stop.tolist())):
        color = _FORCE_COLORS[k % len(_FORCE_COLORS)]
        here = stop == name
        # one curve per stop, a gap (NaN) between its phases
        pieces = [np.append(t_f[here & (phase == j)], np.nan) for j in np.unique(phase[here])]
        values = [np.append(force[here & (phase == j)], np.nan) for j in np.unique(phase[here])]
        line = Series(np.concatenate(pieces), np.concatenate(values),
                      force_entry.format(stop=name), color=color, linestyle="-")
        ax_force.plot(line.x, line.y, zorder=_LINE_ZORDER, label=line.label, **line.style())
        handles.append(line.handle())
    ax_force.set_xlabel(xlabel)
    ax_force.set_ylabel(force_label)
    ax_force.sharex(ax_motion)
    chatter = np.asarray(events["chatter_time"], dtype=float) * time_scale
    if chatter.size and series:
        first = series[0]
        order = np.argsort(first.x)
        y = np.interp(chatter, first.x[order], first.y[order])
        mark = Series(chatter, y, "accumulation point", color="black", linestyle="none",
                      marker="v", filled=True, markersize=5.0)
        ax_motion.plot(mark.x, mark.y, zorder=_LINE_ZORDER + 1, label=mark.label,
                       **mark.style())
        handles.append(mark.handle())
    logger.debug("time history: %d sticking phases, %d accumulation points", starts.size,
                 chatter.size)
    return handles

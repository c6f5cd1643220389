"""Bifurcation diagrams and multiplier plots of continued branches.

The functions read branch datasets (see :mod:`impactcont.dataset`) and never
compute orbits. They draw on the Axes given, or on a new figure, and return
the Axes; they never call ``plt.show`` so they work with any backend (Agg).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.markers import MarkerStyle

from impactcont.dataset.attributes import split_parameters
from impactcont.dataset.schema import (
    SPECIAL_LABELS,
    special_variable,
    validate_branch_dataset,
)
from impactcont.errors import ParameterError
from impactcont.plots.labels import coincident_groups, marker_boxes, merged_labels, place_labels
from impactcont.vocabulary import LABEL_MARKERS, LABEL_NAMES

__all__ = ["LEGEND_PLACES", "NONPHYSICAL_GREY", "NONPHYSICAL_MARKER", "SEGMENT_STYLES",
           "SPECIAL_MARKERS", "SPECIAL_NAMES", "WIDTH_RANGE", "Y_VARIABLES", "axis_label",
           "bifurcation_diagram", "check_width", "diagram_legend", "differing_parameters",
           "fit_text", "fixed_parameters", "label_specials", "legend_below", "legend_fontsize",
           "motion_text", "multipliers_plot", "nest_coincident_markers", "parameter_text",
           "stability_segments",
           "system_text"]

logger = logging.getLogger(__name__)

#: Line style of each kind of segment: stable and physical, unstable and
#: physical, not physical (whatever the stability).
#: Every figure of impactcont draws motions with these styles.
SEGMENT_STYLES: dict[str, dict[str, Any]] = {
    "stable": {"linestyle": "-", "linewidth": 1.6, "alpha": 1.0},
    "unstable": {"linestyle": "--", "linewidth": 1.2, "alpha": 1.0},
    "non-physical": {"linestyle": ":", "linewidth": 1.0, "alpha": 0.45},
}

#: Marker of each special-point label (defined with the labels, in the vocabulary).
SPECIAL_MARKERS: dict[str, str] = dict(LABEL_MARKERS)
#: What each special-point label stands for (legends).
SPECIAL_NAMES: dict[str, str] = dict(LABEL_NAMES)

# Symbols of the paper next to the long names on axes (mathtext).
_SYMBOLS = {"omega": r"$\omega$", "b": "$b$", "R": "$R$", "eta": r"$\eta$",
            "alpha": r"$\alpha$", "beta": r"$\beta$", "delta": r"$\delta$",
            "impact_velocity": r"$\dot{x}_1(T^-)$", "spectral_radius": r"$\rho(G)$"}
#: The widths a figure may have, in inches: a journal's column is 3.5 in, its page at most
#: 7.2 in (every figure of impactcont is drawn at most that wide).
WIDTH_RANGE = (2.0, 7.2)


def check_width(width: Any, name: str = "width") -> float:
    """``width`` (inches) as a float, refused outside :data:`WIDTH_RANGE`.

    Raises
    ------
    ParameterError
        Naming ``name``, the value and the allowed range.
    """
    lo, hi = WIDTH_RANGE
    if isinstance(width, bool) or not isinstance(width, (int, float, np.integer, np.floating)) \
            or not lo <= width <= hi:
        raise ParameterError(f"{name} must be a number of inches in [{lo:g}, {hi:g}] (3.5: a "
                             f"journal's column, 7: its page); got {width!r}")
    return float(width)


#: The branch variables a bifurcation diagram draws on its vertical axis by name (the
#: ``y`` of :func:`bifurcation_diagram`, of a scene's ``[[plots]]`` and of
#: ``impactcont plot --y``); any other real variable on ``point`` is drawn too.
Y_VARIABLES: tuple[str, ...] = ("impact_velocity", "delta", "gap_min", "spectral_radius",
                                "arclength", "omega", "b")
_OUTSIDE = {"loc": "upper left", "bbox_to_anchor": (1.02, 1.0), "borderaxespad": 0.0}

_KINDS = tuple(SEGMENT_STYLES)


def _new_axes(ncols: int = 1) -> Any:
    # pyplot so that notebooks display the figure; nothing here calls show().
    import matplotlib.pyplot as plt

    _, axes = plt.subplots(1, ncols, figsize=(5.0 * ncols, 5.0), layout="constrained")
    return axes


def _branches(datasets: Any, one_parameter: bool = False) -> list[tuple[str, xr.Dataset]]:
    """``(name, dataset)`` pairs from a Dataset, a sequence, a mapping or a DataTree.

    With `one_parameter`, the branches must all be continued in the same parameter.
    """
    if isinstance(datasets, xr.Dataset):
        items: Iterable[tuple[str, Any]] = [("", datasets)]
    elif isinstance(datasets, xr.DataTree):
        items = [(node.path.strip("/") or node.name or "", node.to_dataset(inherit=False))
                 for node in datasets.subtree if node.has_data]
    elif isinstance(datasets, Mapping):
        items = [(str(k), v) for k, v in datasets.items()]
    elif isinstance(datasets, Sequence) and not isinstance(datasets, str):
        items = [("", v) for v in datasets]
    else:
        raise TypeError(f"datasets must be a branch Dataset, a sequence or mapping of them, or "
                        f"a DataTree; got {type(datasets).__name__}")
    out = []
    for name, ds in items:
        if not isinstance(ds, xr.Dataset):
            raise TypeError(f"datasets must hold xarray.Dataset branches; got "
                            f"{type(ds).__name__} for {name!r}")
        out.append((name, validate_branch_dataset(ds)))
    if not out:
        raise ValueError("datasets holds no branch dataset")
    parameters = {ds.attrs["parameter"] for _, ds in out}
    if one_parameter and len(parameters) > 1:
        raise ValueError(f"datasets must all be continued in one parameter; got "
                         f"{sorted(parameters)}")
    return out


def stability_segments(ds: xr.Dataset) -> list[tuple[str, slice]]:
    """Split a branch into runs of one kind: stable, unstable or non-physical.

    Parameters
    ----------
    ds : xarray.Dataset
        A branch dataset.

    Returns
    -------
    list of (str, slice)
        ``(kind, points)``: each run of consecutive points of one kind, its
        slice extended by one point into the next run so the drawn segments
        join; runs never join across two connected components of the branch
        (variable ``connected_component``). ``kind`` is a key of :data:`SEGMENT_STYLES`.
    """
    physical = np.asarray(ds["physical"].values, dtype=bool)
    stable = np.asarray(ds["stable"].values, dtype=bool)
    code = np.where(~physical, 2, np.where(stable, 0, 1))
    npoints = code.size
    if npoints == 0:  # (a selection of no points: nothing to draw)
        return []
    part = (np.asarray(ds["connected_component"].values) if "connected_component" in ds
            else np.zeros(npoints, dtype=int))
    new_part = np.diff(part) != 0
    starts = np.concatenate([[0], np.flatnonzero((np.diff(code) != 0) | new_part) + 1])
    ends = np.concatenate([starts[1:], [npoints]])
    return [(_KINDS[code[s]], slice(int(s), int(e + 1 if e < npoints and not new_part[e - 1]
                                                else e)))
            for s, e in zip(starts, ends, strict=True)]


def axis_label(ds: xr.Dataset, name: str) -> str:
    """``long name symbol [units]`` of variable ``name``, e.g. ``impact phase $\\delta$ [rad]``."""
    attrs = ds[name].attrs
    text = str(attrs.get("long_name", name))
    if name in _SYMBOLS:
        text = f"{text} {_SYMBOLS[name]}"
    units = attrs.get("units")
    return f"{text} [{units}]" if units and units != "1" else text


def fixed_parameters(datasets: Sequence[xr.Dataset]) -> dict[str, float]:
    """``omega``, ``b``, ``R`` and the damping held fixed and equal along all ``datasets``.

    Read from each dataset's ``oscillator`` attribute, without the continued
    ``parameter`` of a branch (or the ``parameters`` of a curve).
    """
    values: dict[str, set[float]] = {}
    for ds in datasets:
        free = {ds.attrs.get("parameter"), *split_parameters(str(ds.attrs.get("parameters", "")))}
        osc = json.loads(ds.attrs.get("oscillator", "{}"))
        for key in ("omega", "b", "R", "eta", "alpha", "beta"):
            if key not in free and isinstance(osc.get(key), (int, float)):
                values.setdefault(key, set()).add(float(osc[key]))
            else:
                values.setdefault(key, set()).add(float("nan"))
    return {k: v.pop() for k, v in values.items() if len(v) == 1 and not np.isnan(next(iter(v)))}


def differing_parameters(groups: Sequence[Sequence[xr.Dataset]]) -> list[str]:
    """The parameters of :func:`fixed_parameters` whose values differ between ``groups``."""
    fixed = [fixed_parameters(list(g)) for g in groups]
    keys = dict.fromkeys(k for f in fixed for k in f)
    return [k for k in keys if len({f.get(k) for f in fixed}) > 1]


def _system_text(values: Mapping[str, float], keys: Iterable[str]) -> str:
    return ", ".join(f"{k} = {values[k]:g}" for k in keys if k in values)


def _y_variable(ds: xr.Dataset, y: Any) -> str:
    if not isinstance(y, str) or y not in ds.data_vars or ds[y].dims != ("point",) \
            or ds[y].dtype.kind not in "iuf":
        allowed = [k for k, v in ds.data_vars.items()
                   if v.dims == ("point",) and v.dtype.kind in "iuf"]
        raise ValueError(f"y must name a real 1-D variable on 'point'; got {y!r}; "
                         f"allowed: {allowed}")
    return y


def _special_xy(ds: xr.Dataset, x: np.ndarray, y: np.ndarray, yname: str, k: int
                ) -> tuple[float, float]:
    """Where to draw special point ``k``: on the drawn polyline, at its parameter value."""
    parameter = ds.attrs["parameter"]
    xs = float(ds[special_variable(parameter)].values[k])
    exact = special_variable(yname)
    if exact in ds.data_vars and ds[exact].dims == ("special",) and math.isfinite(
            float(ds[exact].values[k])):  # a file from before these were stored holds NaN
        return xs, float(ds[exact].values[k])
    p = int(ds[special_variable("point")].values[k])
    for i, j in ((p - 1, p), (p, p + 1)):
        if i >= 0 and j < x.size and min(x[i], x[j]) <= xs <= max(x[i], x[j]) and x[i] != x[j]:
            t = (xs - x[i]) / (x[j] - x[i])
            return xs, float(y[i] + t * (y[j] - y[i]))
    # A fold in the parameter (SN) is not bracketed in x: use the nearest point.
    return float(x[p]), float(y[p])


def _borders_physical(ds: xr.Dataset, physical: np.ndarray, k: int) -> bool:
    """Special point ``k`` lies on, or at the edge of, physical motions (GR and ZV are edges)."""
    p = int(ds[special_variable("point")].values[k])
    return bool(np.any(physical[max(p - 1, 0):p + 2]))


#: Where :func:`bifurcation_diagram` puts its legend.
LEGEND_PLACES = ("below", "right", "inside", None)
#: Grey of the special points of non-physical motions (small, unlabelled).
NONPHYSICAL_GREY = "0.6"
#: Marker of the special points of non-physical motions, whatever their kind: the legend
#: has one entry for them (their kind is no event of the machine).
NONPHYSICAL_MARKER = "o"
_MARKER_SIZE = 6.0  # points
_STACK = 10.0  # points: special points of one kind whose markers (6 pt) nearly touch share a label
_MATH = {"omega": r"\omega", "eta": r"\eta", "alpha": r"\alpha", "beta": r"\beta",
         "b_low": r"b_{low}", "R_low": r"R_{low}"}


def parameter_text(values: Mapping[str, float], keys: Iterable[str]) -> str:
    """``$b = 0.5$, $R = 0.6$, ...``: the parameters ``keys`` of ``values`` in mathtext."""
    return ", ".join(f"${_MATH.get(k, k)} = {values[k]:g}$" for k in keys if k in values)


def _stops(ds: xr.Dataset) -> dict[str, Any]:
    """The stops of a dataset's oscillator: ``{"mass": 1}`` for the paper's one stop."""
    osc = json.loads(ds.attrs.get("oscillator", "{}"))
    stops = osc.get("stops") or {}
    out = {"mass": int(stops.get("mass", 1))}
    if stops.get("b_low") is not None or stops.get("mirror"):
        out["b_low"] = float(stops["b_low"]) if stops.get("b_low") is not None \
            else float(osc.get("b", float("nan")))
        out["R_low"] = float(stops["R_low"]) if stops.get("R_low") is not None \
            else float(osc.get("R", float("nan")))
    return out


def motion_text(datasets: Sequence[xr.Dataset], *, adjective: str = "") -> str:
    """What motions ``datasets`` hold, in words: ``Period-2 motions with 1 impact``.

    An N-p motion repeats after N forcing periods with p impacts in them (``p`` the
    attribute ``impacts``, 1 for an N-1 branch); when N or p differ between the
    datasets they are written as symbols (``Period-$N$ motions with $p$ impacts``),
    never as ``N-1``, which reads as a subtraction. Between two stops, the sequence
    of stops hit follows (``U`` upper, ``L`` lower), and the stops the motion sticks on
    (its pattern's lowercase letters). ``adjective`` goes before ``motions``
    (``symmetric``).
    """
    Ns = sorted({int(ds.attrs["N"]) for ds in datasets})
    ps = sorted({int(ds.attrs.get("impacts", 1)) for ds in datasets})
    patterns = sorted({str(ds.attrs["pattern"]) for ds in datasets
                       if "pattern" in ds.attrs and "b_low" in _stops(ds)})
    n = str(Ns[0]) if len(Ns) == 1 else "$N$"
    impacts = ("1 impact" if ps == [1] else f"{ps[0]} impacts" if len(ps) == 1
               else "$p$ impacts")
    text = f"Period-{n} {adjective + ' ' if adjective else ''}motions with {impacts}"
    if len(patterns) == 1:
        pattern = patterns[0]
        text += f", impacts {pattern.upper()} (L: lower stop)"
        held = sorted({c.upper() for c in pattern if c.islower()})
        if held:  # a lowercase letter: the impact starts a sticking phase on that stop
            text += f", sticking on {' and '.join(held)}"
    return text


def system_text(datasets: Sequence[xr.Dataset], skip: Iterable[str] = ()) -> str:
    """The parameters held fixed along all ``datasets``, the stops included, in mathtext."""
    fixed = fixed_parameters(datasets)
    stops = [_stops(ds) for ds in datasets]
    for key in ("b_low", "R_low"):
        values = {s.get(key) for s in stops}
        if len(values) == 1 and None not in values:
            fixed[key] = values.pop()
    skip = set(skip)
    return parameter_text(fixed, [k for k in ("b", "b_low", "R", "R_low", "omega", "eta",
                                              "alpha", "beta") if k not in skip])


def _y_label(ds: xr.Dataset, y: str) -> str:
    """The vertical axis: the impact velocity of a two-stop branch is a speed towards the stop."""
    stops = _stops(ds)
    j = stops["mass"]
    if y == "impact_velocity" and "b_low" in stops:
        return rf"impact speed towards the stop hit $|\dot{{x}}_{j}(T^-)|$"
    if y == "impact_velocity" and j != 1:
        return rf"impact velocity $\dot{{x}}_{j}(T^-)$"
    return axis_label(ds, y)


def fit_text(text_artist: Any, width: float | None = None) -> None:
    """Break ``text_artist`` at ``, `` (and, in a part too long alone, at spaces outside
    mathtext) into lines that fit ``width`` display units.

    By default the width that keeps the text, centred where it is, inside its
    figure. Call it on a laid-out figure.
    """
    text = text_artist.get_text()
    if not text or "\n" in text:
        return
    if width is None:
        box = text_artist.get_window_extent()
        centre = 0.5 * (box.x0 + box.x1)
        width = 2.0 * min(centre, text_artist.figure.bbox.width - centre) - 4.0
    if text_artist.get_window_extent().width <= width:
        return
    def wrap(parts: list[str], sep: str) -> list[str]:
        lines = [""]
        for part in parts:
            trial = f"{lines[-1]}{sep}{part}" if lines[-1] else part
            text_artist.set_text(trial)
            if lines[-1] and text_artist.get_window_extent().width > width:
                lines[-1] += sep.rstrip()
                lines.append(part)
            else:
                lines[-1] = trial
        return lines

    lines = []
    outside_math = r"(?=(?:[^$]*\$[^$]*\$)*[^$]*$)"  # followed by whole $...$ pairs only
    for line in wrap(re.split(", " + outside_math, text), ", "):
        text_artist.set_text(line)
        if text_artist.get_window_extent().width > width:  # too long alone: break at spaces
            words = re.split(" " + outside_math, line)  # not inside $...$
            lines += wrap(words, " ")
        else:
            lines.append(line)
    text_artist.set_text("\n".join(lines))


def legend_fontsize(fig: Any) -> str:
    """``small`` on a figure of 5 in or more, ``x-small`` on a narrower one (one column)."""
    return "small" if fig.get_size_inches()[0] >= 5.0 else "x-small"


def diagram_legend(ax: Axes, kinds_seen: Any, labels_seen: Any, grey: bool,
                   branch_handles: Sequence[Any], where: str) -> None:
    """The legend of a diagram of branches: the line styles and special-point markers
    drawn, the grey marker of points on non-physical motions, then one entry per branch.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    kinds_seen, labels_seen : collection of str
        The segment kinds (:data:`SEGMENT_STYLES`) and special labels drawn.
    grey : bool
        Whether grey (non-physical) special points are drawn.
    branch_handles : sequence of artists
        One per branch, last.
    where : str
        One of :data:`LEGEND_PLACES`; ``"none"`` draws nothing.
    """
    handles = [Line2D([], [], color="0.2", label=kind, **SEGMENT_STYLES[kind])
               for kind in _KINDS if kind in kinds_seen]
    handles += [Line2D([], [], linestyle="none", marker=SPECIAL_MARKERS[label],
                       markersize=_MARKER_SIZE, markerfacecolor="white",
                       markeredgecolor="black", label=f"{label} {SPECIAL_NAMES[label]}")
                for label in SPECIAL_LABELS if label in labels_seen]
    if grey:
        handles.append(Line2D([], [], linestyle="none", marker=NONPHYSICAL_MARKER,
                              markersize=0.7 * _MARKER_SIZE, markerfacecolor="white",
                              markeredgecolor=NONPHYSICAL_GREY,
                              label="point on non-physical motion"))
    handles += list(branch_handles)
    if where == "below":
        legend_below(ax, handles)
    elif where == "right":
        ax.legend(handles=handles, fontsize="small", **_OUTSIDE)
    elif where == "inside":
        ax.legend(handles=handles, fontsize="x-small", loc="best")


def legend_below(ax: Axes, handles: Sequence[Any], *, fontsize: Any = None,
                 span: str = "figure") -> Any:
    """A legend under the axis labels of ``ax``, in as many columns as its width allows.

    The offset under the axes is in inches (the height of the tick labels and
    the axis label), so it holds wherever a constrained layout moves the axes.
    ``span="figure"``: as wide as the figure allows around the axes' centre;
    ``"axes"``: no wider than the axes (side-by-side panels).
    """
    from matplotlib.transforms import ScaledTranslation, blended_transform_factory

    fig = ax.figure
    fontsize = fontsize or legend_fontsize(fig)
    fig.draw_without_rendering()
    below = (ax.get_window_extent().y0 - ax.xaxis.get_tightbbox().y0) / fig.dpi + 0.04
    shift = ax.transAxes + ScaledTranslation(0.0, -below, fig.dpi_scale_trans)
    if span == "axes":
        room = ax.get_window_extent().width
    else:  # centred on the figure, as wide as the figure
        shift = blended_transform_factory(fig.transFigure, shift)
        room = fig.bbox.width - 8.0
    narrow = fig.get_size_inches()[0] < 5.0
    legend = None
    for ncols in range(min(len(handles), 6), 0, -1):
        legend = ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
                           bbox_transform=shift, ncols=ncols, fontsize=fontsize,
                           frameon=False, handlelength=1.8 if narrow else 2.4,
                           columnspacing=0.8 if narrow else 1.2, handletextpad=0.5,
                           borderaxespad=0.0)
        if legend.get_window_extent().width <= room:
            break
    return legend


def _y_range(values: np.ndarray) -> tuple[float, float, float]:
    lo, hi = float(values.min()), float(values.max())
    pad = 0.08 * (hi - lo) if hi > lo else 0.1 * max(abs(hi), 1.0)
    return lo - pad, hi + pad, pad


def _inset_place(ax: Axes, cluster: np.ndarray, size: tuple[float, float]
                 ) -> list[float] | None:
    """Axes-fraction rectangle of an inset that covers the fewest curves, never the cluster."""
    to_axes = ax.transData + ax.transAxes.inverted()
    parts = [np.asarray(line.get_xydata(), dtype=float) for line in ax.get_lines()
             if line.get_visible() and len(line.get_xydata())]
    parts += [np.asarray(c.get_offsets(), dtype=float) for c in ax.collections
              if c.get_visible() and len(c.get_offsets())]  # scattered points too
    xy = to_axes.transform(np.vstack(parts)) if parts else np.empty((0, 2))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    c = to_axes.transform(cluster)
    w, h = size
    best = None
    for x0 in (0.02, 0.5 - w / 2, 0.98 - w):
        for y0 in (0.98 - h, 0.02, 0.5 - h / 2):
            box = (x0 - 0.02, y0 - 0.02, x0 + w + 0.02, y0 + h + 0.02)

            def inside(p: np.ndarray, box: tuple[float, ...] = box) -> np.ndarray:
                return ((p[:, 0] > box[0]) & (p[:, 0] < box[2]) & (p[:, 1] > box[1])
                        & (p[:, 1] < box[3]))

            if np.any(inside(c)):
                continue
            score = int(np.count_nonzero(inside(xy)))
            if best is None or score < best[0]:
                best = (score, [x0, y0, w, h])
    return None if best is None else best[1]


def _zoom(ax: Axes, points: np.ndarray) -> Axes | None:
    """An inset of ``ax`` showing the data points ``points`` apart, or None if none fits."""
    to_axes = ax.transData + ax.transAxes.inverted()
    frac = to_axes.transform(points)
    (x0, y0), (x1, y1) = frac.min(axis=0), frac.max(axis=0)
    dx, dy = max(x1 - x0, 0.01), max(y1 - y0, 0.05)
    corners = to_axes.inverted().transform([(x0 - 0.25 * dx, y0 - 0.3 * dy),
                                            (x1 + 0.25 * dx, y1 + 0.3 * dy)])
    place = _inset_place(ax, points, (0.4, 0.42))
    if place is None:
        return None
    inset = ax.inset_axes(place)
    inset.set_xscale(ax.get_xscale())
    inset.set_yscale(ax.get_yscale())
    xlim, ylim = tuple(corners[:, 0]), tuple(corners[:, 1])
    for line in ax.get_lines():
        xy = np.asarray(line.get_xydata(), dtype=float)
        if line.get_linestyle() in ("None", "none", " ", ""):  # a marker: inside, or not at all
            f = (to_axes.transform(xy) - [x0 - 0.25 * dx, y0 - 0.3 * dy]) \
                / [1.5 * dx, 1.6 * dy]
            xy = xy[np.all((f >= 0.08) & (f <= 0.92), axis=1)]
            if not len(xy):
                continue
        copy = Line2D(*xy.T)
        copy.update_from(line)
        copy.set_transform(inset.transData)
        inset.add_line(copy)
    inset.set_xlim(*xlim)
    inset.set_ylim(*ylim)
    inset.tick_params(labelsize="x-small", length=2, pad=1.5)
    from matplotlib.ticker import MaxNLocator, NullFormatter

    for axis in (inset.xaxis, inset.yaxis):
        if axis.get_scale() == "linear":
            axis.set_major_locator(MaxNLocator(3))
        else:
            axis.set_minor_formatter(NullFormatter())
    inset.set_facecolor("white")
    inset.set_zorder(5)
    ax.indicate_inset_zoom(inset, edgecolor="0.35", linewidth=0.8)
    return inset


def _label_points(ax: Axes, specials: Sequence[tuple[float, float, str]], *,
                  fontsize: Any = "small", avoid: Sequence[Any] = ()) -> None:
    """One label per cluster: a stack of points of one kind within a label's size is named
    once with its count (``PD ×10``), points of several kinds at one place share a label
    (``SN, GR``)."""
    if not specials:
        return
    ax.figure.draw_without_rendering()
    where: list[tuple[float, float]] = []
    texts: list[str] = []
    for label in dict.fromkeys(lab for _, _, lab in specials):
        own = [(px, py) for px, py, lab in specials if lab == label]
        w, t = merged_labels(ax, own, [label] * len(own), distance=_STACK)
        where += w
        texts += t
    # one place (markers overlapping, 8 points): one label for every kind there
    where, texts = merged_labels(ax, where, texts, distance=8.0, chain=False)
    # every marker is an obstacle: a merged label names one point of its stack
    place_labels(ax, where, texts, fontsize=fontsize, avoid=[*avoid, *marker_boxes(ax)])


def _zoom_group(ax: Axes, xy: np.ndarray, inset_size: tuple[float, float] = (0.4, 0.42),
                magnify: float = 3.0) -> np.ndarray:
    """Indices of the crowded points of ``xy`` that an inset should show apart, or empty.

    Points chained within a label's size (16 points on the page) crowd each
    other; the chain is cut at ever smaller distances (a cluster inside a
    cluster) until its largest group of three or more points fits an inset of
    ``inset_size`` (axes fractions) ``magnify`` times larger than on the axes.
    """
    room = np.asarray(inset_size)  # in axes fractions, whatever the scales
    floor = np.array([0.01, 0.05])
    frac = (ax.transData + ax.transAxes.inverted()).transform(xy)
    for distance in (16.0, 8.0, 4.0, 2.0):
        groups = [g for g in coincident_groups(ax, [tuple(p) for p in xy], distance=distance)
                  if len(g) >= 3]
        if not groups:
            return np.empty(0, dtype=int)
        group = np.array(max(groups, key=len), dtype=int)
        span = np.maximum(np.ptp(frac[group], axis=0), floor) * np.array([1.5, 1.6])
        if np.min(room / span) >= magnify:
            return group
    return np.empty(0, dtype=int)


def nest_coincident_markers(ax: Axes, shrink: float = 0.7) -> None:
    """Draw special-point markers at one place as one combined marker.

    Markers of special points (and the grey circles of those off physical motions)
    closer on the page than a third of the smaller one are one place: drawn alike in
    size, the later one hid the earlier (the ZV points of N = 1 and N = 3 of the paper's
    system at b = 0.5, omega = 1.213462, v = 0). Each later one is drawn ``shrink`` times
    smaller than the smallest marker already there, inside it, so that every one stays
    in view. Lays the figure out; call it once the markers are drawn.
    """
    if not 0.0 < shrink < 1.0:
        raise ValueError(f"shrink must be in (0, 1); got {shrink!r}")
    ax.figure.draw_without_rendering()
    names = {str(MarkerStyle(m).get_marker())
             for m in (*SPECIAL_MARKERS.values(), NONPHYSICAL_MARKER)}
    scale = 72.0 / ax.figure.dpi
    placed: list[tuple[np.ndarray, float]] = []  # (centre in points, marker size) so far
    for line in list(ax.get_lines()):
        if str(line.get_marker()) not in names \
                or line.get_linestyle() not in ("None", "none", " ", ""):
            continue
        xy = np.asarray(line.get_xydata(), dtype=float)
        keep = np.ones(len(xy), dtype=bool)
        size = line.get_markersize()
        for k, p in enumerate(ax.transData.transform(xy) * scale):
            if not np.all(np.isfinite(p)):
                continue
            near = [s for c, s in placed if np.hypot(*(p - c)) < min(s, size) / 3.0]
            if not near or size <= shrink * min(near) + 1e-9:  # alone, or inside already
                placed.append((p, size))
                continue
            keep[k] = False
            small = shrink * min(near)
            ax.plot(*xy[k], linestyle="none", marker=line.get_marker(), markersize=small,
                    markeredgecolor=line.get_markeredgecolor(),
                    markerfacecolor=line.get_markerfacecolor(),
                    markeredgewidth=line.get_markeredgewidth() * shrink,
                    zorder=line.get_zorder(), clip_on=line.get_clip_on())
            placed.append((p, small))
        if not keep.all():
            line.set_data(xy[keep, 0], xy[keep, 1])


def label_specials(ax: Axes, specials: Sequence[tuple[float, float, str]], *,
                   zoom: bool = True, fontsize: Any = "small") -> Axes | None:
    """Label the special points ``(x, y, label)`` of ``ax``; crowded ones in a zoomed inset.

    Call it last, once everything else is drawn. Returns the inset, if one was drawn.
    ``fontsize`` is that of the labels on ``ax`` (the inset's are ``x-small``).
    """
    labelled = list(specials)
    nest_coincident_markers(ax)  # lays the figure out
    crowd = (_zoom_group(ax, np.array([(px, py) for px, py, _ in labelled]))
             if zoom and labelled else np.empty(0, dtype=int))
    if len({labelled[i][2] for i in crowd}) == 1:  # a stack of one kind: one label says it
        crowd = np.empty(0, dtype=int)
    inset = _zoom(ax, np.array([labelled[i][:2] for i in crowd])) if crowd.size else None
    avoid = []
    if inset is not None:
        _label_points(inset, [labelled[i] for i in crowd], fontsize="x-small")
        ax.figure.draw_without_rendering()
        avoid = [inset.get_tightbbox()]
        labelled = [s for i, s in enumerate(labelled) if i not in set(crowd.tolist())]
    _label_points(ax, labelled, avoid=avoid, fontsize=fontsize)
    return inset


@dataclasses.dataclass
class _Drawing:
    """A diagram of branches being drawn: its axes and branches, and what the branches drew
    so far, for the vertical range, the markers, the legend and the labels."""

    ax: Axes
    branches: list[tuple[str, xr.Dataset]]
    differing: list[str]  # the parameters whose values differ between the branches
    kinds_seen: set[str] = dataclasses.field(default_factory=set)
    branch_handles: list[Any] = dataclasses.field(default_factory=list)
    #: x, y, label, colour, whether on (or at the edge of) a physical motion
    specials: list[tuple[float, float, str, str, bool]] = dataclasses.field(default_factory=list)
    seen: list[np.ndarray] = dataclasses.field(default_factory=list)  # values of physical motions

    def draw_curves(self, ds: xr.Dataset, x: np.ndarray, values: np.ndarray, color: str,
                    nonphysical: bool = True) -> tuple[bool, np.ndarray]:
        """Draw ``values`` of the branch ``ds`` against ``x``, split and styled by kind of
        segment (:func:`stability_segments`; the non-physical ones only with
        ``nonphysical``), and keep the values of its physical motions.

        Returns whether anything was drawn, and the branch's ``physical`` column.
        """
        drawn = False
        for kind, sl in stability_segments(ds):
            if kind == "non-physical" and not nonphysical:
                continue
            self.ax.plot(x[sl], values[sl], color=color, **SEGMENT_STYLES[kind])
            self.kinds_seen.add(kind)
            drawn = True
        physical = np.asarray(ds["physical"].values, dtype=bool)
        self.seen.append(values[physical].ravel())
        return drawn, physical


def _start_diagram(datasets: Any, ax: Axes | None, legend: str | None) -> _Drawing:
    """Check ``legend`` and the branches (all continued in one parameter), and the axes."""
    if legend not in LEGEND_PLACES:
        raise ValueError(f"legend must be one of {LEGEND_PLACES}; got {legend!r}")
    branches = _branches(datasets, one_parameter=True)
    if ax is None:
        ax = _new_axes()
    return _Drawing(ax, branches, differing_parameters([[ds] for _, ds in branches]))


def _mark_specials(drawing: _Drawing, physical_range: bool) -> tuple[list[str], bool]:
    """Fit the vertical range and draw the special points (:func:`bifurcation_diagram`).

    With ``physical_range`` the range fits the physical motions and their special points,
    and a point off physical motions is drawn only inside it (never cut by the frame).
    Returns the labels drawn on physical motions, in the order of :data:`SPECIAL_LABELS`,
    and whether a point off physical motions (small, grey, any label) is drawn.
    """
    ax, specials = drawing.ax, drawing.specials
    values = np.concatenate([*drawing.seen, [s[1] for s in specials if s[4]]])
    values = values[np.isfinite(values)]
    lo = hi = pad = None
    if physical_range and values.size:
        lo, hi, pad = _y_range(values)
        ax.set_ylim(lo, hi)
    labels = []
    grey = False
    for label in SPECIAL_LABELS:
        for shown in (True, False):
            pts = [(px, py, c) for px, py, lab, c, keep in specials
                   if lab == label and keep == shown]
            if not shown and lo is not None:  # never cut by the frame: inside or not drawn
                pts = [q for q in pts if lo + 0.5 * pad <= q[1] <= hi - 0.5 * pad]
            for px, py, c in pts:  # off physical motions: one small grey circle, any kind
                ax.plot([px], [py], linestyle="none",
                        marker=SPECIAL_MARKERS[label] if shown else NONPHYSICAL_MARKER,
                        markersize=_MARKER_SIZE if shown else 0.7 * _MARKER_SIZE,
                        markerfacecolor="white", markeredgewidth=1.2 if shown else 0.8,
                        markeredgecolor=c if shown else NONPHYSICAL_GREY, zorder=3)
            if pts and shown:
                labels.append(label)
            grey |= bool(pts) and not shown
    return labels, grey


def _finish_diagram(drawing: _Drawing, ylabel: str, *, physical_range: bool,
                    legend: str | None, title: str | None, label_special: bool, zoom: bool,
                    nest: bool) -> None:
    """Draw the special points, name the axes, add the legend and the title, label the
    special points on physical motions (last: the labels keep clear of everything else).

    ``title=None``: the motions and the system drawn (:func:`motion_text`,
    :func:`system_text`); ``nest``: nest coincident markers even when unlabelled
    (:func:`nest_coincident_markers`; labelling nests them).
    """
    ax = drawing.ax
    labels_seen, grey = _mark_specials(drawing, physical_range)
    labelled = [s[:3] for s in drawing.specials if s[4]] if label_special else []
    if nest and not labelled:
        nest_coincident_markers(ax)
    datasets = [ds for _, ds in drawing.branches]
    parameter = datasets[0].attrs["parameter"]
    ax.set_xlabel(axis_label(datasets[0], parameter))
    ax.set_ylabel(ylabel)
    diagram_legend(ax, drawing.kinds_seen, labels_seen, grey, drawing.branch_handles, legend)
    if title is None:
        where = system_text(datasets, skip={parameter})
        title = motion_text(datasets) + (f", {where}" if where else "")
    if title:
        ax.set_title(title, fontsize="medium")
        ax.figure.draw_without_rendering()
        fit_text(ax.title)
    if labelled:
        label_specials(ax, labelled, zoom=zoom)


def bifurcation_diagram(datasets: Any, *, y: str = "impact_velocity", ax: Axes | None = None,
                        label_special: bool = True, title: str | None = None,
                        physical_range: bool = True, legend: str | None = "below",
                        zoom: bool = True) -> Axes:
    """Draw branches against their continued parameter, styled by stability.

    Stable physical motions are solid, unstable physical ones dashed and
    non-physical ones faint and dotted (:data:`SEGMENT_STYLES`); the line is
    split wherever the kind changes. Each branch has its colour, named in the
    legend with its N (and the parameters that differ, if the branches belong
    to different systems: draw those on separate axes for a clear figure).
    Special points get one marker per label (:data:`SPECIAL_MARKERS`), drawn
    in the colour of their branch, and optionally a text label placed clear of
    the others and of the curves (points closer than a marker share one label,
    ``SN, GR``); those of non-physical motions (not even at the edge of a
    physical one) are small grey circles (:data:`NONPHYSICAL_GREY`,
    :data:`NONPHYSICAL_MARKER`), one legend entry for all kinds, unlabelled.
    Three or more special points crowded within a label's size get a zoomed
    inset, placed where it hides the fewest curves, with their labels.

    Parameters
    ----------
    datasets : Dataset, sequence or mapping of Datasets, or DataTree
        Branch datasets, all continued in the same parameter.
    y : str, optional
        Name of a real variable on ``point`` (``impact_velocity``, ``delta``,
        ``gap_min``, ``spectral_radius``, ...).
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default. With ``legend="below"``
        its figure should use the constrained layout (the default figure does).
    label_special : bool, optional
        Write each special point's label next to its marker.
    title : str, optional
        Axes title; by default the motions and the system drawn
        (``Period-$N$ motions with 1 impact, b = 0.5, R = 0.6, eta = 0.1``), ``""`` for none.
    physical_range : bool, optional
        Fit the vertical range to the physical motions (default), clipping
        non-physical ones at the frame; False fits everything drawn.
    legend : {"below", "right", "inside", None}, optional
        Under the axes (default: the axes keep the figure's width), outside on
        the right, inside the axes (``loc="best"``), or none.
    zoom : bool, optional
        Draw crowded special points again in an inset.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``, or the new figure's; the zoomed inset, if one was drawn, is its child
        axes (``ax.child_axes``).

    Raises
    ------
    ValueError
        ``y`` or ``legend`` is not allowed, or the branches are continued in
        different parameters.
    """
    drawing = _start_diagram(datasets, ax, legend)
    ax, branches, differing = drawing.ax, drawing.branches, drawing.differing
    counts = {int(ds.attrs["N"]) for _, ds in branches}
    for b, (name, ds) in enumerate(branches):
        yname = _y_variable(ds, y)
        parameter = ds.attrs["parameter"]
        x = np.asarray(ds[parameter].values, dtype=float)
        yv = np.asarray(ds[yname].values, dtype=float)
        color = f"C{b % 10}"
        _, physical = drawing.draw_curves(ds, x, yv, color)
        p = int(ds.attrs.get("impacts", 1))
        about = ", ".join([f"N = {int(ds.attrs['N'])}" if p == 1
                           else f"{int(ds.attrs['N'])}-{p}",
                           *([_system_text(fixed_parameters([ds]), differing)]
                             if differing else [])])
        unique = len(counts) == len(branches) and not differing
        drawing.branch_handles.append(Line2D([], [], color=color, linewidth=1.6,
                                     label=f"{name} ({about})" if name and not unique
                                     else about))
        labels = np.asarray(ds[special_variable("label")].values).tolist()
        for k, label in enumerate(labels):
            px, py = _special_xy(ds, x, yv, yname, k)
            drawing.specials.append((px, py, str(label), color, _borders_physical(ds, physical, k)))
    _finish_diagram(drawing, _y_label(branches[0][1], y), physical_range=physical_range,
                    legend=legend, title=title, label_special=label_special, zoom=zoom,
                    nest=True)
    logger.debug("bifurcation diagram: %d branch(es), y=%s", len(branches), y)
    return ax


def multipliers_plot(ds: xr.Dataset, *, ax: Sequence[Axes] | None = None,
                     yscale: str = "auto", label_special: bool = True
                     ) -> tuple[Axes, Axes]:
    """Multipliers of a branch: moduli against the parameter, and the complex plane.

    Left: ``|multipliers|`` of every point (dots coloured by the parameter),
    the spectral radius (line) with the special points on it
    (:data:`SPECIAL_MARKERS`, labelled) and the stability boundary
    ``|mu| = 1``. Right: the multipliers in the complex plane with the unit
    circle, coloured by the parameter, the special points' multipliers marked.
    One legend, under the left panel, names every mark.

    Parameters
    ----------
    ds : xarray.Dataset
        One branch dataset.
    ax : pair of matplotlib.axes.Axes, optional
        Where to draw; a new figure with two panels by default.
    yscale : {"auto", "linear", "log"}, optional
        Scale of the moduli axis; ``auto`` is logarithmic when the largest
        modulus exceeds ten times the larger of 1 and the median modulus (a
        spike near a zero-velocity impact would flatten the rest).
    label_special : bool, optional
        Write each special point's label beside its marker on the left.

    Returns
    -------
    (Axes, Axes)
        The moduli panel and the complex-plane panel.
    """
    validate_branch_dataset(ds)
    if yscale not in ("auto", "linear", "log"):
        raise ValueError(f"yscale must be 'auto', 'linear' or 'log'; got {yscale!r}")
    if ax is None:
        ax_abs, ax_c = _new_axes(2)
    else:
        if isinstance(ax, Axes) or not isinstance(ax, Sequence) or len(ax) != 2 \
                or not all(isinstance(a, Axes) for a in ax):
            raise TypeError(f"ax must be a pair of matplotlib Axes; got {ax!r}")
        ax_abs, ax_c = ax
    parameter = ds.attrs["parameter"]
    x = np.asarray(ds[parameter].values, dtype=float)
    mult = np.asarray(ds["multipliers"].values, dtype=complex)
    moduli_all = np.abs(mult)
    finite = moduli_all[np.isfinite(moduli_all)]
    if yscale == "auto":
        yscale = ("log" if finite.size and finite.max() > 10.0 * max(1.0, np.median(finite))
                  else "linear")
    xx = np.broadcast_to(x[:, None], mult.shape).ravel()
    norm_range = (float(np.min(x)), float(np.max(x)))
    common = {"c": xx, "cmap": "viridis", "vmin": norm_range[0], "vmax": norm_range[1],
              "s": 5, "linewidths": 0}
    shown = moduli_all.ravel() > 0 if yscale == "log" else np.ones(moduli_all.size, bool)
    ax_abs.scatter(xx[shown], moduli_all.ravel()[shown],
                   **{**common, "c": xx[shown]})
    # one line per connected component of the branch, never a chord between two
    rho = np.asarray(ds["spectral_radius"].values, dtype=float)
    xr_, rho_ = x, rho
    if "connected_component" in ds:
        cut = np.flatnonzero(np.diff(np.asarray(ds["connected_component"].values)) != 0) + 1
        xr_, rho_ = np.insert(x, cut, np.nan), np.insert(rho, cut, np.nan)
    ax_abs.plot(xr_, rho_, color="black", linewidth=1.0)
    circle = {"color": "0.4", "linestyle": "--", "linewidth": 1.0}
    ax_abs.axhline(1.0, **circle)
    ax_abs.set_yscale(yscale)
    ax_abs.set_xlabel(axis_label(ds, parameter))
    ax_abs.set_ylabel(r"multiplier moduli $|\mu|$")

    theta = np.linspace(0.0, 2.0 * np.pi, 361)
    ax_c.plot(np.cos(theta), np.sin(theta), **circle)
    moduli = np.abs(mult[np.isfinite(mult)])
    reach = max(1.25, float(np.percentile(moduli, 95)) * 1.05) if moduli.size else 1.25
    inside = np.abs(mult) <= reach  # what the note says is not shown is not drawn
    sc = ax_c.scatter(mult.real[inside], mult.imag[inside],
                      **{**common, "c": np.asarray(common["c"]).ravel()[inside.ravel()]})
    labels = np.asarray(ds[special_variable("label")].values).tolist()
    smult = np.asarray(ds[special_variable("multipliers")].values, dtype=complex)
    sx = np.asarray(ds[special_variable(parameter)].values, dtype=float)
    seen: list[str] = []
    on_rho: list[tuple[float, float, str]] = []
    for label in SPECIAL_LABELS:
        ks = [k for k, lab in enumerate(labels) if lab == label]
        if not ks:
            continue
        seen.append(label)
        m = smult[ks].ravel()
        m = m[np.isfinite(m) & (np.abs(m.real) < 0.95 * reach) & (np.abs(m.imag) < 0.95 * reach)]
        ax_c.plot(m.real, m.imag, linestyle="none", marker=SPECIAL_MARKERS[label],
                  markersize=_MARKER_SIZE, markerfacecolor="none", markeredgecolor="black",
                  markeredgewidth=1.0, zorder=3)
        for k in ks:  # on the drawn spectral radius (a ZV point's own multipliers are a pole)
            r = _special_xy(ds, x, rho, "spectral_radius", k)[1]
            on_rho.append((float(sx[k]), r, label))
            ax_abs.plot([sx[k]], [r], linestyle="none", marker=SPECIAL_MARKERS[label],
                        # open, as on the right: the modulus under it stays in view
                        markersize=_MARKER_SIZE, markerfacecolor="none",
                        markeredgecolor="black", markeredgewidth=1.0, zorder=3)
    # near a ZV point G has a pole (multipliers ~ 1/h2): frame the bulk, say what is cut
    ax_c.set_xlim(-reach, reach)
    ax_c.set_ylim(-reach, reach)
    ax_c.set_aspect("equal", adjustable="box")
    if moduli.size and (moduli.max() > reach or np.any(np.abs(smult) > reach)):
        ax_c.set_title(rf"$|\mu| > {reach:.3g}$ not shown", fontsize="small", loc="left")
    ax_c.set_xlabel(r"Re $\mu$")
    ax_c.set_ylabel(r"Im $\mu$")
    ax_c.figure.colorbar(sc, ax=ax_c, label=axis_label(ds, parameter))
    handles = [Line2D([], [], color="black", linewidth=1.0, label="spectral radius"),
               Line2D([], [], label=r"$|\mu| = 1$", **circle)]
    handles += [Line2D([], [], linestyle="none", marker=SPECIAL_MARKERS[label],
                       markersize=_MARKER_SIZE, markerfacecolor="none",
                       markeredgecolor="black", label=f"{label} {SPECIAL_NAMES[label]}")
                for label in seen]
    legend_below(ax_abs, handles, span="axes")
    if label_special and on_rho:
        label_specials(ax_abs, on_rho)
    logger.debug("multipliers plot: %d points", x.size)
    return ax_abs, ax_c

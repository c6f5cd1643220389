"""Two-parameter diagrams: map regions shaded, continued curves drawn on top.

Every map :func:`impactcont.stability_map` returns is drawn here: the N-1 map of an
oscillator (:func:`two_parameter_diagram`, :func:`two_parameter_figure`: regions per N,
the curves of :func:`impactcont.analysis.curves.curve` on top) and the map of one N-p
motion family (:func:`multi_impact_map_diagram`, which :func:`two_parameter_diagram` draws
too: regions of the family, their boundaries and the seed). The functions read the
datasets only; they never compute orbits and never call ``plt.show``.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from impactcont.dataset.attributes import dataset_tag, split_parameters
from impactcont.dataset.curves import codim2_variable, kind_of_curve, validate_any_curve
from impactcont.dataset.maps import (
    MAP_REASONS,
    map_parameters,
    validate_map_dataset,
    validate_multi_impact_map_dataset,
)
from impactcont.plots.branches import (
    _SYMBOLS,
    SPECIAL_NAMES,
    _stops,
    axis_label,
    check_width,
    fit_text,
    legend_below,
    legend_fontsize,
    motion_text,
    parameter_text,
    system_text,
)
from impactcont.plots.labels import marker_boxes, merged_labels, place_labels
from impactcont.vocabulary import Label, check_positive_integer

__all__ = ["CODIM2_NAMES", "CODIM2_STYLES", "CURVE_PARTS", "CURVE_STYLES",
           "MULTI_MAP_BOUNDARIES", "MULTI_MAP_REGIONS", "REGIONS", "codim2_legend",
           "codim2_name", "multi_impact_map_diagram", "multi_map_regions", "multi_map_title",
           "region_codes", "two_parameter_diagram", "two_parameter_figure"]

logger = logging.getLogger(__name__)

#: Colour of each kind of curve (the line style says what crossing it changes:
#: :data:`CURVE_PARTS`): the kind's own (:attr:`~impactcont.vocabulary.Label.colour`).
CURVE_STYLES: dict[str, dict[str, Any]] = {kind.value: {"color": kind.colour} for kind in Label}

#: Line style of each part of a curve, as the legend names it: bold where
#: crossing it changes an observable stable motion (``stable_side``), thin where
#: the motion is physical but unstable on both sides, faint and dotted where it
#: is not physical.
CURVE_PARTS: dict[str, dict[str, Any]] = {
    "a stable motion changes across it": {"linestyle": "-", "linewidth": 2.2, "alpha": 1.0},
    "physical, no stable motion changes": {"linestyle": "-", "linewidth": 1.0, "alpha": 1.0},
    "not physical": {"linestyle": ":", "linewidth": 0.8, "alpha": 0.6},
}

#: Marker of the codim-2 points on physical motions and on non-physical ones.
CODIM2_STYLES: dict[str, dict[str, Any]] = {
    "codim-2 point": {"marker": "*", "markersize": 10.0, "markerfacecolor": "gold",
                      "markeredgecolor": "black", "markeredgewidth": 0.6},
    "codim-2 point on non-physical motion": {"marker": "*", "markersize": 6.0,
                                             "markerfacecolor": "0.6",
                                             "markeredgecolor": "0.6",
                                             "markeredgewidth": 0.6},
}

#: The standard abbreviation of each smooth codim-2 point of a limit cycle (MatCont's
#: names, the Poincare map being the impact map G here) by the label the curves record,
#: and what it stands for. ``A+B`` and ``B+A`` are one point found from either curve;
#: ``SN+SN`` and ``PD+PD`` are the labels of files written before ``R1`` and ``R2``.
#: The points where a curve meets the grazing (GR) or zero-velocity (ZV) boundary are
#: bifurcations of non-smooth systems without a standard name: they keep their label
#: (``PD+GR``: the PD curve meets the GR curve); see ``docs/two_parameter.md``.
CODIM2_NAMES: dict[str, tuple[str, str]] = {
    "SN+PD": ("LPPD", "fold-flip"), "PD+SN": ("LPPD", "fold-flip"),
    "SN+NS": ("LPNS", "fold-Neimark-Sacker"), "NS+SN": ("LPNS", "fold-Neimark-Sacker"),
    "PD+NS": ("PDNS", "flip-Neimark-Sacker"), "NS+PD": ("PDNS", "flip-Neimark-Sacker"),
    "NS+NS": ("NSNS", "double Neimark-Sacker"),
    "R1": ("R1", "1:1 resonance"), "SN+SN": ("R1", "1:1 resonance"),
    "R2": ("R2", "1:2 resonance"), "PD+PD": ("R2", "1:2 resonance"),
    "R3": ("R3", "1:3 resonance"), "R4": ("R4", "1:4 resonance"),
    "CP": ("CP", "cusp"), "CPC": ("CPC", "cusp of cycles"),
    "GPD": ("GPD", "generalized period doubling"), "CH": ("CH", "Chenciner"),
}


def codim2_name(label: str) -> str:
    """What a figure writes for a codim-2 point: its standard abbreviation
    (:data:`CODIM2_NAMES`: ``PD+SN`` -> ``LPPD``) or, for a non-smooth point without
    one, its label (``PD+GR``)."""
    return CODIM2_NAMES.get(str(label), (str(label), ""))[0]


def codim2_legend(labels: Iterable[str]) -> str:
    """The legend text of the codim-2 marks drawn with these labels, one line each: the
    standard names spelled out, and what ``A+B`` means for the non-smooth points
    without one."""
    names = dict.fromkeys(CODIM2_NAMES[lab] for lab in labels if lab in CODIM2_NAMES)
    parts = [f"{abbr} {words}" for abbr, words in names]
    if any(lab not in CODIM2_NAMES for lab in labels):
        parts.append("A+B: curves A, B meet (no standard name)")
    return "\n".join(parts)


_STAR = 5.0  # half-size of a codim-2 star, in points

#: Region codes of :func:`region_codes`, with their legend text and shade.
REGIONS: dict[int, tuple[str, str]] = {
    0: ("no such motion", "#ffffff"),
    1: ("motions exist, none physical", "#e4e4e4"),
    2: ("physical, unstable", "#f6d7a7"),
    3: ("stable physical motion", "#8fc4e8"),
}


def region_codes(map_ds: xr.Dataset, N: int) -> xr.DataArray:
    """Region of every grid point for one N.

    Returns
    -------
    xarray.DataArray of int, dims the map's two parameters ((omega, b) by default)
        0: no motion (``c^2 + s^2 < b^2``); 1: motions exist, none physical;
        2: a physical motion, none stable; 3: a stable physical motion.
    """
    validate_map_dataset(map_ds)
    if N not in map_ds["N"].values:
        raise ValueError(f"N must be one of the map's {map_ds['N'].values.tolist()}; got {N!r}")
    m = map_ds.sel(N=N)
    code = xr.where(m["n_stable"] > 0, 3, xr.where(m["n_physical"] > 0, 2,
                                                   xr.where(m["exists"], 1, 0)))
    return code.rename("region")


def _curves(curves: Any) -> list[xr.Dataset]:
    if curves is None:
        return []
    if isinstance(curves, xr.Dataset):
        items: Iterable[Any] = [curves]
    elif isinstance(curves, xr.DataTree):
        items = [node.to_dataset(inherit=False) for node in curves.subtree if node.has_data]
    elif isinstance(curves, Mapping):
        items = curves.values()
    elif isinstance(curves, Sequence) and not isinstance(curves, str):
        items = curves
    else:
        raise TypeError(f"curves must be a curve Dataset, a sequence or mapping of them or a "
                        f"DataTree; got {type(curves).__name__}")
    return [validate_any_curve(c) for c in items]


def _segments(mask: np.ndarray) -> list[slice]:
    """Runs of True in ``mask`` (each extended by one point to join the next run)."""
    out, start = [], None
    for i, flag in enumerate(mask):
        if flag and start is None:
            start = i
        if not flag and start is not None:
            out.append(slice(start, min(i + 1, mask.size)))
            start = None
    if start is not None:
        out.append(slice(start, mask.size))
    return out


def _system(map_ds: xr.Dataset | None, curve_list: Sequence[xr.Dataset],
            plane: tuple[str, str] = ("omega", "b")) -> str:
    """The parameters held fixed on the `plane`, in mathtext (``$R = 0.6$, ...``)."""
    datasets = ([map_ds] if map_ds is not None else []) + list(curve_list)
    return system_text(datasets, skip=set(plane))


def _plane(map_ds: xr.Dataset | None, curve_list: Sequence[xr.Dataset]) -> tuple[str, str]:
    """The two parameters drawn, x then y: the map's (its attribute ``parameters``, else
    omega and b), else the first curve's (omega across, b up when they are omega and b)."""
    if map_ds is not None:
        return map_parameters(map_ds)
    px, py = split_parameters(str(curve_list[0].attrs["parameters"]))
    return ("omega", "b") if {px, py} == {"omega", "b"} else (px, py)


def _plane_symbols(plane: tuple[str, str]) -> str:
    """``$(\\omega, b)$``: the plane in mathtext (a name without a symbol as it is)."""
    return "(" + ", ".join(_SYMBOLS.get(name, name) for name in plane) + ")"


def _panel(ax: Axes, map_ds: xr.Dataset | None, curve_list: Sequence[xr.Dataset], N: int,
           label_curves: bool) -> tuple[list[Any], list[tuple[float, float, str, str]]]:
    """Draw one N on ``ax``: its legend handles, and its labels ``(x, y, text, colour)``."""
    handles: list[Any] = []
    first, second = _plane(map_ds, curve_list)
    if map_ds is not None:
        code = region_codes(map_ds, N).transpose(first, second)
        cmap = ListedColormap([REGIONS[k][1] for k in sorted(REGIONS)])
        ax.pcolormesh(map_ds[first].values, map_ds[second].values, code.values.T, cmap=cmap,
                      vmin=-0.5, vmax=len(REGIONS) - 0.5, shading="nearest", rasterized=True)
        present = set(np.unique(code.values).tolist())
        handles += [Patch(facecolor=REGIONS[k][1], edgecolor="0.6", label=REGIONS[k][0])
                    for k in sorted(REGIONS) if k in present]
    kinds_seen: list[str] = []
    parts_seen: set[str] = set()
    labels: list[tuple[float, float, str, str]] = []
    codim2: dict[tuple[float, float], tuple[str, bool]] = {}  # one per place
    part_names = list(CURVE_PARTS)
    for c in curve_list:
        kind = kind_of_curve(c)
        if kind != "ZV" and int(c.attrs["N"]) != N:
            continue
        px, py = split_parameters(str(c.attrs["parameters"]))
        if {px, py} != {first, second}:
            raise ValueError(f"two_parameter_diagram draws curves in ({first}, {second}); got a "
                             f"curve in ({px}, {py}) (the plane is the map's, or the first "
                             f"curve's)")
        x, y = c[first].values, c[second].values
        color = CURVE_STYLES[kind]["color"]
        physical = c["physical"].values.astype(bool)
        strong = c["stable_side"].values.astype(bool) & physical
        for name, mask in zip(part_names, (strong, physical & ~strong, ~physical),
                              strict=True):
            for sl in _segments(mask):
                ax.plot(x[sl], y[sl], color=color, **CURVE_PARTS[name])
            if mask.any():
                parts_seen.add(name)
        if kind not in kinds_seen:
            kinds_seen.append(kind)
        if label_curves and x.size:
            (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
            inside = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
            pick = np.flatnonzero(physical & inside)
            pick = pick if pick.size else np.flatnonzero(inside)
            if pick.size:
                k = int(pick[pick.size // 2])
                labels.append((float(x[k]), float(y[k]), kind, color))
        names = c[codim2_variable("label")].values
        if names.size:
            cx, cy = c[codim2_variable(first)].values, c[codim2_variable(second)].values
            on = physical[c[codim2_variable("point")].values]
            for lab, xx, yy, shown in zip(names, cx, cy, on, strict=True):
                # the same point found from both curves (PD+SN and SN+PD): one mark, one label
                key = (round(float(xx), 6), round(float(yy), 6))
                if key not in codim2 or shown:
                    codim2[key] = (str(lab), bool(shown))
    # only where the motion is physical: the others crowd the panel
    labels += [(xx, yy, codim2_name(lab), "black") for (xx, yy), (lab, s) in codim2.items()
               if s]
    handles += [Line2D([], [], color=CURVE_STYLES[kind]["color"],
                       label=f"{kind} {SPECIAL_NAMES[kind]}",
                       **CURVE_PARTS[part_names[0]]) for kind in kinds_seen]
    handles += [Line2D([], [], color="0.2", label=name, **CURVE_PARTS[name])
                for name in part_names if name in parts_seen]
    for style, shown in zip(CODIM2_STYLES, (True, False), strict=True):
        seen = [lab for lab, s in codim2.values() if s == shown]
        if seen:
            handle = Line2D([], [], linestyle="none", **CODIM2_STYLES[style],
                            label=_codim2_label(style, seen, shown))
            handle.codim2_seen = (style, shown, seen)  # panels' marks merge in _merge
            handles.append(handle)
    src = map_ds if map_ds is not None else next(iter(curve_list))
    ax.set_xlabel(axis_label(src, first))
    ax.set_ylabel(axis_label(src, second))
    if map_ds is not None:
        ax.set_xlim(float(map_ds[first].min()), float(map_ds[first].max()))
        ax.set_ylim(float(map_ds[second].min()), float(map_ds[second].max()))
    # a star in the frame is drawn whole, over the frame if it is at the edge (the map's
    # range is the frame: widened, it would show no map); one outside is not drawn; the
    # small grey stars over the gold ones (under one, a grey star was hidden)
    (x0, x1), (y0, y1) = sorted(ax.get_xlim()), sorted(ax.get_ylim())
    for style, shown in zip(CODIM2_STYLES, (True, False), strict=True):
        xy = np.array([k for k, (_, s) in codim2.items() if s == shown]).reshape(-1, 2)
        xy = xy[(xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) & (xy[:, 1] <= y1)]
        if xy.size:
            ax.plot(xy[:, 0], xy[:, 1], linestyle="none", zorder=4 if shown else 5,
                    clip_on=False, **CODIM2_STYLES[style])
    return handles, labels


def _label(ax: Axes, labels: Sequence[tuple[float, float, str, str]]) -> None:
    """Place the labels of a laid-out panel clear of each other and of the codim-2 marks.

    Codim-2 points (black labels) whose stars touch get one label, one leader
    (:func:`~impactcont.plots.labels.merged_labels`). The curves' labels and the codim-2
    labels are placed in one call, so that none stands over or beside another.
    """
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    inside = [lab for lab in labels if x0 <= lab[0] <= x1 and y0 <= lab[1] <= y1]
    xy: list[tuple[float, float]] = []
    texts: list[str] = []
    styles: list[dict[str, Any]] = []
    for color in dict.fromkeys(lab[3] for lab in inside):
        own = [lab for lab in inside if lab[3] == color]
        where, names = [lab[:2] for lab in own], [lab[2] for lab in own]
        if color == "black":
            ax.figure.draw_without_rendering()
            where, names = merged_labels(ax, where, names, distance=2.0 * _STAR)
            names = [_lines(name) for name in names]
        xy += where
        texts += names
        styles += [{"color": color, "fontweight": "bold" if color != "black" else "normal"}
                   ] * len(names)
    place_labels(ax, xy, texts, fontsize="x-small", avoid=marker_boxes(ax), styles=styles)


def _lines(text: str, per_line: int = 2) -> str:
    """A merged label (``SN+ZV, R1, PDNS, R2``) in lines of ``per_line`` names: one line
    of five names runs out of a crowded panel or over its neighbours' labels."""
    parts = text.split(", ")
    return ",\n".join(", ".join(parts[i:i + per_line]) for i in range(0, len(parts), per_line))


def _codim2_label(style: str, seen: Sequence[str], shown: bool) -> str:
    names = codim2_legend(seen) if shown else ""
    return f"{style}:\n{names}" if names else style


def _merge(handles: Iterable[Any]) -> list[Any]:
    """One handle per label, in order; the codim-2 marks of several panels are one handle
    per style, its text naming the points of every panel."""
    merged: dict[Any, Any] = {}
    codim2: dict[str, tuple[bool, list[str]]] = {}
    for h in handles:
        mark = getattr(h, "codim2_seen", None)
        if mark is None:
            merged[h.get_label()] = h
            continue
        style, shown, seen = mark
        merged.setdefault(("codim2", style), h)
        known = codim2.setdefault(style, (shown, []))[1]
        known += [lab for lab in seen if lab not in known]
    for style, (shown, seen) in codim2.items():
        merged[("codim2", style)].set_label(_codim2_label(style, seen, shown))
    return list(merged.values())


def two_parameter_diagram(map_ds: xr.Dataset | None = None, curves: Any = None, *,
                          N: int | None = None, ax: Axes | None = None,
                          label_curves: bool = True, label_codim2: bool = True,
                          legend: bool = True, title: str | None = None) -> Axes:
    """One panel: the regions of one N shaded, the curves of that N (and ZV) on top.

    Each kind of curve has its colour (:data:`CURVE_STYLES`); its line style
    says what crossing it changes (:data:`CURVE_PARTS`): bold where an
    observable stable motion changes (``stable_side``), thin where the motion
    is physical but unstable on both sides, dotted where it is not physical.
    Codim-2 points are stars (:data:`CODIM2_STYLES`), gold and labelled where
    the motion is physical, small and grey where it is not. Every mark is
    named in the legend under the axes; labels are placed clear of each other.

    Parameters
    ----------
    map_ds : xarray.Dataset, optional
        A map; its regions for ``N`` are shaded (:func:`region_codes`). The map of an
        N-p motion family (:func:`impactcont.multi_impact_map`, or
        :func:`impactcont.stability_map` of a motion) is drawn by
        :func:`multi_impact_map_diagram` (`N`, `label_curves` and `label_codim2` do not
        apply; no curves).
    curves : Dataset, sequence, mapping or DataTree of curve datasets, optional
        Curves in the map's plane ((omega, b), or the two parameters of a map over
        another pair; without a map, the first curve's); those with another ``N`` are
        skipped, except ZV curves, which do not depend on N.
    N : int, optional
        Which N; default the map's first (or the first curve's).
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default. With ``legend`` its
        figure should use the constrained layout (the default figure does).
    label_curves, label_codim2 : bool
        Write the kind next to each curve / the label next to each codim-2 point.
    legend : bool
        Draw the legend (under the axes).
    title : str, optional
        Axes title; by default the motions and the system
        (``Period-2 motions with 1 impact, $R = 0.6$, $\\eta = 0.1$``), ``""`` for none.

    Returns
    -------
    matplotlib.axes.Axes

    Raises
    ------
    ValueError
        Neither a map nor a curve, ``N`` not in the map, or a curve in other
        parameters than the map's (or the first curve's).
    """
    if map_ds is not None and dataset_tag(map_ds) == "multi_impact_map":
        if curves is not None:
            raise ValueError("two_parameter_diagram draws the curves of N-1 motions over an N-1 "
                             "map; got curves with the map of an N-p motion family")
        return multi_impact_map_diagram(map_ds, ax=ax, legend=legend, title=title)
    curve_list = _curves(curves)
    if map_ds is None and not curve_list:
        raise ValueError("give map_ds or curves (or both); got neither")
    if N is None:
        N = int(map_ds["N"].values[0]) if map_ds is not None else int(curve_list[0].attrs["N"])
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.0, 5.4), layout="constrained")
    handles, labels = _panel(ax, map_ds, curve_list, N, label_curves)
    labels = [lab for lab in labels if (label_codim2 if lab[3] == "black" else label_curves)]
    if legend:
        legend_below(ax, handles)
    if title is None:
        where = _system(map_ds, curve_list, _plane(map_ds, curve_list))
        title = f"Period-{N} motions with 1 impact" + (f", {where}" if where else "")
    if title:
        ax.set_title(title, fontsize="medium")
        ax.figure.draw_without_rendering()
        fit_text(ax.title)
    _label(ax, labels)
    logger.debug("two-parameter diagram N=%d: %d curve(s)", N, len(curve_list))
    return ax


def two_parameter_figure(map_ds: xr.Dataset, curves: Any = None, *, ncols: int = 2,
                         width: float = 7.0, title: str | None = None) -> Any:
    """One :func:`two_parameter_diagram` panel per N of the map, one legend; returns the Figure.

    The map of an N-p motion family (:func:`impactcont.multi_impact_map`, or
    :func:`impactcont.stability_map` of a motion) has one panel,
    :func:`multi_impact_map_diagram`, `width` wide.

    Parameters
    ----------
    map_ds : xarray.Dataset
    curves : Dataset, sequence, mapping or DataTree of curve datasets, optional
    ncols : int
        Panels per row (one below 5 in: a single column).
    width : float
        Figure width in inches, in [2, 7.2] (3.5: a journal's column, 7: its page).
    title : str, optional
        Figure title; by default the motions and the system, ``""`` for none.

    Raises
    ------
    ValueError
        ``ncols`` or ``width`` out of range.
    """
    import matplotlib.pyplot as plt

    ncols = check_positive_integer("ncols", ncols, "panels per row")
    width = check_width(width)
    if isinstance(map_ds, xr.Dataset) and dataset_tag(map_ds) == "multi_impact_map":
        fig, ax = plt.subplots(figsize=(width, 0.8 * width + 1.6), layout="constrained")
        two_parameter_diagram(map_ds, curves, ax=ax, title=title)
        return fig
    validate_map_dataset(map_ds)
    curve_list = _curves(curves)
    Ns = [int(k) for k in map_ds["N"].values]
    cols = 1 if width < 5.0 else min(ncols, len(Ns))
    rows = -(-len(Ns) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(width, rows * (0.8 * width / cols + 0.4) + 1.6),
                             layout="constrained", squeeze=False)
    handles: list[Any] = []
    labels = []
    for ax, N in zip(axes.flat, Ns, strict=False):
        more, own = _panel(ax, map_ds, curve_list, N, True)
        handles += more
        labels.append(own)
        ax.set_title(f"$N = {N}$", fontsize="medium")
    for ax in axes.flat[len(Ns):]:
        ax.set_visible(False)
    handles = _merge(handles)
    for n in range(min(len(handles), 4), 0, -1):
        legend = fig.legend(handles=handles, loc="outside lower center", ncols=n,
                            fontsize=legend_fontsize(fig), frameon=False, handlelength=1.8,
                            columnspacing=1.0)
        fig.draw_without_rendering()
        if legend.get_window_extent().width <= fig.bbox.width - 8.0 or n == 1:
            break
        legend.remove()
    if title is None:
        plane = _plane(map_ds, curve_list)
        where = _system(map_ds, curve_list, plane)
        title = (f"Period-$N$ motions with 1 impact in {_plane_symbols(plane)}"
                 + (f", {where}" if where else ""))
    if title:
        fit_text(fig.suptitle(title, fontsize="medium"))
    fig.draw_without_rendering()
    # the legend of one column is long: the figure grows so that the panels keep their
    # height (squashed under it, the labels of a crowded panel find no room)
    panel = 0.8 * width / cols - 0.6  # inches a panel's frame is given
    short = panel - min(ax.get_window_extent().height for ax in axes.flat[:len(Ns)]) / fig.dpi
    if short > 0.05:
        fig.set_size_inches(width, fig.get_size_inches()[1] + rows * short)
        fig.draw_without_rendering()
    for ax, own in zip(axes.flat, labels, strict=False):
        _label(ax, own)
    return fig


# -- the map of one N-p motion family ---------------------------------------------------------
#: Region codes of :func:`multi_map_regions`, with their legend text and shade.
MULTI_MAP_REGIONS: dict[int, tuple[str, str]] = {
    0: ("not found (family not reached)", "#ffffff"),
    1: ("found, not physical", "#e4e4e4"),
    2: ("physical, unstable", "#f6d7a7"),
    3: ("stable physical motion", "#8fc4e8"),
    4: ("found, interior contact not checked", "#d8c6e6"),
    5: ("found, not physical: a stick ended (SE side)", "#c9c9c9"),
    6: ("found, not physical: release grazing (RG side)", "#e8b9b9"),
    7: ("found, not physical: sticking onset (SO side)", "#c7dfc0"),
}
#: The region of a found point that is not physical for a reason of a sticking phase (the
#: bits of the map's ``reason``, :data:`~impactcont.dataset.maps.MAP_REASONS`), in the order
#: a motion checks each sticking phase: its duration, its onset, then its pressing force.
_STICKY_REGIONS = (("stick_ended", 5), ("sticking_onset", 7), ("release_grazing", 6))

#: Colour and line style of the boundary of each region, and its legend text.
MULTI_MAP_BOUNDARIES: dict[str, tuple[str, str, str]] = {
    "found": ("black", "-", "found region"),
    "physical": ("tab:red", "--", "physical region"),
    "stable_physical": ("navy", "-", "stable physical region"),
}
_SEED = {"marker": "*", "markersize": 10.0, "color": "gold", "markeredgecolor": "black",
         "linestyle": "none"}


def multi_map_regions(ds: xr.Dataset) -> xr.DataArray:
    """Region of every grid point of a :func:`~impactcont.analysis.maps.multi_impact_map`.

    Returns
    -------
    xarray.DataArray of int, dims (parameter 0, parameter 1)
        0: not found; 1: found, not physical; 2: physical, unstable; 3: stable and
        physical; 4: found, but its interior contact was not searched
        (``contact_checked`` False: ``checks=False``, or a constant force pushing a free
        mode), so whether it is physical is not known (it is never reported physical).
        The map of a motion with sticking phases (its variable ``reason``) splits 1 by
        the sticking phases' reasons: 5 a stick time <= 0 (past the end of a ride, SE),
        6 release grazing (RG), 7 the sticking onset passed (SO); 1 the other reasons.
    """
    validate_multi_impact_map_dataset(ds)
    found, physical, stable, checked = (ds[k].astype(bool) for k in (
        "found", "physical", "stable", "contact_checked"))
    unphysical = xr.where(found, 1, 0)
    if "reason" in ds:
        reason = ds["reason"].astype(np.int64)
        for name, region in reversed(_STICKY_REGIONS):  # the first reason on top
            unphysical = xr.where(found & ((reason & MAP_REASONS[name]) != 0), region,
                                  unphysical)
    code = xr.where(physical & stable, 3, xr.where(physical, 2, xr.where(
        found & ~checked, 4, unphysical)))
    return code.rename("region")


def multi_map_title(ds: xr.Dataset) -> str:
    """The motion and the system of a map: ``Period-1 symmetric motions with 2 impacts, ...``.

    The parameters held fixed (those not on the map's axes) in mathtext, and
    the stops: a mirrored lower stop moves with ``b``.
    """
    axes = set(split_parameters(str(ds.attrs["parameters"])))
    osc = json.loads(ds.attrs["oscillator"])
    stops = _stops(ds)
    mirror = bool((osc.get("stops") or {}).get("mirror"))
    values = {k: float(osc[k]) for k in ("b", "R", "omega", "eta", "alpha", "beta", "F0")
              if isinstance(osc.get(k), (int, float)) and k not in axes}
    if not mirror:
        values.update({k: stops[k] for k in ("b_low", "R_low") if k in stops})
    text = motion_text([ds], adjective="symmetric" if ds.attrs.get("symmetric") else "")
    where = parameter_text(values, ("b", "b_low", "R", "R_low", "omega", "eta", "alpha",
                                    "beta", "F0"))
    parts = [text, *([where] if where else [])]
    if mirror:
        parts.append(rf"mirror stops $x_{stops['mass']} = \pm b$")
    return ", ".join(parts)


def _boundary(x: np.ndarray, y: np.ndarray, flag: np.ndarray) -> list[np.ndarray]:
    """The 0.5 contour of ``flag`` (dims x, y) as polylines ``(m, 2)`` in (x, y)."""
    from contourpy import contour_generator

    lines = contour_generator(x, y, flag.T.astype(float), line_type="Separate").lines(0.5)
    return [np.asarray(line, dtype=float) for line in lines]


def multi_impact_map_diagram(ds: xr.Dataset, *, ax: Axes | None = None,
                             boundaries: bool = True, legend: bool = True,
                             title: str | None = None) -> Axes:
    """One panel: the map's regions shaded, their boundaries and the seed on top.

    Every shade, boundary and the seed are named in the legend under the axes
    (:data:`MULTI_MAP_REGIONS`, :data:`MULTI_MAP_BOUNDARIES`); the axes are
    named in symbols and the title names the motion, the system and the stops
    (:func:`multi_map_title`).

    Parameters
    ----------
    ds : xarray.Dataset
        A map of :func:`impactcont.analysis.maps.multi_impact_map`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default. With ``legend`` its
        figure should use the constrained layout (the default figure does).
    boundaries : bool
        Draw the boundaries of the found, physical and stable physical regions (the
        0.5 contour of each flag on the grid: within half a grid cell of where the
        flag changes).
    legend : bool
        Draw the legend (under the axes).
    title : str, optional
        Axes title; by default :func:`multi_map_title`, ``""`` for none.

    Returns
    -------
    matplotlib.axes.Axes
    """
    code = multi_map_regions(ds)
    px, py = split_parameters(str(ds.attrs["parameters"]))
    x, y = ds[px].values, ds[py].values
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5.0, 5.6), layout="constrained")
    cmap = ListedColormap([MULTI_MAP_REGIONS[k][1] for k in sorted(MULTI_MAP_REGIONS)])
    ax.pcolormesh(x, y, code.values.T, cmap=cmap, vmin=-0.5,
                  vmax=len(MULTI_MAP_REGIONS) - 0.5, shading="nearest", rasterized=True)
    present = set(np.unique(code.values).tolist())
    handles: list[Any] = [Patch(facecolor=MULTI_MAP_REGIONS[k][1], edgecolor="0.6",
                                label=MULTI_MAP_REGIONS[k][0])
                          for k in sorted(MULTI_MAP_REGIONS) if k in present]
    if boundaries and x.size > 1 and y.size > 1:
        flags = {"found": ds["found"].values, "physical": ds["physical"].values,
                 "stable_physical": ds["physical"].values & ds["stable"].values}
        for order, (key, flag) in enumerate(flags.items()):
            if flag.all() or not flag.any():
                continue
            color, style, text = MULTI_MAP_BOUNDARIES[key]
            for line in _boundary(x, y, np.asarray(flag, dtype=bool)):  # where they coincide,
                ax.plot(line[:, 0], line[:, 1], color=color, linestyle=style,  # found on top
                        linewidth=1.2, zorder=2.3 - 0.1 * order)
            handles.append(Line2D([], [], color=color, linestyle=style, linewidth=1.2,
                                  label=f"boundary of the {text}"))
    seed = json.loads(ds.attrs["seed"])
    if px in seed and py in seed:
        ax.plot(seed[px], seed[py], zorder=4, **_SEED)
        handles.append(Line2D([], [], label="seed", **_SEED))
    ax.set_xlabel(axis_label(ds, px))
    ax.set_ylabel(axis_label(ds, py))
    if legend:
        legend_below(ax, handles)
    title = multi_map_title(ds) if title is None else title
    if title:
        ax.set_title(title, fontsize="medium")
        ax.figure.draw_without_rendering()
        fit_text(ax.title)
    logger.debug("multi-impact map diagram over (%s, %s)", px, py)
    return ax

"""Bifurcation diagrams with one curve per impact: N-1 and N-p branches together.

:func:`impact_diagram` draws a per-impact quantity (impact velocity, phase,
flight time, gap) of every impact of every branch against the continued
parameter, styled by stability like
:func:`impactcont.plots.bifurcation_diagram`; an N-p branch contributes p
curves, an N-1 branch (no ``impact`` dimension) one. This is the picture a
brute-force simulator diagram (every impact velocity after the transient) is
compared with.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from impactcont.dataset.schema import SPECIAL_LABELS, special_variable
from impactcont.plots.branches import (
    LEGEND_PLACES,
    NONPHYSICAL_GREY,
    NONPHYSICAL_MARKER,
    SEGMENT_STYLES,
    SPECIAL_MARKERS,
    _borders_physical,
    _branches,
    _new_axes,
    _stops,
    _y_range,
    axis_label,
    diagram_legend,
    differing_parameters,
    fit_text,
    fixed_parameters,
    label_specials,
    motion_text,
    parameter_text,
    stability_segments,
    system_text,
)

__all__ = ["IMPACT_QUANTITIES", "impact_diagram", "impact_label"]

logger = logging.getLogger(__name__)

#: Per-impact variable -> the variable of an N-1 branch (one impact) holding it.
IMPACT_QUANTITIES: dict[str, str] = {
    "impact_velocity_k": "impact_velocity",
    "delta_k": "delta",
    "gap_min_k": "gap_min",
}


def _per_impact(ds: xr.Dataset, y: str) -> np.ndarray:
    """``(npoints, p)`` values of ``y`` (an N-1 branch gives one column)."""
    if y in ds.data_vars and ds[y].dims == ("point", "impact"):
        return np.asarray(ds[y].values, dtype=float)
    return np.asarray(ds[IMPACT_QUANTITIES[y]].values, dtype=float)[:, None]


def _special_per_impact(ds: xr.Dataset, y: str, values: np.ndarray, k: int) -> np.ndarray:
    name = special_variable(y)
    if name in ds.data_vars and ds[name].dims == ("special", "impact"):
        return np.asarray(ds[name].values[k], dtype=float)
    base = special_variable(IMPACT_QUANTITIES[y])
    if base in ds.data_vars:
        return np.array([float(ds[base].values[k])])
    return values[int(ds[special_variable("point")].values[k])]


_MARKER_SIZE = 6.0  # points, as in the bifurcation diagrams


def impact_label(ds: xr.Dataset, y: str) -> str:
    r"""The vertical axis of an impact diagram, in symbols: ``impact velocity $\dot{x}_1(T_k^-)$``.

    Between two stops the stored velocity is the speed towards the stop hit.
    """
    stops = _stops(ds)
    j = stops["mass"]
    if y == "impact_velocity_k":
        if "b_low" in stops:
            return rf"impact speed towards the stop hit $|\dot{{x}}_{j}(T_k^-)|$"
        return rf"impact velocity $\dot{{x}}_{j}(T_k^-)$"
    if y == "delta_k":
        return r"impact phase $\theta_k$ [rad]"
    return rf"minimum gap of flight $k$ (mass {j})"


def impact_diagram(datasets: Any, *, y: str = "impact_velocity_k", ax: Axes | None = None,
                   label_special: bool = False, specials: tuple[str, ...] = SPECIAL_LABELS,
                   names: bool = True, nonphysical: bool = True,
                   colors: Sequence[str] | None = None, title: str | None = None,
                   physical_range: bool = True, legend: str | None = "below",
                   zoom: bool = True) -> Axes:
    """Draw every impact of every branch against the continued parameter.

    Styled as :func:`impactcont.plots.bifurcation_diagram`: stable physical
    motions solid, unstable dashed, non-physical faint and dotted
    (:data:`~impactcont.plots.SEGMENT_STYLES`); one colour per branch, its p
    impacts p curves of that colour; special points marked on every impact
    (:data:`~impactcont.plots.SPECIAL_MARKERS`) in the colour of their branch,
    small and grey (:data:`~impactcont.plots.branches.NONPHYSICAL_GREY`) on
    non-physical motions; every mark named in the legend, the title naming
    the motions and the system.

    Parameters
    ----------
    datasets : Dataset, sequence or mapping of Datasets, or DataTree
        N-1 and N-p branch datasets, all continued in the same parameter.
    y : str
        A per-impact quantity, one of :data:`IMPACT_QUANTITIES`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new pyplot figure by default. With ``legend="below"``
        its figure should use the constrained layout (the default figure does).
    label_special : bool
        Write each special point's label next to its markers (placed clear of
        the others; crowded ones in a zoomed inset, see ``zoom``).
    specials : tuple of str
        Which special points to mark.
    names : bool
        Add the branch names (mapping keys / groups) to the legend.
    nonphysical : bool
        Draw the non-physical parts of the branches (faint, dotted) and their
        special points.
    colors : sequence of str, optional
        One matplotlib colour per branch (cycled); default ``C0 .. C9``.
    title : str, optional
        Axes title; by default the motions and the system drawn
        (``Period-$N$ motions with $p$ impacts, $b = 0$, $R = 0.6$, ...``), ``""`` for none.
    physical_range : bool
        Fit the vertical range to the physical motions (default), clipping
        non-physical ones at the frame; False fits everything drawn.
    legend : {"below", "right", "inside", None}
        Under the axes (default), outside on the right, inside the axes, or none.
    zoom : bool
        With ``label_special``, draw crowded special points again in an inset.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``, or the new figure's; the zoomed inset, if one was drawn, is its child
        axes (``ax.child_axes``).

    Raises
    ------
    ValueError
        ``y``, ``specials`` or ``legend`` is not allowed, or the branches are
        continued in different parameters.
    """
    if y not in IMPACT_QUANTITIES:
        raise ValueError(f"y must be one of {sorted(IMPACT_QUANTITIES)}; got {y!r}")
    unknown = sorted(set(specials) - set(SPECIAL_LABELS))
    if unknown:
        raise ValueError(f"specials must be a subset of {SPECIAL_LABELS}; got unknown {unknown}")
    if legend not in LEGEND_PLACES:
        raise ValueError(f"legend must be one of {LEGEND_PLACES}; got {legend!r}")
    branches = _branches(datasets, one_parameter=True)
    if ax is None:
        ax = _new_axes()
    differing = differing_parameters([[ds] for _, ds in branches])
    kinds_seen: set[str] = set()
    branch_handles = []
    marks: list[tuple[float, float, str, str, bool]] = []  # x, y, label, colour, physical
    seen: list[np.ndarray] = []  # values of the physical motions
    for b, (name, ds) in enumerate(branches):
        parameter = ds.attrs["parameter"]
        x = np.asarray(ds[parameter].values, dtype=float)
        values = _per_impact(ds, y)
        color = colors[b % len(colors)] if colors else f"C{b % 10}"
        drawn = False
        for kind, sl in stability_segments(ds):
            if kind == "non-physical" and not nonphysical:
                continue
            ax.plot(x[sl], values[sl], color=color, **SEGMENT_STYLES[kind])
            kinds_seen.add(kind)
            drawn = True
        physical = np.asarray(ds["physical"].values, dtype=bool)
        seen.append(values[physical].ravel())
        about = ", ".join([f"{int(ds.attrs['N'])}-{values.shape[1]}",
                           *([parameter_text(fixed_parameters([ds]), differing)]
                             if differing else [])])
        text = f"{name} ({about})" if name and names and about not in name else \
            name if name and names else about
        if drawn:  # a legend names what is drawn: not a branch without physical motions
            branch_handles.append(Line2D([], [], color=color, linewidth=1.6, label=text))
        labels = np.asarray(ds[special_variable("label")].values).tolist()
        xs = np.asarray(ds[special_variable(parameter)].values, dtype=float)
        for k, label in enumerate(labels):
            shown = _borders_physical(ds, physical, k)
            if label not in specials or not (shown or nonphysical):
                continue
            for yk in _special_per_impact(ds, y, values, k):
                if np.isfinite(yk) and np.isfinite(xs[k]):
                    marks.append((float(xs[k]), float(yk), str(label), color, shown))
    values = np.concatenate([*seen, [m[1] for m in marks if m[4]]])
    values = values[np.isfinite(values)]
    lo = hi = pad = None
    if physical_range and values.size:
        lo, hi, pad = _y_range(values)
        ax.set_ylim(lo, hi)
    labels_seen: list[str] = []
    grey = False
    for label in SPECIAL_LABELS:
        for shown in (True, False):
            pts = [m for m in marks if m[2] == label and m[4] == shown]
            if not shown and lo is not None:  # never cut by the frame: inside or not drawn
                pts = [m for m in pts if lo + 0.5 * pad <= m[1] <= hi - 0.5 * pad]
            for color in dict.fromkeys(m[3] for m in pts):
                own = np.array([m[:2] for m in pts if m[3] == color])
                ax.plot(own[:, 0], own[:, 1], linestyle="none",
                        marker=SPECIAL_MARKERS[label] if shown else NONPHYSICAL_MARKER,
                        markersize=_MARKER_SIZE if shown else 0.7 * _MARKER_SIZE,
                        markerfacecolor="white", markeredgewidth=1.2 if shown else 0.8,
                        markeredgecolor=color if shown else NONPHYSICAL_GREY, zorder=3)
            if pts and shown and label not in labels_seen:
                labels_seen.append(label)
            grey |= bool(pts) and not shown
    first = branches[0][1]
    parameter = first.attrs["parameter"]
    ax.set_xlabel(axis_label(first, parameter))
    ax.set_ylabel(impact_label(first, y))
    diagram_legend(ax, kinds_seen, labels_seen, grey, branch_handles, legend)
    if title is None:
        datasets_ = [ds for _, ds in branches]
        where = system_text(datasets_, skip={parameter})
        title = motion_text(datasets_) + (f", {where}" if where else "")
    if title:
        ax.set_title(title, fontsize="medium")
        ax.figure.draw_without_rendering()
        fit_text(ax.title)
    kept = [m[:3] for m in marks if m[4]]
    if label_special and kept:
        label_specials(ax, kept, zoom=zoom)
    logger.debug("impact diagram: %d branch(es), y=%s", len(branches), y)
    return ax
